//! Which refined estimates are not modes: a likelihood fit spends poles on whatever the
//! record holds that its model lacks (a filter's roll-off at Nyquist, drift near 0 Hz, a
//! spectrum's tilt), and those poles come out as "modes" damped at the limit, at the band's
//! edges, or with standard errors larger than their values. They stay in the fit (they are
//! part of what explains the spectrum) but are not reported as modes; the report lists each
//! with its reason.

use crate::{RefinedMode, RefinedRealPole, Refinement};

/// Periods of a mode the whole record must hold, and frequency bins between a mode and
/// Nyquist, for the mode not to be "at" 0 Hz or Nyquist.
const EDGE_BINS: f64 = 5.0;

/// Share of Nyquist within which a mode is "next to" it, whatever the resolution.
const NEAR_NYQUIST: f64 = 0.01;

/// Why a refined estimate is not reported as a mode or real pole.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case", tag = "reason"))]
#[non_exhaustive]
pub enum NotPhysical {
    /// Damped at or above the limit the stabilization diagram uses (`max_damping`).
    DampingAtLimit {
        /// The damping ratio.
        damping_ratio: f64,
        /// The limit.
        limit: f64,
    },
    /// At or next to Nyquist: within 1 % of it, or 5 frequency bins.
    AtNyquist {
        /// The frequency (Hz).
        frequency_hz: f64,
        /// Nyquist (Hz).
        nyquist_hz: f64,
    },
    /// At or next to 0 Hz: the record holds fewer than 5 of its periods.
    AtZero {
        /// The frequency (Hz).
        frequency_hz: f64,
    },
    /// The Fisher information gives it no standard error: the record does not determine it.
    NoStandardError,
    /// A standard error larger than the value itself.
    ErrorAboveValue {
        /// What: "frequency", "damping ratio" or "real pole".
        quantity: String,
        /// The value.
        value: f64,
        /// Its standard error.
        standard_error: f64,
    },
    /// A real pole faster than Nyquist, −λ > π f_s: its decay is over within a sample.
    RealPoleBeyondNyquist {
        /// λ (rad/s).
        lambda: f64,
        /// π f_s (rad/s).
        limit: f64,
    },
    /// A real pole slower than the record, −λ < f_s/N: it does not decay within it.
    RealPoleSlowerThanRecord {
        /// λ (rad/s).
        lambda: f64,
        /// f_s/N (rad/s).
        limit: f64,
    },
    /// A real pole equal to one listed before it (two SSI real poles fitted to one).
    RepeatedRealPole {
        /// λ (rad/s).
        lambda: f64,
    },
}

impl std::fmt::Display for NotPhysical {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            NotPhysical::DampingAtLimit {
                damping_ratio,
                limit,
            } => write!(
                f,
                "damping ratio {damping_ratio:.3} at or above the diagram's limit {limit}"
            ),
            NotPhysical::AtNyquist {
                frequency_hz,
                nyquist_hz,
            } => write!(
                f,
                "{frequency_hz:.4} Hz is at Nyquist ({nyquist_hz:.4} Hz): a filter's roll-off or aliasing, not a mode"
            ),
            NotPhysical::AtZero { frequency_hz } => write!(
                f,
                "{frequency_hz:.4} Hz: the record holds fewer than {EDGE_BINS} of its periods (drift, not a mode)"
            ),
            NotPhysical::NoStandardError => {
                write!(f, "the record does not determine it (no standard error)")
            }
            NotPhysical::ErrorAboveValue {
                quantity,
                value,
                standard_error,
            } => write!(
                f,
                "its {quantity}'s standard error {standard_error:.3e} exceeds the value {value:.3e}"
            ),
            NotPhysical::RealPoleBeyondNyquist { lambda, limit } => write!(
                f,
                "{lambda:.4e} rad/s decays faster than Nyquist allows (−λ > π·fs = {limit:.1} rad/s)"
            ),
            NotPhysical::RealPoleSlowerThanRecord { lambda, limit } => write!(
                f,
                "{lambda:.4e} rad/s does not decay within the record (−λ < fs/N = {limit:.3e} rad/s)"
            ),
            NotPhysical::RepeatedRealPole { lambda } => {
                write!(f, "{lambda:.4} rad/s repeats a real pole listed before it")
            }
        }
    }
}

/// A refined estimate that is not reported, and why.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct NotReported {
    /// Index in [`Refinement::modes`] (`real_pole` false) or [`Refinement::real_poles`].
    pub index: usize,
    /// Whether it is a real pole.
    pub real_pole: bool,
    /// Every reason that applies, the first the most telling.
    pub reasons: Vec<NotPhysical>,
}

/// The refined modes and real poles of `r` that are not physical, for a record of
/// `samples` samples at `fs` Hz analysed with the damping limit `max_damping`.
pub fn not_physical(r: &Refinement, fs: f64, samples: usize, max_damping: f64) -> Vec<NotReported> {
    let mut out: Vec<NotReported> = r
        .modes
        .iter()
        .enumerate()
        .filter_map(|(index, m)| {
            let reasons = mode_reasons(m, fs, samples, max_damping);
            (!reasons.is_empty()).then_some(NotReported {
                index,
                real_pole: false,
                reasons,
            })
        })
        .collect();
    for (index, p) in r.real_poles.iter().enumerate() {
        let mut reasons = real_pole_reasons(p, fs, samples);
        if r.real_poles[..index]
            .iter()
            .any(|q| (q.lambda - p.lambda).abs() <= 1e-9 * p.lambda.abs())
        {
            reasons.push(NotPhysical::RepeatedRealPole { lambda: p.lambda });
        }
        if !reasons.is_empty() {
            out.push(NotReported {
                index,
                real_pole: true,
                reasons,
            });
        }
    }
    out
}

fn mode_reasons(m: &RefinedMode, fs: f64, samples: usize, max_damping: f64) -> Vec<NotPhysical> {
    let mut reasons = Vec::new();
    let nyquist = fs / 2.0;
    let bin = fs / samples.max(1) as f64;
    if m.damping_ratio >= max_damping {
        reasons.push(NotPhysical::DampingAtLimit {
            damping_ratio: m.damping_ratio,
            limit: max_damping,
        });
    }
    if nyquist - m.frequency_hz <= (EDGE_BINS * bin).max(NEAR_NYQUIST * nyquist) {
        reasons.push(NotPhysical::AtNyquist {
            frequency_hz: m.frequency_hz,
            nyquist_hz: nyquist,
        });
    }
    if m.frequency_hz < EDGE_BINS * bin {
        reasons.push(NotPhysical::AtZero {
            frequency_hz: m.frequency_hz,
        });
    }
    match (m.frequency_se_hz, m.damping_se) {
        (Some(sf), Some(sd)) => {
            for (quantity, value, se) in [
                ("frequency", m.frequency_hz, sf),
                ("damping ratio", m.damping_ratio, sd),
            ] {
                // A NaN standard error is no bound either.
                if se.is_nan() || se > value.abs() {
                    reasons.push(NotPhysical::ErrorAboveValue {
                        quantity: quantity.into(),
                        value,
                        standard_error: se,
                    });
                }
            }
        }
        _ => reasons.push(NotPhysical::NoStandardError),
    }
    reasons
}

fn real_pole_reasons(p: &RefinedRealPole, fs: f64, samples: usize) -> Vec<NotPhysical> {
    let mut reasons = Vec::new();
    let rho = -p.lambda;
    let fastest = std::f64::consts::PI * fs;
    let slowest = fs / samples.max(1) as f64;
    if rho > fastest {
        reasons.push(NotPhysical::RealPoleBeyondNyquist {
            lambda: p.lambda,
            limit: fastest,
        });
    }
    if rho < slowest {
        reasons.push(NotPhysical::RealPoleSlowerThanRecord {
            lambda: p.lambda,
            limit: slowest,
        });
    }
    match p.lambda_se {
        Some(se) if se <= rho.abs() => {}
        Some(se) => reasons.push(NotPhysical::ErrorAboveValue {
            quantity: "real pole".into(),
            value: p.lambda,
            standard_error: se,
        }),
        None => reasons.push(NotPhysical::NoStandardError),
    }
    reasons
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Complex64;

    fn mode(f: f64, zeta: f64, se: Option<(f64, f64)>) -> RefinedMode {
        let w = 2.0 * std::f64::consts::PI * f;
        RefinedMode {
            source: None,
            frequency_hz: f,
            damping_ratio: zeta,
            frequency_se_hz: se.map(|s| s.0),
            damping_se: se.map(|s| s.1),
            lambda: Complex64::new(-zeta * w, w * (1.0 - zeta * zeta).sqrt()),
            shape: None,
            shape_se: None,
            mpc: None,
            evidence: 100.0,
        }
    }

    fn pole(lambda: f64, se: Option<f64>) -> RefinedRealPole {
        RefinedRealPole {
            source: 0,
            lambda,
            lambda_se: se,
            evidence: 100.0,
        }
    }

    /// Each reason the issue lists is found, and a plain mode passes: the cases of a
    /// building's record (a real pole at −956 ± 7e20 rad/s, damping 1.000) and of a decimated
    /// steel frame (16.000 Hz at Nyquist 16 Hz).
    #[test]
    fn each_kind_of_nonsense_is_named() {
        let (fs, n) = (32.0, 7680);
        let r = Refinement {
            modes: vec![
                mode(1.2306, 0.0046, Some((0.0019, 0.0016))),
                mode(0.58, 1.0, Some((0.01, 0.01))),
                mode(16.0, 0.01, Some((6.0, 0.01))),
                mode(0.01, 0.02, Some((0.001, 0.001))),
                mode(4.0, 0.002, None),
                mode(5.0, 0.001, Some((0.001, 0.002))),
            ],
            dropped: vec![],
            penalty: 50.0,
            real_poles: vec![
                pole(-3.0, Some(0.5)),
                pole(-956.0, Some(7e20)),
                pole(-3.0, Some(0.5)),
                pole(-0.001, Some(1e-4)),
            ],
            dropped_real_poles: vec![],
            real_pole_penalty: 25.0,
            neg_log_likelihood: 0.0,
            misfit: 0.01,
            frequencies: n / 2,
            iterations: 1,
            joint: false,
            combinations: None,
            bands: 1,
        };
        let bad = not_physical(&r, fs, n, 0.5);
        let modes: Vec<usize> = bad
            .iter()
            .filter(|b| !b.real_pole)
            .map(|b| b.index)
            .collect();
        assert_eq!(modes, vec![1, 2, 3, 4, 5]);
        assert!(matches!(
            bad[0].reasons[0],
            NotPhysical::DampingAtLimit { .. }
        ));
        assert_eq!(bad[1].reasons.len(), 1);
        assert!(matches!(bad[1].reasons[0], NotPhysical::AtNyquist { .. }));
        assert!(matches!(bad[2].reasons[0], NotPhysical::AtZero { .. }));
        assert_eq!(bad[3].reasons, vec![NotPhysical::NoStandardError]);
        assert!(matches!(
            bad[4].reasons[0],
            NotPhysical::ErrorAboveValue { .. }
        ));
        let poles: Vec<usize> = bad
            .iter()
            .filter(|b| b.real_pole)
            .map(|b| b.index)
            .collect();
        assert_eq!(poles, vec![1, 2, 3]);
        assert!(matches!(
            bad[5].reasons[0],
            NotPhysical::RealPoleBeyondNyquist { .. }
        ));
        assert!(matches!(
            bad[6].reasons[0],
            NotPhysical::RepeatedRealPole { .. }
        ));
        assert!(matches!(
            bad[7].reasons[0],
            NotPhysical::RealPoleSlowerThanRecord { .. }
        ));
        assert!(bad[5].reasons[1].to_string().contains("standard error"));
    }
}
