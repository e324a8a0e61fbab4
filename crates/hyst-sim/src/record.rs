//! The response record of an oscillator to a force record, the input known between its
//! samples as the record is: one period of a periodic signal (simulated to steady state), a
//! measured force behind an anti-aliasing filter (band-limited), or samples joined by straight
//! lines (how the project's synthetic records are made). `hyst simulate` and the Python
//! package's `hyst.simulate` both run this.

use hyst_model::Oscillator;

use crate::{Decimation, Input, SimError, SimOptions, simulate, steady_state_period};

/// How a force record is known between its samples.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
#[non_exhaustive]
pub enum InputKind {
    /// One period of a periodic signal, interpolated exactly; the response is one period of
    /// the steady state.
    Periodic,
    /// A band-limited signal (a measured force): windowed-sinc interpolation.
    BandLimited,
    /// Straight lines between the samples.
    Linear,
}

/// The steady state is reached when two successive periods differ by less than this
/// (relative RMS)...
pub const STEADY_STATE_TOLERANCE: f64 = 1e-10;
/// ... within this many periods.
pub const STEADY_STATE_MAX_PERIODS: usize = 200;

/// The response of `model` from rest to the force `u` sampled at `fs`, one output sample per
/// input sample (for [`InputKind::Periodic`], one steady-state period).
pub fn response(
    model: &Oscillator,
    u: &[f64],
    fs: f64,
    kind: InputKind,
    opts: &SimOptions,
) -> Result<Vec<f64>, SimError> {
    match kind {
        InputKind::Periodic => Ok(steady_state_period(
            model,
            u,
            fs,
            opts,
            STEADY_STATE_TOLERANCE,
            STEADY_STATE_MAX_PERIODS,
        )?
        .y),
        InputKind::BandLimited => simulate(model, Input::BandLimited(u), fs, u.len(), opts),
        InputKind::Linear => simulate(model, Input::Sampled(u), fs, u.len(), opts),
    }
}

impl Decimation {
    /// MATLAB-style FIR decimation by `oversample` in stages: its prime factors, ascending
    /// (20 → 2, 2, 5, as the benchmark decimated its multisines).
    pub fn fir_stages(oversample: usize) -> Decimation {
        let mut stages = Vec::new();
        let (mut n, mut p) = (oversample, 2);
        while n > 1 {
            while n.is_multiple_of(p) {
                stages.push(p);
                n /= p;
            }
            p += 1;
        }
        Decimation::Fir(stages)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fir_stages_are_the_prime_factors_ascending() {
        assert_eq!(Decimation::fir_stages(20), Decimation::Fir(vec![2, 2, 5]));
        assert_eq!(Decimation::fir_stages(7), Decimation::Fir(vec![7]));
        assert_eq!(Decimation::fir_stages(1), Decimation::Fir(vec![]));
    }

    /// Each kind is the call it names: the same samples, bit for bit.
    #[test]
    fn each_kind_is_its_simulation() {
        let m = Oscillator::benchmark();
        let u: Vec<f64> = (0..256).map(|k| 40.0 * (0.3 * k as f64).sin()).collect();
        let o = SimOptions::default();
        let steady = steady_state_period(&m, &u, 750.0, &o, 1e-10, 200)
            .unwrap()
            .y;
        assert_eq!(
            response(&m, &u, 750.0, InputKind::Periodic, &o).unwrap(),
            steady
        );
        let band = simulate(&m, Input::BandLimited(&u), 750.0, 256, &o).unwrap();
        assert_eq!(
            response(&m, &u, 750.0, InputKind::BandLimited, &o).unwrap(),
            band
        );
        let lin = simulate(&m, Input::Sampled(&u), 750.0, 256, &o).unwrap();
        assert_eq!(response(&m, &u, 750.0, InputKind::Linear, &o).unwrap(), lin);
    }
}
