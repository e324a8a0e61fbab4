//! Standard errors of the poles and shapes from the inverse Fisher information.

use crate::cluster::Mode;
use crate::linalg::{self, C64, Dense};
use crate::refine::model::{Fit, Model, What};
use crate::refine::pairing::pair_with_ssi_modes;
use crate::refine::parametrization::damping_and_gap;
use crate::refine::results::{RefinedMode, RefinedRealPole};

/// The modes' estimates and standard errors (frequency Hz, damping ratio), in the order of
/// the per-channel fit, with what [`Refinement`] reports of the fit that gave them.
pub(super) struct Estimates {
    pub(super) lambdas: Vec<C64>,
    pub(super) se: Vec<Option<(f64, f64)>>,
    /// The modes' shapes from the joint likelihood (in every channel: from the channels
    /// themselves, or regressed on the fit of combinations of them), largest entry 1, with
    /// each entry's standard error; `None` from the per-channel fit.
    pub(super) shapes: Vec<Option<(Vec<C64>, Vec<f64>)>>,
    /// Real poles λ and their standard errors (rad/s), in the order of the per-channel fit.
    pub(super) reals: Vec<(f64, Option<f64>)>,
    pub(super) l: f64,
    pub(super) misfit: f64,
    pub(super) iterations: usize,
    pub(super) combinations: Option<usize>,
    pub(super) bands: usize,
}

/// The covariance of a shape's entries (rows and columns 0..l its real parts, l..2l its
/// imaginary ones) from the covariance `cov` of θ, whose entries `offset..offset + l` hold
/// Re c and the next l Im c.
pub(super) fn channel_block(cov: &Dense, offset: usize, l: usize) -> Dense {
    let mut out = Dense::zeros(2 * l, 2 * l);
    for i in 0..2 * l {
        for j in 0..2 * l {
            out.set(i, j, cov.at(offset + i, offset + j));
        }
    }
    out
}

/// A shape `c` of the channels as fitted (channel a times `scales[a]`) in the channels' own
/// units, c_a/d_a, scaled so that its largest entry is 1, s_a = c_a/c_b, with each entry's
/// standard error by the delta method, √(E|δs_a|²) (0 for the entry b itself), from the
/// covariance `cov` of c (rows and columns 0..l its real parts, l..2l its imaginary ones):
/// δs_a = δc_a/c_b − c_a δc_b/c_b².
pub(super) fn shape_se(c: &[C64], cov: &Dense, scales: &[f64]) -> (Vec<C64>, Vec<f64>) {
    let l = c.len();
    let c: Vec<C64> = c.iter().zip(scales).map(|(v, d)| v / d).collect();
    let cov_at = |i: usize, j: usize| cov.at(i, j) / (scales[i % l] * scales[j % l]);
    let b = crate::cluster::largest_entry(&c);
    let cb = c[b];
    if cb.norm() == 0.0 {
        return (c, vec![f64::NAN; l]);
    }
    // Complex multiplication by w as a real 2 × 2 matrix acting on (Re, Im).
    let mat = |w: C64| [[w.re, -w.im], [w.im, w.re]];
    let se = (0..l)
        .map(|a| {
            if a == b {
                return 0.0;
            }
            // δs_a (Re, Im) = J (δRe c_a, δIm c_a, δRe c_b, δIm c_b).
            let (p, q) = (mat(1.0 / cb), mat(-c[a] / (cb * cb)));
            let jac = [
                [p[0][0], p[0][1], q[0][0], q[0][1]],
                [p[1][0], p[1][1], q[1][0], q[1][1]],
            ];
            let idx = [a, l + a, b, l + b];
            let mut var = 0.0;
            for row in &jac {
                for (u, &iu) in idx.iter().enumerate() {
                    for (v, &iv) in idx.iter().enumerate() {
                        var += row[u] * cov_at(iu, iv) * row[v];
                    }
                }
            }
            var.max(0.0).sqrt()
        })
        .collect();
    (c.iter().map(|v| v / cb).collect(), se)
}

/// Standard errors of mode j's frequency (Hz) and damping ratio from the covariance `cov` of
/// `theta` (ln ω of the m modes, then their logit ζ, first): dω = ω d ln ω and
/// dζ = ζ(1 − ζ) d logit ζ, 1 − ζ as the poles' derivatives take it.
pub(super) fn pole_se(cov: &Dense, j: usize, m: usize, theta: &[f64]) -> (f64, f64) {
    let w = theta[j].exp();
    let (zeta, gap) = damping_and_gap(theta[m + j]);
    (
        cov.at(j, j).max(0.0).sqrt() * w / (2.0 * std::f64::consts::PI),
        cov.at(m + j, m + j).max(0.0).sqrt() * zeta * gap,
    )
}

/// The per-channel fit's estimates, with their asymptotic covariance: F⁻¹ for one channel;
/// for the per-channel likelihood of several, the composite likelihood's sandwich
/// F⁻¹ J F⁻¹, J the covariance of the score given the channels' coherence.
pub(super) fn per_channel_estimates(
    fitted_model: &Model,
    fit: Fit,
    l: usize,
    misfit: f64,
) -> Estimates {
    let mk = fit.lambdas.len();
    // A mode whose damping has saturated sits on the parameter space's edge, where the
    // likelihood no longer depends on its logit ζ: that row of F is 0 and F has no inverse,
    // which took every estimate's standard error with it. Its logit ζ is held (F's and J's
    // rows and columns for it left out); that mode has no standard error.
    let saturated = |j: usize| fit.theta[mk + j] > SATURATED_LOGIT;
    let free: Vec<usize> = (0..fit.theta.len())
        .filter(|&t| !(mk..2 * mk).contains(&t) || !saturated(t - mk))
        .collect();
    let f = restricted(&fit.fisher, &free);
    let j = (l > 1)
        .then(|| fitted_model.eval(&fit.theta, mk, What::Sandwich))
        .flatten()
        .map(|e| restricted(&e.f, &free));
    // Without the score's covariance (it could not be evaluated) no error is known.
    let (cov, estimable) = if l > 1 && j.is_none() {
        (None, vec![false; free.len()])
    } else {
        covariance_of(&f, j.as_ref())
    };
    let known: Vec<bool> = {
        let mut k = vec![false; fit.theta.len()];
        for (a, &t) in free.iter().enumerate() {
            k[t] = estimable[a];
        }
        k
    };
    let cov = cov.map(|c| embedded(&c, &free, fit.theta.len()));
    Estimates {
        se: (0..mk)
            .map(|j| {
                cov.as_ref()
                    .filter(|_| !saturated(j) && known[j] && known[mk + j])
                    .map(|c| pole_se(c, j, mk, &fit.theta))
            })
            .collect(),
        reals: fit
            .reals
            .iter()
            .enumerate()
            .map(|(i, &lam)| {
                let t = 2 * mk + i;
                let se = cov.as_ref().filter(|_| known[t]);
                (lam, se.map(|c| -lam * c.at(t, t).max(0.0).sqrt()))
            })
            .collect(),
        shapes: vec![None; fit.lambdas.len()],
        lambdas: fit.lambdas,
        l: fit.l,
        misfit,
        iterations: fit.iterations,
        combinations: None,
        bands: 1,
    }
}

/// The covariance of θ from the Fisher information `f` (and for a composite likelihood the
/// score's covariance `j`: the sandwich F⁻¹JF⁻¹), and whether each parameter's variance is
/// known. Where F has an inverse, every one is. Where it has none, the estimable
/// parameters' covariance comes from its pseudo-inverse ([`identified`]), and a parameter's
/// variance is known only where its direction lies outside F's null space and its variance
/// does not depend on where that space is cut: a
/// numerator zero pressed onto the unit circle, or a real pole that does not decay (drift),
/// makes F singular in directions no mode's pole takes part in (seen on the corpus's
/// coloured-load records: every mode's standard error had been lost with them).
fn covariance_of(f: &Dense, j: Option<&Dense>) -> (Option<Dense>, Vec<bool>) {
    let n = f.rows;
    let covariance = |fi: &Dense| match j {
        None => fi.clone(),
        Some(j) => linalg::sandwich(fi, j),
    };
    if let Some(fi) = linalg::spd_inverse(f) {
        return (Some(covariance(&fi)), vec![true; n]);
    }
    let Some((tight, loose, null)) = identified(f) else {
        return (None, vec![false; n]);
    };
    let (a, b) = (covariance(&tight), covariance(&loose));
    let known = (0..n)
        .map(|t| {
            let (va, vb) = (a.at(t, t), b.at(t, t));
            let agree = va.is_finite() && va > 0.0 && (va - vb).abs() <= CUT_AGREEMENT * va;
            agree && null[t] <= NULL_SHARE
        })
        .collect();
    (Some(a), known)
}

/// The two cuts of a singular F's spectrum ([`identified`]): directions whose eigenvalue is
/// below this share of the largest (F scaled to a unit diagonal) are its null space. The
/// first is near the rounding of F's entries, summed over ~10⁵ bins (an eigenvalue there is
/// rounding, not information); the second a hundred times above it.
const NULL_CUTS: [f64; 2] = [1e-11, 1e-9];

/// A parameter's variance is known when the two cuts give it within this share of each
/// other: it then hardly depends on where the null space is cut. A parameter tied to a
/// direction whose eigenvalue lies between the cuts gets variances up to their ratio apart,
/// a hundredfold; the modes' poles of corpus records whose numerators have zeros on the
/// unit circle moved by 0.1–30 % (their standard errors by half that).
const CUT_AGREEMENT: f64 = 0.5;

/// A parameter is estimable when at most this share of its direction (F scaled to a unit
/// diagonal) lies in F's null space: its variance is then that of an estimable function.
/// On the corpus records whose F is singular the poles' shares were 10⁻¹⁷–10⁻⁸, the tied
/// numerator coefficients' 0.02–0.6.
const NULL_SHARE: f64 = 1e-6;

/// The pseudo-inverses of the symmetric positive semi-definite `f` at the cuts
/// [`NULL_CUTS`] (scaled to a unit diagonal first, so that parameters in different units
/// weigh alike; a parameter with no information gets a variance of 0, which reads as unknown): the covariance of
/// the estimable functions of θ, cᵀF⁺c, whatever generalised inverse; and the share of
/// each parameter's direction in the null space of the looser cut (1 for a parameter with
/// no information). `None` if the eigen-decomposition fails.
fn identified(f: &Dense) -> Option<(Dense, Dense, Vec<f64>)> {
    let n = f.rows;
    let d: Vec<f64> = (0..n).map(|i| f.at(i, i).max(0.0).sqrt()).collect();
    let mut g = Dense::zeros(n, n);
    for i in 0..n {
        for k in 0..n {
            if d[i] > 0.0 && d[k] > 0.0 {
                g.set(i, k, f.at(i, k) / (d[i] * d[k]));
            }
        }
    }
    let (values, vectors) = linalg::symmetric_eigen(&g)?;
    let top = values.iter().copied().fold(0.0f64, f64::max);
    let inverse = |cut: f64| {
        let mut out = Dense::zeros(n, n);
        for (e, &v) in values.iter().enumerate() {
            if v <= cut * top {
                continue;
            }
            for i in 0..n {
                let a = vectors.at(i, e) / v;
                for k in 0..n {
                    let cur = out.at(i, k);
                    out.set(i, k, cur + a * vectors.at(k, e));
                }
            }
        }
        for i in 0..n {
            for k in 0..n {
                let s = d[i] * d[k];
                let v = if s > 0.0 { out.at(i, k) / s } else { 0.0 };
                out.set(i, k, v);
            }
        }
        out
    };
    let null = (0..n)
        .map(|i| {
            if d[i] == 0.0 {
                return 1.0;
            }
            (0..n)
                .filter(|&e| values[e] <= NULL_CUTS[1] * top)
                .map(|e| vectors.at(i, e).powi(2))
                .sum()
        })
        .collect();
    Some((inverse(NULL_CUTS[0]), inverse(NULL_CUTS[1]), null))
}

/// Beyond this logit ζ a mode's damping has saturated: ζ(1 − ζ) < 10⁻¹³, so L moves by less
/// than rounding when it changes, and ζ reads as 1 to twelve digits.
const SATURATED_LOGIT: f64 = 30.0;

/// The rows and columns `keep` of the square `d`.
fn restricted(d: &Dense, keep: &[usize]) -> Dense {
    let mut r = Dense::zeros(keep.len(), keep.len());
    for (a, &i) in keep.iter().enumerate() {
        for (b, &j) in keep.iter().enumerate() {
            r.set(a, b, d.at(i, j));
        }
    }
    r
}

/// The `n × n` matrix holding `d` at the rows and columns `at`, 0 elsewhere.
fn embedded(d: &Dense, at: &[usize], n: usize) -> Dense {
    let mut e = Dense::zeros(n, n);
    for (a, &i) in at.iter().enumerate() {
        for (b, &j) in at.iter().enumerate() {
            e.set(i, j, d.at(a, b));
        }
    }
    e
}

/// The refined modes of `est` with their `evidence`, named after the SSI `modes` they are,
/// by frequency.
pub(super) fn refined_modes(est: &Estimates, evidence: &[f64], modes: &[Mode]) -> Vec<RefinedMode> {
    let mut kept: Vec<RefinedMode> = est
        .lambdas
        .iter()
        .zip(&est.se)
        .zip(&est.shapes)
        .enumerate()
        .map(|(j, ((&lam, se), shape_and_se))| {
            let w = lam.norm();
            RefinedMode {
                source: None,
                frequency_hz: w / (2.0 * std::f64::consts::PI),
                damping_ratio: -lam.re / w,
                frequency_se_hz: se.map(|s| s.0),
                damping_se: se.map(|s| s.1),
                lambda: lam,
                shape: shape_and_se.as_ref().map(|s| s.0.clone()),
                shape_se: shape_and_se.as_ref().map(|s| s.1.clone()),
                mpc: shape_and_se.as_ref().map(|s| crate::mpc(&s.0)),
                evidence: evidence[j],
            }
        })
        .collect();
    pair_with_ssi_modes(&mut kept, modes);
    kept.sort_by(|a, b| a.frequency_hz.total_cmp(&b.frequency_hz));
    kept
}

/// The refined real poles of `est`, with the SSI clusters they started from and their
/// evidence, slowest first.
pub(super) fn refined_real_poles(
    est: &Estimates,
    sources: &[usize],
    evidence: &[f64],
) -> Vec<RefinedRealPole> {
    let mut real_kept: Vec<RefinedRealPole> = est
        .reals
        .iter()
        .zip(sources.iter().zip(evidence))
        .map(
            |(&(lambda, lambda_se), (&source, &evidence))| RefinedRealPole {
                source,
                lambda,
                lambda_se,
                evidence,
            },
        )
        .collect();
    real_kept.sort_by(|a, b| b.lambda.total_cmp(&a.lambda));
    real_kept
}

#[cfg(test)]
mod tests {
    use super::*;

    /// JᵀJ for the columns `cols` (each of the same length).
    fn gram(cols: &[Vec<f64>]) -> Dense {
        let n = cols.len();
        let mut f = Dense::zeros(n, n);
        for a in 0..n {
            for b in 0..n {
                f.set(a, b, cols[a].iter().zip(&cols[b]).map(|(x, y)| x * y).sum());
            }
        }
        f
    }

    /// Columns of a Jacobian: a pole's, a coupled numerator coefficient's, and two more whose
    /// sum is the second's (a numerator direction that moves nothing: F singular there).
    fn singular_columns() -> Vec<Vec<f64>> {
        let k = 400;
        let pole: Vec<f64> = (0..k).map(|i| (i as f64 * 0.37).sin() * 3.0).collect();
        let b1: Vec<f64> = (0..k)
            .map(|i| (i as f64 * 0.11).cos() + 0.2 * pole[i])
            .collect();
        let b2: Vec<f64> = (0..k)
            .map(|i| 0.5 * b1[i] + (i as f64 * 0.05).sin())
            .collect();
        let b3: Vec<f64> = (0..k)
            .map(|i| 0.5 * b1[i] - (i as f64 * 0.05).sin())
            .collect();
        vec![pole, b1, b2, b3]
    }

    #[test]
    fn a_singular_information_keeps_the_errors_of_what_it_determines() {
        let cols = singular_columns();
        let f = gram(&cols);
        // F has no inverse: b1 − b2 − b3 moves nothing.
        assert!(linalg::spd_inverse(&f).is_none());
        let (cov, known) = covariance_of(&f, None);
        let cov = cov.expect("a covariance of what is estimable");
        // The pole is estimable; the three numerator coefficients, tied, are not.
        assert_eq!(known, vec![true, false, false, false]);
        // Its variance is that of the model without b3, whose span is the same (b1 and b2
        // give b3): F of the three other columns has an inverse, and its (0, 0) is the
        // pole's variance whatever generalised inverse. Rounding of F's ~10⁵-sized entries,
        // amplified by its condition, stays far below 1e-8 of it.
        let reduced = linalg::spd_inverse(&gram(&cols[..3])).expect("invertible");
        let (a, b) = (cov.at(0, 0), reduced.at(0, 0));
        assert!((a - b).abs() <= 1e-8 * b, "{a} against {b}");
    }

    #[test]
    fn an_invertible_information_gives_its_inverse() {
        let cols = singular_columns();
        let f = gram(&cols[..3]);
        let (cov, known) = covariance_of(&f, None);
        assert_eq!(known, vec![true; 3]);
        assert_eq!(cov, linalg::spd_inverse(&f));
    }
}
