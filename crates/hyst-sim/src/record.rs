//! The response record of an oscillator to a force record, the input known between its
//! samples as the record is: one period of a periodic signal (simulated to steady state), a
//! measured force behind an anti-aliasing filter (band-limited), or samples joined by straight
//! lines (how the project's synthetic records are made). `hyst simulate` and the Python
//! package's `hyst.simulate` both run this.

use hyst_model::Oscillator;

use crate::excitation::{add_noise, white_noise};
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

/// Sensor noise on a synthetic record: white, Gaussian.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum SensorNoise {
    /// None: the response as simulated.
    None,
    /// Of this standard deviation, in the record's unit.
    Std(f64),
    /// This fraction of the response's RMS (about zero, over the samples kept).
    OfRms(f64),
}

/// A synthetic record of an oscillator under a white force, as the project's tests of
/// identification make them: a Gaussian force of RMS `force_rms` ([`white_noise`], seed
/// `seed`) over `warm_up + samples` samples, the response from rest ([`response`], the force
/// known between samples as `input` says), the first `warm_up` samples of both dropped, then
/// [`SensorNoise`] (seed `noise_seed`) added to the response. One generator, so that a test's
/// record is said by its numbers rather than rebuilt in each test.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct WhiteForceRecord {
    /// The force's RMS (over all its samples, the warm-up's included).
    pub force_rms: f64,
    /// Samples kept.
    pub samples: usize,
    /// Samples simulated first and dropped (the start from rest).
    pub warm_up: usize,
    /// The force's seed.
    pub seed: u64,
    /// How the force is known between its samples.
    pub input: InputKind,
    /// The sensor noise on the response.
    pub noise: SensorNoise,
    /// The noise's seed.
    pub noise_seed: u64,
    /// The simulation's options.
    pub sim: SimOptions,
}

impl WhiteForceRecord {
    /// `samples` samples under a force of RMS `force_rms` (seed `seed`), from rest, straight
    /// lines between the force's samples, no noise (its seed `seed + 1` once given), the
    /// simulation's defaults.
    pub fn new(force_rms: f64, samples: usize, seed: u64) -> Self {
        WhiteForceRecord {
            force_rms,
            samples,
            warm_up: 0,
            seed,
            input: InputKind::Linear,
            noise: SensorNoise::None,
            noise_seed: seed.wrapping_add(1),
            sim: SimOptions::default(),
        }
    }

    /// This record with `warm_up` samples simulated first and dropped.
    pub fn with_warm_up(mut self, warm_up: usize) -> Self {
        self.warm_up = warm_up;
        self
    }

    /// This record with the force known between its samples as `input` says.
    pub fn with_input(mut self, input: InputKind) -> Self {
        self.input = input;
        self
    }

    /// This record with `noise` on the response.
    pub fn with_noise(mut self, noise: SensorNoise) -> Self {
        self.noise = noise;
        self
    }

    /// This record with the noise drawn from `seed`.
    pub fn with_noise_seed(mut self, seed: u64) -> Self {
        self.noise_seed = seed;
        self
    }

    /// This record simulated with `sim`.
    pub fn with_sim(mut self, sim: SimOptions) -> Self {
        self.sim = sim;
        self
    }

    /// The force and the noisy response of `model` at `fs` Hz, `samples` each.
    pub fn generate(&self, model: &Oscillator, fs: f64) -> Result<(Vec<f64>, Vec<f64>), SimError> {
        let total = self.warm_up.saturating_add(self.samples);
        let mut u = white_noise(total, self.force_rms, self.seed)?;
        let mut y = response(model, &u, fs, self.input, &self.sim)?;
        let u = u.split_off(self.warm_up.min(u.len()));
        let mut y = y.split_off(self.warm_up.min(y.len()));
        let std = match self.noise {
            SensorNoise::None => None,
            SensorNoise::Std(s) => Some(s),
            SensorNoise::OfRms(f) => {
                let n = y.len().max(1) as f64;
                Some(f * (y.iter().map(|v| v * v).sum::<f64>() / n).sqrt())
            }
        };
        if let Some(std) = std {
            add_noise(&mut y, std, self.noise_seed)?;
        }
        Ok((u, y))
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

    /// The record is its steps, bit for bit: the force drawn for warm-up and record, the
    /// response from rest, the warm-up cut from both, the noise added to what is kept.
    #[test]
    fn a_white_force_record_is_its_steps() {
        let m = Oscillator::benchmark();
        let (n, warm, fs) = (512, 128, 750.0);
        let o = SimOptions::default();
        let u_all = white_noise(n + warm, 20.0, 7).unwrap();
        let y_all = simulate(&m, Input::Sampled(&u_all), fs, n + warm, &o).unwrap();
        let rms = (y_all[warm..].iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
        let mut y = y_all[warm..].to_vec();
        add_noise(&mut y, 0.05 * rms, 99).unwrap();
        let made = WhiteForceRecord::new(20.0, n, 7)
            .with_warm_up(warm)
            .with_noise(SensorNoise::OfRms(0.05))
            .with_noise_seed(99)
            .generate(&m, fs)
            .unwrap();
        assert_eq!(made, (u_all[warm..].to_vec(), y));
        // No noise: the response itself; the noise's default seed is the force's + 1.
        let clean = WhiteForceRecord::new(20.0, n, 7).generate(&m, fs).unwrap();
        assert_eq!(
            clean.1,
            simulate(&m, Input::Sampled(&clean.0), fs, n, &o).unwrap()
        );
        let mut noisy = clean.1.clone();
        add_noise(&mut noisy, 1e-6, 8).unwrap();
        let given = WhiteForceRecord::new(20.0, n, 7)
            .with_noise(SensorNoise::Std(1e-6))
            .generate(&m, fs)
            .unwrap();
        assert_eq!(given.1, noisy);
    }
}
