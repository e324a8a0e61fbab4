//! Seeded, reproducible excitation signals.
//!
//! The random generator is Xoshiro256++ seeded by `seed_from_u64`, whose output is specified
//! and portable: the same seed gives the same signal on every machine.

use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use rand_distr::StandardNormal;
use realfft::RealFftPlanner;

use crate::SimError;

fn rng(seed: u64) -> Xoshiro256PlusPlus {
    Xoshiro256PlusPlus::seed_from_u64(seed)
}

/// `value` (of the parameter `what`) must be finite and not negative.
fn check_level(what: &'static str, value: f64) -> Result<(), SimError> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(SimError::InvalidSignal { what, value })
    }
}

/// An empty buffer with room for `n` samples: `n` = 0 and more than memory holds are errors
/// (a signal to simulate has samples; a failed allocation would abort the program).
fn signal_buffer(n: usize) -> Result<Vec<f64>, SimError> {
    if n == 0 {
        return Err(SimError::InvalidSignal {
            what: "samples",
            value: 0.0,
        });
    }
    let mut v = Vec::new();
    v.try_reserve_exact(n)
        .map_err(|_| SimError::TooLong { samples: n })?;
    Ok(v)
}

fn scale_to_rms(x: &mut [f64], rms: f64) {
    let cur = (x.iter().map(|v| v * v).sum::<f64>() / x.len().max(1) as f64).sqrt();
    if cur > 0.0 {
        let s = rms / cur;
        for v in x.iter_mut() {
            *v *= s;
        }
    }
}

/// Gaussian white noise of `n` samples, scaled so that its sample RMS is exactly `rms`.
pub fn white_noise(n: usize, rms: f64, seed: u64) -> Result<Vec<f64>, SimError> {
    check_level("rms", rms)?;
    let mut r = rng(seed);
    let mut x = signal_buffer(n)?;
    x.extend((0..n).map(|_| r.sample::<f64, _>(StandardNormal)));
    scale_to_rms(&mut x, rms);
    Ok(x)
}

/// Add Gaussian white measurement noise of standard deviation `std` to `y`.
pub fn add_noise(y: &mut [f64], std: f64, seed: u64) -> Result<(), SimError> {
    check_level("noise std", std)?;
    let mut r = rng(seed);
    for v in y.iter_mut() {
        let e: f64 = r.sample(StandardNormal);
        *v += std * e;
    }
    Ok(())
}

/// A random-phase multisine: flat amplitude on the DFT bins `first_bin..=last_bin` of a period
/// of `period` samples, phases uniform on [0, 2π), scaled to an RMS.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct Multisine {
    /// Samples per period.
    pub period: usize,
    /// First excited DFT bin (≥ 1).
    pub first_bin: usize,
    /// Last excited DFT bin (< period / 2).
    pub last_bin: usize,
    /// RMS of the signal.
    pub rms: f64,
}

impl Multisine {
    /// The Bouc-Wen benchmark's multisine: 8192 samples per period at 750 Hz, bins 55..=1639
    /// (5.04–150.06 Hz), at the given RMS (the benchmark uses 50 N).
    pub fn benchmark(rms: f64) -> Self {
        Multisine {
            period: 8192,
            first_bin: 55,
            last_bin: 1639,
            rms,
        }
    }

    /// Flat on the band [`f_lo`, `f_hi`] Hz at sampling rate `fs`: bins
    /// `ceil(f_lo·period/fs)..=floor(f_hi·period/fs)`.
    pub fn band(period: usize, fs: f64, f_lo: f64, f_hi: f64, rms: f64) -> Result<Self, SimError> {
        if !(fs.is_finite() && fs > 0.0) {
            return Err(SimError::NonPositiveRate { fs });
        }
        let first = (f_lo * period as f64 / fs).ceil().max(1.0) as usize;
        let last = (f_hi * period as f64 / fs).floor() as usize;
        // An edge that is NaN, or edges the wrong way round, make no band; every empty band
        // is one error.
        let unordered = f_lo.is_nan() || f_hi.is_nan() || f_lo > f_hi;
        if unordered || first > last || last.saturating_mul(2) >= period {
            return Err(SimError::EmptyBand {
                low_hz: f_lo,
                high_hz: f_hi,
                fs,
                period,
            });
        }
        let m = Multisine {
            period,
            first_bin: first,
            last_bin: last,
            rms,
        };
        m.check()?;
        Ok(m)
    }

    fn check(&self) -> Result<(), SimError> {
        check_level("rms", self.rms)?;
        // Saturating: a last bin past usize::MAX / 2 must fail, not wrap round and pass.
        if self.first_bin == 0
            || self.first_bin > self.last_bin
            || self.last_bin.saturating_mul(2) >= self.period
        {
            return Err(SimError::InvalidSignal {
                what: "multisine band (bins)",
                value: self.last_bin as f64,
            });
        }
        Ok(())
    }

    /// One period of a realization with the given seed.
    pub fn generate(&self, seed: u64) -> Result<Vec<f64>, SimError> {
        self.check()?;
        // The inverse FFT's buffers are allocated by realfft, which panics on a size beyond
        // memory: ask for the output's room first.
        drop(signal_buffer(self.period)?);
        let mut r = rng(seed);
        let n = self.period;
        let mut planner = RealFftPlanner::<f64>::new();
        let inv = planner.plan_fft_inverse(n);
        let mut spec = inv.make_input_vec();
        for bin in spec.iter_mut().take(self.last_bin + 1).skip(self.first_bin) {
            let phase: f64 = r.random::<f64>() * 2.0 * std::f64::consts::PI;
            *bin = realfft::num_complex::Complex::from_polar(1.0, phase);
        }
        let mut out = inv.make_output_vec();
        inv.process(&mut spec, &mut out)
            .expect("buffer sizes come from the plan");
        scale_to_rms(&mut out, self.rms);
        Ok(out)
    }
}

/// Band-limited Gaussian noise: `n` samples at `fs` whose spectrum is flat on average on
/// [`f_lo`, `f_hi`] Hz and zero elsewhere, scaled so that its sample RMS is exactly `rms`.
/// Made as the first half of a period of 2n samples with independent complex Gaussian DFT
/// coefficients on the band, so that the record is random, not periodic (a random force
/// behind a band-pass filter), and band-limited between its samples too.
pub fn band_limited_noise(
    n: usize,
    fs: f64,
    f_lo: f64,
    f_hi: f64,
    rms: f64,
    seed: u64,
) -> Result<Vec<f64>, SimError> {
    let period = n.checked_mul(2).ok_or(SimError::TooLong { samples: n })?;
    drop(signal_buffer(period)?);
    let band = Multisine::band(period, fs, f_lo, f_hi, rms)?;
    let mut r = rng(seed);
    let mut planner = RealFftPlanner::<f64>::new();
    let inv = planner.plan_fft_inverse(period);
    let mut spec = inv.make_input_vec();
    for bin in spec.iter_mut().take(band.last_bin + 1).skip(band.first_bin) {
        *bin = realfft::num_complex::Complex::new(
            r.sample::<f64, _>(StandardNormal),
            r.sample::<f64, _>(StandardNormal),
        );
    }
    let mut out = inv.make_output_vec();
    inv.process(&mut spec, &mut out)
        .expect("buffer sizes come from the plan");
    out.truncate(n);
    scale_to_rms(&mut out, rms);
    Ok(out)
}

/// Linear sine sweep $u(t) = a\sin(2\pi(f_0 t + (f_1 - f_0)t^2/(2T)))$ from `f0` to `f1` Hz
/// over `duration` seconds, evaluated at time `t`.
///
/// The benchmark's `sinesweep_val` is `Sweep { amplitude: 40, f0: 18, f1: 52, duration: 204 }`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct Sweep {
    /// Amplitude a.
    pub amplitude: f64,
    /// Start frequency (Hz).
    pub f0: f64,
    /// End frequency (Hz).
    pub f1: f64,
    /// Sweep duration T (s).
    pub duration: f64,
}

impl Sweep {
    /// The benchmark's validation sweep: 40 N, 18 → 52 Hz over 204 s.
    pub fn benchmark() -> Self {
        Sweep {
            amplitude: 40.0,
            f0: 18.0,
            f1: 52.0,
            duration: 204.0,
        }
    }

    /// Value at time `t` (s).
    pub fn at(&self, t: f64) -> f64 {
        let rate = (self.f1 - self.f0) / (2.0 * self.duration);
        self.amplitude * (2.0 * std::f64::consts::PI * (self.f0 * t + rate * t * t)).sin()
    }

    /// `n` samples at rate `fs`, starting at t = 0.
    pub fn sample(&self, n: usize, fs: f64) -> Result<Vec<f64>, SimError> {
        if !(fs.is_finite() && fs > 0.0) {
            return Err(SimError::NonPositiveRate { fs });
        }
        // A NaN or infinite parameter would give a record of NaN, written without complaint.
        check_level("sweep amplitude", self.amplitude)?;
        check_level("sweep start frequency", self.f0)?;
        check_level("sweep end frequency", self.f1)?;
        if !(self.duration.is_finite() && self.duration > 0.0) {
            return Err(SimError::InvalidSignal {
                what: "sweep duration",
                value: self.duration,
            });
        }
        let mut x = signal_buffer(n)?;
        x.extend((0..n).map(|k| self.at(k as f64 / fs)));
        Ok(x)
    }
}

/// The kinds of excitation [`ExcitationDesign::generate`] makes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
#[non_exhaustive]
pub enum ExcitationKind {
    /// Random-phase multisine flat on [f_min, f_max], periodic with `samples` samples
    /// ([`Multisine::band`]).
    #[default]
    Multisine,
    /// Gaussian white noise ([`white_noise`]).
    White,
    /// Linear sine sweep from f_min to f_max over the record, amplitude √2·rms ([`Sweep`]).
    Sweep,
}

impl ExcitationKind {
    /// The names, as the command line and the Python package spell them.
    pub const NAMES: [&'static str; 3] = ["multisine", "white", "sweep"];

    /// The kind named `name` (one of [`ExcitationKind::NAMES`]).
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "multisine" => Some(ExcitationKind::Multisine),
            "white" => Some(ExcitationKind::White),
            "sweep" => Some(ExcitationKind::Sweep),
            _ => None,
        }
    }
}

/// A generated excitation: its kind, level, length, seed and band. The defaults are the
/// benchmark's: a 50 N RMS multisine of 8192 samples on 5–150 Hz, seed 1.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
#[non_exhaustive]
pub struct ExcitationDesign {
    /// The kind.
    pub kind: ExcitationKind,
    /// RMS (N).
    pub rms: f64,
    /// Samples (a multisine: one period).
    pub samples: usize,
    /// Seed of the random generator.
    pub seed: u64,
    /// Lowest excited frequency (Hz; multisine and sweep).
    pub f_min: f64,
    /// Highest excited frequency (Hz; multisine and sweep).
    pub f_max: f64,
}

impl Default for ExcitationDesign {
    fn default() -> Self {
        ExcitationDesign {
            kind: ExcitationKind::Multisine,
            rms: 50.0,
            samples: 8192,
            seed: 1,
            f_min: 5.0,
            f_max: 150.0,
        }
    }
}

impl ExcitationDesign {
    /// The signal at `fs` Hz.
    pub fn generate(&self, fs: f64) -> Result<Vec<f64>, SimError> {
        match self.kind {
            ExcitationKind::Multisine => {
                Multisine::band(self.samples, fs, self.f_min, self.f_max, self.rms)?
                    .generate(self.seed)
            }
            ExcitationKind::White => white_noise(self.samples, self.rms, self.seed),
            ExcitationKind::Sweep => Sweep {
                amplitude: self.rms * std::f64::consts::SQRT_2,
                f0: self.f_min,
                f1: self.f_max,
                duration: self.samples as f64 / fs,
            }
            .sample(self.samples, fs),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn seeds_are_reproducible_and_distinct() {
        let a = white_noise(1000, 2.0, 7).unwrap();
        let b = white_noise(1000, 2.0, 7).unwrap();
        let c = white_noise(1000, 2.0, 8).unwrap();
        assert_eq!(a, b);
        assert_ne!(a, c);
        let rms = (a.iter().map(|v| v * v).sum::<f64>() / 1000.0).sqrt();
        assert_relative_eq!(rms, 2.0, epsilon = 1e-12);
        let m = Multisine::benchmark(50.0);
        assert_eq!(m.generate(3).unwrap(), m.generate(3).unwrap());
        assert_ne!(m.generate(3).unwrap(), m.generate(4).unwrap());
    }

    #[test]
    fn multisine_is_flat_on_its_band_and_zero_elsewhere() {
        let m = Multisine::benchmark(50.0);
        let x = m.generate(1).unwrap();
        let rms = (x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt();
        assert_relative_eq!(rms, 50.0, epsilon = 1e-9);
        let mut planner = RealFftPlanner::<f64>::new();
        let f = planner.plan_fft_forward(x.len());
        let mut buf = x.clone();
        let mut spec = f.make_output_vec();
        f.process(&mut buf, &mut spec).unwrap();
        let a0 = spec[55].norm();
        for (k, s) in spec.iter().enumerate() {
            if (55..=1639).contains(&k) {
                assert_relative_eq!(s.norm(), a0, max_relative = 1e-9);
            } else {
                assert!(s.norm() < 1e-9 * a0, "bin {k}");
            }
        }
        let band = Multisine::band(8192, 750.0, 5.0, 150.0, 1.0).unwrap();
        assert_eq!((band.first_bin, band.last_bin), (55, 1638));
    }

    #[test]
    fn bad_signal_requests_are_named() {
        // The noise's standard deviation is named as such, not as an RMS.
        let mut y = vec![0.0; 10];
        assert_eq!(
            add_noise(&mut y, f64::NAN, 1).unwrap_err().to_string(),
            "invalid signal parameter `noise std`: NaN"
        );
        assert!(matches!(
            white_noise(10, -1.0, 1),
            Err(SimError::InvalidSignal { what: "rms", .. })
        ));
        // An empty signal is refused rather than simulated into an empty record.
        let none = SimError::InvalidSignal {
            what: "samples",
            value: 0.0,
        };
        assert_eq!(white_noise(0, 1.0, 1), Err(none.clone()));
        assert_eq!(Sweep::benchmark().sample(0, 750.0), Err(none));
        // More samples than memory can hold are an error, not an allocation panic.
        let too_long = SimError::TooLong {
            samples: usize::MAX,
        };
        assert_eq!(white_noise(usize::MAX, 1.0, 1), Err(too_long.clone()));
        assert_eq!(
            Sweep::benchmark().sample(usize::MAX, 750.0),
            Err(too_long.clone())
        );
        let huge = Multisine {
            period: usize::MAX,
            first_bin: 1,
            last_bin: 2,
            rms: 1.0,
        };
        assert_eq!(huge.generate(1), Err(too_long));
        // A band's last bin past half of usize::MAX is no band below Nyquist: 2·last_bin
        // must not wrap round into a small number that passes.
        let wrapped = Multisine {
            period: 8192,
            first_bin: 1,
            last_bin: usize::MAX / 2 + 2,
            rms: 1.0,
        };
        assert!(matches!(
            wrapped.generate(1),
            Err(SimError::InvalidSignal {
                what: "multisine band (bins)",
                ..
            })
        ));
        // A sweep's parameters must give numbers.
        let sweep = Sweep::benchmark();
        for (bad, what, value) in [
            (
                Sweep {
                    f0: f64::NAN,
                    ..sweep
                },
                "sweep start frequency",
                f64::NAN,
            ),
            (
                Sweep {
                    f1: f64::INFINITY,
                    ..sweep
                },
                "sweep end frequency",
                f64::INFINITY,
            ),
            (
                Sweep {
                    amplitude: -1.0,
                    ..sweep
                },
                "sweep amplitude",
                -1.0,
            ),
            (
                Sweep {
                    duration: 0.0,
                    ..sweep
                },
                "sweep duration",
                0.0,
            ),
        ] {
            match bad.sample(10, 750.0) {
                Err(SimError::InvalidSignal { what: w, value: v }) => {
                    assert_eq!(w, what);
                    assert!(v == value || (v.is_nan() && value.is_nan()), "{what}: {v}");
                }
                other => panic!("{what}: {other:?}"),
            }
        }
        // A band with no DFT bin below Nyquist says so in Hz.
        for (lo, hi) in [(400.0, 500.0), (50.0, 10.0), (1.0, 1.2), (f64::NAN, 10.0)] {
            let e = Multisine::band(1000, 750.0, lo, hi, 1.0).unwrap_err();
            assert!(
                matches!(e, SimError::EmptyBand { period: 1000, .. }),
                "{lo}..{hi}: {e}"
            );
        }
        let e = Multisine::band(1000, 750.0, 400.0, 500.0, 1.0).unwrap_err();
        assert_eq!(
            e.to_string(),
            "no DFT bin of a 1000-sample period at 750 Hz (spacing 0.75 Hz) lies in the band 400–500 Hz below the Nyquist frequency 375 Hz"
        );
    }

    /// The noise's power lies in its band (up to the leakage of cutting a period in half),
    /// its RMS is the one asked for, it is not periodic in the record, and seeds differ.
    #[test]
    fn band_limited_noise_stays_in_its_band() {
        let n = 16384;
        let x = band_limited_noise(n, 750.0, 5.0, 150.0, 20.0, 9).unwrap();
        let rms = (x.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
        assert_relative_eq!(rms, 20.0, epsilon = 1e-9);
        assert_ne!(
            x,
            band_limited_noise(n, 750.0, 5.0, 150.0, 20.0, 10).unwrap()
        );
        let mut planner = RealFftPlanner::<f64>::new();
        let f = planner.plan_fft_forward(n);
        let mut buf = x.clone();
        let mut spec = f.make_output_vec();
        f.process(&mut buf, &mut spec).unwrap();
        let power = |lo: f64, hi: f64| -> f64 {
            spec.iter()
                .enumerate()
                .filter(|(k, _)| (lo..hi).contains(&(*k as f64 * 750.0 / n as f64)))
                .map(|(_, s)| s.norm_sqr())
                .sum()
        };
        let total = power(0.0, 376.0);
        // Half a period has the leakage of a rectangular window: its sidelobes fall as
        // 1/f², so a few per mille of the power lands outside the band, not more.
        assert!(power(5.0, 150.5) > 0.99 * total);
        assert!(power(200.0, 376.0) < 1e-3 * total);
        // Not periodic in the record: its two halves are unrelated.
        let c: f64 = x[..n / 2].iter().zip(&x[n / 2..]).map(|(a, b)| a * b).sum();
        assert!(c.abs() < 0.1 * 400.0 * (n / 2) as f64);
        assert!(band_limited_noise(n, 750.0, 400.0, 500.0, 1.0, 1).is_err());
    }

    #[test]
    fn sweep_matches_the_benchmark_formula() {
        let s = Sweep::benchmark();
        let t: f64 = 3.7;
        let expected = 40.0 * (2.0 * std::f64::consts::PI * (18.0 * t + t * t / 12.0)).sin();
        assert_relative_eq!(s.at(t), expected, epsilon = 1e-12);
    }
}
