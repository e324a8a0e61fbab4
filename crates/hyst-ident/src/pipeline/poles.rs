//! Step 3: the oscillating pair, the real pole and the damping guess chosen from SSI's poles.

use crate::{DampingGuess, IdentError, IdentOptions, Prepared};
use covssi::{Complex64, RealPoleCluster, SsiResult, Stability};

/// The poles the models are built from.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SelectedPoles {
    /// The oscillating pair (Im > 0), rad/s: the mean of its cluster, or, when the record
    /// follows the stationary model, the pair refined by maximum likelihood together with
    /// the real pole (a note says so).
    pub pair: Complex64,
    /// Every pole of that cluster (one per model order).
    pub pair_cluster: Vec<Complex64>,
    /// The real pole, if one was found (rad/s): SSI's, or refined with the pair.
    pub real: Option<f64>,
    /// Whether the pair and the real pole are the refined ones (the record follows the
    /// stationary model).
    pub refined: bool,
    /// Viscous damping guess c (N s/m).
    pub c: f64,
    /// Where c came from.
    pub c_source: String,
    /// Remarks (fallbacks taken).
    pub notes: Vec<String>,
}

/// Step 3: choose the pair, the real pole and c.
pub fn select_poles(
    ssi: &SsiResult,
    p: &Prepared,
    opts: &IdentOptions,
) -> Result<SelectedPoles, IdentError> {
    let mut notes = Vec::new();
    let near = |f: f64| (f - p.dominant_hz).abs() / p.dominant_hz;
    let mode = ssi
        .modes
        .iter()
        .filter(|m| near(m.frequency_hz) < 0.3)
        .max_by(|a, b| {
            a.members
                .len()
                .cmp(&b.members.len())
                .then(near(b.frequency_hz).total_cmp(&near(a.frequency_hz)))
        })
        .ok_or(IdentError::NoStablePair {
            dominant_hz: p.dominant_hz,
        })?;
    let (ssi_real, real_candidates) = real_pole(ssi, &mut notes);
    let refined = check_support(mode, &real_candidates, p, &mut notes)?;
    let (pair, real, refined) = match refined {
        Some((pair, real)) => (pair, Some(real), true),
        None => (mode.lambda, ssi_real, false),
    };
    let pair_cluster: Vec<Complex64> = mode
        .members
        .iter()
        .filter_map(|&(order, idx)| {
            ssi.diagram
                .orders
                .iter()
                .find(|o| o.order == order)
                .map(|o| o.poles[idx].lambda)
        })
        .collect();
    let (c, c_source) = match opts.damping_guess {
        DampingGuess::Value(c) => (c, "given".to_string()),
        DampingGuess::LowDampingCluster | DampingGuess::ZenerSpectrum => {
            // Poles at least stable in frequency, within 10 % of the pair's frequency, damped
            // less than half as much as the pair.
            let f0 = mode.frequency_hz;
            let mut re: Vec<f64> = ssi
                .diagram
                .orders
                .iter()
                .flat_map(|o| o.poles.iter())
                .filter(|q| {
                    matches!(q.status, covssi::PoleStatus::Stable(s) if s != Stability::Real)
                        && (q.frequency_hz - f0).abs() < 0.1 * f0
                        && q.damping_ratio < 0.5 * mode.damping_ratio
                })
                .map(|q| q.lambda.re)
                .collect();
            if re.len() >= 3 {
                re.sort_by(f64::total_cmp);
                let med = re[re.len() / 2];
                (
                    -2.0 * opts.mass * med,
                    format!(
                        "c = −2m·Re λ of a low-damping cluster: {} poles, median Re λ = {med:.3} rad/s",
                        re.len()
                    ),
                )
            } else {
                notes.push("no low-damping cluster near the pair: c = 0".to_string());
                (0.0, "none found (c = 0)".to_string())
            }
        }
    };
    Ok(SelectedPoles {
        pair,
        pair_cluster,
        real,
        refined,
        c,
        c_source,
        notes,
    })
}

/// SSI's real pole (the largest stable real cluster, else the median of all stable real
/// poles when there are at least three), and the clusters the refinement is to test: SSI's,
/// or the median as a cluster of its own.
pub(crate) fn real_pole(
    ssi: &SsiResult,
    notes: &mut Vec<String>,
) -> (Option<f64>, Vec<RealPoleCluster>) {
    if let Some(r) = ssi.real_poles.iter().max_by_key(|r| r.members.len()) {
        return (Some(r.lambda), ssi.real_poles.clone());
    }
    let mut all: Vec<(f64, (usize, usize))> = ssi
        .diagram
        .orders
        .iter()
        .flat_map(|o| {
            o.poles
                .iter()
                .enumerate()
                .map(move |(i, q)| (o.order, i, q))
        })
        .filter(|(_, _, q)| q.status == covssi::PoleStatus::Stable(Stability::Real))
        .map(|(order, i, q)| (q.lambda.re, (order, i)))
        .collect();
    if all.len() >= 3 {
        all.sort_by(|a, b| a.0.total_cmp(&b.0));
        notes.push(format!(
            "no cluster of stable real poles; using the median of {} stable real poles",
            all.len()
        ));
        let median = all[all.len() / 2].0;
        let cluster = RealPoleCluster {
            lambda: median,
            lambda_std: 0.0,
            members: all.iter().map(|a| a.1).collect(),
        };
        (Some(median), vec![cluster])
    } else {
        notes.push(
            "no stable real pole found: the Zener and Bouc-Wen models fall back to the linear model"
                .to_string(),
        );
        (None, Vec::new())
    }
}

/// Whether the record supports the pair: a stabilization diagram can hold a stable cluster
/// that is a draw of the noise (white noise gives one now and then), and every model would
/// then be built on it. The pair is fitted to the whole record by maximum likelihood
/// ([`covssi::refine()`], one mode) and kept when removing it raises the negative
/// log-likelihood by at least the BIC penalty of a mode; otherwise it is an error when the
/// record follows the model without the pair (misfit within
/// [`covssi::refine::MISFIT_LIMIT`]). When it does not (a free decay, a record with little
/// noise: the stationary model does not apply), or the test cannot run (a record too short
/// for it), a note says so and the pair is kept.
///
/// When the pair is kept and the record follows its model, the pair is fitted once more
/// with the real-pole clusters `reals` ([`covssi::refine_with_real_poles`]); if the record
/// follows that model too and it keeps the pair and a real pole, their refined values are
/// returned (the real pole with the most evidence), to be used in place of SSI's. SSI sees
/// the record only through its correlations: on Zener records under white noise the
/// refined poles are several times closer (`crates/hyst-ident/tests/integration/zener_real_pole.rs`). Records that do not
/// follow the model (a multisine's line spectrum) are not refitted.
pub(crate) fn check_support(
    mode: &covssi::Mode,
    reals: &[RealPoleCluster],
    p: &Prepared,
    notes: &mut Vec<String>,
) -> Result<Option<(Complex64, f64)>, IdentError> {
    let opts = covssi::RefineOptions {
        joint: false,
        ..covssi::RefineOptions::default()
    };
    let pair = std::slice::from_ref(mode);
    match covssi::refine(&[&p.y], p.fs, pair, &opts) {
        Ok(r) if r.modes.is_empty() => {
            let evidence = r.dropped.last().map_or(0.0, |d| d.evidence);
            if r.misfit <= covssi::refine::MISFIT_LIMIT {
                // The record follows a model without the pair: it shows no resonance.
                Err(IdentError::PairNotSupported {
                    frequency_hz: mode.frequency_hz,
                    evidence,
                    penalty: r.penalty,
                    misfit: r.misfit,
                })
            } else {
                // Nor does it follow the model without the pair (a free decay, a record with
                // little noise, a non-random excitation): the test says nothing.
                notes.push(format!(
                    "the pair's support by the record could not be tested: its evidence ({evidence:.1}) is below the penalty ({:.1}), but the record does not follow the stationary model without it either (misfit {:.3}); the pair is kept",
                    r.penalty, r.misfit
                ));
                Ok(None)
            }
        }
        Ok(r) if r.misfit <= covssi::refine::MISFIT_LIMIT && !reals.is_empty() => {
            let Ok(r) = covssi::refine_with_real_poles(&[&p.y], p.fs, pair, reals, &opts) else {
                return Ok(None);
            };
            let real = r
                .real_poles
                .iter()
                .max_by(|a, b| a.evidence.total_cmp(&b.evidence));
            match (r.modes.first(), real) {
                (Some(m), Some(q)) if r.misfit <= covssi::refine::MISFIT_LIMIT => {
                    notes.push(format!(
                        "pair and real pole refined by maximum likelihood on the record (misfit {:.3}): {:.3} (SSI {:.3}) and {:.3} rad/s",
                        r.misfit, m.lambda, mode.lambda, q.lambda
                    ));
                    Ok(Some((m.lambda, q.lambda)))
                }
                _ => Ok(None),
            }
        }
        Ok(_) => Ok(None),
        Err(e) => {
            notes.push(format!(
                "the pair's support by the record could not be tested: {e}"
            ));
            Ok(None)
        }
    }
}
