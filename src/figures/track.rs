//! The figures of `hyst track --svg-dir`.

use crate::monitor::TrackReport;

/// For each reference mode: its frequency and its damping against time (days) with ± one
/// standard error and the alarms marked, and its frequency against the first covariate
/// (named by the report's `covariate_names`).
pub fn track_figures(dir: &std::path::Path, r: &TrackReport) -> Result<(), String> {
    use crate::plot::{colors, scatter};
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let day = |t: f64| t / 86400.0;
    for (j, m) in r.reference.iter().enumerate() {
        let rows: Vec<_> = r.rows.iter().filter(|row| row.mode == j).collect();
        // Named as the text names it (numbered from 1, or the estimates' column), the
        // file's name keeping only what a file name safely holds.
        let name = r.mode_name(j);
        let file = file_safe(&name);
        let se = |v: Option<f64>| v.unwrap_or(f64::NAN);
        let series = |value: &dyn Fn(&crate::monitor::TrackRow) -> f64,
                      spread: &dyn Fn(&crate::monitor::TrackRow) -> f64| {
            vec![
                (
                    "estimate".to_string(),
                    rows.iter().map(|w| (day(w.time), value(w))).collect(),
                    colors::BLUE,
                ),
                (
                    "± standard error".to_string(),
                    rows.iter()
                        .flat_map(|w| {
                            [
                                (day(w.time), value(w) - spread(w)),
                                (day(w.time), value(w) + spread(w)),
                            ]
                        })
                        .collect(),
                    colors::GREY,
                ),
                (
                    "alarm".to_string(),
                    rows.iter()
                        .filter(|w| w.alarm.is_some())
                        .map(|w| (day(w.time), value(w)))
                        .collect(),
                    colors::RED,
                ),
            ]
        };
        scatter(
            &dir.join(format!("mode{file}_frequency.svg")),
            &format!("Mode {name} ({:.3} Hz): frequency", m.frequency_hz),
            "time (days)",
            "frequency (Hz)",
            &series(&|w| w.frequency_hz, &|w| se(w.frequency_se_hz)),
        )?;
        scatter(
            &dir.join(format!("mode{file}_damping.svg")),
            &format!("Mode {name} ({:.3} Hz): damping", m.frequency_hz),
            "time (days)",
            "damping ratio",
            &series(&|w| w.damping_ratio, &|w| se(w.damping_se)),
        )?;
        if let Some(covariate) = r.covariate_names.first() {
            scatter(
                &dir.join(format!("mode{file}_vs_{}.svg", file_safe(covariate))),
                &format!("Mode {name}: frequency against {covariate}"),
                covariate,
                "frequency (Hz)",
                &[
                    (
                        "records".to_string(),
                        rows.iter()
                            .filter_map(|w| w.covariates.first().map(|c| (*c, w.frequency_hz)))
                            .collect(),
                        colors::BLUE,
                    ),
                    (
                        "alarm".to_string(),
                        rows.iter()
                            .filter(|w| w.alarm.is_some())
                            .filter_map(|w| w.covariates.first().map(|c| (*c, w.frequency_hz)))
                            .collect(),
                        colors::RED,
                    ),
                ],
            )?;
        }
    }
    if let Some(c) = &r.subspace {
        subspace_figure(dir, c)?;
    }
    if let Some(c) = &r.joint {
        joint_figure(dir, c)?;
    }
    Ok(())
}

/// The joint chart's statistic against time: the training records, the later ones and
/// those that raised an alarm.
fn joint_figure(
    dir: &std::path::Path,
    c: &crate::monitor::joint::JointChart,
) -> Result<(), String> {
    let alarms: Vec<usize> = c.alarms.iter().map(|a| a.record).collect();
    crate::plot::scatter(
        &dir.join("joint.svg"),
        &format!(
            "Modes judged together: what {} shared factor(s) leave of {} modes' residuals",
            c.common_factors,
            c.modes.len()
        ),
        "time (days)",
        "statistic Q",
        &timeline(&c.time, &c.statistic, c.training, &alarms, "alarm"),
    )
}

/// A statistic of each record (`values`, at `time` in s) as the series of a figure against
/// time in days: the first `training` records, the later ones, and the `alarms` (records)
/// under `alarm`; a record without a value or a time is left out.
fn timeline(
    time: &[f64],
    values: &[f64],
    training: usize,
    alarms: &[usize],
    alarm: &str,
) -> Vec<crate::plot::Series> {
    use crate::plot::colors;
    let point = |i: usize| {
        let (t, v) = (*time.get(i)?, *values.get(i)?);
        (t.is_finite() && v.is_finite()).then_some((t / 86400.0, v))
    };
    let n = values.len();
    let points = |range: std::ops::Range<usize>| range.filter_map(point).collect();
    vec![
        (
            "training".to_string(),
            points(0..training.min(n)),
            colors::GREY,
        ),
        (
            "later records".to_string(),
            points(training.min(n)..n),
            colors::BLUE,
        ),
        (
            alarm.to_string(),
            alarms.iter().filter_map(|&i| point(i)).collect(),
            colors::RED,
        ),
    ]
}

/// `name` as a part of a file's name: letters, digits and `-` kept, anything else `_` (a
/// name is the user's: an estimates table's column, a covariate's).
fn file_safe(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// The subspace test's T² against time: the training records, the later ones, those the
/// CUSUM alarmed at, and the single-record threshold.
fn subspace_figure(
    dir: &std::path::Path,
    c: &crate::monitor::subspace::SubspaceChart,
) -> Result<(), String> {
    let day = |i: usize| c.time.get(i).copied().unwrap_or(i as f64) / 86400.0;
    let n = c.t2.len();
    let (start, end) = (day(0), day(n.saturating_sub(1)));
    let threshold: Vec<(f64, f64)> = (0..=200)
        .map(|k| (start + (end - start) * k as f64 / 200.0, c.threshold))
        .collect();
    let mut series = timeline(&c.time, &c.t2, c.training, &c.alarms, "CUSUM alarm");
    series.push((
        "threshold".to_string(),
        threshold,
        crate::plot::colors::GREY,
    ));
    crate::plot::scatter(
        &dir.join("subspace.svg"),
        &format!(
            "Subspace damage test: T² of {} entries (threshold at {} % per record)",
            c.dof,
            100.0 * c.alpha
        ),
        "time (days)",
        "T²",
        &series,
    )
}
