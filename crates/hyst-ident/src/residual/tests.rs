use super::candidates::{already_has, not_dissipating};
use super::selection::held_out_reason;
use super::start::{first_usable, fresh_bouc_wen};
use super::*;
use hyst_model::{BoucWen, Coulomb};

/// A record made with negative quadratic damping (a force that feeds energy in): the
/// quadratic-damping candidate cannot follow it below zero. Its regression start is
/// negative and refused, and its fit, on a log scale, keeps the coefficient positive,
/// where it explains nothing: the candidate is no evidence for the effect. (Before the
/// log scale the fit followed the record to a negative coefficient, which was then
/// rejected after the fit.)
#[test]
fn no_fit_reaches_an_effect_that_feeds_energy_in() {
    let fs = 100.0;
    let n = 4000;
    let w = 2.0 * std::f64::consts::PI * 2.0;
    let (m, c, k, q) = (1.0, 1.0, w * w, 50.0);
    let t = |i: usize| i as f64 / fs;
    let y: Vec<f64> = (0..n).map(|i| 0.1 * (w * t(i)).sin()).collect();
    let u: Vec<f64> = (0..n)
        .map(|i| {
            let (x, v, a) = (
                0.1 * (w * t(i)).sin(),
                0.1 * w * (w * t(i)).cos(),
                -0.1 * w * w * (w * t(i)).sin(),
            );
            m * a + c * v + k * x - q * v * v.abs()
        })
        .collect();
    let rec = Record {
        u: &u,
        y: &y,
        fs,
        interpolation: InputInterpolation::Linear,
    };
    // The loop offers candidates to a model fitted to convergence.
    let (base, c0) = fit(&Oscillator::linear(m, c, k), &rec, (0, n), false, 300)
        .expect("the linear model is stable");
    let (evidence, _) = diagnose(&base, c0, &rec, (0, n), false, None);
    let quad = evidence
        .iter()
        .find(|e| e.effect == Effect::QuadraticDamping)
        .expect("every candidate is reported");
    assert!(quad.model.is_none_or(|m| m.extras.quadratic_damping > 0.0));
    assert!(
        quad.delta_bic > SIGNIFICANT_BIC || quad.rejected.is_some(),
        "{quad:?}"
    );
}

/// Progress moves within a step: every fit iteration tells the step again with the
/// iterations so far, in order, between the loop's own step messages.
#[test]
fn every_fit_iteration_moves_the_progress() {
    let fs = 100.0;
    let n = 3000;
    let u = hyst_sim::excitation::white_noise(n, 1.0, 3).expect("force");
    let truth = Oscillator::linear(1.0, 0.5, 400.0);
    let y = hyst_sim::simulate(
        &truth,
        hyst_sim::Input::Sampled(&u),
        fs,
        n,
        &Default::default(),
    )
    .expect("simulation");
    let rec = Record {
        u: &u,
        y: &y,
        fs,
        interpolation: InputInterpolation::Linear,
    };
    let heard = std::sync::Mutex::new(Vec::<String>::new());
    let r = refine_with(
        &Oscillator::linear(1.0, 0.8, 350.0),
        &rec,
        (0, 2000),
        &[(2000, n)],
        false,
        &|p| heard.lock().expect("lock").push(p.what.to_string()),
    );
    assert!(r.is_ok(), "{r:?}");
    let heard = heard.into_inner().expect("lock");
    let counts: Vec<usize> = heard
        .iter()
        .filter_map(|w| {
            let (_, tail) = w.rsplit_once(" (")?;
            tail.strip_suffix(" least-squares iterations so far)")?
                .parse()
                .ok()
        })
        .collect();
    assert!(counts.len() > 3, "{heard:?}");
    assert!(counts.windows(2).all(|c| c[1] > c[0]), "{counts:?}");
    assert!(heard[0].starts_with("fitting the start"), "{heard:?}");
    assert!(
        heard[1].starts_with("fitting the start by output error (1 least-squares"),
        "{heard:?}"
    );
}

/// Rows that are no range within the record are named, whichever of the estimation or
/// The Bouc-Wen element started afresh sits on the equation-error linear model: on a
/// linear record, k + α is the true stiffness (the regression's, within 1 %: white noise
/// of 1 % on the output blurs ÿ and ẏ little at 20 samples a period), the element's
/// share 20 % of it.
#[test]
fn a_fresh_element_keeps_the_regressions_stiffness() {
    let truth = Oscillator::linear(2.0, 3.0, 5e3);
    let fs = 100.0;
    let u = hyst_sim::excitation::white_noise(4000, 10.0, 11).unwrap();
    let opts = hyst_sim::SimOptions::default();
    let mut y = hyst_sim::simulate(&truth, hyst_sim::Input::Sampled(&u), fs, 4000, &opts).unwrap();
    let sy = (y.iter().map(|v| v * v).sum::<f64>() / 4000.0).sqrt();
    hyst_sim::excitation::add_noise(&mut y, 0.01 * sy, 12).unwrap();
    let rec = Record {
        u: &u,
        y: &y,
        fs,
        interpolation: InputInterpolation::Linear,
    };
    let m = fresh_bouc_wen(&rec, (0, 4000), 2.0, false).expect("a start");
    let hyst_model::Restoring::BoucWen(b) = m.restoring else {
        panic!("no element: {m}");
    };
    let k = m.stiffness + b.alpha;
    assert!((k / 5e3 - 1.0).abs() < 0.01, "k + α = {k}");
    assert!((b.alpha / k - 0.2).abs() < 1e-9, "α share {}", b.alpha / k);
    assert!(b.beta_gamma() > 0.0, "{b:?}");
}

/// test ranges they are; so is a start that no fit can follow.
#[test]
fn bad_rows_and_a_diverging_start_are_named() {
    let fs = 100.0;
    let n = 400;
    let u: Vec<f64> = (0..n).map(|i| (0.3 * i as f64).sin()).collect();
    let y: Vec<f64> = (0..n).map(|i| 1e-3 * (0.3 * i as f64).cos()).collect();
    let rec = Record {
        u: &u,
        y: &y,
        fs,
        interpolation: InputInterpolation::Linear,
    };
    let base = Oscillator::linear(1.0, 1.0, 100.0);
    for (estimate, tests, bad) in [
        ((50, 10), &[][..], (50, 10)),
        ((0, 401), &[], (0, 401)),
        ((0, 200), &[(300, 300)], (300, 300)),
    ] {
        assert_eq!(
            refine(&base, &rec, estimate, tests, false).unwrap_err(),
            IdentError::BadRows {
                start: bad.0,
                end: bad.1,
                samples: n
            }
        );
    }
    // Hysteresis with γ, δ < 0 feeds energy in: ż grows with |z|·z and the simulation
    // blows up within the record, from the start and from every step of the fit.
    let wild = Oscillator::bouc_wen(
        1.0,
        1.0,
        100.0,
        hyst_model::BoucWen::from_products(100.0, -1e9, -1e9, 1.0),
    );
    assert!(residual(&wild, &Prepared::new(&rec), (0, n)).is_none());
    assert_eq!(
        refine(&wild, &rec, (0, n), &[], false).unwrap_err(),
        IdentError::StartDiverges { start: 0, end: n }
    );
}

/// A start the pipeline does not give, and one whose fit diverges, fall back along the
/// chain with a note each; the first that runs is used; another error stops the chain;
/// when every start diverges, that is the error.
#[test]
fn starts_fall_back_and_say_why() {
    let lin = Oscillator::linear(1.0, 1.0, 1.0);
    let zen = Oscillator::zener(
        1.0,
        1.0,
        1.0,
        hyst_model::ZenerParams {
            k_inf: 1.0,
            omega: 1.0,
        },
    );
    let diverges = IdentError::StartDiverges { start: 0, end: 10 };
    // No Bouc-Wen model; the Zener start diverges; the linear one runs.
    let models = |c: ModelClass| match c {
        ModelClass::BoucWen => None,
        ModelClass::Zener => Some(zen),
        ModelClass::Linear => Some(lin),
    };
    let run = |m: &Oscillator| {
        if ModelClass::of(m) == ModelClass::Zener {
            Err(diverges.clone())
        } else {
            Ok(ModelClass::of(m))
        }
    };
    let (ran, used, notes) = first_usable(ModelClass::BoucWen, (0, 10), models, run).unwrap();
    assert_eq!((ran, used), (ModelClass::Linear, ModelClass::Linear));
    assert_eq!(
        notes,
        [
            "the output-only pipeline gave no bouc-wen model: falling back",
            "the zener start diverges on the estimation rows: falling back"
        ]
    );
    // Asked for linear: no fallback, no note.
    let (_, used, notes) = first_usable(ModelClass::Linear, (0, 10), models, run).unwrap();
    assert_eq!((used, notes.len()), (ModelClass::Linear, 0));
    // Every start diverges: the divergence is the error.
    let all = |_: &Oscillator| -> Result<(), IdentError> { Err(diverges.clone()) };
    assert_eq!(
        first_usable(ModelClass::Zener, (0, 10), models, all).unwrap_err(),
        diverges
    );
    // Another error is not passed over.
    let other = |_: &Oscillator| -> Result<(), IdentError> {
        Err(IdentError::BadRows {
            start: 5,
            end: 1,
            samples: 10,
        })
    };
    assert!(matches!(
        first_usable(ModelClass::BoucWen, (0, 10), models, other),
        Err(IdentError::BadRows { .. })
    ));
}

/// Why a candidate was not added says what the test found and what it needs.
#[test]
fn the_held_out_reason_says_what_the_test_found() {
    let g = HeldOutGain {
        mse_before: 1.0,
        mse_after: 0.995,
        t: 1.0,
        p_value: 0.17,
        blocks: 8,
    };
    assert_eq!(
        held_out_reason(&g),
        "held out: mean squared error -0.50 % (p = 0.170 over 8 blocks; adding needs p < 0.01 and a drop of at least 1 %)"
    );
    let g = HeldOutGain {
        mse_after: f64::INFINITY,
        ..g
    };
    assert_eq!(
        held_out_reason(&g),
        "held out: its simulation diverges on a test range"
    );
}

/// The loop names an effect only if the fitted model has it: a dissipative effect fitted
/// with the sign that feeds energy in is no such effect, and no effect is added twice.
#[test]
fn effects_are_named_only_when_the_model_has_them() {
    let bw =
        |bg: f64| Oscillator::bouc_wen(1.0, 1.0, 1e3, BoucWen::from_products(1e3, bg, -1.0, 1.0));
    assert!(not_dissipating(Effect::Hysteresis, &bw(5.0)).is_none());
    let why = not_dissipating(Effect::Hysteresis, &bw(-0.003)).unwrap();
    assert!(why.contains("does not dissipate"), "{why}");
    let mut o = Oscillator::linear(1.0, 1.0, 1e3);
    o.extras.coulomb = Some(Coulomb {
        force: -1.0,
        smoothing_velocity: 0.1,
    });
    assert!(not_dissipating(Effect::CoulombFriction, &o).is_some());
    o.extras.coulomb = Some(Coulomb {
        force: 1.0,
        smoothing_velocity: 0.1,
    });
    assert!(not_dissipating(Effect::CoulombFriction, &o).is_none());
    assert_eq!(
        already_has(&o, Effect::CoulombFriction),
        Some("the model already has Coulomb friction")
    );
    assert_eq!(already_has(&o, Effect::CubicStiffness), None);
}
