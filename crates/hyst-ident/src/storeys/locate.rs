//! Where the element is: every candidate cross-validated over the records' halves, the
//! storey of best held-out score, and the test of whether there is an element at all.

use super::error::StoreyError;
use super::fitting::{Halves, cross_validate};
use super::model::Layout;
use super::setup::{Setup, start_for};
use super::types::{ElementEvidence, StoreyCandidate, StoreyOptions, StoreyProgress};
use crate::IdentError;
use hyst_sim::building::ShearBuilding;

/// Each candidate's scores (none first, then the storeys) and its first fit, `None` where
/// its fit failed (the reason in its candidate).
#[allow(clippy::type_complexity)]
pub(super) fn locate(
    setup: &Setup,
    halves: &Halves<'_>,
    linear: (&ShearBuilding, &[f64]),
    records: &[Vec<Vec<f64>>],
    opts: &StoreyOptions,
    progress: &(dyn Fn(StoreyProgress<'_>) + Sync),
) -> Result<(Vec<StoreyCandidate>, Vec<Option<(Layout, Vec<f64>)>>), IdentError> {
    let candidates: Vec<Option<usize>> = std::iter::once(None)
        .chain(
            opts.candidates
                .clone()
                .unwrap_or_else(|| (0..setup.floors).collect())
                .into_iter()
                .map(Some),
        )
        .collect();
    let mut scored = Vec::new();
    let mut fits = Vec::new();
    for storey in candidates {
        let layout = Layout {
            floors: setup.floors,
            levels: setup.levels,
            storey,
            folded: setup.folded,
        };
        let name = match storey {
            None => "no element".to_string(),
            Some(s) => format!("storey {}", s + 1),
        };
        let theta0 = start_for(setup, &layout, linear.0, linear.1, records, opts)?;
        match cross_validate(setup, &layout, &theta0, halves, opts, &name, progress) {
            Ok((held_out, fitted, theta)) => {
                progress(StoreyProgress {
                    stage: &format!("{name}: held-out score {held_out:.1}"),
                    iteration: 0,
                    cost: fitted,
                });
                scored.push(StoreyCandidate {
                    storey,
                    held_out,
                    fitted,
                    failed: None,
                });
                fits.push(Some((layout, theta)));
            }
            Err(e) => {
                scored.push(StoreyCandidate {
                    storey,
                    held_out: f64::INFINITY,
                    fitted: f64::NAN,
                    failed: Some(e.to_string()),
                });
                fits.push(None);
            }
        }
    }
    Ok((scored, fits))
}

/// The candidate to report (its index in `scored`) and the evidence for an element: the
/// element candidate of best held-out score when its fits beat the linear structure's by
/// more than chance ([`ElementEvidence`]), else the linear structure.
pub(super) fn choose(
    scored: &[StoreyCandidate],
    fits: &[Option<(Layout, Vec<f64>)>],
) -> Result<(usize, Option<ElementEvidence>), StoreyError> {
    let fitted = |i: &usize| fits[*i].is_some();
    let none = (0..scored.len())
        .filter(fitted)
        .find(|&i| scored[i].storey.is_none());
    let element = (0..scored.len())
        .filter(fitted)
        .filter(|&i| scored[i].storey.is_some())
        .min_by(|&i, &j| scored[i].held_out.total_cmp(&scored[j].held_out));
    use statrs::distribution::{ChiSquared, ContinuousCDF};
    // The 99 % point of χ² with 6 degrees of freedom (16.81).
    let chi2_6_99 = ChiSquared::new(6.0).map_or(f64::NAN, |d| d.inverse_cdf(0.99));
    let evidence = match (none, element) {
        (Some(n), Some(e)) => scored[e].storey.map(|storey| ElementEvidence {
            storey,
            improvement: scored[n].fitted - scored[e].fitted,
            threshold: 2.0 * chi2_6_99,
        }),
        _ => None,
    };
    let pick = match (none, element, evidence) {
        (Some(n), _, Some(ev)) if ev.improvement <= ev.threshold => Some(n),
        (_, Some(e), _) => Some(e),
        (Some(n), None, _) => Some(n),
        (None, None, _) => None,
    };
    pick.map(|i| (i, evidence))
        .ok_or(StoreyError::NoCandidateFitted {
            reasons: scored.iter().filter_map(|c| c.failed.clone()).collect(),
        })
}
