use super::tests::{record, views};
use super::*;
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use rand_distr::StandardNormal;

const FS: f64 = 20.0;

/// 16 384 samples at FS of a 1.5 Hz, 2 % oscillator under white noise plus `gain` times a
/// first-order process with the real pole λ = −2 rad/s (each driven by its own unit white
/// noise; at gain 2 the two have about equal variance), plus 5 % white measurement noise.
fn oscillator_and_relaxation(gain: f64, seed: u64) -> Vec<Vec<f64>> {
    let mut y = record(16384, &[(1.5, 0.02)], &[vec![1.0]], 0.0, seed);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(1000 + seed);
    let mu = (-2.0 / FS).exp();
    let mut x = 0.0f64;
    for _ in 0..2000 {
        x = mu * x + rng.sample::<f64, _>(StandardNormal);
    }
    for v in y[0].iter_mut() {
        x = mu * x + rng.sample::<f64, _>(StandardNormal);
        *v += gain * x;
    }
    let sd = (y[0].iter().map(|v| v * v).sum::<f64>() / y[0].len() as f64).sqrt();
    for v in y[0].iter_mut() {
        *v += 0.05 * sd * rng.sample::<f64, _>(StandardNormal);
    }
    y
}

/// SSI (40 block rows, defaults otherwise) and the refinement with its real poles.
fn ssi_and_refine(y: &[Vec<f64>]) -> (crate::SsiResult, Refinement) {
    let v = views(y);
    let opts = crate::SsiOptions {
        block_rows: crate::BlockRows::Count(40),
        ..Default::default()
    };
    let ssi = crate::identify(&v, FS, &opts).unwrap();
    let r = refine_with_real_poles(
        &v,
        FS,
        &ssi.modes,
        &ssi.real_poles,
        &RefineOptions::default(),
    )
    .unwrap();
    (ssi, r)
}

/// On every record the refinement keeps one real pole and the one mode, whatever else the
/// diagram held (spurious modes and real-pole clusters on most records), and the real
/// pole's standard error is what it claims.
#[test]
fn a_real_pole_is_found_with_calibrated_standard_errors() {
    let mut z = Vec::new();
    // What `refine` alone, without the real poles, makes of the same records: a second
    // mode damped near 1 in the real pole's place, or the one mode pulled off 1.5 Hz.
    let (mut near_critical, mut pulled, mut other) = (0, 0, 0);
    for seed in 0..20 {
        let y = oscillator_and_relaxation(2.0, seed);
        let (ssi, r) = ssi_and_refine(&y);
        let plain = refine(&views(&y), FS, &ssi.modes, &RefineOptions::default()).unwrap();
        let right = |m: &RefinedMode| (m.frequency_hz - 1.5).abs() < 0.01;
        if plain.modes.iter().any(|m| m.damping_ratio > 0.9) {
            near_critical += 1;
        } else if plain.modes.len() == 1 && !right(&plain.modes[0]) {
            pulled += 1;
        } else if !(plain.modes.len() == 1 && right(&plain.modes[0])) {
            other += 1;
        }
        assert!(!ssi.real_poles.is_empty(), "seed {seed}: no SSI real pole");
        assert_eq!(r.real_poles.len(), 1, "seed {seed}: {r:?}");
        assert_eq!(r.modes.len(), 1, "seed {seed}: {r:?}");
        assert!((r.modes[0].frequency_hz - 1.5).abs() < 0.01, "{r:?}");
        let p = &r.real_poles[0];
        assert!(p.evidence >= r.real_pole_penalty);
        z.push((p.lambda + 2.0) / p.lambda_se.unwrap());
    }
    let rms = (z.iter().map(|v| v * v).sum::<f64>() / z.len() as f64).sqrt();
    println!("real pole z-scores {z:.2?}, RMS {rms:.3}");
    // The RMS of 20 standard normal variables is 1 ± 0.16 (1/√40): ±2.8 of that.
    assert!((0.55..=1.45).contains(&rms), "RMS z {rms}");
    let wrong = near_critical + pulled + other;
    println!(
        "refine without the real poles: wrong on {wrong} of 20 records ({near_critical} with a mode damped above 0.9, {pulled} with the one mode off 1.5 Hz by 0.01 Hz or more, {other} otherwise)"
    );
    // What docs/covssi.md says of `refine` on these records: wrong on most (20 of 20 when
    // this was written).
    assert!(wrong > 10, "{wrong}");
}

/// Without a real pole in the record, the real-pole clusters the diagram holds are
/// dropped, and the mode is the one `refine` finds.
#[test]
fn spurious_real_poles_are_dropped() {
    let mut candidates = 0;
    for seed in 0..20 {
        let y = oscillator_and_relaxation(0.0, seed);
        let (ssi, r) = ssi_and_refine(&y);
        candidates += ssi.real_poles.len();
        assert!(r.real_poles.is_empty(), "seed {seed}: {r:?}");
        assert_eq!(r.dropped_real_poles.len(), ssi.real_poles.len());
        assert!(
            r.dropped_real_poles
                .iter()
                .all(|d| d.evidence < r.real_pole_penalty)
        );
        let plain = refine(&views(&y), FS, &ssi.modes, &RefineOptions::default()).unwrap();
        assert_eq!(r.modes.len(), plain.modes.len());
        for (a, b) in r.modes.iter().zip(&plain.modes) {
            // Same model from the same start, on spectra binned for different poles (the
            // real-pole candidates narrow the bins near 0 Hz): each binning biases an
            // estimate by less than 1/24 of its standard error (`spectra`), so the two
            // differ by less than a tenth of it.
            let (fa, za) = (a.frequency_se_hz.unwrap(), a.damping_se.unwrap());
            assert!(
                (a.frequency_hz - b.frequency_hz).abs() < 0.1 * fa,
                "{a:?} {b:?}"
            );
            assert!(
                (a.damping_ratio - b.damping_ratio).abs() < 0.1 * za,
                "{a:?} {b:?}"
            );
        }
    }
    // Not vacuous: 7 of the 20 diagrams hold a real-pole cluster.
    assert!(candidates >= 5, "{candidates} candidates");
}

#[test]
fn a_real_pole_that_is_not_negative_is_an_error() {
    let y = oscillator_and_relaxation(2.0, 0);
    let v = views(&y);
    for lambda in [0.0, 1.0, f64::NAN] {
        let bad = RealPoleCluster {
            lambda,
            lambda_std: 0.0,
            members: vec![(1, 0)],
        };
        let r = refine_with_real_poles(&v, FS, &[], &[bad], &RefineOptions::default());
        assert!(
            matches!(r, Err(SsiError::NotNegativeRealPole { lambda: l }) if l.to_bits() == lambda.to_bits()),
            "{r:?}"
        );
    }
}
