//! `cargo xtask bench setups`: `hyst ssi --setups` on the steel frame's 15 setups (each
//! identified with the jackknife's errors, then merged), as a user runs it, with its wall time,
//! peak memory and JSON's size, beside pyOMA2's PoSER and PreGER merging the same files in the
//! same run, and its time with `--refine` (the maximum-likelihood refinement, off by default);
//! and how often the analysis tells its progress (the longest time between two
//! reports of `hyst::setups::analyze_setups_with_progress`, run in this process).
//!
//! PoSER's and PreGER's times leave out loading the records (`setups_timing.py`, through
//! `setups_fdd.steelframe`), hyst's include it and writing the JSON: the ratio is not in
//! hyst's favour. pyOMA2 uses the BLAS threads it finds; hyst rayon's (both cores here).

use std::process::Command;
use std::sync::Mutex;
use std::time::Instant;

use crate::bench_command::{release_hyst, timed};

pub fn run() -> Result<(), String> {
    let root = hyst_testkit::workspace_root();
    let Some(data) = hyst_testkit::data_dir() else {
        println!("hyst_setups_s_steelframe skipped: no shared data (set HYST_DATA_DIR)");
        return Ok(());
    };
    let frame = data.join("steelframe");
    let hyst = release_hyst()?;
    let out = root.join("target/bench");
    std::fs::create_dir_all(&out).map_err(|e| format!("{}: {e}", out.display()))?;
    let json = out.join("steelframe_setups.json");
    // `hyst ssi --setups FRAME …` under /usr/bin/time: its wall time and peak memory.
    let setups_timed = |more: &[&std::ffi::OsStr]| {
        timed(
            Command::new("/usr/bin/time")
                .args(["-f", "TIMED %e %M"])
                .arg(&hyst)
                .args(["ssi", "--setups"])
                .arg(&frame)
                .args(more),
        )
    };
    let (s, mb) = setups_timed(&["--json".as_ref(), json.as_os_str()])?;
    let text = std::fs::read_to_string(&json).map_err(|e| format!("{}: {e}", json.display()))?;
    let report: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| format!("{}: {e}", json.display()))?;
    let modes = report["merged"]["modes"].as_array().map_or(0, Vec::len);
    println!(
        "hyst_setups_s_steelframe {s:.2} s (15 setups, each with its jackknife; {modes} merged modes)"
    );
    println!("hyst_setups_peak_mb_steelframe {mb:.0} MB (target at most 300)");
    println!(
        "hyst_setups_json_mb_steelframe {:.2} MB",
        text.len() as f64 / 1e6
    );
    // The same with the refinement asked for (`--refine`): its share of the time.
    let (refined, _) = setups_timed(&["--refine".as_ref()])?;
    println!("hyst_setups_refine_s_steelframe {refined:.2} s (the same, --refine)");
    progress_gap(&frame)?;
    let python = root.join("target/compare-venv/bin/python");
    if !python.is_file() {
        println!(
            "pyoma2_poser_s_steelframe unavailable (no {}; `cargo xtask compare-tools` makes it)",
            python.display()
        );
        return Ok(());
    }
    let run = Command::new(&python)
        .arg(root.join("xtask/studies/compare/setups_timing.py"))
        .arg(&frame)
        .output()
        .map_err(|e| format!("setups_timing.py: {e}"))?;
    if !run.status.success() {
        return Err(format!(
            "setups_timing.py failed: {}",
            String::from_utf8_lossy(&run.stderr)
        ));
    }
    let py: serde_json::Value = serde_json::from_slice(&run.stdout)
        .map_err(|e| format!("setups_timing.py's output: {e}"))?;
    let seconds = |name: &str| {
        py[name]["seconds"]
            .as_f64()
            .ok_or_else(|| format!("setups_timing.py gave no {name} time"))
    };
    let (poser, preger) = (seconds("poser")?, seconds("preger")?);
    println!(
        "pyoma2_poser_s_steelframe {poser:.2} s (SSI-cov per setup at 100 block rows, no errors; loading excluded)"
    );
    println!("pyoma2_preger_s_steelframe {preger:.2} s");
    println!(
        "hyst_setups_over_poser_steelframe {:.2} (defaults: SSI with its jackknife)",
        s / poser
    );
    println!(
        "hyst_setups_refine_over_poser_steelframe {:.2} (target at most 1.5)",
        refined / poser
    );
    Ok(())
}

/// The longest time between two progress reports of the setups' analysis, and the step it
/// followed.
fn progress_gap(frame: &std::path::Path) -> Result<(), String> {
    let setups = hyst::io::read_setups(frame).map_err(|e| e.to_string())?;
    let opts = hyst::settings::SsiSettings::default()
        .analysis()
        .map_err(|e| e.to_string())?;
    let t0 = Instant::now();
    // (time of the last report, its step, longest gap, the step before it)
    let last = Mutex::new((0.0f64, String::new(), 0.0f64, String::new()));
    hyst::setups::analyze_setups_with_progress(
        &setups,
        None,
        &hyst::io::ReadOptions::default(),
        &opts,
        &covssi::multisetup::MergeOptions::default(),
        &|p| {
            let now = t0.elapsed().as_secs_f64();
            if std::env::var_os("HYST_BENCH_TIMELINE").is_some() && p.setup.is_none() {
                eprintln!("{now:.2} s: {}", p.what);
            }
            if let Ok(mut l) = last.lock() {
                if now - l.0 > l.2 {
                    l.2 = now - l.0;
                    l.3 = l.1.clone();
                }
                l.0 = now;
                l.1 = format!("{}: {}", p.setup.unwrap_or("all"), p.what);
            }
        },
    )
    .map_err(|e| e.to_string())?;
    let end = t0.elapsed().as_secs_f64();
    let (at, step, mut gap, mut before) = last.into_inner().map_err(|e| e.to_string())?;
    if end - at > gap {
        gap = end - at;
        before = step;
    }
    println!(
        "hyst_setups_progress_longest_gap_s_steelframe {gap:.2} s (of {end:.2} s; after \"{before}\"; target at most 5)"
    );
    Ok(())
}
