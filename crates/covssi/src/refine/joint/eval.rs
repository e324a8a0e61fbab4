//! The joint likelihood at θ: its value over the band, and with derivatives its score and
//! Fisher information, frequency by frequency in chunks run in parallel.
//!
//! At each frequency $H(z) = I + \sum_r (c_r k_r^\top d_1 + \bar c_r \bar k_r^\top d_2)$,
//! $d_1 = 1/(z-\mu_r)$, $d_2 = 1/(z-\bar\mu_r)$; the innovation $\varepsilon = M x$ with
//! $M = \Lambda^{-1}H^{-1}$ is white with unit covariance under the model, and
//! $L = \sum_k \ln\det\Sigma + 2\ln|\det H| + \|\varepsilon\|^2$. Each parameter's column of
//! the Jacobian holds the Hermitian coordinates of $Y + Y^H$, $Y = M\,\partial H\,\ldots$, so
//! that the score is $\sum_k J_k^\top \operatorname{vec}(\varepsilon\varepsilon^H - I)$ and the
//! Fisher information $\sum_k J_k^\top J_k$.

use rayon::prelude::*;

use super::{CHUNK, Joint, ZERO, invert, parameters};
use crate::linalg::{self, C64, Dense};
use crate::refine::model::Eval;
use crate::refine::parametrization::Denominator;
use crate::refine::results::MisfitCounts;
use crate::refine::spectra::{FREQUENCY_CHUNK, Spectra};

/// The coordinates of a Hermitian l×l matrix: the l diagonal entries, then √2 Re and √2 Im
/// of each entry above it, so that tr(XY) is their dot product.
struct Hermitian {
    l: usize,
    /// The entries above the diagonal, row by row.
    upper: Vec<(usize, usize)>,
}

impl Hermitian {
    fn new(l: usize) -> Self {
        Hermitian {
            l,
            upper: (0..l)
                .flat_map(|c| (c + 1..l).map(move |d| (c, d)))
                .collect(),
        }
    }

    /// The coordinates of X = Y + Yᴴ for a row-major Y.
    fn coords(&self, y: &[C64], out: &mut [f64]) {
        let l = self.l;
        for c in 0..l {
            out[c] = 2.0 * y[c * l + c].re;
        }
        for (t, &(c, d)) in self.upper.iter().enumerate() {
            let v = y[c * l + d] + y[d * l + c].conj();
            out[l + 2 * t] = std::f64::consts::SQRT_2 * v.re;
            out[l + 2 * t + 1] = std::f64::consts::SQRT_2 * v.im;
        }
    }

    /// The coordinates of E − I for a Hermitian E (row-major), times `scale`.
    fn residual(&self, e: &[C64], scale: f64, out: &mut [f64]) {
        let l = self.l;
        for c in 0..l {
            out[c] = scale * (e[c * l + c].re - 1.0);
        }
        for (t, &(c, d)) in self.upper.iter().enumerate() {
            let w = e[c * l + d] * scale;
            out[l + 2 * t] = std::f64::consts::SQRT_2 * w.re;
            out[l + 2 * t + 1] = std::f64::consts::SQRT_2 * w.im;
        }
    }
}

/// What the evaluation (and the channels' shapes' regression) needs of θ that does not
/// depend on the frequency.
pub(super) struct Terms {
    pub(super) den: Denominator,
    /// Each mode's c_r and c̄_r, k_r, and the row vectors k_rᵀΛ and k̄_rᵀΛ.
    pub(super) cs: Vec<Vec<C64>>,
    pub(super) cs_conj: Vec<Vec<C64>>,
    pub(super) ks: Vec<Vec<C64>>,
    pub(super) k_lam: Vec<Vec<C64>>,
    pub(super) kc_lam: Vec<Vec<C64>>,
    /// Λ⁻¹ (row-major), and Λ's rows as complex vectors.
    pub(super) lam_inv: Vec<f64>,
    lam_rows: Vec<Vec<C64>>,
    /// ln det Σ.
    log_det_sigma: f64,
    /// The Σ parameters' columns (Y = Λ⁻¹ ∂Λ), which do not depend on the frequency.
    sigma_cols: Vec<Vec<f64>>,
    herm: Hermitian,
}

/// The work space of one frequency's derivative columns.
struct Columns {
    /// The Jacobian's rows of the chunk (l² per frequency), one column per parameter.
    jac: Dense,
    /// Y of the column being written.
    y: Vec<C64>,
    /// Vectors of l entries.
    bufs: [Vec<C64>; 7],
}

/// Y = u wᵀ (row-major), or Y + u wᵀ when `add`.
fn outer(y: &mut [C64], u: &[C64], w: &[C64], add: bool) {
    let l = u.len();
    for a in 0..l {
        for b in 0..l {
            let t = u[a] * w[b];
            y[a * l + b] = if add { y[a * l + b] + t } else { t };
        }
    }
}

/// (p d1 + q d2, i (p d1 − q d2)): what the real and the imaginary part of a parameter
/// entering beside the pole pair contribute.
fn re_im(p: &[C64], q: &[C64], d1: C64, d2: C64, re: &mut [C64], im: &mut [C64]) {
    let i1 = C64::new(0.0, 1.0);
    for (((a, b), re), im) in p.iter().zip(q).zip(re).zip(im) {
        *re = a * d1 + b * d2;
        *im = i1 * (a * d1 - b * d2);
    }
}

impl Joint<'_> {
    /// L over the band at θ (the free modes' and Λ); with `derivs` the score U = −∇L and
    /// the Fisher information, with respect to θ; with `misfit` over single frequencies,
    /// with the misfit's counts of the whitened ordinates. `None` outside the model (a pole
    /// at Nyquist, H(z) singular on the unit circle, overflow).
    pub(in crate::refine) fn eval(&self, th: &[f64], derivs: bool, misfit: bool) -> Option<Eval> {
        let np = parameters(self.l(), self.free);
        debug_assert_eq!(th.len(), np);
        let terms = self.terms(&self.full(th))?;
        let zero = || Eval::zero(if derivs { np } else { 0 });
        let sp = &self.rec.sp;
        // The ordinates are per frequency (the misfit needs them so); L, U and F sum over
        // the bins. Chunks are summed in order, whatever the threads.
        let parts: Vec<Option<Eval>> = if misfit {
            let k = sp.edges[self.band.start]..sp.edges[self.band.end];
            (0..k.len().div_ceil(FREQUENCY_CHUNK))
                .into_par_iter()
                .map(|ci| {
                    let lo = k.start + ci * FREQUENCY_CHUNK;
                    let f = sp.frequencies(lo..(lo + FREQUENCY_CHUNK).min(k.end));
                    let mut acc = zero();
                    acc.misfit = Some(MisfitCounts::new());
                    self.eval_chunk(&f, &terms, 0..f.bins(), derivs, acc)
                })
                .collect()
        } else {
            (0..self.band.len().div_ceil(CHUNK))
                .into_par_iter()
                .map(|ci| {
                    let lo = self.band.start + ci * CHUNK;
                    let hi = (lo + CHUNK).min(self.band.end);
                    self.eval_chunk(sp, &terms, lo..hi, derivs, zero())
                })
                .collect()
        };
        let mut total = zero();
        for part in parts {
            total = total.merge(part?);
        }
        total.l.is_finite().then_some(total)
    }

    /// The terms of θ (all modes' and Λ) that do not depend on the frequency.
    pub(super) fn terms(&self, th: &[f64]) -> Option<Terms> {
        let l = self.l();
        let m = self.refs.len();
        let den = Denominator::new(th, m, self.rec.fs)?;
        let (cs, ks) = self.shapes(th);
        let (lam, lam_inv) = self.lambda(th);
        let herm = Hermitian::new(l);
        // ∂Λ = scale·E_ab, so Y_cd = scale · Λ⁻¹[c, a] δ_{d b}.
        let sigma_col = |a: usize, b: usize, scale: f64| {
            let y: Vec<C64> = (0..l * l)
                .map(|i| {
                    let (c, d) = (i / l, i % l);
                    let v = if d == b {
                        scale * lam_inv[c * l + a]
                    } else {
                        0.0
                    };
                    C64::new(v, 0.0)
                })
                .collect();
            let mut v = vec![0.0; l * l];
            herm.coords(&y, &mut v);
            v
        };
        let mut sigma_cols: Vec<Vec<f64>> =
            (0..l).map(|a| sigma_col(a, a, lam[a * l + a])).collect();
        for a in 1..l {
            for b in 0..a {
                sigma_cols.push(sigma_col(a, b, 1.0));
            }
        }
        // Row vector uᵀΛ.
        let vl = |u: &[C64]| -> Vec<C64> {
            (0..l)
                .map(|d| (d..l).map(|b| u[b] * lam[b * l + d]).sum())
                .collect()
        };
        let conj = |v: &[C64]| -> Vec<C64> { v.iter().map(|x| x.conj()).collect() };
        Some(Terms {
            den,
            cs_conj: cs.iter().map(|c| conj(c)).collect(),
            k_lam: ks.iter().map(|k| vl(k)).collect(),
            kc_lam: ks.iter().map(|k| vl(&conj(k))).collect(),
            lam_rows: (0..l)
                .map(|b| (0..l).map(|d| C64::new(lam[b * l + d], 0.0)).collect())
                .collect(),
            log_det_sigma: 2.0 * (0..l).map(|a| lam[a * l + a].ln()).sum::<f64>(),
            cs,
            ks,
            lam_inv,
            sigma_cols,
            herm,
        })
    }

    /// H(z) (row-major) and each mode's d1 = 1/(z − μ), d2 = 1/(z − μ̄) at z.
    pub(super) fn transfer(
        &self,
        t: &Terms,
        z: C64,
        hz: &mut [C64],
        d1: &mut [C64],
        d2: &mut [C64],
    ) {
        let l = self.l();
        for (i, h) in hz.iter_mut().enumerate() {
            *h = C64::new(if i / l == i % l { 1.0 } else { 0.0 }, 0.0);
        }
        for rr in 0..self.refs.len() {
            d1[rr] = (z - t.den.mu[2 * rr]).inv();
            d2[rr] = (z - t.den.mu[2 * rr + 1]).inv();
            let (c, k) = (&t.cs[rr], &t.ks[rr]);
            for a in 0..l {
                for b in 0..l {
                    let v = c[a] * k[b];
                    hz[a * l + b] += v * d1[rr] + v.conj() * d2[rr];
                }
            }
        }
    }

    /// L over the bins `rows` of `sp` added into `acc`, with the score and Fisher information
    /// when `derivs`, the whitened ordinates (diagonal of E) counted into `acc.misfit` when it
    /// is there. Each bin adds
    /// n_b [ln det S + tr E], E = M Ŝ_b Mᴴ; its rows of the Jacobian are scaled by √n_b.
    fn eval_chunk(
        &self,
        sp: &Spectra,
        t: &Terms,
        rows: std::ops::Range<usize>,
        derivs: bool,
        mut acc: Eval,
    ) -> Option<Eval> {
        let l = self.l();
        let m = self.refs.len();
        let ll = l * l;
        let np = acc.u.len();
        let mut cols = Columns {
            jac: if derivs {
                Dense::zeros(rows.len() * ll, np)
            } else {
                Dense::zeros(0, 0)
            },
            y: vec![ZERO; ll],
            bufs: std::array::from_fn(|_| vec![ZERO; l]),
        };
        let mut hz = vec![ZERO; ll];
        let mut r = vec![0.0; ll];
        let mut d1 = vec![ZERO; m];
        let mut d2 = vec![ZERO; m];
        let mut ms = vec![ZERO; ll];
        let mut e = vec![ZERO; ll];
        for (row, kk) in rows.enumerate() {
            let (w, sw) = (sp.w[kk], sp.w[kk].sqrt());
            self.transfer(t, sp.z[kk], &mut hz, &mut d1, &mut d2);
            let (g, log_abs_det) = invert(&hz, l)?;
            // M = Λ⁻¹ H⁻¹, ε = M x.
            let mut mm = vec![ZERO; ll];
            for a in 0..l {
                for b in 0..l {
                    mm[a * l + b] = (0..=a).map(|s| g[s * l + b] * t.lam_inv[a * l + s]).sum();
                }
            }
            // E = M Ŝ Mᴴ (its diagonal |ε|², ε = M x, at a single frequency).
            let s_b = &sp.s[kk * ll..(kk + 1) * ll];
            for a in 0..l {
                for c in 0..l {
                    ms[a * l + c] = (0..l).map(|b| mm[a * l + b] * s_b[b * l + c]).sum();
                }
            }
            for a in 0..l {
                for c in 0..l {
                    e[a * l + c] = (0..l).map(|b| ms[a * l + b] * mm[c * l + b].conj()).sum();
                }
            }
            let quad: f64 = (0..l).map(|a| e[a * l + a].re).sum();
            acc.l += w * (t.log_det_sigma + 2.0 * log_abs_det + quad);
            if let Some(counts) = &mut acc.misfit {
                (0..l).for_each(|a| counts.add(e[a * l + a].re));
            }
            if !derivs {
                continue;
            }
            t.herm.residual(&e, sw, &mut r);
            let base = row * ll;
            for rr in 0..self.free {
                self.mode_columns(t, rr, &mm, (d1[rr], d2[rr]), base, &mut cols);
            }
            let s_off = np - l * (l + 1) / 2;
            for (c, col) in t.sigma_cols.iter().enumerate() {
                let at = (s_off + c) * cols.jac.rows + base;
                cols.jac.data[at..at + ll].copy_from_slice(col);
            }
            // The bin's rows times √n_b; U = −∇L = Σ_b J_bᵀ vec(n_b (E − I)).
            for col in 0..np {
                let at = col * cols.jac.rows + base;
                let rows = &mut cols.jac.data[at..at + ll];
                rows.iter_mut().for_each(|v| *v *= sw);
                acc.u[col] += rows.iter().zip(&r).map(|(j, ri)| j * ri).sum::<f64>();
            }
        }
        if derivs {
            linalg::gram_add(&cols.jac, &mut acc.f);
        }
        Some(acc)
    }

    /// The columns of the free mode `rr` at one frequency (rows from `base`): its poles',
    /// c_r's and k_r's, given M and the mode's (d1, d2) there.
    fn mode_columns(
        &self,
        t: &Terms,
        rr: usize,
        mm: &[C64],
        (d1, d2): (C64, C64),
        base: usize,
        cols: &mut Columns,
    ) {
        let l = self.l();
        let mf = self.free;
        let mv = |u: &[C64], out: &mut [C64]| {
            for (a, o) in out.iter_mut().enumerate() {
                *o = (0..l).map(|b| mm[a * l + b] * u[b]).sum();
            }
        };
        let [mc, mcc, u1, u2, w_re, w_im, col] = &mut cols.bufs;
        mv(&t.cs[rr], mc);
        mv(&t.cs_conj[rr], mcc);
        let (kl, kcl) = (&t.k_lam[rr], &t.kc_lam[rr]);
        let put = |c: usize, y: &[C64], jac: &mut Dense| {
            let at = c * jac.rows + base;
            t.herm.coords(y, &mut jac.data[at..at + l * l]);
        };
        // Poles: ∂H = d1² (∂μ) c kᵀ + d2² (∂μ̄) c̄ k̄ᵀ.
        for (s, dm) in t.den.dmu[rr].iter().enumerate() {
            let f1 = d1 * d1 * dm;
            let f2 = d2 * d2 * dm.conj();
            for (u, v) in u1.iter_mut().zip(mc.iter()) {
                *u = v * f1;
            }
            for (u, v) in u2.iter_mut().zip(mcc.iter()) {
                *u = v * f2;
            }
            outer(&mut cols.y, u1, kl, false);
            outer(&mut cols.y, u2, kcl, true);
            put(s * mf + rr, &cols.y, &mut cols.jac);
        }
        let off = 2 * mf + rr * (4 * l - 2);
        // c: ∂H = e_a (kᵀ d1 + k̄ᵀ d2) for Re c_a, i e_a (kᵀ d1 − k̄ᵀ d2) for Im.
        re_im(kl, kcl, d1, d2, w_re, w_im);
        for a in 0..l {
            for (i, c) in col.iter_mut().enumerate() {
                *c = mm[i * l + a];
            }
            outer(&mut cols.y, col, w_re, false);
            put(off + a, &cols.y, &mut cols.jac);
            outer(&mut cols.y, col, w_im, false);
            put(off + l + a, &cols.y, &mut cols.jac);
        }
        // k_b: ∂H = (c d1 + c̄ d2) e_bᵀ for Re, i (c d1 − c̄ d2) e_bᵀ for Im.
        // (In u1 and u2, which the pole columns are done with.)
        re_im(mc, mcc, d1, d2, u1, u2);
        let mut s = off + 2 * l;
        for (b, row_b) in t.lam_rows.iter().enumerate() {
            if b == self.refs[rr] {
                continue;
            }
            outer(&mut cols.y, u1, row_b, false);
            put(s, &cols.y, &mut cols.jac);
            outer(&mut cols.y, u2, row_b, false);
            put(s + 1, &cols.y, &mut cols.jac);
            s += 2;
        }
    }
}
