//! Resampling: exact band-limited upsampling of periodic records and MATLAB-compatible FIR
//! decimation.
//!
//! [`decimate`] reproduces MATLAB's `decimate(x, r, 'fir')`: the 31-tap low-pass
//! `fir1(30, 1/r)` (Hamming window, unit gain at DC), applied with the ends of the record
//! extended by the point mirror $2x_0 - x_{j}$ (and likewise at the far end), with the filter's
//! 15-sample delay removed, so that output sample $k$ lines up with input sample $rk$.

use realfft::RealFftPlanner;

/// Number of taps of MATLAB's default FIR decimation filter minus one.
pub const FIR_ORDER: usize = 30;

/// Taps of `fir1(order, cutoff)` for a low-pass with a Hamming window, `cutoff` as a fraction
/// of the Nyquist frequency (0 < cutoff < 1), scaled to unit gain at DC.
pub fn fir1_lowpass(order: usize, cutoff: f64) -> Vec<f64> {
    let n = order + 1;
    let half = order as f64 / 2.0;
    let mut h: Vec<f64> = (0..n)
        .map(|i| {
            let t = i as f64 - half;
            let ideal = if t == 0.0 {
                cutoff
            } else {
                (std::f64::consts::PI * cutoff * t).sin() / (std::f64::consts::PI * t)
            };
            let w = if order == 0 {
                1.0
            } else {
                0.54 - 0.46 * (2.0 * std::f64::consts::PI * i as f64 / order as f64).cos()
            };
            ideal * w
        })
        .collect();
    let sum: f64 = h.iter().sum();
    for v in &mut h {
        *v /= sum;
    }
    h
}

/// `decimate(x, r, 'fir')`: low-pass with [`fir1_lowpass`]`(30, 1/r)` and keep every `r`-th
/// sample, starting with the first. `r = 1` returns a copy.
///
/// The output has `ceil(len / r)` samples. Records shorter than 31 samples are extended by
/// mirroring only as far as they reach (the taps past the record's length see the mirror of
/// its last available sample).
pub fn decimate(x: &[f64], r: usize) -> Vec<f64> {
    if r <= 1 || x.is_empty() {
        return x.to_vec();
    }
    let b = fir1_lowpass(FIR_ORDER, 1.0 / r as f64);
    let n = x.len() as isize;
    let half = (FIR_ORDER / 2) as isize;
    let last = n - 1;
    let ext = |i: isize| -> f64 {
        if i < 0 {
            2.0 * x[0] - x[(-i).min(last) as usize]
        } else if i > last {
            2.0 * x[last as usize] - x[(2 * last - i).max(0) as usize]
        } else {
            x[i as usize]
        }
    };
    let count = x.len().div_ceil(r);
    (0..count)
        .map(|k| {
            let c = (k * r) as isize;
            // y[c] = Σ_j b[j] x[c + half − j]  (causal filter, delay `half` removed)
            b.iter()
                .enumerate()
                .map(|(j, bj)| bj * ext(c + half - j as isize))
                .sum()
        })
        .collect()
}

/// Apply [`decimate`] stage by stage (e.g. `[2, 2, 5]` for a factor 20).
pub fn decimate_stages(x: &[f64], stages: &[usize]) -> Vec<f64> {
    let mut y = x.to_vec();
    for &r in stages {
        y = decimate(&y, r);
    }
    y
}

/// Exact band-limited interpolation of one period of a periodic record by the integer factor
/// `r` (zero-padding of its DFT). The result has `r · len` samples, of which every `r`-th is
/// the input sample. A component at exactly the Nyquist frequency is split evenly between
/// the positive and negative frequency, as interpolation of a real cosine requires.
pub fn upsample_periodic(x: &[f64], r: usize) -> Vec<f64> {
    let n = x.len();
    if r <= 1 || n == 0 {
        return x.to_vec();
    }
    let m = n * r;
    let mut planner = RealFftPlanner::<f64>::new();
    let fwd = planner.plan_fft_forward(n);
    let inv = planner.plan_fft_inverse(m);
    let mut input = x.to_vec();
    let mut spec = fwd.make_output_vec();
    fwd.process(&mut input, &mut spec)
        .expect("buffer sizes come from the plan");
    let mut big = inv.make_input_vec();
    big[..spec.len()].copy_from_slice(&spec);
    if n.is_multiple_of(2) {
        big[n / 2] *= 0.5;
    }
    let mut out = inv.make_output_vec();
    inv.process(&mut big, &mut out)
        .expect("buffer sizes come from the plan");
    let scale = 1.0 / n as f64;
    for v in &mut out {
        *v *= scale;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn fir1_taps_match_matlab() {
        // MATLAB: b = fir1(30, 1/2); b(16) = 0.5000 at the centre (after DC normalisation the
        // centre tap of a half-band filter is 0.5/sum), symmetric, odd taps from centre zero.
        let b = fir1_lowpass(30, 0.5);
        assert_eq!(b.len(), 31);
        for i in 0..31 {
            assert_relative_eq!(b[i], b[30 - i], epsilon = 1e-15);
        }
        // Half-band filter: the ideal response sin(πt/2)/(πt) vanishes at even offsets t ≠ 0.
        for i in (2..=14).step_by(2) {
            assert!(b[15 + i].abs() < 1e-15, "half-band zero at {}", 15 + i);
        }
        assert_relative_eq!(b.iter().sum::<f64>(), 1.0, epsilon = 1e-14);
    }

    #[test]
    fn decimation_filter_response() {
        // Properties of a 31-tap Hamming-window low-pass: unit gain at DC; beyond the main lobe
        // of the window (half-width 4/31 of Nyquist) past the cut-off, the stop band lies below
        // −45 dB (Hamming windows give about −50 dB; the shortest cut-off, r = 20, is the
        // worst at −46 dB); where the filter is long enough to have a pass band (r = 2, 5), the
        // gain is 0.5 at the cut-off and flat to 0.5 % below it.
        let lobe = 4.0 / 31.0 + 0.01;
        for r in [2usize, 5, 20] {
            let b = fir1_lowpass(30, 1.0 / r as f64);
            let gain = |f: f64| {
                // f as a fraction of Nyquist
                let w = std::f64::consts::PI * f;
                let (re, im) = b.iter().enumerate().fold((0.0, 0.0), |(re, im), (k, bk)| {
                    (
                        re + bk * (w * k as f64).cos(),
                        im - bk * (w * k as f64).sin(),
                    )
                });
                (re * re + im * im).sqrt()
            };
            assert_relative_eq!(gain(0.0), 1.0, epsilon = 1e-12);
            let cut = 1.0 / r as f64;
            let mut f = cut + lobe;
            while f <= 1.0 {
                assert!(
                    gain(f) < 10f64.powf(-45.0 / 20.0),
                    "r={r} f={f}: {}",
                    gain(f)
                );
                f += 0.001;
            }
            if cut > lobe {
                assert!(
                    (gain(cut) - 0.5).abs() < 0.01,
                    "r={r}: cut-off gain {}",
                    gain(cut)
                );
                let mut f = 0.0;
                while f <= cut - lobe {
                    assert!((gain(f) - 1.0).abs() < 0.005, "r={r} f={f}: {}", gain(f));
                    f += 0.001;
                }
            }
        }
    }

    #[test]
    fn decimate_keeps_a_slow_sine_and_aligns_samples() {
        let n = 2000;
        let x: Vec<f64> = (0..n).map(|i| (0.01 * i as f64).sin()).collect();
        let y = decimate(&x, 5);
        assert_eq!(y.len(), 400);
        for (k, yk) in y.iter().enumerate().skip(10).take(380) {
            // The pass-band ripple of fir1(30, 0.2) at 0.0032·Nyquist is far below 1e-4.
            assert_relative_eq!(*yk, x[5 * k], epsilon = 1e-4);
        }
    }

    #[test]
    fn upsampling_is_exact_on_band_limited_signals() {
        let n = 64;
        let f = |t: f64| {
            (2.0 * std::f64::consts::PI * 3.0 * t).sin()
                + 0.3 * (2.0 * std::f64::consts::PI * 7.0 * t + 0.4).cos()
        };
        let x: Vec<f64> = (0..n).map(|i| f(i as f64 / n as f64)).collect();
        let y = upsample_periodic(&x, 5);
        assert_eq!(y.len(), 5 * n);
        for (j, yj) in y.iter().enumerate() {
            assert_relative_eq!(*yj, f(j as f64 / (5 * n) as f64), epsilon = 1e-12);
        }
    }
}
