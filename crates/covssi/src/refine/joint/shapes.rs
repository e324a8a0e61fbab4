//! Every channel's shape of the modes a joint fit of combinations found.
//!
//! A fit through combinations $z = Ty$ of the channels gives the modes' poles $\mu_r$, gains
//! $k_r$, the combinations' shapes $c_r$ and $\Sigma = \Lambda\Lambda^\top$, the innovation form
//! $z = H\varepsilon$ of the combinations. A channel $y_a = C_a x + w_a$ reads the same modal
//! state $x$, and $C_a$ in modal coordinates is its shape $\phi_a$. Its cross-spectrum with
//! the whitened innovations $\tilde\varepsilon = \Lambda^{-1}\varepsilon$, with
//! $M = H^{-H}\Lambda^{-\top}$, is then exactly
//!
//! $$ \hat S_{y_a z} M \approx \sum_r \Big[\frac{\phi_{a,r}\,k_r^\top\Lambda}{z-\mu_r}
//!    + \frac{\alpha_{a,r}\,c_r^\top M}{1-z\mu_r} + \text{conj.}\Big] + \beta_a^\top M, $$
//!
//! with $z = e^{i\omega}$: the part of $y_a$ the past innovations predict (through the Kalman
//! predictor of $x$, whose transfer from $\varepsilon$ is $(zI-A)^{-1}K$) is causal and carries
//! the shape; the state's prediction error $e_t$ and the channel's own noise in $z$ meet only
//! present and future innovations, and by the push-through identity
//! $C(I - zA + zKC)^{-1} = H(z^{-1})^{-1}C(I-zA)^{-1}$ (and $H(\bar z) = \bar H(z)$ on the unit
//! circle) that anticausal part is the second sum and the last term, with
//! $\alpha_a = E[y_a e_t^\top]$ and $\beta_a = E[w_a (Tw)^\top]$ unknown. Given the fit, this is
//! linear in $\phi_a$, $\alpha_a$, $\beta_a$: a least-squares fit over the fit's bins (rows
//! weighted by $\sqrt{n_b}$), the same regressors for every channel. The left side's error is
//! that of a cross-periodogram with white innovations, about $S_{v_a}/n_b$ in each entry,
//! $v_a$ what the innovations do not explain (mostly the channel's measurement noise), so
//! the rows are of about equal variance, and the covariance of the channels' coefficients is
//! $\hat\Sigma_v \otimes G^{-1}$, $G$ the normal matrix and $\hat\Sigma_v$ the residuals'
//! cross-products over the rows left after the fit.

use super::{Joint, ZERO, invert};
use crate::linalg::{self, C64, Dense};
use crate::refine::spectra::Spectra;
use rayon::prelude::*;

/// A mode's shape in every channel and the covariance of its entries: rows and columns
/// 0..l hold the real parts, l..2l the imaginary ones.
pub(in crate::refine) type ChannelShape = (Vec<C64>, Dense);

/// The channels' regression on the innovations.
struct Regression {
    /// Coefficients, cols × channels: Re and Im φ_r of each mode, Re and Im α_r, then β.
    b: Dense,
    /// The normal matrix's inverse.
    g_inv: Dense,
    /// The residuals' cross-products per observation, channels × channels (row-major).
    residual: Vec<f64>,
    l: usize,
}

impl Regression {
    /// The covariance, given the fit, of mode r's shape entries i and k (0..l its real
    /// parts, l..2l its imaginary ones): Σ_v ⊗ G⁻¹.
    fn covariance(&self, r: usize, i: usize, k: usize) -> f64 {
        let l = self.l;
        self.residual[(i % l) * l + k % l] * self.g_inv.at(2 * r + i / l, 2 * r + k / l)
    }
}

/// The normal equations of the channels' regression, summed over bins.
struct Normal {
    /// XᵀX, cols × cols.
    g: Dense,
    /// XᵀY, cols × channels.
    h: Dense,
}

/// What the regression needs of the channels, whatever θ: over the fit's band, each bin's
/// Ŝ Tᵀ (channels × combinations, row-major, bin after bin), the channels' own
/// Σ_b n_b Re Ŝ_b (YᵀY) and the count of real observations, two per frequency.
struct Cross {
    q: Vec<C64>,
    yy: Dense,
    rows: usize,
}

impl Cross {
    fn new(channels: &Spectra, rows: &[Vec<f64>], band: std::ops::Range<usize>) -> Self {
        let (l, lz) = (channels.l, rows.len());
        let mut q = Vec::with_capacity(band.len() * l * lz);
        let mut yy = Dense::zeros(l, l);
        let mut count = 0;
        for bin in band {
            let nb = channels.w[bin];
            for a in 0..l {
                for row in rows {
                    q.push((0..l).map(|c| channels.at(bin, a, c) * row[c]).sum());
                }
                for c in 0..l {
                    yy.set(a, c, yy.at(a, c) + nb * channels.at(bin, a, c).re);
                }
            }
            count += 2 * nb as usize;
        }
        Cross { q, yy, rows: count }
    }
}

impl Joint<'_> {
    /// The shapes, in every channel of `channels` (the spectra the combinations `rows` were
    /// made of, in the same bins), of the first `count` modes of this model, given θ of a fit
    /// (the free modes' and Λ) and its covariance `cov`, with their covariance: the
    /// regression's, given the fit, plus what the fit's own uncertainty carries into them,
    /// J cov Jᵀ with J the shapes' derivatives in θ (forward differences, steps a thousandth
    /// of each parameter's standard error, which err by about that fraction). The two parts
    /// are uncorrelated: the score of the combinations' likelihood is uncorrelated with that
    /// of the channels given them.
    /// `None` when the band has fewer than ten observations per unknown or the regression is
    /// singular.
    pub(in crate::refine) fn channel_shapes(
        &self,
        th: &[f64],
        cov: &Dense,
        (channels, rows): (&Spectra, &[Vec<f64>]),
        count: usize,
    ) -> Option<Vec<ChannelShape>> {
        let l = channels.l;
        let cross = Cross::new(channels, rows, self.band.clone());
        let reg = self.regression(th, &cross)?;
        // ∂(Re φ, Im φ)/∂θ_t of the `count` modes, for each t.
        let raw = |b: &Dense| -> Vec<f64> {
            (0..count)
                .flat_map(|r| (0..2 * l).map(move |i| b.at(2 * r + i / l, i % l)))
                .collect()
        };
        let base = raw(&reg.b);
        let columns: Vec<Vec<f64>> = (0..th.len())
            .into_par_iter()
            .map(|t| {
                let h = 1e-3 * cov.at(t, t).max(0.0).sqrt();
                if h == 0.0 {
                    return Some(vec![0.0; count * 2 * l]);
                }
                let mut moved = th.to_vec();
                moved[t] += h;
                let up = raw(&self.regression(&moved, &cross)?.b);
                Some(up.iter().zip(&base).map(|(u, b)| (u - b) / h).collect())
            })
            .collect::<Option<_>>()?;
        let np = th.len();
        let shapes = (0..count)
            .map(|r| {
                let phi: Vec<C64> = (0..l)
                    .map(|a| C64::new(reg.b.at(2 * r, a), reg.b.at(2 * r + 1, a)))
                    .collect();
                let mut out = Dense::zeros(2 * l, 2 * l);
                // J cov Jᵀ.
                let jc: Vec<Vec<f64>> = (0..2 * l)
                    .map(|i| {
                        (0..np)
                            .map(|u| {
                                (0..np)
                                    .map(|v| columns[v][r * 2 * l + i] * cov.at(v, u))
                                    .sum()
                            })
                            .collect()
                    })
                    .collect();
                for (i, jc_i) in jc.iter().enumerate() {
                    for k in 0..2 * l {
                        let prop: f64 = (0..np).map(|u| jc_i[u] * columns[u][r * 2 * l + k]).sum();
                        out.set(i, k, reg.covariance(r, i, k) + prop);
                    }
                }
                (phi, out)
            })
            .collect();
        Some(shapes)
    }

    /// The regression of the channels on the innovations at θ: its coefficients and what
    /// their covariance needs.
    fn regression(&self, th: &[f64], cross: &Cross) -> Option<Regression> {
        let full = self.full(th);
        let (m, l) = (self.refs.len(), cross.yy.rows);
        let cols = 4 * m + self.l();
        if cross.rows < 10 * cols {
            return None;
        }
        let ne = self.normal_equations(&full, cross)?;
        // Columns of very different sizes (a pole's terms near its peak against β's): the
        // normal matrix is inverted with its diagonal scaled to 1.
        let d: Vec<f64> = (0..cols).map(|i| 1.0 / ne.g.at(i, i).sqrt()).collect();
        if !d.iter().all(|v| v.is_finite()) {
            return None;
        }
        let mut gs = ne.g.clone();
        for i in 0..cols {
            for j in 0..cols {
                gs.set(i, j, ne.g.at(i, j) * d[i] * d[j]);
            }
        }
        let mut g_inv = linalg::spd_inverse(&gs)?;
        for i in 0..cols {
            for j in 0..cols {
                g_inv.set(i, j, g_inv.at(i, j) * d[i] * d[j]);
            }
        }
        // B = G⁻¹ XᵀY, and the residuals' cross-products YᵀY − Bᵀ XᵀY.
        let mut b = Dense::zeros(cols, l);
        for i in 0..cols {
            for a in 0..l {
                b.set(
                    i,
                    a,
                    (0..cols).map(|j| g_inv.at(i, j) * ne.h.at(j, a)).sum(),
                );
            }
        }
        let dof = (cross.rows - cols) as f64;
        let residual = |a: usize, c: usize| {
            (cross.yy.at(a, c) - (0..cols).map(|i| b.at(i, a) * ne.h.at(i, c)).sum::<f64>()) / dof
        };
        let residual = (0..l * l).map(|t| residual(t / l, t % l)).collect();
        Some(Regression {
            b,
            g_inv,
            residual,
            l,
        })
    }

    /// The normal equations of the regression of `channels`' cross-spectra with the whitened
    /// innovations on the model's terms, over this fit's band, at θ `full` of all modes.
    /// Columns: Re and Im φ_r of each mode, then Re and Im α_r, then β.
    fn normal_equations(&self, full: &[f64], cross: &Cross) -> Option<Normal> {
        let (m, lz, l) = (self.refs.len(), self.l(), cross.yy.rows);
        let cols = 4 * m + lz;
        let t = self.terms(full)?;
        let mu = &t.den.mu;
        let i1 = C64::new(0.0, 1.0);
        let mut ne = Normal {
            g: Dense::zeros(cols, cols),
            h: Dense::zeros(cols, l),
        };
        let mut x = vec![ZERO; cols * lz];
        let (mut h, mut d1, mut d2) = (vec![ZERO; lz * lz], vec![ZERO; m], vec![ZERO; m]);
        let mut rows_of = Rows::new(cols, lz, l, self.band.len().min(BINS));
        for bin in self.band.clone() {
            let z = self.rec.sp.z[bin];
            // H(z) with each mode's 1/(z − μ) and 1/(z − μ̄), then M = H⁻ᴴ Λ⁻ᵀ.
            self.transfer(&t, z, &mut h, &mut d1, &mut d2);
            let (h_inv, _) = invert(&h, lz)?;
            let mm = product(
                (lz, lz, lz),
                |i, k| h_inv[k * lz + i].conj(),
                |k, j| C64::new(t.lam_inv[j * lz + k], 0.0),
            );
            // The regressors' values at each output j.
            for r in 0..m {
                let (e1, e2) = (1.0 / (1.0 - z * mu[2 * r]), 1.0 / (1.0 - z * mu[2 * r + 1]));
                for j in 0..lz {
                    let (g1, g2) = (t.k_lam[r][j] * d1[r], t.kc_lam[r][j] * d2[r]);
                    let cm: C64 = (0..lz).map(|i| t.cs[r][i] * mm[i * lz + j]).sum();
                    let ccm: C64 = (0..lz).map(|i| t.cs_conj[r][i] * mm[i * lz + j]).sum();
                    let (a1, a2) = (cm * e1, ccm * e2);
                    x[(2 * r) * lz + j] = g1 + g2;
                    x[(2 * r + 1) * lz + j] = i1 * (g1 - g2);
                    x[(2 * m + 2 * r) * lz + j] = a1 + a2;
                    x[(2 * m + 2 * r + 1) * lz + j] = i1 * (a1 - a2);
                }
            }
            for i in 0..lz {
                for j in 0..lz {
                    x[(4 * m + i) * lz + j] = mm[i * lz + j];
                }
            }
            // The channels' cross-spectra with the whitened innovations, Ŝ Tᵀ M, and the
            // innovations' own, Mᴴ Ŝ_zz M.
            let q = &cross.q[(bin - self.band.start) * l * lz..][..l * lz];
            let sp = product((l, lz, lz), |a, i| q[a * lz + i], |i, j| mm[i * lz + j]);
            let szm = product(
                (lz, lz, lz),
                |i, k| self.rec.sp.at(bin, i, k),
                |k, j| mm[k * lz + j],
            );
            let see = product(
                (lz, lz, lz),
                |i, k| mm[k * lz + i].conj(),
                |k, j| szm[k * lz + j],
            );
            rows_of.add_bin(&x, &see, &sp, self.rec.sp.w[bin]);
            if rows_of.full() {
                rows_of.flush(&mut ne);
            }
        }
        rows_of.flush(&mut ne);
        Some(ne)
    }
}

/// The product of an n×k and a k×p complex matrix given by their entries `a(i, k)` and
/// `b(k, j)`, row-major.
fn product(
    (n, k, p): (usize, usize, usize),
    a: impl Fn(usize, usize) -> C64,
    b: impl Fn(usize, usize) -> C64,
) -> Vec<C64> {
    (0..n * p)
        .map(|t| (0..k).map(|s| a(t / p, s) * b(s, t % p)).sum())
        .collect()
}

/// Bins whose rows are gathered before they are added to the normal equations.
const BINS: usize = 256;

/// The real rows of some bins' terms of the per-frequency regression
/// y_a(ω_k) = Σ_p θ_p X_p(ω_k) ε̃(ω_k) + v_a(ω_k), written from each bin's sufficient
/// statistics so that the normal equations are sums of matrix products: over a bin's n_b
/// frequencies, Σ_k Re(X_p ε̃ (X_q ε̃)ᴴ) = n_b Re(X_p Ŝ_εε X_qᴴ) and
/// Σ_k Re(y_a (X_p ε̃)ᴴ) = n_b Re(Ŝ_{yε} X_pᴴ), each the dot product of real rows (Re, Im
/// of each of the lz entries).
struct Rows {
    /// n_b X Ŝ_εε, n_b X and n_b Ŝ_{yε} as real rows (2 lz per bin).
    xs: Dense,
    x: Dense,
    y: Dense,
    /// Rows written.
    at: usize,
    lz: usize,
}

impl Rows {
    fn new(cols: usize, lz: usize, l: usize, bins: usize) -> Self {
        let n = 2 * lz * bins;
        Rows {
            xs: Dense::zeros(n, cols),
            x: Dense::zeros(n, cols),
            y: Dense::zeros(n, l),
            at: 0,
            lz,
        }
    }

    /// A bin's rows, from the regressors X_p (`x`, lz values each), Ŝ of the whitened
    /// innovations (`see`), the channels' cross-spectra with them (`sye`, l × lz) and its
    /// frequencies' count `nb`.
    fn add_bin(&mut self, x: &[C64], see: &[C64], sye: &[C64], nb: f64) {
        let lz = self.lz;
        let (cols, l) = (self.x.cols, self.y.cols);
        let sw = nb.sqrt();
        for j in 0..lz {
            let (re, im) = (self.at + 2 * j, self.at + 2 * j + 1);
            for p in 0..cols {
                let xs: C64 = (0..lz).map(|i| x[p * lz + i] * see[i * lz + j]).sum();
                self.xs.set(re, p, sw * xs.re);
                self.xs.set(im, p, sw * xs.im);
                self.x.set(re, p, sw * x[p * lz + j].re);
                self.x.set(im, p, sw * x[p * lz + j].im);
            }
            for a in 0..l {
                self.y.set(re, a, sw * sye[a * lz + j].re);
                self.y.set(im, a, sw * sye[a * lz + j].im);
            }
        }
        self.at += 2 * lz;
    }

    fn full(&self) -> bool {
        self.at == self.x.rows
    }

    /// The rows written added to the normal equations, and forgotten.
    fn flush(&mut self, ne: &mut Normal) {
        if self.at < self.x.rows {
            // Unwritten rows are zero (a fresh chunk, or the last one cleared below).
            for d in [&mut self.xs, &mut self.x, &mut self.y] {
                let cols = d.cols;
                let rows = d.rows;
                for c in 0..cols {
                    d.data[c * rows + self.at..(c + 1) * rows].fill(0.0);
                }
            }
        }
        linalg::tn_add(&self.xs, &self.x, &mut ne.g);
        linalg::tn_add(&self.x, &self.y, &mut ne.h);
        self.at = 0;
    }
}
