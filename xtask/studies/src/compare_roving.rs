//! The synthetic roving test with truth (`covssi::synth::RovingTest`, the records
//! `crates/covssi/tests/integration/multisetup.rs` calibrates the merge on) for `cargo xtask
//! compare-setups`: the records written for pyOMA2 (one CSV per setup), then hyst's merge and
//! pyOMA2's PoSER each against the truth (MAC), seed by seed.

use std::path::Path;

use covssi::Complex64 as C64;
use covssi::mac;
use covssi::multisetup::{MergeOptions, SetupModes, merge};
use covssi::synth::{RovingChannel, RovingTest};

/// Seeds of the comparison: fresh when it was written (1000 apart).
const SEEDS: [u64; 5] = [5_600_001, 5_601_001, 5_602_001, 5_603_001, 5_604_001];

/// pyOMA2's SSI-cov settings: hyst's block rows on these records (read from them: 96) and
/// order 40, hyst's default largest order.
const BLOCK_ROWS: usize = 96;
const MAX_ORDER: usize = 40;

/// Every seed's setups as CSV files (one column per channel, the roving channels first, then
/// the references) in `dir`, and `roving.json` describing them for the Python side.
pub fn write(dir: &Path) -> Result<(), String> {
    let t = RovingTest::cantilever(2);
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let mut seeds = Vec::new();
    for seed in SEEDS {
        let mut files = Vec::new();
        let mut references = Vec::new();
        for (s, chans) in t.layout().iter().enumerate() {
            let y = t.record(s, seed);
            let name = format!("roving_{seed}_{s}.csv");
            let mut text = String::new();
            for n in 0..t.samples {
                let row: Vec<String> = y.iter().map(|c| format!("{:e}", c[n])).collect();
                text.push_str(&row.join(","));
                text.push('\n');
            }
            std::fs::write(dir.join(&name), text).map_err(|e| format!("{name}: {e}"))?;
            files.push(name);
            let refs: Vec<usize> = (0..chans.len()).filter(|&c| chans[c].reference).collect();
            references.push(refs);
        }
        seeds.push(serde_json::json!({"seed": seed, "files": files, "references": references}));
    }
    let manifest = serde_json::json!({
        "fs": t.fs,
        "block_rows": BLOCK_ROWS,
        "max_order": MAX_ORDER,
        "truth_hz": t.modes.iter().map(|m| m.0).collect::<Vec<_>>(),
        "seeds": seeds,
    });
    std::fs::write(dir.join("roving.json"), manifest.to_string()).map_err(|e| e.to_string())
}

/// hyst's merge of `seed`'s setups (analysed as `hyst ssi --setups` analyses them): each
/// mode's frequency and MAC to the truth over every node.
fn hyst_merge(t: &RovingTest, seed: u64) -> Result<Vec<(f64, f64)>, String> {
    let opts = hyst::settings::SsiSettings::default()
        .analysis()
        .map_err(|e| e.to_string())?;
    let mut setups = Vec::new();
    for (s, chans) in t.layout().iter().enumerate() {
        let y = t.record(s, seed);
        let views: Vec<&[f64]> = y.iter().map(Vec::as_slice).collect();
        let a = covssi::analyze(&views, t.fs, &opts).map_err(|e| e.to_string())?;
        setups.push(SetupModes {
            name: format!("setup {}", s + 1),
            channels: chans.iter().map(RovingChannel::setup_channel).collect(),
            modes: a.reported_modes(),
        });
    }
    let merged = merge(&setups, &MergeOptions::default()).map_err(|e| e.to_string())?;
    Ok(t.modes
        .iter()
        .enumerate()
        .map(|(j, &(f, _))| {
            let near = merged.modes.iter().min_by(|a, b| {
                (a.frequency_hz - f)
                    .abs()
                    .total_cmp(&(b.frequency_hz - f).abs())
            });
            near.map_or((f64::NAN, f64::NAN), |m| {
                let (shape, truth): (Vec<C64>, Vec<C64>) = merged
                    .dofs
                    .iter()
                    .zip(&m.shape)
                    .filter_map(|(d, v)| {
                        let k: usize = d.node.parse().ok()?;
                        Some(((*v)?, C64::new(t.truth(j, k), 0.0)))
                    })
                    .unzip();
                (m.frequency_hz, mac(&shape, &truth))
            })
        })
        .collect())
}

/// Prints, seed by seed and mode by mode, hyst's and PoSER's frequency and MAC to the truth
/// (PoSER's over all its rows, and over the roving rows alone), and the means.
pub fn compare(py: &serde_json::Value) -> Result<(), String> {
    let t = RovingTest::cantilever(2);
    let layout = t.layout();
    // PoSER's rows: the references (as the first setup orders them), then each setup's
    // roving channels.
    let mut rows: Vec<(usize, bool)> = layout[0]
        .iter()
        .filter(|c| c.reference)
        .map(|c| (c.node, true))
        .collect();
    for chans in &layout {
        rows.extend(
            chans
                .iter()
                .filter(|c| !c.reference)
                .map(|c| (c.node, false)),
        );
    }
    println!(
        "\nsynthetic roving test (5 setups, 2 reference accelerometers, velocities roving; {} seeds):",
        SEEDS.len()
    );
    println!("  seed     mode  truth Hz | hyst Hz   MAC     | PoSER Hz  MAC all  MAC roving");
    let empty = Vec::new();
    let runs = py["roving"].as_array().unwrap_or(&empty);
    let (mut sums, mut n) = ([0.0f64; 3], 0usize);
    for (seed, run) in SEEDS.iter().zip(runs) {
        let ours = hyst_merge(&t, *seed)?;
        let fns = crate::json_values::numbers(&run["fn"]);
        let phis: Vec<Vec<C64>> = run["phi"]
            .as_array()
            .map(|a| a.iter().map(crate::json_values::complex).collect())
            .unwrap_or_default();
        for (j, &(f, _)) in t.modes.iter().enumerate() {
            let (hf, hmac) = ours[j];
            let phi = phis.get(j).cloned().unwrap_or_default();
            let pick = |roving_only: bool| -> f64 {
                let (a, b): (Vec<C64>, Vec<C64>) = rows
                    .iter()
                    .zip(&phi)
                    .filter(|((_, is_ref), _)| !(roving_only && *is_ref))
                    .map(|((node, _), v)| (*v, C64::new(t.truth(j, *node), 0.0)))
                    .unzip();
                mac(&a, &b)
            };
            let (all, roving) = (pick(false), pick(true));
            println!(
                "  {seed}  {j}  {f:>8.4} | {hf:>8.4}  {hmac:.5} | {:>8.4}  {all:.5}  {roving:.5}",
                fns.get(j).copied().unwrap_or(f64::NAN)
            );
            for (s, v) in sums.iter_mut().zip([hmac, all, roving]) {
                *s += v;
            }
            n += 1;
        }
    }
    if n > 0 {
        println!(
            "  mean MAC to the truth: hyst {:.5}; PoSER {:.5} over all rows, {:.5} over the roving rows",
            sums[0] / n as f64,
            sums[1] / n as f64,
            sums[2] / n as f64
        );
    }
    Ok(())
}
