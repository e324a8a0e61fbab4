//! The global estimation: every setup's output correlations against the references, scaled
//! to one excitation level and stacked into one correlation sequence over all the DOFs, and
//! SSI run once on it (pre-identification merging, as PreGER does).
//!
//! Setup $s$'s correlations $R^{(s)}_k$ (its channels against the common references, means
//! removed) are scaled by $c_s = \big(\sum_k \lVert R^{(1)}_{k,RR}\rVert^2 /
//! \sum_k \lVert R^{(s)}_{k,RR}\rVert^2\big)^{1/2}$, the ratio of the first setup's
//! reference-by-reference correlations to its own: under ambient excitation of one spatial
//! pattern, the setups differ by that level alone. The stacked $R_k$ has the references' rows
//! (the mean of the setups' scaled ones) and every other DOF's (its setup's scaled ones). Its
//! modes' shapes are one vector over all the DOFs, in the channels' units, then made
//! displacements as [`merge`](super::merge) does. SSI gives no standard errors.

use super::{MergeError, MergedMode, MergedModes, SetupChannel, same_dof};
use crate::{Complex64 as C64, SsiError, SsiOptions, corr, identify_from_correlations};

/// One setup's record for the global estimation.
#[derive(Debug, Clone)]
pub struct SetupRecord<'a> {
    /// Its name.
    pub name: String,
    /// Its channels.
    pub channels: Vec<SetupChannel>,
    /// Its samples, one slice per channel, at the rate given to [`merge_global`].
    pub y: Vec<&'a [f64]>,
}

/// Why the global estimation failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum GlobalError {
    /// The setups cannot be merged (no common reference, a bad channel).
    #[error(transparent)]
    Merge(#[from] MergeError),
    /// SSI on the stacked correlations failed.
    #[error("SSI on all setups' correlations: {0}")]
    Ssi(#[from] SsiError),
    /// A setup's reference correlations are zero: its level cannot be matched.
    #[error("setup `{0}`: its references' correlations are zero")]
    SilentReferences(String),
}

/// SSI once on all `setups`' correlations, sampled at `fs` Hz, with `block_rows` and
/// `opts`; its modes on the merged DOFs. Each setup's correlations against the common
/// references are scaled to the first setup's level by their reference-by-reference energy
/// and stacked over every DOF (the references' rows averaged); the shapes are made
/// displacements as [`merge`](super::merge) does. No standard errors.
pub fn merge_global(
    setups: &[SetupRecord<'_>],
    fs: f64,
    block_rows: usize,
    opts: &SsiOptions,
) -> Result<MergedModes, GlobalError> {
    let described: Vec<(String, Vec<SetupChannel>)> = setups
        .iter()
        .map(|s| (s.name.clone(), s.channels.clone()))
        .collect();
    let mut notes = Vec::new();
    let dofs = super::dofs_of(&described, &mut notes)?;
    let references: Vec<usize> = (0..dofs.len()).filter(|&d| dofs[d].reference).collect();
    let (l, r) = (dofs.len(), references.len());
    let corr = stack(setups, &dofs, &references, 2 * block_rows)?;
    let ssi = identify_from_correlations(&corr, fs, block_rows, opts)?;
    // Each DOF's unit and gain, from a setup that measures it.
    let unit: Vec<(i32, f64)> = dofs
        .iter()
        .map(|d| {
            setups
                .iter()
                .flat_map(|s| &s.channels)
                .find(|ch| same_dof(&ch.node, ch.direction, d))
                .map_or((0, 1.0), |ch| (ch.quantity.power(), ch.gain))
        })
        .collect();
    let modes = ssi
        .modes
        .iter()
        .map(|m| {
            let raw: Vec<C64> = m
                .shape
                .iter()
                .zip(&unit)
                .map(|(v, &(p, g))| v / (g * m.lambda.powi(p)))
                .collect();
            let top = raw
                .iter()
                .copied()
                .max_by(|a, b| a.norm().total_cmp(&b.norm()))
                .unwrap_or(C64::new(1.0, 0.0));
            let shape: Vec<Option<C64>> = raw.iter().map(|v| Some(v / top)).collect();
            let shape_se = vec![None; l];
            let nodes = super::nodes::node_motions(&dofs, &shape, &shape_se);
            MergedMode {
                frequency_hz: m.frequency_hz,
                frequency_se_hz: None,
                damping_ratio: m.damping_ratio,
                damping_se: None,
                scatter_ratio: None,
                // Every setup's correlations made each mode: none is one setup's.
                seen_in: Vec::new(),
                shape,
                shape_se,
                nodes,
            }
        })
        .collect();
    notes.push(format!(
        "global estimation: SSI once on all {} setups' correlations ({} DOFs, {} references, {block_rows} block rows); no standard errors",
        setups.len(),
        l,
        r
    ));
    Ok(MergedModes {
        setups: setups.iter().map(|s| s.name.clone()).collect(),
        dofs,
        modes,
        notes,
    })
}

/// Every setup's correlations against the references, each setup scaled to the first's
/// level, stacked over the `dofs` (the rows a DOF gets from several setups averaged).
fn stack(
    setups: &[SetupRecord<'_>],
    dofs: &[super::MergedDof],
    references: &[usize],
    lags: usize,
) -> Result<crate::Correlations, GlobalError> {
    let l = dofs.len();
    let r = references.len();
    let mut stacked = vec![vec![0.0; l * r]; lags + 1];
    let mut counts = vec![0usize; l];
    let mut anchor_energy = None;
    for s in setups {
        let at = |d: usize| {
            s.channels
                .iter()
                .position(|ch| same_dof(&ch.node, ch.direction, &dofs[d]))
        };
        let refs: Vec<usize> = references.iter().filter_map(|&d| at(d)).collect();
        let centred: Vec<Vec<f64>> =
            s.y.iter()
                .map(|c| {
                    let m = c.iter().sum::<f64>() / c.len().max(1) as f64;
                    c.iter().map(|v| v - m).collect()
                })
                .collect();
        let views: Vec<&[f64]> = centred.iter().map(Vec::as_slice).collect();
        let rk = corr::estimate(&views, &refs, lags);
        let nc = s.channels.len();
        let energy: f64 =
            rk.r.iter()
                .map(|m| {
                    refs.iter()
                        .enumerate()
                        .map(|(b, _)| refs.iter().map(|&a| m[a + b * nc].powi(2)).sum::<f64>())
                        .sum::<f64>()
                })
                .sum();
        if !(energy > 0.0 && energy.is_finite()) {
            return Err(GlobalError::SilentReferences(s.name.clone()));
        }
        let scale = (anchor_energy.get_or_insert(energy).to_owned() / energy).sqrt();
        for (d, count) in counts.iter_mut().enumerate() {
            let Some(c) = at(d) else { continue };
            *count += 1;
            for (k, m) in rk.r.iter().enumerate() {
                for b in 0..r {
                    stacked[k][d + b * l] += scale * m[c + b * nc];
                }
            }
        }
    }
    for m in &mut stacked {
        for b in 0..r {
            for (d, &count) in counts.iter().enumerate() {
                m[d + b * l] /= count.max(1) as f64;
            }
        }
    }
    Ok(crate::Correlations {
        channels: l,
        references: r,
        r: stacked,
    })
}
