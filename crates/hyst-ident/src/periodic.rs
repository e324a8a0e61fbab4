//! Whether a record's input is periodic, told from the data: what decides whether a model is
//! simulated to its steady state over the record (one period) or from rest.
//!
//! Two cases. A record of **several periods** repeats: its input's normalised correlation
//! with itself one period later is at least [`PERIODIC_CORRELATION`] ([`input_period`]). A
//! record of **exactly one period** of a band-limited periodic signal (a multisine's period,
//! as validation records are shipped) cannot be seen to repeat, but its discrete Fourier
//! transform over the record's length has no leakage: the bins the signal does not excite are
//! zero to rounding (below [`EMPTY_BIN`] of the strongest), where any other record leaks into
//! every bin ([`is_one_period`]). An input measured with noise is neither, and is simulated
//! from rest.

/// Lowest correlation of the input with itself one period later for it to count as periodic.
pub const PERIODIC_CORRELATION: f64 = 0.99;

/// The input's period in samples, if it repeats: [`repeat_period`] from 16 samples (at most
/// a third of the record, so that three periods are there).
pub fn input_period(u: &[f64]) -> Option<usize> {
    repeat_period(u, 16)
}

/// The first lag from `min_lag` samples to a third of the record at which `u`'s normalised
/// correlation with itself is at least [`PERIODIC_CORRELATION`], moved on to where that
/// correlation peaks: the period of a record that repeats. For a response, `min_lag` must
/// exceed the time over which a lightly damped mode stays correlated with itself (a mode of
/// damping ratio ζ keeps a correlation of e^(−2πζ) after one cycle: 0.994 at ζ = 0.1 %).
pub fn repeat_period(u: &[f64], min_lag: usize) -> Option<usize> {
    let n = u.len();
    if n < 3 * min_lag.max(16) {
        return None;
    }
    let mean = u.iter().sum::<f64>() / n as f64;
    let x: Vec<f64> = u.iter().map(|v| v - mean).collect();
    // Autocorrelation by FFT, zero-padded against wrap-around.
    let mut padded = x.clone();
    padded.resize(2 * n, 0.0);
    let spec: Vec<_> = crate::fft::rfft(&padded)
        .into_iter()
        .map(|c| crate::fft::C::new(c.norm_sqr(), 0.0))
        .collect();
    let r = crate::fft::irfft(&spec, 2 * n);
    // Energies of the leading and trailing parts, for the normalised correlation.
    let mut head = vec![0.0; n + 1];
    for i in 0..n {
        head[i + 1] = head[i] + x[i] * x[i];
    }
    let total = head[n];
    if total <= 0.0 {
        return None;
    }
    let corr = |lag: usize| {
        let a = head[n - lag];
        let b = total - head[lag];
        if a > 0.0 && b > 0.0 {
            r[lag] / (a * b).sqrt()
        } else {
            f64::NAN
        }
    };
    let first = (min_lag.max(1)..=n / 3).find(|&lag| corr(lag) >= PERIODIC_CORRELATION)?;
    // A smooth (oversampled) record is already that correlated a sample or two before its
    // period: the period is where the correlation peaks.
    let mut lag = first;
    while lag < n / 3 && corr(lag + 1) > corr(lag) {
        lag += 1;
    }
    Some(lag)
}

/// A bin's power below this fraction of the strongest bin's counts as empty (rounding of
/// the file's 17-digit numbers leaves about 1e-32; a record that is not one period leaks
/// far above it: 1e-12 for a band-limited random record of 8192 samples).
pub const EMPTY_BIN: f64 = 1e-20;

/// Whether `u` is exactly one period of a band-limited periodic signal: at least a tenth of
/// its DFT bins (DC apart) are empty.
pub fn is_one_period(u: &[f64]) -> bool {
    let n = u.len();
    if n < 32 {
        return false;
    }
    let power: Vec<f64> = crate::fft::rfft(u)
        .iter()
        .skip(1)
        .map(|c| c.norm_sqr())
        .collect();
    let peak = power.iter().copied().fold(0.0, f64::max);
    if peak <= 0.0 {
        return false;
    }
    let empty = power.iter().filter(|&&p| p < EMPTY_BIN * peak).count();
    empty * 10 >= power.len()
}

/// How a record repeats.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum Periodicity {
    /// The record is a whole number of periods of its input (one or more).
    Periodic {
        /// The period in samples (the record's length for one period).
        period: usize,
    },
    /// The input does not repeat over the record, or not in whole periods.
    NotPeriodic,
}

/// How the record with input `u` repeats: a whole number of periods ([`input_period`]
/// dividing the length), else one period ([`is_one_period`]).
pub fn periodicity(u: &[f64]) -> Periodicity {
    match input_period(u) {
        Some(p) if u.len().is_multiple_of(p) => Periodicity::Periodic { period: p },
        _ if is_one_period(u) => Periodicity::Periodic { period: u.len() },
        _ => Periodicity::NotPeriodic,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use hyst_sim::excitation::{Multisine, band_limited_noise};

    #[test]
    fn multisine_periods_are_periodic_and_noise_is_not() {
        let one = Multisine::band(8192, 750.0, 5.0, 150.0, 50.0)
            .unwrap()
            .generate(3)
            .unwrap();
        assert_eq!(periodicity(&one), Periodicity::Periodic { period: 8192 });
        let three: Vec<f64> = one.iter().cycle().take(3 * 8192).copied().collect();
        assert_eq!(periodicity(&three), Periodicity::Periodic { period: 8192 });
        // Two and a half periods repeat, but not in whole periods.
        let cut = &three[..8192 * 5 / 2];
        assert_eq!(periodicity(cut), Periodicity::NotPeriodic);
        // Written to a file with 17 significant digits and read back: still one period.
        let rounded: Vec<f64> = one
            .iter()
            .map(|v| format!("{v:.16e}").parse().unwrap())
            .collect();
        assert!(is_one_period(&rounded));
        let noise = band_limited_noise(8192, 750.0, 5.0, 150.0, 50.0, 4).unwrap();
        assert_eq!(periodicity(&noise), Periodicity::NotPeriodic);
        // A period with measurement noise on the input is not taken for one.
        let noisy: Vec<f64> = one.iter().zip(&noise).map(|(a, b)| a + 1e-3 * b).collect();
        assert!(!is_one_period(&noisy));
    }

    /// A smooth periodic response (an oversampled multisine) with sensor noise: its period,
    /// exactly (the correlation reaches 0.99 a sample early). A lightly damped mode's random
    /// response (ζ = 0.02 %, 40 samples a cycle) repeats itself a cycle later at 0.999: found
    /// as a "period" from 16 samples, not from 50 cycles (e^(−2π·50·0.0002) = 0.94).
    #[test]
    fn a_response_repeats_only_when_its_excitation_does() {
        let one = Multisine::band(4000, 400.0, 1.0, 20.0, 1.0)
            .unwrap()
            .generate(7)
            .unwrap();
        let noise = band_limited_noise(5 * 4000, 400.0, 1.0, 190.0, 0.01, 8).unwrap();
        let y: Vec<f64> = one.iter().cycle().zip(&noise).map(|(a, b)| a + b).collect();
        assert_eq!(repeat_period(&y, 1000), Some(4000));
        // x[t] = 2r cos(θ) x[t−1] − r² x[t−2] + e[t]: a mode at 10 Hz, ζ = 0.02 %, fs 400 Hz.
        let (theta, r) = (
            2.0 * std::f64::consts::PI / 40.0,
            (-0.0002 * 2.0 * std::f64::consts::PI / 40.0).exp(),
        );
        let e = hyst_sim::excitation::white_noise(40_000, 1.0, 3).unwrap();
        let mut x = vec![0.0; e.len()];
        for t in 2..e.len() {
            x[t] = 2.0 * r * theta.cos() * x[t - 1] - r * r * x[t - 2] + e[t];
        }
        assert!(repeat_period(&x, 16).is_some());
        assert_eq!(repeat_period(&x, 50 * 40), None);
    }
}
