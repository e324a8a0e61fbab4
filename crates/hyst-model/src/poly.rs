//! Roots of real polynomials, independent of any eigenvalue solver.
//!
//! Used to check the state-space poles against the characteristic polynomial (eq. 32) and to
//! solve small polynomial equations elsewhere. Method: Aberth–Ehrlich simultaneous iteration
//! on the monic polynomial, started on a circle of Cauchy-bound radius.

use nalgebra::Complex;

type C = Complex<f64>;

fn eval(coeffs: &[f64], x: C) -> (C, C) {
    // Horner for p and p'.
    let mut p = C::new(coeffs[0], 0.0);
    let mut dp = C::new(0.0, 0.0);
    for &c in &coeffs[1..] {
        dp = dp * x + p;
        p = p * x + c;
    }
    (p, dp)
}

/// All complex roots of $\sum_i c_i \lambda^{n-i}$ (coefficients highest power first).
///
/// Leading zeros are dropped; an empty or constant polynomial has no roots. Roots of a real
/// polynomial come in exact conjugate pairs in the result only up to rounding.
pub fn roots(coeffs: &[f64]) -> Vec<Complex<f64>> {
    let start = coeffs
        .iter()
        .position(|&c| c != 0.0)
        .unwrap_or(coeffs.len());
    let c = &coeffs[start..];
    if c.len() < 2 {
        return Vec::new();
    }
    let lead = c[0];
    let monic: Vec<f64> = c.iter().map(|v| v / lead).collect();
    let n = monic.len() - 1;
    let radius = 1.0 + monic[1..].iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut z: Vec<C> = (0..n)
        .map(|k| {
            let th = 2.0 * std::f64::consts::PI * (k as f64 + 0.25) / n as f64 + 0.4;
            C::from_polar(radius * 0.5, th)
        })
        .collect();
    for _ in 0..500 {
        let mut max_step = 0.0f64;
        for i in 0..n {
            let (p, dp) = eval(&monic, z[i]);
            if p.norm() == 0.0 {
                continue;
            }
            let ratio = p / dp;
            let mut s = C::new(0.0, 0.0);
            for j in 0..n {
                if j != i {
                    s += C::new(1.0, 0.0) / (z[i] - z[j]);
                }
            }
            let w = ratio / (C::new(1.0, 0.0) - ratio * s);
            z[i] -= w;
            max_step = max_step.max(w.norm() / z[i].norm().max(1e-300));
        }
        if max_step < 1e-15 {
            break;
        }
    }
    // Newton polish on the original coefficients.
    for r in z.iter_mut() {
        for _ in 0..3 {
            let (p, dp) = eval(&monic, *r);
            if dp.norm() == 0.0 {
                break;
            }
            *r -= p / dp;
        }
    }
    z
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cubic_with_known_roots() {
        // (λ + 1)(λ² + 2λ + 5): roots −1, −1 ± 2i.
        let r = roots(&[1.0, 3.0, 7.0, 5.0]);
        let mut found = [false; 3];
        for x in r {
            for (k, t) in [C::new(-1.0, 0.0), C::new(-1.0, 2.0), C::new(-1.0, -2.0)]
                .iter()
                .enumerate()
            {
                if (x - t).norm() < 1e-12 {
                    found[k] = true;
                }
            }
        }
        assert_eq!(found, [true; 3]);
    }
}
