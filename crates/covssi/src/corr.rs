//! Output correlations by the unbiased estimator (eq. 27),
//! $\hat R_k = \frac{1}{N-k}\sum_{n=0}^{N-1-k} y(n+k)\,y_{\text{ref}}(n)^\top$.
//!
//! Two exact algorithms, chosen by cost: direct sums, blocked so that each stretch of the
//! record is read once for all lags, and zero-padded FFTs over segments (overlap-save), which
//! cost $O(N\,l\,(\log M + l_{\text{ref}}))$ for any number of lags. Neither builds a block data
//! matrix: memory beyond the record is $O(l\,l_{\text{ref}}\,M)$.

use realfft::RealFftPlanner;
use realfft::num_complex::Complex;

/// Correlation matrices $R_k$ (l × r, column-major) for lags 0..lags.
#[derive(Debug, Clone, PartialEq)]
pub struct Correlations {
    /// Number of output channels l.
    pub channels: usize,
    /// Number of reference channels r.
    pub references: usize,
    /// `r[k]` is $R_k$, entry (a, b) at `a + b·l`.
    pub r: Vec<Vec<f64>>,
}

impl Correlations {
    /// Entry (a, b) of $R_k$: channel `a` lagged by k against reference `b`.
    pub fn at(&self, k: usize, a: usize, b: usize) -> f64 {
        self.r[k][a + b * self.channels]
    }
}

/// Direct sums (reference implementation and fastest for few lags and channels).
pub fn direct(y: &[&[f64]], refs: &[usize], lags: usize) -> Correlations {
    direct_centred(y, refs, lags, &vec![0.0; y.len()])
}

/// [`direct`] of `y` minus `means` (one per channel), centred stretch by stretch.
fn direct_centred(y: &[&[f64]], refs: &[usize], lags: usize, means: &[f64]) -> Correlations {
    let l = y.len();
    let nr = refs.len();
    let n = y[0].len();
    let mut acc = vec![vec![0.0; l * nr]; lags];
    const BLOCK: usize = 4096;
    // Each channel's stretch [start, end + lags), centred, in a buffer that stays in cache.
    let mut c: Vec<Vec<f64>> = vec![vec![0.0; BLOCK + lags]; l];
    let mut start = 0;
    while start < n {
        let end = (start + BLOCK).min(n);
        let reach = (end + lags).min(n);
        for ((ca, ya), m) in c.iter_mut().zip(y).zip(means) {
            for (d, v) in ca.iter_mut().zip(&ya[start..reach]) {
                *d = v - m;
            }
        }
        for (k, ak) in acc.iter_mut().enumerate() {
            if start + k >= n {
                break;
            }
            let stop = end.min(n - k);
            if stop <= start {
                continue;
            }
            let len = stop - start;
            for (bi, &b) in refs.iter().enumerate() {
                let yb = &c[b][..len];
                for (a, ca) in c.iter().enumerate() {
                    ak[a + bi * l] += dot(&ca[k..k + len], yb);
                }
            }
        }
        start = end;
    }
    for (k, ak) in acc.iter_mut().enumerate() {
        let d = (n - k) as f64;
        for v in ak.iter_mut() {
            *v /= d;
        }
    }
    Correlations {
        channels: l,
        references: nr,
        r: acc,
    }
}

#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    // Sixteen independent accumulators hide the latency of the vectorised multiply-adds.
    let mut s = [0.0f64; 16];
    let chunks = a.len() / 16;
    for (ca, cb) in a.chunks_exact(16).zip(b.chunks_exact(16)) {
        for j in 0..16 {
            s[j] += ca[j] * cb[j];
        }
    }
    let mut t: f64 = s.iter().sum();
    for i in chunks * 16..a.len() {
        t += a[i] * b[i];
    }
    t
}

/// FFT size for `lags` lags: four times the lags, at least 256 (small transforms stay in L1).
fn fft_size(lags: usize) -> usize {
    (4 * lags).max(256).next_power_of_two()
}

/// Segmented zero-padded FFT (exact, up to rounding). The record is split into stretches
/// processed in parallel (rayon), each accumulating its own cross-spectra.
pub fn fft(y: &[&[f64]], refs: &[usize], lags: usize) -> Correlations {
    fft_centred(y, refs, lags, &vec![0.0; y.len()])
}

/// [`fft`] of `y` minus `means` (one per channel), centred as each block is transformed.
fn fft_centred(y: &[&[f64]], refs: &[usize], lags: usize, means: &[f64]) -> Correlations {
    use rayon::prelude::*;
    let l = y.len();
    let nr = refs.len();
    let n = y[0].len();
    let m = fft_size(lags);
    let block = m - lags + 1; // block + lags − 1 ≤ m: no circular wrap for lags < `lags`
    let bins = m / 2 + 1;
    let nblocks = n.div_ceil(block);
    // A fixed number of stretches, whatever the thread count, so that the summation order —
    // and so every bit of the result — does not depend on the machine.
    let per = nblocks.div_ceil(8).max(1);
    let starts: Vec<usize> = (0..nblocks).step_by(per).collect();
    let partial: Vec<Vec<f64>> = starts
        .par_iter()
        .map(|&b0| {
            let b1 = (b0 + per).min(nblocks);
            accumulate(
                y,
                means,
                refs,
                lags,
                m,
                block,
                b0 * block,
                (b1 * block).min(n),
            )
        })
        .collect();
    // Sum the stretches: acc holds, per pair (a, b), re[bins] then im[bins].
    let mut acc = vec![0.0; l * nr * 2 * bins];
    for p in &partial {
        for (a, v) in acc.iter_mut().zip(p) {
            *a += v;
        }
    }
    let mut planner = RealFftPlanner::<f64>::new();
    let inv = planner.plan_fft_inverse(m);
    let mut buf = vec![0.0; m];
    let mut spec = inv.make_input_vec();
    let mut iscratch = inv.make_scratch_vec();
    let mut r = vec![vec![0.0; l * nr]; lags];
    for p in 0..l * nr {
        let (re, im) = acc[p * 2 * bins..(p + 1) * 2 * bins].split_at(bins);
        for (k, s) in spec.iter_mut().enumerate() {
            *s = Complex::new(re[k], im[k]);
        }
        // The imaginary parts of the DC and Nyquist bins are rounding noise of a real signal.
        spec[0].im = 0.0;
        spec[bins - 1].im = 0.0;
        inv.process_with_scratch(&mut spec, &mut buf, &mut iscratch)
            .expect("sizes from the plan");
        for (k, rk) in r.iter_mut().enumerate() {
            rk[p] = buf[k] / (m as f64 * (n - k) as f64);
        }
    }
    Correlations {
        channels: l,
        references: nr,
        r,
    }
}

/// Cross-spectra Σ conj(X_ref) · Y of the centred channels over the blocks starting in
/// [from, to).
#[allow(clippy::too_many_arguments)]
fn accumulate(
    y: &[&[f64]],
    means: &[f64],
    refs: &[usize],
    lags: usize,
    m: usize,
    block: usize,
    from: usize,
    to: usize,
) -> Vec<f64> {
    let (l, nr, n) = (y.len(), refs.len(), y[0].len());
    let bins = m / 2 + 1;
    let mut planner = RealFftPlanner::<f64>::new();
    let fwd = planner.plan_fft_forward(m);
    let mut scratch = fwd.make_scratch_vec();
    let mut buf = vec![0.0; m];
    let mut spec = fwd.make_output_vec();
    // Split re/im (structure of arrays) so the accumulation vectorises.
    let mut xr = vec![0.0; nr * bins];
    let mut xi = vec![0.0; nr * bins];
    let mut yr = vec![0.0; l * bins];
    let mut yi = vec![0.0; l * bins];
    let mut acc = vec![0.0; l * nr * 2 * bins];
    let mut start = from;
    while start < to {
        let bend = (start + block).min(n);
        let send = (start + block + lags - 1).min(n);
        let mut transform = |src: &[f64], mean: f64, re: &mut [f64], im: &mut [f64]| {
            for (d, v) in buf.iter_mut().zip(src) {
                *d = v - mean;
            }
            buf[src.len()..].fill(0.0);
            fwd.process_with_scratch(&mut buf, &mut spec, &mut scratch)
                .expect("sizes from the plan");
            for (k, c) in spec.iter().enumerate() {
                re[k] = c.re;
                im[k] = c.im;
            }
        };
        for (bi, &b) in refs.iter().enumerate() {
            let s = bi * bins..(bi + 1) * bins;
            transform(&y[b][start..bend], means[b], &mut xr[s.clone()], &mut xi[s]);
        }
        for (a, ya) in y.iter().enumerate() {
            let s = a * bins..(a + 1) * bins;
            transform(&ya[start..send], means[a], &mut yr[s.clone()], &mut yi[s]);
        }
        for bi in 0..nr {
            let (br, bim) = (
                &xr[bi * bins..(bi + 1) * bins],
                &xi[bi * bins..(bi + 1) * bins],
            );
            for a in 0..l {
                let (ar, ai) = (&yr[a * bins..(a + 1) * bins], &yi[a * bins..(a + 1) * bins]);
                let p = a + bi * l;
                let (sr, si) = acc[p * 2 * bins..(p + 1) * 2 * bins].split_at_mut(bins);
                // conj(X) · Y
                for k in 0..bins {
                    sr[k] += br[k] * ar[k] + bim[k] * ai[k];
                    si[k] += br[k] * ai[k] - bim[k] * ar[k];
                }
            }
        }
        start = bend;
    }
    acc
}

/// The cheaper of [`direct`] and [`fft`] for this size.
pub fn estimate(y: &[&[f64]], refs: &[usize], lags: usize) -> Correlations {
    estimate_centred(y, refs, lags, &vec![0.0; y.len()])
}

/// [`estimate`] of `y` minus `means` (one per channel), without a centred copy of the record.
pub(crate) fn estimate_centred(
    y: &[&[f64]],
    refs: &[usize],
    lags: usize,
    means: &[f64],
) -> Correlations {
    let l = y.len() as f64;
    let nr = refs.len() as f64;
    let m = fft_size(lags) as f64;
    // Operations per sample: direct l·r·lags multiply-adds; FFT (l + r) transforms of size
    // m per (m − lags) samples (≈ 2.5 m log2 m flops each) plus l·r complex products per bin.
    let direct_cost = l * nr * lags as f64;
    let fft_cost = ((l + nr) * 1.25 * m * m.log2() + l * nr * 2.0 * m) / (m - lags as f64);
    if direct_cost <= fft_cost {
        direct_centred(y, refs, lags, means)
    } else {
        fft_centred(y, refs, lags, means)
    }
}
