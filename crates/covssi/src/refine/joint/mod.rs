//! The joint likelihood of several channels: the Whittle likelihood of the vector of their
//! Fourier transforms $x_k$, cross-spectra included,
//!
//! $$ L(\theta) = \sum_k \Big[\ln\det S(\omega_k) + x_k^H S(\omega_k)^{-1} x_k\Big], \qquad
//! S = H\,\Sigma\,H^H,\quad
//! H(z) = I + \sum_r \Big[\frac{c_r k_r^\top}{z-\mu_r} + \frac{\bar c_r \bar k_r^\top}{z-\bar\mu_r}\Big], $$
//!
//! the innovation form of a sampled linear system of $m$ modes driven by white noise, plus
//! white measurement noise, in modal coordinates: each mode enters through its discrete pole
//! $\mu_r$ (shared with the per-channel model), its shape $c_r$ and its gain $k_r$ from the
//! innovations ($k_r$ normalised to 1 in one component), and $\Sigma = \Lambda\Lambda^\top$
//! ($\Lambda$ lower triangular, its diagonal by logarithms). For one channel $H = B/A$ in
//! partial fractions, the per-channel model. (A common denominator with a matrix numerator,
//! $S = B\Sigma B^H/|A|^2$, describes the same spectra but must place $l-1$ zeros next to each
//! lightly damped pole to cancel it off the mode's shape; those near-cancellations made its
//! scoring crawl on low-noise records.)
//!
//! With $\varepsilon_k = \Lambda^{-1}H^{-1}x_k$ (the whitened transform) the score and the
//! Fisher information are sums over $k$ of $\operatorname{tr}\big((\varepsilon\varepsilon^H - I)X_t\big)$
//! and $\operatorname{tr}(X_s X_t)$, where $X_t = \Lambda^{-1}H^{-1}(\partial_t S)H^{-H}\Lambda^{-\top}$
//! is Hermitian: stacking each $X_t$'s $l^2$ real coordinates makes both a least-squares
//! product.

use super::model::scoring::scoring;
use super::model::{Fit, Model};
use super::options::RefineOptions;
use super::parametrization::{discrete_poles, unpack};
use super::results::MisfitCounts;
use crate::error::SsiError;
use crate::linalg::C64;
use std::ops::Range;

/// Bins per parallel chunk (each gives l² rows of the Jacobian).
const CHUNK: usize = 32;

/// Iterations of the first phase of [`Joint::fit`], the poles held. On a 16-channel, 8-mode
/// record of the bench's generator (seed 8, measured with a temporary program, not a
/// repository command) the fit by bands lands on the same estimates (their z-scores equal to
/// 0.05) with this cap as with the default 200, in 94 s instead of 150 s.
const SETTLE_ITERATIONS: usize = 40;

/// The joint model of a record's channels, over a band of its frequencies, with its first
/// `free` modes fitted and the others held.
pub(super) struct Joint<'a> {
    /// The record's spectra.
    rec: &'a Model,
    /// For each mode, the component of k_r held at 1.
    refs: Vec<usize>,
    /// Modes 0..free are fitted; θ (in [`Self::eval`] and [`Self::fit`]) holds theirs and Λ,
    /// laid out as for a model of `free` modes.
    free: usize,
    /// The held modes' parameters: their ln ω, their logit ζ, then their c and k.
    held: Vec<f64>,
    /// The bins of the record's spectra that L sums over.
    band: Range<usize>,
}

/// Number of parameters for l channels and m modes: per mode ln ω, logit ζ, c (2l reals) and
/// k (2l − 2 reals), then Λ.
pub(super) fn parameters(l: usize, m: usize) -> usize {
    4 * l * m + l * (l + 1) / 2
}

/// Where, in θ of a fit of `free` modes (the layout [`Joint::fit`] returns: their ln ω, their
/// logit ζ, their blocks of c and k, then Λ) on `l` channels, the real parts of free mode
/// `i`'s shape c begin; the imaginary parts follow them.
pub(super) fn shape_offset(i: usize, free: usize, l: usize) -> usize {
    2 * free + i * (4 * l - 2)
}

/// θ of all `m` modes (for `l` channels) split into the first `free` modes' and Λ, and the
/// others' ([`layout`]); [`Joint::full`] puts them back together.
fn split(th: &[f64], m: usize, free: usize, l: usize) -> (Vec<f64>, Vec<f64>) {
    let (mut fitted, mut held) = (Vec::new(), Vec::new());
    for (r, is_free) in layout(m, free, l, th.len()) {
        if is_free { &mut fitted } else { &mut held }.extend_from_slice(&th[r]);
    }
    (fitted, held)
}

const ZERO: C64 = C64 { re: 0.0, im: 0.0 };

/// The stretches of θ of all `m` modes (`len` entries, for `l` channels), in order, each
/// marked free (the first `free` modes' and Λ) or held: the ln ω, the logit ζ, the modes'
/// blocks of c and k, then Λ.
fn layout(m: usize, free: usize, l: usize, len: usize) -> [(Range<usize>, bool); 7] {
    let (b, bl) = (2 * m, 4 * l - 2);
    [
        (0..free, true),
        (free..m, false),
        (m..m + free, true),
        (m + free..b, false),
        (b..b + free * bl, true),
        (b + free * bl..b + m * bl, false),
        (b + m * bl..len, true),
    ]
}

impl<'a> Joint<'a> {
    /// The model over the frequencies `band` and θ to start from, given the poles of a
    /// per-channel fit (`poles`: the modes' ln ω, then their logit ζ), of which the first
    /// `free` are fitted and the others held: the poles μ_r, and c_r, k_r, Σ by regressions on
    /// the record (every mode's, over the whole record). A long
    /// autoregression of y gives the innovations ε̂; then y_t − ε̂_t = Σ_r 2 Re(R_r φ_{r,t}),
    /// φ_{r,t} = Σ_{j≥1} μ_r^{j−1} ε̂_{t−j}, is linear in the residues R_r = c_r k_rᵀ, whose
    /// best rank-one parts give c_r and k_r; Σ is the covariance of ε̂. `None` if a
    /// regression is singular or Σ is not positive definite (a channel that the others predict
    /// exactly, e.g. a copy).
    pub(super) fn start(
        rec: &'a Model,
        poles: &[f64],
        free: usize,
        band: Range<usize>,
    ) -> Option<(Self, Vec<f64>)> {
        let l = rec.l();
        let m = poles.len() / 2;
        let mu = discrete_poles(&unpack(poles, m), rec.fs)?;
        // The regressions run on the record's start (centred), enough for a start.
        let y = &rec.sp.head;
        let n = y.first()?.len();
        // Long autoregression: order 6m (at least 4), at most a tenth of the samples.
        let p = (6 * m).max(4).min(n / 10);
        let fill_lags = |t: usize, x: &mut [f64]| {
            for lag in 1..=p {
                for c in 0..l {
                    x[(lag - 1) * l + c] = y[c][t - lag];
                }
            }
        };
        let ar = regress(n - p, l * p, l, |r, x, yv| {
            fill_lags(r + p, x);
            for c in 0..l {
                yv[c] = y[c][r + p];
            }
        })?;
        // Innovations ε̂_t for t ≥ p (index t − p).
        let mut eps = vec![vec![0.0; n - p]; l];
        let mut x = vec![0.0; l * p];
        for t in p..n {
            fill_lags(t, &mut x);
            for (c, ec) in eps.iter_mut().enumerate() {
                ec[t - p] = y[c][t] - (0..l * p).map(|i| x[i] * ar.at(i, c)).sum::<f64>();
            }
        }
        let len = n - p;
        // φ_{r,t} for every mode, by the recursion φ_{t+1} = μ φ_t + ε̂_t from φ = 0, carried
        // along as the rows are filled in order (so it is never stored for every t).
        let mut phi = vec![ZERO; m * l];
        let res = regress(len, 2 * l * m, l, |t, xr, yv| {
            if t > 0 {
                for r in 0..m {
                    for c in 0..l {
                        phi[r * l + c] = mu[2 * r] * phi[r * l + c] + eps[c][t - 1];
                    }
                }
            }
            for r in 0..m {
                for c in 0..l {
                    xr[2 * l * r + c] = phi[r * l + c].re;
                    xr[2 * l * r + l + c] = phi[r * l + c].im;
                }
            }
            for c in 0..l {
                yv[c] = y[c][t + p] - eps[c][t];
            }
        })?;
        let mut th = poles.to_vec();
        let mut refs = Vec::with_capacity(m);
        for r in 0..m {
            // 2 Re(R φ) = 2 Re R · Re φ − 2 Im R · Im φ.
            let big_r: Vec<C64> = (0..l * l)
                .map(|i| {
                    let (a, b) = (i / l, i % l);
                    C64::new(res.at(2 * l * r + b, a), -res.at(2 * l * r + l + b, a)) * 0.5
                })
                .collect();
            let (c, k, at) = rank_one(&big_r, l)?;
            refs.push(at);
            th.extend(c.iter().map(|v| v.re));
            th.extend(c.iter().map(|v| v.im));
            for (b, kb) in k.iter().enumerate() {
                if b != at {
                    th.push(kb.re);
                    th.push(kb.im);
                }
            }
        }
        let count = len as f64;
        let mut sigma = vec![0.0; l * l];
        for a in 0..l {
            for b in 0..=a {
                sigma[a * l + b] =
                    eps[a].iter().zip(&eps[b]).map(|(u, v)| u * v).sum::<f64>() / count;
            }
        }
        let chol = cholesky(&sigma, l)?;
        th.extend((0..l).map(|a| chol[a * l + a].ln()));
        for a in 1..l {
            th.extend((0..a).map(|b| chol[a * l + b]));
        }
        if !th.iter().all(|v| v.is_finite()) {
            return None;
        }
        let (fth, held) = split(&th, m, free, l);
        let joint = Joint {
            rec,
            refs,
            free,
            held,
            band,
        };
        Some((joint, fth))
    }

    /// θ of all modes from the free modes' θ and the held parameters.
    fn full(&self, th: &[f64]) -> Vec<f64> {
        let len = th.len() + self.held.len();
        let (mut free, mut held) = (th, &self.held[..]);
        let mut v = Vec::with_capacity(len);
        for (r, is_free) in layout(self.refs.len(), self.free, self.l(), len) {
            let from = if is_free { &mut free } else { &mut held };
            let (now, rest) = from.split_at(r.len());
            v.extend_from_slice(now);
            *from = rest;
        }
        v
    }

    fn l(&self) -> usize {
        self.rec.l()
    }

    /// Fisher scoring of the joint likelihood from θ: first with the poles held, so that the
    /// shapes and gains (from regressions) settle where the poles are (at most
    /// [`SETTLE_ITERATIONS`]), then over the frequencies `narrow` with only the first `moving`
    /// modes free, poles and all, the others held where the first phase left them. The model
    /// is then that of `moving` free modes over `narrow`: θ of the fit returned is theirs and
    /// Λ.
    pub(super) fn fit(
        &mut self,
        th: Vec<f64>,
        moving: usize,
        narrow: Range<usize>,
        opts: &RefineOptions,
    ) -> Result<Fit, SsiError> {
        let eval = |t: &[f64], derivs: bool| self.eval(t, derivs, false);
        let settle = RefineOptions {
            max_iterations: opts.max_iterations.min(SETTLE_ITERATIONS),
            ..opts.clone()
        };
        let held = scoring(
            eval,
            th,
            (self.free, 0),
            &settle,
            opts.tolerance,
            2 * self.free,
            None,
        )?;
        // Modes moving..free join the held ones.
        let (th, kept) = split(&self.full(&held.theta), self.refs.len(), moving, self.l());
        self.free = moving;
        self.held = kept;
        self.band = narrow;
        let eval = |t: &[f64], derivs: bool| self.eval(t, derivs, false);
        let free = scoring(eval, th, (moving, 0), opts, opts.tolerance, 0, None)?;
        Ok(Fit {
            iterations: held.iterations + free.iterations,
            ..free
        })
    }

    /// The misfit's counts of the whitened periodogram ordinates |ε_c(ω_k)|² (unit
    /// exponential under the model).
    pub(super) fn misfit(&self, th: &[f64]) -> Option<MisfitCounts> {
        self.eval(th, false, true).and_then(|e| e.misfit)
    }

    /// The shapes c_r of every mode, in the model's order, given θ of the fitted modes and Λ
    /// (a [`Fit`]'s).
    pub(super) fn fitted_shapes(&self, th: &[f64]) -> Vec<Vec<C64>> {
        self.shapes(&self.full(th)).0
    }

    /// c_r and k_r of θ (k_r with its reference component 1).
    fn shapes(&self, th: &[f64]) -> (Vec<Vec<C64>>, Vec<Vec<C64>>) {
        let l = self.l();
        let m = self.refs.len();
        let mut cs = Vec::with_capacity(m);
        let mut ks = Vec::with_capacity(m);
        for (r, &at) in self.refs.iter().enumerate() {
            let off = 2 * m + r * (4 * l - 2);
            cs.push(
                (0..l)
                    .map(|a| C64::new(th[off + a], th[off + l + a]))
                    .collect(),
            );
            let mut t = off + 2 * l;
            ks.push(
                (0..l)
                    .map(|b| {
                        if b == at {
                            C64::new(1.0, 0.0)
                        } else {
                            t += 2;
                            C64::new(th[t - 2], th[t - 1])
                        }
                    })
                    .collect(),
            );
        }
        (cs, ks)
    }

    /// Λ (row-major, lower triangular) and its inverse from θ's last l(l+1)/2 entries.
    fn lambda(&self, th: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let l = self.l();
        let off = th.len() - l * (l + 1) / 2;
        let mut lam = vec![0.0; l * l];
        for a in 0..l {
            lam[a * l + a] = th[off + a].exp();
        }
        let mut t = off + l;
        for a in 1..l {
            for b in 0..a {
                lam[a * l + b] = th[t];
                t += 1;
            }
        }
        // Forward substitution, column by column of the identity.
        let mut inv = vec![0.0; l * l];
        for col in 0..l {
            for a in col..l {
                let mut v = if a == col { 1.0 } else { 0.0 };
                for b in col..a {
                    v -= lam[a * l + b] * inv[b * l + col];
                }
                inv[a * l + col] = v / lam[a * l + a];
            }
        }
        (lam, inv)
    }
}

mod eval;
mod shapes;
mod small;
pub(super) use shapes::ChannelShape;
use small::{cholesky, invert, rank_one, regress};

#[cfg(test)]
mod tests;
