//! A campaign whose frequencies wander with an effect the temperature does not explain,
//! correlated over a day: the residuals charted as they are raise false alarms; their
//! innovations (the default) do not, and the change is still found. Tracked on the
//! campaign's true frequencies plus estimation noise of a known standard error, so that
//! many campaigns of 60 days run in a test (the end-to-end identification of records is
//! `campaign.rs`'s test).

use hyst_monitor::campaign::Campaign;
use hyst_monitor::{Identified, ModeEstimate, RecordModes, Side, TrackOptions, track};
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

/// Relative standard error of each frequency estimate (about a 10-minute record's).
const SE: f64 = 1e-3;

/// Record `i`'s modes as an identification with relative standard error `SE` would give.
fn estimated(c: &Campaign, i: usize) -> RecordModes {
    let s = c.state(i);
    let mut rng = rand::rngs::StdRng::seed_from_u64(c.seed ^ (i as u64).wrapping_mul(0x9e37));
    let normal = Normal::new(0.0, 1.0).unwrap();
    let modes = s
        .frequencies
        .iter()
        .map(|&f| ModeEstimate {
            frequency_hz: f * (1.0 + SE * normal.sample(&mut rng)),
            frequency_se_hz: Some(SE * f),
            damping_ratio: 0.015,
            damping_se: Some(0.002),
            shape: None,
        })
        .collect();
    RecordModes {
        name: i.to_string(),
        time: s.time_s,
        covariates: vec![s.temperature],
        outcome: Ok(Identified {
            modes,
            misfit: Some(0.01),
        }),
    }
}

/// (false alarms before the change, the first alarm's delay on the changed mode in hours).
fn run(seed: u64, hours: f64, whiten: bool) -> (usize, Option<f64>) {
    let mut c = Campaign::default();
    c.seed = seed;
    c.unexplained = 1e-3;
    c.unexplained_hours = hours;
    let records: Vec<RecordModes> = (0..c.len()).map(|i| estimated(&c, i)).collect();
    let mut opts = TrackOptions::default();
    opts.whiten = whiten;
    let report = track(&records, None, &opts).unwrap();
    let (day, mode, _) = c.change.unwrap();
    let change = day * 86400.0;
    let before = report.alarms.iter().filter(|a| a.time < change).count();
    let delay = report
        .alarms
        .iter()
        .find(|a| a.time >= change && a.mode == mode && a.side == Side::Down)
        .map(|a| (a.time - change) / 3600.0);
    (before, delay)
}

/// Forty 60-day campaigns (the default design: hourly records, a 0.5 % loss of mode 1 from
/// day 45, two weeks of training), the unexplained effect of 0.1 % correlated over a day,
/// as large as the estimation error. Charted as they are, the residuals raise 22–47 false
/// alarms per campaign (seeds 9000011–9000040, on which these figures were measured before
/// they were asserted); their innovations 0–2 (11 over the 30), and the loss is found 2–24 h
/// after it starts on every campaign (raw: 3–6 h, when it is told from the alarms around
/// it at all). Asserted: at least ten times fewer false alarms whitened, the loss found
/// within two days on every campaign; and with an independent effect of the same size,
/// whitening costs nothing (no more false alarms, the same delay within a few hours).
#[test]
fn correlated_residuals_are_whitened_before_the_chart() {
    let (mut raw_alarms, mut white_alarms) = (0, 0);
    for seed in 9_000_001..=9_000_040u64 {
        let (raw, _) = run(seed, 24.0, false);
        let (white, delay) = run(seed, 24.0, true);
        println!("seed {seed}: false alarms {raw} raw, {white} whitened; found after {delay:?} h");
        let delay = delay.unwrap_or_else(|| panic!("seed {seed}: the loss is not found"));
        assert!(delay <= 48.0, "seed {seed}: {delay} h");
        raw_alarms += raw;
        white_alarms += white;
    }
    println!("false alarms over 40 campaigns: {raw_alarms} raw, {white_alarms} whitened");
    assert!(
        10 * white_alarms <= raw_alarms,
        "{white_alarms} vs {raw_alarms}"
    );
    for seed in 9_000_001..=9_000_010u64 {
        let (raw, raw_delay) = run(seed, 0.0, false);
        let (white, delay) = run(seed, 0.0, true);
        println!(
            "independent, seed {seed}: {raw} / {white} false alarms, found after {raw_delay:?} / {delay:?} h"
        );
        assert!(white <= raw, "seed {seed}");
        let (a, b) = (raw_delay.unwrap(), delay.unwrap());
        assert!(
            (a - b).abs() <= 3.0,
            "seed {seed}: {a} h raw, {b} h whitened"
        );
    }
}
