//! The report of a [`ModalAnalysis`] as text: the report `hyst ssi` prints.

use std::fmt;

use super::ModalAnalysis;
use crate::refine::{MISFIT_LIMIT, SAME_MODE_DISTANCE};
use crate::{LagLimit, Refinement};

/// A mode shape as "magnitude∠phase°" per entry (phase rounded to a degree), entries joined
/// by `sep`: how reports print shapes.
pub fn shape_text(shape: &[crate::Complex64], sep: &str) -> String {
    shape
        .iter()
        .map(|v| {
            // + 0.0 turns a rounded −0 into 0.
            let deg = v.arg().to_degrees().round() + 0.0;
            format!("{:.3}∠{deg:.0}°", v.norm())
        })
        .collect::<Vec<_>>()
        .join(sep)
}

/// A rate or frequency with at most four decimals, trailing zeros dropped (64, 85.3333).
fn rate_text(v: f64) -> String {
    let t = format!("{v:.4}");
    let t = t.trim_end_matches('0').trim_end_matches('.');
    t.to_string()
}

/// A standard error to four decimals, or in exponent form beyond 1e5 (a real pole far
/// outside the band, say: thirty digits say nothing more than that the record does not
/// determine it); `?` when there is none.
fn se_text(v: Option<f64>) -> String {
    v.map_or("?".to_string(), |v| {
        if v.abs() < 1e5 {
            format!("{v:.4}")
        } else {
            format!("{v:.1e}")
        }
    })
}

impl ModalAnalysis {
    fn fmt_ssi(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let res = &self.ssi;
        self.fmt_decimation(f)?;
        let largest_lag = 2 * res.block_rows - 1;
        write!(
            f,
            "{} block rows: correlations up to lag {largest_lag} ({:.4} s at {} Hz)",
            res.block_rows,
            largest_lag as f64 / self.fs_hz,
            rate_text(self.fs_hz)
        )?;
        match &res.auto_lag {
            None => writeln!(f)?,
            Some(lag) => match (lag.lowest_peak_hz, lag.periods) {
                (Some(peak), Some(periods)) => {
                    let limit = match lag.limited_by {
                        Some(LagLimit::MatrixSize) => format!(
                            "; fewer than {} to keep the Toeplitz matrix within {} rows (give --references or --lag-seconds)",
                            crate::survey::LAG_PERIODS,
                            crate::survey::MAX_TOEPLITZ_ROWS
                        ),
                        Some(LagLimit::RecordLength) => {
                            "; fewer, to keep the lag within an eighth of the record".into()
                        }
                        _ => String::new(),
                    };
                    writeln!(
                        f,
                        ", {periods:.1} periods of the record's lowest spectral peak ({peak:.4} Hz){limit}"
                    )?
                }
                _ => writeln!(
                    f,
                    ": the record's spectrum shows no peak to size the lag by"
                )?,
            },
        }
        if let Some(chosen) = &res.chosen_references {
            let names: Vec<String> = chosen.channels.iter().map(|c| c.to_string()).collect();
            writeln!(
                f,
                "references: {} of the {} channels ({}), those that see the {} mode shape(s) at the record's {} spectral peak(s) best (give --references to name them)",
                chosen.channels.len(),
                res.diagram.channels,
                names.join(", "),
                chosen.modes_seen,
                chosen.peaks_hz.len()
            )?;
        }
        if !res.modes.is_empty() || !res.real_poles.is_empty() {
            writeln!(
                f,
                "SSI (± is the spread over each cluster's poles, not a standard error):"
            )?;
        }
        for m in &res.modes {
            // Members come by increasing order: the first and last give the span of orders.
            let span = match (m.members.first(), m.members.last()) {
                (Some(lo), Some(hi)) => format!(", orders {}–{}", lo.0, hi.0),
                _ => String::new(),
            };
            writeln!(
                f,
                "mode {:>9.4} ± {:.4} Hz  damping ratio {:.4} ± {:.4}  ({} poles{span})",
                m.frequency_hz,
                m.frequency_std_hz,
                m.damping_ratio,
                m.damping_std,
                m.members.len()
            )?;
        }
        self.fmt_ssi_errors(f)?;
        // Shapes say something with several channels only (a one-channel shape is a number).
        if self.channels.len() > 1 && !res.modes.is_empty() {
            writeln!(
                f,
                "shapes (channels {}; magnitude∠phase, the largest entry 1; MPC 1 for a real mode):",
                self.channels.join(", ")
            )?;
            for m in &res.modes {
                writeln!(
                    f,
                    "  {:>9.4} Hz  {}  MPC {:.3}",
                    m.frequency_hz,
                    shape_text(&m.shape, "  "),
                    m.mpc
                )?;
            }
            writeln!(
                f,
                "MAC between the modes (1 on the diagonal; near 0 where the channels tell two modes apart):"
            )?;
            for (m, row) in res.modes.iter().zip(&self.mac) {
                let cells: Vec<String> = row.iter().map(|v| format!("{v:.3}")).collect();
                writeln!(f, "  {:>9.4} Hz  {}", m.frequency_hz, cells.join("  "))?;
            }
        }
        for r in &res.real_poles {
            writeln!(
                f,
                "real pole {:.4} ± {:.4} rad/s ({} poles)",
                r.lambda,
                r.lambda_std,
                r.members.len()
            )?;
        }
        for n in &res.notes {
            writeln!(f, "note: {n}")?;
        }
        Ok(())
    }

    /// SSI's modes with the jackknife's standard errors, when made.
    fn fmt_ssi_errors(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let Some(e) = &self.ssi_errors else {
            return Ok(());
        };
        writeln!(
            f,
            "SSI's modes with standard errors (jackknife over {} blocks of the record):",
            e.blocks
        )?;
        for (m, err) in self.ssi.modes.iter().zip(&e.modes) {
            match err {
                Some(err) => writeln!(
                    f,
                    "mode {:>9.4} ± {:.4} Hz  damping ratio {:.4} ± {:.4}  ({} of {} replicates)",
                    m.frequency_hz,
                    err.frequency_se_hz,
                    m.damping_ratio,
                    err.damping_se,
                    err.replicates,
                    e.blocks
                )?,
                None => writeln!(
                    f,
                    "mode {:>9.4} Hz: found in too few replicates for an error",
                    m.frequency_hz
                )?,
            }
        }
        Ok(())
    }

    fn fmt_decimation(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let d = &self.decimation;
        match (&d.survey, d.factor) {
            (Some(s), 1) => writeln!(
                f,
                "not decimated: 99 % of the record's power lies below {:.4} Hz, {:.0} % of Nyquist ({} Hz)",
                s.band_hz,
                100.0 * s.band_hz / (s.fs_hz / 2.0),
                rate_text(s.fs_hz / 2.0)
            ),
            (Some(s), r) => writeln!(
                f,
                "decimated by {r} from {} Hz to {} Hz (read from the record: 99 % of its power lies below {:.4} Hz{}; --decimate 1 keeps the rate)",
                rate_text(d.recorded_fs_hz),
                rate_text(self.fs_hz),
                s.band_hz,
                s.peaks_hz.last().map_or(String::new(), |p| format!(
                    ", its highest spectral peak at {p:.4} Hz"
                ))
            ),
            (None, 1) => Ok(()),
            (None, r) => writeln!(
                f,
                "decimated by {r} from {} Hz to {} Hz",
                rate_text(d.recorded_fs_hz),
                rate_text(self.fs_hz)
            ),
        }
    }

    /// The estimates that are not physical, each with its reason, and whether the record
    /// follows the model.
    fn fmt_fit_quality(&self, f: &mut fmt::Formatter<'_>, r: &Refinement) -> fmt::Result {
        for n in &self.not_reported {
            let what = if n.real_pole {
                format!("real pole {:.4e} rad/s", r.real_poles[n.index].lambda)
            } else {
                let m = &r.modes[n.index];
                format!(
                    "{:.4} Hz, damping ratio {:.4}",
                    m.frequency_hz, m.damping_ratio
                )
            };
            let why: Vec<String> = n.reasons.iter().map(|w| w.to_string()).collect();
            writeln!(
                f,
                "not a {}: {what} ({}); kept in the fit, not reported",
                if n.real_pole { "real pole" } else { "mode" },
                why.join("; ")
            )?;
        }
        if r.misfit > MISFIT_LIMIT {
            writeln!(
                f,
                "warning: the record does not follow the refinement's model (misfit {:.3} > {}: \
                 its periodogram departs from the modes' spectrum by more than a random \
                 record's scatter): the answer is SSI's estimates, not the refined ones",
                r.misfit, MISFIT_LIMIT
            )
        } else if !self.not_reported.is_empty() {
            writeln!(
                f,
                "misfit {:.3}, within {MISFIT_LIMIT}, but only with the {} estimate(s) above that are not physical: the model spends poles on what it lacks",
                r.misfit,
                self.not_reported.len()
            )
        } else {
            writeln!(f, "misfit {:.3} (the record follows the model)", r.misfit)
        }
    }

    fn fmt_refined(&self, f: &mut fmt::Formatter<'_>, r: &Refinement) -> fmt::Result {
        let res = &self.ssi;
        writeln!(
            f,
            "refined by maximum likelihood ({} frequencies, {}; a mode needs evidence above {:.1}; ± one standard error):",
            r.frequencies,
            r.fitted_by(),
            r.penalty
        )?;
        for (i, m) in r.modes.iter().enumerate() {
            if !self.is_reported(i, false) {
                continue;
            }
            let ssi = m.source.map_or_else(
                || {
                    format!(
                        "no SSI mode within {:.0} % of its pole",
                        100.0 * SAME_MODE_DISTANCE
                    )
                },
                |i| format!("SSI mode at {:.4} Hz", res.modes[i].frequency_hz),
            );
            writeln!(
                f,
                "mode {:>9.4} ± {} Hz  damping ratio {:.4} ± {}  (evidence {:.0}; {ssi})",
                m.frequency_hz,
                se_text(m.frequency_se_hz),
                m.damping_ratio,
                se_text(m.damping_se),
                m.evidence,
            )?;
            if let (Some(shape), Some(sd), Some(mpc)) = (&m.shape, &m.shape_se, m.mpc) {
                // Two digits whatever the size; the entry scaled to 1 has none.
                let se: Vec<String> = sd
                    .iter()
                    .map(|&v| {
                        if v == 0.0 {
                            "0".into()
                        } else {
                            format!("{v:.1e}")
                        }
                    })
                    .collect();
                writeln!(
                    f,
                    "     shape {}  (standard errors {}; MPC {:.3})",
                    shape_text(shape, "  "),
                    se.join(", "),
                    mpc
                )?;
            } else if let Some(s) = m.source.filter(|_| self.channels.len() > 1) {
                writeln!(
                    f,
                    "     shape {}  (SSI's: the refinement gives shapes only from a joint fit, and this one was of {})",
                    shape_text(&res.modes[s].shape, "  "),
                    r.fitted_by()
                )?;
            }
        }
        for d in &r.dropped {
            match d.fitted {
                Some(p) => writeln!(
                    f,
                    "dropped the mode the fit had moved to {:.4} Hz, damping ratio {:.4} (nearest SSI mode {:.4} Hz): evidence {:.1}",
                    p.frequency_hz, p.damping_ratio, d.frequency_hz, d.evidence
                )?,
                None => writeln!(
                    f,
                    "dropped the SSI mode at {:.4} Hz: evidence {:.1}",
                    d.frequency_hz, d.evidence
                )?,
            }
        }
        for (i, p) in r.real_poles.iter().enumerate() {
            if !self.is_reported(i, true) {
                continue;
            }
            writeln!(
                f,
                "real pole {:.4} ± {} rad/s  (evidence {:.0}, above {:.1}; SSI real pole at {:.4})",
                p.lambda,
                se_text(p.lambda_se),
                p.evidence,
                r.real_pole_penalty,
                res.real_poles[p.source].lambda
            )?;
        }
        for d in &r.dropped_real_poles {
            writeln!(
                f,
                "dropped the SSI real pole at {:.4} rad/s: evidence {:.1}, below {:.1}",
                d.lambda, d.evidence, r.real_pole_penalty
            )?;
        }
        self.fmt_fit_quality(f, r)
    }
}

impl fmt::Display for ModalAnalysis {
    /// The report `hyst ssi` prints: the block rows, SSI's modes with their spread (with
    /// several channels their shapes, MPC and the MAC between them), real poles and notes;
    /// then the refined modes and real poles with their standard errors, what was dropped,
    /// and the misfit.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.fmt_ssi(f)?;
        if let Some(why) = &self.not_refined {
            writeln!(f, "not refined: {why}")?;
        }
        if let Some(r) = &self.refined {
            self.fmt_refined(f, r)?;
        }
        if let Some(why) = &self.no_errors {
            writeln!(f, "no standard errors: {why}")?;
        }
        self.decision.fmt_with(f)
    }
}
