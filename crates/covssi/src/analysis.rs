//! The whole modal analysis of a record in one call: SSI ([`identify`]), the MAC between its
//! modes, then the maximum-likelihood refinement ([`refine_with_real_poles`]), as one report
//! that prints as text ([`std::fmt::Display`]) and serializes (feature `serde`).

use std::fmt;

use crate::progress::Progress;
use crate::refine::{MISFIT_LIMIT, SAME_MODE_DISTANCE};
use crate::{RefineOptions, Refinement, SsiError, SsiOptions, SsiResult, identify, mac};

/// Options of [`analyze`]: SSI's, and the refinement's (`None`: SSI alone).
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
#[non_exhaustive]
pub struct AnalysisOptions {
    /// SSI's options.
    pub ssi: SsiOptions,
    /// The refinement's options; `None` skips it. Default: on, with its defaults.
    pub refine: Option<RefineOptions>,
}

impl Default for AnalysisOptions {
    fn default() -> Self {
        AnalysisOptions {
            ssi: SsiOptions::default(),
            refine: Some(RefineOptions::default()),
        }
    }
}

impl AnalysisOptions {
    /// These options with SSI's set to `ssi`.
    pub fn with_ssi(mut self, ssi: SsiOptions) -> Self {
        self.ssi = ssi;
        self
    }

    /// These options with the refinement's set to `refine` (`None`: SSI alone).
    pub fn with_refine(mut self, refine: Option<RefineOptions>) -> Self {
        self.refine = refine;
        self
    }
}

/// What [`analyze`] finds: SSI's result (its fields at the top level in JSON), the MAC
/// between its modes, and the refinement.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ModalAnalysis {
    /// The channels' names, in the order given: their indices from [`analyze`]; a caller
    /// that knows their names sets them (they head the shapes in the text).
    pub channels: Vec<String>,
    /// The sampling rate analysed (Hz).
    pub fs_hz: f64,
    /// SSI's result.
    #[cfg_attr(feature = "serde", serde(flatten))]
    pub ssi: SsiResult,
    /// MAC between SSI's modes (1 on the diagonal).
    pub mac: Vec<Vec<f64>>,
    /// The refinement; `None` when it was not asked for, SSI found nothing to refine, or it
    /// failed (`not_refined` says why).
    pub refined: Option<Refinement>,
    /// Why the refinement asked for gave no result (e.g. a record too short for the modes SSI
    /// found): SSI's result stands, and the report says so rather than failing.
    pub not_refined: Option<String>,
}

/// SSI on the channels `y` sampled at `fs` Hz, then the refinement of its modes and real
/// poles when `opts.refine` asks for it and SSI found any. An error of SSI is this
/// function's; an error of the refinement leaves SSI's result, with
/// [`ModalAnalysis::not_refined`] saying why.
pub fn analyze(y: &[&[f64]], fs: f64, opts: &AnalysisOptions) -> Result<ModalAnalysis, SsiError> {
    analyze_with_progress(y, fs, opts, &|_| {})
}

/// [`analyze`], telling `progress` of each step as it starts: SSI, then the refinement's
/// steps ([`crate::refine::refine_with_progress`]).
pub fn analyze_with_progress(
    y: &[&[f64]],
    fs: f64,
    opts: &AnalysisOptions,
    progress: &dyn Fn(Progress),
) -> Result<ModalAnalysis, SsiError> {
    progress(Progress {
        done: 0,
        total: 1,
        what: "SSI",
    });
    let ssi = identify(y, fs, &opts.ssi)?;
    let mac = ssi
        .modes
        .iter()
        .map(|a| ssi.modes.iter().map(|b| mac(&a.shape, &b.shape)).collect())
        .collect();
    let (refined, not_refined) = match &opts.refine {
        Some(r) if !(ssi.modes.is_empty() && ssi.real_poles.is_empty()) => {
            match crate::refine::refine_with_progress(
                y,
                fs,
                &ssi.modes,
                &ssi.real_poles,
                r,
                progress,
            ) {
                Ok(refined) => (Some(refined), None),
                // An option of the refinement out of range is the caller's to hear.
                Err(e @ SsiError::InvalidOption { .. }) => return Err(e),
                Err(e) => (None, Some(e.to_string())),
            }
        }
        _ => (None, None),
    };
    Ok(ModalAnalysis {
        channels: (0..y.len()).map(|c| c.to_string()).collect(),
        fs_hz: fs,
        ssi,
        mac,
        refined,
        not_refined,
    })
}

impl ModalAnalysis {
    /// The refinement when its modes are the ones to report: it ran, kept modes, and the
    /// record follows its model (misfit at most [`MISFIT_LIMIT`]); `None` when SSI's modes
    /// are the ones to report.
    pub fn reported_refinement(&self) -> Option<&Refinement> {
        self.refined
            .as_ref()
            .filter(|r| r.misfit <= MISFIT_LIMIT && !r.modes.is_empty())
    }

    /// The modes to report, as [`ModalAnalysis::reported_refinement`] chooses: the refined
    /// modes with their shapes (`None` where the refinement gave none), else SSI's.
    pub fn reported_modes(&self) -> Vec<ReportedMode> {
        match self.reported_refinement() {
            Some(r) => r
                .modes
                .iter()
                .map(|m| ReportedMode {
                    frequency_hz: m.frequency_hz,
                    frequency_se_hz: m.frequency_se_hz,
                    damping_ratio: m.damping_ratio,
                    damping_se: m.damping_se,
                    shape: m.shape.clone(),
                })
                .collect(),
            None => self
                .ssi
                .modes
                .iter()
                .map(|m| ReportedMode {
                    frequency_hz: m.frequency_hz,
                    frequency_se_hz: None,
                    damping_ratio: m.damping_ratio,
                    damping_se: None,
                    shape: Some(m.shape.clone()),
                })
                .collect(),
        }
    }
}

/// A mode as reported: the refinement's, or SSI's when the refinement does not hold.
#[derive(Debug, Clone, PartialEq)]
pub struct ReportedMode {
    /// Natural frequency (Hz).
    pub frequency_hz: f64,
    /// Its standard error (Hz): the refinement's; `None` for SSI's modes.
    pub frequency_se_hz: Option<f64>,
    /// Damping ratio.
    pub damping_ratio: f64,
    /// Its standard error: the refinement's; `None` for SSI's modes.
    pub damping_se: Option<f64>,
    /// The shape, one entry per channel, its largest entry 1; `None` for a refined mode
    /// whose shape the refinement could not give.
    pub shape: Option<Vec<crate::Complex64>>,
}

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
        let largest_lag = 2 * res.block_rows - 1;
        writeln!(
            f,
            "{} block rows: correlations up to lag {largest_lag} ({:.4} s at {} Hz)",
            res.block_rows,
            largest_lag as f64 / self.fs_hz,
            self.fs_hz
        )?;
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
                "mode {:>9.4} ± {:.4} Hz  damping {:.4} ± {:.4}  ({} poles{span})",
                m.frequency_hz,
                m.frequency_std_hz,
                m.damping_ratio,
                m.damping_std,
                m.members.len()
            )?;
        }
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

    fn fmt_refined(&self, f: &mut fmt::Formatter<'_>, r: &Refinement) -> fmt::Result {
        let res = &self.ssi;
        writeln!(
            f,
            "refined by maximum likelihood ({} frequencies, {}; a mode needs evidence above {:.1}; ± one standard error):",
            r.frequencies,
            r.fitted_by(),
            r.penalty
        )?;
        for m in &r.modes {
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
                "mode {:>9.4} ± {} Hz  damping {:.4} ± {}  (evidence {:.0}; {ssi})",
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
            }
        }
        for d in &r.dropped {
            writeln!(
                f,
                "dropped the SSI mode at {:.4} Hz: evidence {:.1}",
                d.frequency_hz, d.evidence
            )?;
        }
        for p in &r.real_poles {
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
        if r.misfit > MISFIT_LIMIT {
            writeln!(
                f,
                "warning: the record does not follow the refinement's model (misfit {:.3} > {}): \
                 the excitation may not be broadband random (e.g. a multisine), or the record \
                 holds what the model lacks; trust the SSI modes above instead",
                r.misfit, MISFIT_LIMIT
            )
        } else {
            writeln!(f, "misfit {:.3} (the record follows the model)", r.misfit)
        }
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
        match &self.refined {
            Some(r) => self.fmt_refined(f, r),
            None => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::refine_with_real_poles;

    /// The analysis is SSI then the refinement, nothing more: the same modes as the two
    /// calls made by hand, and without refinement none.
    #[test]
    fn analysis_is_identify_then_refine() {
        let fs = 50.0;
        let y: Vec<f64> = (0..6000)
            .map(|n| {
                let t = n as f64 / fs;
                (-0.4 * t).exp() * (2.0 * std::f64::consts::PI * 3.0 * t).cos()
                    + 0.01 * ((n * 7919) % 97) as f64 / 97.0
            })
            .collect();
        let opts = AnalysisOptions::default().with_ssi(SsiOptions {
            max_order: Some(10),
            ..SsiOptions::default()
        });
        let a = analyze(&[&y], fs, &opts).unwrap();
        let ssi = identify(&[&y], fs, &opts.ssi).unwrap();
        assert_eq!(a.ssi, ssi);
        assert_eq!(a.channels, vec!["0".to_string()]);
        assert_eq!(a.mac.len(), ssi.modes.len());
        assert!(!ssi.modes.is_empty());
        let by_hand = refine_with_real_poles(
            &[&y],
            fs,
            &ssi.modes,
            &ssi.real_poles,
            &RefineOptions::default(),
        )
        .unwrap();
        assert_eq!(a.refined.as_ref(), Some(&by_hand));
        let text = a.to_string();
        assert!(
            text.starts_with("20 block rows: correlations up to lag 39"),
            "{text}"
        );
        let none = analyze(&[&y], fs, &opts.clone().with_refine(None)).unwrap();
        assert!(none.refined.is_none() && none.not_refined.is_none());
    }

    /// A record long enough for SSI but too short to refine its modes: SSI's result stands,
    /// and the report says why there is no refinement.
    #[test]
    fn a_refinement_that_cannot_run_leaves_ssi_and_says_why() {
        let fs = 50.0;
        let y: Vec<f64> = (0..150)
            .map(|n| {
                let t = n as f64 / fs;
                (-0.4 * t).exp() * (2.0 * std::f64::consts::PI * 3.0 * t).cos()
                    + (-0.3 * t).exp() * (2.0 * std::f64::consts::PI * 7.0 * t).sin()
            })
            .collect();
        let opts = AnalysisOptions::default().with_ssi(SsiOptions {
            max_order: Some(10),
            min_cluster_size: Some(2),
            ..SsiOptions::default()
        });
        let a = analyze(&[&y], fs, &opts).unwrap();
        assert!(!a.ssi.modes.is_empty(), "{a}");
        assert!(a.refined.is_none());
        let why = a.not_refined.as_deref().unwrap_or_default();
        assert!(why.contains("samples"), "{why}");
        assert!(a.to_string().contains("not refined: "));
    }
}
