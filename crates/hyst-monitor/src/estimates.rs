//! Modal estimates made by another system, tracked as [`track()`](fn@crate::track) tracks
//! the records hyst identifies: the modes are named by the table's columns, so no matching is
//! needed, and the normalization, the slow effect's model and the chart are the same.
//!
//! Without standard errors, a mode's estimation noise is read from its training rows: the
//! median absolute difference of consecutive records' frequencies, over √2 and scaled to a
//! normal's standard deviation ($s = 1.4826\,\mathrm{med}|f_{i+1} - f_i| / \sqrt 2$). The
//! environment moves a frequency slowly against the record-to-record scatter of estimation,
//! so consecutive differences are mostly that scatter, and the median keeps a frost day's
//! jump out of it.

use crate::MonitorError;
use crate::matching::ModeEstimate;
use crate::track::{TrackOptions, TrackReport, TrackRow, chart_modes};
use crate::training::median;

/// One record's row of an estimates table.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct RecordEstimates {
    /// The record's name.
    pub name: String,
    /// When it was recorded (s, on the campaign's clock).
    pub time: f64,
    /// Its covariates (NaN where missing).
    pub covariates: Vec<f64>,
    /// Each named mode's estimate, `None` where the record did not have it.
    pub modes: Vec<Option<ModeEstimate>>,
}

/// Track `records` (in time order), whose modes are named by `mode_names` (one per entry of
/// each record's `modes`). The reference of each mode is its median frequency and damping
/// over the training records; a mode without standard errors has them read from its
/// training rows ([module doc](self); [`TrackReport::noise_from_training`] says so).
pub fn track_estimates(
    records: &[RecordEstimates],
    mode_names: &[String],
    opts: &TrackOptions,
) -> Result<TrackReport, MonitorError> {
    let training = opts.training.min(records.len());
    let modes = mode_names.len();
    let mut reference = Vec::with_capacity(modes);
    let mut noise = Vec::with_capacity(modes);
    for k in 0..modes {
        let train: Vec<&ModeEstimate> = records[..training]
            .iter()
            .filter_map(|r| r.modes.get(k).and_then(Option::as_ref))
            .collect();
        let f: Vec<f64> = train.iter().map(|m| m.frequency_hz).collect();
        let d: Vec<f64> = train.iter().map(|m| m.damping_ratio).collect();
        let given = records
            .iter()
            .filter_map(|r| r.modes.get(k).and_then(Option::as_ref))
            .any(|m| m.frequency_se_hz.is_some());
        noise.push((!given).then(|| consecutive_scatter(&f)));
        reference.push(ModeEstimate {
            frequency_hz: median(&f),
            frequency_se_hz: None,
            damping_ratio: median(&d),
            damping_se: None,
            shape: None,
        });
    }
    let mut rows = Vec::new();
    let mut seen = vec![0usize; modes];
    for (i, r) in records.iter().enumerate() {
        for (k, m) in r.modes.iter().enumerate().take(modes) {
            let Some(m) = m else { continue };
            seen[k] += 1;
            let se = noise[k].or(m.frequency_se_hz);
            rows.push(TrackRow {
                record: i,
                name: r.name.clone(),
                time: r.time,
                mode: k,
                frequency_hz: m.frequency_hz,
                frequency_se_hz: se,
                damping_ratio: m.damping_ratio,
                damping_se: m.damping_se,
                mac: f64::NAN,
                misfit_flag: false,
                z: None,
                innovation: None,
                alarm: None,
                covariates: r.covariates.clone(),
                extrapolated: false,
            });
        }
    }
    let mut report = chart_modes(reference, rows, records.len(), opts);
    report.tracked = seen
        .iter()
        .map(|&s| s as f64 / records.len().max(1) as f64)
        .collect();
    report.noise_from_training = noise;
    report.mode_names = mode_names.to_vec();
    Ok(report)
}

/// The estimation noise read from consecutive values ([module doc](self)).
fn consecutive_scatter(f: &[f64]) -> f64 {
    let d: Vec<f64> = f.windows(2).map(|w| (w[1] - w[0]).abs()).collect();
    1.4826 * median(&d) / std::f64::consts::SQRT_2
}

#[cfg(test)]
mod tests {
    use super::*;

    /// White estimation noise of σ = 2 mHz on a frequency that drifts slowly with
    /// temperature: the consecutive-difference scatter finds σ within 10 % (the median of
    /// 499 |differences| has a relative standard error of about 1.1/√499 = 5 %), where the
    /// plain standard deviation would take in the drift.
    #[test]
    fn the_noise_is_read_from_consecutive_records() {
        let mut x: u64 = 7;
        let mut normal = || {
            // Box–Muller on a small LCG: a rough normal is all the test needs.
            let mut u = || {
                x = x
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((x >> 11) as f64 + 0.5) / (1u64 << 53) as f64
            };
            let (a, b) = (u(), u());
            (-2.0 * a.ln()).sqrt() * (2.0 * std::f64::consts::PI * b).cos()
        };
        let f: Vec<f64> = (0..500)
            .map(|i| 4.0 + 0.05 * (i as f64 / 80.0).sin() + 0.002 * normal())
            .collect();
        let s = consecutive_scatter(&f);
        assert!((s / 0.002 - 1.0).abs() < 0.1, "{s}");
    }

    /// Issue 58's reproduction: one training cell of 100 Hz (a typo for 1 Hz), or 1e308,
    /// among a mode's values of 1 Hz ± 0.2 % no longer blinds the chart: the cell is set
    /// apart by the gross rule, named by its record, and a later 2 % drop is alarmed (it was
    /// not: the baseline was 5.95 Hz with an SD of 22 Hz), with no alarm before it.
    #[test]
    fn a_typed_training_cell_is_set_apart_and_a_drop_still_alarms() {
        for typo in [100.0, 1e308] {
            let mut x: u64 = 11;
            let mut u = || {
                x = x
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((x >> 11) as f64 + 0.5) / (1u64 << 53) as f64
            };
            let records: Vec<RecordEstimates> = (0..300)
                .map(|i| {
                    let (a, b) = (u(), u());
                    let e = (-2.0 * a.ln()).sqrt() * (2.0 * std::f64::consts::PI * b).cos();
                    let level = if i >= 250 { 0.98 } else { 1.0 };
                    let f = if i == 40 { typo } else { level + 0.002 * e };
                    RecordEstimates {
                        name: format!("r{i}"),
                        time: i as f64,
                        covariates: vec![],
                        modes: vec![Some(ModeEstimate {
                            frequency_hz: f,
                            frequency_se_hz: None,
                            damping_ratio: 0.01,
                            damping_se: None,
                            shape: None,
                        })],
                    }
                })
                .collect();
            let opts = TrackOptions::for_campaign(records.len(), Some(150), true, true);
            let r = track_estimates(&records, &["f1".into()], &opts).unwrap();
            assert_eq!(r.training_outliers.len(), 1, "{:?}", r.training_outliers);
            assert_eq!(r.training_outliers[0].record, 40);
            assert!(matches!(
                r.training_outliers[0].rule,
                crate::OutlierRule::Gross { .. }
            ));
            let b = r.baselines[0].as_ref().unwrap();
            // The baseline is the clean values' (1 Hz within a few of their 0.02 % errors).
            assert!((b.coefficients[0] - 1.0).abs() < 1e-3, "{b:?}");
            assert!(r.alarms.iter().all(|a| a.record >= 250), "{:?}", r.alarms);
            assert!(!r.alarms.is_empty(), "the 2 % drop is alarmed");
            assert!(r.to_string().contains("training record r40"), "{r}");
        }
    }
}
