//! The residual loop on data the project's own simulator makes with an effect the
//! identification is not told about: the right effect is named and the held-out error at least
//! halves; with no effect, `none`; with a Bouc-Wen element of exponent 2, hysteresis and then
//! its exponent; on a noise-free record where the held-out rows do not clearly support even
//! the true effect, nothing is added.

use crate::common;

use hyst_ident::residual::{self, Effect, InputInterpolation, ModelClass, Record};
use hyst_model::{BoucWen, Coulomb, Oscillator, SecondMass};
use hyst_sim::excitation::{add_noise, white_noise};
use hyst_sim::{self as sim, Input, SimOptions};

const FS: f64 = 200.0;
const N: usize = 8192;

/// The base system: 10 Hz, 2 % damping, m = 1.
fn base() -> Oscillator {
    let w = 2.0 * std::f64::consts::PI * 10.0;
    Oscillator::linear(1.0, 2.0 * 0.02 * w, w * w)
}

fn record(o: &Oscillator) -> (Vec<f64>, Vec<f64>) {
    sim::WhiteForceRecord::new(10.0, N, 31)
        .with_noise(sim::SensorNoise::OfRms(0.002))
        .generate(o, FS)
        .unwrap()
}

/// σ of x and ẋ of the base system's response (to size the effects).
fn scales() -> (f64, f64) {
    let (_, y) = record(&base());
    let sx = (y.iter().map(|v| v * v).sum::<f64>() / N as f64).sqrt();
    (sx, sx * 2.0 * std::f64::consts::PI * 10.0)
}

/// Estimation rows (the first 75 %) and held-out rows (the rest).
const ESTIMATE: (usize, usize) = (0, 3 * N / 4);
const HELD_OUT: (usize, usize) = (3 * N / 4, N);

/// The loop on `truth`'s record from a linear start (mass known), and the record.
fn run_with<R>(
    truth: &Oscillator,
    then: impl FnOnce(&Record<'_>) -> R,
) -> (residual::Refinement, R) {
    let (u, y) = record(truth);
    let rec = Record {
        u: &u,
        y: &y,
        fs: FS,
        // The records are simulated with linearly interpolated input.
        interpolation: InputInterpolation::Linear,
    };
    let r = residual::refine_record(&rec, Some(1.0), ModelClass::Linear, ESTIMATE, &[HELD_OUT])
        .unwrap();
    (r, then(&rec))
}

fn run(truth: &Oscillator) -> residual::Refinement {
    run_with(truth, |_| ()).0
}

fn report(name: &str, r: &residual::Refinement) {
    eprintln!("{name}: baseline {:?}\n   final {:?}", r.baseline, r.model);
    for s in &r.steps {
        eprintln!(
            "{name}: step {:?}: before {:.4} % after {:.4} % | peak {:.1} Hz, above-resonance share {:.2}",
            s.effect.map(|e| e.name()),
            100.0 * s.before[0].epsilon,
            100.0 * s.after[0].epsilon,
            s.spectrum.peak_hz,
            s.spectrum.above_resonance
        );
        for e in &s.evidence {
            eprintln!(
                "    {}: dBIC {:.1}, explained {:.3}{}",
                e.effect.name(),
                e.delta_bic,
                e.variance_explained,
                e.held_out.map_or(String::new(), |g| format!(
                    ", held out {:+.2} % (p {:.2e}), {}",
                    -100.0 * g.relative_gain(),
                    g.p_value,
                    e.rejected.as_deref().unwrap_or("")
                ))
            );
        }
    }
}

fn check(name: &str, truth: Oscillator, expect: Effect) {
    let r = run(&truth);
    report(name, &r);
    let first = &r.steps[0];
    assert_eq!(first.effect, Some(expect), "{name}");
    assert!(
        first.after[0].epsilon <= 0.5 * first.before[0].epsilon,
        "{name}: {} -> {}",
        first.before[0].epsilon,
        first.after[0].epsilon
    );
}

#[test]
fn finds_a_cubic_spring() {
    let (sx, _) = scales();
    let mut t = base();
    // At x = σ the cubic spring adds 10 % to the linear one (at 3σ, 90 %).
    t.extras.cubic_stiffness = 0.1 * t.stiffness / (sx * sx);
    check("cubic", t, Effect::CubicStiffness);
}

#[test]
fn finds_quadratic_damping() {
    let (_, sv) = scales();
    let mut t = base();
    t.extras.quadratic_damping = 3.0 * t.damping / sv;
    check("quadratic", t, Effect::QuadraticDamping);
}

#[test]
fn finds_coulomb_friction() {
    let (_, sv) = scales();
    let mut t = base();
    t.extras.coulomb = Some(Coulomb {
        force: 1.0 * t.damping * sv,
        smoothing_velocity: 0.05 * sv,
    });
    check("coulomb", t, Effect::CoulombFriction);
}

#[test]
fn finds_a_second_mode() {
    let mut t = base();
    let w2 = 2.0 * std::f64::consts::PI * 25.0;
    t.extras.second_mass = Some(SecondMass {
        mass: 0.2,
        stiffness: 0.2 * w2 * w2,
        damping: 2.0 * 0.02 * 0.2 * w2,
    });
    check("second mode", t, Effect::SecondMode);
}

#[test]
fn finds_hysteresis_from_a_linear_start() {
    let (sx, _) = scales();
    let b = base();
    let t = Oscillator::bouc_wen(
        1.0,
        b.damping,
        0.6 * b.stiffness,
        BoucWen::from_products(0.4 * b.stiffness, 0.5 / sx, -0.2 / sx, 1.0),
    );
    check("hysteresis", t, Effect::Hysteresis);
}

/// The output channel sampled one sample after the input's (a skew in the acquisition, made
/// here by shifting the record, not by the simulator's measurement chain): the loop adds the
/// chain's delay first, not a structural effect, finds d = 1/fs within three standard
/// errors, and ends at the noise (ε within 1.3× the control's).
#[test]
fn takes_a_late_output_channel_for_the_acquisition() {
    let (u, y) = record(&base());
    let late: Vec<f64> = std::iter::once(0.0)
        .chain(y[..N - 1].iter().copied())
        .collect();
    let rec = Record {
        u: &u,
        y: &late,
        fs: FS,
        interpolation: InputInterpolation::Linear,
    };
    let r = residual::refine_record(&rec, Some(1.0), ModelClass::Linear, ESTIMATE, &[HELD_OUT])
        .unwrap();
    report("late output", &r);
    assert_eq!(r.steps[0].effect, Some(Effect::OutputDelay));
    let d = r
        .estimates
        .iter()
        .find(|e| e.name == "chain_delay")
        .expect("the delay is estimated");
    assert!(
        (d.value - 1.0 / FS).abs() <= 3.0 * d.se,
        "delay {} ± {} s, true {}",
        d.value,
        d.se,
        1.0 / FS
    );
    let control = run(&base());
    assert!(
        r.tests[0].epsilon <= 1.3 * control.tests[0].epsilon,
        "{} against the control's {}",
        r.tests[0].epsilon,
        control.tests[0].epsilon
    );
}

#[test]
fn control_with_no_effect_reports_none() {
    let r = run(&base());
    report("control", &r);
    assert_eq!(r.steps[0].effect, None);
}

/// A Bouc-Wen element whose exponent is 2, not the 1 the loop's elements start with: the loop
/// adds hysteresis (ν = 1), then frees the exponent, and ends at the true model's held-out
/// error with ν near 2.
#[test]
fn finds_a_sharper_hysteresis_exponent() {
    let (sx, _) = scales();
    let b = base();
    let alpha = 0.4 * b.stiffness;
    // At x = σ the element is as far into its loop as the ν = 1 case above:
    // (βγ)^(1/ν) (αA)/α^(1/ν) = 0.5.
    let bg = 0.25 / (alpha * sx * sx);
    let t = Oscillator::bouc_wen(
        1.0,
        b.damping,
        0.6 * b.stiffness,
        BoucWen::from_products(alpha, bg, -0.4 * bg, 2.0),
    );
    // The true model's own held-out error, on the same record.
    let (r, truth) = run_with(&t, |rec| residual::test_error(&t, rec, HELD_OUT).unwrap());
    report("exponent", &r);
    let effects: Vec<Option<Effect>> = r.steps.iter().map(|s| s.effect).collect();
    assert_eq!(
        effects,
        [
            Some(Effect::Hysteresis),
            Some(Effect::HysteresisExponent),
            None
        ]
    );
    // The held-out error ends at the true model's (the measurement noise; measured: 0.0387 %
    // both, from 2.52 % linear and 0.63 % with a ν = 1 element); 1 % leaves room for the
    // fit's stopping tolerance.
    eprintln!(
        "exponent: held-out ε final {:.4} %, true model {:.4} %",
        100.0 * r.tests[0].epsilon,
        100.0 * truth.epsilon
    );
    assert!(r.tests[0].epsilon < 1.01 * truth.epsilon);
    // Every parameter within four standard errors of the truth (measured: |z| ≤ 2.8, the
    // largest for k and α, which share the static stiffness; ν = 1.9991 ± 0.0009).
    let expected = [
        ("damping", t.damping),
        ("stiffness", t.stiffness),
        ("alpha", alpha),
        ("beta_gamma", bg),
        ("beta_delta", -0.4 * bg),
        ("nu", 2.0),
    ];
    common::assert_estimates_near("exponent: ", &r.estimates, &expected, 4.0);
}

/// The held-out test asks for a gain that holds block after block, not for a large one. On
/// a noise-free record of the cubic spring, 16384 samples, the free-run simulation of this
/// hardening oscillator does not lock onto the record (the true model itself scores 9.43 %
/// on the held-out rows, printed below), and the cubic spring's candidate, though it lowers
/// the held-out squared error by about half, does so unevenly over the blocks (measured:
/// −51.6 %, p = 0.012 over 8 blocks): the loop declines it and stops, saying why, rather than
/// add what the rows it never saw do not clearly support. (Before the paired test, the
/// check compared the held-out ε alone: the cubic spring was added, 12.60 → 8.75 %, and
/// quadratic damping refused after it, 8.75 → 9.43 %.) On the same system with 0.2 % of
/// noise the cubic spring is found (`finds_a_cubic_spring`).
#[test]
fn the_held_out_test_asks_for_a_consistent_gain() {
    let n = 2 * N;
    let mut t = base();
    let u = white_noise(n, 10.0, 31).unwrap();
    let opts = SimOptions::default();
    let y0 = sim::simulate(&t, Input::Sampled(&u), FS, n, &opts).unwrap();
    let sx = (y0.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
    t.extras.cubic_stiffness = 0.1 * t.stiffness / (sx * sx);
    let y = sim::simulate(&t, Input::Sampled(&u), FS, n, &opts).unwrap();
    let rec = Record {
        u: &u,
        y: &y,
        fs: FS,
        interpolation: InputInterpolation::Linear,
    };
    let held_out = (3 * n / 4, n);
    let r = residual::refine_record(
        &rec,
        Some(1.0),
        ModelClass::Linear,
        (0, 3 * n / 4),
        &[held_out],
    )
    .unwrap();
    report("held-out check", &r);
    let truth = residual::test_error(&t, &rec, held_out).unwrap();
    eprintln!(
        "held-out check: true model {:.4} %, loop's model {:.4} %",
        100.0 * truth.epsilon,
        100.0 * r.tests[0].epsilon
    );
    let effects: Vec<Option<Effect>> = r.steps.iter().map(|s| s.effect).collect();
    assert_eq!(effects, [None]);
    let cubic = r.steps[0]
        .evidence
        .iter()
        .find(|e| e.effect == Effect::CubicStiffness)
        .expect("every candidate is reported");
    let gain = cubic
        .held_out
        .expect("the cubic spring is tried on the test rows");
    assert!(gain.relative_gain() > 0.3 && !gain.accepts(), "{gain:?}");
    let why = cubic.rejected.as_deref().unwrap_or_default();
    assert!(why.starts_with("held out: mean squared error -"), "{why}");
}

/// A Bouc-Wen start with no viscous damping (the output-only pipeline holds c at 0 when the
/// spectrum's most likely c is negative): c moves on a log scale and cannot leave zero, so
/// the loop used to stay at c ≈ 1e-11 and add a "second mass" (0.39 kg at 3 Hz, below the
/// force's band) to stand in for it (issue 45, an independently generated control). Now the
/// baseline is also started at 1 % of critical damping: it recovers c, and nothing is added.
/// The record: the benchmark under a 5–150 Hz random force, trapezoidal rule at 40× the rate
/// with FIR decimation (not the loop's integrator), 8e-6 m of sensor noise.
#[test]
fn a_start_without_viscous_damping_recovers_it() {
    let fs = 750.0;
    let n = 16384;
    let truth = Oscillator::benchmark();
    let u = hyst_sim::excitation::band_limited_noise(n, fs, 5.0, 150.0, 50.0, 97_001).unwrap();
    let opts = SimOptions {
        oversample: 40,
        integrator: hyst_sim::Integrator::Trapezoidal,
        decimation: hyst_sim::Decimation::Fir(vec![2, 4, 5]),
        ..SimOptions::default()
    };
    let mut y = sim::simulate(&truth, Input::BandLimited(&u), fs, n, &opts).unwrap();
    add_noise(&mut y, 8e-6, 97_002).unwrap();
    let rec = Record {
        u: &u,
        y: &y,
        fs,
        interpolation: InputInterpolation::BandLimited,
    };
    let start = Oscillator {
        damping: 0.0,
        ..truth
    };
    let r = residual::refine(&start, &rec, (0, 3 * n / 4), &[(3 * n / 4, n)], false).unwrap();
    report("no viscous damping", &r);
    // c's standard error on such a record is about 0.03 N s/m (cargo xtask loop-battery).
    assert!((r.baseline.damping - 10.0).abs() < 0.5, "{:?}", r.baseline);
    assert!(r.steps.iter().all(|s| s.effect.is_none()), "{:?}", r.model);
}
