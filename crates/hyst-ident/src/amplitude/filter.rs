//! Each mode's response from the channels: a modal filter (the pseudo-inverse of the
//! shapes) when there are at least as many channels as modes, the projection on the mode's
//! shape otherwise, then a zero-phase band-pass around the mode.

use crate::fft::{irfft, rfft};

use super::ModeToFollow;

/// The real shape closest to `shape` (its entries turned by the phase that makes the
/// shape most real), scaled to unit length.
pub(super) fn real_shape(shape: &[covssi::Complex64]) -> Vec<f64> {
    // The phase θ maximizing Σ Re(φ e^{-iθ})² is half the argument of Σ φ².
    let s: covssi::Complex64 = shape.iter().map(|p| p * p).sum();
    let rot = covssi::Complex64::from_polar(1.0, -0.5 * s.arg());
    let v: Vec<f64> = shape.iter().map(|p| (p * rot).re).collect();
    let n = v.iter().map(|x| x * x).sum::<f64>().sqrt();
    v.iter().map(|x| x / n.max(f64::MIN_POSITIVE)).collect()
}

/// The weights that take the channels to each mode's coordinate: the rows of the
/// shapes' pseudo-inverse when every mode has a shape and the channels are at least as
/// many as the modes and tell them apart, else each mode's own unit shape (a projection).
/// A single channel is its own mode coordinate.
pub(super) fn modal_weights(modes: &[ModeToFollow], channels: usize) -> Vec<Vec<f64>> {
    let shapes: Option<Vec<Vec<f64>>> = modes
        .iter()
        .map(|m| {
            m.shape
                .as_ref()
                .filter(|s| s.len() == channels)
                .map(|s| real_shape(s))
        })
        .collect();
    let Some(shapes) = shapes.filter(|_| channels > 1) else {
        let own = |m: &ModeToFollow| match &m.shape {
            Some(s) if s.len() == channels && channels > 1 => real_shape(s),
            _ => vec![1.0 / (channels as f64).sqrt(); channels],
        };
        return modes.iter().map(own).collect();
    };
    if channels >= modes.len() {
        let phi = nalgebra::DMatrix::from_fn(channels, modes.len(), |i, j| shapes[j][i]);
        // Channels that tell the modes apart: the smallest singular value well above
        // rounding (a condition number below 1e6).
        let sv = phi.singular_values();
        let (hi, lo) = (sv.max(), sv.min());
        if lo > 1e-6 * hi
            && let Ok(pinv) = phi.pseudo_inverse(1e-12 * hi)
        {
            return (0..modes.len())
                .map(|j| pinv.row(j).iter().copied().collect())
                .collect();
        }
    }
    shapes
}

/// `x` band-passed to [lo, hi] Hz by zeroing its spectrum outside, with raised-cosine
/// edges a fifth of the band's half-width wide inside it (zero phase: the filter shifts
/// no cycle in time).
pub(super) fn band_pass(x: &[f64], fs: f64, lo: f64, hi: f64) -> Vec<f64> {
    let n = x.len();
    let mut spec = rfft(x);
    let w = band_weights(spec.len(), n, fs, lo, hi);
    spec.iter_mut().zip(&w).for_each(|(v, w)| *v *= *w);
    irfft(&spec, n)
}

/// The band-pass's gain at each of `bins` bins of an `n`-sample DFT at `fs`.
pub(super) fn band_weights(bins: usize, n: usize, fs: f64, lo: f64, hi: f64) -> Vec<f64> {
    (0..bins)
        .map(|b| band_weight(b as f64 * fs / n as f64, lo, hi))
        .collect()
}

/// The band-pass's gain at `f` Hz: 1 inside [lo, hi] with raised-cosine edges a tenth of
/// the band wide inside it, 0 outside.
pub(super) fn band_weight(f: f64, lo: f64, hi: f64) -> f64 {
    let edge = 0.1 * (hi - lo);
    if f <= lo || f >= hi {
        0.0
    } else if f < lo + edge {
        0.5 * (1.0 - (std::f64::consts::PI * (f - lo) / edge).cos())
    } else if f > hi - edge {
        0.5 * (1.0 - (std::f64::consts::PI * (hi - f) / edge).cos())
    } else {
        1.0
    }
}

/// The channels weighted by `weights`: a mode's coordinate, unfiltered.
pub(super) fn combine(y: &[&[f64]], weights: &[f64]) -> Vec<f64> {
    let n = y.first().map_or(0, |c| c.len());
    let mut q = vec![0.0; n];
    for (c, w) in y.iter().zip(weights) {
        for (qi, v) in q.iter_mut().zip(c.iter()) {
            *qi += w * v;
        }
    }
    q
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two modes' coordinates come back from their mixture on three channels; a sine inside
    /// the band passes unchanged and one outside is removed.
    #[test]
    fn the_modal_filter_and_band_pass_separate_modes() {
        let fs = 100.0;
        let n = 4000;
        let t = |i: usize| i as f64 / fs;
        let s1: Vec<f64> = (0..n)
            .map(|i| (2.0 * std::f64::consts::PI * 5.0 * t(i)).sin())
            .collect();
        let s2: Vec<f64> = (0..n)
            .map(|i| (2.0 * std::f64::consts::PI * 12.0 * t(i)).cos())
            .collect();
        let phi = [[1.0, 0.5], [0.8, -1.0], [0.3, 0.7]];
        let y: Vec<Vec<f64>> = phi
            .iter()
            .map(|p| (0..n).map(|i| p[0] * s1[i] + p[1] * s2[i]).collect())
            .collect();
        let views: Vec<&[f64]> = y.iter().map(|c| c.as_slice()).collect();
        let mode = |f: f64, k: usize| ModeToFollow {
            frequency_hz: f,
            damping_ratio: 0.01,
            shape: Some(
                phi.iter()
                    .map(|p| covssi::Complex64::new(p[k], 0.0))
                    .collect(),
            ),
        };
        let modes = [mode(5.0, 0), mode(12.0, 1)];
        let w = modal_weights(&modes, 3);
        // The pseudo-inverse's rows take each shape to its own coordinate alone (the
        // shapes come back at unit length, so the coordinates are scaled).
        for (j, wj) in w.iter().enumerate() {
            for k in 0..2 {
                let dot: f64 = wj.iter().zip(&phi).map(|(a, p)| a * p[k]).sum();
                let norm = phi.iter().map(|p| p[k] * p[k]).sum::<f64>().sqrt();
                let want = if j == k { norm } else { 0.0 };
                assert!((dot - want).abs() < 1e-12, "{j} {k}: {dot}");
            }
        }
        // Band-passed around 5 Hz, the 12 Hz line is gone from a projection as well.
        let p = band_pass(&combine(&views[..1], &[1.0]), fs, 4.0, 6.0);
        for i in (0..n).step_by(89) {
            assert!((p[i] - s1[i]).abs() < 1e-9, "{i}: {} {}", p[i], s1[i]);
        }
    }
}
