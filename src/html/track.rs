//! The page of a monitoring campaign (`hyst track --html`): each reference mode's frequency
//! and damping against time with ± one standard error, the records after training marked,
//! and the alarms; the reference modes' table, shapes and MAC.

use hyst_monitor::TrackReport;

use super::data::{ModeRow, ModeSeries, PageData, Shapes, TrackSeries, mac_matrix, pair};
use covssi::Complex64 as C64;

/// The page of a campaign's report.
pub fn track_page_data(title: &str, report: &TrackReport) -> PageData {
    let t0 = report
        .rows
        .iter()
        .map(|r| r.time)
        .fold(f64::INFINITY, f64::min);
    let day = |t: f64| (t - t0) / 86_400.0;
    let modes: Vec<ModeSeries> = report
        .reference
        .iter()
        .enumerate()
        .map(|(j, m)| {
            let rows: Vec<_> = report.rows.iter().filter(|r| r.mode == j).collect();
            ModeSeries {
                label: format!("mode {} ({:.3} Hz)", report.mode_name(j), m.frequency_hz),
                days: rows.iter().map(|r| day(r.time)).collect(),
                frequency_hz: rows.iter().map(|r| r.frequency_hz).collect(),
                frequency_se_hz: rows.iter().map(|r| r.frequency_se_hz).collect(),
                damping_ratio: rows.iter().map(|r| r.damping_ratio).collect(),
                damping_se: rows.iter().map(|r| r.damping_se).collect(),
                alarm_days: report
                    .alarms
                    .iter()
                    .filter(|a| a.mode == j)
                    .map(|a| day(a.time))
                    .collect(),
            }
        })
        .collect();
    // The first record charted (with a z) ends the training.
    let training_end_days = report
        .rows
        .iter()
        .filter(|r| r.z.is_some())
        .map(|r| day(r.time))
        .fold(None, |a: Option<f64>, t| Some(a.map_or(t, |a| a.min(t))));
    let shapes: Vec<Vec<C64>> = report
        .reference
        .iter()
        .map(|m| m.shape.clone().unwrap_or_default())
        .collect();
    let n = shapes.iter().map(Vec::len).max().unwrap_or(0);
    let zero = [0.0, 0.0];
    let records = report
        .rows
        .iter()
        .map(|r| r.record)
        .max()
        .map_or(0, |m| m + 1);
    PageData {
        title: title.to_string(),
        summary: summary(report, records, t0),
        diagram: None,
        setup_diagrams: Vec::new(),
        modes: report
            .reference
            .iter()
            .enumerate()
            .map(|(j, m)| ModeRow {
                name: report.mode_name(j),
                frequency_hz: m.frequency_hz,
                frequency_se_hz: m.frequency_se_hz,
                damping_ratio: m.damping_ratio,
                damping_se: m.damping_se,
                mpc: m.shape.as_deref().map(covssi::mpc),
                mpd: m.shape.as_deref().map(covssi::mpd),
                efdd: None,
                seen: Some(format!(
                    "tracked in {:.1} % of records",
                    100.0 * report.tracked.get(j).copied().unwrap_or(0.0)
                )),
            })
            .collect(),
        mac: mac_matrix(&shapes),
        shapes: Shapes {
            names: (0..n).map(|c| c.to_string()).collect(),
            xyz: (0..n).map(|i| [i as f64, 0.0, 0.0]).collect(),
            lines: (1..n).map(|i| [i - 1, i]).collect(),
            motion: shapes
                .iter()
                .map(|s| {
                    (0..n)
                        .map(|c| [zero, zero, s.get(c).map_or(zero, |v| pair(*v))])
                        .collect()
                })
                .collect(),
        },
        track: Some(TrackSeries {
            modes,
            training_end_days,
        }),
    }
}

/// The page's summary: the campaign in a sentence, and the joint chart's verdict (days from
/// `t0`, the first record's time, as the page's axes count them).
fn summary(report: &TrackReport, records: usize, t0: f64) -> Vec<String> {
    let mut lines = vec![format!(
        "{records} records, {} reference modes, {} alarms, {} records skipped.",
        report.reference.len(),
        report.alarms.len(),
        report.skipped.len()
    )];
    if let Some(j) = &report.joint {
        let alarms: Vec<String> = j
            .alarms
            .iter()
            .map(|a| {
                let driver = a.drivers.first().map_or_else(String::new, |d| {
                    format!(", driven by mode {}", report.mode_name(d.0))
                });
                format!("day {:.2}{driver}", (a.time - t0) / 86_400.0)
            })
            .collect();
        lines.push(format!(
            "Modes judged together: {} shared factor(s) set apart; {}.",
            j.common_factors,
            if alarms.is_empty() {
                "no alarm".to_string()
            } else {
                format!("alarms at {}", alarms.join("; "))
            }
        ));
    }
    lines
}
