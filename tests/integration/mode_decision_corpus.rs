//! The decision of what is a mode (`covssi::decision`) over records made outside covssi:
//! shear buildings integrated in physical coordinates under coloured, modulated loads with
//! machines, sensor noise and drift (`hyst_sim::corpus`), analysed with the defaults and
//! scored against their truth. `cargo xtask corpus` runs the same at full size; here a few
//! seeds no earlier run used, so that CI sees records no rule was built on.
//!
//! `HYST_CORPUS_SEEDS` / `HYST_CORPUS_SEED` / `HYST_CORPUS_PERIODS` change the set.

use hyst::covssi::{AnalysisOptions, ModeSource, analyze};
use hyst::sim::corpus::{Estimate, Score, Summary, realistic};

fn env(name: &str, default: f64) -> f64 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

#[test]
fn defaults_report_structural_modes_with_calibrated_errors() {
    let seeds = env("HYST_CORPUS_SEEDS", 6.0) as u64;
    let first = env("HYST_CORPUS_SEED", 7_700_001.0) as u64;
    let periods = env("HYST_CORPUS_PERIODS", 400.0);
    let (mut all, mut ssi, mut refined): (Vec<Score>, Vec<Score>, Vec<Score>) = Default::default();
    for seed in (0..seeds).map(|k| first + 1000 * k) {
        let case = realistic(seed, periods).expect("a corpus case");
        let y = case.generate().expect("its record");
        let views: Vec<&[f64]> = y.iter().map(|c| c.as_slice()).collect();
        let a = analyze(&views, case.building.fs, &AnalysisOptions::default()).expect("analysed");
        let reported: Vec<Estimate> = a
            .reported_modes()
            .iter()
            .map(|m| {
                (
                    m.frequency_hz,
                    m.frequency_se_hz,
                    m.damping_ratio,
                    m.damping_se,
                )
            })
            .collect();
        let s = case.score(&reported);
        eprintln!(
            "seed {seed}: {}\n  {}\n  found {}/{}, reported {}, not structural {:?}, missed {:?}, z frequency {:.2?}, z damping {:.2?}",
            case.description,
            a.decision.headline(),
            s.found,
            s.in_band,
            s.reported,
            s.spurious,
            s.missed,
            s.z_frequency,
            s.z_damping
        );
        match a.decision.source {
            ModeSource::Refined => refined.push(s.clone()),
            _ => ssi.push(s.clone()),
        }
        all.push(s);
    }
    let sum = Summary::of(&all);
    let by_ssi = Summary::of(&ssi);
    eprintln!(
        "{sum}\nSSI's answers (jackknife errors): {by_ssi}\nthe refinement's answers: {}",
        Summary::of(&refined)
    );
    // From `cargo xtask corpus` (docs/covssi.md, "What is a mode"): 40 fresh seeds found
    // 92.9 % of the in-band modes with 0.5 % of the reported modes not structural. Six
    // short records hold ~30 modes: one missed mode is ~3 %, one spurious ~3 %; the bounds
    // allow about two of each beyond the measured shares.
    assert!(sum.found >= 0.85, "{sum}");
    assert!(sum.spurious <= 0.08, "{sum}");
    // SSI's answers carry the jackknife's errors: z RMS within the 0.7–1.3, widened
    // by the scatter of an RMS over ~15–25 values (±0.2 at two standard deviations). The
    // refinement's answers are printed, not bounded: on loads its model lacks (a coloured
    // load's resonance beside a mode, an amplitude-modulated load) its errors read small
    // (docs/covssi.md), an open part of issue 57.
    if by_ssi.z_frequency_rms.1 >= 10 {
        assert!(
            (0.5..=1.5).contains(&by_ssi.z_frequency_rms.0),
            "frequency: {by_ssi}"
        );
        assert!(
            (0.5..=1.5).contains(&by_ssi.z_damping_rms.0),
            "damping: {by_ssi}"
        );
    }
}
