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
            ..Default::default()
        }),
    }
}

/// (false alarms before the change, the first alarm's delay on the changed mode in hours).
fn run(seed: u64, hours: f64, whiten: bool) -> (usize, Option<f64>) {
    let mut c = Campaign::default();
    c.seed = seed;
    c.unexplained = 1e-3;
    c.unexplained_hours = hours;
    run_campaign(c, whiten, true, true)
}

/// `c` tracked, whitened or not, with the environmental model chosen or the covariates as
/// they are, the charts' limits calibrated on the training values or nominal.
fn run_campaign(
    c: Campaign,
    whiten: bool,
    environment: bool,
    calibrate: bool,
) -> (usize, Option<f64>) {
    let records: Vec<RecordModes> = (0..c.len()).map(|i| estimated(&c, i)).collect();
    let mut opts = TrackOptions::default();
    opts.whiten = whiten;
    opts.environment = environment;
    opts.calibrate = calibrate;
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

/// Seeds of the campaigns each test runs (`HYST_CAMPAIGN_SEED` moves them: the figures in
/// docs/monitoring.md are from other seeds than the ones the bounds were set on).
fn seeds(first: u64, count: u64) -> impl Iterator<Item = u64> {
    let base = std::env::var("HYST_CAMPAIGN_SEED")
        .ok()
        .and_then(|s| s.parse::<u64>().ok())
        .unwrap_or(first);
    base..base + count
}

/// (false alarms, losses found, longest delay in hours) over `campaigns`, charted raw
/// with the nominal limit, raw with the limit calibrated on the training values, and
/// whitened (calibrated: the default), with the environmental model or without; prints
/// each.
fn compare(
    what: &str,
    campaigns: impl Iterator<Item = Campaign>,
    environment: bool,
) -> [(usize, usize, f64); 3] {
    let mut out = [(0, 0, 0.0f64); 3];
    let mut count = 0;
    let arms = [
        ("raw", false, false),
        ("raw calibrated", false, true),
        ("whitened", true, true),
    ];
    for c in campaigns {
        count += 1;
        for (k, (name, whiten, calibrate)) in arms.into_iter().enumerate() {
            let (alarms, delay) = run_campaign(c.clone(), whiten, environment, calibrate);
            out[k].0 += alarms;
            if let Some(d) = delay {
                out[k].1 += 1;
                out[k].2 = out[k].2.max(d);
            }
            println!(
                "{what}, seed {}, {name}: {alarms} false alarm(s), found after {delay:?} h",
                c.seed
            );
        }
    }
    println!(
        "{what}: {count} campaigns; (false alarms, found, at most h) raw {:?}, raw calibrated {:?}, whitened {:?}",
        out[0], out[1], out[2]
    );
    out
}

/// Twenty 60-day campaigns (the default design: hourly records, a 0.5 % loss of mode 1 from
/// day 45, two weeks of training) with 0.1 % of frequency unexplained and correlated over a
/// day, as large as the estimation error. Charted as they are, the residuals raise dozens of
/// false alarms per campaign; the filter's innovations about none, and the loss is still
/// found on every campaign. Measured on four sets of twenty (seeds from 9000001, 9100001,
/// 9300001, 9400001): 760–1210 false alarms raw against 0, 6, 3 and 0 whitened, every loss
/// found within 9 h. Asserted: at least fifty times fewer false alarms, every loss found
/// within two days.
#[test]
fn a_slow_unexplained_effect_is_not_taken_for_a_change() {
    let campaigns = seeds(9_000_001, 20).map(|seed| {
        let mut c = Campaign::default();
        c.seed = seed;
        c.unexplained = 1e-3;
        c.unexplained_hours = 24.0;
        c
    });
    let [raw, calibrated, white] = compare("slow effect", campaigns, true);
    assert!(raw.0 >= 100, "the scenario: {raw:?}");
    // The limit calibrated on the training values alone (no whitening): 36 false alarms
    // over seeds 9000001–9000020 against 760 (the limit there 2–4 times the nominal 12),
    // every loss found within 39 h. Asserted: at least five times fewer.
    assert!(5 * calibrated.0 <= raw.0, "{calibrated:?} against {raw:?}");
    assert!(50 * white.0 <= raw.0, "{white:?} against {raw:?}");
    assert!(white.1 == 20 && white.2 <= 48.0, "{white:?}");
}

/// The same design with the structure's temperature lagging the air's by a 3-hour time
/// constant, the covariate the air's: regressed on the covariate as it is, a daily residual
/// of ±0.29 % of frequency the covariate cannot explain, outside the latent model's form.
/// Whitened, no false alarm; but the loss is slower to tell from the swing it resembles.
/// Measured on four sets of twenty (seeds from 9000001, 9100001, 9300001, 9400001):
/// 1563–1714 false alarms raw, 0 whitened; 17, 19, 18 and 19 of the 20 losses found,
/// within 111 h. Asserted: at least fifty times fewer false alarms, at least 16 of 20 losses
/// found (with p = 0.91 per campaign, fewer than 16 has a chance of about 3 %).
///
/// With the environmental model chosen on the training records (the default), the lag is
/// the model's (a first-order lag of whole hours, [`hyst_monitor::environment`]): on seeds
/// 9100001–9100020, 1 false alarm raw and 1 whitened, every loss found within 3 h.
/// Asserted: at most 5 false alarms in the 20 campaigns either way (against 1552 for the
/// covariate as it is, raw), every loss found within a day.
#[test]
fn a_thermal_lag_is_not_taken_for_a_change() {
    let campaigns = || {
        seeds(9_100_001, 20).map(|seed| {
            let mut c = Campaign::default();
            c.seed = seed;
            c.thermal_lag_hours = 3.0;
            c
        })
    };
    let [raw, _, white] = compare("thermal lag, covariate as it is", campaigns(), false);
    assert!(raw.0 >= 100, "the scenario: {raw:?}");
    assert!(50 * white.0 <= raw.0, "{white:?} against {raw:?}");
    assert!(white.1 >= 16, "{white:?}");
    let [raw, calibrated, white] = compare("thermal lag, environmental model", campaigns(), true);
    for r in [raw, calibrated, white] {
        assert!(r.0 <= 5 && r.1 == 20 && r.2 <= 24.0, "{r:?}");
    }
}

/// With an independent unexplained effect of the same size the model is rarely kept (BIC's
/// bar is passed by chance on a few per cent of modes), and whitening costs nothing: no
/// more false alarms, the loss found as soon within an hour or two.
#[test]
fn independent_residuals_are_charted_as_they_are() {
    for seed in seeds(9_000_001, 10) {
        let (raw, raw_delay) = run(seed, 0.0, false);
        let (white, delay) = run(seed, 0.0, true);
        println!(
            "independent, seed {seed}: {raw} / {white} false alarms, found after {raw_delay:?} / {delay:?} h"
        );
        assert!(white <= raw, "seed {seed}");
        let (a, b) = (raw_delay.unwrap_or(f64::NAN), delay.unwrap_or(f64::NAN));
        assert!(b <= a + 2.0, "seed {seed}: {a} h raw, {b} h whitened");
    }
}

/// What one campaign gave each chart: (false alarms before the change, the first alarm's
/// delay after it in hours) for the modes' own charts (on the changed mode) and the joint
/// chart (driven first by the changed mode).
struct Charts {
    modes: (usize, Option<f64>),
    joint: (usize, Option<f64>),
}

fn charts(c: &Campaign, opts: &TrackOptions) -> Charts {
    let records: Vec<RecordModes> = (0..c.len()).map(|i| estimated(c, i)).collect();
    let report = track(&records, None, opts).unwrap();
    let (day, mode, _) = c.change.unwrap();
    let change = day * 86400.0;
    let before = report.alarms.iter().filter(|a| a.time < change).count();
    let delay = report
        .alarms
        .iter()
        .find(|a| a.time >= change && a.mode == mode)
        .map(|a| (a.time - change) / 3600.0);
    let joint = report.joint.as_ref().expect("a joint chart");
    let joint_before = joint.alarms.iter().filter(|a| a.time < change).count();
    let joint_delay = joint
        .alarms
        .iter()
        .find(|a| a.time >= change && a.drivers.first().map(|d| d.0) == Some(mode))
        .map(|a| (a.time - change) / 3600.0);
    Charts {
        modes: (before, delay),
        joint: (joint_before, joint_delay),
    }
}

/// Campaigns whose four modes share an unexplained effect — 0.2 % of the first mode's
/// frequency (the last mode half of it) wandering with a correlation time of a day, and in
/// episodes of two days (a fifth of them) a support that sticks, 0.5 % — with a 1 % loss
/// of mode 2 from day 45. Each mode's chart meets the episodes alone: its filter of a slow
/// effect expects no jump, and its limit, calibrated on two weeks that may hold no episode,
/// cannot know them. The joint chart finds the shared factor in the training records and
/// charts what it leaves. Measured over six sets of ten (seeds from 8500401, 8501001,
/// 8502001, 8503001, 8504001, 8505001): the modes' charts 179 false alarms with the nominal
/// limit and 130 calibrated, the joint chart none; every loss found by both within 4 h, the
/// joint chart naming mode 2 first. (Before the joint chart regressed every mode on the
/// union of their environmental terms, 37 false alarms in three of the twenty campaigns
/// from 8501001 and 8502001: one mode's model had taken a breakpoint for an episode, and its
/// residual left the shared pattern after training.) Asserted: the scenario (the modes'
/// charts alarm falsely at least once), the joint chart at most one false alarm over the
/// ten campaigns and every loss found within 24 h with mode 2 its first driver.
#[test]
fn a_shared_slow_effect_is_judged_together() {
    let mut totals = [(0usize, 0usize, 0.0f64); 3];
    let mut count = 0;
    for seed in seeds(8_500_401, 10) {
        let mut c = Campaign::default();
        c.seed = seed;
        c.shared_unexplained = (2e-3, 24.0);
        c.shared_episodes = (5e-3, 48.0, 0.2);
        c.change = Some((45.0, 1, -0.01));
        count += 1;
        let mut nominal = TrackOptions::default();
        nominal.calibrate = false;
        let plain = charts(&c, &nominal);
        let calibrated = charts(&c, &TrackOptions::default());
        for (k, r) in [plain.modes, calibrated.modes, calibrated.joint]
            .into_iter()
            .enumerate()
        {
            totals[k].0 += r.0;
            if let Some(d) = r.1 {
                totals[k].1 += 1;
                totals[k].2 = totals[k].2.max(d);
            }
        }
        println!(
            "shared effect, seed {seed}: modes (nominal limit) {:?}, modes (calibrated) {:?}, joint {:?}",
            plain.modes, calibrated.modes, calibrated.joint
        );
    }
    println!(
        "shared effect over {count}: (false alarms, found, longest delay h) modes nominal {:?}, modes calibrated {:?}, joint {:?}",
        totals[0], totals[1], totals[2]
    );
    assert!(totals[1].0 >= 1, "the scenario: {totals:?}");
    let joint = totals[2];
    assert!(
        joint.0 <= 1 && joint.1 == count && joint.2 <= 24.0,
        "{joint:?}"
    );
}
