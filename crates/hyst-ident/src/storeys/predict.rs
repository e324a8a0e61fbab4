//! What the fitted structure predicts at a force level no record was taken at: each mode
//! band's centroid, spread and power at every channel, and each storey's RMS drift, read
//! from simulated records exactly as the fit read the measured ones.
//!
//! A prediction has two uncertainties. A record's own: the spread of the statistics over
//! replicates of the model (forces drawn afresh), what a record of that length would show
//! around the prediction even if the model were true. The parameters': by the delta method,
//! $\sigma^2_i = g_i^\top C g_i$ with $C$ the fit's covariance and $g_i$ the statistic's
//! derivative in the parameters, differenced under common random numbers (the same forces
//! at every parameter set, so the derivative is the model's and not the replicates' noise).
//! [`LevelPrediction::z_scores`] combines both against a measured record.

use rayon::prelude::*;

use hyst_sim::building::{Reading as Quantity, ShearBuilding};

use super::document::inconsistent;
use super::error::StoreyError;
use super::model::{self, Layout};
use super::statistics::{self, Reading, Simulator};
use super::types::{LevelStatistics, StoreyFit};
use crate::IdentError;

/// Options of [`predict_level`].
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
#[non_exhaustive]
pub struct PredictionOptions {
    /// Simulated records behind the prediction (their mean) and a record's spread. Default 16.
    pub replicates: usize,
    /// Seed of their forces. Default 9300.
    pub seed: u64,
}

impl Default for PredictionOptions {
    fn default() -> Self {
        PredictionOptions {
            replicates: 16,
            seed: 9300,
        }
    }
}

/// The fitted structure's response at a force level of its choosing.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct LevelPrediction {
    /// The force density asked for (N²/Hz, two-sided, on each loaded floor).
    pub force_density: f64,
    /// The record length predicted (samples).
    pub samples: usize,
    /// Replicates averaged.
    pub replicates: usize,
    /// The statistics, the mean over the replicates; `se` is one record's spread around it.
    pub statistics: LevelStatistics,
    /// Each statistic's standard error from the parameters' covariance (the order of
    /// `statistics.se`).
    #[cfg_attr(feature = "serde", serde(with = "crate::nullable"))]
    pub parameters_se: Vec<f64>,
    /// Each storey's RMS drift (m), storey 1 (ground to first floor) first.
    pub drift_rms: Vec<f64>,
}

impl LevelPrediction {
    /// A measured record's statistics (read by [`level_statistics`]) against the prediction:
    /// each difference over the standard deviation of the record's own spread, the
    /// prediction's (a mean of `replicates`) and the parameters', in the order of
    /// [`LevelStatistics::se`].
    pub fn z_scores(&self, measured: &LevelStatistics) -> Vec<f64> {
        let m = statistics::vector(measured);
        let p = statistics::vector(&self.statistics);
        let r = self.replicates.max(1) as f64;
        m.iter()
            .zip(&p)
            .zip(self.statistics.se.iter().zip(&self.parameters_se))
            .map(|((m, p), (s, g))| (m - p) / (s * s * (1.0 + 1.0 / r) + g * g).sqrt())
            .collect()
    }
}

/// The fit's model taken apart again: what simulating and reading it needs.
struct Rebuilt {
    reading: Reading,
    sim: Simulator,
    layout: Layout,
    template: ShearBuilding,
    theta: Vec<f64>,
    nu: f64,
    channels: usize,
}

fn rebuild(fit: &StoreyFit, seed: u64) -> Result<Rebuilt, IdentError> {
    fit.validate()?;
    let b = &fit.building;
    let floors = b.masses.len();
    let channels = b.sensors.len();
    let layout = Layout {
        floors,
        levels: fit.force_densities.len(),
        storey: fit.storey,
        folded: b.reading == Quantity::Acceleration,
    };
    let r = &fit.reading;
    let template = model::template(&b.masses, &b.sensors, b.reading, b.fs, &fit.load_floors);
    let nu = b.hysteresis.as_ref().map_or(1.0, |h| h.nu);
    Ok(Rebuilt {
        reading: Reading {
            fs: b.fs,
            segment: r.segment,
            edges: r.bands_hz.clone(),
        },
        sim: Simulator::new(
            (floors, channels),
            fit.load_floors.clone(),
            (r.steps_per_sample, r.warm_up),
            &[],
            seed,
        ),
        layout,
        template,
        theta: fit.parameters.iter().map(|p| p.value).collect(),
        nu,
        channels,
    })
}

/// A record's statistics read as `fit` read its levels (the same bands and segments), to
/// set beside a [`LevelPrediction`]: `record` holds one vector per channel, the channels in
/// the fit's order.
pub fn level_statistics(
    fit: &StoreyFit,
    record: &[Vec<f64>],
) -> Result<LevelStatistics, IdentError> {
    let r = rebuild(fit, 0)?;
    if record.len() != r.channels {
        return Err(StoreyError::ChannelCount {
            level: 1,
            channels: record.len(),
            sensors: r.channels,
        }
        .into());
    }
    let needed = 3 * r.reading.segment;
    let first = record[0].len();
    for (c, y) in record.iter().enumerate() {
        if y.len() != first || y.len() < needed || y.iter().any(|v| !v.is_finite()) {
            return Err(StoreyError::BadLength {
                level: 1,
                channel: c + 1,
                samples: y.len(),
                first,
                needed,
            }
            .into());
        }
    }
    Ok(statistics::level(
        &r.reading.of(record),
        (r.layout.floors, r.channels),
        vec![],
    ))
}

/// Whether `record`'s statistics (read by [`level_statistics`]) are the fit's level
/// `level` (0-based): within chance of that level's measured statistics (the whitened
/// squared distance under the 99.9 % point of 2χ²_d, two records' noise, d statistics) and
/// nearer it than any other level. A record given in another order, read as another
/// quantity, or with its channels on other floors is refused.
pub fn check_level(
    fit: &StoreyFit,
    level: usize,
    record: &LevelStatistics,
) -> Result<(), IdentError> {
    use statrs::distribution::{ChiSquared, ContinuousCDF};
    let given = statistics::vector(record);
    let distance = |l: &LevelStatistics| -> f64 {
        given
            .iter()
            .zip(statistics::vector(l))
            .zip(&l.se)
            .map(|((a, b), se)| ((a - b) / se).powi(2))
            .sum()
    };
    let Some(own) = fit.measured.get(level) else {
        return Ok(());
    };
    let d = own.se.len() as f64;
    let limit = 2.0
        * ChiSquared::new(d).map_or(f64::NAN, |c| c.inverse_cdf(1.0 - super::agreement::CHANCE));
    let here = distance(own);
    let nearest = fit
        .measured
        .iter()
        .enumerate()
        .map(|(j, l)| (j, distance(l)))
        .min_by(|a, b| a.1.total_cmp(&b.1));
    let closest = match nearest {
        Some((j, dj)) if j != level && dj < here => format!(", but as its level {}", j + 1),
        _ => String::new(),
    };
    if here <= limit && closest.is_empty() {
        return Ok(());
    }
    Err(StoreyError::NotItsLevel {
        record: level + 1,
        closest,
        distance: here,
        limit,
    }
    .into())
}

/// What the fitted structure shows at force density `force_density` (N²/Hz, two-sided, on
/// each loaded floor: a recorded level's is in [`StoreyFit::force_densities`], and a force
/// σ times as strong has σ² times the density) in a record of `samples` samples: the mean of
/// `opts.replicates` simulated records' statistics, one record's spread, the parameters'
/// share of the uncertainty, and each storey's RMS drift.
pub fn predict_level(
    fit: &StoreyFit,
    force_density: f64,
    samples: usize,
    opts: &PredictionOptions,
) -> Result<LevelPrediction, IdentError> {
    if !(force_density > 0.0 && force_density.is_finite()) {
        return Err(StoreyError::Unphysical {
            name: "the force density (N²/Hz)",
            value: force_density,
        }
        .into());
    }
    let r = rebuild(fit, opts.seed)?;
    let needed = 3 * r.reading.segment;
    if samples < needed {
        return Err(StoreyError::TooShort { samples, needed }.into());
    }
    let count = opts.replicates.max(3);
    let seeds: Vec<u64> = (0..count as u64)
        .map(|i| opts.seed.wrapping_add(i))
        .collect();
    // Every replicate's statistics at θ (the same forces for every θ).
    let at = |theta: &[f64]| -> Result<Vec<Vec<f64>>, IdentError> {
        let (b, _, folded) = model::building(&r.template, &r.layout, theta, r.nu)?;
        seeds
            .par_iter()
            .map(|&s| {
                let y = r.sim.replicate(&b, samples, (force_density, folded), s)?;
                Ok(r.reading.of(&y))
            })
            .collect()
    };
    let base = at(&r.theta)?;
    let d = base[0].len();
    let mean = |stats: &[Vec<f64>]| -> Vec<f64> {
        (0..d)
            .map(|k| stats.iter().map(|s| s[k]).sum::<f64>() / stats.len() as f64)
            .collect()
    };
    let centre = mean(&base);
    let spread: Vec<f64> = (0..d)
        .map(|k| {
            let v = base.iter().map(|s| (s[k] - centre[k]).powi(2)).sum::<f64>();
            (v / (count - 1) as f64).sqrt()
        })
        .collect();
    let gradient = gradient(&r, &at, &mean, &centre)?;
    let parameters_se = (0..d)
        .map(|i| {
            let mut v = 0.0;
            for (a, ga) in &gradient {
                for (b, gb) in &gradient {
                    v += ga[i] * fit.covariance[*a][*b] * gb[i];
                }
            }
            v.max(0.0).sqrt()
        })
        .collect();
    let drift_rms = drifts(&r, force_density, samples, &seeds)?;
    // A number that is not one is not a prediction (said as not predicted, by the caller).
    if let Some((s, d)) = drift_rms.iter().enumerate().find(|(_, d)| !d.is_finite()) {
        return Err(StoreyError::NotFinite {
            what: format!("storey {}'s predicted drift is {d}", s + 1),
        }
        .into());
    }
    if let Some(v) = centre.iter().chain(&spread).find(|v| !v.is_finite()) {
        return Err(StoreyError::NotFinite {
            what: format!("a predicted statistic is {v}"),
        }
        .into());
    }
    Ok(LevelPrediction {
        force_density,
        samples,
        replicates: count,
        statistics: statistics::level(&centre, (r.layout.floors, r.channels), spread),
        parameters_se,
        drift_rms,
    })
}

/// Every replicate's statistics at a parameter vector.
type Statistics<'a> = dyn Fn(&[f64]) -> Result<Vec<Vec<f64>>, IdentError> + Sync + 'a;

/// Each parameter's derivative of the mean statistics (the levels' densities left out: a
/// prediction has its own), by a step of 1 % of the parameter (β and γ: of the larger),
/// forward unless that leaves the model's range.
fn gradient(
    r: &Rebuilt,
    at: &Statistics<'_>,
    mean: &dyn Fn(&[Vec<f64>]) -> Vec<f64>,
    centre: &[f64],
) -> Result<Vec<(usize, Vec<f64>)>, IdentError> {
    let n = r.layout.floors;
    let densities = 2 * n..2 * n + r.layout.levels;
    let np = r.theta.len();
    let element_scale = match r.layout.storey {
        Some(_) => r.theta[np - 2].abs().max(r.theta[np - 1].abs()),
        None => 0.0,
    };
    let mut out = Vec::new();
    for k in (0..np).filter(|k| !densities.contains(k)) {
        let is_element_rate = r.layout.storey.is_some() && k >= np - 2;
        let size = if is_element_rate {
            element_scale
        } else {
            r.theta[k].abs()
        };
        let h = 1e-2 * if size > 0.0 { size } else { 1.0 };
        let mut moved = None;
        for step in [h, -h] {
            let mut theta = r.theta.clone();
            theta[k] += step;
            match at(&theta) {
                Ok(stats) => {
                    moved = Some((step, mean(&stats)));
                    break;
                }
                Err(IdentError::Storey(StoreyError::Unphysical { .. })) => continue,
                Err(e) => return Err(e),
            }
        }
        // A parameter at both ends of its range at once has no derivative to give.
        if let Some((step, m)) = moved {
            out.push((
                k,
                m.iter().zip(centre).map(|(a, b)| (a - b) / step).collect(),
            ));
        }
    }
    Ok(out)
}

/// Records of the fitted structure at each recorded level (its fitted force density and,
/// for accelerations, the folded band), `lengths[l]` samples for level `l`, forces drawn
/// from `seed` (level l from seed + l): what the fitted model says the records are, to be
/// analysed exactly as the measured ones (e.g. their amplitude curves set beside theirs).
pub fn model_records(
    fit: &StoreyFit,
    lengths: &[usize],
    seed: u64,
) -> Result<Vec<Vec<Vec<f64>>>, IdentError> {
    let r = rebuild(fit, seed)?;
    if lengths.len() != fit.force_densities.len() {
        return Err(inconsistent(format!(
            "{} records asked for; the fit has {} levels",
            lengths.len(),
            fit.force_densities.len()
        )));
    }
    let (b, q, folded) = model::building(&r.template, &r.layout, &r.theta, r.nu)?;
    lengths
        .par_iter()
        .enumerate()
        .map(|(l, &n)| {
            r.sim
                .replicate(&b, n, (q[l], folded), seed.wrapping_add(l as u64))
        })
        .collect()
}

/// Each storey's RMS drift (m), the mean over the replicates' forces.
fn drifts(
    r: &Rebuilt,
    force_density: f64,
    samples: usize,
    seeds: &[u64],
) -> Result<Vec<f64>, IdentError> {
    let (mut b, _, _) = model::building(&r.template, &r.layout, &r.theta, r.nu)?;
    let floors = r.layout.floors;
    b.reading = Quantity::Displacement;
    b.sensors = (0..floors).collect();
    let per: Vec<Vec<f64>> = seeds
        .par_iter()
        .map(|&s| {
            let x = r.sim.replicate(&b, samples, (force_density, 0.0), s)?;
            Ok((0..floors)
                .map(|i| {
                    let below = |t: usize| if i > 0 { x[i - 1][t] } else { 0.0 };
                    let ms = (0..x[i].len())
                        .map(|t| (x[i][t] - below(t)).powi(2))
                        .sum::<f64>()
                        / x[i].len() as f64;
                    ms.sqrt()
                })
                .collect())
        })
        .collect::<Result<_, IdentError>>()?;
    Ok((0..floors)
        .map(|i| per.iter().map(|d| d[i]).sum::<f64>() / per.len() as f64)
        .collect())
}

#[cfg(test)]
pub(crate) mod tests_support {
    use super::*;
    use crate::storeys::types::{StoreyParameter, StoreyReading};

    /// A linear two-floor structure's fit as the fit would report it (no uncertainty).
    pub(crate) fn linear_fit(masses: [f64; 2], k: [f64; 2], zeta: [f64; 2], q: f64) -> StoreyFit {
        two_floor_fit(masses, &[k[0], k[1], zeta[0], zeta[1], q], None)
    }

    /// The two-floor structure of `theta` (the layout's order: k, ζ, q, then a, β, γ of
    /// an element in `storey`) as the fit would report it (no uncertainty).
    pub(crate) fn two_floor_fit(
        masses: [f64; 2],
        theta: &[f64],
        storey: Option<usize>,
    ) -> StoreyFit {
        let fs = 100.0;
        let template = model::template(&masses, &[0, 1], Quantity::Displacement, fs, &[0, 1]);
        let layout = Layout {
            floors: 2,
            levels: 1,
            storey,
            folded: false,
        };
        let theta = theta.to_vec();
        let p = theta.len();
        let (building, _, _) = model::building(&template, &layout, &theta, 1.0).unwrap();
        StoreyFit {
            storey,
            building,
            force_densities: vec![theta[4]],
            load_floors: vec![0, 1],
            parameters: layout
                .names()
                .into_iter()
                .zip(theta)
                .map(|(name, value)| StoreyParameter {
                    name,
                    value,
                    se: 0.0,
                })
                .collect(),
            candidates: vec![],
            element_evidence: None,
            measured: vec![],
            simulated: vec![],
            predictions: vec![],
            not_predicted: vec![],
            covariance: vec![vec![0.0; p]; p],
            reading: StoreyReading {
                bands_hz: vec![2.0, 12.0, 40.0],
                segment: 512,
                steps_per_sample: 8,
                warm_up: 500,
            },
            residual_rms: 0.0,
            iterations: 0,
            agreement: Default::default(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::tests_support::linear_fit;
    use super::*;
    use nalgebra::{DMatrix, SymmetricEigen};

    /// The drifts' variances of a linear chain under white forces, from the Lyapunov
    /// equation $AP + PA^\top + BQB^\top = 0$ of its state space (classical damping built from
    /// the modes), solved by its Kronecker form: an answer that shares nothing with the
    /// simulator but the structure.
    fn lyapunov_drifts(masses: [f64; 2], k: [f64; 2], zeta: [f64; 2], q: f64) -> Vec<f64> {
        let m = DMatrix::from_diagonal(&nalgebra::DVector::from_row_slice(&masses));
        let kk = DMatrix::from_row_slice(2, 2, &[k[0] + k[1], -k[1], -k[1], k[1]]);
        let inv = DMatrix::from_fn(
            2,
            2,
            |i, j| if i == j { 1.0 / masses[i].sqrt() } else { 0.0 },
        );
        let e = SymmetricEigen::new(&inv * &kk * &inv);
        let mut order = [0, 1];
        order.sort_by(|&a, &b| e.eigenvalues[a].total_cmp(&e.eigenvalues[b]));
        let phi = DMatrix::from_fn(2, 2, |r, c| inv[(r, r)] * e.eigenvectors[(r, order[c])]);
        let d = DMatrix::from_fn(2, 2, |i, j| {
            if i == j {
                2.0 * zeta[i] * e.eigenvalues[order[i]].sqrt()
            } else {
                0.0
            }
        });
        let c = &m * &phi * d * phi.transpose() * &m;
        let minv = m.clone().try_inverse().unwrap();
        let mut a = DMatrix::zeros(4, 4);
        a.view_mut((0, 2), (2, 2))
            .copy_from(&DMatrix::identity(2, 2));
        a.view_mut((2, 0), (2, 2)).copy_from(&(-&minv * kk));
        a.view_mut((2, 2), (2, 2)).copy_from(&(-&minv * c));
        let mut b = DMatrix::zeros(4, 2);
        b.view_mut((2, 0), (2, 2)).copy_from(&minv);
        let rhs = -(&b * q * b.transpose());
        let eye = DMatrix::<f64>::identity(4, 4);
        let big = eye.kronecker(&a) + a.kronecker(&eye);
        let p = big
            .lu()
            .solve(&nalgebra::DVector::from_column_slice(rhs.as_slice()))
            .unwrap();
        let p = DMatrix::from_column_slice(4, 4, p.as_slice());
        vec![
            p[(0, 0)].sqrt(),
            (p[(1, 1)] - 2.0 * p[(0, 1)] + p[(0, 0)]).sqrt(),
        ]
    }

    #[test]
    fn a_linear_chains_drifts_are_the_lyapunov_equations() {
        let (masses, k, zeta, q) = ([1000.0, 800.0], [4e6, 3e6], [0.05, 0.05], 50.0);
        let fit = linear_fit(masses, k, zeta, q);
        let got = predict_level(&fit, q, 6000, &PredictionOptions::default()).unwrap();
        let want = lyapunov_drifts(masses, k, zeta, q);
        for (g, w) in got.drift_rms.iter().zip(&want) {
            // 16 records of 60 s: about 900 decay times τ = 1/(ζω) of the lowest mode, so
            // each RMS is estimated to ~1.2 % (one standard deviation of √(1/(2ζωT))); the
            // force is white only below Nyquist (50 Hz, eight times the top mode): well
            // under 1 % of a displacement's variance. 5 % is four standard deviations.
            assert!(
                (g / w - 1.0).abs() < 0.05,
                "{:?} against {want:?}",
                got.drift_rms
            );
        }
        // No parameter uncertainty, none in the prediction.
        assert!(got.parameters_se.iter().all(|v| *v == 0.0));
    }

    #[test]
    fn a_record_of_the_model_scores_as_chance_against_its_prediction() {
        let (masses, k, zeta, q) = ([1000.0, 800.0], [4e6, 3e6], [0.02, 0.03], 50.0);
        let fit = linear_fit(masses, k, zeta, q);
        let got = predict_level(&fit, q, 6000, &PredictionOptions::default()).unwrap();
        // Statistics and back: the same numbers.
        let there = statistics::vector(&got.statistics);
        let back = statistics::vector(&statistics::level(&there, (2, 2), vec![]));
        for (a, b) in there.iter().zip(&back) {
            assert!((a - b).abs() < 1e-9 * a.abs().max(1.0));
        }
        // Ten records of the model itself, forces unlike the prediction's.
        let r = rebuild(&fit, 77).unwrap();
        let mut z2 = Vec::new();
        for seed in 0..10 {
            let y = r
                .sim
                .replicate(&fit.building, 6000, (q, 0.0), 1000 + seed)
                .unwrap();
            let measured = level_statistics(&fit, &y).unwrap();
            z2.extend(got.z_scores(&measured).iter().map(|z| z * z));
        }
        // 100 z's (10 statistics each): their mean square is 1 within ±0.5 unless the
        // spread is misstated (correlated statistics widen the chance range; a spread off
        // by a factor 1.5 moves it to 0.44 or 2.25).
        let ms = z2.iter().sum::<f64>() / z2.len() as f64;
        assert!((0.5..1.5).contains(&ms), "mean square z {ms}");
    }

    #[test]
    fn a_prediction_refuses_what_it_cannot_do_by_name() {
        let fit = linear_fit([1000.0, 800.0], [4e6, 3e6], [0.02, 0.03], 50.0);
        let o = PredictionOptions::default();
        assert!(matches!(
            predict_level(&fit, -1.0, 6000, &o),
            Err(IdentError::Storey(StoreyError::Unphysical { value, .. })) if value == -1.0
        ));
        assert!(matches!(
            predict_level(&fit, 1.0, 100, &o),
            Err(IdentError::Storey(StoreyError::TooShort {
                samples: 100,
                needed: 1536
            }))
        ));
        let mut edited = fit.clone();
        edited.parameters.pop();
        let e = predict_level(&edited, 1.0, 6000, &o).unwrap_err();
        assert!(e.to_string().contains("does not hold together"), "{e}");
        assert!(matches!(
            level_statistics(&fit, &[vec![0.0; 6000]]),
            Err(IdentError::Storey(StoreyError::ChannelCount {
                channels: 1,
                sensors: 2,
                ..
            }))
        ));
    }
}
