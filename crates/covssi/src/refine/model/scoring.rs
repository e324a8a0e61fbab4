//! Fisher scoring with a Levenberg–Marquardt safeguard, and the evidence of each mode.

use crate::error::SsiError;
use crate::linalg::{self, Dense};
use crate::refine::model::{Eval, Fit};
use crate::refine::options::RefineOptions;
use crate::refine::parametrization::unpack;

/// What an evidence fit (a mode removed) needs of L, so that it can stop before converging.
#[derive(Debug, Clone, Copy)]
pub(in crate::refine) struct Evidence {
    /// L of the model with every mode: the fit stops once it gains less than 10⁻⁵ of the
    /// rise above it.
    pub(in crate::refine) full: f64,
    /// Below this L the decision is made (a removed mode goes, an added one stays): stop
    /// once it is out of reach, and, with `stop_below`, once L is below it.
    pub(in crate::refine) drop_below: f64,
    /// Stop once L is below `drop_below`. Not for a pole being added: a kept fit must
    /// converge.
    pub(in crate::refine) stop_below: bool,
}

impl Evidence {
    /// For the fit of a model with a pole added to one whose L is `current`: it stays when L
    /// falls below `current − penalty`, so the fit stops once that is out of reach (nothing
    /// else: a fit that reaches it runs to convergence, as without this). `None` without a
    /// penalty (no selection).
    pub(in crate::refine) fn adding(current: f64, penalty: Option<f64>) -> Option<Self> {
        penalty.map(|p| Evidence {
            full: f64::INFINITY,
            drop_below: current - p,
            stop_below: false,
        })
    }
}

/// Fisher scoring with a Levenberg–Marquardt safeguard from θ, whose first 2m entries are the
/// `m` modes' ln ω and logit ζ and the next `reals` the real poles' ln ρ; `eval(θ, true)`
/// gives L, the score and the Fisher information, `eval(θ, false)` L alone (`None` outside
/// the model). Stops when neither the last step nor a full Gauss–Newton step gains `tol`; for
/// an `evidence` fit, also when neither gains 10⁻⁵ of the rise of L above the full model's,
/// when L is below `drop_below` (if `stop_below`), or when `drop_below` is out of reach:
/// further from L than ten times the larger of the two gains over each iteration left (the
/// iteration cap would decide the same unless the gains grew tenfold).
pub(in crate::refine) fn scoring(
    eval: impl Fn(&[f64], bool) -> Option<Eval>,
    mut th: Vec<f64>,
    (m, reals): (usize, usize),
    opts: &RefineOptions,
    tol: f64,
    held: usize,
    evidence: Option<Evidence>,
) -> Result<Fit, SsiError> {
    let mut cur = eval(&th, true).ok_or(SsiError::Refinement {
        reason: "the starting model has a non-finite likelihood",
    })?;
    let mut nu = 1e-3;
    let mut iterations = 0;
    while iterations < opts.max_iterations {
        iterations += 1;
        let mut accepted = None;
        for _ in 0..30 {
            let mut a = damped(&cur.f, nu);
            let u = masked(&cur.u, held);
            if held > 0 {
                // Rows and columns of the held parameters become identity (their score is
                // 0): they do not move.
                for t in 0..held {
                    for k in 0..a.rows {
                        a.set(t, k, 0.0);
                        a.set(k, t, 0.0);
                    }
                    a.set(t, t, 1.0);
                }
            }
            if let Some(step) = linalg::spd_solve(&a, &u) {
                let trial: Vec<f64> = th.iter().zip(&step).map(|(x, s)| x + s).collect();
                if let Some(e) = eval(&trial, false)
                    && e.l < cur.l
                {
                    accepted = Some((trial, e.l));
                    break;
                }
            }
            nu *= 10.0;
        }
        let Some((trial, l_new)) = accepted else {
            break; // no step lowers L: a minimum to working precision
        };
        let gain = cur.l - l_new;
        th = trial;
        cur = eval(&th, true).ok_or(SsiError::Refinement {
            reason: "the likelihood became non-finite at an accepted step",
        })?;
        nu = (nu / 10.0).max(1e-12);
        // Converged when even a full Gauss–Newton step would gain less than `tol` (the
        // Newton decrement ½ Uᵀ F⁻¹ U); a small gain alone may be a short damped step.
        let u = masked(&cur.u, held);
        let decrement = linalg::spd_solve(&damped(&cur.f, 0.0), &u)
            .map(|x| 0.5 * x.iter().zip(&u).map(|(a, b)| a * b).sum::<f64>());
        let gains_below = |t: f64| gain < t && decrement.is_none_or(|d| d < t);
        if gains_below(tol) {
            break;
        }
        if let Some(ev) = evidence {
            let left = (opts.max_iterations - iterations) as f64;
            let step = gain.max(decrement.unwrap_or(f64::INFINITY));
            if gains_below(1e-5 * (cur.l - ev.full))
                || (ev.stop_below && cur.l < ev.drop_below)
                || (ev.drop_below.is_finite() && 10.0 * left * step < cur.l - ev.drop_below)
            {
                break;
            }
        }
    }
    Ok(Fit {
        lambdas: unpack(&th, m),
        reals: th[2 * m..2 * m + reals].iter().map(|v| -v.exp()).collect(),
        theta: th,
        l: cur.l,
        fisher: cur.f,
        iterations,
    })
}

/// `f` with its diagonal F_tt raised to F_tt·(1 + ν) (Levenberg–Marquardt damping) plus
/// 1e-12·(1 + F_tt), so that a semi-definite F still factors.
pub(in crate::refine) fn damped(f: &Dense, nu: f64) -> Dense {
    let mut a = f.clone();
    for t in 0..a.rows {
        let dg = f.at(t, t);
        a.set(t, t, dg * (1.0 + nu) + 1e-12 * (1.0 + dg));
    }
    a
}

/// The score with its first `held` entries (held parameters) zeroed.
pub(in crate::refine) fn masked(u: &[f64], held: usize) -> Vec<f64> {
    let mut v = u.to_vec();
    v.iter_mut().take(held).for_each(|x| *x = 0.0);
    v
}
