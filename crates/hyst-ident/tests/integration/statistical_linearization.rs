//! The statistical linearization of the Bouc-Wen benchmark (hyst-linearize) against direct
//! simulation (hyst-sim) and output-only identification (hyst-ident): the Zener element the
//! pipeline fits to the response under a white force is the one the linearization predicts,
//! one Bouc-Wen model from several levels validates better than each level's own
//! one-amplitude mapping, and the model fitted by simulation (indirect inference) better still,
//! its parameters within four standard errors of the benchmark's.

use hyst_ident::{self as ident, IdentOptions, Linearization};
use hyst_linearize::statistical;
use hyst_model::{Oscillator, Restoring};
use hyst_sim::InputKind;
use hyst_sim::excitation::add_noise;

const FS: f64 = 750.0;

/// One steady-state period of the benchmark's response to a periodic white force of RMS
/// `level` (N): input and output.
fn steady(level: f64, samples: usize, seed: u64) -> (Vec<f64>, Vec<f64>) {
    steady_of(&Oscillator::benchmark(), level, samples, seed)
}

/// [`steady`] of any oscillator.
fn steady_of(o: &Oscillator, level: f64, samples: usize, seed: u64) -> (Vec<f64>, Vec<f64>) {
    hyst_sim::WhiteForceRecord::new(level, samples, seed)
        .with_input(InputKind::Periodic)
        .generate(o, FS)
        .unwrap()
}

#[test]
fn identified_zener_is_the_statistical_linearization_and_levels_give_one_bouc_wen() {
    let truth = Oscillator::benchmark();
    let Restoring::BoucWen(bw) = truth.restoring else {
        unreachable!("the benchmark is a Bouc-Wen oscillator")
    };
    let opts = IdentOptions {
        linearization: Linearization::Paper,
        ..IdentOptions::default()
    };
    let levels = [10.0, 30.0, 50.0];
    let mut fits = Vec::new();
    let mut mapped = Vec::new();
    for (i, &level) in levels.iter().enumerate() {
        let (_, mut y) = steady(level, 1 << 17, 100 + i as u64);
        // The benchmark's measurement noise.
        add_noise(&mut y, 7.4e-6, 200 + i as u64).unwrap();
        let id = ident::identify(&y, FS, &opts).unwrap();
        let f = id
            .zener_spectrum
            .clone()
            .expect("a white force: step 3b runs");
        let (pred, _) = statistical::equivalent_zener(
            truth.mass,
            truth.damping,
            truth.stiffness,
            &bw,
            level * level / FS,
        )
        .unwrap();
        let z = [
            (f.k_inf - pred.k_inf) / f.se[2],
            (f.omega - pred.omega) / f.se[3],
        ];
        eprintln!(
            "{level} N: k∞ {:.0} ± {:.0} (predicted {:.0}), Ω {:.2} ± {:.2} (predicted {:.2})",
            f.k_inf, f.se[2], pred.k_inf, f.omega, f.se[3], pred.omega
        );
        // Four standard errors: an unbiased estimate lands outside once in ~16000 draws. The
        // Gaussian closure's own bias grows with the level (on `cargo xtask sweep-random` k∞
        // is 5 standard errors below at 80-90 N); up to 50 N it was within 2.
        for z in z {
            assert!(z.abs() < 4.0, "{level} N: z = {z}");
        }
        mapped.push(id.models.bouc_wen_mapped.expect("the paper's mapping"));
        fits.push(f);
    }
    let refs: Vec<_> = fits.iter().collect();
    let model = ident::levels::bouc_wen_from_levels(&refs).unwrap();
    eprintln!("levels' model: {:?} se {:?}", model.oscillator, model.se);
    // With the exponent free too, the levels give the benchmark's ν = 1 back (the Gaussian
    // closure's bias included, within four of its standard errors).
    let free = ident::levels::bouc_wen_and_exponent_from_levels(&refs).unwrap();
    let Restoring::BoucWen(b) = free.oscillator.restoring else {
        unreachable!("a Bouc-Wen model")
    };
    eprintln!(
        "levels' model with ν free: ν = {:.3} ± {:.3}, χ² per dof {:.2} (ν = 1: {:.2})",
        b.nu, free.nu_se, free.chi2_per_dof, model.chi2_per_dof
    );
    assert!(
        (b.nu - 1.0).abs() < 4.0 * free.nu_se,
        "ν = {} ± {}",
        b.nu,
        free.nu_se
    );
    // Indirect inference from there: the model whose simulated records give the same fits.
    let sim = ident::levels::bouc_wen_by_simulation(
        &refs,
        &[1 << 17; 3],
        &model.oscillator,
        &ident::levels::SimulationOptions {
            periodic: true,
            ..Default::default()
        },
        &|it, cost| eprintln!("simulation fit, iteration {it}: {cost:.2}"),
    )
    .unwrap();
    eprintln!(
        "by simulation: {:?} se {:?}, residual RMS {:.2}",
        sim.oscillator, sim.se, sim.residual_rms
    );
    // Indirect inference is consistent: every parameter within four of its standard errors of
    // the benchmark (over five nine-level sweeps the spread was at most about the standard
    // errors, docs/paper-deviations.md).
    let Restoring::BoucWen(got) = sim.oscillator.restoring else {
        unreachable!("a Bouc-Wen model")
    };
    let o = &sim.oscillator;
    for (name, value, truth, se) in [
        ("c", o.damping, truth.damping, sim.se[0]),
        ("k", o.stiffness, truth.stiffness, sim.se[1]),
        ("alpha", got.alpha, bw.alpha, sim.se[2]),
        ("beta_gamma", got.beta_gamma(), bw.beta_gamma(), sim.se[3]),
        ("beta_delta", got.beta_delta(), bw.beta_delta(), sim.se[4]),
    ] {
        assert!(
            (value - truth).abs() < 4.0 * se,
            "{name}: {value} ± {se} against {truth}"
        );
    }
    for (i, &level) in levels.iter().enumerate() {
        let (uv, yv) = steady(level, 8192, 300 + i as u64);
        let eps = |m: &Oscillator| {
            let yhat = ident::simulate_model(m, &uv, FS, true).unwrap();
            ident::epsilon(&yhat, &yv).epsilon
        };
        let (all, own, by_sim) = (
            eps(&model.oscillator),
            eps(&mapped[i]),
            eps(&sim.oscillator),
        );
        eprintln!(
            "{level} N: ε levels' model {all:.4}, by simulation {by_sim:.4}, this level's mapping {own:.4}"
        );
        assert!(all < own, "{level} N: {all} vs {own}");
        assert!(by_sim < all, "{level} N: {by_sim} vs {all}");
    }
}

/// An element of exponent ν = 2 (softening, γ + δ > 0, as strong as the benchmark's at
/// |z| = 33 N), output only at three force levels: with ν free the levels give ν = 2 back
/// within four standard errors, and ν = 1 does not explain them (χ² above 30.7, the 1e-6
/// upper quantile of χ² with 3 degrees of freedom). Measured: ν = 1.90 ± 0.10, χ² 7.0 with
/// ν free (2 degrees of freedom) and 84 with ν = 1. (`hyst levels --fit-exponent
/// --by-simulation` removes the closure's bias at the cost of minutes: docs/results.md.)
#[test]
fn levels_tell_the_exponent() {
    let bg = 800.0 / 33.0;
    let truth = Oscillator::bouc_wen(
        2.0,
        10.0,
        5e4,
        hyst_model::BoucWen::from_products(5e4, bg, -0.5 * bg, 2.0),
    );
    let opts = IdentOptions {
        mass: truth.mass,
        ..IdentOptions::default()
    };
    let fits: Vec<_> = [10.0, 50.0, 90.0]
        .iter()
        .enumerate()
        .map(|(i, &level)| {
            let (_, mut y) = steady_of(&truth, level, 1 << 17, 100 + i as u64);
            add_noise(&mut y, 7.4e-6, 200 + i as u64).unwrap();
            let id = ident::identify(&y, FS, &opts).unwrap();
            id.zener_spectrum.expect("a white force: step 3b runs")
        })
        .collect();
    let refs: Vec<_> = fits.iter().collect();
    let one = ident::levels::bouc_wen_from_levels(&refs).unwrap();
    let free = ident::levels::bouc_wen_and_exponent_from_levels(&refs).unwrap();
    let Restoring::BoucWen(b) = free.oscillator.restoring else {
        unreachable!("a Bouc-Wen model")
    };
    let (chi2_one, chi2_free) = (3.0 * one.chi2_per_dof, 2.0 * free.chi2_per_dof);
    eprintln!(
        "ν = {:.3} ± {:.3}; χ² {chi2_free:.1} with ν free, {chi2_one:.1} with ν = 1; {:?}",
        b.nu, free.nu_se, free.oscillator
    );
    assert!(
        (b.nu - 2.0).abs() < 4.0 * free.nu_se,
        "ν = {} ± {}",
        b.nu,
        free.nu_se
    );
    assert!(chi2_one > 30.7, "ν = 1 explains the levels: χ² {chi2_one}");
}
