//! The battery's measurement chains, made apart from the loop's own ([`hyst_sim`] applies a
//! model's chain in the time domain, sub-step by sub-step): here the chain's frequency
//! response multiplies the decimated record's spectrum, zero-padded to twice its length so
//! that nothing wraps around. The record starts at rest, so the padding ahead is exact; the
//! samples near its end lack the future a fractional delay's sinc reaches into, so the
//! record is made [`TAIL`] samples longer and cut after the chain.

use realfft::RealFftPlanner;
use realfft::num_complex::Complex;

/// Samples made past the record's end and cut after the chain: a fractional delay's sinc
/// has fallen to under 1/(π·1024) = 3e-4 of a jump there, on a signal that has none.
pub const TAIL: usize = 1024;

/// A measurement chain between the structure's displacement and the record.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Chain {
    /// A delay d (s) and a first-order lag τ (s): $e^{-i\omega d}/(1 + i\omega\tau)$.
    DelayLag { delay: f64, lag: f64 },
    /// A second-order Butterworth low-pass with its corner at `corner` Hz, on the output
    /// channel only: an anti-aliasing filter the input channel does not share.
    Butterworth2 { corner: f64 },
}

impl Chain {
    /// The chain's response at angular frequency ω (rad/s).
    fn response(&self, w: f64) -> Complex<f64> {
        match *self {
            Chain::DelayLag { delay, lag } => {
                Complex::from_polar(1.0, -w * delay) / Complex::new(1.0, w * lag)
            }
            Chain::Butterworth2 { corner } => {
                let r = w / (2.0 * std::f64::consts::PI * corner);
                Complex::new(1.0, 0.0) / Complex::new(1.0 - r * r, std::f64::consts::SQRT_2 * r)
            }
        }
    }

    /// `y` (sampled at `fs`, from rest) through the chain.
    pub fn apply(&self, y: &[f64], fs: f64) -> Vec<f64> {
        let m = 2 * y.len();
        let mut planner = RealFftPlanner::<f64>::new();
        let forward = planner.plan_fft_forward(m);
        let inverse = planner.plan_fft_inverse(m);
        let mut buf = vec![0.0; m];
        buf[..y.len()].copy_from_slice(y);
        let mut spec = forward.make_output_vec();
        forward
            .process(&mut buf, &mut spec)
            .expect("buffers of the planned length");
        for (k, s) in spec.iter_mut().enumerate() {
            let w = 2.0 * std::f64::consts::PI * k as f64 * fs / m as f64;
            *s *= self.response(w);
        }
        // The Nyquist bin of a real signal is real: keep the real part of its response.
        if let Some(last) = spec.last_mut() {
            *last = Complex::new(last.re, 0.0);
        }
        spec[0] = Complex::new(spec[0].re, 0.0);
        let mut out = inverse.make_output_vec();
        inverse
            .process(&mut spec, &mut out)
            .expect("buffers of the planned length");
        out.truncate(y.len());
        out.iter().map(|v| v / m as f64).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sine through a delay and a lag, away from the ends: the analytic gain and phase,
    /// to 1e-4 (the sine, cut at the record's start and end, is not band-limited there; its
    /// leakage falls as 1/distance from the cut).
    #[test]
    fn a_sine_gets_the_chains_gain_and_phase() {
        let (fs, n) = (750.0, 8192);
        let f = 25.0;
        let w = 2.0 * std::f64::consts::PI * f;
        let y: Vec<f64> = (0..n).map(|k| (w * k as f64 / fs).sin()).collect();
        let (delay, lag) = (0.4 / fs, 2e-4);
        let out = Chain::DelayLag { delay, lag }.apply(&y, fs);
        let gain = 1.0 / (1.0 + (w * lag).powi(2)).sqrt();
        let phase = w * delay + (w * lag).atan();
        let worst = (2000..6000)
            .map(|k| (out[k] - gain * (w * k as f64 / fs - phase).sin()).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-4, "{worst}");
    }
}
