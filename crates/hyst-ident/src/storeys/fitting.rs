//! The fits themselves: indirect inference of a layout's parameters (the levels'
//! Levenberg–Marquardt), the statistics' spread over replicates, two-fold
//! cross-validation's held-out score, and the standard errors' sandwich.

use nalgebra::DMatrix;
use rayon::prelude::*;

use super::model::{self, Layout};
use super::setup::Setup;
use super::statistics::Simulator;
use super::types::{StoreyOptions, StoreyProgress};
use crate::IdentError;
use crate::levels::{ParameterSteps, SimulationOptions, indirect_lm};
use hyst_sim::building::ShearBuilding;

/// One fit's end.
pub(super) struct Fitted {
    pub(super) theta: Vec<f64>,
    pub(super) cost: f64,
    pub(super) residuals: usize,
    pub(super) iterations: usize,
    /// The last iteration gained less than the tolerance (else the iteration limit ended it).
    pub(super) converged: bool,
    pub(super) simulated: Vec<Vec<f64>>,
    /// The last Jacobian of the whitened residuals in the scaled parameters.
    pub(super) jacobian: Option<Vec<Vec<f64>>>,
    /// The scales: θ = p · scale (for an element, its last two are (β + γ, β − γ)).
    pub(super) scale: Vec<f64>,
    /// The last two parameters are an element's sum and difference.
    pub(super) element: bool,
}

/// Indirect inference of `layout`'s parameters from `theta0` against `measured` (per level)
/// whitened by `spread`.
#[allow(clippy::too_many_arguments)]
pub(super) fn fit(
    setup: &Setup,
    layout: &Layout,
    theta0: &[f64],
    sim: &Simulator,
    measured: &[Vec<f64>],
    spread: &[Vec<f64>],
    opts: &StoreyOptions,
    stage: &str,
    progress: &(dyn Fn(StoreyProgress<'_>) + Sync),
) -> Result<Fitted, IdentError> {
    // The element's (β, γ) move as (β + γ, β − γ): its bounded range (β + γ > 0, γ ≤ β)
    // is then a box the Levenberg–Marquardt clamps to, not a wall it is refused at (refused
    // steps left long records' fits stuck at γ = β, their residuals three times chance).
    let element = layout.storey.is_some();
    let mut start = theta0.to_vec();
    let k = start.len();
    if element {
        let (b, g) = (theta0[k - 2], theta0[k - 1]);
        (start[k - 2], start[k - 1]) = (b + g, b - g);
    }
    let mut scale: Vec<f64> = start
        .iter()
        .map(|v| if *v != 0.0 { v.abs() } else { 1.0 })
        .collect();
    if element {
        // Sum and difference on the sum's scale (the difference may reach zero).
        let s = if start[k - 2] > 0.0 {
            start[k - 2]
        } else {
            1.0
        };
        scale[k - 2] = s;
        scale[k - 1] = s;
    }
    let theta = |p: &[f64]| -> Vec<f64> {
        let mut t: Vec<f64> = p.iter().zip(&scale).map(|(a, b)| a * b).collect();
        if element {
            let (sum, diff) = (t[k - 2], t[k - 1]);
            (t[k - 2], t[k - 1]) = (0.5 * (sum + diff), 0.5 * (sum - diff));
        }
        t
    };
    let aux = |p: &[f64]| -> Result<Vec<Vec<f64>>, IdentError> {
        let (b, q, folded) = model::building(&setup.template, layout, &theta(p), opts.nu)?;
        (0..setup.levels)
            .into_par_iter()
            .map(|l| Ok(setup.reading.of(&sim.record(&b, l, (q[l], folded))?)))
            .collect()
    };
    let resid = |s: &Vec<Vec<f64>>| -> Vec<f64> {
        s.iter()
            .zip(measured)
            .zip(spread)
            .flat_map(|((a, m), sd)| {
                a.iter()
                    .zip(m)
                    .zip(sd)
                    .map(|((a, m), sd)| (a - m) / sd)
                    .collect::<Vec<_>>()
            })
            .collect()
    };
    let mut p: Vec<f64> = start.iter().zip(&scale).map(|(a, b)| a / b).collect();
    let nonnegative = vec![true; p.len()];
    let min_step = vec![1e-3; p.len()];
    let lm = SimulationOptions {
        max_iterations: opts.max_iterations,
        tolerance: opts.tolerance,
        ..SimulationOptions::default()
    };
    let tell = |iteration: usize, cost: f64| {
        progress(StoreyProgress {
            stage,
            iteration,
            cost,
        })
    };
    tell(
        0,
        aux(&p).map_or(f64::NAN, |s| resid(&s).iter().map(|v| v * v).sum()),
    );
    let fit = indirect_lm(
        &mut p,
        &ParameterSteps {
            nonnegative: &nonnegative,
            min_step: &min_step,
        },
        &aux,
        &resid,
        &lm,
        &tell,
    )?;
    Ok(Fitted {
        theta: theta(&p),
        cost: fit.cost,
        residuals: fit.residuals,
        iterations: fit.iterations,
        converged: fit.converged,
        simulated: fit.simulated,
        jacobian: fit.jacobian,
        scale,
        element,
    })
}

/// Each statistic's spread over `opts.replicates` simulated records of `building` at each
/// level (forces drawn afresh), and its covariance, level by level.
#[allow(clippy::type_complexity)]
pub(super) fn spread(
    setup: &Setup,
    building: &ShearBuilding,
    (q, folded): (&[f64], f64),
    lengths: &[usize],
    opts: &StoreyOptions,
) -> Result<(Vec<Vec<f64>>, Vec<DMatrix<f64>>), IdentError> {
    let sim = setup.simulator(&[], opts.seed);
    let r = opts.replicates.max(3);
    let mut sds = Vec::new();
    let mut covs = Vec::new();
    for (l, (&n, &q)) in lengths.iter().zip(q).enumerate() {
        let first_seed = opts.seed.wrapping_add(100_000 + 1000 * l as u64);
        let stats = replicates(setup, &sim, building, (n, (q, folded)), (r, first_seed))?;
        let d = stats[0].len();
        let mean: Vec<f64> = (0..d)
            .map(|k| stats.iter().map(|s| s[k]).sum::<f64>() / r as f64)
            .collect();
        let cov = DMatrix::from_fn(d, d, |a, b| {
            stats
                .iter()
                .map(|s| (s[a] - mean[a]) * (s[b] - mean[b]))
                .sum::<f64>()
                / (r - 1) as f64
        });
        sds.push((0..d).map(|k| cov[(k, k)].sqrt().max(1e-12)).collect());
        covs.push(cov);
    }
    Ok((sds, covs))
}

/// The statistics of `count` records of `n` samples of `building` under forces (density,
/// folded band) drawn afresh from seeds `first_seed`, `first_seed + 1`, … (in parallel).
fn replicates(
    setup: &Setup,
    sim: &Simulator,
    building: &ShearBuilding,
    (n, force): (usize, (f64, f64)),
    (count, first_seed): (usize, u64),
) -> Result<Vec<Vec<f64>>, IdentError> {
    (0..count)
        .into_par_iter()
        .map(|i| {
            let y = sim.replicate(building, n, force, first_seed.wrapping_add(i as u64))?;
            Ok(setup.reading.of(&y))
        })
        .collect()
}

/// The whitened distance of the held-out halves' statistics from the mean of four fresh
/// simulations of the model.
pub(super) fn held_out_score(
    setup: &Setup,
    building: &ShearBuilding,
    (q, folded): (&[f64], f64),
    second: &[Vec<Vec<f64>>],
    measured: &[Vec<f64>],
    spread: &[Vec<f64>],
    opts: &StoreyOptions,
) -> Result<f64, IdentError> {
    let sim = setup.simulator(&[], opts.seed);
    const DRAWS: usize = 4;
    let mut total = 0.0;
    for (l, r) in second.iter().enumerate() {
        let n = r[0].len();
        let first_seed = opts.seed.wrapping_add(500_000 + 1000 * l as u64);
        let stats = replicates(
            setup,
            &sim,
            building,
            (n, (q[l], folded)),
            (DRAWS, first_seed),
        )?;
        for k in 0..measured[l].len() {
            let mean = stats.iter().map(|s| s[k]).sum::<f64>() / DRAWS as f64;
            total += ((mean - measured[l][k]) / spread[l][k]).powi(2);
        }
    }
    Ok(total)
}

/// The covariance of θ: the sandwich of the whitened Jacobian with the statistics'
/// covariance (whitened the same way), doubled for the simulated records' own noise, in
/// physical units (rows in θ's order). NaN when the Jacobian is singular.
pub(super) fn sandwich(fit: &Fitted, spread: &[Vec<f64>], cov: &[DMatrix<f64>]) -> DMatrix<f64> {
    let np = fit.theta.len();
    let nan = DMatrix::from_element(np, np, f64::NAN);
    let Some(cols) = &fit.jacobian else {
        return nan;
    };
    let rows = cols.first().map_or(0, Vec::len);
    let j = DMatrix::from_fn(rows, np, |r, c| cols[c][r]);
    // The whitened statistics' covariance, block-diagonal over levels (independent records).
    let mut s = DMatrix::zeros(rows, rows);
    let mut at = 0;
    for (sd, c) in spread.iter().zip(cov) {
        let d = sd.len();
        for a in 0..d {
            for b in 0..d {
                s[(at + a, at + b)] = c[(a, b)] / (sd[a] * sd[b]);
            }
        }
        at += d;
    }
    let Some(inv) = (j.transpose() * &j).try_inverse() else {
        return nan;
    };
    let v = &inv * j.transpose() * s * &j * &inv * 2.0;
    // From the scaled parameters to θ: the scales, and (β, γ) = ((s + d)/2, (s − d)/2).
    let mut to_theta = DMatrix::from_diagonal(&nalgebra::DVector::from_column_slice(&fit.scale));
    if fit.element {
        let (a, b) = (np - 2, np - 1);
        let s = fit.scale[a];
        to_theta[(a, a)] = 0.5 * s;
        to_theta[(a, b)] = 0.5 * s;
        to_theta[(b, a)] = 0.5 * s;
        to_theta[(b, b)] = -0.5 * s;
    }
    &to_theta * v * to_theta.transpose()
}

/// The two halves of every record, their statistics, and the statistics' spread at half
/// length.
pub(super) struct Halves<'a> {
    pub(super) records: [&'a [Vec<Vec<f64>>]; 2],
    pub(super) measured: [&'a [Vec<f64>]; 2],
    pub(super) spread: &'a [Vec<f64>],
}

/// Two-fold cross-validation of a candidate: fitted on the first halves and scored on the
/// second, then fitted on the second (from the first fit) and scored on the first. The
/// summed held-out scores, the summed fitted costs, and the first fit's parameters.
#[allow(clippy::too_many_arguments)]
pub(super) fn cross_validate(
    setup: &Setup,
    layout: &Layout,
    theta0: &[f64],
    halves: &Halves<'_>,
    opts: &StoreyOptions,
    name: &str,
    progress: &(dyn Fn(StoreyProgress<'_>) + Sync),
) -> Result<(f64, f64, Vec<f64>), IdentError> {
    let mut theta = theta0.to_vec();
    let mut first_fit = None;
    let (mut held_out, mut fitted) = (0.0, 0.0);
    for (fold, (train, test)) in [(0, 1), (1, 0)].into_iter().enumerate() {
        let lengths: Vec<usize> = halves.records[train].iter().map(|r| r[0].len()).collect();
        let sim = setup.simulator(&lengths, opts.seed + 2000 * fold as u64);
        let which = ["first", "second"][train];
        let stage = format!("{name}: fitting the {which} halves");
        let f = fit(
            setup,
            layout,
            &theta,
            &sim,
            halves.measured[train],
            halves.spread,
            opts,
            &stage,
            progress,
        )?;
        let (b, q, folded) = model::building(&setup.template, layout, &f.theta, opts.nu)?;
        held_out += held_out_score(
            setup,
            &b,
            (&q, folded),
            halves.records[test],
            halves.measured[test],
            halves.spread,
            opts,
        )?;
        fitted += f.cost;
        theta = f.theta.clone();
        first_fit.get_or_insert(f.theta);
    }
    Ok((held_out, fitted, first_fit.unwrap_or(theta)))
}
