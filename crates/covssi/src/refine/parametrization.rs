//! The parameters: poles by ln ω and logit ζ (ln ρ for a real pole), and the spectrum's
//! denominator built from them.

use crate::linalg::C64;

/// A pole's parameters: ln ω and logit ζ (ζ clamped to [1e-6, 0.99] so that both are finite);
/// [`unpack`] is the inverse.
pub(super) fn pole_params(lam: C64) -> (f64, f64) {
    let zeta = (-lam.re / lam.norm()).clamp(1e-6, 0.99);
    (lam.norm().ln(), (zeta / (1.0 - zeta)).ln())
}

/// The poles λ_j of θ's first 2m entries (ln ω, then logit ζ); [`pole_params`] is the inverse.
pub(super) fn unpack(th: &[f64], m: usize) -> Vec<C64> {
    (0..m)
        .map(|j| {
            let w = th[j].exp();
            let (zeta, gap) = damping_and_gap(th[m + j]);
            w * C64::new(-zeta, (gap * (1.0 + zeta)).sqrt())
        })
        .collect()
}

pub(super) fn logistic(s: f64) -> f64 {
    1.0 / (1.0 + (-s).exp())
}

/// ζ = logistic(s) and 1 − ζ = logistic(−s), the latter computed itself: as 1 − ζ it is 0
/// once ζ rounds to 1 (s above 37), and the pole's imaginary part √((1 − ζ)(1 + ζ)) and its
/// derivative by s (which tends to 0) would be 0 and 0·∞.
pub(super) fn damping_and_gap(s: f64) -> (f64, f64) {
    (logistic(s), logistic(-s))
}

/// Real coefficients (highest power first, leading 1) of ∏ (z − r).
pub(super) fn poly(roots: &[C64]) -> Vec<f64> {
    let mut c = vec![C64::new(1.0, 0.0)];
    for r in roots {
        let mut next = vec![C64::new(0.0, 0.0); c.len() + 1];
        for (k, ck) in c.iter().enumerate() {
            next[k] += ck;
            next[k + 1] -= ck * r;
        }
        c = next;
    }
    c.iter().map(|v| v.re).collect()
}

/// Σ_k coef[k] w^k (coefficients lowest power first, e.g. a polynomial in z⁻¹ at w = z̄ on the
/// unit circle).
pub(super) fn poly_at(coef: &[f64], w: C64) -> C64 {
    let mut acc = C64::new(0.0, 0.0);
    let mut p = C64::new(1.0, 0.0);
    for c in coef {
        acc += c * p;
        p *= w;
    }
    acc
}

/// The denominator |A(e^{iω})|² of the spectrum: the discrete poles of θ's modes and real
/// poles, and their derivatives by the pole parameters.
pub(super) struct Denominator {
    /// μ_j, μ̄_j of each mode, then μ_i = e^{−ρ_i/f_s} of each real pole λ_i = −ρ_i.
    pub(super) mu: Vec<C64>,
    /// dμ_j/d(ln ω_j) and dμ_j/d(logit ζ_j).
    pub(super) dmu: Vec<[C64; 2]>,
    /// dμ_i/d(ln ρ_i) of each real pole.
    pub(super) dreal: Vec<f64>,
}

impl Denominator {
    /// The modes of θ alone. `None` when a natural frequency reaches Nyquist.
    pub(super) fn new(th: &[f64], m: usize, fs: f64) -> Option<Self> {
        Self::with_reals(th, m, 0, fs)
    }

    /// The `m` modes of θ's first 2m entries and the `r` real poles of the next r (ln ρ).
    /// `None` when a natural frequency reaches Nyquist or a real pole is not finite.
    pub(super) fn with_reals(th: &[f64], m: usize, r: usize, fs: f64) -> Option<Self> {
        let lambdas = unpack(th, m);
        let mut mu = discrete_poles(&lambdas, fs)?;
        let dmu = lambdas
            .iter()
            .enumerate()
            .map(|(j, lam)| {
                // λ = ω(−ζ + i√(1−ζ²)), ζ = logistic(s): dλ/ds = dλ/dζ · ζ(1−ζ)
                // = −ω(ζ(1−ζ) + iζ²√((1−ζ)/(1+ζ))), finite (0 in the limit) as ζ → 1.
                let w = th[j].exp();
                let (zeta, gap) = damping_and_gap(th[m + j]);
                let dl_ds = -w * C64::new(zeta * gap, zeta * zeta * (gap / (1.0 + zeta)).sqrt());
                [mu[2 * j] * lam / fs, mu[2 * j] * dl_ds / fs]
            })
            .collect();
        let mut dreal = Vec::with_capacity(r);
        for &ln_rho in &th[2 * m..2 * m + r] {
            let rho = ln_rho.exp();
            let u = (-rho / fs).exp();
            if !(rho.is_finite() && u.is_finite()) {
                return None;
            }
            mu.push(C64::new(u, 0.0));
            dreal.push(-u * rho / fs);
        }
        Some(Denominator { mu, dmu, dreal })
    }

    /// ln|A(z)|² at z on the unit circle; with `derivs`, `da[t]` = ∂ ln|A|²/∂θ_t for the
    /// 2m + r pole parameters.
    pub(super) fn at(&self, z: C64, derivs: bool, da: &mut [f64]) -> f64 {
        let m = self.dmu.len();
        // ln|A|² = ln Π|z − μ|², the product's logarithm taken once (a logarithm per factor
        // was a fifth of the refinement's time), and whenever the product leaves
        // [PRODUCT_FLOOR, 1/PRODUCT_FLOOR] so that it can neither underflow nor overflow.
        let mut log = LogProduct::default();
        for (j, dm_j) in self.dmu.iter().enumerate() {
            let d1 = z - self.mu[2 * j];
            let d2 = z - self.mu[2 * j + 1];
            let (n1, n2) = (d1.norm_sqr(), d2.norm_sqr());
            log.times(n1 * n2);
            if derivs {
                // Re(dμ/d) = Re(dμ·d̄)/|d|²: one real division per factor, not a complex one
                // per parameter.
                let (e1, e2) = (d1.conj() * (-2.0 / n1), d2.conj() * (-2.0 / n2));
                for (t, dm) in dm_j.iter().enumerate() {
                    da[t * m + j] = (dm * e1).re + (dm.conj() * e2).re;
                }
            }
        }
        for (i, dm) in self.dreal.iter().enumerate() {
            let d1 = z - self.mu[2 * m + i];
            let n1 = d1.norm_sqr();
            log.times(n1);
            if derivs {
                da[2 * m + i] = -2.0 * dm * d1.re / n1;
            }
        }
        log.ln()
    }
}

/// A product kept as a running logarithm and a factor within [`PRODUCT_FLOOR`] and its
/// inverse: the logarithm of many factors with one `ln` for each 10³⁰⁰ of range rather than
/// one per factor (the same value to rounding).
#[derive(Debug, Clone, Copy)]
pub(super) struct LogProduct {
    log: f64,
    factor: f64,
}

/// Where a [`LogProduct`]'s factor is folded into its logarithm (a factor of the product is
/// at most 16 and at least 10⁻³⁰, so the running factor stays far inside the doubles).
const PRODUCT_FLOOR: f64 = 1e-150;

impl Default for LogProduct {
    fn default() -> Self {
        LogProduct {
            log: 0.0,
            factor: 1.0,
        }
    }
}

impl LogProduct {
    /// Multiply by `v` (positive; 0, ∞ or NaN carry into the logarithm as `ln` gives them).
    #[inline]
    pub(super) fn times(&mut self, v: f64) {
        self.factor *= v;
        if !(PRODUCT_FLOOR..=1.0 / PRODUCT_FLOOR).contains(&self.factor) {
            self.log += self.factor.ln();
            self.factor = 1.0;
        }
    }

    /// The product's natural logarithm.
    #[inline]
    pub(super) fn ln(self) -> f64 {
        self.log + self.factor.ln()
    }
}

/// Discrete poles μ, μ̄ of each mode, or `None` when a natural frequency reaches Nyquist.
pub(super) fn discrete_poles(lambdas: &[C64], fs: f64) -> Option<Vec<C64>> {
    let mut mu = Vec::with_capacity(2 * lambdas.len());
    for lam in lambdas {
        if lam.norm() / fs >= std::f64::consts::PI || !lam.re.is_finite() {
            return None;
        }
        let u = (lam / fs).exp();
        mu.push(u);
        mu.push(u.conj());
    }
    Some(mu)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The discrete pole's derivative by logit ζ is the central difference of μ itself while
    /// ζ is below 1, and stays finite (tending to 0) where ζ rounds to 1 (logit ζ above 37).
    /// Computed through 1 − ζ it was 0·∞ there: a fit whose pole had saturated got a NaN
    /// score and stopped, far from its optimum (the steel frame's setups, L 10⁴ above the
    /// fit with that mode removed).
    #[test]
    fn a_pole_damped_towards_one_keeps_a_finite_derivative() {
        let (fs, ln_w) = (50.0, (2.0 * std::f64::consts::PI * 3.0f64).ln());
        for s in [-8.0, 0.0, 3.0, 12.0, 30.0, 36.0, 38.0, 76.0, 700.0] {
            let th = [ln_w, s];
            let den = Denominator::new(&th, 1, fs).expect("below Nyquist");
            let d = den.dmu[0][1];
            assert!(d.re.is_finite() && d.im.is_finite(), "logit ζ = {s}: {d}");
            let lam = unpack(&th, 1)[0];
            assert!(lam.im >= 0.0 && lam.re < 0.0, "logit ζ = {s}: {lam}");
            if s <= 30.0 {
                // Central difference with step h: error ~h²|μ'''|, here below 1e-9 of |μ'|
                // or of ζ(1 − ζ)'s own size.
                let h = 1e-5;
                let mu = |v: f64| discrete_poles(&unpack(&[ln_w, v], 1), fs).expect("pole")[0];
                let fd = (mu(s + h) - mu(s - h)) / (2.0 * h);
                assert!(
                    (fd - d).norm() <= 1e-7 * d.norm() + 1e-12,
                    "logit ζ = {s}: {fd} against {d}"
                );
            } else {
                // Beyond 30 the derivative is below ω e^(−s/2)/fs: nothing a step can use.
                assert!(
                    d.norm() <= 2.0 * ln_w.exp() / fs * (-s / 2.0).exp(),
                    "logit ζ = {s}: {d}"
                );
            }
        }
    }

    /// The product's logarithm is the sum of the factors' logarithms to rounding, through
    /// ranges a plain product would leave (10⁻⁴⁰⁰ and 10⁴⁰⁰); a zero factor gives −∞ and a
    /// NaN NaN, as the sum of logarithms does.
    #[test]
    fn a_log_product_is_the_sum_of_logarithms() {
        for factors in [
            vec![0.5, 3.0, 1e-7, 12.0, 0.25],
            vec![1e-20; 20],
            vec![1e20; 20],
            (1..200)
                .map(|k| (k as f64 * 0.37).sin().abs() * 16.0 + 1e-30)
                .collect(),
        ] {
            let mut p = LogProduct::default();
            factors.iter().for_each(|&v| p.times(v));
            let sum: f64 = factors.iter().map(|v| v.ln()).sum();
            assert!(
                (p.ln() - sum).abs() <= 1e-13 * sum.abs().max(1.0),
                "{} {sum}",
                p.ln()
            );
        }
        let mut p = LogProduct::default();
        [2.0, 0.0, 3.0].iter().for_each(|&v| p.times(v));
        assert_eq!(p.ln(), f64::NEG_INFINITY);
        let mut p = LogProduct::default();
        [2.0, f64::NAN].iter().for_each(|&v| p.times(v));
        assert!(p.ln().is_nan());
    }
}
