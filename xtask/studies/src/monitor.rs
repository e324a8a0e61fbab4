//! `cargo xtask monitor-demo`: issue 33's synthetic monitoring campaign made, identified and
//! tracked; prints the detection delay, the false alarms, how often each mode was tracked,
//! and the run time, and draws each mode's figures into `target/monitor/`.

use std::time::Instant;

use hyst_monitor::campaign::Campaign;
use hyst_monitor::{RecordModes, Side, TrackOptions, identify_record, track};
use rayon::prelude::*;

/// The campaign's size, on the command line.
#[derive(clap::Args, Debug)]
pub struct DemoArgs {
    /// Days recorded (the change comes on day 45 of the default 60).
    #[arg(long, default_value_t = 60)]
    days: usize,
    /// Records per day.
    #[arg(long, default_value_t = 24)]
    per_day: usize,
    /// The campaign's seed.
    #[arg(long, default_value_t = 700_000)]
    seed: u64,
    /// The day the stiffness loss starts.
    #[arg(long, default_value_t = 45.0)]
    change_day: f64,
    /// The relative frequency change the temperature does not explain (standard deviation).
    #[arg(long, default_value_t = 2e-4)]
    unexplained: f64,
    /// Its correlation time in hours (0: independent from record to record).
    #[arg(long, default_value_t = 0.0)]
    unexplained_hours: f64,
}

/// Peak resident memory so far (MB), from /proc (0 where there is none).
fn peak_mb() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|v| v.parse::<f64>().ok())
        })
        .map_or(0.0, |kb| kb / 1024.0)
}

pub fn run(a: &DemoArgs) -> Result<(), String> {
    let mut campaign = Campaign::default();
    campaign.days = a.days;
    campaign.per_day = a.per_day;
    campaign.seed = a.seed;
    campaign.unexplained = a.unexplained;
    campaign.unexplained_hours = a.unexplained_hours;
    if let Some(c) = campaign.change.as_mut() {
        c.0 = a.change_day;
    }
    let n = campaign.len();
    let t0 = Instant::now();
    let (records, half_peak) = identify_campaign(&campaign);
    let identify_s = t0.elapsed().as_secs_f64();
    let mut opts = TrackOptions::default();
    opts.training = (campaign.per_day * 14).min(n / 2);
    let mut report = track(&records, None, &opts).map_err(|e| e.to_string())?;
    // The campaign's one covariate.
    report.name_covariates(vec!["temperature".to_string()]);
    let total_s = t0.elapsed().as_secs_f64();
    println!(
        "monitor_records {n} ({} days × {}/day, {} s at {} Hz, {} channels; unexplained {:e} correlated over {} h)",
        campaign.days,
        campaign.per_day,
        campaign.seconds,
        campaign.fs,
        campaign.channels,
        campaign.unexplained,
        campaign.unexplained_hours
    );
    for (j, (m, share)) in report.reference.iter().zip(&report.tracked).enumerate() {
        println!(
            "monitor_mode {}: {:.4} Hz, tracked in {:.2} % of the records",
            report.mode_name(j),
            m.frequency_hz,
            100.0 * share
        );
    }
    println!("monitor_skipped {}", report.skipped.len());
    println!(
        "monitor_split {} (record × mode held twice with one shape, not tracked there)",
        report.split.len()
    );
    let change = campaign.change;
    // The alarms before the change: false ones.
    let false_alarms = |r: &hyst_monitor::TrackReport| -> Vec<hyst_monitor::ModeAlarm> {
        r.alarms
            .iter()
            .filter(|al| change.is_none_or(|(day, _, _)| al.time < day * 86400.0))
            .cloned()
            .collect()
    };
    let before = false_alarms(&report);
    println!("monitor_false_alarms {}", before.len());
    // The same records charted without whitening, for comparison.
    let mut raw_opts = opts.clone();
    raw_opts.whiten = false;
    let raw = track(&records, None, &raw_opts).map_err(|e| e.to_string())?;
    println!(
        "monitor_false_alarms_unwhitened {}",
        false_alarms(&raw).len()
    );
    for (j, m) in report.residual_models.iter().enumerate() {
        if let Some(m) = m {
            println!(
                "  mode {j}: a slow effect of {:.2e} Hz, persistence {:.3} (−2 ln L down {:.1}); {:.0} % of a lasting change kept",
                m.latent_var.sqrt(),
                m.persistence,
                m.deviance_drop,
                100.0 * m.lasting_change_share
            );
        }
    }
    for al in &before {
        println!(
            "  false alarm: mode {} at day {:.2} ({:?})",
            al.mode,
            al.time / 86400.0,
            al.side
        );
    }
    if let Some((day, mode, _)) = change {
        let hit = report
            .alarms
            .iter()
            .find(|al| al.mode == mode && al.side == Side::Down && al.time >= day * 86400.0);
        match hit {
            Some(al) => println!(
                "monitor_detection_delay_h {:.1}",
                (al.time / 86400.0 - day) * 24.0
            ),
            None => println!("monitor_detection_delay_h none (not detected)"),
        }
    }
    subspace_lines(&report, change.map(|(day, _, _)| day));
    joint_lines(&report, change.map(|(day, _, _)| day));
    println!(
        "monitor_in_control_run_length {:.3e} records per mode",
        report.in_control_run_length
    );
    println!("monitor_identify_s {identify_s:.1}");
    println!("monitor_total_s {total_s:.1}");
    println!(
        "monitor_records_per_minute {:.1}",
        n as f64 / identify_s * 60.0
    );
    println!(
        "monitor_peak_mb_half {half_peak:.0} monitor_peak_mb_all {:.0}",
        peak_mb()
    );
    let dir = hyst_testkit::workspace_root().join("target/monitor");
    hyst::figures::track_figures(&dir, &report)?;
    println!("figures in {}", dir.display());
    Ok(())
}

/// The joint chart's figures beside the modes' own: its shared factors, false alarms before
/// the change and delay after it (the first alarm at or after it).
fn joint_lines(report: &hyst::monitor::TrackReport, change_day: Option<f64>) {
    let Some(c) = &report.joint else {
        println!(
            "monitor_joint not drawn: {}",
            report.joint_error.as_deref().unwrap_or("not asked")
        );
        return;
    };
    let change = change_day.map_or(f64::INFINITY, |d| d * 86400.0);
    let early = c.alarms.iter().filter(|a| a.time < change).count();
    println!(
        "monitor_joint_shared_factors {} (eigenvalues {:?}, edge {:.2})",
        c.common_factors, c.eigenvalues, c.noise_edge
    );
    println!("monitor_joint_false_alarms {early}");
    match c.alarms.iter().find(|a| a.time >= change) {
        Some(a) => println!(
            "monitor_joint_detection_delay_h {:.1} (first driver mode {})",
            (a.time - change) / 3600.0,
            a.drivers
                .first()
                .map_or_else(String::new, |d| report.mode_name(d.0))
        ),
        None => println!("monitor_joint_detection_delay_h none (not detected)"),
    }
}

/// The subspace test's figures beside the modal chart's: records above its single-record
/// threshold before the change (against the nominal rate), its CUSUM's false alarms, and its
/// delay.
fn subspace_lines(report: &hyst::monitor::TrackReport, change_day: Option<f64>) {
    let Some(c) = &report.subspace else {
        println!(
            "monitor_subspace not run: {}",
            report
                .subspace_error
                .as_deref()
                .unwrap_or("no correlations")
        );
        return;
    };
    let change = change_day.map_or(f64::INFINITY, |d| d * 86400.0);
    let undamaged = (c.training..c.t2.len())
        .filter(|&i| c.time[i] < change)
        .count();
    let above = c
        .above_threshold
        .iter()
        .filter(|&&i| c.time[i] < change)
        .count();
    let early = c.alarms.iter().filter(|&&i| c.time[i] < change).count();
    println!(
        "monitor_subspace_above_threshold {above} of {undamaged} undamaged records (nominal {} %)",
        100.0 * c.alpha
    );
    println!("monitor_subspace_false_alarms {early}");
    match c.alarms.iter().find(|&&i| c.time[i] >= change) {
        Some(&i) => println!(
            "monitor_subspace_detection_delay_h {:.1}",
            (c.time[i] - change) / 3600.0
        ),
        None => println!("monitor_subspace_detection_delay_h none (not detected)"),
    }
}

/// `cargo xtask bench monitor`: issue 33's throughput figure. Four 1-hour records of the
/// campaign's structure on 10 sensors at 100 Hz (360 000 × 10 samples), identified two at a
/// time (the machine's two cores) as `hyst track` does; records per minute, and the peak
/// memory against one record's size.
pub fn bench() {
    bench_estimates();
    let mut campaign = Campaign::default();
    campaign.fs = 100.0;
    campaign.seconds = 3600.0;
    campaign.channels = 10;
    campaign.seed = 760_000;
    let analysis = covssi::AnalysisOptions::default().with_ssi(covssi::SsiOptions {
        block_rows: covssi::BlockRows::Seconds(3.0),
        ..covssi::SsiOptions::default()
    });
    let records = 4;
    let t0 = Instant::now();
    let identified: Vec<usize> = (0..records)
        .into_par_iter()
        .map(|i| {
            let r = campaign.record(i);
            let views: Vec<&[f64]> = r.channels.iter().map(|c| c.as_slice()).collect();
            identify_record(&views, campaign.fs, &analysis).map_or(0, |m| m.modes.len())
        })
        .collect();
    let s = t0.elapsed().as_secs_f64();
    let record_mb = 360_000.0 * 10.0 * 8.0 / 1e6;
    println!(
        "monitor_records_per_minute_1h_10ch_100hz {:.1} ({records} records in {s:.1} s, generation included; modes found {identified:?})",
        records as f64 / s * 60.0
    );
    println!(
        "monitor_peak_mb_1h_10ch_100hz {:.0} (one record is {record_mb:.0} MB; two in flight)",
        peak_mb()
    );
}

/// `hyst track --estimates`'s reader on tables of 10⁵ and 10⁶ rows (four modes with
/// standard errors and damping): the time to read each, and the peak memory after each
/// (issue 58: ≤ 10 s for 10⁶ rows, memory linear in rows; it was quadratic in time).
fn bench_estimates() {
    let dir = std::env::temp_dir().join(format!("hyst-bench-est-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    for rows in [100_000usize, 1_000_000] {
        let path = dir.join(format!("estimates_{rows}.csv"));
        let mut text = String::from("record,time");
        for m in 1..=4 {
            text.push_str(&format!(",f{m}_hz,f{m}_hz_se,f{m}_damping"));
        }
        text.push('\n');
        for i in 0..rows {
            text.push_str(&format!("r{i},{}", 3600 * i));
            for m in 1..=4 {
                let f = m as f64 * (1.0 + 1e-3 * ((i * 7919 % 1000) as f64 / 1000.0 - 0.5));
                text.push_str(&format!(",{f:.6},0.001,0.012"));
            }
            text.push('\n');
        }
        if let Err(e) = std::fs::write(&path, &text) {
            println!("estimates_read_s_{rows}_rows failed: {e}");
            return;
        }
        let mb = text.len() as f64 / 1e6;
        drop(text);
        let t0 = Instant::now();
        let read = hyst::io::read_estimates(&path);
        let s = t0.elapsed().as_secs_f64();
        match read {
            Ok(t) => println!(
                "estimates_read_s_{rows}_rows {s:.2} ({} rows, {mb:.0} MB of text; target ≤ 10 s at 10⁶)",
                t.rows.len()
            ),
            Err(e) => println!("estimates_read_s_{rows}_rows failed: {e}"),
        }
        println!(
            "estimates_peak_mb_after_{rows}_rows {:.0} (the process's peak so far)",
            peak_mb()
        );
        let _ = std::fs::remove_file(&path);
    }
    let _ = std::fs::remove_dir(&dir);
}

/// Every record of `campaign` identified, in two halves (to see whether memory grows with the
/// records done); the records and the peak memory after the first half (MB).
fn identify_campaign(campaign: &Campaign) -> (Vec<RecordModes>, f64) {
    let n = campaign.len();
    let analysis = covssi::AnalysisOptions::default().with_ssi(covssi::SsiOptions {
        block_rows: covssi::BlockRows::Seconds(3.0),
        ..covssi::SsiOptions::default()
    });
    let bar = indicatif::ProgressBar::new(n as u64);
    let mut half_peak = 0.0;
    let mut records: Vec<RecordModes> = Vec::with_capacity(n);
    // In two halves, to see whether memory grows with the records done.
    for range in [0..n / 2, n / 2..n] {
        let part: Vec<RecordModes> = range
            .into_par_iter()
            .map(|i| {
                let r = campaign.record(i);
                let views: Vec<&[f64]> = r.channels.iter().map(|c| c.as_slice()).collect();
                let outcome =
                    identify_record(&views, campaign.fs, &analysis).map_err(|e| e.to_string());
                bar.inc(1);
                RecordModes {
                    name: format!("record {i}"),
                    time: r.time_s,
                    covariates: vec![r.temperature],
                    outcome,
                }
            })
            .collect();
        records.extend(part);
        if half_peak == 0.0 {
            half_peak = peak_mb();
        }
    }
    bar.finish_and_clear();
    (records, half_peak)
}
