//! Each step's choice: the candidates with significant evidence tried on the test rows,
//! strongest first, and the effect to add picked by their held-out gain.

use hyst_model::Oscillator;
use rayon::prelude::*;

use super::heldout::{self, HeldOutGain, paired_gain};
use super::{Effect, Evidence, SIGNIFICANT_BIC, surface};

/// The candidate a step adds.
pub(super) struct Chosen {
    pub(super) i: usize,
    pub(super) model: Oscillator,
    pub(super) c: f64,
    pub(super) gain: Option<HeldOutGain>,
}

/// A candidate fitted to convergence: the model, its sum of squares and its outputs on the
/// test rows.
pub(super) type Converged = (Oscillator, f64, Vec<Option<Vec<f64>>>);

/// Why a candidate was not fitted to convergence.
pub(super) enum NotConverged {
    /// The fit failed (its simulation diverged).
    FitFailed,
    /// It converged to a size that is not a finding ([`plausible`]): why.
    NotAFinding(String),
}

/// A candidate fitted to convergence that passed the held-out test: its index, model, sum
/// of squares and outputs on the test rows.
pub(super) type Tried = (usize, Oscillator, f64, Vec<Option<Vec<f64>>>);

/// Pick the effect to add from the fitted candidates `evidence` (the current model's sum of
/// squares `c0`, its outputs `before` on the test rows `ys`). `converge` fits a candidate to
/// convergence and returns it with its sum of squares and test outputs. `progress` hears
/// each candidate tried.
pub(super) fn choose(
    evidence: &mut [Evidence],
    trace: Option<&surface::SurfaceFit>,
    c0: f64,
    ys: &[&[f64]],
    before: &[Option<Vec<f64>>],
    converge: impl Fn(Effect, &Oscillator) -> Result<Converged, NotConverged> + Sync,
    progress: &dyn Fn(&str),
) -> Option<Chosen> {
    let mut order: Vec<usize> = (0..evidence.len())
        .filter(|&i| evidence[i].model.is_some() && evidence[i].delta_bic < SIGNIFICANT_BIC)
        .collect();
    order.sort_by(|&a, &b| evidence[a].delta_bic.total_cmp(&evidence[b].delta_bic));
    if ys.is_empty() {
        return strongest_finding(&order, evidence, c0, &converge);
    }
    // Judge one candidate, fitted to convergence (`fitted`), on the test rows against the
    // current model's outputs: the index of the accepted one in `tried`.
    let mut tried: Vec<Tried> = Vec::new();
    let mut judge =
        |i: usize, fitted: Result<Converged, NotConverged>, ev: &mut [Evidence]| -> Option<usize> {
            let (m, c1, out) = match fitted {
                Ok(v) => v,
                Err(NotConverged::FitFailed) => return None,
                Err(NotConverged::NotAFinding(why)) => {
                    ev[i].model = None;
                    ev[i].rejected = Some(why);
                    return None;
                }
            };
            let gain = paired_gain(ys, before, &out);
            ev[i].held_out = Some(gain);
            if gain.accepts() {
                tried.push((i, m, c1, out));
                Some(tried.len() - 1)
            } else {
                ev[i].model = None;
                ev[i].rejected = Some(held_out_reason(&gain));
                None
            }
        };
    // The first of `candidates` (in order) the test rows accept. They are fitted to
    // convergence two at a time in parallel (one fit's Jacobian is one lockstep batch, on
    // one core) and judged in order, so the outcome is the sequential one; the second of a
    // pair is wasted only when the first is accepted.
    let mut first_accepted = |candidates: &[usize], ev: &mut [Evidence]| -> Option<usize> {
        for pair in candidates.chunks(2) {
            let todo: Vec<(usize, Effect, Oscillator)> = pair
                .iter()
                .filter_map(|&i| ev[i].model.map(|m| (i, ev[i].effect, m)))
                .collect();
            for (_, e, _) in &todo {
                progress(&format!("trying {} on the test rows", e.name()));
            }
            let fitted: Vec<(usize, Result<Converged, NotConverged>)> = todo
                .into_par_iter()
                .map(|(i, e, m)| (i, converge(e, &m)))
                .collect();
            for (i, f) in fitted {
                if let Some(k) = judge(i, f, ev) {
                    return Some(k);
                }
            }
        }
        None
    };
    let (named_order, surface_order): (Vec<usize>, Vec<usize>) =
        order.iter().partition(|&&i| evidence[i].effect.is_named());
    let named = first_accepted(&named_order, evidence);
    // The surface is for shapes no named effect has: tried when no named effect pays, or
    // when the missing force's strongest group is one none of them has (damping that
    // depends on the displacement, or is even in the velocity). A shape a named effect has
    // is left to it, one effect per step, so that two effects at once are named one after
    // the other (on the Silverbox the surface, with the cubic term and three small ones,
    // beat the cubic spring alone by 7 % on the test rows at the first step, where the
    // strongest group is the odd stiffness the cubic spring has).
    let uncovered = trace.is_some_and(|f| {
        f.present()
            .next()
            .is_some_and(|g| matches!(g.group, surface::Group::Mixed | surface::Group::EvenDamping))
    });
    let surface = if named.is_none() || uncovered {
        first_accepted(&surface_order[..surface_order.len().min(1)], evidence)
    } else {
        if let Some(&i) = surface_order.first() {
            evidence[i].rejected = Some(
                "not tried: a named effect pays, and the missing force has no shape outside the named ones"
                    .into(),
            );
            evidence[i].model = None;
        }
        None
    };
    let pick = prefer(evidence, &tried, ys, named, surface)?;
    let (i, m, c1, _) = tried.swap_remove(pick);
    Some(Chosen {
        i,
        model: m,
        c: c1,
        gain: evidence[i].held_out,
    })
}

/// Of the accepted named effect `named` and surface `surface` (indices into `tried`), the
/// one to add: the surface only when it beats the named effect on the test rows `ys`; the
/// other's evidence says why it was not.
pub(super) fn prefer(
    evidence: &mut [Evidence],
    tried: &[Tried],
    ys: &[&[f64]],
    named: Option<usize>,
    surface: Option<usize>,
) -> Option<usize> {
    match (named, surface) {
        (Some(a), Some(b)) => {
            // The surface only when it beats the named effect on the test rows.
            let g = paired_gain(ys, &tried[a].3, &tried[b].3);
            if g.accepts() {
                let why = format!(
                    "the missing force's surface does better on the test rows ({})",
                    held_out_reason(&g)
                );
                let ia = tried[a].0;
                evidence[ia].rejected = Some(why);
                Some(b)
            } else {
                let ib = tried[b].0;
                evidence[ib].rejected = Some(format!(
                    "no better than {} on the test rows ({})",
                    evidence[tried[a].0].effect.name(),
                    held_out_reason(&g)
                ));
                Some(a)
            }
        }
        (Some(a), None) => Some(a),
        (None, Some(b)) => Some(b),
        (None, None) => None,
    }
}

/// Without test rows: the strongest candidate of `order` (by ΔBIC) that is a finding, fitted
/// to convergence (as fitted by the diagnosis when that fails).
pub(super) fn strongest_finding(
    order: &[usize],
    evidence: &mut [Evidence],
    c0: f64,
    converge: &dyn Fn(Effect, &Oscillator) -> Result<Converged, NotConverged>,
) -> Option<Chosen> {
    for &i in order {
        let Some(m) = evidence[i].model else { continue };
        let (model, c) = match converge(evidence[i].effect, &m) {
            Ok((m, c1, _)) => (m, c1),
            Err(NotConverged::NotAFinding(why)) => {
                evidence[i].model = None;
                evidence[i].rejected = Some(why);
                continue;
            }
            Err(NotConverged::FitFailed) => (m, c0 * (1.0 - evidence[i].variance_explained)),
        };
        return Some(Chosen {
            i,
            model,
            c,
            gain: None,
        });
    }
    None
}

/// Why a candidate's held-out gain does not add it, in words.
pub(super) fn held_out_reason(g: &HeldOutGain) -> String {
    if g.mse_after.is_infinite() {
        return "held out: its simulation diverges on a test range".into();
    }
    format!(
        "held out: mean squared error {:+.2} % (p = {:.3} over {} blocks; adding needs p < {} and a drop of at least {} %)",
        -100.0 * g.relative_gain(),
        g.p_value,
        g.blocks,
        heldout::SIGNIFICANCE,
        100.0 * heldout::MIN_RELATIVE_GAIN
    )
}
