//! A campaign with what a real structure's has: frost below 0 °C (frequencies rising
//! steeply as it freezes), the structure's temperature lagging the air's by 4 h, frequencies
//! drifting with the excitation's amplitude, a machine's harmonic in a third of the records,
//! records broken (a NaN burst, clipped, a stuck channel, far too short) and records missing
//! — trained over a period with frost, a 1 % loss of one mode after. Each record identified as
//! `hyst track` does; every fresh campaign must show no false alarm after training until the
//! change, the change within 24 h, every true mode tracked in at least 95 % of the good
//! records, the harmonic named and never tracked, every broken record skipped with its
//! reason. `HYST_CAMPAIGN_SEED`, `HYST_CAMPAIGNS` and `HYST_CAMPAIGN_DAYS` move and widen it;
//! `--nocapture` prints each campaign's figures.

use crate::common;

use hyst_monitor::{RecordModes, Side, TrackOptions, identify_record, track};
use rayon::prelude::*;

/// What is wrong with record `i` of the campaign seeded `seed`, if anything: about one record
/// in twenty (0 NaN burst, 1 clipped, 2 stuck, 3 far too short, 4 missing).
fn fault(seed: u64, i: usize) -> Option<u64> {
    let h = (i as u64).wrapping_mul(7919).wrapping_add(seed) % 97;
    (h < 5).then_some(h)
}

fn break_record(kind: u64, ch: &mut [Vec<f64>]) {
    let n = ch[0].len();
    match kind {
        0 => ch[2][n / 3..n / 3 + 40].fill(f64::NAN),
        1 => {
            let mut a: Vec<f64> = ch[0].iter().map(|v| v.abs()).collect();
            a.sort_by(f64::total_cmp);
            let level = a[a.len() * 99 / 100];
            ch[0].iter_mut().for_each(|v| *v = v.clamp(-level, level));
        }
        2 => {
            let v = ch[4][n / 2];
            ch[4][n / 2..].fill(v);
        }
        _ => ch.iter_mut().for_each(|c| c.truncate(n * 3 / 10)),
    }
}

#[test]
fn a_confounded_campaign_alarms_only_on_its_change() {
    for mut c in common::campaigns(9_950_001, 24) {
        let seed = c.seed;
        // Cold first (the training period holds frost), warm, then cold again.
        c.temperature = (2.0, 4.0, -6.0, 2.0 * c.days as f64 / 3.0);
        c.frost = (0.0, -0.008);
        c.thermal_lag_hours = 4.0;
        c.amplitude_coefficient = -0.004;
        c.harmonic = Some((2.3, 1.0, 0.3));
        let change_day = (0.75 * c.days as f64).round();
        c.change = Some((change_day, 1, -0.01));
        let opts = common::analysis();
        let kept: Vec<usize> = (0..c.len())
            .filter(|&i| fault(seed, i) != Some(4))
            .collect();
        let records: Vec<RecordModes> = kept
            .par_iter()
            .map(|&i| {
                let mut r = c.record(i);
                if let Some(kind) = fault(seed, i) {
                    break_record(kind, &mut r.channels);
                }
                let views: Vec<&[f64]> = r.channels.iter().map(|v| v.as_slice()).collect();
                RecordModes {
                    name: format!("{i}"),
                    time: r.time_s,
                    covariates: vec![r.temperature],
                    outcome: identify_record(&views, c.fs, &opts).map_err(|e| e.to_string()),
                }
            })
            .collect();
        let mut track_opts = TrackOptions::default();
        track_opts.training = records.len() / 2;
        track_opts.level_covariate = true;
        let mut report = track(&records, None, &track_opts).unwrap();
        report.name_covariates(vec!["temperature".into()]);
        let change = change_day * 86400.0;
        let trained_until = records[track_opts.training].time;
        let false_alarms: Vec<_> = report.alarms.iter().filter(|a| a.time < change).collect();
        let changed = report
            .reference
            .iter()
            .position(|m| (m.frequency_hz / 3.2 - 1.0).abs() < 0.1);
        let delay = report
            .alarms
            .iter()
            .find(|a| Some(a.mode) == changed && a.side == Side::Down && a.time >= change)
            .map(|a| (a.time - change) / 3600.0);
        let broken = kept.iter().filter(|&&i| fault(seed, i).is_some()).count();
        let truth = [1.1, 3.2, 5.6, 8.3];
        let tracked: Vec<(f64, f64)> = truth
            .iter()
            .map(|&f| {
                let j = report
                    .reference
                    .iter()
                    .position(|m| (m.frequency_hz / f - 1.0).abs() < 0.1);
                (f, j.map_or(0.0, |j| report.tracked[j]))
            })
            .collect();
        let frozen = (0..c.len())
            .filter(|&i| c.state(i).temperature < 0.0)
            .count();
        println!(
            "seed {seed}: {} records ({} missing, {broken} broken, {frozen} below 0 °C), training until day {:.1}; {} skipped; harmonics in {} records; reference {:?}; tracked {tracked:?}; false alarms {}; change found after {delay:?} h",
            c.len(),
            c.len() - kept.len(),
            trained_until / 86400.0,
            report.skipped.len(),
            report.harmonics.len(),
            report
                .reference
                .iter()
                .map(|m| (m.frequency_hz * 1e3).round() / 1e3)
                .collect::<Vec<_>>(),
            false_alarms.len(),
        );
        for line in report.to_string().lines() {
            println!("  {line}");
        }
        // The modes judged together: no alarm before the change, the change within a day,
        // the changed mode its first driver.
        let joint = report.joint.as_ref().expect("a joint chart");
        let joint_false: Vec<_> = joint.alarms.iter().filter(|a| a.time < change).collect();
        let joint_delay = joint
            .alarms
            .iter()
            .find(|a| a.time >= change && a.drivers.first().map(|d| d.0) == changed)
            .map(|a| (a.time - change) / 3600.0);
        // The subspace test with its environmental model: its single-record threshold's
        // passes before the change, its chart's false alarms and delay (printed, not
        // asserted: on 48-day campaigns, trained on 288 records, it charts each mode's
        // frequency change and found the change within a day, docs/monitoring.md; this
        // 24-day campaign trains too few records for three block rows).
        let sub = report.subspace.as_ref().expect("a subspace chart");
        let first_change = sub.time.partition_point(|&t| t < change);
        let sub_passed = sub
            .above_threshold
            .iter()
            .filter(|&&i| i < first_change)
            .count();
        let sub_false = sub.alarms.iter().filter(|&&i| i < first_change).count();
        let sub_delay = sub
            .alarms
            .iter()
            .find(|&&i| i >= first_change)
            .map(|&i| (sub.time[i] - change) / 3600.0);
        println!(
            "seed {seed}: joint chart ({} shared factor(s)): {} false alarm(s), change found after {joint_delay:?} h; subspace test (regressed on {} term(s)): {sub_passed} of {} undamaged records above its 1 % threshold, {sub_false} chart alarm(s) before the change, change found after {sub_delay:?} h",
            joint.common_factors,
            joint_false.len(),
            sub.environment.as_ref().map_or(0, |e| e.terms.len()),
            first_change.saturating_sub(sub.training),
        );
        assert!(joint_false.is_empty(), "seed {seed}: {joint_false:?}");
        let joint_delay =
            joint_delay.unwrap_or_else(|| panic!("seed {seed}: joint chart: the change not found"));
        assert!(
            joint_delay <= 24.0,
            "seed {seed}: joint chart: {joint_delay} h"
        );
        assert_eq!(
            sub_false, 0,
            "seed {seed}: subspace chart alarmed before the change"
        );
        assert!(false_alarms.is_empty(), "seed {seed}: {false_alarms:?}");
        let delay = delay.unwrap_or_else(|| panic!("seed {seed}: the change not found"));
        assert!(delay <= 24.0, "seed {seed}: {delay} h");
        for (f, share) in &tracked {
            assert!(
                *share >= 0.95,
                "seed {seed}: mode {f} Hz tracked in {share}"
            );
        }
        assert!(
            report
                .reference
                .iter()
                .all(|m| (m.frequency_hz - 2.3).abs() > 0.05),
            "seed {seed}: the harmonic in the reference"
        );
        assert!(
            !report.harmonics.is_empty(),
            "seed {seed}: no harmonic named"
        );
        assert_eq!(report.skipped.len(), broken, "{:?}", report.skipped);
    }
}
