//! The identification pipeline end to end: the paper's Section 4 on the benchmark's records,
//! a nearly linear case with known parameters, and bad input.

use crate::common;

use hyst_ident::{self as ident, IdentError, IdentOptions, Linearization};
use hyst_model::Oscillator;
use hyst_sim::excitation::{Multisine, add_noise};
use hyst_sim::{self as sim, Input, SimOptions};

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
        assert_eq!(
            id.models.bouc_wen_mapped,
            Some(bw),
            "no band given: the mapped model"
        );
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
        // The paper's route through one amplitude does not meet the Bouc-Wen target
        // (< 3.41 %): both mappings land near 4–5.5 % (docs/results.md); the flatness route
        // below does. This bound keeps the mapped level from regressing.
        assert!(bw_ms.epsilon <= 0.06, "bouc-wen {}", bw_ms.epsilon);
    }
}

/// The flatness route (the excitation's band known, not its record): identified from the
/// output of `multisine_train.csv` only, the Bouc-Wen model validates on both official records
/// almost as well as the true model, its parameters land near the benchmark's, and the force
/// it implies matches the recorded input the fit never saw.
#[test]
fn section4_flatness_route_beats_the_zener_floor() {
    use hyst_ident::flatness::{self, ExcitationBand};
    use hyst_model::Restoring;
    let Some((u, y)) = common::load_uy("boucwen/multisine_train.csv") else {
        return;
    };
    let Some((uv, yv)) = common::load_uy("boucwen/multisine_val.csv") else {
        return;
    };
    let Some((us, ys)) = common::load_uy("boucwen/sinesweep_val.csv") else {
        return;
    };
    let band = ExcitationBand::benchmark();
    let opts = IdentOptions {
        excitation: Some(band),
        ..IdentOptions::default()
    };
    let id = ident::identify(&y[8192..], 750.0, &opts).unwrap();
    let fit = id.flatness.as_ref().expect("the flatness fit runs");
    let bw = id.models.bouc_wen.unwrap();
    assert_eq!(bw, fit.model);
    let ms = ident::validate(&bw, &uv, &yv, 750.0, true).unwrap();
    let sw = ident::validate(&bw, &us, &ys, 750.0, false).unwrap();
    let truth = Oscillator::benchmark();
    let ms_true = ident::validate(&truth, &uv, &yv, 750.0, true).unwrap();
    let sw_true = ident::validate(&truth, &us, &ys, 750.0, false).unwrap();
    eprintln!(
        "flatness: {fit:?}\nmultisine_val {:.4} % (true model {:.4} %), sinesweep_val {:.4} % (true model {:.4} %)",
        100.0 * ms.epsilon,
        100.0 * ms_true.epsilon,
        100.0 * sw.epsilon,
        100.0 * sw_true.epsilon
    );
    // The target: below the Zener floor, 3.41 %. Measured 0.024 %; the bound 0.1 %
    // leaves room for the noise of the 4 averaged periods, which sets the parameter errors.
    assert!(ms.epsilon < 1e-3, "{}", ms.epsilon);
    // On the sweep the true model itself (RK4 and plain subsampling here, Newmark and FIR
    // decimation in the record) is at 0.083 %; the flatness model was at 0.077 %.
    assert!(
        sw.epsilon < 2.0 * sw_true.epsilon,
        "{} vs {}",
        sw.epsilon,
        sw_true.epsilon
    );
    let Restoring::BoucWen(b) = bw.restoring else {
        panic!("{bw:?}")
    };
    // Against the benchmark's Table 1. Measured deviations ≤ 2 % for c and ≤ 0.7 % for the
    // others; the sweep over 10–90 N (docs/results.md) shows the same scatter from noise.
    let rel = |got: f64, want: f64| ((got - want) / want).abs();
    assert!(rel(bw.damping, 10.0) < 0.05, "c {}", bw.damping);
    assert!(rel(bw.stiffness, 5e4) < 0.02, "k {}", bw.stiffness);
    assert!(rel(b.alpha, 5e4) < 0.02, "alpha {}", b.alpha);
    assert!(rel(b.beta_gamma(), 800.0) < 0.02, "bg {}", b.beta_gamma());
    assert!(rel(b.beta_delta(), -1100.0) < 0.02, "bd {}", b.beta_delta());
    // Independent check: the implied force against the recorded input (never used), averaged
    // over the same 4 periods, on the band (the record also excites bin 54, 4.94 Hz, below
    // the band's 5 Hz: that line is removed from the recorded input). The RMS level to 0.5 %;
    // the waveform to 5 % (measured 3.7 %: the measurement noise, 7.4e-6 m / 2 after
    // averaging, amplified by |k − m·ω²| up to 1.8e6 N/m at 150 Hz).
    let uh = flatness::implied_input(&bw, &y[8192..], 750.0, &band).unwrap();
    let n = band.period;
    let mut ua: Vec<f64> = (0..n)
        .map(|i| (1..5).map(|k| u[k * n + i]).sum::<f64>() / 4.0)
        .collect();
    let phase = |i: usize| 2.0 * std::f64::consts::PI * (54 * i % n) as f64 / n as f64;
    let (re, im) = ua.iter().enumerate().fold((0.0, 0.0), |(re, im), (i, v)| {
        (re + v * phase(i).cos(), im - v * phase(i).sin())
    });
    for (i, v) in ua.iter_mut().enumerate() {
        *v -= 2.0 / n as f64 * (re * phase(i).cos() - im * phase(i).sin());
    }
    let rms = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
    let diff: Vec<f64> = uh.iter().zip(&ua).map(|(a, b)| a - b).collect();
    eprintln!(
        "implied input RMS {:.4} N, recorded {:.4} N, difference {:.4} N",
        rms(&uh),
        rms(&ua),
        rms(&diff)
    );
    assert!(rel(rms(&uh), rms(&ua)) < 0.005);
    assert!(rms(&diff) < 0.05 * rms(&ua));
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
    let y = hyst_sim::excitation::white_noise(20000, 1.0, 3).unwrap();
    let e = ident::identify(&y, 750.0, &IdentOptions::default()).unwrap_err();
    assert!(matches!(e, IdentError::NoStablePair { .. }), "{e}");
}

/// White noise has no resonance, yet its stabilization diagram now and then holds a stable
/// cluster near the spectrum's largest bump. Every record of 24 seeds must end in an error,
/// never in models built on noise: some at the diagram (no stable pair), the others at the
/// likelihood test of the pair.
#[test]
fn white_noise_never_yields_a_model() {
    let (mut no_pair, mut not_supported) = (0, 0);
    for seed in 0..24 {
        let y = hyst_sim::excitation::white_noise(20000, 1.0, seed).unwrap();
        match ident::identify(&y, 750.0, &IdentOptions::default()) {
            Err(IdentError::NoStablePair { .. }) => no_pair += 1,
            Err(IdentError::PairNotSupported {
                evidence, penalty, ..
            }) => {
                assert!(evidence < penalty, "seed {seed}: {evidence} >= {penalty}");
                not_supported += 1;
            }
            Ok(id) => panic!(
                "seed {seed}: white noise gave models from the pair {:.2}",
                id.poles.pair
            ),
            Err(e) => panic!("seed {seed}: white noise gave another error: {e}"),
        }
    }
    eprintln!(
        "white noise, 24 seeds: {no_pair} without a stable pair, {not_supported} with a stable pair the likelihood rejects"
    );
}

/// A noise-free free decay, x = sin(225 t)·e^(−0.75 t) at 750 Hz (pole −0.75 + 225i rad/s),
/// does not follow the stationary model the pair's likelihood test rests on: the test then
/// says nothing, a note says so, and the pair is kept. The decay also leaves the Toeplitz
/// matrix below the default order's rank, so fewer orders are used, with a note.
#[test]
fn a_free_decay_keeps_its_pair_with_notes() {
    let y: Vec<f64> = (0..3000)
        .map(|k| (0.3 * k as f64).sin() * (-1e-3 * k as f64).exp())
        .collect();
    let id = ident::identify(&y, 750.0, &IdentOptions::default()).unwrap();
    let pair = id.poles.pair;
    // SSI on a short decimated decay: the frequency to 0.1 %, the decay rate to 30 %.
    assert!((pair.im - 225.0).abs() < 0.225, "{pair}");
    assert!((pair.re + 0.75).abs() < 0.25, "{pair}");
    assert!(
        id.poles
            .notes
            .iter()
            .any(|n| n.contains("could not be tested") && n.contains("misfit")),
        "{:?}",
        id.poles.notes
    );
    assert!(
        id.ssi.notes.iter().any(|n| n.contains("orders up to")),
        "{:?}",
        id.ssi.notes
    );
}

/// A record whose variance is not a normal double with room to spare is an error naming the
/// range, not a "constant" record or a garbage dominant frequency.
#[test]
fn a_record_beyond_the_double_range_is_an_error() {
    let y = hyst_sim::excitation::white_noise(4000, 1.0, 9).unwrap();
    for s in [1e-160, 1e160] {
        let ys: Vec<f64> = y.iter().map(|v| v * s).collect();
        let e = ident::identify(&ys, 750.0, &IdentOptions::default()).unwrap_err();
        assert!(
            matches!(e, IdentError::Ssi(covssi::SsiError::OutOfRange { .. })),
            "scale {s:e}: {e}"
        );
    }
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
    let y = hyst_sim::excitation::white_noise(2000, 1.0, 3).unwrap();
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
    let u = hyst_sim::excitation::white_noise(40000, 10.0, 5).unwrap();
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
