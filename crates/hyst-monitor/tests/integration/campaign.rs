//! End to end on short synthetic campaigns: every record identified as `hyst ssi` does, the
//! modes tracked, the change found, no alarm before it; a broken record skipped with its
//! reason.

use hyst_monitor::campaign::Campaign;
use hyst_monitor::{RecordModes, Side, TrackOptions, identify_record, track};
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
        outcome: identify_record(&views, c.fs, &analysis()).map_err(|e| e.to_string()),
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

/// Records that break a real campaign: a NaN, a dead (constant) channel, one too short to
/// identify, a clipped channel, one channel fewer, one far shorter than the rest (but
/// identifiable), each skipped with the reason; a machine's harmonic in a record named a
/// harmonic and not tracked, that record's modes tracked; the good records tracked.
#[test]
fn a_broken_record_is_skipped_with_its_reason() {
    let mut c = Campaign::default();
    c.days = 1;
    c.per_day = 10;
    c.seconds = 300.0;
    c.seed = 740_000;
    let records: Vec<RecordModes> = (0..c.len())
        .map(|i| {
            identified(&c, i, |ch| match i {
                2 => ch[3][100] = f64::NAN,
                // A dead sensor: its channel constant.
                3 => ch[1].iter_mut().for_each(|v| *v = 0.0),
                4 => ch.iter_mut().for_each(|v| v.truncate(40)),
                // Clipped: 1 % of channel 0's samples at its limits.
                5 => {
                    let mut a: Vec<f64> = ch[0].iter().map(|v| v.abs()).collect();
                    a.sort_by(f64::total_cmp);
                    let level = a[a.len() * 99 / 100];
                    ch[0].iter_mut().for_each(|v| *v = v.clamp(-level, level));
                }
                6 => {
                    ch.pop();
                }
                7 => ch.iter_mut().for_each(|v| v.truncate(v.len() * 35 / 100)),
                // A machine at 2.2 Hz, between modes 1 and 2, on every channel.
                8 => {
                    for (k, v) in ch.iter_mut().enumerate() {
                        let rms = (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
                        for (n, x) in v.iter_mut().enumerate() {
                            let t = n as f64 / 25.0;
                            *x +=
                                2.0 * rms * (2.0 * std::f64::consts::PI * 2.2 * t + k as f64).sin();
                        }
                    }
                }
                _ => {}
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
    let says = [
        (
            "2",
            "channel 3 has 1 value(s) that are not finite numbers, the first at sample 100",
        ),
        (
            "3",
            "channel 1 holds 0 for 7500 consecutive samples from sample 0: stuck",
        ),
        ("4", "40 samples are too few"),
        ("5", "channel 0 has"),
        (
            "6",
            "its modes are on 5 channels, the reference's on 6: another sensor layout",
        ),
        (
            "7",
            "its 2625 samples are 35 % of the campaign's median 7500: far shorter",
        ),
    ];
    assert_eq!(skipped.len(), says.len(), "{skipped:?}");
    for ((name, why), (n, w)) in skipped.iter().zip(says) {
        assert!(*name == n && why.contains(w), "{name}: {why}, not {w}");
    }
    assert!(skipped[3].1.contains("clipped"), "{skipped:?}");
    for broken in [2, 3, 4, 5, 6, 7] {
        assert_eq!(report.rows.iter().filter(|r| r.record == broken).count(), 0);
    }
    // The harmonic named at its frequency, in record 8 alone, and its modes all tracked.
    assert_eq!(report.harmonics.len(), 1, "{:?}", report.harmonics);
    let (record, f) = report.harmonics[0];
    assert!(
        record == 8 && (f - 2.2).abs() < 0.01,
        "{:?}",
        report.harmonics
    );
    assert!(
        report
            .to_string()
            .contains("harmonics (steady spectral lines")
    );
    for good in [8, 9] {
        assert_eq!(report.rows.iter().filter(|r| r.record == good).count(), 4);
    }
    assert!(
        report.baseline_errors.iter().all(|e| e
            .as_deref()
            .is_some_and(|e| e.contains("2 training record(s) for 2"))),
        "{:?}",
        report.baseline_errors
    );
    assert!(report.alarms.is_empty());
}
