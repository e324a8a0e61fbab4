//! A structure whose linear stiffness changes over the record (ageing, temperature, damage),
//! simulated the way the project makes its records: the input interpolated to the fine rate
//! (exactly for one period of a periodic signal, by the windowed sinc of
//! [`crate::resample::interpolate_band_limited`] otherwise), RK4 there in pieces, each with
//! its own stiffness, the state carried across, and MATLAB's FIR decimation back to the
//! sample rate. With no drift it is one piece: the stationary record.

use hyst_model::{Oscillator, State};

use crate::resample::{decimate_stages, interpolate_band_limited, upsample_periodic};
use crate::{Input, SimError, SimOptions, simulate_from};

/// `n` samples at `fs` of the response of `model` to `input` (a [`Input::Periodic`] period,
/// repeated, or a [`Input::BandLimited`] record), simulated at `stages`' product times the
/// rate and FIR-decimated in those stages, the linear stiffness k multiplied by
/// 1 + `drift`·t/T (t from the first to the last sample T) in `pieces` steps (each piece
/// takes the value at its middle).
pub fn simulate_drifting(
    model: &Oscillator,
    input: Input<'_>,
    fs: f64,
    n: usize,
    stages: &[usize],
    drift: f64,
    pieces: usize,
) -> Result<Vec<f64>, SimError> {
    let r = crate::stages_product(stages);
    crate::check_oversample(r)?;
    if n < 2 {
        return Err(SimError::InvalidSignal {
            what: "samples",
            value: n as f64,
        });
    }
    if !drift.is_finite() || drift <= -1.0 {
        return Err(SimError::InvalidSignal {
            what: "stiffness drift",
            value: drift,
        });
    }
    let total = (n - 1) * r + 1;
    let fine: Vec<f64> = match input {
        Input::Periodic(p) => {
            if p.is_empty() {
                return Err(SimError::EmptyInput);
            }
            upsample_periodic(p, r)
                .iter()
                .cycle()
                .take(total)
                .copied()
                .collect()
        }
        Input::BandLimited(u) => {
            if u.len() < n {
                return Err(SimError::InputTooShort {
                    requested: n,
                    available: u.len(),
                });
            }
            interpolate_band_limited(&u[..n], r)
        }
        Input::Sampled(_) => {
            return Err(SimError::UnsupportedInput {
                what: "a linearly interpolated record",
            });
        }
        Input::Function(_) => {
            return Err(SimError::UnsupportedInput { what: "a function" });
        }
        Input::Interpolated { .. } => {
            return Err(SimError::UnsupportedInput {
                what: "an interpolated record",
            });
        }
    };
    let opts = SimOptions {
        oversample: 1,
        ..SimOptions::default()
    };
    let pieces = pieces.clamp(1, total - 1);
    let mut y = Vec::with_capacity(total);
    let mut s = State::zeros();
    for p in 0..pieces {
        let (a, b) = (p * (total - 1) / pieces, (p + 1) * (total - 1) / pieces);
        let mut m = *model;
        m.stiffness *= 1.0 + drift * (a + b) as f64 / (2.0 * (total - 1) as f64);
        let (piece, end) = simulate_from(
            &m,
            s,
            Input::Sampled(&fine[a..=b]),
            fs * r as f64,
            b - a + 1,
            &opts,
        )?;
        y.extend_from_slice(&piece[usize::from(p > 0)..]);
        s = end;
    }
    let mut out = decimate_stages(&y, stages);
    out.truncate(n);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Decimation;
    use crate::excitation::band_limited_noise;

    /// Without drift, one piece or many give the record `simulate` makes with the same
    /// oversampling and FIR decimation; with drift the record differs, and more where the
    /// stiffness has moved further.
    #[test]
    fn no_drift_is_the_stationary_record_and_drift_grows_over_it() {
        let fs = 750.0;
        let n = 4096;
        let u = band_limited_noise(n, fs, 5.0, 150.0, 50.0, 3).unwrap();
        let o = Oscillator::benchmark();
        let opts = SimOptions {
            oversample: 20,
            decimation: Decimation::Fir(vec![2, 2, 5]),
            ..SimOptions::default()
        };
        let reference = crate::simulate(&o, Input::BandLimited(&u), fs, n, &opts).unwrap();
        let rms = |v: &[f64]| (v.iter().map(|a| a * a).sum::<f64>() / v.len() as f64).sqrt();
        for pieces in [1, 16] {
            let y = simulate_drifting(&o, Input::BandLimited(&u), fs, n, &[2, 2, 5], 0.0, pieces)
                .unwrap();
            let d: Vec<f64> = y.iter().zip(&reference).map(|(a, b)| a - b).collect();
            // Both sample the same interpolated input: one with linear interpolation of its
            // fine samples at the RK4 midpoints (here), one with the sinc itself there; 1e-4 of
            // the response bounds that difference at 20× oversampling.
            assert!(
                rms(&d) < 1e-4 * rms(&reference),
                "{pieces} pieces: {}",
                rms(&d)
            );
        }
        let y =
            simulate_drifting(&o, Input::BandLimited(&u), fs, n, &[2, 2, 5], -0.08, 16).unwrap();
        let d: Vec<f64> = y.iter().zip(&reference).map(|(a, b)| a - b).collect();
        let (early, late) = (rms(&d[..n / 4]), rms(&d[3 * n / 4..]));
        assert!(late > 3.0 * early, "{early} then {late}");
        assert!(matches!(
            simulate_drifting(&o, Input::Sampled(&u), fs, n, &[2], 0.0, 1),
            Err(SimError::UnsupportedInput { .. })
        ));
    }
}
