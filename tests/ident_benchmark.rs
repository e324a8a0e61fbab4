//! The identification pipeline end to end: the paper's Section 4 on the benchmark's records,
//! a nearly linear case with known parameters, and bad input.

mod common;

use hyst::ident::{self, IdentError, IdentOptions, Linearization};
use hyst::model::Oscillator;
use hyst::sim::excitation::{Multisine, add_noise};
use hyst::sim::{self, Input, SimOptions};

/// Identify from the output of `multisine_train.csv` only (first, transient period dropped);
/// validate on `multisine_val.csv` and `sinesweep_val.csv`.
#[test]
fn section4_on_the_benchmark() {
    let Some((_, y)) = common::load_uy("boucwen/multisine_train.csv") else {
        return;
    };
    let Some((uv, yv)) = common::load_uy("boucwen/multisine_val.csv") else {
        return;
    };
    let Some((us, ys)) = common::load_uy("boucwen/sinesweep_val.csv") else {
        return;
    };
    for lin in [Linearization::Harmonic, Linearization::Paper] {
        let opts = IdentOptions {
            linearization: lin,
            ..IdentOptions::default()
        };
        let id = ident::identify(&y[8192..], 750.0, &opts).unwrap();
        // The paper reports kurtosis 2.59 and skewness −0.02 for its record.
        eprintln!(
            "{lin:?}: kurtosis {:.3} skewness {:.3}; pair {:.3}, real {:?}, c {:.2} ({})",
            id.prepared.kurtosis,
            id.prepared.skewness,
            id.poles.pair,
            id.poles.real,
            id.poles.c,
            id.poles.c_source
        );
        let lin_ms = ident::validate(&id.models.linear, &uv, &yv, 750.0, true).unwrap();
        let zen = id
            .models
            .zener
            .expect("a real pole is found on this record");
        let zen_ms = ident::validate(&zen, &uv, &yv, 750.0, true).unwrap();
        let bw = id.models.bouc_wen.expect("the Bouc-Wen mapping succeeds");
        let bw_ms = ident::validate(&bw, &uv, &yv, 750.0, true).unwrap();
        let sweep: Vec<String> = [Some(id.models.linear), Some(zen), Some(bw)]
            .iter()
            .map(
                |m| match ident::validate(m.as_ref().unwrap(), &us, &ys, 750.0, false) {
                    Ok(v) => format!("{:.2} %", 100.0 * v.epsilon),
                    Err(e) => format!("failed ({e})"),
                },
            )
            .collect();
        eprintln!(
            "{lin:?}: multisine_val eps linear {:.2} %, zener {:.2} %, bouc-wen {:.2} %; sinesweep_val {sweep:?}",
            100.0 * lin_ms.epsilon,
            100.0 * zen_ms.epsilon,
            100.0 * bw_ms.epsilon
        );
        eprintln!("{lin:?}: bouc-wen model {bw:?}");
        // Targets: within 10 % of the model classes' floors (3.98 % and 3.41 %).
        assert!(lin_ms.epsilon <= 0.044, "linear {}", lin_ms.epsilon);
        assert!(zen_ms.epsilon <= 0.0375, "zener {}", zen_ms.epsilon);
        // The Bouc-Wen target (< 3.41 %) is not met yet: both routes land near 4–5.5 %
        // (docs/results.md). This bound keeps the measured level from regressing.
        assert!(bw_ms.epsilon <= 0.06, "bouc-wen {}", bw_ms.epsilon);
    }
}

/// At low amplitude the benchmark is nearly linear (0.2 N RMS: βγ·σₓ ≈ 0.005, so the hysteretic damping adds about 0.5 N s/m): the identified linear
/// stiffness and damping are those of k + α = 1e5 N/m and c = 10 N s/m, to 2 % and 10 %.
#[test]
fn nearly_linear_case_recovers_stiffness_and_damping() {
    let model = Oscillator::benchmark();
    let period = Multisine::benchmark(0.2).generate(21).unwrap();
    let n = period.len();
    let mut y = sim::simulate(
        &model,
        Input::Periodic(&period),
        750.0,
        9 * n,
        &SimOptions::default(),
    )
    .unwrap()
    .split_off(n);
    add_noise(&mut y, 1e-9, 22).unwrap();
    let id = ident::identify(&y, 750.0, &IdentOptions::default()).unwrap();
    let (k, c) = (id.models.linear.stiffness, id.models.linear.damping);
    eprintln!(
        "low amplitude: sigma_x {:.2e}, k {k:.1}, c {c:.3}",
        id.prepared.sigma_x
    );
    assert!((k - 1e5).abs() <= 0.02 * 1e5, "k = {k}");
    assert!((c - 10.0).abs() <= 1.0, "c = {c}");
}

#[test]
fn no_stable_pair_is_an_error() {
    // White noise has no resonance.
    let y = hyst::sim::excitation::white_noise(20000, 1.0, 3).unwrap();
    let e = ident::identify(&y, 750.0, &IdentOptions::default()).unwrap_err();
    assert!(matches!(e, IdentError::NoStablePair { .. }), "{e}");
}

#[test]
fn too_short_and_bad_mass() {
    let y = vec![1.0, 2.0, 3.0];
    assert!(matches!(
        ident::identify(&y, 750.0, &IdentOptions::default()),
        Err(IdentError::TooShort { samples: 3, .. })
    ));
    let opts = IdentOptions {
        mass: 0.0,
        ..IdentOptions::default()
    };
    let y = hyst::sim::excitation::white_noise(2000, 1.0, 3).unwrap();
    assert!(matches!(
        ident::identify(&y, 750.0, &opts),
        Err(IdentError::NonPositiveMass { .. })
    ));
}

#[test]
fn no_real_pole_falls_back_to_the_linear_model() {
    // A linear oscillator's record, cut so short and sampled so that no real pole stabilises:
    // when none is found the Zener and Bouc-Wen models are absent and a note says why.
    let model = Oscillator::linear(2.0, 20.0, 1e5);
    let u = hyst::sim::excitation::white_noise(40000, 10.0, 5).unwrap();
    let y = sim::simulate(
        &model,
        Input::Sampled(&u),
        750.0,
        u.len(),
        &SimOptions::default(),
    )
    .unwrap();
    let id = ident::identify(&y, 750.0, &IdentOptions::default()).unwrap();
    if id.poles.real.is_none() {
        assert!(id.models.zener.is_none() && id.models.bouc_wen.is_none());
        assert!(
            id.poles
                .notes
                .iter()
                .any(|n| n.contains("no stable real pole"))
        );
    } else {
        // A spurious stable real pole was found on this record: then the note says it was
        // taken from the median of isolated poles or a cluster, and the models exist.
        assert!(id.models.zener.is_some() || !id.models.notes.is_empty());
    }
}
