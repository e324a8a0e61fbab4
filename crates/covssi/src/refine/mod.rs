//! Maximum-likelihood refinement of the modes in the frequency domain.
//!
//! SSI-COV is consistent but not efficient: it sees the record only through a few dozen
//! correlation lags. This step takes its modes as a start and fits them to the whole record by
//! the Whittle likelihood of the periodograms $I_c(\omega_k) = |\sum_n y_c(n) e^{-i\omega_k n}|^2/N$,
//!
//! $$ L(\theta) = \sum_c \sum_k \Big[\ln S_c(\omega_k) + \frac{I_c(\omega_k)}{S_c(\omega_k)}\Big],
//! \qquad S_c(\omega) = \sigma_c^2\,\frac{|B_c(e^{i\omega})|^2}{|A(e^{i\omega})|^2}, $$
//!
//! where $A(z) = \prod_j (z-\mu_j)(z-\bar\mu_j)$ holds the modes' discrete poles
//! $\mu_j = e^{\lambda_j/f_s}$, shared by all channels, and $B_c$ is a monic polynomial of the
//! same degree $2m$ for each channel (the spectrum of any sampled linear system driven by white
//! noise plus white measurement noise has this form). Each pole is parametrised by
//! $\ln\omega_j$ and $\operatorname{logit}\zeta_j$. $L$ is minimised by Fisher scoring with a
//! Levenberg–Marquardt safeguard: the expected Hessian of $L$ is
//! $F = \sum_{c,k} \nabla\ln S_c\,\nabla\ln S_c^\top$, which also gives the asymptotic covariance
//! $F^{-1}$ of the estimates and so each mode's standard errors. For several channels the
//! channels are treated as independent (a composite likelihood): still consistent, but the
//! standard errors ignore the channels' coherence.
//!
//! The periodograms enter through their averages over frequency bins narrower than the
//! modes' half-power bands (the `spectra` module): over a bin of $n_b$ frequencies where $S$
//! hardly changes, the terms add up to $n_b[\ln S(\bar\omega_b) + \bar I_b/S(\bar\omega_b)]$
//! (jointly, $n_b[\ln\det S + \operatorname{tr}(S^{-1}\hat S_b)]$, a Wishart likelihood), so after
//! one pass over the record the fits cost the same whatever its length. The bins are sized
//! from SSI's poles so that the bias this makes stays under 1/24 of each estimate's standard
//! error; a short record keeps one frequency per bin, Whittle's likelihood exactly. $K$ still
//! counts the frequencies, and the misfit still looks at each of them.
//!
//! Which modes are real is decided by the record, with the BIC penalty of one mode's
//! parameters, $\tfrac12(2+2l)\ln K$ for $l$ channels and $K$ frequencies, as the bar:
//! 1. the strong SSI modes (at least half the largest member count) are fitted together, so
//!    that every peak has its pole from the start (a pole left to travel to a peak without one
//!    can end in a poor local optimum); the others are added one at a time, most members
//!    first, each kept when adding it lowers $L$ by at least the penalty (two starts per step:
//!    fresh numerators, and the current model with the new pole cancelled by a numerator zero,
//!    from which $L$ cannot rise);
//! 2. each kept mode's *evidence* is the rise of $L$ when it is removed, the other poles held
//!    and the numerators refitted. For the decision everything is then let move from there
//!    (a pole sharing a peak with another then costs little to remove); while the weakest
//!    such rise is below the penalty, that mode goes.
//!
//! So spurious clusters of the stabilization diagram do not enter the final model. Whether
//! the record follows the model at all is [`Refinement::misfit`]: under the model the ratios
//! $I_c/S_c$ are unit exponential variables.
//!
//! 3. For 2 to [`JOINT_MAX_CHANNELS`] channels the chosen modes are then fitted once more by
//!    the *joint* likelihood of all channels, cross-spectra included (the `joint` module:
//!    $S = H\Sigma H^H$, $H$ the innovation form in modal coordinates), whose $F^{-1}$ is the
//!    exact asymptotic covariance. A mode every channel sees weakly is then seen through all
//!    of them at once (on the shared 3-DOF record, the 4 Hz mode's damping standard error goes
//!    from 3.1 % to 2.1 %, the Cramér–Rao bound). With more channels it is the joint
//!    likelihood of [`JOINT_MAX_CHANNELS`] combinations of them that span the modes' shapes
//!    (the channels scaled to equal noise floors, then the leading eigenvectors of their
//!    cross-spectral matrices over the modes' bands, each normalised to unit trace); what
//!    the combinations leave out is then measurement noise, so little is lost
//!    ([`Refinement::combinations`]). Every channel's shape then comes from its
//!    cross-spectra with the combinations' whitened innovations, linear in the shape once
//!    the fit is known (the `joint::shapes` module), with standard errors that carry the
//!    fit's own uncertainty. With more modes than combinations, the modes are
//!    split into groups of at most that many at the widest frequency gaps, and each group is
//!    fitted over its own band of frequencies through combinations carrying its modes, the
//!    other modes in the model but held ([`Refinement::bands`]); the likelihood of a band is
//!    that of its own frequencies, which are independent of the others'.
//!
//! **Real poles** ([`refine_with_real_poles`]): a real pole λ = −ρ adds the factor
//! $z - e^{-\rho/f_s}$ to $A$ (parametrised by $\ln\rho$) and one to each $B_c$'s degree. The
//! SSI real-pole clusters are tested as the modes are, against their own penalty
//! $\tfrac12(1+l)\ln K$: the strong ones (by the same member count rule) join the strong
//! modes' fit, the others are added next, before the weak modes (a model without a record's
//! real pole spends a mode on it, a pole pair damped near ζ = 1, and the real pole then has
//! nothing left to explain); each kept one's evidence is its removal's cost, and the
//! weakest goes while that is below the penalty. The joint likelihood has no real poles: with
//! one kept, the estimates are the per-channel fit's.

use crate::linalg::C64;

use crate::progress::{Progress, Steps};
use crate::{Mode, RealPoleCluster, SsiError, SsiOption};

use rayon::prelude::*;

mod bands;
mod joint;
mod model;
mod options;
mod pairing;
mod parametrization;
mod real_poles;
mod results;
mod spectra;
mod standard_errors;

use bands::joint_by_bands;
use model::{Fit, Model, What};
pub use options::RefineOptions;
pub use pairing::SAME_MODE_DISTANCE;
use pairing::nearest_mode;
use real_poles::{RealPoles, add_real_poles, bic_penalty, real_pole_evidence, weakest};
pub use results::{
    DroppedMode, DroppedRealPole, FittedPole, MISFIT_LIMIT, RefinedMode, RefinedRealPole,
    Refinement, exponential_misfit,
};
use spectra::{Scale, Spectra};
use standard_errors::{per_channel_estimates, refined_modes, refined_real_poles};

/// Most channels fitted by the joint likelihood; its cost grows as l⁴ (4lm parameters, l²
/// observations per frequency). More channels are fitted through this many combinations of
/// them.
pub const JOINT_MAX_CHANNELS: usize = 4;

/// Channels whose peak deviations differ by more than this factor are scaled to like sizes
/// before the fit; closer ones are fitted as given.
const EQUILIBRATE_ABOVE: f64 = 1024.0;

/// Refine `modes` (e.g. [`crate::SsiResult::modes`]) on the channels `y` sampled at `fs` Hz.
pub fn refine(
    y: &[&[f64]],
    fs: f64,
    modes: &[Mode],
    opts: &RefineOptions,
) -> Result<Refinement, SsiError> {
    refine_up_to(y, fs, modes, &[], opts, JOINT_MAX_CHANNELS, &|_| {})
}

/// [`refine`], testing and refining the real poles `real_poles` (e.g.
/// [`crate::SsiResult::real_poles`]) too, beside the modes: the strong ones (by member count,
/// as for the modes) are fitted with the strong modes, the others added before the weak
/// modes, each kept when it lowers `L` by at least [`Refinement::real_pole_penalty`] and
/// while its evidence stays above it ([`Refinement::real_poles`],
/// [`Refinement::dropped_real_poles`]). A record with a real pole needs this: fitted without
/// it, the likelihood spends a spurious mode damped near ζ = 1 on it. The joint likelihood
/// has no real poles, so when one is kept the estimates are those of each channel's
/// spectrum. With no real poles given this is [`refine`]. An error if a real pole is not
/// negative and finite.
pub fn refine_with_real_poles(
    y: &[&[f64]],
    fs: f64,
    modes: &[Mode],
    real_poles: &[RealPoleCluster],
    opts: &RefineOptions,
) -> Result<Refinement, SsiError> {
    refine_up_to(y, fs, modes, real_poles, opts, JOINT_MAX_CHANNELS, &|_| {})
}

/// [`refine_with_real_poles`], telling `progress` of each step as it starts: the spectra,
/// the strong modes' fit, each weak mode added, the real poles, the evidence, the joint fit.
pub fn refine_with_progress(
    y: &[&[f64]],
    fs: f64,
    modes: &[Mode],
    real_poles: &[RealPoleCluster],
    opts: &RefineOptions,
    progress: &dyn Fn(Progress),
) -> Result<Refinement, SsiError> {
    refine_up_to(y, fs, modes, real_poles, opts, JOINT_MAX_CHANNELS, progress)
}

/// [`refine_with_progress`], fitting up to `joint_max` channels themselves by the joint
/// likelihood and more through `joint_max` combinations of them.
fn refine_up_to(
    y: &[&[f64]],
    fs: f64,
    modes: &[Mode],
    real_poles: &[RealPoleCluster],
    opts: &RefineOptions,
    joint_max: usize,
    progress: &dyn Fn(Progress),
) -> Result<Refinement, SsiError> {
    crate::checks::check_fs(fs)?;
    let (n, means) = crate::checks::check_channels(y)?;
    check_refine_options(opts, real_poles)?;
    let (m, l) = (modes.len(), y.len());
    check_length(n, m, l, real_poles.len())?;
    // Steps: the spectra, the strong modes, each other mode, the real poles, the evidence,
    // the joint fit (those strong are not added alone: the count is made exact below).
    let mut steps = Steps::new(m + 5, progress);
    steps.start(&format!(
        "refining: spectra of {l} channel(s) of {n} samples"
    ));
    let (model, scales) = binned_model(y, &means, fs, modes, real_poles);
    let penalty = bic_penalty(l, model.k());
    let real_penalty = 0.5 * (1.0 + l as f64) * (model.k() as f64).ln();
    // 1. The strong modes and real poles, then the other real poles, then the weak modes.
    steps.start(&format!(
        "refining: the strong modes in {} bins of {} frequencies",
        model.sp.bins(),
        model.k()
    ));
    let (first, weak, weak_reals) = strong_first(&model, modes, real_poles, opts)?;
    steps.set_total(steps.done() + weak.len() + 3);
    steps.start("refining: the real poles");
    let reals = add_real_poles(&model, first, real_poles, &weak_reals, real_penalty, opts)?;
    //    The real poles' evidence is weighed once here, before the weak modes, too: a
    //    spurious strong real pole left in wanders through every weak mode's fit, slowing
    //    each (on a Zener record, 2.9 s against 0.3 s for the weak modes' fits).
    let mut real_dropped = reals.dropped;
    let reals = real_pole_evidence(
        &model,
        reals.fit,
        reals.sources,
        real_poles,
        real_penalty,
        opts,
    )?;
    real_dropped.extend(reals.dropped);
    let real_sources = reals.sources;
    let with_reals = reals.model;
    let cur = with_reals.as_ref().unwrap_or(&model);
    let mut dropped = Vec::new();
    let weak_fits = WeakModes {
        modes,
        weak: &weak,
        penalty,
    };
    let fit = add_weak_modes(cur, reals.fit, &weak_fits, opts, &mut dropped, &mut steps)?;
    // 2. Each kept mode's evidence, the weakest dropped while below the penalty.
    steps.start("refining: each mode's evidence");
    let (fit, evidence) = mode_evidence(cur, fit, modes, penalty, opts, &mut dropped)?;
    // 2b. The real poles' evidence, tested the same way.
    let reals = real_pole_evidence(&model, fit, real_sources, real_poles, real_penalty, opts)?;
    real_dropped.extend(reals.dropped);
    let fit = reals.fit;
    let fitted_model = reals.model.as_ref().unwrap_or(&model);
    // 3. The chosen modes fitted once more by the joint likelihood, when asked, when the
    //    record follows the per-channel model (a record that does not, e.g. under a
    //    multisine, will not follow the joint one either) and when it has enough frequencies
    //    for the joint parameters (ten observations each, a frequency giving l² of them). If
    //    that fails the per-channel fit stands.
    let mk = fit.lambdas.len();
    let per_channel_misfit = fitted_model
        .eval(&fit.theta, mk, What::Misfit)
        .and_then(|e| e.misfit)
        .map_or(1.0, |m| m.distance());
    //    Above `joint_max` channels (the joint cost grows as l⁴) the joint likelihood is that
    //    of `joint_max` combinations of them carrying the modes; with more modes than
    //    combinations, band by band (see [`joint_by_bands`]).
    //    The joint model has no real poles: with one kept, the per-channel fit stands.
    let wanted = opts.joint && mk > 0 && fit.reals.is_empty() && per_channel_misfit <= MISFIT_LIMIT;
    steps.start("refining: the joint likelihood");
    let joint_fit = wanted
        .then(|| joint_by_bands(&model, &fit, joint_max, &scales, opts))
        .flatten();
    let joint = joint_fit.is_some();
    let est = match joint_fit {
        Some(est) => est,
        None => per_channel_estimates(fitted_model, fit, l, per_channel_misfit),
    };
    let kept = refined_modes(&est, &evidence, modes);
    let real_kept = refined_real_poles(&est, &reals.sources, &reals.evidence);
    Ok(Refinement {
        modes: kept,
        dropped,
        penalty,
        real_poles: real_kept,
        dropped_real_poles: real_dropped,
        real_pole_penalty: real_penalty,
        // S of a channel scaled by d is d² times its own: each frequency's ln S (ln det S,
        // jointly) rises by Σ ln d². Combinations are built from the channels over their own
        // noise floors, whatever their units, and need no correction.
        neg_log_likelihood: match est.combinations {
            None => est.l - model.k() as f64 * scales.iter().map(|d| 2.0 * d.ln()).sum::<f64>(),
            Some(_) => est.l,
        },
        misfit: est.misfit,
        frequencies: model.k(),
        iterations: est.iterations,
        joint,
        combinations: est.combinations,
        bands: est.bands,
    })
}

/// An error unless a record of `n` samples has enough frequencies for the Fisher information
/// of `m` modes and `reals` real poles on `l` channels to be estimated: ten per parameter.
fn check_length(n: usize, m: usize, l: usize, reals: usize) -> Result<(), SsiError> {
    let p = 2 * m + reals;
    let params = p + l * (p + 1);
    let needed = 2 * (10 * params + 1) + 2;
    if n < needed {
        return Err(SsiError::TooShortToRefine {
            samples: n,
            modes: m,
            needed,
        });
    }
    Ok(())
}

/// The model of the record `y` (less `means`, sampled at `fs` Hz), its spectra in bins sized
/// for SSI's `modes` and `real_poles`, and each channel's scale ([`equilibrated`]).
fn binned_model(
    y: &[&[f64]],
    means: &[f64],
    fs: f64,
    modes: &[Mode],
    real_poles: &[RealPoleCluster],
) -> (Model, Vec<f64>) {
    let scales = equilibrated(y, means);
    let poles: Vec<Scale> = modes
        .iter()
        .map(|md| Scale::of_pole(md.lambda, fs))
        .chain(
            real_poles
                .iter()
                .map(|r| Scale::of_pole(C64::new(r.lambda, 0.0), fs)),
        )
        .collect();
    let model = Model::new(Spectra::new(y, means, &scales, &poles), fs);
    (model, scales)
}

/// The options the refinement checks itself: no iterations would report the starts as
/// estimates; a tolerance that is not a positive number never (or always) ends a fit; a
/// real pole must be negative and finite.
fn check_refine_options(
    opts: &RefineOptions,
    real_poles: &[RealPoleCluster],
) -> Result<(), SsiError> {
    if opts.max_iterations == 0 {
        return Err(SsiError::InvalidOption {
            option: SsiOption::MaxIterations,
            value: 0.0,
        });
    }
    if !(opts.tolerance.is_finite() && opts.tolerance > 0.0) {
        return Err(SsiError::InvalidOption {
            option: SsiOption::Tolerance,
            value: opts.tolerance,
        });
    }
    if let Some(bad) = real_poles
        .iter()
        .find(|p| !(p.lambda < 0.0 && p.lambda.is_finite()))
    {
        return Err(SsiError::NotNegativeRealPole { lambda: bad.lambda });
    }
    Ok(())
}

/// The scale of each channel: a power of two that brings it to the size of the largest, when
/// their peak deviations differ by more than [`EQUILIBRATE_ABOVE`]; otherwise 1.
fn equilibrated(y: &[&[f64]], means: &[f64]) -> Vec<f64> {
    let l = y.len();
    // Channels of very different sizes (units a million apart) made the start's regressions
    // ill-conditioned, and the joint fit failed and fell back to the per-channel one. As
    // LAPACK equilibrates a matrix only when it is badly scaled, each channel is then scaled
    // by the power of two nearest the ratio of the largest channel's peak deviation to its
    // own, which leaves the poles as they are; within `EQUILIBRATE_ABOVE` of each other the
    // channels are fitted as given (scaling them anyway moved no estimate by more than 5e-9
    // of itself on the shared records, but changed the joint fit's path: 1.5 times the time
    // on the bench's three-channel record).
    // Only the likelihood's value depends on the units; it is given back in the user's.
    let peaks: Vec<f64> = y
        .iter()
        .zip(means)
        .map(|(c, m)| c.iter().fold(0.0f64, |a, v| a.max((v - m).abs())))
        .collect();
    let top = peaks.iter().copied().fold(0.0f64, f64::max);
    let low = peaks.iter().copied().fold(f64::INFINITY, f64::min);
    if top > EQUILIBRATE_ABOVE * low {
        peaks
            .iter()
            .map(|p| 2f64.powi((top / p).log2().round() as i32))
            .collect()
    } else {
        vec![1.0; l]
    }
}

/// Step 1: the strong SSI modes and real poles fitted together; the weak modes (most
/// members first) and the real poles still to add, in the order to add them.
fn strong_first(
    model: &Model,
    modes: &[Mode],
    real_poles: &[RealPoleCluster],
    opts: &RefineOptions,
) -> Result<(RealPoles, Vec<usize>, Vec<usize>), SsiError> {
    let m = modes.len();
    // 1. The strong SSI modes (at least half the largest member count) are fitted together:
    //    each then has a pole at its place from the start, and no pole has to travel to a
    //    peak left without one. The others are added one at a time, most members first, and
    //    kept when L falls by at least the penalty; two starts for each, fresh numerators and
    //    the current model with the new pole cancelled by a numerator zero (L cannot rise),
    //    the better counts.
    //    Real poles ([`refine_with_real_poles`]) are treated as the modes are, and before the
    //    weak modes: the strong ones join the strong modes' fit, the others are added next. A
    //    model without a record's real pole spends a mode on it (a pole pair at damping near 1
    //    under the real pole's low-frequency hump), which then leaves the real pole nothing
    //    to explain.
    let by_members = |a: &RealPoleCluster| a.members.len();
    let most = modes
        .iter()
        .map(|md| md.members.len())
        .chain(real_poles.iter().map(by_members))
        .max()
        .unwrap_or(0);
    let (core, mut weak): (Vec<usize>, Vec<usize>) =
        (0..m).partition(|&k| 2 * modes[k].members.len() >= most);
    weak.sort_by(|&a, &b| modes[b].members.len().cmp(&modes[a].members.len()));
    let is_strong = |i: usize| 2 * real_poles[i].members.len() >= most;
    let strong: Vec<usize> = (0..real_poles.len()).filter(|&i| is_strong(i)).collect();
    let mut by_size: Vec<usize> = (0..real_poles.len()).collect();
    by_size.sort_by(|&a, &b| by_members(&real_poles[b]).cmp(&by_members(&real_poles[a])));
    let mut weak_reals: Vec<usize> = by_size.iter().copied().filter(|&i| !is_strong(i)).collect();
    let start: Vec<C64> = core.iter().map(|&k| modes[k].lambda).collect();
    let strong_fit = (!strong.is_empty())
        .then(|| {
            let lams: Vec<f64> = strong.iter().map(|&i| real_poles[i].lambda).collect();
            let with = model.with_reals(lams.len());
            let th = with.start_with(&start, &lams)?;
            let fit = with.fit_from(th, start.len(), opts, opts.tolerance, false, None)?;
            Ok::<_, SsiError>((fit, with))
        })
        .and_then(Result::ok);
    let first = match strong_fit {
        Some((fit, with)) => RealPoles {
            model: Some(with),
            fit,
            sources: strong,
            evidence: Vec::new(),
            dropped: Vec::new(),
        },
        None => {
            // No strong real pole, or their fit failed: every real pole is added in turn.
            weak_reals = by_size;
            RealPoles {
                model: None,
                fit: model.fit(&start, opts, opts.tolerance, false)?,
                sources: Vec::new(),
                evidence: Vec::new(),
                dropped: Vec::new(),
            }
        }
    };
    Ok((first, weak, weak_reals))
}

/// The weak modes to add: the SSI modes, which of them are weak (in the order to add them),
/// and the penalty each must beat.
struct WeakModes<'a> {
    modes: &'a [Mode],
    weak: &'a [usize],
    penalty: f64,
}

/// Step 1, continued: the weak modes added one at a time to `fit`, each kept when L falls by
/// at least their penalty (when selecting), else recorded in `dropped`.
fn add_weak_modes(
    cur: &Model,
    mut fit: Fit,
    w: &WeakModes,
    opts: &RefineOptions,
    dropped: &mut Vec<DroppedMode>,
    steps: &mut Steps,
) -> Result<Fit, SsiError> {
    let (modes, penalty) = (w.modes, w.penalty);
    for &cand in w.weak {
        steps.start(&format!(
            "refining: adding the SSI mode at {:.4} Hz",
            modes[cand].frequency_hz
        ));
        let next = cur.fit_with(
            &fit,
            modes[cand].lambda,
            opts.select.then_some(penalty),
            opts,
        )?;
        let evidence = fit.l - next.l;
        if !opts.select || evidence >= penalty {
            fit = next;
        } else {
            dropped.push(DroppedMode {
                source: cand,
                frequency_hz: modes[cand].frequency_hz,
                evidence,
                fitted: None,
            });
        }
    }
    Ok(fit)
}

/// Step 2: each kept mode's evidence (the rise of L when it is removed, the other poles held
/// and the numerators refitted), and the fit once every mode left has at least `penalty`
/// (when selecting); those dropped are recorded in `dropped`.
fn mode_evidence(
    cur: &Model,
    mut fit: Fit,
    modes: &[Mode],
    penalty: f64,
    opts: &RefineOptions,
    dropped: &mut Vec<DroppedMode>,
) -> Result<(Fit, Vec<f64>), SsiError> {
    // For the decision, everything is let move from the held fit: the other poles stay at
    // their own peaks unless the removed one shared a peak with them, and then the rise is
    // small. While the weakest rise is below the penalty, that mode goes.
    let evidence = loop {
        let without: Vec<(f64, Fit)> = (0..fit.lambdas.len())
            .into_par_iter()
            .map(|k| {
                let mut rest = fit.lambdas.clone();
                rest.remove(k);
                let penalty = opts.select.then_some(penalty);
                cur.without(&fit, &rest, &fit.reals, penalty, false, opts)
            })
            .collect::<Result<_, SsiError>>()?;
        match weakest(&fit, &without) {
            Some((k, ev)) if opts.select && ev < penalty => {
                let src = nearest_mode(modes, fit.lambdas[k]);
                dropped.push(DroppedMode {
                    source: src,
                    frequency_hz: modes[src].frequency_hz,
                    evidence: ev,
                    fitted: Some(FittedPole::of(fit.lambdas[k])),
                });
                let (_, next) = without.into_iter().nth(k).expect("k < modes");
                fit = cur.fit_from(
                    next.theta,
                    next.lambdas.len(),
                    opts,
                    opts.tolerance,
                    false,
                    None,
                )?;
            }
            _ => break without.iter().map(|(held, _)| *held).collect::<Vec<f64>>(),
        }
    };
    Ok((fit, evidence))
}

#[cfg(test)]
pub(super) mod tests;

#[cfg(test)]
mod real_pole_tests;
