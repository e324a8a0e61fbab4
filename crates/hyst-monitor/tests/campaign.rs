//! End to end on short synthetic campaigns: every record identified as `hyst ssi` does, the
//! modes tracked, the change found, no alarm before it; a broken record skipped with its
//! reason.

use hyst_monitor::campaign::Campaign;
use hyst_monitor::{RecordModes, Side, TrackOptions, identify, track};
use rayon::prelude::*;

fn analysis() -> covssi::AnalysisOptions {
    covssi::AnalysisOptions::default().with_ssi(covssi::SsiOptions {
        block_rows: covssi::BlockRows::Seconds(3.0),
        ..covssi::SsiOptions::default()
    })
}

/// Record `i` of `c` identified, `broken` applied to its channels first.
fn identified(c: &Campaign, i: usize, broken: impl Fn(&mut Vec<Vec<f64>>)) -> RecordModes {
    let mut r = c.record(i);
    broken(&mut r.channels);
    let views: Vec<&[f64]> = r.channels.iter().map(|v| v.as_slice()).collect();
    RecordModes {
        name: format!("{i}"),
        time: r.time_s,
        covariates: vec![r.temperature],
        outcome: identify(&views, c.fs, &analysis()).map_err(|e| e.to_string()),
    }
}

/// Four days of records every two hours, the change (mode 1 down 0.5 %) on day 3, the first
/// two days training: over two fresh campaigns, each mode tracked in every record, no alarm
/// before the change, and the change found within a day on the right mode and side.
#[test]
fn a_short_campaign_finds_its_change_and_nothing_else() {
    for seed in [720_000, 730_000] {
        let mut c = Campaign::default();
        c.days = 4;
        c.per_day = 12;
        c.seed = seed;
        c.change = Some((3.0, 1, -0.005));
        let records: Vec<RecordModes> = (0..c.len())
            .into_par_iter()
            .map(|i| identified(&c, i, |_| {}))
            .collect();
        let mut opts = TrackOptions::default();
        opts.training = 24;
        let report = track(&records, None, &opts).unwrap();
        assert_eq!(report.reference.len(), 4, "{:?}", report.reference);
        assert!(
            report.tracked.iter().all(|&t| t == 1.0),
            "{:?}",
            report.tracked
        );
        let change = 3.0 * 86400.0;
        assert!(
            report.alarms.iter().all(|a| a.time >= change),
            "seed {seed}: {:?}",
            report.alarms
        );
        let first = report
            .alarms
            .iter()
            .find(|a| a.mode == 1 && a.side == Side::Down)
            .unwrap_or_else(|| panic!("seed {seed}: no alarm on mode 1"));
        let delay_h = (first.time - change) / 3600.0;
        println!("seed {seed}: detected after {delay_h} h");
        assert!(delay_h <= 24.0, "seed {seed}: {delay_h} h");
    }
}

/// A record with a NaN, a dead (constant) channel, or far shorter than the others gives no
/// modes: it is skipped with the reason, and the others are tracked.
#[test]
fn a_broken_record_is_skipped_with_its_reason() {
    let mut c = Campaign::default();
    c.days = 1;
    c.per_day = 6;
    c.seconds = 300.0;
    c.seed = 740_000;
    let records: Vec<RecordModes> = (0..c.len())
        .map(|i| {
            identified(&c, i, |ch| {
                if i == 2 {
                    ch[3][100] = f64::NAN;
                }
                // A dead sensor: its channel constant.
                if i == 3 {
                    ch[1].iter_mut().for_each(|v| *v = 0.0);
                }
                // A record far shorter than the others.
                if i == 4 {
                    ch.iter_mut().for_each(|v| v.truncate(40));
                }
            })
        })
        .collect();
    let mut opts = TrackOptions::default();
    // Records 0 and 1 train (record 2 is broken): too few for a regression on the
    // temperature, which each mode says.
    opts.training = 3;
    let report = track(&records, None, &opts).unwrap();
    // Each broken record skipped with what is wrong with it, the others tracked.
    let skipped: Vec<(&str, &str)> = report
        .skipped
        .iter()
        .map(|(n, why)| (n.as_str(), why.as_str()))
        .collect();
    assert_eq!(skipped.len(), 3, "{skipped:?}");
    assert_eq!(skipped[0].0, "2");
    assert!(
        skipped[0].1.contains("sample 100: value NaN is not finite"),
        "{skipped:?}"
    );
    assert_eq!(skipped[1].0, "3");
    assert!(
        skipped[1].1.contains("channel 1 is constant"),
        "{skipped:?}"
    );
    assert_eq!(skipped[2].0, "4");
    assert!(
        skipped[2].1.contains("40 samples are too few"),
        "{skipped:?}"
    );
    for broken in [2, 3, 4] {
        assert_eq!(report.rows.iter().filter(|r| r.record == broken).count(), 0);
    }
    assert_eq!(report.rows.iter().filter(|r| r.record == 5).count(), 4);
    assert!(
        report.baseline_errors.iter().all(|e| e
            .as_deref()
            .is_some_and(|e| e.contains("2 training record(s) for 2"))),
        "{:?}",
        report.baseline_errors
    );
    assert!(report.alarms.is_empty());
}
