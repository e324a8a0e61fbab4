//! A chart's alarm limit calibrated on the values it charts over the training records.
//!
//! A CUSUM's in-control run length by Siegmund's formula holds for independent standard
//! normal values. A campaign's charted values are neither quite: a slow effect left in them
//! correlates them from record to record, a heavy tail (a frost day, an odd record) makes
//! large values likelier, and the run length falls by orders of magnitude. So the limit is
//! set on the training records' own charted values v₁ … v_m:
//!
//! 1. **Their dependence kept**: the values are resampled by the circular block bootstrap
//!    (Politis and Romano; Künsch) in blocks of L = max(⌈m^{1/3}⌉, ⌈2 τ⌉) consecutive values, τ
//!    the integrated autocorrelation time 1 + 2 Σ ρ_k (summed until ρ_k first falls below
//!    zero), so that a block spans the values' memory; into a series of 400 000 values.
//! 2. **The run length measured**: the chart run over that series at limits h = 1, 1.5, …
//!    gives the run length ARL(h) = values / alarms wherever 30 alarms or more are counted.
//!    A CUSUM's run length grows exponentially with its limit (for normal values, Siegmund's
//!    e^{2k(h + 1.166)}/(2k²); for any light-tailed law, e^{θh} with θ the root of
//!    E e^{θ(v − k)} = 1), so ln ARL is fitted as a straight line in h over the measured
//!    limits with ARL ≥ 50, and extrapolated to the limit that gives the target run length.
//! 3. **Never below the nominal limit**: a bootstrap can draw no value beyond the training
//!    records' largest, so it cannot see a tail heavier than they show; a limit below the
//!    one the normal law asks would trust that. The limit charted is the larger of the two,
//!    and its run length is the one measured at it.
//!
//! The series is drawn from a seed fixed by the values' count, so that the same training
//! records always give the same limit (a run and its resumption agree).

use crate::chart::Cusum;
use rand::{RngExt, SeedableRng, rngs::Xoshiro256PlusPlus};

/// Fewest finite training values for a calibration: below it the nominal limit is used.
pub const FEWEST: usize = 50;

/// Length of the bootstrap series.
const SERIES: usize = 400_000;

/// Fewest alarms for a run length to count as measured.
const COUNTED: usize = 30;

/// Least run length in the fit (below it the exponential law has not set in).
const SHORTEST: f64 = 50.0;

/// Which sides of the CUSUM raise alarms.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum Sides {
    /// Either way (a mode's frequency may rise or fall).
    Both,
    /// Up only (a statistic that a change makes larger).
    Up,
}

/// A chart's limit as calibrated on its training values.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Calibration {
    /// The limit charted: the larger of `nominal_h` and `bootstrap_h`.
    pub h: f64,
    /// The limit for the target run length on independent standard normal values.
    pub nominal_h: f64,
    /// The limit the training values' bootstrap asks for the target run length.
    pub bootstrap_h: f64,
    /// The target: records per false alarm.
    pub target_run_length: f64,
    /// Records per false alarm at `h`, measured on the training values (their bootstrap,
    /// extrapolated as above).
    pub run_length: f64,
    /// At the nominal limit, measured the same way: what the nominal claim would have given.
    pub nominal_run_length: f64,
    /// The training values the bootstrap drew from.
    pub values: usize,
    /// Their lag-one autocorrelation.
    pub lag_one: f64,
    /// The bootstrap's block length.
    pub block: usize,
}

impl Calibration {
    /// The chart with the calibrated limit.
    pub fn chart(&self, chart: &Cusum) -> Cusum {
        Cusum {
            k: chart.k,
            h: self.h,
        }
    }
}

/// The target run length of `chart` on `sides`: its nominal one (Siegmund's, for
/// independent standard normal values; one side alone alarms half as often as both).
pub fn target_run_length(chart: &Cusum, sides: Sides) -> f64 {
    match sides {
        Sides::Both => chart.in_control_run_length(),
        Sides::Up => 2.0 * chart.in_control_run_length(),
    }
}

/// `chart`'s limit calibrated on the training values `values` (NaN values are gaps and
/// passed over) for `chart`'s own nominal run length; `None` with fewer than [`FEWEST`]
/// finite values, or when the run length could not be measured at two limits.
pub fn calibrate(values: &[f64], chart: &Cusum, sides: Sides) -> Option<Calibration> {
    let v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    let m = v.len();
    if m < FEWEST {
        return None;
    }
    let target = target_run_length(chart, sides);
    let (lag_one, tau) = autocorrelation_time(&v);
    let block = ((m as f64).cbrt().ceil() as usize)
        .max((2.0 * tau).ceil() as usize)
        .min(m / 2)
        .max(1);
    let series = block_bootstrap(&v, block, SERIES, m as u64);
    let run_length_at = |h: f64| {
        let alarms = count_alarms(&series, chart.k, h, sides);
        (alarms >= COUNTED).then(|| series.len() as f64 / alarms as f64)
    };
    let mut points = Vec::new();
    let mut h = 1.0;
    while let Some(arl) = run_length_at(h) {
        if arl >= SHORTEST {
            points.push((h, arl.ln()));
        }
        h += 0.5;
        if h > 200.0 {
            break;
        }
    }
    let (a, b) = line(&points)?;
    if b <= 0.0 {
        return None;
    }
    let nominal_h = nominal_limit(chart.k, target, sides);
    let bootstrap_h = (target.ln() - a) / b;
    let h = nominal_h.max(bootstrap_h);
    Some(Calibration {
        h,
        nominal_h,
        bootstrap_h,
        target_run_length: target,
        run_length: (a + b * h).exp(),
        nominal_run_length: (a + b * nominal_h).exp(),
        values: m,
        lag_one,
        block,
    })
}

/// The limit whose Siegmund run length on independent standard normal values is `target`
/// (bisection: the run length grows with h).
fn nominal_limit(k: f64, target: f64, sides: Sides) -> f64 {
    let arl = |h: f64| target_run_length(&Cusum { k, h }, sides);
    let (mut lo, mut hi) = (0.0, 1.0);
    while arl(hi) < target && hi < 1e4 {
        hi *= 2.0;
    }
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if arl(mid) < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The lag-one autocorrelation and the integrated autocorrelation time 1 + 2 Σ ρ_k, summed
/// while ρ_k stays positive (at most m/4 lags).
fn autocorrelation_time(v: &[f64]) -> (f64, f64) {
    let m = v.len();
    let mean = v.iter().sum::<f64>() / m as f64;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / m as f64;
    if var <= 0.0 {
        return (0.0, 1.0);
    }
    let rho = |k: usize| {
        v.iter()
            .zip(&v[k..])
            .map(|(a, b)| (a - mean) * (b - mean))
            .sum::<f64>()
            / (m as f64 * var)
    };
    let mut tau = 1.0;
    for k in 1..=m / 4 {
        let r = rho(k);
        if r <= 0.0 {
            break;
        }
        tau += 2.0 * r;
    }
    (rho(1), tau)
}

/// `length` values made of blocks of `block` consecutive values of `v` (circularly), each
/// starting at a uniformly drawn place, from the seed `seed`.
fn block_bootstrap(v: &[f64], block: usize, length: usize, seed: u64) -> Vec<f64> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0xca1b_0000);
    let m = v.len();
    let mut out = Vec::with_capacity(length + block);
    while out.len() < length {
        let start = rng.random_range(0..m);
        out.extend((0..block).map(|i| v[(start + i) % m]));
    }
    out.truncate(length);
    out
}

/// Alarms of the CUSUM (k, h) over `v`, on `sides`.
fn count_alarms(v: &[f64], k: f64, h: f64, sides: Sides) -> usize {
    Cusum { k, h }
        .alarms(v)
        .iter()
        .filter(|a| sides == Sides::Both || a.side == crate::chart::Side::Up)
        .count()
}

/// The gamma law with the mean and variance of `values` (a statistic's law when nothing
/// changed, fitted to the training records' values: the subspace test's and the joint
/// chart's); `None` when they do not make one.
pub(crate) fn gamma_by_moments(values: &[f64]) -> Option<statrs::distribution::Gamma> {
    let n = values.len() as f64;
    if n < 2.0 {
        return None;
    }
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|t| (t - mean).powi(2)).sum::<f64>() / (n - 1.0);
    statrs::distribution::Gamma::new(mean * mean / var, mean / var).ok()
}

/// The least-squares line y = a + b x through `points`; `None` with fewer than two.
fn line(points: &[(f64, f64)]) -> Option<(f64, f64)> {
    if points.len() < 2 {
        return None;
    }
    let n = points.len() as f64;
    let mx = points.iter().map(|p| p.0).sum::<f64>() / n;
    let my = points.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx = points.iter().map(|p| (p.0 - mx).powi(2)).sum::<f64>();
    let sxy = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum::<f64>();
    if sxx <= 0.0 {
        return None;
    }
    let b = sxy / sxx;
    Some((my - b * mx, b))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_distr::{Distribution, Normal, StudentT};

    fn normal(m: usize, seed: u64) -> Vec<f64> {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let n = Normal::new(0.0, 1.0).unwrap();
        (0..m).map(|_| n.sample(&mut rng)).collect()
    }

    /// On independent standard normal training values the calibration measures about the
    /// nominal run length at the nominal limit, and keeps that limit.
    #[test]
    fn normal_values_keep_the_nominal_limit() {
        let chart = Cusum::default();
        let mut ratios = Vec::new();
        for seed in 0..8 {
            let c = calibrate(&normal(336, 8_500_001 + seed), &chart, Sides::Both).unwrap();
            assert!((c.nominal_h - 12.0).abs() < 0.05, "{c:?}");
            assert!(c.h >= c.nominal_h);
            ratios.push(c.nominal_run_length / c.target_run_length);
        }
        ratios.sort_by(f64::total_cmp);
        // The median over 8 sets of 336 values: the bootstrap of 336 values carries their
        // sample's mean and spread (±5 % in SD), each a factor of about e^{±1.2} in the run
        // length at h = 12 (ln ARL ≈ 2k·h·σ⁻² for a spread σ); the median within a factor 4.
        let median = ratios[4];
        assert!((0.25..4.0).contains(&median), "{ratios:?}");
    }

    /// Values correlated from record to record (a first-order autoregression, φ = 0.9: a
    /// slow effect left in them) are calibrated to a far higher limit: the nominal limit's
    /// run length measured on them is a small share of its claim, and at the limit charted
    /// a fresh series of the same process alarms about as rarely as the target says (a
    /// simulation of 4·10⁷ values, independent of the bootstrap).
    #[test]
    fn correlated_values_raise_the_limit_to_their_run_length() {
        let phi: f64 = 0.9;
        let ar = |m: usize, seed: u64| {
            let e = normal(m, seed);
            let mut x = 0.0;
            let s = (1.0 - phi * phi).sqrt();
            e.iter()
                .map(|e| {
                    x = phi * x + s * e;
                    x
                })
                .collect::<Vec<f64>>()
        };
        // A shorter target for the check's sake (k = 0.5, h = 6: about 2600 values).
        let chart = Cusum::new(0.5, 6.0).unwrap();
        let c = calibrate(&ar(2000, 8_500_101), &chart, Sides::Both).unwrap();
        assert!(c.lag_one > 0.8, "{c:?}");
        assert!(c.block >= 19, "{c:?}");
        assert!(c.nominal_run_length < 0.05 * c.target_run_length, "{c:?}");
        assert!(c.h > 3.0 * c.nominal_h, "{c:?}");
        let fresh = ar(40_000_000, 8_500_102);
        let alarms = count_alarms(&fresh, chart.k, c.h, Sides::Both);
        let measured = fresh.len() as f64 / alarms.max(1) as f64;
        // 2000 training values hold ~100 correlation times: the limit's run length is
        // uncertain by a factor of about 2 either way.
        assert!(
            (0.3..3.0).contains(&(measured / c.target_run_length)),
            "{measured} against {} ({c:?})",
            c.target_run_length
        );
    }

    /// A heavy tail (Student's t with 3 degrees of freedom, scaled to unit variance) raises
    /// the limit above the nominal one; too few values give no calibration.
    #[test]
    fn a_heavy_tail_raises_the_limit_and_few_values_give_none() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(8_500_201);
        let t = StudentT::new(3.0).unwrap();
        let v: Vec<f64> = (0..2000)
            .map(|_| t.sample(&mut rng) / 3f64.sqrt())
            .collect();
        let chart = Cusum::default();
        let c = calibrate(&v, &chart, Sides::Both).unwrap();
        assert!(c.bootstrap_h > c.nominal_h, "{c:?}");
        assert!(calibrate(&v[..FEWEST - 1], &chart, Sides::Both).is_none());
        // The upper side alone alarms half as often: its target is twice both sides', met
        // at the same nominal limit.
        let up = calibrate(&normal(336, 8_500_202), &chart, Sides::Up).unwrap();
        assert!(up.target_run_length > 2.0 * 5.0e5, "{up:?}");
        assert!((up.nominal_h - 12.0).abs() < 0.05, "{up:?}");
    }
}
