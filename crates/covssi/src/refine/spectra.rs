//! The record as the likelihood sees it: its periodogram matrices averaged over frequency
//! bins narrower than the modes' half-power bands.
//!
//! The Whittle likelihood sums over the $K = \lfloor (N-1)/2 \rfloor$ Fourier frequencies. Over
//! a bin $b$ of $n_b$ neighbouring frequencies across which the model's spectrum $S$ hardly
//! changes, its terms add up to
//!
//! $$ n_b\Big[\ln\det S(\bar\omega_b) + \operatorname{tr}\big(S(\bar\omega_b)^{-1}\hat S_b\big)\Big],
//! \qquad \hat S_b = \frac1{n_b}\sum_{k\in b} x_k x_k^H, $$
//!
//! the Wishart likelihood of the averaged periodogram matrix $\hat S_b$ (the averaged-Whittle
//! likelihood): the $\hat S_b$ are then sufficient statistics, and the likelihood's cost no
//! longer grows with $N$. Evaluating $S$ at the bin's mean frequency $\bar\omega_b$ instead of
//! averaging it over the bin errs by $\tfrac{w^2}{24} S''$ for a bin of width $w$: near a mode
//! of half-power half-width $h$ that broadens its peak as $h^2 \to h^2 + w^2/12$, a relative
//! bias of $(w/h)^2/24$ in its damping, against a relative standard error of about
//! $1/\sqrt{\pi h N}$ ($h$ in rad per sample). Bins are therefore at most
//! $w = h \min\big(\tfrac14, (\pi h N)^{-1/4}\big)$ wide near a mode, which keeps the bias
//! under 1/24 of the standard error, and at most that ratio times the distance to the mode
//! farther from it; the half-width used is half of SSI's (SSI's damping is often high) and
//! every bin holds at least one frequency, so a short record is fitted frequency by frequency
//! as before. [`Spectra::unbinned`] keeps every frequency in its own bin: the likelihood is
//! then exactly Whittle's.
//!
//! The per-frequency transforms are kept too, for what needs single frequencies: the misfit's
//! ratios, which a bin average would hide.

use crate::linalg::C64;
use rayon::iter::{
    IndexedParallelIterator, IntoParallelIterator, IntoParallelRefIterator, ParallelIterator,
};
use realfft::RealFftPlanner;
use std::ops::Range;
use std::sync::Arc;

/// Samples of the record's start kept in the time domain, for the regressions that start the
/// numerators and the joint model (a start needs no more; the fits then use every frequency).
pub(super) const HEAD: usize = 65536;

/// Narrowest relative bin (a fraction of the local scale): see the module's documentation.
const MAX_RATIO: f64 = 0.25;

/// Bins are at most this wide (rad per sample) anywhere: 512 across the band at least, so
/// that the spectrum's shape between far-apart modes is seen.
const WIDEST: f64 = std::f64::consts::PI / 512.0;

/// Frequencies per parallel chunk where single frequencies are evaluated (the misfit).
pub(super) const FREQUENCY_CHUNK: usize = 8192;

/// Half-width (frequencies) of the window that estimates the channels' coherence.
pub(super) const COHERENCE_HALF_WIDTH: usize = 16;

/// A record's periodogram matrices averaged over bins, with what the fits need besides.
pub(super) struct Spectra {
    /// Samples of the record.
    pub(super) n: usize,
    /// Channels (or combinations of them).
    pub(super) l: usize,
    /// Bin b holds the frequencies k in `edges[b]..edges[b + 1]` (index k: ω = 2π(k+1)/N).
    pub(super) edges: Vec<usize>,
    /// e^{iω̄_b}, ω̄_b the mean of the bin's frequencies (rad per sample).
    pub(super) z: Vec<C64>,
    /// The number of frequencies in each bin, n_b.
    pub(super) w: Vec<f64>,
    /// Ŝ_b of each bin, l×l row-major.
    pub(super) s: Vec<C64>,
    /// Squared coherence of each channel pair a < b at index `pair(a, b, l)` (empty
    /// otherwise), per bin, over a window of at least 2·COHERENCE_HALF_WIDTH + 1 frequencies.
    pub(super) coherence: Vec<Vec<f64>>,
    /// The first [`HEAD`] samples of each channel, centred (and scaled or combined as the
    /// spectra are).
    pub(super) head: Vec<Vec<f64>>,
    /// The transforms x_c(ω_k) = DFT/√N of the record's channels, and the rows of the
    /// combination that makes these spectra's channels of them (`None`: the channels
    /// themselves).
    x: Arc<Vec<Vec<C64>>>,
    combination: Option<Vec<Vec<f64>>>,
}

/// Where a mode's (or real pole's) spectrum changes: its centre and half-width, rad per
/// sample.
#[derive(Clone, Copy, Debug)]
pub(super) struct Scale {
    pub(super) centre: f64,
    pub(super) half_width: f64,
}

impl Scale {
    /// The scale of a continuous-time pole λ (rad/s) sampled at `fs`: centre Im λ/f_s, and
    /// half of its half-power half-width −Re λ/f_s (SSI's damping is often high).
    pub(super) fn of_pole(lam: C64, fs: f64) -> Self {
        Scale {
            centre: lam.im.abs() / fs,
            half_width: 0.5 * (-lam.re).abs() / fs,
        }
    }
}

impl Spectra {
    /// The spectra of the channels `y` less `means`, each times `scale`, in bins sized for the
    /// `scales` (none: one bin of every frequency, whatever it is, at most [`WIDEST`] wide).
    pub(super) fn new(y: &[&[f64]], means: &[f64], scale: &[f64], scales: &[Scale]) -> Self {
        Self::of_record(y, means, scale, layout(y[0].len(), scales))
    }

    /// The spectra of `y` less `means` with every frequency its own bin: the likelihood is
    /// then exactly Whittle's.
    #[cfg(test)]
    pub(super) fn unbinned(y: &[&[f64]], means: &[f64]) -> Self {
        let k = (y[0].len() - 1) / 2;
        Self::of_record(y, means, &vec![1.0; y.len()], (0..=k).collect())
    }

    /// The spectra of the channels `y` less `means`, each times `scale`, in the bins `edges`.
    fn of_record(y: &[&[f64]], means: &[f64], scale: &[f64], edges: Vec<usize>) -> Self {
        let n = y[0].len();
        let head = y
            .iter()
            .zip(means)
            .zip(scale)
            .map(|((c, m), d)| c[..n.min(HEAD)].iter().map(|v| (v - m) * d).collect())
            .collect();
        let x = transforms(y, means, scale);
        Self::from_parts(n, Arc::new(x), None, edges, head)
    }

    fn from_parts(
        n: usize,
        x: Arc<Vec<Vec<C64>>>,
        combination: Option<Vec<Vec<f64>>>,
        edges: Vec<usize>,
        head: Vec<Vec<f64>>,
    ) -> Self {
        let l = combination.as_ref().map_or(x.len(), Vec::len);
        let bins = edges.len() - 1;
        let per_bin: Vec<(C64, f64, Vec<C64>)> = (0..bins)
            .into_par_iter()
            .map(|b| {
                let range = edges[b]..edges[b + 1];
                let count = range.len() as f64;
                let mut s = vec![C64::new(0.0, 0.0); l * l];
                let mut xk = vec![C64::new(0.0, 0.0); l];
                let mut mean_k = 0.0;
                for k in range {
                    mean_k += (k + 1) as f64;
                    frequency(&x, combination.as_deref(), k, &mut xk);
                    for a in 0..l {
                        for c in 0..l {
                            s[a * l + c] += xk[a] * xk[c].conj();
                        }
                    }
                }
                s.iter_mut().for_each(|v| *v /= count);
                let omega = 2.0 * std::f64::consts::PI * mean_k / count / n as f64;
                (C64::from_polar(1.0, omega), count, s)
            })
            .collect();
        let mut z = Vec::with_capacity(bins);
        let mut w = Vec::with_capacity(bins);
        let mut s = Vec::with_capacity(bins * l * l);
        for (zb, wb, sb) in per_bin {
            z.push(zb);
            w.push(wb);
            s.extend(sb);
        }
        let mut spectra = Spectra {
            n,
            l,
            edges,
            z,
            w,
            s,
            coherence: Vec::new(),
            head,
            x,
            combination,
        };
        spectra.coherence = spectra.coherences();
        spectra
    }

    /// Number of bins.
    pub(super) fn bins(&self) -> usize {
        self.z.len()
    }

    /// Number of frequencies, K.
    pub(super) fn k(&self) -> usize {
        self.edges.last().copied().unwrap_or(0)
    }

    /// Ŝ_b[a, c].
    pub(super) fn at(&self, b: usize, a: usize, c: usize) -> C64 {
        self.s[(b * self.l + a) * self.l + c]
    }

    /// The bin holding the frequency nearest ω (rad per sample).
    pub(super) fn bin_at(&self, omega: f64) -> usize {
        let k = ((omega * self.n as f64 / (2.0 * std::f64::consts::PI)).round() as usize)
            .clamp(1, self.k().max(1))
            - 1;
        self.edges.partition_point(|&e| e <= k).saturating_sub(1)
    }

    /// The frequencies `k` as spectra of their own, one frequency per bin (z, weight 1,
    /// Ŝ = x xᴴ), for what needs every frequency (the misfit's ratios).
    pub(super) fn frequencies(&self, k: Range<usize>) -> Spectra {
        let l = self.l;
        let count = k.len();
        let mut z = Vec::with_capacity(count);
        let mut s = Vec::with_capacity(count * l * l);
        let mut xk = vec![C64::new(0.0, 0.0); l];
        for kk in k.clone() {
            z.push(C64::from_polar(
                1.0,
                2.0 * std::f64::consts::PI * (kk + 1) as f64 / self.n as f64,
            ));
            frequency(&self.x, self.combination.as_deref(), kk, &mut xk);
            for a in 0..l {
                for c in 0..l {
                    s.push(xk[a] * xk[c].conj());
                }
            }
        }
        Spectra {
            n: self.n,
            l,
            edges: (k.start..=k.end).collect(),
            z,
            w: vec![1.0; count],
            s,
            coherence: Vec::new(),
            head: Vec::new(),
            x: Arc::new(Vec::new()),
            combination: None,
        }
    }

    /// The spectra of the combinations `rows` (p × l) of these channels, in the same bins:
    /// Ŝ' = T Ŝ Tᵀ, without copying the record.
    pub(super) fn combined(&self, rows: Vec<Vec<f64>>) -> Spectra {
        let head = rows
            .iter()
            .map(|r| {
                (0..self.head.first().map_or(0, Vec::len))
                    .map(|t| r.iter().zip(&self.head).map(|(g, h)| g * h[t]).sum())
                    .collect()
            })
            .collect();
        // Combinations of combinations compose.
        let rows = match &self.combination {
            None => rows,
            Some(inner) => rows
                .iter()
                .map(|r| {
                    (0..inner[0].len())
                        .map(|c| r.iter().zip(inner).map(|(g, i)| g * i[c]).sum())
                        .collect()
                })
                .collect(),
        };
        Self::from_parts(
            self.n,
            Arc::clone(&self.x),
            Some(rows),
            self.edges.clone(),
            head,
        )
    }

    /// The squared coherence of each channel pair per bin, from the cross-spectra summed over
    /// the bins around it until they hold 2·COHERENCE_HALF_WIDTH + 1 frequencies (fewer at the
    /// ends of the band). With one frequency per bin, the window is ±COHERENCE_HALF_WIDTH.
    fn coherences(&self) -> Vec<Vec<f64>> {
        let (l, bins) = (self.l, self.bins());
        let need = (2 * COHERENCE_HALF_WIDTH + 1) as f64;
        // Prefix sums of n_b Ŝ_b over the bins.
        let mut windows = Vec::with_capacity(bins);
        for b in 0..bins {
            let (mut lo, mut hi) = (b, b + 1);
            let mut total = self.w[b];
            while total < need && (lo > 0 || hi < bins) {
                if lo > 0 {
                    lo -= 1;
                    total += self.w[lo];
                }
                if hi < bins && total < need {
                    hi += 1;
                    total += self.w[hi - 1];
                }
            }
            windows.push(lo..hi);
        }
        let mut out = vec![Vec::new(); l * l];
        let prefix = |a: usize, c: usize| -> Vec<C64> {
            let mut p = vec![C64::new(0.0, 0.0); bins + 1];
            for b in 0..bins {
                p[b + 1] = p[b] + self.at(b, a, c) * self.w[b];
            }
            p
        };
        let diag: Vec<Vec<C64>> = (0..l).map(|a| prefix(a, a)).collect();
        for a in 0..l {
            for c in a + 1..l {
                let cross = prefix(a, c);
                out[pair(a, c, l)] = windows
                    .iter()
                    .map(|r| {
                        let den = (diag[a][r.end] - diag[a][r.start]).re
                            * (diag[c][r.end] - diag[c][r.start]).re;
                        if den > 0.0 {
                            ((cross[r.end] - cross[r.start]).norm_sqr() / den).min(1.0)
                        } else {
                            0.0
                        }
                    })
                    .collect();
            }
        }
        out
    }
}

/// The channels' transforms x_c(ω_k) = DFT/√N at 0 < ω_k < π, each less its mean and times
/// its scale.
fn transforms(y: &[&[f64]], means: &[f64], scale: &[f64]) -> Vec<Vec<C64>> {
    let n = y[0].len();
    let k_max = (n - 1) / 2;
    let mut planner = RealFftPlanner::<f64>::new();
    let fft = planner.plan_fft_forward(n);
    let norm = 1.0 / (n as f64).sqrt();
    y.par_iter()
        .zip(means)
        .zip(scale)
        .map(|((ch, mean), d)| {
            let mut buf: Vec<f64> = ch.iter().map(|v| v - mean).collect();
            let mut spec = fft.make_output_vec();
            // Lengths match the plan, so this cannot fail.
            fft.process(&mut buf, &mut spec).expect("FFT lengths");
            drop(buf);
            spec[1..=k_max].iter().map(|c| c * (norm * d)).collect()
        })
        .collect()
}

/// x at frequency k: the channels', or their combinations `rows`.
fn frequency(x: &[Vec<C64>], rows: Option<&[Vec<f64>]>, k: usize, out: &mut [C64]) {
    match rows {
        None => out.iter_mut().zip(x).for_each(|(o, c)| *o = c[k]),
        Some(rows) => {
            for (o, r) in out.iter_mut().zip(rows) {
                *o = r.iter().zip(x).map(|(g, c)| c[k] * g).sum();
            }
        }
    }
}

/// The bins' edges for a record of `n` samples: each bin as wide as [`width`] allows where it
/// starts and where it would end, and at least one frequency.
fn layout(n: usize, scales: &[Scale]) -> Vec<usize> {
    let k = (n - 1) / 2;
    let step = 2.0 * std::f64::consts::PI / n as f64;
    let mut edges = vec![0];
    let mut at = 0;
    while at < k {
        let omega = step * (at as f64 + 0.5);
        let w1 = width(omega, n, scales);
        let w = w1.min(width(omega + w1, n, scales));
        let count = ((w / step).floor() as usize).max(1);
        at = (at + count).min(k);
        edges.push(at);
    }
    edges
}

/// The widest bin at ω (rad per sample): for each scale, its ratio (see the module's
/// documentation) times the larger of its half-width and the distance to its centre; the
/// narrowest of those, and at most [`WIDEST`].
fn width(omega: f64, n: usize, scales: &[Scale]) -> f64 {
    scales
        .iter()
        .filter(|s| s.half_width > 0.0 && s.half_width.is_finite())
        .map(|s| {
            let h = s.half_width;
            let ratio = MAX_RATIO.min((std::f64::consts::PI * h * n as f64).powf(-0.25));
            ratio * h.max((omega - s.centre).abs())
        })
        .fold(WIDEST, f64::min)
}

/// Index of the unordered channel pair (a, b), a ≠ b, among l channels.
pub(in crate::refine) fn pair(a: usize, b: usize, l: usize) -> usize {
    let (a, b) = if a < b { (a, b) } else { (b, a) };
    a * l + b
}

#[cfg(test)]
mod tests {
    use super::*;

    fn noise(n: usize, seed: u64) -> Vec<f64> {
        let mut s = seed;
        (0..n)
            .map(|_| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5
            })
            .collect()
    }

    #[test]
    fn bins_cover_every_frequency_once_and_narrow_near_a_mode() {
        let n = 100_000;
        let scales = [Scale {
            centre: 1.0,
            half_width: 0.01,
        }];
        let e = layout(n, &scales);
        assert_eq!(*e.first().unwrap(), 0);
        assert_eq!(*e.last().unwrap(), (n - 1) / 2);
        assert!(e.windows(2).all(|w| w[1] > w[0]));
        let step = 2.0 * std::f64::consts::PI / n as f64;
        // Within its half-width of the mode a bin is at most min(1/4, (π h N)^(-1/4)) =
        // 0.1335 of that half-width (159 frequencies here), and one frequency more at most.
        let near = e
            .windows(2)
            .filter(|w| ((w[0] as f64 + 1.0) * step - 1.0).abs() < 0.01)
            .map(|w| (w[1] - w[0]) as f64 * step)
            .fold(0.0, f64::max);
        assert!(near <= 0.1335 * 0.01 + step, "{near}");
        // Far fewer bins than frequencies.
        assert!(e.len() < 1000, "{}", e.len());
    }

    #[test]
    fn averaged_matrices_are_the_frequencies_mean_and_combinations_commute() {
        let n = 4097;
        let a = noise(n, 1);
        let b: Vec<f64> = noise(n, 2)
            .iter()
            .zip(&a)
            .map(|(u, v)| u + 0.5 * v)
            .collect();
        let y: Vec<&[f64]> = vec![&a, &b];
        let means = [0.0, 0.0];
        let scales = [Scale {
            centre: 0.5,
            half_width: 0.05,
        }];
        let sp = Spectra::new(&y, &means, &[1.0, 1.0], &scales);
        let exact = Spectra::unbinned(&y, &means);
        assert_eq!(exact.bins(), exact.k());
        // Each bin's Ŝ is the mean of its frequencies' x xᴴ (exact to rounding).
        for bin in [0, sp.bins() / 2, sp.bins() - 1] {
            let r = sp.edges[bin]..sp.edges[bin + 1];
            let mean: C64 = r.clone().map(|k| exact.at(k, 0, 1)).sum::<C64>() / r.len() as f64;
            assert!((sp.at(bin, 0, 1) - mean).norm() <= 1e-12 * mean.norm().max(1e-300));
        }
        // A combination's spectra equal T Ŝ Tᵀ.
        let t = vec![vec![0.6, -0.8], vec![0.8, 0.6]];
        let c = sp.combined(t.clone());
        let bin = sp.bins() / 3;
        let want: C64 = (0..2)
            .flat_map(|i| (0..2).map(move |j| (i, j)))
            .map(|(i, j)| sp.at(bin, i, j) * t[0][i] * t[1][j])
            .sum();
        assert!((c.at(bin, 0, 1) - want).norm() <= 1e-12 * want.norm().max(1e-300));
        // The per-frequency view of the combination agrees with its bin's mean.
        let f = c.frequencies(c.edges[bin]..c.edges[bin + 1]);
        let mean: C64 = (0..f.bins()).map(|k| f.at(k, 0, 1)).sum::<C64>() / f.bins() as f64;
        assert!((c.at(bin, 0, 1) - mean).norm() <= 1e-12 * mean.norm());
    }
}
