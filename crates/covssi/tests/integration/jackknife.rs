//! The jackknife's standard errors of SSI's modes against their errors over seeds: three
//! modes of known frequency, damping and (real) shape seen by three accelerometers, records made by
//! `covssi::synth` (the modes' states stepped exactly, not SSI's model), SSI without its
//! refinement, errors over 10 blocks.
//!
//! `HYST_JACKKNIFE_SEEDS` (default 12) seeds from `HYST_JACKKNIFE_SEED` (default 5_100_001),
//! 1000 apart: `cargo test --release -p covssi --test jackknife -- --nocapture`.

use covssi::synth::{ModalRecord, pole};
use covssi::{AnalysisOptions, ReportedMode, analyze};

const MODES: [(f64, f64); 3] = [(1.3, 0.015), (3.9, 0.02), (6.6, 0.025)];
const FS: f64 = 25.0;
const SAMPLES: usize = 8000;
/// Each channel's reading of each mode: a cantilever's sine shapes at three nodes of twelve.
fn shape(j: usize, c: usize) -> f64 {
    let node = [4.0, 8.0, 12.0][c];
    ((2 * j + 1) as f64 * std::f64::consts::PI * node / 24.0).sin()
}

#[test]
fn the_jackknifes_errors_match_ssis_errors_over_seeds() {
    let seeds: u64 = std::env::var("HYST_JACKKNIFE_SEEDS").map_or(12, |v| v.parse().unwrap());
    let base: u64 = std::env::var("HYST_JACKKNIFE_SEED").map_or(5_100_001, |v| v.parse().unwrap());
    // Accelerations (each mode's reading times λ²), as a modal test's accelerometers read.
    let gains: Vec<Vec<f64>> = (0..3)
        .map(|c| {
            MODES
                .iter()
                .enumerate()
                .flat_map(|(j, &(f, z))| {
                    let g = shape(j, c) * pole(f, z).powi(2);
                    [g.re, -g.im]
                })
                .collect()
        })
        .collect();
    let opts = AnalysisOptions::default()
        .with_refine(None)
        .with_ssi_errors(Some(10));
    let (mut freq_z, mut damp_z, mut shape_z) = (vec![], vec![], vec![]);
    let mut without = 0;
    for seed in (0..seeds).map(|i| base + 1000 * i) {
        let y = ModalRecord::new(FS, &MODES)
            .with_gains(gains.clone())
            .with_noise(0.05)
            .generate(SAMPLES, seed);
        let views: Vec<&[f64]> = y.iter().map(Vec::as_slice).collect();
        let a = analyze(&views, FS, &opts).unwrap();
        let reported = a.reported_modes();
        for (j, &(f, z)) in MODES.iter().enumerate() {
            let distance = |m: &&ReportedMode| (m.frequency_hz - f).abs();
            let m = reported
                .iter()
                .min_by(|a, b| distance(a).total_cmp(&distance(b)))
                .unwrap();
            // Found at all (SSI alone puts the weakest mode up to 2 % off, with an error to
            // say so: the z below judges that).
            assert!((m.frequency_hz - f).abs() < 0.1 * f, "seed {seed}: {m:?}");
            let (Some(fse), Some(dse), Some(sse)) = (m.frequency_se_hz, m.damping_se, &m.shape_se)
            else {
                // Too few replicates found it: said in the report, no error given.
                println!(
                    "seed {seed} mode {j}: {:.4} Hz without an error",
                    m.frequency_hz
                );
                without += 1;
                continue;
            };
            let shape_m = m.shape.as_ref().unwrap();
            // The truth scaled as the estimate is: its entry 1 where the estimate's is.
            let one = (0..3).find(|&c| sse[c] == 0.0).unwrap();
            let zs: Vec<f64> = (0..3)
                .filter(|&c| c != one)
                .map(|c| (shape_m[c] - shape(j, c) / shape(j, one)).norm() / sse[c])
                .collect();
            println!(
                "seed {seed} mode {j}: {:.4} ± {fse:.4} Hz (truth {f}), ζ {:.4} ± {dse:.4} (truth {z}), shape z {zs:.2?}",
                m.frequency_hz, m.damping_ratio
            );
            freq_z.push((m.frequency_hz - f) / fse);
            damp_z.push((m.damping_ratio - z) / dse);
            shape_z.extend(zs);
        }
    }
    let rms = |v: &[f64]| (v.iter().map(|z| z * z).sum::<f64>() / v.len() as f64).sqrt();
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    println!(
        "{seeds} seeds: frequency z RMS {:.2} (mean {:+.2}), damping z RMS {:.2} (mean {:+.2}), shape z RMS {:.2} over {} entries",
        rms(&freq_z),
        mean(&freq_z),
        rms(&damp_z),
        mean(&damp_z),
        rms(&shape_z),
        shape_z.len()
    );
    // Calibrated errors give z of unit RMS. Over 36 frequencies the RMS of unit normals
    // spreads by about 0.12 (1/√72), over 72 shape entries by 0.08: 0.6–1.5 is over three of
    // those either side. Damping is left unasserted: SSI's damping is biased low at 5 % noise
    // (z means −0.3 to −0.6 over 60 seeds of merged setups), which an error does not describe.
    let (zf, zs) = (rms(&freq_z), rms(&shape_z));
    println!("{without} of {} modes without an error", 3 * seeds);
    // A mode some replicates miss gets no error rather than one from the rest: rare here
    // (1 of 120 modes over 40 seeds 5200001 + 1000 k before SSI's member shapes were scaled
    // alike, none after), at most one in ten allowed.
    assert!(
        without * 10 <= 3 * seeds as usize,
        "{without} modes without an error"
    );
    assert!((0.6..=1.5).contains(&zf), "frequency z RMS {zf}");
    assert!((0.6..=1.5).contains(&zs), "shape z RMS {zs}");
}
