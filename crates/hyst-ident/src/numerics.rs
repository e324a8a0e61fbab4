//! Numerics the fits share: Welch's PSD, normal equations, a Levenberg–Marquardt step, and
//! Gaussian elimination.

use crate::fft;

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

/// How a Levenberg–Marquardt fit damps its steps: λ multiplies the normal equations'
/// diagonal by `1 + λ`; a rejected step raises λ by `grow`, an accepted one lowers it by
/// `shrink` (not below `min`); past `max` the fit has no step left.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct LmSchedule {
    /// Factor λ is multiplied by after an accepted step (< 1).
    pub shrink: f64,
    /// Factor λ is multiplied by after a rejected step (> 1).
    pub grow: f64,
    /// Smallest λ.
    pub min: f64,
    /// Largest λ tried.
    pub max: f64,
}

impl Default for LmSchedule {
    /// λ × 0.3 on success (at least 1e-12), × 10 on failure, up to 1e10.
    fn default() -> Self {
        LmSchedule {
            shrink: 0.3,
            grow: 10.0,
            min: 1e-12,
            max: 1e10,
        }
    }
}

/// One Levenberg–Marquardt step on the normal equations `a·step = g` (Gauss–Newton matrix and
/// gradient of ½‖r‖²) with the default [`LmSchedule`]; see [`lm_step_with`].
pub(crate) fn lm_step(
    a: &[Vec<f64>],
    g: &[f64],
    lambda: &mut f64,
    try_step: impl FnMut(&[f64]) -> Option<bool>,
) -> bool {
    lm_step_with(&LmSchedule::default(), a, g, lambda, try_step)
}

/// One Levenberg–Marquardt step on the normal equations `a·step = g`: the diagonal is damped
/// by `1 + λ` and λ raised by the schedule until `try_step` accepts the step (the caller
/// moves to `x − step` when its cost is lower and returns `Some(significant)`, else `None`);
/// on acceptance λ shrinks. Returns whether an accepted step lowered the cost
/// significantly; `false` also when λ passes the schedule's largest. Every fit of the crate
/// steps through here.
pub(crate) fn lm_step_with(
    schedule: &LmSchedule,
    a: &[Vec<f64>],
    g: &[f64],
    lambda: &mut f64,
    mut try_step: impl FnMut(&[f64]) -> Option<bool>,
) -> bool {
    while *lambda < schedule.max {
        let mut m = a.to_vec();
        for (i, row) in m.iter_mut().enumerate() {
            row[i] = row[i] * (1.0 + *lambda) + 1e-300;
        }
        if let Some(step) = solve(m, g.to_vec())
            && let Some(significant) = try_step(&step)
        {
            *lambda = (*lambda * schedule.shrink).max(schedule.min);
            return significant;
        }
        *lambda *= schedule.grow;
    }
    false
}

/// Solve the small dense system `a x = b` (nalgebra's LU with partial pivoting); `None` if
/// it is singular or the result is not finite.
pub(crate) fn solve(a: Vec<Vec<f64>>, b: Vec<f64>) -> Option<Vec<f64>> {
    let n = b.len();
    if a.len() != n || a.iter().any(|row| row.len() != n) {
        return None;
    }
    let m = nalgebra::DMatrix::from_fn(n, n, |i, j| a[i][j]);
    let x = m.lu().solve(&nalgebra::DVector::from_vec(b))?;
    x.iter()
        .all(|v| v.is_finite())
        .then(|| x.iter().copied().collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The solve against a system with a known answer, a singular one, and a zero pivot that
    /// partial pivoting steps around.
    #[test]
    fn solve_is_exact_on_small_systems() {
        let a = vec![
            vec![0.0, 2.0, 1.0],
            vec![1.0, 1.0, 0.0],
            vec![2.0, 0.0, 3.0],
        ];
        let x = [1.0, -2.0, 0.5];
        let b: Vec<f64> = a
            .iter()
            .map(|r| r.iter().zip(&x).map(|(p, q)| p * q).sum())
            .collect();
        let got = solve(a, b).unwrap();
        for (g, e) in got.iter().zip(x) {
            // Three unknowns of order 1: rounding only.
            approx::assert_abs_diff_eq!(*g, e, epsilon = 1e-14);
        }
        assert!(solve(vec![vec![1.0, 2.0], vec![2.0, 4.0]], vec![1.0, 1.0]).is_none());
    }

    /// Levenberg–Marquardt on f(x) = (x − 3)²: steps until the cost stops falling, and λ
    /// follows the schedule (shrunk on success, grown on failure, capped).
    #[test]
    fn lm_reaches_the_minimum_of_a_parabola() {
        let mut x = 0.0f64;
        let mut lambda = 1e-3;
        for _ in 0..50 {
            // r = x − 3, J = 1: JᵀJ = 1, Jᵀr = x − 3.
            let (a, g) = (vec![vec![1.0]], vec![x - 3.0]);
            let cost = (x - 3.0).powi(2);
            let moved = lm_step(&a, &g, &mut lambda, |step| {
                let q = x - step[0];
                ((q - 3.0).powi(2) < cost).then(|| {
                    x = q;
                    true
                })
            });
            if !moved {
                break;
            }
        }
        approx::assert_abs_diff_eq!(x, 3.0, epsilon = 1e-9);
        let s = LmSchedule {
            shrink: 0.5,
            grow: 4.0,
            min: 0.1,
            max: 100.0,
        };
        let mut l = 0.15;
        assert!(lm_step_with(&s, &[vec![1.0]], &[1.0], &mut l, |_| Some(
            true
        )));
        assert_eq!(l, 0.1);
        let mut l = 1.0;
        assert!(!lm_step_with(&s, &[vec![1.0]], &[1.0], &mut l, |_| None));
        assert_eq!(l, 256.0);
    }
}
