//! The whole job on one record ([`amplitude_analysis`]): the modes by [`covssi`], the
//! ones asked for followed, and the text `hyst amplitude` prints.

use std::fmt;

use super::{AmplitudeOptions, AmplitudeReport, ModeCurve, ModeToFollow, amplitude_curves};

/// What [`amplitude_analysis`] finds.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct AmplitudeAnalysis {
    /// Where the modes followed came from: `"refined"` (covssi's maximum likelihood) or
    /// `"ssi"`.
    pub modes_from: String,
    /// Frequencies asked for that no identified mode lies within 5 % of (followed there,
    /// with every channel weighted alike).
    pub unidentified: Vec<f64>,
    /// The curves.
    pub curves: AmplitudeReport,
}

/// Identify `y`'s modes (`analysis`), then follow those nearest `follow` (Hz; every
/// reported mode when empty) through their amplitudes.
pub fn amplitude_analysis(
    y: &[&[f64]],
    fs: f64,
    analysis: &covssi::AnalysisOptions,
    opts: &AmplitudeOptions,
    follow: &[f64],
) -> Result<AmplitudeAnalysis, crate::IdentError> {
    super::check_channels(y)?;
    let modal = covssi::analyze(y, fs, analysis)?;
    let reported = modal.reported_modes();
    let modes_from = if modal.reported_refinement().is_some() {
        "refined"
    } else {
        "ssi"
    };
    let as_follow = |m: &covssi::ReportedMode| ModeToFollow {
        frequency_hz: m.frequency_hz,
        damping_ratio: m.damping_ratio,
        shape: m.shape.clone(),
    };
    let identified: Vec<ModeToFollow> = reported.iter().map(as_follow).collect();
    let mut unidentified = Vec::new();
    let mut followed = Vec::new();
    let mut others: Vec<ModeToFollow> = Vec::new();
    if follow.is_empty() {
        followed = identified;
    } else {
        let mut taken = vec![false; identified.len()];
        for &f in follow {
            let near = (0..identified.len())
                .filter(|&i| (identified[i].frequency_hz - f).abs() <= 0.05 * f)
                .min_by(|&a, &b| {
                    (identified[a].frequency_hz - f)
                        .abs()
                        .total_cmp(&(identified[b].frequency_hz - f).abs())
                });
            match near {
                Some(i) => {
                    taken[i] = true;
                    followed.push(identified[i].clone());
                }
                None => {
                    unidentified.push(f);
                    followed.push(ModeToFollow {
                        frequency_hz: f,
                        damping_ratio: 0.01,
                        shape: None,
                    });
                }
            }
        }
        others.extend(
            (0..identified.len())
                .filter(|&i| !taken[i])
                .map(|i| identified[i].clone()),
        );
    }
    let curves = amplitude_curves(y, fs, &followed, &others, opts)?;
    Ok(AmplitudeAnalysis {
        modes_from: modes_from.into(),
        unidentified,
        curves,
    })
}

impl fmt::Display for AmplitudeAnalysis {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "modes from {}, as `hyst ssi` reports them",
            if self.modes_from == "refined" {
                "the maximum-likelihood refinement"
            } else {
                "SSI"
            }
        )?;
        for u in &self.unidentified {
            writeln!(
                f,
                "note: no identified mode within 5 % of {u} Hz: followed there with every channel weighted alike"
            )?;
        }
        self.curves.fmt(f)
    }
}

impl fmt::Display for AmplitudeReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let unit = match (self.measured, self.amplitude_of) {
            (a, b) if a == b => format!("{}, in the record's unit", a.name()),
            (a, b) => format!(
                "{} from the measured {} (the record's unit × s^{})",
                b.name(),
                a.name(),
                a.order() - b.order()
            ),
        };
        writeln!(
            f,
            "amplitude: of each mode's coordinate ({unit}); ± one standard error (jackknife over stretches of the record)"
        )?;
        for c in &self.modes {
            c.fmt(f)?;
        }
        Ok(())
    }
}

impl fmt::Display for ModeCurve {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "mode {:.4} Hz (damping ratio {:.2} %), filtered to {:.3}–{:.3} Hz:",
            self.mode.frequency_hz,
            100.0 * self.mode.damping_ratio,
            self.band_hz.0,
            self.band_hz.1
        )?;
        if !self.points.is_empty() {
            writeln!(
                f,
                "  {:>11}  {:>20}  {:>18}  {:>8}",
                "amplitude", "frequency (Hz)", "damping ratio (%)", "triggers"
            )?;
        }
        for p in &self.points {
            writeln!(
                f,
                "  {:>11.4e}  {:>10.4} ± {:<7.4}  {:>7.3} ± {:<7.3}  {:>8}",
                p.amplitude,
                p.frequency_hz,
                p.frequency_se_hz,
                100.0 * p.damping_ratio,
                100.0 * p.damping_se,
                p.triggers
            )?;
        }
        if let Some(l) = &self.linearity {
            let (a0, a1) = self
                .points
                .iter()
                .fold((f64::INFINITY, 0.0f64), |(lo, hi), p| {
                    (lo.min(p.amplitude), hi.max(p.amplitude))
                });
            writeln!(
                f,
                "  from {a0:.3e} to {a1:.3e}: frequency {:+.4} ± {:.4} Hz (p = {:.2e}), damping ratio {:+.3} ± {:.3} % (p = {:.2e}): {}",
                l.frequency.change,
                l.frequency.change_se,
                l.frequency.p_value,
                100.0 * l.damping.change,
                100.0 * l.damping.change_se,
                l.damping.p_value,
                if l.linear {
                    "no significant change: linear over these amplitudes"
                } else {
                    "amplitude-dependent"
                }
            )?;
        }
        for n in &self.notes {
            writeln!(f, "  note: {n}")?;
        }
        Ok(())
    }
}
