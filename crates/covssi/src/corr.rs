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
    let l = y.len();
    let nr = refs.len();
    let n = y[0].len();
    let mut acc = vec![vec![0.0; l * nr]; lags];
    const BLOCK: usize = 4096;
    let mut start = 0;
    while start < n {
        let end = (start + BLOCK).min(n);
        for (k, ak) in acc.iter_mut().enumerate() {
            if start + k >= n {
                break;
            }
            let stop = end.min(n - k);
            if stop <= start {
                continue;
            }
            for (bi, &b) in refs.iter().enumerate() {
                let yb = &y[b][start..stop];
                for (a, ya) in y.iter().enumerate() {
                    let ya = &ya[start + k..stop + k];
                    ak[a + bi * l] += dot(ya, yb);
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
    // Four independent accumulators let the compiler vectorise the sum.
    let mut s = [0.0f64; 4];
    let chunks = a.len() / 4;
    for i in 0..chunks {
        for j in 0..4 {
            s[j] += a[4 * i + j] * b[4 * i + j];
        }
    }
    let mut t = (s[0] + s[1]) + (s[2] + s[3]);
    for i in chunks * 4..a.len() {
        t += a[i] * b[i];
    }
    t
}

/// Segmented zero-padded FFT (exact, up to rounding).
pub fn fft(y: &[&[f64]], refs: &[usize], lags: usize) -> Correlations {
    let l = y.len();
    let nr = refs.len();
    let n = y[0].len();
    let m = (4 * lags).max(2048).next_power_of_two();
    let block = m - lags + 1; // block + lags − 1 ≤ m: no circular wrap for lags < `lags`
    let bins = m / 2 + 1;
    let mut planner = RealFftPlanner::<f64>::new();
    let fwd = planner.plan_fft_forward(m);
    let inv = planner.plan_fft_inverse(m);
    let mut scratch = fwd.make_scratch_vec();
    let mut buf = vec![0.0; m];
    // Spectra of this segment: references (blocks) and all channels (segments).
    let mut xref = vec![vec![Complex::new(0.0, 0.0); bins]; nr];
    let mut yseg = vec![vec![Complex::new(0.0, 0.0); bins]; l];
    let mut acc = vec![vec![Complex::new(0.0, 0.0); bins]; l * nr];
    let mut start = 0;
    while start < n {
        let bend = (start + block).min(n);
        let send = (start + block + lags - 1).min(n);
        for (bi, &b) in refs.iter().enumerate() {
            buf.fill(0.0);
            buf[..bend - start].copy_from_slice(&y[b][start..bend]);
            fwd.process_with_scratch(&mut buf, &mut xref[bi], &mut scratch)
                .expect("sizes from the plan");
        }
        for (a, ya) in y.iter().enumerate() {
            buf.fill(0.0);
            buf[..send - start].copy_from_slice(&ya[start..send]);
            fwd.process_with_scratch(&mut buf, &mut yseg[a], &mut scratch)
                .expect("sizes from the plan");
        }
        for bi in 0..nr {
            let xb = &xref[bi];
            for a in 0..l {
                let ya = &yseg[a];
                let s = &mut acc[a + bi * l];
                for ((sv, xv), yv) in s.iter_mut().zip(xb).zip(ya) {
                    // conj(X) · Y
                    sv.re += xv.re * yv.re + xv.im * yv.im;
                    sv.im += xv.re * yv.im - xv.im * yv.re;
                }
            }
        }
        start = bend;
    }
    let mut r = vec![vec![0.0; l * nr]; lags];
    let mut iscratch = inv.make_scratch_vec();
    for (p, spec) in acc.iter_mut().enumerate() {
        // The imaginary parts of the DC and Nyquist bins are rounding noise of a real signal.
        spec[0].im = 0.0;
        spec[bins - 1].im = 0.0;
        inv.process_with_scratch(spec, &mut buf, &mut iscratch)
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

/// The cheaper of [`direct`] and [`fft`] for this size.
pub fn estimate(y: &[&[f64]], refs: &[usize], lags: usize) -> Correlations {
    let l = y.len() as f64;
    let nr = refs.len() as f64;
    let m = ((4 * lags).max(2048).next_power_of_two()) as f64;
    // Operations per sample: direct l·r·lags multiply-adds; FFT (l + r) transforms of size
    // m per (m − lags) samples (≈ 2.5 m log2 m flops each) plus l·r complex products per bin.
    let direct_cost = l * nr * lags as f64;
    let fft_cost = ((l + nr) * 1.25 * m * m.log2() + l * nr * 2.0 * m) / (m - lags as f64);
    if direct_cost <= fft_cost {
        direct(y, refs, lags)
    } else {
        fft(y, refs, lags)
    }
}
