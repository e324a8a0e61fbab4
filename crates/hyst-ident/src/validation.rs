//! Step 5: a model simulated with a measured input and scored by ε (eq. 39).

use crate::*;

/// A model's error against a measured output.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Validation {
    /// ε of eq. (39): RMS error divided by the range of the measured output (a fraction).
    pub epsilon: f64,
    /// RMS error in the output's units.
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
