//! Step 5: a model simulated with a measured input and scored by ε (eq. 39).

use crate::{IdentError, periodic};
use hyst_model::Oscillator;
use hyst_sim::{Decimation, Input, SimOptions};

/// A model's error against a measured output.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Validation {
    /// ε of eq. (39): RMS error divided by the range of the measured output (a fraction).
    #[cfg_attr(feature = "serde", serde(with = "crate::nullable"))]
    pub epsilon: f64,
    /// RMS error in the output's units.
    #[cfg_attr(feature = "serde", serde(with = "crate::nullable"))]
    pub rms: f64,
}

/// ε and RMS of `yhat` against `y`.
pub fn epsilon(yhat: &[f64], y: &[f64]) -> Validation {
    let n = y.len().min(yhat.len()).max(1) as f64;
    let rms = (yhat
        .iter()
        .zip(y)
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f64>()
        / n)
        .sqrt();
    let (lo, hi) = y
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
            (l.min(*v), h.max(*v))
        });
    Validation {
        epsilon: rms / (hi - lo),
        rms,
    }
}

/// The response of `model` to the input `u` (RK4, 20 sub-steps): for a `periodic` record one
/// steady-state period, otherwise from rest. Between samples the input is taken as
/// band-limited, as a measured or designed excitation is: exactly for a periodic record, by a
/// windowed sinc otherwise ([`hyst_sim::Input::BandLimited`]; linear interpolation would
/// misstate the force by about 1 %).
pub fn simulate_model(
    model: &Oscillator,
    u: &[f64],
    fs: f64,
    periodic: bool,
) -> Result<Vec<f64>, IdentError> {
    let opts = SimOptions {
        decimation: Decimation::Subsample,
        ..SimOptions::default()
    };
    Ok(if periodic {
        hyst_sim::steady_state_period(model, u, fs, &opts, 1e-9, 200)?.y
    } else {
        hyst_sim::simulate(model, Input::BandLimited(u), fs, u.len(), &opts)?
    })
}

/// Step 5: simulate `model` with input `u` ([`simulate_model`]) and compare with `y`.
pub fn validate(
    model: &Oscillator,
    u: &[f64],
    y: &[f64],
    fs: f64,
    periodic: bool,
) -> Result<Validation, IdentError> {
    if u.len() != y.len() {
        return Err(IdentError::LengthMismatch {
            input: u.len(),
            output: y.len(),
        });
    }
    Ok(epsilon(&simulate_model(model, u, fs, periodic)?, y))
}

/// A record models are validated on: the measured input and output, and how it is simulated.
#[derive(Debug, Clone, PartialEq)]
pub struct ValidationRecord {
    /// What to call it in a report (its file).
    pub name: String,
    /// The measured input.
    pub u: Vec<f64>,
    /// The measured output.
    pub y: Vec<f64>,
    /// One steady-state period (or a whole number of them) of a periodic input: simulated to
    /// steady state; otherwise from rest.
    pub periodic: bool,
}

impl ValidationRecord {
    /// A record whose kind is told from its input ([`periodic::periodicity`]).
    pub fn new(name: impl Into<String>, u: Vec<f64>, y: Vec<f64>) -> Self {
        let periodic = matches!(
            periodic::periodicity(&u),
            periodic::Periodicity::Periodic { .. }
        );
        ValidationRecord {
            name: name.into(),
            u,
            y,
            periodic,
        }
    }
}

/// `model` validated on every record, in order: ε, or why it could not be simulated.
pub fn validate_all(
    model: &Oscillator,
    records: &[ValidationRecord],
    fs: f64,
) -> Vec<Result<Validation, IdentError>> {
    records
        .iter()
        .map(|r| validate(model, &r.u, &r.y, fs, r.periodic))
        .collect()
}

/// Which of several candidates' validations ([`validate_all`]) is best: the lowest ε on the
/// first record, a failed simulation worst; the first candidate when there are no records
/// (`None` when there are no candidates).
pub fn best_by_validation(scores: &[Vec<Result<Validation, IdentError>>]) -> Option<usize> {
    let first = |rows: &Vec<Result<Validation, IdentError>>| match rows.first() {
        Some(Ok(v)) => v.epsilon,
        _ => f64::INFINITY,
    };
    (0..scores.len()).min_by(|&i, &j| first(&scores[i]).total_cmp(&first(&scores[j])))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_best_candidate_is_the_lowest_error_on_the_first_record() {
        let ok = |e: f64| Ok(Validation { epsilon: e, rms: e });
        let failed = || {
            Err(IdentError::LengthMismatch {
                input: 1,
                output: 2,
            })
        };
        let scores = vec![
            vec![ok(0.03), ok(0.001)],
            vec![ok(0.02), ok(0.5)],
            vec![failed(), ok(0.0)],
        ];
        assert_eq!(best_by_validation(&scores), Some(1));
        assert_eq!(best_by_validation(&[vec![], vec![]]), Some(0));
        assert_eq!(best_by_validation(&[]), None);
    }

    #[test]
    fn a_record_s_kind_is_told_from_its_input() {
        let u = hyst_sim::excitation::Multisine::band(4096, 750.0, 5.0, 150.0, 50.0)
            .unwrap()
            .generate(1)
            .unwrap();
        let r = ValidationRecord::new("anything.csv", u.clone(), u.clone());
        assert!(r.periodic);
        let noise =
            hyst_sim::excitation::band_limited_noise(4096, 750.0, 5.0, 150.0, 50.0, 2).unwrap();
        assert!(!ValidationRecord::new("multisine.csv", noise.clone(), noise).periodic);
    }
}
