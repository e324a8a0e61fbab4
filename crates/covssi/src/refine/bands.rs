//! Many modes: groups at the widest frequency gaps, each fitted jointly over its own band.

use crate::linalg::{self, C64, Dense};
use crate::refine::joint;
use crate::refine::model::{Fit, Model};
use crate::refine::options::RefineOptions;
use crate::refine::results::MisfitCounts;
use crate::refine::spectra::Spectra;
use crate::refine::standard_errors::{Estimates, channel_block, pole_se, shape_se};
use std::ops::Range;

/// The modes of a per-channel fit split into groups of at most `p`, by increasing frequency:
/// as few groups as that allows, ⌈m/p⌉, cut where the narrowest cut gap (ratio of
/// neighbouring frequencies) is widest, ties going to the larger product of the cut gaps
/// ([`cuts`]); with the frequency indices each group's band spans: from 0 and up to the
/// last bin of `sp`, cut at the geometric mean of the neighbouring groups' frequencies. Each band's
/// edges are where modes outside its group (held in its fit) reach in, so the fewer and the
/// wider apart the cuts, the less of the held modes' tails each fit sees.
pub(super) fn split_into_bands(
    lambdas: &[C64],
    p: usize,
    fs: f64,
    sp: &Spectra,
) -> Vec<(Vec<usize>, Range<usize>)> {
    let mut order: Vec<usize> = (0..lambdas.len()).collect();
    order.sort_by(|&a, &b| lambdas[a].norm().total_cmp(&lambdas[b].norm()));
    // ln of the gap below each sorted mode (the first has none).
    let gaps: Vec<f64> = (0..order.len())
        .map(|i| match i {
            0 => 0.0,
            _ => (lambdas[order[i]].norm() / lambdas[order[i - 1]].norm()).ln(),
        })
        .collect();
    let mut bounds = vec![0];
    bounds.extend(cuts(&gaps, p));
    bounds.push(order.len());
    let groups: Vec<Vec<usize>> = bounds
        .windows(2)
        .map(|w| order[w[0]..w[1]].to_vec())
        .collect();
    let k = sp.bins();
    let index = |w: f64| sp.bin_at(w / fs);
    let edges: Vec<usize> = groups
        .windows(2)
        .map(|w| {
            let below = lambdas[*w[0].last().expect("groups are not empty")].norm();
            let above = lambdas[w[1][0]].norm();
            index((below * above).sqrt())
        })
        .collect();
    groups
        .into_iter()
        .enumerate()
        .map(|(i, g)| {
            let lo = if i == 0 { 0 } else { edges[i - 1] };
            let hi = edges.get(i).copied().unwrap_or(k);
            (g, lo..hi)
        })
        .collect()
}

/// Where to cut m sorted modes (`gaps[i]`: ln of the gap below mode i) into ⌈m/p⌉ groups of
/// at most `p`: the cut positions (indices of each later group's first mode), maximising the
/// narrowest cut gap, then the sum of the cut gaps among the cuts as wide as that. Empty for
/// at most `p` modes.
pub(super) fn cuts(gaps: &[f64], p: usize) -> Vec<usize> {
    let m = gaps.len();
    let p = p.max(1);
    let groups = m.div_ceil(p);
    if groups <= 1 {
        return Vec::new();
    }
    // The cuts that maximise the sum of their gaps, each gap at least `floor`: best[j][i] is
    // that sum for the first i modes in j groups, with where its last group starts.
    let best_sum = |floor: f64| -> Option<Vec<usize>> {
        let mut best = vec![vec![None::<(f64, usize)>; m + 1]; groups + 1];
        best[0][0] = Some((0.0, 0));
        for j in 1..=groups {
            for i in j..=m {
                best[j][i] = (i.saturating_sub(p)..i)
                    .filter(|&s| (s == 0) == (j == 1) && (s == 0 || gaps[s] >= floor))
                    .filter_map(|s| best[j - 1][s].map(|(v, _)| (v + gaps[s], s)))
                    .max_by(|a, b| a.0.total_cmp(&b.0));
            }
        }
        let mut out = Vec::with_capacity(groups - 1);
        let mut i = m;
        for j in (2..=groups).rev() {
            i = best[j][i]?.1;
            out.push(i);
        }
        out.reverse();
        Some(out)
    };
    // The widest floor that still leaves a partition: the largest gap that some cut set has
    // as its narrowest.
    let mut floors: Vec<f64> = gaps[1..].to_vec();
    floors.sort_by(|a, b| b.total_cmp(a));
    floors
        .iter()
        .find_map(|&floor| best_sum(floor))
        .unwrap_or_default()
}

/// The chosen modes fitted by the joint likelihood, or `None` when it cannot be fitted (then
/// the per-channel fit stands). Up to `joint_max` channels, the channels themselves over all
/// frequencies. More are fitted through `joint_max` combinations of them carrying the modes
/// ([`Model::project`]); with more modes than combinations, the modes are split into groups
/// of at most `joint_max` ([`split_into_bands`]) and each group is fitted over its own band of
/// frequencies, through combinations carrying its own modes, with the other modes in the
/// model but held: their tails reach into the band. Their poles are the per-channel fit's;
/// the shapes and gains of the two next to the group (by |λ|) are fitted with the group's in
/// the first phase of the fit, the poles held, over the band widened past their peaks, and
/// the others' come from the start's regressions. (Held at the regressions' values, the
/// neighbours' tails pulled the estimates of the bench's 16-channel, 8-mode record up to 4.2
/// standard errors off; likely because the regressions' error need not shrink as the record
/// grows.)
pub(super) fn joint_by_bands(
    model: &Model,
    fit: &Fit,
    joint_max: usize,
    scales: &[f64],
    opts: &RefineOptions,
) -> Option<Estimates> {
    let l = model.l();
    let mk = fit.lambdas.len();
    let combine = l > joint_max;
    let groups = if combine && mk > joint_max {
        split_into_bands(&fit.lambdas, joint_max, model.fs, &model.sp)
    } else {
        vec![((0..mk).collect(), 0..model.sp.bins())]
    };
    let scale: Option<Vec<f64>> = if combine {
        Some(
            model
                .noise_floor(&fit.theta, mk)?
                .iter()
                .map(|v| v.sqrt())
                .collect(),
        )
    } else {
        None
    };
    let mut est = Estimates {
        reals: Vec::new(),
        lambdas: fit.lambdas.clone(),
        se: vec![None; mk],
        shapes: vec![None; mk],
        l: 0.0,
        misfit: 0.0,
        iterations: 0,
        combinations: None,
        bands: groups.len(),
    };
    // The modes by |λ|, when there are bands (their neighbours are fitted with them).
    let by_size: Vec<usize> = if groups.len() > 1 {
        groups.iter().flat_map(|(g, _)| g.iter().copied()).collect()
    } else {
        Vec::new()
    };
    let mut misfit = MisfitCounts::new();
    for (group, band) in &groups {
        let BandFit {
            fit: jf,
            covariance: cov,
            shapes,
            channels: lj,
            misfit: band_misfit,
        } = fit_band(
            model,
            fit,
            (group, band),
            &by_size,
            scale.as_deref(),
            joint_max,
            opts,
        )?;
        misfit.merge(&band_misfit);
        let mf = group.len();

        for (i, &j) in group.iter().enumerate() {
            est.lambdas[j] = jf.lambdas[i];
            est.se[j] = Some(pole_se(&cov, i, mf, &jf.theta));
            est.shapes[j] = shapes
                .as_ref()
                .map(|sh| shape_se(&sh[i].0, &sh[i].1, scales));
        }
        est.l += jf.l;
        est.iterations += jf.iterations;
        est.combinations = combine.then_some(lj);
    }
    est.misfit = misfit.distance();
    Some(est)
}

/// A band's joint fit.
struct BandFit {
    fit: Fit,
    /// Its asymptotic covariance F⁻¹.
    covariance: Dense,
    /// The shapes of the group's modes in every channel, with their covariance; `None` when
    /// the channels' regression on a fit of combinations cannot be made (too few
    /// frequencies in the band for its unknowns, or singular), which leaves the poles as
    /// fitted.
    shapes: Option<Vec<joint::ChannelShape>>,
    /// The channels fitted (the combinations' count when combined).
    channels: usize,
    /// The misfit's counts of the whitened periodogram ordinates of the fit.
    misfit: MisfitCounts,
}

/// The joint fit of the modes `group` over the frequencies `band` (through combinations of
/// the channels scaled by `scale` when given), their neighbours by |λ| (`by_size`) fitted
/// with them, with its whitened ordinates. `None` when the band has too
/// few observations, the fit fails, F is singular, or a pole leaves its band.
fn fit_band(
    model: &Model,
    fit: &Fit,
    (group, band): (&[usize], &Range<usize>),
    by_size: &[usize],
    scale: Option<&[f64]>,
    joint_max: usize,
    opts: &RefineOptions,
) -> Option<BandFit> {
    let mk = fit.lambdas.len();
    let combined = match scale {
        Some(scale) => {
            let lams: Vec<C64> = group.iter().map(|&j| fit.lambdas[j]).collect();
            Some(model.project(&lams, joint_max, scale)?)
        }
        None => None,
    };
    let combined_model = combined
        .as_ref()
        .map(|rows| Model::new(model.sp.combined(rows.clone()), model.fs));
    let rec = combined_model.as_ref().unwrap_or(model);
    let lj = rec.l();
    // The modes next to the group's (by |λ|), whose tails reach furthest into the band:
    // their shapes and gains are fitted with the group's before its poles move.
    let fitted: Vec<usize> = group
        .iter()
        .copied()
        .chain(neighbours(by_size, group))
        .collect();
    let (mf, mn) = (group.len(), fitted.len());
    // Ten observations per parameter, a frequency giving l² of them.
    let frequencies = rec.sp.edges[band.end] - rec.sp.edges[band.start];
    if !(2..=joint_max).contains(&lj) || frequencies * lj * lj < 10 * joint::parameters(lj, mf) {
        return None;
    }
    // The group's modes first, then their neighbours, then the others.
    let order: Vec<usize> = fitted
        .iter()
        .copied()
        .chain((0..mk).filter(|j| !fitted.contains(j)))
        .collect();
    let poles: Vec<f64> = [0, mk]
        .iter()
        .flat_map(|&off| order.iter().map(move |&j| fit.theta[off + j]))
        .collect();
    // The first phase of the fit, poles held, reaches three half-power half-widths past
    // each neighbour's peak, so that its shape and gain come from its peak and not only
    // from the tail that reaches into the band.
    let index = |w: f64| model.sp.bin_at(w / model.fs);
    let wide = fitted[mf..].iter().fold(band.clone(), |b, &j| {
        let (w, h) = (fit.lambdas[j].norm(), -fit.lambdas[j].re);
        b.start.min(index(w - 3.0 * h))..b.end.max(index(w + 3.0 * h) + 1)
    });
    let (mut jm, start) = joint::Joint::start(rec, &poles, mn, wide)?;
    let jf = jm.fit(start, mf, band.clone(), opts).ok()?;
    let misfit = jm.misfit(&jf.theta)?;
    // Its asymptotic covariance is F⁻¹ (an exact likelihood); a singular F means the
    // channels are degenerate for it (e.g. one a copy of another).
    let cov = linalg::spd_inverse(&jf.fisher)?;
    // A pole that left its band (to a neighbour's peak) is not that band's mode.
    let (lo, hi) = (rec.sp.z[band.start].arg(), rec.sp.z[band.end - 1].arg());
    if band.len() < rec.sp.bins()
        && jf
            .lambdas
            .iter()
            .any(|lam| !(lo..=hi).contains(&(lam.im / model.fs)))
    {
        return None;
    }
    // The group's shapes with their covariance: the fit's own when the channels were fitted
    // themselves, else each channel's regressed on the fit's innovations.
    let shapes = match &combined {
        None => {
            let c = jm.fitted_shapes(&jf.theta);
            let own = (0..mf)
                .map(|i| {
                    let offset = joint::shape_offset(i, mf, lj);
                    (c[i].clone(), channel_block(&cov, offset, lj))
                })
                .collect();
            Some(own)
        }
        Some(rows) => jm.channel_shapes(&jf.theta, &cov, (&model.sp, rows), mf),
    };
    Some(BandFit {
        fit: jf,
        covariance: cov,
        shapes,
        channels: lj,
        misfit,
    })
}

/// The modes just below and just above `group` in `by_size` (modes in order of |λ|, `group`
/// a stretch of it); none when `by_size` is empty.
pub(super) fn neighbours(by_size: &[usize], group: &[usize]) -> Vec<usize> {
    let at = |j: &usize| group.contains(j);
    match (by_size.iter().position(at), by_size.iter().rposition(at)) {
        (Some(lo), Some(hi)) => lo
            .checked_sub(1)
            .into_iter()
            .chain((hi + 1 < by_size.len()).then_some(hi + 1))
            .map(|i| by_size[i])
            .collect(),
        _ => Vec::new(),
    }
}
