//! The modes judged together: what the modes' residuals share, set apart, and what is left
//! of them charted as one statistic.
//!
//! A structure's modes feel one environment, and what the covariates leave unexplained of
//! it is often common to them all (a slow effect of moisture, a support stiffened by frost
//! beyond what the temperature says): charted mode by mode, each chart meets it alone, and
//! alarms. Here every record's standardized residuals z = (z₁ … z_p) of the p modes with a
//! baseline are judged together. [`crate::track()`] gives them from a baseline of each mode on
//! the same regressors, the union of the modes' environmental models' terms
//! ([`crate::environment`]): a term one mode's model took for an effect the modes share (a
//! breakpoint fitted to an episode of it) is then taken by every mode in its own proportion,
//! and what it predicts after training stays along the shared direction instead of leaving
//! one mode's residual off the pattern (on the shared-effect campaigns, 37 false alarms in
//! 20 campaigns before, none after). Then:
//!
//! 1. **The common factors, from the training records**: the residuals' mean μ and
//!    correlation matrix R = D^{−½} S D^{−½} (S their covariance, D its diagonal) over the
//!    training records that hold every mode; R = Σ λ_k e_k e_kᵀ. Independent residuals would
//!    give eigenvalues within Marchenko and Pastur's edge (1 + √(p/m))² for m records; each
//!    eigenvalue above it is a factor the modes share (at most p − 1 of them).
//! 2. **What they do not explain**: with u = D^{−½}(z − μ) and the common factors' directions
//!    e₁ … e_c set apart, Q = Σ_{k > c} (e_kᵀu)²/λ_k, Hotelling's T² of the components the
//!    factors leave: χ² with p − c degrees of freedom for normal residuals. A change of one
//!    mode moves u along that mode's axis, most of which lies outside the common directions
//!    (they load every mode); an effect the modes share moves u along them and leaves Q.
//!    With no common factor, Q is the T² of all the residuals.
//! 3. **Charted as the subspace test is**: Q through the gamma law fitted by moments to the
//!    training records' Q, to a standard normal score, and into the CUSUM's upper side, its
//!    limit calibrated on the training scores ([`crate::calibration`]).
//! 4. **The modes that drive an alarm**: Q = Σ_j c_j with c_j = u_j (W u)_j,
//!    W = Σ_{k > c} e_k e_kᵀ/λ_k; over the records of the run that raised an alarm, each
//!    mode's share of what the modes added (Σ_t c_j, a negative sum counting none) is
//!    reported, largest first.
//!
//! What the joint chart cannot see is a change along a common factor (every mode moving in
//! the training period's common proportion: a change of the whole structure's stiffness);
//! the modes' own charts still watch for it.

use crate::MonitorError;
use crate::calibration::{self, Calibration, Sides};
use crate::chart::{Cusum, Side};
use nalgebra::{DMatrix, DVector};
use statrs::distribution::{ContinuousCDF, Normal};

/// An alarm of the joint chart.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct JointAlarm {
    /// The record that raised it (0-based, among the campaign's).
    pub record: usize,
    /// Its time (s).
    pub time: f64,
    /// The modes (0-based) and their shares of the statistic over the run that raised it
    /// (of the positive parts; summing to 1), largest first.
    pub drivers: Vec<(usize, f64)>,
}

/// The joint chart over a campaign.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct JointChart {
    /// The modes judged (0-based; those with a baseline).
    pub modes: Vec<usize>,
    /// The eigenvalues of the training residuals' correlation matrix, largest first.
    pub eigenvalues: Vec<f64>,
    /// Marchenko and Pastur's edge for independent residuals, (1 + √(p/m))².
    pub noise_edge: f64,
    /// The factors the modes share (eigenvalues above the edge).
    pub common_factors: usize,
    /// Each common factor's direction over the modes (unit length, in `modes`' order).
    pub loadings: Vec<Vec<f64>>,
    /// The records before charting (the training period).
    pub training: usize,
    /// Those of them that held every mode, which the model was fitted on.
    pub trained_on: usize,
    /// Each record's time (s).
    pub time: Vec<f64>,
    /// Each record's statistic Q (NaN where a mode is missing).
    pub statistic: Vec<f64>,
    /// Its score (standard normal when nothing changed), charted.
    pub score: Vec<f64>,
    /// The chart's limit, calibrated on the training scores (`None`: too few, the nominal
    /// limit used).
    pub calibration: Option<Calibration>,
    /// The limit charted.
    pub limit: f64,
    /// The alarms, in time order.
    pub alarms: Vec<JointAlarm>,
}

/// The joint chart of the modes' standardized residuals `z` (`z[j][t]`: mode j, record t;
/// NaN where record t has no residual of mode j; a mode whose values are all NaN, one without
/// a baseline, is left out), the records at `time` (s), the first `training` train it,
/// charted by `chart`'s upper side with its limit calibrated on the training scores when
/// `calibrate`.
pub fn joint_chart(
    z: &[Vec<f64>],
    time: &[f64],
    training: usize,
    chart: &Cusum,
    calibrate: bool,
) -> Result<JointChart, MonitorError> {
    let modes: Vec<usize> = (0..z.len())
        .filter(|&j| z[j].iter().any(|v| v.is_finite()))
        .collect();
    let p = modes.len();
    if p < 2 {
        return Err(MonitorError::TooFewModesForJoint { modes: p });
    }
    let records = time.len();
    let training = training.min(records);
    let row = |t: usize| -> Option<DVector<f64>> {
        let v: Vec<f64> = modes
            .iter()
            .map(|&j| z[j].get(t).copied().unwrap_or(f64::NAN))
            .collect();
        v.iter()
            .all(|x| x.is_finite())
            .then(|| DVector::from_vec(v))
    };
    let train: Vec<DVector<f64>> = (0..training).filter_map(row).collect();
    let m = train.len();
    if m < FEWEST.max(5 * p) {
        return Err(MonitorError::TooFewForJoint {
            records: m,
            modes: p,
        });
    }
    let model = Model::fit(&train)?;
    let statistic: Vec<f64> = (0..records)
        .map(|t| row(t).map_or(f64::NAN, |v| model.statistic(&v)))
        .collect();
    let train_q: Vec<f64> = train.iter().map(|v| model.statistic(v)).collect();
    let law = calibration::gamma_by_moments(&train_q).ok_or(MonitorError::Collinear)?;
    let normal = Normal::standard();
    let score: Vec<f64> = statistic
        .iter()
        .map(|&q| {
            if q.is_finite() {
                normal.inverse_cdf(law.cdf(q)).clamp(-8.0, 8.0)
            } else {
                f64::NAN
            }
        })
        .collect();
    let calibration = if calibrate {
        calibration::calibrate(&score[..training], chart, Sides::Up)
    } else {
        None
    };
    let used = calibration.as_ref().map_or(*chart, |c| c.chart(chart));
    let alarms = used
        .runs(&score[training..])
        .into_iter()
        .filter(|(a, _)| a.side == Side::Up)
        .map(|(a, from)| {
            let record = training + a.index;
            let mut share = vec![0.0; p];
            for t in training + from..=record {
                if let Some(v) = row(t) {
                    for (s, c) in share.iter_mut().zip(model.contributions(&v)) {
                        *s += c;
                    }
                }
            }
            // Shares of what the modes added (a mode whose part was negative, one that
            // moved against the others' pattern less than the model expects, adds none).
            let total: f64 = share.iter().map(|s| s.max(0.0)).sum();
            let mut drivers: Vec<(usize, f64)> = modes
                .iter()
                .zip(&share)
                .map(|(&j, &s)| (j, if total > 0.0 { s.max(0.0) / total } else { 0.0 }))
                .collect();
            drivers.sort_by(|a, b| b.1.total_cmp(&a.1));
            JointAlarm {
                record,
                time: time[record],
                drivers,
            }
        })
        .collect();
    Ok(JointChart {
        modes,
        eigenvalues: model.eigenvalues.clone(),
        noise_edge: model.edge,
        common_factors: model.common,
        loadings: (0..model.common)
            .map(|k| model.axes.column(k).iter().copied().collect())
            .collect(),
        training,
        trained_on: m,
        time: time.to_vec(),
        statistic,
        score,
        limit: used.h,
        calibration,
        alarms,
    })
}

/// Fewest complete training records for the joint model.
const FEWEST: usize = 20;

/// The residuals' joint model over the training records.
struct Model {
    mean: DVector<f64>,
    /// D^{−½}: each mode's inverse standard deviation.
    scale: DVector<f64>,
    /// The correlation matrix's eigenvectors, as columns, largest eigenvalue first.
    axes: DMatrix<f64>,
    eigenvalues: Vec<f64>,
    edge: f64,
    common: usize,
    /// W = Σ_{k > c} e_k e_kᵀ / λ_k.
    weight: DMatrix<f64>,
}

impl Model {
    fn fit(train: &[DVector<f64>]) -> Result<Model, MonitorError> {
        let m = train.len();
        let p = train[0].len();
        let mut mean = DVector::<f64>::zeros(p);
        for v in train {
            mean += v;
        }
        mean /= m as f64;
        let mut cov = DMatrix::<f64>::zeros(p, p);
        for v in train {
            let d = v - &mean;
            cov += &d * d.transpose();
        }
        cov /= (m - 1) as f64;
        let scale = cov
            .diagonal()
            .map(|v| if v > 0.0 { 1.0 / v.sqrt() } else { 0.0 });
        if scale.iter().any(|&s| s == 0.0 || !s.is_finite()) {
            return Err(MonitorError::Collinear);
        }
        let corr = DMatrix::from_fn(p, p, |a, b| cov[(a, b)] * scale[a] * scale[b]);
        let eig = corr.symmetric_eigen();
        let mut order: Vec<usize> = (0..p).collect();
        order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
        let eigenvalues: Vec<f64> = order.iter().map(|&i| eig.eigenvalues[i]).collect();
        if eigenvalues[p - 1] <= 1e-9 * eigenvalues[0] {
            return Err(MonitorError::Collinear);
        }
        let axes = DMatrix::from_columns(
            &order
                .iter()
                .map(|&i| eig.eigenvectors.column(i).into_owned())
                .collect::<Vec<_>>(),
        );
        let edge = (1.0 + (p as f64 / m as f64).sqrt()).powi(2);
        let common = eigenvalues
            .iter()
            .take(p - 1)
            .take_while(|&&l| l > edge)
            .count();
        let mut weight = DMatrix::<f64>::zeros(p, p);
        for (k, l) in eigenvalues.iter().enumerate().skip(common) {
            let e = axes.column(k);
            weight += e * e.transpose() / *l;
        }
        Ok(Model {
            mean,
            scale,
            axes,
            eigenvalues,
            edge,
            common,
            weight,
        })
    }

    fn standardized(&self, v: &DVector<f64>) -> DVector<f64> {
        (v - &self.mean).component_mul(&self.scale)
    }

    /// Q = uᵀ W u.
    fn statistic(&self, v: &DVector<f64>) -> f64 {
        let u = self.standardized(v);
        u.dot(&(&self.weight * &u))
    }

    /// Each mode's part of Q, c_j = u_j (W u)_j.
    fn contributions(&self, v: &DVector<f64>) -> Vec<f64> {
        let u = self.standardized(v);
        let wu = &self.weight * &u;
        u.iter().zip(wu.iter()).map(|(a, b)| a * b).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{SeedableRng, rngs::Xoshiro256PlusPlus};
    use rand_distr::{Distribution, Normal as N};

    /// Four modes' residuals sharing a slow factor (a first-order autoregression with a
    /// correlation time of a day of hourly records, loading the modes 1, 0.9, 0.8, 0.7 and
    /// three times each mode's own white residual), mode `changed` moved by `step` standard
    /// deviations of its own residual from record `from`.
    fn residuals(
        records: usize,
        seed: u64,
        changed: usize,
        step: f64,
        from: usize,
    ) -> Vec<Vec<f64>> {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let n = N::new(0.0, 1.0).unwrap();
        let phi = (-1.0f64 / 24.0).exp();
        let loadings = [1.0, 0.9, 0.8, 0.7];
        let mut g = 0.0;
        let mut z: Vec<Vec<f64>> = (0..4).map(|_| Vec::with_capacity(records)).collect();
        for t in 0..records {
            g = phi * g + (1.0 - phi * phi).sqrt() * n.sample(&mut rng);
            for (j, zj) in z.iter_mut().enumerate() {
                let shift = if j == changed && t >= from { step } else { 0.0 };
                zj.push(3.0 * loadings[j] * g + n.sample(&mut rng) + shift);
            }
        }
        z
    }

    /// The shared slow factor is found (one eigenvalue above the edge, loading every mode
    /// alike), the joint chart raises no alarm over 2000 undamaged records after 336 of
    /// training, while a CUSUM of any one mode's residuals alone alarms again and again;
    /// a step of three standard deviations of its own residual in mode 2 (a 0.3 % change
    /// against a 10-minute record's 0.1 % estimation error) is alarmed within a day, mode 2
    /// named as the first driver. (A step of one standard deviation took 59 records on
    /// this seed: Q pools p − c = 3 components, so a shift along one of them moves its
    /// score by a third of a standard deviation or so.)
    #[test]
    fn a_shared_slow_effect_is_set_apart_and_a_change_of_one_mode_found() {
        let records = 336 + 2000 + 100;
        let z = residuals(records, 8_500_301, 2, -3.0, 336 + 2000);
        let time: Vec<f64> = (0..records).map(|t| 3600.0 * t as f64).collect();
        let c = joint_chart(&z, &time, 336, &Cusum::default(), true).unwrap();
        assert_eq!(
            c.common_factors, 1,
            "{:?} edge {}",
            c.eigenvalues, c.noise_edge
        );
        // The factor loads every mode with one sign and about alike (1, 0.9, 0.8, 0.7
        // times three against unit noise: correlations 0.9 and more).
        let l = &c.loadings[0];
        assert!(l.iter().all(|&x| x * l[0] > 0.0 && x.abs() > 0.35), "{l:?}");
        let first = c.alarms.first().expect("the change alarmed");
        assert!(
            first.record >= 336 + 2000 && first.record < 336 + 2000 + 24,
            "{:?}",
            c.alarms
        );
        assert_eq!(first.drivers[0].0, 2, "{:?}", first.drivers);
        // Mode by mode, the shared factor alarms before the change.
        let alone = Cusum::default().alarms(&z[0][336..336 + 2000]).len();
        assert!(alone >= 5, "{alone}");
    }

    /// Independent residuals: no common factor; Q is the T² of all four; too few modes or
    /// records are said.
    #[test]
    fn independent_residuals_have_no_common_factor() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(8_500_302);
        let n = N::new(0.0, 1.0).unwrap();
        let z: Vec<Vec<f64>> = (0..4)
            .map(|_| (0..600).map(|_| n.sample(&mut rng)).collect())
            .collect();
        let time: Vec<f64> = (0..600).map(|t| t as f64).collect();
        let c = joint_chart(&z, &time, 336, &Cusum::default(), true).unwrap();
        assert_eq!(c.common_factors, 0, "{:?}", c.eigenvalues);
        let mean_q = c.statistic[336..].iter().sum::<f64>() / 264.0;
        // χ² with 4 degrees of freedom: mean 4, the mean of 264 within ±0.5 (SD 0.17).
        assert!((mean_q - 4.0).abs() < 0.5, "{mean_q}");
        assert!(c.alarms.is_empty(), "{:?}", c.alarms);
        let e = joint_chart(&z[..1], &time, 336, &Cusum::default(), true).unwrap_err();
        assert!(
            matches!(e, MonitorError::TooFewModesForJoint { modes: 1 }),
            "{e}"
        );
        let e = joint_chart(&z, &time, 10, &Cusum::default(), true).unwrap_err();
        assert!(
            matches!(
                e,
                MonitorError::TooFewForJoint {
                    records: 10,
                    modes: 4
                }
            ),
            "{e}"
        );
    }
}
