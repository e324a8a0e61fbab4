//! `cargo xtask bench command`: the whole `hyst ssi` command on a long ten-channel record, as
//! a user runs it (CSV in, JSON out), with its wall time and peak memory, beside pyOMA2's and
//! koma's SSI-cov identification of the same record in the same run.
//!
//! The record: ten channels, 10⁶ samples at 100 Hz, five modes 1.3–13.2 Hz damped 1–2.5 %
//! (`covssi::synth::ModalRecord`, fixed dense gains), 5 % white measurement noise, written once
//! under `target/bench/` with seven significant digits (a 24-bit sensor's resolution; 135 MB).
//! The peak memory is the maximum resident set size `/usr/bin/time` reports; the record as
//! f64 is 80 MB.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The record's modes: frequency (Hz) and damping ratio.
pub const MODES: [(f64, f64); 5] = [
    (1.3, 0.01),
    (3.4, 0.015),
    (6.1, 0.02),
    (9.5, 0.025),
    (13.2, 0.02),
];

/// Samples, channels and sampling rate of the record.
pub const SAMPLES: usize = 1_000_000;
pub const CHANNELS: usize = 10;
pub const FS: f64 = 100.0;

/// The record: ten channels reading every mode's two states through fixed dense gains.
pub fn record(n: usize, seed: u64) -> Vec<Vec<f64>> {
    covssi::synth::ModalRecord::new(FS, &MODES)
        .with_gains(crate::dense_gains(CHANNELS, MODES.len(), 0.3))
        .with_noise(0.05)
        .generate(n, seed)
}

/// The record as CSV under `dir` (made once, then reused).
fn record_csv(dir: &Path) -> Result<PathBuf, String> {
    let path = dir.join("ssi_1e6_10ch.csv");
    if path.is_file() {
        return Ok(path);
    }
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let y = record(SAMPLES, 2026);
    let tmp = dir.join("ssi_1e6_10ch.csv.part");
    let file = std::fs::File::create(&tmp).map_err(|e| format!("{}: {e}", tmp.display()))?;
    let mut w = std::io::BufWriter::new(file);
    let header: Vec<String> = (0..CHANNELS).map(|c| format!("y{c}")).collect();
    let io = |e: std::io::Error| format!("{}: {e}", tmp.display());
    writeln!(w, "{}", header.join(",")).map_err(io)?;
    for t in 0..SAMPLES {
        for (c, ch) in y.iter().enumerate() {
            let sep = if c + 1 == CHANNELS { '\n' } else { ',' };
            write!(w, "{:.6e}{sep}", ch[t]).map_err(io)?;
        }
    }
    w.flush().map_err(io)?;
    drop(w);
    std::fs::rename(&tmp, &path).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(path)
}

/// `hyst` built in release (the benches time the command as a user runs it): its path.
pub(crate) fn release_hyst() -> Result<PathBuf, String> {
    let root = hyst_testkit::workspace_root();
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let built = Command::new(cargo)
        .args(["build", "--release", "--quiet", "--bin", "hyst"])
        .current_dir(&root)
        .status()
        .map_err(|e| format!("cargo build: {e}"))?;
    if !built.success() {
        return Err("cargo build --release --bin hyst failed".into());
    }
    Ok(root.join("target").join("release").join("hyst"))
}

/// Wall time (s) and peak resident memory (MB) of `cmd`, by `/usr/bin/time`.
pub(crate) fn timed(cmd: &mut Command) -> Result<(f64, f64), String> {
    let out = cmd.output().map_err(|e| format!("could not start: {e}"))?;
    if !out.status.success() {
        return Err(format!(
            "failed ({}): {}",
            out.status,
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    let err = String::from_utf8_lossy(&out.stderr);
    let last = err
        .lines()
        .rev()
        .find(|l| l.starts_with("TIMED "))
        .ok_or("no /usr/bin/time line")?;
    let f: Vec<f64> = last
        .split_whitespace()
        .skip(1)
        .filter_map(|v| v.parse().ok())
        .collect();
    match f[..] {
        [secs, kb] => Ok((secs, kb / 1024.0)),
        _ => Err(format!("unreadable /usr/bin/time line: {last}")),
    }
}

/// Issue 76's many-channel target: `hyst ssi` with its defaults on a bridge deck's ambient
/// record of 66 channels (22 stations × 3 directions) over 30 minutes at 20 Hz
/// ([`hyst_sim::deck`]: modal superposition with red loads, close modes, a lowest mode at
/// 0.2 Hz), its time and peak memory against the targets (30 s, 1 GB), and how many of the
/// deck's 16 modes the answer holds.
fn deck(hyst: &Path, dir: &Path) -> Result<(), String> {
    use hyst_sim::deck::{BridgeDeck, DECK_MODES};
    let csv = dir.join("deck_66ch_30min.csv");
    let deck = BridgeDeck::with(22, 20.0);
    if !csv.is_file() {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        let y = deck.accelerations(76_201).map_err(|e| e.to_string())?;
        let names: Vec<String> = (0..y.len()).map(|c| format!("a{c}")).collect();
        let names: Vec<&str> = names.iter().map(String::as_str).collect();
        let columns: Vec<&[f64]> = y.iter().map(Vec::as_slice).collect();
        hyst_io::write_csv(&csv, &names, &columns).map_err(|e| e.to_string())?;
    }
    let json = dir.join("deck_66ch_30min.json");
    let (s, mb) = timed(
        Command::new("/usr/bin/time")
            .args(["-f", "TIMED %e %M"])
            .arg(hyst)
            .args(["ssi", "--fs", "20", "--input"])
            .arg(&csv)
            .arg("--json")
            .arg(&json),
    )?;
    let doc: serde_json::Value = std::fs::read_to_string(&json)
        .map_err(|e| format!("{}: {e}", json.display()))
        .and_then(|t| serde_json::from_str(&t).map_err(|e| e.to_string()))?;
    let answer: Vec<f64> = doc["modes"]
        .as_array()
        .map(|m| {
            m.iter()
                .filter_map(|m| m["frequency_hz"].as_f64())
                .collect()
        })
        .unwrap_or_default();
    // A deck mode is found when a reported mode lies within 1 % of it (the closest two are
    // 2.8 % apart).
    let found = DECK_MODES
        .iter()
        .filter(|t| {
            answer
                .iter()
                .any(|f| (f / t.frequency_hz - 1.0).abs() <= 0.01)
        })
        .count();
    println!(
        "hyst_ssi_s_deck_66ch_30min {s:.1} s (peak {mb:.0} MB; defaults; {found} of the deck's {} modes in {} reported; targets 30 s, 1024 MB)",
        DECK_MODES.len(),
        answer.len()
    );
    Ok(())
}

/// The median of three in-process reads of `csv` by hyst's reader (seconds).
fn read_seconds(csv: &Path) -> Result<f64, String> {
    let mut times = Vec::new();
    for _ in 0..3 {
        let t0 = std::time::Instant::now();
        let t = hyst_io::read_csv(csv).map_err(|e| e.to_string())?;
        times.push(t0.elapsed().as_secs_f64());
        if t.len() != SAMPLES {
            return Err(format!(
                "{}: read {} rows, not {SAMPLES}",
                csv.display(),
                t.len()
            ));
        }
    }
    times.sort_by(f64::total_cmp);
    Ok(times[1])
}

/// The bench: `hyst ssi` with its defaults (SSI's modes with the jackknife's errors) and
/// with `--refine`, from the CSV and from the `.npy` copy, and pyOMA2 and koma when their
/// environment exists; hyst's CSV reader beside pandas'.
pub fn run() -> Result<(), String> {
    let root = hyst_testkit::workspace_root();
    let target = root.join("target");
    let csv = record_csv(&target.join("bench"))?;
    let npy = target.join("bench").join("ssi_1e6_10ch.npy");
    let hyst = release_hyst()?;
    let json = target.join("bench").join("ssi_1e6_10ch.json");
    let run = |input: &Path, extra: &[&str]| {
        timed(
            Command::new("/usr/bin/time")
                .args(["-f", "TIMED %e %M"])
                .arg(&hyst)
                .args(["ssi", "--fs", "100", "--input"])
                .arg(input)
                .arg("--json")
                .arg(&json)
                .args(extra),
        )
    };
    let reader = read_seconds(&csv)?;
    println!("hyst_read_csv_s_1e6_10ch {reader:.3} s (hyst_io::read_csv, median of three)");
    // The peers' settings (20 block rows, no decimation), so that the ratios compare like
    // with like; the defaults read from this record (a lag of ten periods of 1.3 Hz, cut to
    // the Toeplitz budget of 120 block rows here) are timed on their own line.
    let same = ["--block-rows", "20", "--decimate", "1"];
    let (s, mb) = run(&csv, &same)?;
    println!("hyst_ssi_s_1e6_10ch {s:.2} s (from CSV, 20 block rows, as the peers)");
    println!("hyst_ssi_peak_mb_1e6_10ch {mb:.0} MB (the record as f64: 80 MB)");
    let (sd, mbd) = run(&csv, &[])?;
    println!(
        "hyst_ssi_defaults_s_1e6_10ch {sd:.2} s (peak {mbd:.0} MB; lag and decimation read from the record)"
    );
    let (sr, mbr) = run(&csv, &[&same[..], &["--refine"]].concat())?;
    println!("hyst_ssi_refine_s_1e6_10ch {sr:.2} s (peak {mbr:.0} MB; with --refine)");
    deck(&hyst, &target.join("bench"))?;
    let python = target.join("compare-venv").join("bin").join("python");
    if !python.is_file() {
        println!(
            "pyoma2_ssi_cov_s_1e6_10ch unavailable (no {}; `cargo xtask compare-tools` makes it)",
            python.display()
        );
        return Ok(());
    }
    let out = Command::new(&python)
        .arg(root.join("xtask/studies/compare/ssi_timing.py"))
        .arg(&csv)
        .arg("100")
        .arg(&npy)
        .env("OMP_NUM_THREADS", "1")
        .env("OPENBLAS_NUM_THREADS", "1")
        .env("MKL_NUM_THREADS", "1")
        .output()
        .map_err(|e| format!("ssi_timing.py: {e}"))?;
    if !out.status.success() {
        return Err(format!(
            "ssi_timing.py failed: {}",
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    let text = String::from_utf8_lossy(&out.stdout);
    let tool = |name: &str| -> Result<f64, String> {
        text.lines()
            .find_map(|l| l.strip_prefix(name)?.trim().parse().ok())
            .ok_or_else(|| format!("ssi_timing.py printed no {name} time: {text:?}"))
    };
    let (py, koma, pandas) = (tool("pyoma2 ")?, tool("koma ")?, tool("pandas_read_csv ")?);
    let (sn, _) = run(&npy, &same)?;
    println!("hyst_ssi_npy_s_1e6_10ch {sn:.2} s (from .npy, 20 block rows)");
    let (srn, _) = run(&npy, &[&same[..], &["--refine"]].concat())?;
    println!("hyst_ssi_npy_refine_s_1e6_10ch {srn:.2} s (from .npy, with --refine)");
    println!("pyoma2_ssi_cov_s_1e6_10ch {py:.2} s (identification only, one BLAS thread)");
    println!("koma_ssi_cov_s_1e6_10ch {koma:.2} s (identification only, one BLAS thread)");
    println!("pandas_read_csv_s_1e6_10ch {pandas:.3} s (pandas' C reader, median of three)");
    println!(
        "hyst_read_csv_over_pandas_1e6_10ch {:.2} (target at most 1)",
        reader / pandas
    );
    println!(
        "hyst_ssi_over_pyoma2_1e6_10ch {:.2} from CSV, {:.2} from .npy (target at most 1); with --refine {:.2} and {:.2}",
        s / py,
        sn / py,
        sr / py,
        srn / py
    );
    println!(
        "hyst_ssi_over_koma_1e6_10ch {:.2} from CSV, {:.2} from .npy; with --refine {:.2} and {:.2}",
        s / koma,
        sn / koma,
        sr / koma,
        srn / koma
    );
    Ok(())
}
