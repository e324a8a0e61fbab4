//! The SSI real-pole clusters tested against the record, as the modes are.

use crate::cluster::RealPoleCluster;
use crate::error::SsiError;
use crate::refine::model::scoring::Evidence;
use crate::refine::model::{Fit, Model, better};
use crate::refine::options::RefineOptions;
use crate::refine::results::DroppedRealPole;
use rayon::iter::{IntoParallelIterator, ParallelIterator};

/// What [`add_real_poles`] leaves.
pub(super) struct RealPoles {
    /// The record's model with the kept real poles; `None` when none is kept.
    pub(super) model: Option<Model>,
    /// The fit of the modes and the kept real poles.
    pub(super) fit: Fit,
    /// The SSI cluster each kept real pole started from, in the fit's order.
    pub(super) sources: Vec<usize>,
    /// Each kept real pole's evidence, in the fit's order.
    pub(super) evidence: Vec<f64>,
    pub(super) dropped: Vec<DroppedRealPole>,
}

/// Step 1b: the real poles `order` of `candidates` added in turn to the fit of the strong
/// modes and real poles `first`, each kept when it lowers L by at least `penalty` (two starts
/// each: the model with the new pole cancelled by a numerator zero, and fresh numerators).
/// No evidence yet.
pub(super) fn add_real_poles(
    model: &Model,
    first: RealPoles,
    candidates: &[RealPoleCluster],
    order: &[usize],
    penalty: f64,
    opts: &RefineOptions,
) -> Result<RealPoles, SsiError> {
    let RealPoles {
        model: mut fitted,
        mut fit,
        mut sources,
        mut dropped,
        ..
    } = first;
    let m = fit.lambdas.len();
    for &cand in order {
        let new = candidates[cand].lambda;
        let next_model = model.with_reals(fit.reals.len() + 1);
        let ev = Evidence::adding(fit.l, opts.select.then_some(penalty));
        let nested = next_model.nested_real_start(&fit, new);
        let nested = next_model.fit_from(nested, m, opts, opts.tolerance, false, ev);
        let mut reals = fit.reals.clone();
        reals.push(new);
        let fresh = next_model
            .start_with(&fit.lambdas, &reals)
            .and_then(|th| next_model.fit_from(th, m, opts, opts.tolerance, false, ev));
        let next = better(nested, fresh)?;
        let evidence = fit.l - next.l;
        if !opts.select || evidence >= penalty {
            fit = next;
            sources.push(cand);
            fitted = Some(next_model);
        } else {
            dropped.push(DroppedRealPole {
                source: cand,
                lambda: new,
                evidence,
            });
        }
    }
    Ok(RealPoles {
        model: fitted,
        fit,
        sources,
        evidence: Vec::new(),
        dropped,
    })
}

/// Step 2b: as for the modes, each real pole of `fit` (started from the clusters
/// `sources` of `candidates`)'s evidence is the rise of L when it is removed, the other poles
/// held; while the weakest rise with everything free is below `penalty`, that pole goes.
pub(super) fn real_pole_evidence(
    model: &Model,
    mut fit: Fit,
    mut sources: Vec<usize>,
    candidates: &[RealPoleCluster],
    penalty: f64,
    opts: &RefineOptions,
) -> Result<RealPoles, SsiError> {
    let m = fit.lambdas.len();
    let mut dropped = Vec::new();
    let mut fitted = (!fit.reals.is_empty()).then(|| model.with_reals(fit.reals.len()));
    let evidence = loop {
        let r = fit.reals.len();
        if r == 0 {
            break Vec::new();
        }
        let less = model.with_reals(r - 1);
        let without: Vec<(f64, Fit)> = (0..r)
            .into_par_iter()
            .map(|i| {
                let mut rest = fit.reals.clone();
                rest.remove(i);
                let penalty = opts.select.then_some(penalty);
                less.without(&fit, &fit.lambdas, &rest, penalty, true, opts)
            })
            .collect::<Result<_, SsiError>>()?;
        match weakest(&fit, &without) {
            Some((i, ev)) if opts.select && ev < penalty => {
                let source = sources.remove(i);
                dropped.push(DroppedRealPole {
                    source,
                    lambda: candidates[source].lambda,
                    evidence: ev,
                });
                let (_, next) = without.into_iter().nth(i).expect("i < real poles");
                fit = less.fit_from(next.theta, m, opts, opts.tolerance, false, None)?;
                fitted = (r > 1).then_some(less);
            }
            _ => break without.iter().map(|(held, _)| *held).collect(),
        }
    };
    Ok(RealPoles {
        model: fitted,
        fit,
        sources,
        evidence,
        dropped,
    })
}

/// Which pole's removal (`without`, from [`Model::without`]) raises `full`'s L least once
/// everything is let move, and by how much.
pub(super) fn weakest(full: &Fit, without: &[(f64, Fit)]) -> Option<(usize, f64)> {
    without
        .iter()
        .map(|(_, free)| free.l - full.l)
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(&b.1))
}

/// The BIC penalty of one mode for `l` channels and `k` frequencies: ½(2 + 2l) ln k, its
/// pole's two parameters and each channel's two numerator coefficients.
pub(super) fn bic_penalty(l: usize, k: usize) -> f64 {
    0.5 * (2.0 + 2.0 * l as f64) * (k as f64).ln()
}
