//! `cargo xtask compare-setups`: hyst's multi-setup merge and EFDD beside pyOMA2's on the same
//! files, in one run — the steel frame's 15 setups merged by hyst and by pyOMA2's PoSER and
//! PreGER (frequencies, damping, and the MAC of each merged shape with hyst's in the channels'
//! own units), FDD/EFDD on the OMA records with truth (values and time), and both merges on
//! synthetic roving setups with truth ([`crate::compare_roving`]).
//!
//! pyOMA2 runs in `target/compare-venv` (made by `cargo xtask compare-tools`), driven by
//! `xtask/studies/compare/setups_fdd.py`.

use crate::json_values::{complex, numbers};
use std::path::Path;
use std::process::Command;
use std::time::Instant;

use covssi::Complex64 as C64;
use covssi::fdd::{FddOptions, efdd, fdd};
use covssi::multisetup::MergeOptions;
use hyst::io::{ReadOptions, read_record, read_setups};

const README_HZ: [f64; 11] = [
    1.2287, 1.4359, 2.1000, 4.0172, 4.7706, 6.6822, 7.6156, 9.6652, 12.1668, 12.5982, 13.863,
];

pub fn run() -> Result<(), String> {
    let root = hyst_testkit::workspace_root();
    let python = root.join("target/compare-venv/bin/python");
    if !python.is_file() {
        return Err(
            "target/compare-venv is missing: run `cargo xtask compare-tools` once to make it"
                .into(),
        );
    }
    let data = hyst_testkit::data_dir().ok_or("no shared data folder: set HYST_DATA_DIR")?;
    let roving = root.join("target/compare-setups");
    crate::compare_roving::write(&roving)?;
    eprintln!("pyOMA2 (PoSER, PreGER, FDD, EFDD) ...");
    let out = Command::new(&python)
        .arg(root.join("xtask/studies/compare/setups_fdd.py"))
        .arg(&data)
        .arg(&roving)
        .output()
        .map_err(|e| format!("python: {e}"))?;
    if !out.status.success() {
        return Err(format!(
            "setups_fdd.py failed: {}",
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    let py: serde_json::Value =
        serde_json::from_slice(&out.stdout).map_err(|e| format!("setups_fdd.py's output: {e}"))?;
    steelframe(&data, &py)?;
    oma_efdd(&data, &py)?;
    crate::compare_roving::compare(&py)
}

fn steelframe(data: &Path, py: &serde_json::Value) -> Result<(), String> {
    let setups = read_setups(&data.join("steelframe")).map_err(|e| e.to_string())?;
    // As `hyst ssi --setups` analyses them: SSI's modes with the jackknife's errors.
    let opts = hyst::settings::SsiSettings::default()
        .analysis()
        .map_err(|e| e.to_string())?;
    let t0 = Instant::now();
    let report = hyst::setups::analyze_setups(
        &setups,
        None,
        &ReadOptions::default(),
        &opts,
        &MergeOptions::default(),
    )
    .map_err(|e| e.to_string())?;
    let seconds = t0.elapsed().as_secs_f64();
    let m = &report.merged;
    println!(
        "steel frame, 15 setups: hyst {seconds:.1} s, pyOMA2 PoSER {:.1} s, PreGER {:.1} s (each setup identified and merged)",
        py["poser"]["seconds"].as_f64().unwrap_or(f64::NAN),
        py["preger"]["seconds"].as_f64().unwrap_or(f64::NAN)
    );
    println!(
        "{:>9} | {:>20} {:>16} | {:>17} {:>7} {:>6} | {:>9} {:>7} {:>6}",
        "README Hz",
        "hyst f (Hz)",
        "ζ (%)",
        "PoSER f ± sd",
        "ζ (%)",
        "MAC",
        "PreGER f",
        "ζ (%)",
        "MAC"
    );
    let (pf, psd, pz) = (
        numbers(&py["poser"]["fn"]),
        numbers(&py["poser"]["fn_std"]),
        numbers(&py["poser"]["xi"]),
    );
    let (gf, gz) = (numbers(&py["preger"]["fn"]), numbers(&py["preger"]["xi"]));
    let pphi: Vec<Vec<C64>> = py["poser"]["phi"]
        .as_array()
        .map(|a| a.iter().map(complex).collect())
        .unwrap_or_default();
    let gphi: Vec<Vec<C64>> = py["preger"]["phi"]
        .as_array()
        .map(|a| a.iter().map(complex).collect())
        .unwrap_or_default();
    for (j, &f) in README_HZ.iter().enumerate() {
        let Some(mode) = m
            .modes
            .iter()
            .find(|x| (x.frequency_hz - f).abs() < 0.01 * f)
        else {
            println!("{f:>9.4} | hyst: not found");
            continue;
        };
        // hyst's merged shape in pyOMA2's rows (the references, then each setup's lasers), in
        // the channels' own units: displacement × λ (velocity) or λ² (acceleration).
        let lambda = covssi::synth::pole(mode.frequency_hz, mode.damping_ratio);
        let mut rows = Vec::new();
        for (s, setup) in setups.iter().enumerate() {
            for ch in &setup.channels {
                if ch.reference && s > 0 {
                    continue;
                }
                let d = m.dofs.iter().position(|d| {
                    d.node == ch.node
                        && (0..3)
                            .map(|k| d.direction[k] * ch.direction[k])
                            .sum::<f64>()
                            > 0.9999
                });
                let v = d
                    .and_then(|d| mode.shape[d])
                    .unwrap_or(C64::new(f64::NAN, 0.0));
                rows.push(v * ch.gain * lambda.powi(ch.quantity.power()));
            }
        }
        // pyOMA2's rows put the references first: move setup 1's two references there.
        let (refs, rest): (Vec<C64>, Vec<C64>) =
            (rows[3..5].to_vec(), [&rows[..3], &rows[5..]].concat());
        let ours: Vec<C64> = refs.into_iter().chain(rest).collect();
        let mac_with = |other: Option<&Vec<C64>>| {
            other.and_then(|o| {
                let (a, b): (Vec<C64>, Vec<C64>) = ours
                    .iter()
                    .zip(o)
                    .filter(|(a, b)| a.is_finite() && b.is_finite())
                    .map(|(a, b)| (*a, *b))
                    .unzip();
                (a.len() == ours.len()).then(|| covssi::mac(&a, &b))
            })
        };
        let found = |v: Option<&f64>| v.copied().filter(|x| (x - f).abs() < 0.01 * f);
        let cell = |x: Option<f64>, d: usize| x.map_or("—".to_string(), |v| format!("{v:.d$}"));
        println!(
            "{f:>9.4} | {:>9.4} ± {:<8.4} {:>6.3} ± {:<6.3} | {:>9} {:>7} {:>7} {:>6} | {:>9} {:>7} {:>6}",
            mode.frequency_hz,
            mode.frequency_se_hz.unwrap_or(f64::NAN),
            100.0 * mode.damping_ratio,
            100.0 * mode.damping_se.unwrap_or(f64::NAN),
            cell(found(pf.get(j)), 4),
            cell(psd.get(j).copied(), 4),
            cell(pz.get(j).map(|z| 100.0 * z), 3),
            cell(found(pf.get(j)).and(mac_with(pphi.get(j))), 3),
            cell(found(gf.get(j)), 4),
            cell(found(gf.get(j)).and(gz.get(j).map(|z| 100.0 * z)), 3),
            cell(found(gf.get(j)).and(mac_with(gphi.get(j))), 3),
        );
    }
    println!(
        "(PoSER's ± is the setups' standard deviation; pyOMA2 gives no damping or shape error. — : not within 1 % of the README's frequency.)"
    );
    Ok(())
}

fn oma_efdd(data: &Path, py: &serde_json::Value) -> Result<(), String> {
    println!("\nFDD/EFDD on the OMA records (truth files), nxseg 4096, Welch 50 %:");
    for name in ["sdof", "3dof"] {
        let table = read_record(
            &data.join(format!("oma/data_{name}.csv")),
            &ReadOptions::default(),
        )
        .map_err(|e| e.to_string())?;
        let y: Vec<&[f64]> = table
            .names
            .iter()
            .zip(&table.columns)
            .filter(|(n, _)| n.as_str() != "t")
            .map(|(_, c)| c.as_slice())
            .collect();
        let truth: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(data.join(format!("oma/truth_{name}.json")))
                .map_err(|e| e.to_string())?,
        )
        .map_err(|e| e.to_string())?;
        let (tf, tz) = (numbers(&truth["fn_hz"]), numbers(&truth["zeta"]));
        let mut opts = FddOptions::default();
        opts.segment = Some(4096);
        let t0 = Instant::now();
        let mut ours = Vec::new();
        const REPEATS: usize = 5;
        for _ in 0..REPEATS {
            let spectra = fdd(&y, 20.0, &opts).map_err(|e| e.to_string())?;
            ours = tf.iter().map(|&f| efdd(&spectra, f, &opts)).collect();
        }
        let ms = 1000.0 * t0.elapsed().as_secs_f64() / REPEATS as f64;
        let p = &py["efdd"][name]["efdd"];
        let pyms = 1000.0 * p["seconds"].as_f64().unwrap_or(f64::NAN);
        println!(
            "{name}: covssi {ms:.0} ms, pyOMA2 {}",
            p["error"]
                .as_str()
                .map_or(format!("{pyms:.0} ms"), |e| format!("failed: {e}"))
        );
        let (pf, pz) = (numbers(&p["fn"]), numbers(&p["xi"]));
        for (j, (&f, &z)) in tf.iter().zip(&tz).enumerate() {
            let pct = |v: f64, t: f64| format!("{:+.2} %", 100.0 * (v / t - 1.0));
            let e = ours[j].as_ref();
            println!(
                "  mode {} ({f:.4} Hz, ζ {z:.3}): covssi f {} ζ {} | pyOMA2 f {} ζ {}",
                j + 1,
                e.map_or("—".into(), |e| pct(e.frequency_hz, f)),
                e.map_or("—".into(), |e| pct(e.damping_ratio, z)),
                pf.get(j).map_or("—".into(), |v| pct(*v, f)),
                pz.get(j).map_or("—".into(), |v| pct(*v, z)),
            );
        }
    }
    Ok(())
}
