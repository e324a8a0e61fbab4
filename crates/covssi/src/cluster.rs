//! The stable poles of a labelled diagram clustered into modes ([`Mode`]) and real-pole
//! clusters ([`RealPoleCluster`]), each with its spread over the orders.

use crate::linalg::C64;
use crate::stabilize::{Pole, PoleStatus, Stability, mac, mpc, rel};
use crate::{SsiOptions, StabilizationDiagram};

/// A physical mode: a cluster of fully stable oscillating poles.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Mode {
    /// Mean natural frequency (Hz).
    pub frequency_hz: f64,
    /// Standard deviation of the members' frequencies (Hz).
    pub frequency_std_hz: f64,
    /// Mean damping ratio.
    pub damping_ratio: f64,
    /// Standard deviation of the members' damping ratios.
    pub damping_std: f64,
    /// Mean of the members' shapes, each scaled alike (one common entry 1), then the mean
    /// scaled so that its largest entry is 1.
    pub shape: Vec<C64>,
    /// Standard deviation of the scaled shapes' entries (magnitude of the complex spread).
    pub shape_std: Vec<f64>,
    /// Member poles as (order, index in that order's pole list), one per order, by increasing
    /// order.
    pub members: Vec<(usize, usize)>,
    /// Mean continuous-time pole (rad/s).
    pub lambda: C64,
    /// Modal phase collinearity of `shape` ([`mpc`]): 1 for a real (normal) mode.
    pub mpc: f64,
}

/// A cluster of stable real poles.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct RealPoleCluster {
    /// Mean real pole λ (rad/s, negative).
    pub lambda: f64,
    /// Standard deviation of the members.
    pub lambda_std: f64,
    /// Member poles as (order, index in that order's pole list).
    pub members: Vec<(usize, usize)>,
}

fn mean_std(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = if v.len() > 1 {
        v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0)
    } else {
        0.0
    };
    (m, var.sqrt())
}

/// Index of a shape's largest entry (the last of equals; 0 for an empty shape).
pub(crate) fn largest_entry(shape: &[C64]) -> usize {
    (0..shape.len())
        .max_by(|&a, &b| shape[a].norm().total_cmp(&shape[b].norm()))
        .unwrap_or(0)
}

/// The shapes `members` of one mode each scaled so that one common entry is 1: the entry
/// largest over them all (by the sum of each member's share of its own energy there). Scaled
/// each by its own largest entry, members whose two largest entries are about equal (a mode
/// shape antisymmetric about a node) would flip sign between orders and average to nothing.
fn scaled_alike(members: &[&[C64]]) -> Vec<Vec<C64>> {
    let l = members.first().map_or(0, |s| s.len());
    let weight = |a: usize| -> f64 {
        members
            .iter()
            .map(|s| {
                let e: f64 = s.iter().map(|v| v.norm_sqr()).sum();
                if e > 0.0 { s[a].norm_sqr() / e } else { 0.0 }
            })
            .sum()
    };
    let common = (0..l)
        .max_by(|&a, &b| weight(a).total_cmp(&weight(b)))
        .unwrap_or(0);
    members
        .iter()
        .map(|s| match s.get(common) {
            Some(v) if v.norm() > 0.0 => s.iter().map(|x| x / v).collect(),
            _ => normalise(s),
        })
        .collect()
}

fn normalise(shape: &[C64]) -> Vec<C64> {
    let big = shape
        .get(largest_entry(shape))
        .copied()
        .unwrap_or(C64::new(1.0, 0.0));
    if big.norm() == 0.0 {
        return shape.to_vec();
    }
    shape.iter().map(|v| v / big).collect()
}

/// Group candidates (sorted by `key`) into runs whose neighbours differ by at most `tol`
/// relatively; keep one member per order (the nearest to the run's median); drop small runs.
/// Used for real poles, which have one coordinate.
fn runs(
    mut cand: Vec<(f64, usize, usize)>,
    tol: f64,
    min_size: usize,
) -> Vec<Vec<(f64, usize, usize)>> {
    cand.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut out: Vec<Vec<(f64, usize, usize)>> = Vec::new();
    for c in cand {
        match out.last_mut() {
            Some(run) if rel(run.last().expect("runs are non-empty").0, c.0) <= tol => run.push(c),
            _ => out.push(vec![c]),
        }
    }
    out.into_iter()
        .map(|run| {
            let med = run[run.len() / 2].0;
            one_per_order(run, |c| c.1, |c| (c.0 - med).abs())
        })
        .filter(|run| run.len() >= min_size)
        .collect()
}

/// Keep one member per order (`order` of a member), the one with the smallest `dist`; the
/// first met wins a tie. Members keep the order they came in.
fn one_per_order<T>(
    members: Vec<T>,
    order: impl Fn(&T) -> usize,
    dist: impl Fn(&T) -> f64,
) -> Vec<T> {
    let mut best: Vec<T> = Vec::new();
    for m in members {
        match best.iter_mut().find(|b| order(b) == order(&m)) {
            Some(b) if dist(&m) < dist(b) => *b = m,
            Some(_) => {}
            None => best.push(m),
        }
    }
    best
}

/// Relative distance of two poles in the complex plane, |λa − λb| / max(|λa|, |λb|). Unlike a
/// frequency gap it separates poles of one frequency but different damping: a physical mode
/// and a lightly damped noise pole beside it.
pub(crate) fn pole_distance(a: C64, b: C64) -> f64 {
    let m = a.norm().max(b.norm());
    if m == 0.0 { 0.0 } else { (a - b).norm() / m }
}

fn find(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

/// Cluster oscillating poles, given as (order index, pole index), by single linkage: two poles
/// join when their [`pole_distance`] is at most `tol` and, with several channels, their shapes
/// agree within `mac` (1 − MAC). Each cluster keeps one pole per order, the one nearest its
/// centre (the median of Re λ and of Im λ over the cluster); clusters with fewer than
/// `min_size` orders are dropped.
fn pole_clusters(
    d: &StabilizationDiagram,
    mut cand: Vec<(usize, usize)>,
    tol: f64,
    mac_tol: f64,
    min_size: usize,
) -> Vec<Vec<(usize, usize)>> {
    let pole = |&(o, p): &(usize, usize)| &d.orders[o].poles[p];
    cand.sort_by(|a, b| pole(a).frequency_hz.total_cmp(&pole(b).frequency_hz));
    let mut parent: Vec<usize> = (0..cand.len()).collect();
    for (i, ca) in cand.iter().enumerate() {
        let a = pole(ca);
        // |Δλ| ≥ |Δ|λ||: once the frequencies differ by more than `tol`, so do the poles.
        for (j, cb) in cand.iter().enumerate().skip(i + 1) {
            let b = pole(cb);
            if rel(a.frequency_hz, b.frequency_hz) > tol {
                break;
            }
            let near = pole_distance(a.lambda, b.lambda) <= tol
                && (d.channels == 1 || 1.0 - mac(&a.shape, &b.shape) <= mac_tol);
            if near {
                let (ra, rb) = (find(&mut parent, i), find(&mut parent, j));
                parent[ra.max(rb)] = ra.min(rb);
            }
        }
    }
    let mut groups: Vec<Vec<(usize, usize)>> = Vec::new();
    let mut slot = vec![usize::MAX; cand.len()];
    for (i, &c) in cand.iter().enumerate() {
        let r = find(&mut parent, i);
        if slot[r] == usize::MAX {
            slot[r] = groups.len();
            groups.push(Vec::new());
        }
        groups[slot[r]].push(c);
    }
    groups
        .into_iter()
        .map(|g| {
            let median = |f: &dyn Fn(C64) -> f64| {
                let mut v: Vec<f64> = g.iter().map(|m| f(pole(m).lambda)).collect();
                v.sort_by(f64::total_cmp);
                v[v.len() / 2]
            };
            let centre = C64::new(median(&|l| l.re), median(&|l| l.im));
            let mut best = one_per_order(g, |m| m.0, |m| (pole(m).lambda - centre).norm());
            best.sort_unstable();
            best
        })
        .filter(|g| g.len() >= min_size)
        .collect()
}

/// The most a mode's poles may spread in frequency (standard deviation over the cluster),
/// in half-power bandwidths $2\zeta f$ of the mode they make. The poles of one mode found at
/// different orders differ by a fraction of its bandwidth (on the shared measured records
/// the widest is 0.94); a cluster spread wider was chained from distinct lightly damped poles
/// (the Silverbox record's multisine lines: 0.12 % damping, ± 1.5 Hz, 9.4 bandwidths).
const MAX_SPREAD_BANDWIDTHS: f64 = 2.0;

/// The mean of a mode's member poles' shapes (scaled alike, then the mean's largest entry 1)
/// and each entry's standard deviation over them (magnitude of the complex spread).
fn mean_shape(poles: &[&Pole]) -> (Vec<C64>, Vec<f64>) {
    let member_shapes: Vec<&[C64]> = poles.iter().map(|p| p.shape.as_slice()).collect();
    let shapes = scaled_alike(&member_shapes);
    let l = shapes.first().map_or(0, Vec::len);
    let k = shapes.len() as f64;
    let mean: Vec<C64> = (0..l)
        .map(|a| shapes.iter().map(|s| s[a]).sum::<C64>() / k)
        .collect();
    // The mean's own largest entry 1, the members with it.
    let big = mean
        .get(largest_entry(&mean))
        .copied()
        .unwrap_or(C64::new(1.0, 0.0));
    let big = if big.norm() > 0.0 {
        big
    } else {
        C64::new(1.0, 0.0)
    };
    let mean: Vec<C64> = mean.iter().map(|v| v / big).collect();
    let shapes: Vec<Vec<C64>> = shapes
        .iter()
        .map(|s| s.iter().map(|v| v / big).collect())
        .collect();
    let spread: Vec<f64> = (0..l)
        .map(|a| {
            let v = shapes
                .iter()
                .map(|s| (s[a] - mean[a]).norm_sqr())
                .sum::<f64>();
            if shapes.len() > 1 {
                (v / (k - 1.0)).sqrt()
            } else {
                0.0
            }
        })
        .collect();
    (mean, spread)
}

pub(crate) fn cluster(
    d: &StabilizationDiagram,
    opts: &SsiOptions,
) -> (Vec<Mode>, Vec<RealPoleCluster>, Vec<String>) {
    let top = d.full_stability();
    let min_size = opts
        .min_cluster_size
        .unwrap_or_else(|| (d.orders.len() / 5).max(3));
    let mut osc = Vec::new();
    let mut real = Vec::new();
    for (oi, o) in d.orders.iter().enumerate() {
        for (pi, p) in o.poles.iter().enumerate() {
            match p.status {
                PoleStatus::Stable(s) if s == top => osc.push((oi, pi)),
                PoleStatus::Stable(Stability::Real) => real.push((-p.lambda.re, oi, pi)),
                _ => {}
            }
        }
    }
    let mut notes = Vec::new();
    let n_osc = osc.len();
    let mut modes: Vec<Mode> =
        pole_clusters(d, osc, opts.cluster_tolerance, opts.criteria.mac, min_size)
            .into_iter()
            .map(|run| {
                let poles: Vec<&Pole> = run.iter().map(|&(o, p)| &d.orders[o].poles[p]).collect();
                let f: Vec<f64> = poles.iter().map(|p| p.frequency_hz).collect();
                let z: Vec<f64> = poles.iter().map(|p| p.damping_ratio).collect();
                let (fm, fs) = mean_std(&f);
                let (zm, zs) = mean_std(&z);
                let (mean, spread) = mean_shape(&poles);
                let k = poles.len() as f64;
                let lambda = poles.iter().map(|p| p.lambda).sum::<C64>() / k;
                Mode {
                    mpc: mpc(&mean),
                    frequency_hz: fm,
                    frequency_std_hz: fs,
                    damping_ratio: zm,
                    damping_std: zs,
                    shape: mean,
                    shape_std: spread,
                    members: run.iter().map(|&(o, p)| (d.orders[o].order, p)).collect(),
                    lambda,
                }
            })
            .collect();
    modes.sort_by(|a, b| a.frequency_hz.total_cmp(&b.frequency_hz));
    modes.retain(|m| {
        let bandwidth = 2.0 * m.damping_ratio * m.frequency_hz;
        let one_mode = m.frequency_std_hz <= MAX_SPREAD_BANDWIDTHS * bandwidth;
        if !one_mode {
            notes.push(format!(
                "{} stable poles near {:.4} Hz chained into one cluster, but they spread over ± {:.4} Hz, more than {MAX_SPREAD_BANDWIDTHS} times the half-power bandwidth their damping ({:.4}) gives ({:.4} Hz): distinct lightly damped poles (harmonics of the excitation, or noise), not one mode; not reported",
                m.members.len(),
                m.frequency_hz,
                m.frequency_std_hz,
                m.damping_ratio,
                bandwidth
            ));
        }
        one_mode
    });
    // A chained cluster dropped above has said why there is no mode.
    if modes.is_empty() && notes.is_empty() {
        notes.push(if n_osc == 0 {
            "no pole was stable in frequency and damping at any order: no mode found (try more block rows, a higher order, or looser thresholds)".to_string()
        } else {
            format!(
                "{n_osc} stable poles, but no cluster reached {min_size} members: no mode found (too few orders agree on any one pole; a lag shorter than the modes' periods does that: give more block rows or --lag-seconds)"
            )
        });
    }
    let real_clusters: Vec<RealPoleCluster> = runs(real, 0.25, min_size)
        .into_iter()
        .map(|run| {
            let v: Vec<f64> = run
                .iter()
                .map(|&(_, o, p)| d.orders[o].poles[p].lambda.re)
                .collect();
            let (m, s) = mean_std(&v);
            RealPoleCluster {
                lambda: m,
                lambda_std: s,
                members: run
                    .iter()
                    .map(|&(_, o, p)| (d.orders[o].order, p))
                    .collect(),
            }
        })
        .collect();
    (modes, real_clusters, notes)
}

#[cfg(test)]
mod tests {
    #[test]
    fn members_whose_largest_entry_flips_average_to_their_shape() {
        // An antisymmetric shape [1, 0, −1] whose members' largest entry alternates between
        // the ends (noise): scaled alike they average to it, not to nothing.
        let a = [
            C64::new(1.0, 0.0),
            C64::new(0.01, 0.0),
            C64::new(-0.98, 0.0),
        ];
        let b = [C64::new(-0.97, 0.0), C64::new(0.0, 0.0), C64::new(1.0, 0.0)];
        let b: Vec<C64> = b.iter().map(|v| -v * 2.0).collect();
        let scaled = scaled_alike(&[&a, &b]);
        for s in &scaled {
            assert!((s[0] - 1.0).norm() < 1e-12 || (s[2] - 1.0).norm() < 1e-12);
            // Each member scaled by one common entry: its ends −1 apart within 3 %.
            assert!((s[0] / s[2] + 1.0).norm() < 0.04, "{s:?}");
        }
    }

    use super::*;
    use crate::{OrderPoles, SsiOptions, StabilizationDiagram};

    /// A pole of natural frequency `f` Hz and damping `zeta`, as covssi makes it from a
    /// discrete eigenvalue at 20 Hz, labelled fully stable for one channel.
    fn stable_pole(f: f64, zeta: f64) -> Pole {
        let fs = 20.0;
        let w = 2.0 * std::f64::consts::PI * f;
        let lambda = C64::new(-zeta * w, w * (1.0 - zeta * zeta).sqrt());
        let mut p = Pole::new((lambda / fs).exp(), fs, vec![C64::new(1.0, 0.0)]);
        p.status = PoleStatus::Stable(Stability::FrequencyDamping);
        p
    }

    /// The diagram of one channel at 20 Hz holding `orders`.
    fn one_channel_diagram(orders: Vec<OrderPoles>) -> StabilizationDiagram {
        StabilizationDiagram {
            orders,
            fs: 20.0,
            channels: 1,
            ..StabilizationDiagram::default()
        }
    }

    /// A physical mode (4.05 Hz, 5 % damping) and, from order 6 up, a lightly damped noise
    /// pole (1.5 %) at nearly the same frequency, nearer the mode's median frequency than the
    /// physical pole is. Clustered by frequency alone, the mode took the noise pole at those
    /// orders (its mean damping fell to about 3 %); by distance in the complex plane the two
    /// stay apart.
    #[test]
    fn a_noise_pole_at_the_same_frequency_does_not_join_the_mode() {
        let orders: Vec<OrderPoles> = (1..=10)
            .map(|order| {
                let jitter = 1e-4 * (order as f64 - 5.0);
                let mut poles = vec![stable_pole(4.05 + jitter, 0.05)];
                if order >= 6 {
                    poles.push(stable_pole(4.05 + jitter / 10.0, 0.015));
                }
                OrderPoles { order, poles }
            })
            .collect();
        let d = one_channel_diagram(orders);
        let opts = SsiOptions {
            min_cluster_size: Some(3),
            ..SsiOptions::default()
        };
        let (modes, _, _) = cluster(&d, &opts);
        assert_eq!(modes.len(), 2, "{modes:?}");
        // Members are exact poles of damping 0.05 and 0.015: only rounding separates them.
        approx::assert_relative_eq!(modes[0].damping_ratio, 0.015, max_relative = 1e-9);
        assert_eq!(modes[0].members.len(), 5);
        approx::assert_relative_eq!(modes[1].damping_ratio, 0.05, max_relative = 1e-9);
        assert_eq!(modes[1].members.len(), 10);
    }

    /// Lightly damped poles (0.1 %) a little apart at each order, as an excitation's
    /// spectral lines give, chain into one cluster by single linkage; their spread (± 1.5 %
    /// of the frequency) is many half-power bandwidths (0.2 %): not a mode. A mode whose
    /// poles scatter within a fraction of its bandwidth beside them is kept.
    #[test]
    fn poles_spread_over_many_bandwidths_are_not_one_mode() {
        let orders: Vec<OrderPoles> = (1..=20)
            .map(|order| {
                let step = (order as f64 - 10.5) / 10.0;
                OrderPoles {
                    order,
                    poles: vec![
                        stable_pole(3.0 * (1.0 + 0.025 * step), 0.001),
                        stable_pole(6.0 * (1.0 + 1e-4 * step), 0.01),
                    ],
                }
            })
            .collect();
        let d = one_channel_diagram(orders);
        let opts = SsiOptions {
            min_cluster_size: Some(3),
            cluster_tolerance: 0.01,
            ..SsiOptions::default()
        };
        let (modes, _, notes) = cluster(&d, &opts);
        assert_eq!(modes.len(), 1, "{modes:?}");
        approx::assert_relative_eq!(modes[0].frequency_hz, 6.0, max_relative = 1e-6);
        assert_eq!(notes.len(), 1, "{notes:?}");
        assert!(notes[0].contains("not one mode"), "{}", notes[0]);
    }

    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]

        /// Whatever the poles: each mode has at most one member per order and only fully
        /// stable members, the modes come by increasing frequency, a mode's mean frequency
        /// lies within its members', and rotating the pole lists of every order (which renames
        /// the poles) changes no mode.
        #[test]
        fn modes_take_one_stable_pole_per_order_whatever_the_pole_order(
            orders in prop::collection::vec(
                prop::collection::vec((1.0f64..5.0, 0.005f64..0.1, any::<bool>()), 0..6),
                3..15,
            ),
            rot in 0usize..6,
        ) {
            let build = |rotate: usize| {
                let orders: Vec<OrderPoles> = orders
                    .iter()
                    .enumerate()
                    .map(|(o, ps)| {
                        let mut poles: Vec<Pole> = ps
                            .iter()
                            .map(|&(f, z, full)| {
                                let mut p = stable_pole(f, z);
                                if !full {
                                    p.status = PoleStatus::Stable(Stability::Frequency);
                                }
                                p
                            })
                            .collect();
                        if !poles.is_empty() {
                            let r = rotate % poles.len();
                            poles.rotate_left(r);
                        }
                        OrderPoles { order: o + 1, poles }
                    })
                    .collect();
                StabilizationDiagram { orders, fs: 20.0, channels: 1, ..StabilizationDiagram::default() }
            };
            let opts = SsiOptions { min_cluster_size: Some(3), ..SsiOptions::default() };
            let d = build(0);
            let (modes, _, _) = cluster(&d, &opts);
            for pair in modes.windows(2) {
                prop_assert!(pair[0].frequency_hz <= pair[1].frequency_hz);
            }
            for m in &modes {
                prop_assert!(m.members.len() >= 3);
                let mut seen: Vec<usize> = m.members.iter().map(|&(o, _)| o).collect();
                seen.dedup();
                prop_assert_eq!(seen.len(), m.members.len(), "one pole per order: {:?}", m.members);
                let f: Vec<f64> = m
                    .members
                    .iter()
                    .map(|&(o, i)| {
                        let p = &d.orders[o - 1].poles[i];
                        assert_eq!(p.status, PoleStatus::Stable(Stability::FrequencyDamping));
                        p.frequency_hz
                    })
                    .collect();
                let (lo, hi) = f.iter().fold((f64::MAX, f64::MIN), |(a, b), &v| (a.min(v), b.max(v)));
                // A mean lies within the range of what it averages, up to its rounding.
                prop_assert!(m.frequency_hz >= lo * (1.0 - 1e-15) && m.frequency_hz <= hi * (1.0 + 1e-15));
            }
            let (rotated, _, _) = cluster(&build(rot), &opts);
            prop_assert_eq!(rotated.len(), modes.len());
            for (a, b) in modes.iter().zip(&rotated) {
                // The same poles, summed in the same order (one per order, by order): equal.
                prop_assert_eq!(a.frequency_hz, b.frequency_hz);
                prop_assert_eq!(a.damping_ratio, b.damping_ratio);
                let orders_of = |m: &Mode| m.members.iter().map(|&(o, _)| o).collect::<Vec<_>>();
                prop_assert_eq!(orders_of(a), orders_of(b));
            }
        }
    }
}
