//! EFDD over seeds: its frequency and damping errors on records of three modes of known
//! frequencies and damping (1, 2 and 5 %, as the OMA records'), each mode's bias and spread.
//!
//! `HYST_FDD_SEEDS` (default 12) seeds from `HYST_FDD_SEED` (default 4_800_001), 1000 apart:
//! `cargo test --release -p covssi --test fdd -- --nocapture`.

use covssi::fdd::{FddOptions, efdd, efdd_of_mode, fdd};
use covssi::synth::ModalRecord;

const MODES: [(f64, f64); 3] = [(1.0017, 0.01), (2.8067, 0.02), (4.0558, 0.05)];

#[test]
fn efdd_errors_over_seeds() {
    let seeds: u64 = std::env::var("HYST_FDD_SEEDS").map_or(12, |v| v.parse().unwrap());
    let base: u64 = std::env::var("HYST_FDD_SEED").map_or(4_800_001, |v| v.parse().unwrap());
    // Three channels reading the modes as a 3-mass chain's shapes do.
    let gains = vec![
        vec![0.33, 0.0, 0.74, 0.0, 0.59, 0.0],
        vec![0.59, 0.0, 0.33, 0.0, -0.74, 0.0],
        vec![0.74, 0.0, -0.59, 0.0, 0.33, 0.0],
    ];
    let system = ModalRecord::new(20.0, &MODES)
        .with_gains(gains)
        .with_noise(0.05);
    let mut errors = vec![(Vec::new(), Vec::new()); MODES.len()];
    for seed in (0..seeds).map(|i| base + 1000 * i) {
        let y = system.generate(65536, seed);
        let views: Vec<&[f64]> = y.iter().map(|c| c.as_slice()).collect();
        let spectra = fdd(&views, 20.0, &FddOptions::default()).unwrap();
        for (j, &(f, z)) in MODES.iter().enumerate() {
            let e = efdd(&spectra, f, &FddOptions::default()).unwrap();
            errors[j].0.push(100.0 * (e.frequency_hz / f - 1.0));
            errors[j].1.push(100.0 * (e.damping_ratio / z - 1.0));
        }
    }
    let stats = |v: &[f64]| {
        let n = v.len() as f64;
        let m = v.iter().sum::<f64>() / n;
        let sd = (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0).max(1.0)).sqrt();
        (m, sd)
    };
    for (j, (f, z)) in errors.iter().enumerate() {
        let ((fm, fs), (zm, zs)) = (stats(f), stats(z));
        println!(
            "mode {} ({} Hz, ζ {}): frequency error {fm:+.3} ± {fs:.3} %, damping error {zm:+.1} ± {zs:.1} % over {seeds} seeds",
            j + 1,
            MODES[j].0,
            MODES[j].1
        );
        // What EFDD is known to give on records of 65 536 samples: the frequency within
        // 0.5 %, the damping within 20 % (a bell cut at MAC 0.8 loses the tails of a 5 %
        // damped mode) on every seed.
        // Measured over 30 seeds (4810001…): frequency biases +0.02, −0.02, −0.70 % (spread
        // 0.1 %), damping +7 ± 11, +3 ± 5, −10 ± 4 %; the 5 % mode's bell, cut where the
        // MAC falls below 0.8, loses its tails. Bounds on the means over 12 seeds of 1 % and
        // 20 % hold those biases with three standard errors (0.1 and 3.2 %) to spare.
        assert!(fm.abs() < 1.0 && fs < 0.5, "{f:?}");
        assert!(zm.abs() < 20.0 && zs < 20.0, "{z:?}");
    }
}

/// Two modes 3 % apart (ζ 1 %), of different shapes: one peak of s₁ serves both, so EFDD
/// from the peak answers one mode twice; EFDD of each mode's own shape finds each its own
/// bell (the second mode's in s₂ where the first dominates) and its frequency and damping.
#[test]
fn close_modes_each_get_their_own_efdd() {
    const CLOSE: [(f64, f64); 2] = [(1.0, 0.01), (1.03, 0.01)];
    let shapes = [[1.0, 0.5, -0.3], [-0.4, 1.0, 0.6]];
    let gains = (0..3)
        .map(|c| vec![shapes[0][c], 0.0, shapes[1][c], 0.0])
        .collect();
    let system = ModalRecord::new(20.0, &CLOSE)
        .with_gains(gains)
        .with_noise(0.05);
    let seeds: Vec<u64> = (0..8).map(|i| 4_900_001 + 1000 * i).collect();
    let mut errors = vec![(Vec::new(), Vec::new()); 2];
    let mut borrowed = 0;
    for &seed in &seeds {
        let y = system.generate(65536, seed);
        let views: Vec<&[f64]> = y.iter().map(|c| c.as_slice()).collect();
        let spectra = fdd(&views, 20.0, &FddOptions::default()).unwrap();
        for (j, &(f, z)) in CLOSE.iter().enumerate() {
            let shape: Vec<covssi::Complex64> = shapes[j]
                .iter()
                .map(|&v| covssi::Complex64::new(v, 0.0))
                .collect();
            let e = efdd_of_mode(&spectra, f, &shape, &FddOptions::default())
                .unwrap_or_else(|| panic!("seed {seed}: no EFDD of the mode at {f} Hz"));
            // From the peak of s₁, a mode is often answered with the other's.
            let peak = efdd(&spectra, f, &FddOptions::default()).unwrap();
            borrowed += usize::from((peak.frequency_hz / f - 1.0).abs() > 0.015);
            errors[j].0.push(100.0 * (e.frequency_hz / f - 1.0));
            errors[j].1.push(100.0 * (e.damping_ratio / z - 1.0));
        }
    }
    println!(
        "EFDD from the peak of s1 answered a mode with the other's {borrowed} times in {}",
        2 * seeds.len()
    );
    for (j, (f, z)) in errors.iter().enumerate() {
        println!(
            "close mode {}: frequency errors {f:.3?} %, damping errors {z:.1?} %",
            j + 1
        );
        // Each mode's own: frequencies within 0.5 % (the two are 3 % apart, so an answer
        // borrowed from the other mode misses by 3 %).
        assert!(f.iter().all(|e| e.abs() < 0.5), "{f:?}");
        // The damping is the mode's own within a factor of 2 on every seed. It is biased
        // more than a lone mode's (the test above): the bell of a mode beside a stronger one
        // is cut one-sided where their shapes mix. Measured over these 8 seeds: mode 1
        // −7 ± 13 %, mode 2 −24 ± 17 %.
        assert!(
            z.iter().all(|e| (1.0 + e / 100.0).ln().abs() < 2f64.ln()),
            "{z:?}"
        );
    }
}
