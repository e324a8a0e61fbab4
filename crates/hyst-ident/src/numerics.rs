//! Numerics the fits share: Welch's PSD, normal equations, a Levenberg–Marquardt step, and
//! Gaussian elimination.

use crate::*;

/// One-sided power spectral density by Welch's method (Hann window, `segment` samples, 50 %
/// overlap): (frequencies in Hz, PSD in units²/Hz).
pub fn welch_psd(y: &[f64], fs: f64, segment: usize) -> (Vec<f64>, Vec<f64>) {
    let seg = segment.min(y.len()).max(2);
    let win: Vec<f64> = (0..seg)
        .map(|i| 0.5 - 0.5 * (2.0 * std::f64::consts::PI * i as f64 / seg as f64).cos())
        .collect();
    let u: f64 = win.iter().map(|w| w * w).sum();
    let bins = seg / 2 + 1;
    let mut acc = vec![0.0; bins];
    let mut count = 0usize;
    let mut start = 0;
    while start + seg <= y.len() {
        let windowed: Vec<f64> = y[start..start + seg]
            .iter()
            .zip(&win)
            .map(|(v, w)| v * w)
            .collect();
        for (a, x) in acc.iter_mut().zip(fft::rfft(&windowed)) {
            *a += x.norm_sqr();
        }
        count += 1;
        start += seg / 2;
    }
    let scale = 2.0 / (fs * u * count.max(1) as f64);
    (
        (0..bins).map(|b| b as f64 * fs / seg as f64).collect(),
        acc.iter().map(|v| v * scale).collect(),
    )
}

/// Gauss–Newton matrix JᵀJ and gradient Jᵀr from the Jacobian's columns and the residuals.
pub(crate) fn normal_equations(cols: &[Vec<f64>], r: &[f64]) -> (Vec<Vec<f64>>, Vec<f64>) {
    let np = cols.len();
    let mut a = vec![vec![0.0; np]; np];
    let mut g = vec![0.0; np];
    for i in 0..np {
        g[i] = cols[i].iter().zip(r).map(|(p, q)| p * q).sum();
        for j in i..np {
            let v: f64 = cols[i].iter().zip(&cols[j]).map(|(p, q)| p * q).sum();
            a[i][j] = v;
            a[j][i] = v;
        }
    }
    (a, g)
}

/// One Levenberg–Marquardt step on the normal equations `a·step = g` (Gauss–Newton matrix and
/// gradient of ½‖r‖²): the diagonal is damped by `1 + λ` and `λ` raised tenfold until `try_step`
/// accepts the step (the caller moves to `x − step` when its cost is lower and returns
/// `Some(significant)`, else `None`); on acceptance λ shrinks to 0.3 λ. Returns whether an
/// accepted step lowered the cost significantly; `false` also when λ passes 1e10.
pub(crate) fn lm_step(
    a: &[Vec<f64>],
    g: &[f64],
    lambda: &mut f64,
    mut try_step: impl FnMut(&[f64]) -> Option<bool>,
) -> bool {
    while *lambda < 1e10 {
        let mut m = a.to_vec();
        for (i, row) in m.iter_mut().enumerate() {
            row[i] = row[i] * (1.0 + *lambda) + 1e-300;
        }
        if let Some(step) = solve(m, g.to_vec())
            && let Some(significant) = try_step(&step)
        {
            *lambda = (*lambda * 0.3).max(1e-12);
            return significant;
        }
        *lambda *= 10.0;
    }
    false
}

/// Solve the small dense system `a x = b` by Gaussian elimination with partial pivoting;
/// `None` if it is singular or the result is not finite.
pub(crate) fn solve(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Option<Vec<f64>> {
    let n = b.len();
    for col in 0..n {
        let piv = (col..n).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        a.swap(col, piv);
        b.swap(col, piv);
        if a[col][col] == 0.0 || !a[col][col].is_finite() {
            return None;
        }
        for row in col + 1..n {
            let f = a[row][col] / a[col][col];
            let pivot_row = a[col].clone();
            for (k, v) in a[row].iter_mut().enumerate().skip(col) {
                *v -= f * pivot_row[k];
            }
            b[row] -= f * b[col];
        }
    }
    for col in (0..n).rev() {
        let s: f64 = (col + 1..n).map(|k| a[col][k] * b[k]).sum();
        b[col] = (b[col] - s) / a[col][col];
    }
    b.iter().all(|v| v.is_finite()).then_some(b)
}
