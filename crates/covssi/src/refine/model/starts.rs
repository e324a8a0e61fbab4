//! Starting values of θ: each channel's numerator from the record filtered by the poles, the
//! poles' own, a model nested in a fitted one, and the channel combinations that carry the
//! modes.

use crate::error::SsiError;
use crate::linalg::{self, C64, Dense};
use crate::refine::model::{Fit, Model};
use crate::refine::parametrization::{discrete_poles, pole_params, poly, poly_at};

impl Model {
    /// `p` combinations of the channels that carry the modes `lambdas` (rows of l weights),
    /// each channel first divided by `scale` (the square root of its noise floor, so
    /// that the noise is white with equal level in all: then the directions orthogonal to the
    /// modes' shapes hold noise alone, independent of the rest). For each mode the
    /// cross-spectral matrix of the scaled channels over its half-power band (at least ±3
    /// frequencies) is normalised to unit trace, so a weak mode weighs as much as a strong one;
    /// the combinations are the leading `p` eigenvectors of the real part of their sum, which
    /// spans the modes' shapes (real and imaginary parts). Scaling a channel changes nothing
    /// (its scale scales with it); permuting them changes the combinations' signs at most.
    /// `None` if a band holds no power or the eigenvectors cannot be computed.
    pub(in crate::refine) fn project(
        &self,
        lambdas: &[C64],
        p: usize,
        scale: &[f64],
    ) -> Option<Vec<Vec<f64>>> {
        let l = self.l();
        let bin = 2.0 * std::f64::consts::PI / self.sp.n as f64;
        let mut g = Dense::zeros(l, l);
        for lam in lambdas {
            let centre = lam.im / self.fs;
            let half = (-lam.re / self.fs).max(3.0 * bin);
            let (lo, hi) = (self.sp.bin_at(centre - half), self.sp.bin_at(centre + half));
            let mut s = Dense::zeros(l, l);
            for b in lo..=hi {
                let w = self.sp.w[b];
                for a in 0..l {
                    for c in 0..l {
                        let v = w * self.sp.at(b, a, c).re / (scale[a] * scale[c]);
                        s.set(a, c, s.at(a, c) + v);
                    }
                }
            }
            let trace: f64 = (0..l).map(|a| s.at(a, a)).sum();
            if !(trace > 0.0 && trace.is_finite()) {
                return None;
            }
            g.data
                .iter_mut()
                .zip(&s.data)
                .for_each(|(gv, sv)| *gv += sv / trace);
        }
        let (u, _) = linalg::thin_svd_u(&g).ok()?;
        Some(
            (0..p.min(l))
                .map(|j| (0..l).map(|c| u.at(c, j) / scale[c]).collect())
                .collect(),
        )
    }

    /// Starting numerator of channel c: σ² and B from the autocovariances of the record
    /// filtered by A (an MA process of order 2m), tapered by a triangle so that the spectrum
    /// they describe is positive (a biased autocovariance times a triangle is a positive
    /// definite sequence), then factored.
    pub(in crate::refine) fn start_numerator(&self, c: usize, mu: &[C64]) -> Vec<f64> {
        let q = mu.len();
        let a = poly(mu);
        // The record's start is enough for a start ([`HEAD`] samples).
        let y = &self.sp.head[c];
        let e: Vec<f64> = (0..y.len() - q)
            .map(|t| (0..=q).map(|k| a[k] * y[t + q - k]).sum())
            .collect();
        let r: Vec<f64> = (0..=q)
            .map(|k| {
                let biased = e[..e.len() - k]
                    .iter()
                    .zip(&e[k..])
                    .map(|(u, v)| u * v)
                    .sum::<f64>()
                    / e.len() as f64;
                biased * (1.0 - k as f64 / (q + 1) as f64)
            })
            .collect();
        let flat = {
            let mut v = vec![r[0].ln()];
            v.extend(std::iter::repeat_n(0.0, q));
            v
        };
        if q == 0 || r[q].abs() < 1e-12 * r[0] {
            return flat;
        }
        // Roots of z^q · Σ_k r_|k| z^k (degree 2q), by the companion matrix; they pair as
        // (z, 1/z̄), and the q inside the unit circle make B minimum-phase.
        let deg = 2 * q;
        let coef: Vec<f64> = (0..=deg)
            .map(|k| r[(k as isize - q as isize).unsigned_abs()])
            .collect();
        let mut comp = Dense::zeros(deg, deg);
        for k in 0..deg {
            comp.set(0, k, -coef[k + 1] / coef[0]);
            if k + 1 < deg {
                comp.set(k + 1, k, 1.0);
            }
        }
        let Ok(mut roots) = linalg::eigenvalues(&comp) else {
            return flat;
        };
        roots.sort_by(|a, b| a.norm().total_cmp(&b.norm()));
        let inside: Vec<C64> = roots[..q]
            .iter()
            .map(|z| {
                if z.norm() > 0.98 {
                    z * (0.98 / z.norm())
                } else {
                    *z
                }
            })
            .collect();
        let b = poly(&inside);
        let grid = 256;
        let mean_b2 = (0..grid)
            .map(|g| {
                let w = std::f64::consts::PI * (g as f64 + 0.5) / grid as f64;
                poly_at(&b, C64::from_polar(1.0, -w)).norm_sqr()
            })
            .sum::<f64>()
            / grid as f64;
        let mut v = vec![(r[0] / mean_b2).ln()];
        v.extend_from_slice(&b[1..]);
        if v.iter().all(|x| x.is_finite()) {
            v
        } else {
            flat
        }
    }

    /// θ of the starting poles, with numerators from [`Self::start_numerator`].
    pub(in crate::refine) fn start(&self, poles: &[C64]) -> Result<Vec<f64>, SsiError> {
        self.start_with(poles, &[])
    }

    /// θ of the starting modes' poles and real poles (as many as the model has), with
    /// numerators from [`Self::start_numerator`].
    pub(in crate::refine) fn start_with(
        &self,
        poles: &[C64],
        reals: &[f64],
    ) -> Result<Vec<f64>, SsiError> {
        debug_assert_eq!(reals.len(), self.reals);
        let (mut th, logits): (Vec<f64>, Vec<f64>) = poles.iter().map(|&s| pole_params(s)).unzip();
        th.extend(logits);
        th.extend(reals.iter().map(|v| (-v).ln()));
        let mut mu = discrete_poles(poles, self.fs).ok_or(SsiError::Refinement {
            reason: "a starting pole is at or above the Nyquist frequency",
        })?;
        mu.extend(reals.iter().map(|v| C64::new((v / self.fs).exp(), 0.0)));
        for c in 0..self.l() {
            th.extend(self.start_numerator(c, &mu));
        }
        Ok(th)
    }

    /// The start that nests `prev` in a model with one more mode `new`: its pole pair is
    /// cancelled by a numerator zero pair, so the spectrum and L are exactly `prev`'s. The
    /// fit from here can only lower L.
    pub(in crate::refine) fn nested_start(&self, prev: &Fit, new: C64) -> Option<Vec<f64>> {
        let (m, r) = (prev.lambdas.len(), prev.reals.len());
        debug_assert_eq!(self.reals, r);
        let q = 2 * m + r;
        let mu = discrete_poles(&[new], self.fs)?[0];
        let factor = [1.0, -2.0 * mu.re, mu.norm_sqr()];
        let (ln_w, logit_zeta) = pole_params(new);
        let mut th: Vec<f64> = prev.theta[..m].to_vec();
        th.push(ln_w);
        th.extend_from_slice(&prev.theta[m..2 * m]);
        th.push(logit_zeta);
        th.extend_from_slice(&prev.theta[2 * m..q]);
        th.extend(self.numerators_times(&prev.theta, q, &factor));
        Some(th)
    }

    /// The start that nests `prev` (a fit with one real pole fewer than this model has) in
    /// this model, its new real pole `new` (λ < 0) cancelled by a numerator zero: the
    /// spectrum and L are exactly `prev`'s.
    pub(in crate::refine) fn nested_real_start(&self, prev: &Fit, new: f64) -> Vec<f64> {
        let (m, r) = (prev.lambdas.len(), prev.reals.len());
        debug_assert_eq!(self.reals, r + 1);
        let q = 2 * m + r;
        let mu = (new / self.fs).exp();
        let mut th: Vec<f64> = prev.theta[..q].to_vec();
        th.push((-new).ln());
        th.extend(self.numerators_times(&prev.theta, q, &[1.0, -mu]));
        th
    }

    /// The numerators of θ (pole parameters and numerator degree `q`), each multiplied by
    /// `factor` (coefficients of z⁻ᵏ from k = 0, leading 1): every channel's ln σ², then its
    /// new B's coefficients after the leading 1. They cancel the poles `factor` adds to A.
    pub(in crate::refine) fn numerators_times(
        &self,
        theta: &[f64],
        q: usize,
        factor: &[f64],
    ) -> Vec<f64> {
        let mut out = Vec::with_capacity(self.l() * (q + factor.len()));
        for c in 0..self.l() {
            let off = q + c * (q + 1);
            out.push(theta[off]);
            let mut b = vec![1.0];
            b.extend_from_slice(&theta[off + 1..off + 1 + q]);
            let mut nb = vec![0.0; q + factor.len()];
            for (k, bk) in b.iter().enumerate() {
                for (t, ft) in factor.iter().enumerate() {
                    nb[k + t] += bk * ft;
                }
            }
            out.extend_from_slice(&nb[1..]);
        }
        out
    }
}
