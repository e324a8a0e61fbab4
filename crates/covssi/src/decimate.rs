//! Decimation for modal analysis: an ideal low-pass by FFT, then every r-th sample.
//!
//! A record sampled far above its modes wastes block rows: the lag that covers ten periods
//! of the lowest mode takes `fs/f` lags per period. Decimating first keeps the lag and the
//! Toeplitz matrix small. The low-pass must neither colour the band that is kept (the
//! refinement fits the spectrum's shape up to Nyquist, and a short FIR's roll-off there is
//! fitted as a pole at Nyquist) nor let anything above the new Nyquist fold back. So the
//! record is extended by its mirror image (even extension: no jump where it wraps round),
//! transformed, every bin above the new Nyquist $f_s/2r$ set to zero (the last 2 % of the
//! kept band tapered by a half cosine, which keeps the filter's impulse response short),
//! transformed back, and sampled at $n = 0, r, 2r, \dots$ Output sample $k$ lines up with
//! input sample $rk$ (the filter is zero-phase).

use realfft::RealFftPlanner;
use realfft::num_complex::Complex;

/// Share of the kept band, below the new Nyquist, over which the low-pass falls from 1 to 0.
pub(crate) const TAPER: f64 = 0.02;

/// `x` low-passed below `fs/(2r)` (ideal, zero-phase) and decimated by `r`: samples
/// `0, r, 2r, …` of the filtered record, `⌈len/r⌉` of them. `r ≤ 1` returns `x` as it is.
pub fn decimate(x: &[f64], r: usize) -> Vec<f64> {
    let n = x.len();
    if r <= 1 || n < 2 {
        return x.to_vec();
    }
    let m = 2 * n;
    let mut planner = RealFftPlanner::<f64>::new();
    let fwd = planner.plan_fft_forward(m);
    let inv = planner.plan_fft_inverse(m);
    let mut buf: Vec<f64> = x.iter().chain(x.iter().rev()).copied().collect();
    let mut spec = fwd.make_output_vec();
    fwd.process(&mut buf, &mut spec)
        .expect("buffer sizes from the plan");
    // Bin k is at k·fs/m; the new Nyquist fs/(2r) is bin m/(2r) = n/r.
    let cut = n as f64 / r as f64;
    let start = cut * (1.0 - TAPER);
    for (k, s) in spec.iter_mut().enumerate() {
        let k = k as f64;
        let gain = if k <= start {
            1.0
        } else if k >= cut {
            0.0
        } else {
            0.5 * (1.0 + (std::f64::consts::PI * (k - start) / (cut - start)).cos())
        };
        *s *= gain;
    }
    // The imaginary parts of the DC and Nyquist bins are rounding noise of a real signal.
    spec[0].im = 0.0;
    if let Some(last) = spec.last_mut() {
        *last = Complex::new(last.re, 0.0);
    }
    inv.process(&mut spec, &mut buf)
        .expect("buffer sizes from the plan");
    let scale = 1.0 / m as f64;
    buf[..n].iter().step_by(r).map(|v| v * scale).collect()
}

/// Every channel of `y` decimated by `factor` ([`decimate`], channels in parallel); none when
/// `factor` is at most 1 (the caller uses the channels as they are).
pub fn decimate_channels(y: &[&[f64]], factor: usize) -> Vec<Vec<f64>> {
    use rayon::prelude::*;
    if factor <= 1 {
        return Vec::new();
    }
    y.par_iter().map(|c| decimate(c, factor)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// A sinusoid inside the kept band comes through unchanged (away from the ends, which
    /// the mirror extension makes a turning point), one above the new Nyquist is removed
    /// rather than folded back, and the output lines up with the input's samples r·k.
    #[test]
    fn keeps_the_band_and_folds_nothing_back() {
        let (fs, r, n) = (256.0, 4, 8192);
        let keep = |t: f64| (2.0 * PI * 10.0 * t + 0.3).sin();
        // 40 Hz is above the new Nyquist (32 Hz): undecimated it would fold to 24 Hz.
        let drop = |t: f64| 0.5 * (2.0 * PI * 40.0 * t).cos();
        let x: Vec<f64> = (0..n)
            .map(|i| {
                let t = i as f64 / fs;
                keep(t) + drop(t)
            })
            .collect();
        let y = decimate(&x, r);
        assert_eq!(y.len(), n / r);
        // Error of the kept sinusoid over the middle (the ends see the mirror's kink, a
        // slope discontinuity whose ripple dies within a few hundred samples).
        let err = y[200..y.len() - 200]
            .iter()
            .enumerate()
            .map(|(k, v)| (v - keep((k + 200) as f64 * r as f64 / fs)).abs())
            .fold(0.0, f64::max);
        // 10 Hz is 31 % of the new Nyquist, in the flat part of the pass band: the error is
        // leakage of the record's non-periodic ends only.
        assert!(err < 1e-3, "largest error {err}");
    }

    /// r = 1 and records too short to filter are returned as given.
    #[test]
    fn factor_one_is_the_identity() {
        let x = [1.0, -2.0, 3.5];
        assert_eq!(decimate(&x, 1), x.to_vec());
        assert_eq!(decimate(&x[..1], 3), vec![1.0]);
    }
}
