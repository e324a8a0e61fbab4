//! The floor of a linear model class on a periodic record: the best linear or Zener
//! oscillator (mass fixed) fitted *with the input*, by output-error least squares in the
//! frequency domain.
//!
//! For one steady-state period, the output of a linear model is exactly
//! $\hat Y(f) = H(f)\,U(f)$ at every DFT bin, so the time-domain output error equals (Parseval)
//! $\sum_f |Y(f) - H(f)U(f)|^2$, minimised by Gauss–Newton / Levenberg–Marquardt over
//! $(c, k)$ with $H = 1/(k - m\omega^2 + i\omega c)$, or over $(c, k, k_\infty, \Omega)$ with
//! $H = 1/(k - m\omega^2 + i\omega c + k_\infty\,i\omega/(i\omega + \Omega))$. No identified
//! model of the class can validate better than this on that record.

use hyst_model::{Oscillator, ZenerParams};

use crate::fft::{C, irfft, rfft};
use crate::{Validation, epsilon};

/// The output of the linear model `h(ω)` driven by one period with spectrum `u` (length n).
fn response(h: impl Fn(f64) -> C, u: &[C], n: usize, fs: f64) -> Vec<f64> {
    let spec: Vec<C> = u
        .iter()
        .enumerate()
        .map(|(i, ui)| {
            let w = 2.0 * std::f64::consts::PI * i as f64 * fs / n as f64;
            h(w) * ui
        })
        .collect();
    irfft(&spec, n)
}

/// Levenberg–Marquardt on complex residuals `r(p)` (finite differences).
fn lm<const P: usize>(mut p: [f64; P], r: impl Fn(&[f64; P]) -> Vec<C>) -> [f64; P] {
    let cost = |v: &[C]| v.iter().map(|x| x.norm_sqr()).sum::<f64>();
    let mut cur = r(&p);
    let mut c = cost(&cur);
    let mut lambda = 1e-3;
    for _ in 0..200 {
        let mut jac = vec![[C::new(0.0, 0.0); P]; cur.len()];
        for j in 0..P {
            let h = 1e-7 * p[j].abs().max(1e-6);
            let mut q = p;
            q[j] += h;
            let rq = r(&q);
            for (row, (a, b)) in jac.iter_mut().zip(rq.iter().zip(&cur)) {
                row[j] = (a - b) / h;
            }
        }
        let mut a = vec![vec![0.0; P]; P];
        let mut g = vec![0.0; P];
        for (row, ri) in jac.iter().zip(&cur) {
            for i in 0..P {
                g[i] += (row[i].conj() * ri).re;
                for j in 0..P {
                    a[i][j] += (row[i].conj() * row[j]).re;
                }
            }
        }
        let improved = crate::lm_step(&a, &g, &mut lambda, |step| {
            let mut q = p;
            for (v, s) in q.iter_mut().zip(step) {
                *v -= s;
            }
            let rq = r(&q);
            let cq = cost(&rq);
            (cq < c).then(|| {
                let significant = c - cq > 1e-13 * c;
                (p, cur, c) = (q, rq, cq);
                significant
            })
        });
        if !improved {
            break;
        }
    }
    p
}

/// A fitted floor model and its error on the record.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Floor {
    /// The best model of the class.
    pub model: Oscillator,
    /// Its error on the record.
    pub validation: Validation,
}

/// Fit the frequency response `h(p, ω)` to one steady-state period by output error; returns
/// the parameters and the error of the fitted model on the record.
fn fit_class<const P: usize>(
    u: &[f64],
    y: &[f64],
    fs: f64,
    start: [f64; P],
    h: impl Fn(&[f64; P], f64) -> C,
) -> ([f64; P], Validation) {
    let n = u.len();
    let (su, sy) = (rfft(u), rfft(y));
    let w = |i: usize| 2.0 * std::f64::consts::PI * i as f64 * fs / n as f64;
    let p = lm(start, |p| {
        su.iter()
            .zip(&sy)
            .enumerate()
            .map(|(i, (ui, yi))| yi - h(p, w(i)) * ui)
            .collect()
    });
    let yhat = response(|w| h(&p, w), &su, n, fs);
    (p, epsilon(&yhat, y))
}

/// The best linear oscillator of mass `m` on one steady-state period (u, y) at `fs`,
/// starting from `start` (c, k).
pub fn linear(u: &[f64], y: &[f64], fs: f64, m: f64, start: (f64, f64)) -> Floor {
    let (p, validation) = fit_class(u, y, fs, [start.0, start.1], |p, w| {
        C::new(1.0, 0.0) / C::new(p[1] - m * w * w, w * p[0])
    });
    Floor {
        model: Oscillator::linear(m, p[0], p[1]),
        validation,
    }
}

/// The best Zener oscillator of mass `m` on one steady-state period, starting from
/// `start` (c, k, k∞, Ω).
pub fn zener(u: &[f64], y: &[f64], fs: f64, m: f64, start: [f64; 4]) -> Floor {
    let (p, validation) = fit_class(u, y, fs, start, |p, w| {
        let iw = C::new(0.0, w);
        let z = iw * p[2] / (iw + p[3]);
        C::new(1.0, 0.0) / (C::new(p[1] - m * w * w, w * p[0]) + z)
    });
    Floor {
        model: Oscillator::zener(
            m,
            p[0],
            p[1],
            ZenerParams {
                k_inf: p[2],
                omega: p[3],
            },
        ),
        validation,
    }
}
