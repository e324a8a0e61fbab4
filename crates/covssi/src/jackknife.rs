//! Standard errors of SSI's modes by the delete-one-block jackknife.
//!
//! SSI's modes ([`crate::Mode`]) carry the spread of their poles over model orders, which is
//! not their error: the orders all read the same record. The refinement's errors
//! ([`crate::refine()`]) hold only where the record follows its model. This module gives SSI's
//! modes errors of their own, from the record's variability alone:
//!
//! 1. The record is cut into $B$ blocks; each block's correlation sums
//!    $S_{b,k} = \sum_{n\in b} y(n+k)\,y_{\text{ref}}(n)^\top$ (about the record's means) and
//!    counts $N_{b,k}$ are formed once.
//! 2. Replicate $b$ leaves block $b$ out: $\hat R^{(-b)}_k = \sum_{c\ne b} S_{c,k} /
//!    \sum_{c\ne b} N_{c,k}$, and SSI is run on it with the record's block rows and largest
//!    order, so that each replicate is the estimator the record's modes came from. Its
//!    Toeplitz matrix differs little from the record's, so its leading singular vectors are
//!    found by subspace iteration from the record's (a few sweeps, each accepted only when
//!    every triplet up to the largest order has a residual within $10^{-12}\sigma_1$: the
//!    SVD of a matrix within about that of the replicate's), the full SVD where that does not
//!    converge.
//! 3. Each of the record's modes is matched to the replicate's mode nearest its pole (within
//!    [`FREQUENCY_TOLERANCE`] in frequency and a MAC of at least [`MIN_MAC`]); the
//!    replicate's shape is scaled so that the entry the mode's shape has as 1 is 1.
//! 4. For each quantity $\theta$ (frequency, damping ratio, each shape entry) over the $B'$
//!    replicates that found the mode, the jackknife variance
//!    $\widehat{\operatorname{var}}\,\theta = \frac{B'-1}{B'}\sum_b |\theta_{(b)}-\bar\theta|^2$.
//!
//! Blocks much longer than the correlations' lags keep each replicate's estimate close to the
//! record's; a block shorter than a mode's decay makes blocks' estimates depend on each other
//! and the jackknife read low, so blocks are as long as [`MIN_BLOCK_LAGS`] times the lags at
//! least (fewer blocks on a short record, none below [`MIN_BLOCKS`]). A mode found by fewer
//! than [`MIN_FOUND`] of the replicates gets no error.

use crate::corr::Correlations;
use crate::identify::{Run, SsiResult, identify_with_basis};
use crate::linalg::{C64, Dense};
use crate::{SsiError, SsiOptions, mac};

/// Relative frequency difference within which a replicate's mode may be the record's.
pub const FREQUENCY_TOLERANCE: f64 = 0.02;
/// The least MAC between a replicate's mode and the record's.
pub const MIN_MAC: f64 = 0.8;
/// Each block holds at least this many times the correlations' largest lag.
pub const MIN_BLOCK_LAGS: usize = 4;
/// The fewest blocks a jackknife is made of.
pub const MIN_BLOCKS: usize = 5;
/// The fewest samples the jackknife is made on with SSI's lag of `block_rows` block rows:
/// [`MIN_BLOCKS`] blocks of [`MIN_BLOCK_LAGS`] times the largest lag.
pub(crate) fn samples_needed(block_rows: usize) -> usize {
    MIN_BLOCKS * MIN_BLOCK_LAGS * 2 * block_rows
}

/// The least share of replicates that must find a mode for it to get an error.
pub const MIN_FOUND: f64 = 0.8;

/// One mode's jackknife standard errors.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ModeErrors {
    /// Natural frequency's (Hz).
    pub frequency_se_hz: f64,
    /// Damping ratio's.
    pub damping_se: f64,
    /// Each shape entry's, √E|δ|² (0 for the entry scaled to 1).
    pub shape_se: Vec<f64>,
    /// How many replicates found the mode.
    pub replicates: usize,
}

/// The jackknife's result: one entry per mode of the record's [`SsiResult`].
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SsiErrors {
    /// Blocks the record was cut into.
    pub blocks: usize,
    /// Each mode's errors, `None` where too few replicates found it.
    pub modes: Vec<Option<ModeErrors>>,
    /// How many replicates found each mode (of those SSI could be run on, at most
    /// `blocks`): a structural mode is found in nearly every replicate, each of which holds
    /// all but one block of the record.
    #[cfg_attr(feature = "serde", serde(default))]
    pub found: Vec<usize>,
}

/// Jackknife errors of `ssi`'s modes, SSI having been run on `y` (centred about `means`) at
/// `fs` Hz with `opts` and reference channels `refs`, its Toeplitz matrix's leading left
/// singular vectors `basis` (each replicate's SVD starts from them); at most `blocks` blocks.
/// `None` when the record is too short for [`MIN_BLOCKS`] blocks of [`MIN_BLOCK_LAGS`] lags.
pub(crate) fn ssi_errors(
    y: &[&[f64]],
    fs: f64,
    (refs, means): (&[usize], &[f64]),
    (ssi, basis): (&SsiResult, &Dense),
    opts: &SsiOptions,
    blocks: usize,
) -> Result<Option<SsiErrors>, SsiError> {
    let n = y.first().map_or(0, |c| c.len());
    let lags = 2 * ssi.block_rows;
    let blocks = blocks.min(n / (MIN_BLOCK_LAGS * lags).max(1));
    if n < samples_needed(ssi.block_rows) || blocks < MIN_BLOCKS || ssi.modes.is_empty() {
        return Ok(None);
    }
    let sums = block_sums(y, (refs, means), lags, blocks);
    let max_order = ssi.diagram.orders.last().map_or(0, |o| o.order);
    let opts = SsiOptions {
        max_order: Some(max_order),
        ..opts.clone()
    };
    use rayon::prelude::*;
    // A replicate SSI cannot be run on (its Toeplitz matrix of lower rank than the record's
    // largest order) finds no mode: it counts against each mode's share, it does not fail
    // the analysis.
    let replicates: Vec<SsiResult> = (0..blocks)
        .into_par_iter()
        .filter_map(|b| {
            let corr = leave_out(&sums, b);
            let near = (max_order, Some(basis), Run::Replicate);
            identify_with_basis(&corr, fs, ssi.block_rows, &opts, near, &|_| {})
                .ok()
                .map(|(r, _)| r)
        })
        .collect();
    let (found, modes) = ssi
        .modes
        .iter()
        .map(|m| mode_errors(m, &replicates, blocks))
        .unzip();
    Ok(Some(SsiErrors {
        blocks,
        modes,
        found,
    }))
}

/// Each block's correlation sums and pair counts per lag.
struct BlockSums {
    /// `sums[b]`: block b's $S_{b,k}$ as [`Correlations`] (sums, not means).
    sums: Vec<Correlations>,
    /// `counts[b][k]`: pairs block b adds at lag k.
    counts: Vec<Vec<f64>>,
    /// The record's sums, all blocks' together (each replicate takes one block off them).
    total: Correlations,
    /// The record's pair counts per lag.
    total_counts: Vec<f64>,
}

/// The correlation sums of each of `blocks` equal stretches of `y` (the last takes the rest).
/// A block's pairs $(n+k, n)$ are those whose earlier sample $n$ lies in it, so the blocks'
/// sums add up to the record's.
fn block_sums(
    y: &[&[f64]],
    (refs, means): (&[usize], &[f64]),
    lags: usize,
    blocks: usize,
) -> BlockSums {
    let n = y.first().map_or(0, |c| c.len());
    let per = n / blocks;
    let (sums, counts): (Vec<Correlations>, Vec<Vec<f64>>) = (0..blocks)
        .map(|b| {
            let start = b * per;
            let end = if b + 1 == blocks { n } else { (b + 1) * per };
            // The block and the samples its pairs reach past it.
            let reach = (end + lags - 1).min(n);
            let views: Vec<&[f64]> = y.iter().map(|c| &c[start..reach]).collect();
            let mut corr = crate::corr::estimate_centred(&views, refs, lags, means);
            let len = reach - start;
            // The estimator's mean over len − k pairs back to a sum; then the pairs whose
            // earlier sample is at or past `end` (the next block's) taken off.
            for (k, rk) in corr.r.iter_mut().enumerate() {
                let pairs = len.saturating_sub(k) as f64;
                rk.iter_mut().for_each(|v| *v *= pairs);
                for t in end..reach.saturating_sub(k) {
                    for (bi, &rf) in refs.iter().enumerate() {
                        let yr = y[rf][t] - means[rf];
                        for (a, ch) in y.iter().enumerate() {
                            rk[a + bi * y.len()] -= (ch[t + k] - means[a]) * yr;
                        }
                    }
                }
            }
            let count: Vec<f64> = (0..lags)
                .map(|k| (end - start).min(n.saturating_sub(k).saturating_sub(start)) as f64)
                .collect();
            (corr, count)
        })
        .unzip();
    let mut total = sums[0].clone();
    for block in &sums[1..] {
        for (tk, bk) in total.r.iter_mut().zip(&block.r) {
            tk.iter_mut().zip(bk).for_each(|(t, v)| *t += v);
        }
    }
    let total_counts = (0..lags)
        .map(|k| counts.iter().map(|c| c[k]).sum())
        .collect();
    BlockSums {
        sums,
        counts,
        total,
        total_counts,
    }
}

/// The record's correlations without block `b`'s pairs.
fn leave_out(s: &BlockSums, b: usize) -> Correlations {
    let r = s
        .total
        .r
        .iter()
        .zip(&s.sums[b].r)
        .enumerate()
        .map(|(k, (tk, bk))| {
            let count = s.total_counts[k] - s.counts[b][k];
            tk.iter().zip(bk).map(|(t, v)| (t - v) / count).collect()
        })
        .collect();
    Correlations {
        channels: s.total.channels,
        references: s.total.references,
        r,
    }
}

/// How many replicates found mode `m`, and its jackknife errors over them (`None` when
/// fewer than [`MIN_FOUND`] of the `blocks` did).
fn mode_errors(
    m: &crate::Mode,
    replicates: &[SsiResult],
    blocks: usize,
) -> (usize, Option<ModeErrors>) {
    let Some(one) = m
        .shape
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.norm_sqr().total_cmp(&b.1.norm_sqr()))
        .map(|(j, _)| j)
    else {
        return (0, None);
    };
    let found: Vec<(f64, f64, Vec<C64>)> = replicates
        .iter()
        .filter_map(|rep| {
            let near = rep
                .modes
                .iter()
                .filter(|r| {
                    (r.frequency_hz - m.frequency_hz).abs() <= FREQUENCY_TOLERANCE * m.frequency_hz
                        && mac(&r.shape, &m.shape) >= MIN_MAC
                })
                .min_by(|a, b| {
                    (a.lambda - m.lambda)
                        .norm()
                        .total_cmp(&(b.lambda - m.lambda).norm())
                })?;
            let scale = near.shape[one];
            (scale.norm() > 0.0).then(|| {
                (
                    near.frequency_hz,
                    near.damping_ratio,
                    near.shape.iter().map(|v| v / scale).collect(),
                )
            })
        })
        .collect();
    let count = found.len();
    if (count as f64) < MIN_FOUND * blocks as f64 || count < 2 {
        return (count, None);
    }
    let spread = |values: &[C64]| -> f64 {
        let mean: C64 = values.iter().sum::<C64>() / count as f64;
        let ss: f64 = values.iter().map(|v| (v - mean).norm_sqr()).sum();
        ((count - 1) as f64 / count as f64 * ss).sqrt()
    };
    let real =
        |values: Vec<f64>| -> Vec<C64> { values.into_iter().map(|v| C64::new(v, 0.0)).collect() };
    let errors = ModeErrors {
        frequency_se_hz: spread(&real(found.iter().map(|r| r.0).collect())),
        damping_se: spread(&real(found.iter().map(|r| r.1).collect())),
        shape_se: (0..m.shape.len())
            .map(|j| spread(&found.iter().map(|r| r.2[j]).collect::<Vec<_>>()))
            .collect(),
        replicates: count,
    };
    (count, Some(errors))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic, irregular record of `l` channels.
    fn record(l: usize, n: usize) -> Vec<Vec<f64>> {
        (0..l)
            .map(|c| {
                (0..n)
                    .map(|t| ((t * (c + 3)) as f64 * 0.37).sin() + ((t * t + c) % 17) as f64 * 0.1)
                    .collect()
            })
            .collect()
    }

    #[test]
    fn the_blocks_sums_add_up_to_the_records_correlations() {
        let y = record(3, 1013);
        let views: Vec<&[f64]> = y.iter().map(|c| c.as_slice()).collect();
        let means: Vec<f64> = y
            .iter()
            .map(|c| c.iter().sum::<f64>() / c.len() as f64)
            .collect();
        let refs = [0, 2];
        let lags = 24;
        let whole = crate::corr::estimate_centred(&views, &refs, lags, &means);
        for blocks in [1, 5, 7] {
            let s = block_sums(&views, (&refs, &means), lags, blocks);
            for k in 0..lags {
                let count: f64 = s.counts.iter().map(|c| c[k]).sum();
                // Every pair once: N − k of them.
                assert_eq!(count, (1013 - k) as f64);
                for (j, w) in whole.r[k].iter().enumerate() {
                    let pooled: f64 = s.sums.iter().map(|b| b.r[k][j]).sum::<f64>() / count;
                    // Sums of ~1000 products of order 1, in another order: 1e-10 relative.
                    assert!(
                        (pooled - w).abs() < 1e-10 * (1.0 + w.abs()),
                        "{blocks} {k} {j}"
                    );
                }
            }
        }
    }

    #[test]
    fn leaving_a_block_out_is_the_correlation_of_the_rest() {
        // With the record's own pairs removed, leaving the last block out is the correlation
        // of the samples before it (pairs whose earlier sample lies there).
        let y = record(2, 900);
        let views: Vec<&[f64]> = y.iter().map(|c| c.as_slice()).collect();
        let means = vec![0.0, 0.0];
        let s = block_sums(&views, (&[0], &means), 10, 6);
        let rest = leave_out(&s, 5);
        for k in 0..10 {
            for a in 0..2 {
                let direct: f64 = (0..750).map(|t| y[a][t + k] * y[0][t]).sum::<f64>() / 750.0;
                assert!((rest.at(k, a, 0) - direct).abs() < 1e-12 * (1.0 + direct.abs()));
            }
        }
    }

    /// Each replicate's SVD found from the record's basis by subspace iteration gives the
    /// errors the full SVD of each replicate gives: five channels of eleven modes damped
    /// 0.2 % with 10 % noise, 224 block rows (the steel frame's setups' shape). The replicates'
    /// triplets are accepted at residuals of 1e-12 σ₁, which moves a pole by about that over
    /// its singular-value gap (≥ 1e-4 σ₁ here): 1e-6 relative is a wide margin that still
    /// tells an approximate subspace (1e-3 and worse after one sweep) from the exact one.
    #[test]
    fn replicates_from_the_records_basis_give_the_full_svds_errors() {
        let modes: Vec<(f64, f64)> = [1.2, 1.4, 2.1, 4.0, 4.8, 6.7, 7.6, 9.7, 12.2, 12.6, 13.9]
            .iter()
            .map(|&f| (f, 0.002))
            .collect();
        let gains: Vec<Vec<f64>> = (0..5)
            .map(|c| {
                (0..22)
                    .map(|k| (((c * 7 + k * 3) % 11) as f64 - 5.0) / 5.0)
                    .collect()
            })
            .collect();
        let y = crate::synth::ModalRecord::new(64.0, &modes)
            .with_gains(gains)
            .with_noise(0.1)
            .generate(15360, 4_910_001);
        let views: Vec<&[f64]> = y.iter().map(Vec::as_slice).collect();
        let opts = SsiOptions {
            block_rows: crate::BlockRows::Count(224),
            ..SsiOptions::default()
        };
        let (ssi, basis) =
            crate::identify::identify_surveyed_with_basis(&views, 64.0, &opts, None, &|_| {})
                .unwrap();
        let refs: Vec<usize> = (0..5).collect();
        let means: Vec<f64> = y
            .iter()
            .map(|c| c.iter().sum::<f64>() / c.len() as f64)
            .collect();
        let run = |start: &Dense| {
            ssi_errors(&views, 64.0, (&refs, &means), (&ssi, start), &opts, 8)
                .unwrap()
                .unwrap()
        };
        // A replicate's SVD is found from the basis (only the basis's width of singular
        // values then), not by the full SVD.
        let sums = block_sums(&views, (&refs, &means), 2 * ssi.block_rows, 8);
        let order = ssi.diagram.orders.last().unwrap().order;
        let fixed = SsiOptions {
            max_order: Some(order),
            ..opts.clone()
        };
        let (replicate, _) = identify_with_basis(
            &leave_out(&sums, 3),
            64.0,
            ssi.block_rows,
            &fixed,
            (order, Some(&basis), Run::Replicate),
            &|_| {},
        )
        .unwrap();
        assert_eq!(replicate.singular_values.len(), basis.cols);
        let near = run(&basis);
        // A basis no wider than the order is refused: every replicate takes the full SVD.
        let full = run(&crate::linalg::leading_columns(&basis, 0));
        assert_eq!(near.found, full.found);
        assert!(near.modes.iter().flatten().count() >= 8, "{:?}", near.found);
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-6 * a.abs().max(b.abs());
        for (a, b) in near.modes.iter().zip(&full.modes) {
            let (Some(a), Some(b)) = (a, b) else {
                assert_eq!(a.is_some(), b.is_some());
                continue;
            };
            assert!(close(a.frequency_se_hz, b.frequency_se_hz), "{a:?} {b:?}");
            assert!(close(a.damping_se, b.damping_se), "{a:?} {b:?}");
            for (p, q) in a.shape_se.iter().zip(&b.shape_se) {
                assert!(close(*p, *q), "{a:?} {b:?}");
            }
        }
    }
}
