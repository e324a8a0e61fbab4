//! The block Toeplitz matrix of the correlations, $T$ ($l\,i \times r\,i$, block $(p, q)$ =
//! $R_{i+p-q}$), stored when small and otherwise applied without being stored.
//!
//! Applied, $T x$ is a convolution: with $h_k = R_k$ ($k = 0 \dots 2i-1$) and $x$ cut into
//! blocks $x_q \in \mathbb R^r$, $(T x)_p = \sum_q h_{i+p-q} x_q = c_{i+p}$, where $c = h * x$.
//! A circular convolution of length $M \ge 2i$ equals the linear one at $i \dots 2i-1$ (the
//! linear one ends at $3i-2 < M + i$), so $T x$ is read from $\mathcal F^{-1}(H X)$ at offset
//! $i$; $T^\top z$ is the correlation $\sum_p h_{i+p-q}^\top z_p$, read from
//! $\mathcal F^{-1}(H^* Z)$ at $M - i + q$. $H$ (the FFT of every entry's lags) holds
//! $l\,r\,(M/2+1)$ complex values instead of $T$'s $l\,r\,i^2$ reals, and one product costs
//! $(l + r)$ FFTs of length $M$ and $l\,r\,(M/2+1)$ complex products instead of $l\,r\,i^2$.

use std::sync::Arc;

use rayon::prelude::*;
use realfft::num_complex::Complex;
use realfft::{ComplexToReal, RealFftPlanner, RealToComplex};

use crate::Correlations;
use crate::linalg::{Dense, Operator};

/// Most entries of a stored Toeplitz matrix: at this size (1200 × 1200, 11 MB) a full SVD
/// takes about a second; past it, the matrix is applied by FFT and only its leading
/// singular triplets are sought.
pub(crate) const MAX_STORED_ENTRIES: usize = 1200 * 1200;

/// Vectors one rayon task applies the matrix to (each task keeps its own FFT buffers).
const VECTORS_PER_TASK: usize = 8;

/// The block Toeplitz matrix of `corr` with `i` block rows, scaled by `scale`.
pub(crate) enum Toeplitz {
    /// Stored densely.
    Stored(Dense),
    /// Applied by FFT.
    Applied(BlockToeplitz),
}

impl Toeplitz {
    /// Stored when it has at most [`MAX_STORED_ENTRIES`] entries, else applied.
    pub(crate) fn new(corr: &Correlations, i: usize, scale: f64) -> Toeplitz {
        let (l, r) = (corr.channels, corr.references);
        if (l * i).saturating_mul(r * i) <= MAX_STORED_ENTRIES {
            Toeplitz::Stored(stored(corr, i, scale))
        } else {
            Toeplitz::Applied(BlockToeplitz::new(corr, i, scale))
        }
    }
}

/// `T` built entry by entry.
pub(crate) fn stored(corr: &Correlations, i: usize, scale: f64) -> Dense {
    let (l, r) = (corr.channels, corr.references);
    let mut t = Dense::zeros(l * i, r * i);
    for p in 0..i {
        for q in 0..i {
            let rk = &corr.r[i + p - q];
            for b in 0..r {
                for a in 0..l {
                    t.set(p * l + a, q * r + b, scale * rk[a + b * l]);
                }
            }
        }
    }
    t
}

/// `T` applied by FFT: see the [module](self).
pub(crate) struct BlockToeplitz {
    l: usize,
    r: usize,
    i: usize,
    len: usize,
    /// `h[bin * l * r + b * l + a]`: the FFT of entry (a, b)'s lags 0 … 2i − 1, scaled, over
    /// the circular length (divided by it, so that the inverse FFT needs no scaling).
    h: Vec<Complex<f64>>,
    forward: Arc<dyn RealToComplex<f64>>,
    inverse: Arc<dyn ComplexToReal<f64>>,
}

impl BlockToeplitz {
    fn new(corr: &Correlations, i: usize, scale: f64) -> BlockToeplitz {
        let (l, r) = (corr.channels, corr.references);
        let len = smooth_length(2 * i);
        let mut planner = RealFftPlanner::<f64>::new();
        let forward = planner.plan_fft_forward(len);
        let inverse = planner.plan_fft_inverse(len);
        let bins = len / 2 + 1;
        let mut h = vec![Complex::new(0.0, 0.0); bins * l * r];
        let mut buf = vec![0.0; len];
        let mut spec = forward.make_output_vec();
        let norm = scale / len as f64;
        for b in 0..r {
            for a in 0..l {
                buf.fill(0.0);
                for (k, rk) in corr.r.iter().take(2 * i).enumerate() {
                    buf[k] = norm * rk[a + b * l];
                }
                forward
                    .process(&mut buf, &mut spec)
                    .expect("buffer sizes from the plan");
                for (bin, v) in spec.iter().enumerate() {
                    h[bin * l * r + b * l + a] = *v;
                }
            }
        }
        BlockToeplitz {
            l,
            r,
            i,
            len,
            h,
            forward,
            inverse,
        }
    }

    /// `T x` (`transpose` false) or `Tᵀ x` for each column of `x`.
    fn product(&self, x: &Dense, transpose: bool) -> Dense {
        let (inputs, outputs) = if transpose {
            (self.l, self.r)
        } else {
            (self.r, self.l)
        };
        let (i, len) = (self.i, self.len);
        let out_rows = outputs * i;
        let columns: Vec<Vec<f64>> = (0..x.cols)
            .collect::<Vec<_>>()
            .par_chunks(VECTORS_PER_TASK)
            .flat_map_iter(|chunk| {
                let bins = len / 2 + 1;
                let mut buf = vec![0.0; len];
                let mut xs = vec![Complex::new(0.0, 0.0); bins * inputs];
                let mut ys = vec![Complex::new(0.0, 0.0); bins];
                let mut spec = self.forward.make_output_vec();
                chunk
                    .iter()
                    .map(|&c| {
                        let col = &x.data[c * x.rows..(c + 1) * x.rows];
                        for j in 0..inputs {
                            buf.fill(0.0);
                            for q in 0..i {
                                buf[q] = col[q * inputs + j];
                            }
                            self.forward
                                .process(&mut buf, &mut spec)
                                .expect("buffer sizes from the plan");
                            xs[j * bins..(j + 1) * bins].copy_from_slice(&spec);
                        }
                        let mut out = vec![0.0; out_rows];
                        for o in 0..outputs {
                            for (bin, y) in ys.iter_mut().enumerate() {
                                let h = &self.h[bin * self.l * self.r..];
                                *y = (0..inputs)
                                    .map(|j| {
                                        let x = xs[j * bins + bin];
                                        if transpose {
                                            h[o * self.l + j].conj() * x
                                        } else {
                                            h[j * self.l + o] * x
                                        }
                                    })
                                    .sum();
                            }
                            // The imaginary parts of the zero bin, and of the Nyquist bin
                            // of an even length, are rounding.
                            ys[0].im = 0.0;
                            if len % 2 == 0 {
                                ys[bins - 1].im = 0.0;
                            }
                            self.inverse
                                .process(&mut ys, &mut buf)
                                .expect("buffer sizes from the plan");
                            for p in 0..i {
                                let at = if transpose { len - i + p } else { i + p };
                                out[p * outputs + o] = buf[at];
                            }
                        }
                        out
                    })
                    .collect::<Vec<_>>()
            })
            .collect();
        Dense {
            rows: out_rows,
            cols: x.cols,
            data: columns.concat(),
        }
    }
}

impl Operator for BlockToeplitz {
    fn rows(&self) -> usize {
        self.l * self.i
    }
    fn cols(&self) -> usize {
        self.r * self.i
    }
    fn apply(&self, x: &Dense) -> Dense {
        self.product(x, false)
    }
    fn apply_t(&self, y: &Dense) -> Dense {
        self.product(y, true)
    }
}

/// The smallest length at least `n` whose only prime factors are 2, 3 and 5 (fast FFTs).
pub(crate) fn smooth_length(n: usize) -> usize {
    (n.max(1)..)
        .find(|&m| {
            let mut k = m;
            for p in [2, 3, 5] {
                while k % p == 0 {
                    k /= p;
                }
            }
            k == 1
        })
        .expect("5-smooth numbers are unbounded")
}

/// A `rows × cols` block of standard normal numbers from `seed` (splitmix64 and
/// Box–Muller): the start of subspace iteration, the same on every run.
pub(crate) fn gaussian_start(rows: usize, cols: usize, seed: u64) -> Dense {
    let mut state = seed;
    let mut next = || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        // 53 bits in (0, 1].
        ((z >> 11) as f64 + 1.0) / (1u64 << 53) as f64
    };
    let mut d = Dense::zeros(rows, cols);
    for v in d.data.iter_mut() {
        let (u1, u2) = (next(), next());
        *v = (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos();
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    fn correlations(l: usize, r: usize, lags: usize) -> Correlations {
        let start = gaussian_start(l * r, lags, 7);
        Correlations {
            channels: l,
            references: r,
            r: (0..lags)
                .map(|k| start.data[k * l * r..(k + 1) * l * r].to_vec())
                .collect(),
        }
    }

    /// The FFT products equal the stored matrix's, for both the product and its transpose,
    /// with more channels than references and an `i` whose `2i` is not 5-smooth.
    #[test]
    fn products_by_fft_equal_the_stored_matrix() {
        let (l, r, i) = (5, 3, 7);
        let corr = correlations(l, r, 2 * i);
        let t = stored(&corr, i, 0.5);
        let fast = BlockToeplitz::new(&corr, i, 0.5);
        assert_eq!(fast.len, 15);
        let x = gaussian_start(r * i, 11, 3);
        let z = gaussian_start(l * i, 11, 4);
        for (got, want) in [
            (fast.apply(&x), t.apply(&x)),
            (fast.apply_t(&z), t.apply_t(&z)),
        ] {
            assert_eq!((got.rows, got.cols), (want.rows, want.cols));
            let size = want.data.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for (g, w) in got.data.iter().zip(&want.data) {
                // Sums of 2i·r terms of size ~1 through FFTs of length 15: rounding only.
                approx::assert_abs_diff_eq!(g, w, epsilon = 1e-12 * size);
            }
        }
    }

    /// Subspace iteration on the FFT operator finds the full SVD's leading singular values.
    #[test]
    fn iterated_singular_values_match_the_full_svd() {
        let (l, r, i) = (4, 4, 30);
        let corr = correlations(l, r, 2 * i);
        let t = stored(&corr, i, 1.0);
        let (_, full) = crate::linalg::thin_svd_u(&t).unwrap();
        let fast = BlockToeplitz::new(&corr, i, 1.0);
        let k = 10;
        let found = crate::linalg::leading_svd_iterated(
            &fast,
            gaussian_start(l * i, 3 * k, 1),
            k,
            (1e-10, 500),
            &|_| {},
        )
        .unwrap();
        assert!(found.converged, "residual {}", found.residual);
        for (got, want) in found.values.iter().zip(&full).take(k) {
            // A residual of 1e-10·σ₁ bounds each value's error by about that much.
            approx::assert_relative_eq!(got, want, max_relative = 1e-8);
        }
    }

    #[test]
    fn smooth_lengths_have_only_small_prime_factors() {
        assert_eq!(smooth_length(14), 15);
        assert_eq!(smooth_length(1000), 1000);
        assert_eq!(smooth_length(1001), 1024);
        assert_eq!(smooth_length(502), 512);
        assert_eq!(smooth_length(0), 1);
    }
}
