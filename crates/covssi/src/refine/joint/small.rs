//! Small dense complex and real linear algebra the joint likelihood's start and evaluation
//! need (l×l matrices, l ≤ 4): a rank-one part, a least-squares regression, an inverse with
//! its log-determinant, a Cholesky factor.

use crate::linalg::{self, C64, Dense};

/// The best rank-one part c kᵀ of the complex l×l matrix `r` (row-major), by power iteration
/// on rᴴr, with k scaled to 1 in its largest component, whose index is returned too. `None`
/// if `r` is zero.
pub(super) fn rank_one(r: &[C64], l: usize) -> Option<(Vec<C64>, Vec<C64>, usize)> {
    let col_norm = |b: usize| (0..l).map(|a| r[a * l + b].norm_sqr()).sum::<f64>();
    let start = (0..l).max_by(|&a, &b| col_norm(a).total_cmp(&col_norm(b)))?;
    let mut v: Vec<C64> = (0..l)
        .map(|b| C64::new(if b == start { 1.0 } else { 0.0 }, 0.0))
        .collect();
    for _ in 0..50 {
        let rv: Vec<C64> = (0..l)
            .map(|a| (0..l).map(|b| r[a * l + b] * v[b]).sum())
            .collect();
        let w: Vec<C64> = (0..l)
            .map(|b| (0..l).map(|a| r[a * l + b].conj() * rv[a]).sum())
            .collect();
        let norm = w.iter().map(|x| x.norm_sqr()).sum::<f64>().sqrt();
        if !(norm > 0.0 && norm.is_finite()) {
            return None;
        }
        v = w.iter().map(|x| x / norm).collect();
    }
    // r ≈ (r v) vᴴ: c = r v, kᵀ = vᴴ, then scaled.
    let c: Vec<C64> = (0..l)
        .map(|a| (0..l).map(|b| r[a * l + b] * v[b]).sum())
        .collect();
    let k: Vec<C64> = v.iter().map(|x| x.conj()).collect();
    let at = (0..l).max_by(|&a, &b| k[a].norm().total_cmp(&k[b].norm()))?;
    let s = k[at];
    Some((
        c.iter().map(|x| x * s).collect(),
        k.iter().map(|x| x / s).collect(),
        at,
    ))
}

/// Least squares of `outputs` targets on `cols` regressors over `rows` rows, `fill(r, x, y)`
/// writing row r, called for r = 0, 1, … in order; the coefficients (cols × outputs), or
/// `None` if the normal equations are singular. The normal equations are summed over chunks
/// of rows, so memory does not grow with the record.
pub(super) fn regress(
    rows: usize,
    cols: usize,
    outputs: usize,
    mut fill: impl FnMut(usize, &mut [f64], &mut [f64]),
) -> Option<Dense> {
    const ROWS: usize = 4096;
    let mut g = Dense::zeros(cols, cols);
    let mut h = Dense::zeros(cols, outputs);
    let mut x = vec![0.0; cols];
    let mut y = vec![0.0; outputs];
    for lo in (0..rows).step_by(ROWS) {
        let hi = (lo + ROWS).min(rows);
        let mut xc = Dense::zeros(hi - lo, cols);
        let mut yc = Dense::zeros(hi - lo, outputs);
        for r in lo..hi {
            fill(r, &mut x, &mut y);
            for (c, v) in x.iter().enumerate() {
                xc.set(r - lo, c, *v);
            }
            for (c, v) in y.iter().enumerate() {
                yc.set(r - lo, c, *v);
            }
        }
        linalg::gram_add(&xc, &mut g);
        linalg::tn_add(&xc, &yc, &mut h);
    }
    let mut coef = Dense::zeros(cols, outputs);
    for o in 0..outputs {
        let rhs: Vec<f64> = (0..cols).map(|c| h.at(c, o)).collect();
        let sol = linalg::spd_solve(&g, &rhs)?;
        for (c, v) in sol.iter().enumerate() {
            coef.set(c, o, *v);
        }
    }
    Some(coef)
}

/// Inverse of the complex l×l matrix `a` (row-major) by Gauss–Jordan elimination with partial
/// pivoting, and ln|det a|; `None` if it is singular to working precision.
pub(super) fn invert(a: &[C64], l: usize) -> Option<(Vec<C64>, f64)> {
    let mut w = a.to_vec();
    let mut inv: Vec<C64> = (0..l * l)
        .map(|t| C64::new(if t / l == t % l { 1.0 } else { 0.0 }, 0.0))
        .collect();
    let scale = a.iter().map(|v| v.norm()).fold(0.0, f64::max);
    let mut log_det = 0.0;
    for col in 0..l {
        let piv =
            (col..l).max_by(|&r, &s| w[r * l + col].norm().total_cmp(&w[s * l + col].norm()))?;
        let p = w[piv * l + col];
        if p.norm().is_nan() || p.norm() <= 1e-13 * scale {
            return None;
        }
        if piv != col {
            for t in 0..l {
                w.swap(piv * l + t, col * l + t);
                inv.swap(piv * l + t, col * l + t);
            }
        }
        log_det += p.norm().ln();
        let pinv = p.inv();
        for t in 0..l {
            w[col * l + t] *= pinv;
            inv[col * l + t] *= pinv;
        }
        for r in 0..l {
            if r != col {
                let f = w[r * l + col];
                if f != C64::new(0.0, 0.0) {
                    for t in 0..l {
                        let (wc, ic) = (w[col * l + t], inv[col * l + t]);
                        w[r * l + t] -= f * wc;
                        inv[r * l + t] -= f * ic;
                    }
                }
            }
        }
    }
    Some((inv, log_det))
}

/// Lower Cholesky factor (row-major) of the symmetric l×l matrix whose lower triangle is
/// `a`; `None` unless positive definite with room to spare.
pub(super) fn cholesky(a: &[f64], l: usize) -> Option<Vec<f64>> {
    let mut c = vec![0.0; l * l];
    for i in 0..l {
        for j in 0..=i {
            let s = a[i * l + j] - (0..j).map(|k| c[i * l + k] * c[j * l + k]).sum::<f64>();
            if i == j {
                // Relative to the diagonal entry: a channel that the others predict exactly
                // (a copy, a sum) makes Σ singular, and the joint model does not apply.
                if s.is_nan() || s <= 1e-10 * a[i * l + i] {
                    return None;
                }
                c[i * l + i] = s.sqrt();
            } else {
                c[i * l + j] = s / c[j * l + j];
            }
        }
    }
    Some(c)
}
