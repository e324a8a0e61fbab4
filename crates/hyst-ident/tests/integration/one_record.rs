//! One random-force record of one hysteretic oscillator (issue 44): what it tells about the
//! Bouc-Wen element, and what it leaves free.
//!
//! The system is not the benchmark's: m = 1.5 kg, c = 6 N s/m, k = 3·10⁴ N/m, α = 3·10⁴ N/m,
//! βγ = 700, βδ = 300 N⁻¹ (ν = 1; a softening element that saturates at α/(βγ + βδ) = 30 N,
//! about 1 mm). Records from rest under a white force at 20, 50 and 80 N, made by another
//! integrator than the identification's (trapezoidal at 40 sub-steps, FIR decimation
//! 2·4·5), 1·10⁻⁵ m of white sensor noise.

use hyst_ident::amplitude::ModeToFollow;
use hyst_ident::{self as ident, IdentOptions};
use hyst_model::{BoucWen, Oscillator};
use hyst_sim::excitation::{add_noise, white_noise};
use hyst_sim::{
    Decimation, Input, InputKind, Integrator, SensorNoise, SimOptions, WhiteForceRecord,
};

const FS: f64 = 750.0;
const NOISE: f64 = 1e-5;

fn truth() -> Oscillator {
    Oscillator::bouc_wen(
        1.5,
        6.0,
        3e4,
        BoucWen::from_products(3e4, 700.0, 300.0, 1.0),
    )
}

/// A record from rest: force and noisy output.
fn record(o: &Oscillator, level: f64, n: usize, seed: u64) -> (Vec<f64>, Vec<f64>) {
    let opts = SimOptions {
        oversample: 40,
        integrator: Integrator::Trapezoidal,
        decimation: Decimation::Fir(vec![2, 4, 5]),
        ..SimOptions::default()
    };
    WhiteForceRecord::new(level, n, seed)
        .with_input(InputKind::BandLimited)
        .with_sim(opts)
        .with_noise(SensorNoise::Std(NOISE))
        .generate(o, FS)
        .unwrap()
}

/// The validation error of `m` on (u, y) from rest, in units of the noise's standard deviation.
fn error_in_noise(m: &Oscillator, u: &[f64], y: &[f64]) -> f64 {
    let yhat = ident::simulate_model(m, u, FS, false).unwrap();
    ident::epsilon(&yhat, y).rms / NOISE
}

/// `hyst ident` does not keep a Bouc-Wen model that validates worse than its own Zener model,
/// and says why. The validation record is made by the identified Zener model itself (its
/// error there is the noise alone), so no Bouc-Wen candidate can beat it: the rule is tested
/// without depending on which model one noisy record favours.
#[test]
fn a_bouc_wen_model_worse_than_its_zener_is_not_kept() {
    let (_, y) = record(&truth(), 50.0, 1 << 15, 76_000);
    let opts = IdentOptions {
        mass: 1.5,
        ..IdentOptions::default()
    };
    let first = ident::identify_and_validate(&y, FS, &opts, None, &[]).unwrap();
    let zener = first.zener.expect("a white force gives a Zener model");
    assert!(
        first.bouc_wen.is_some(),
        "without records the first is kept"
    );
    assert!(
        first
            .notes
            .iter()
            .any(|n| n.contains("bound the ratio βδ/βγ only")),
        "{:?}",
        first.notes
    );
    let u = white_noise(8192, 50.0, 76_100).unwrap();
    let mut yv = ident::simulate_model(&zener, &u, FS, false).unwrap();
    add_noise(&mut yv, NOISE, 76_101).unwrap();
    let records = [ident::ValidationRecord::new("zener_made", u, yv)];
    let report = ident::identify_and_validate(&y, FS, &opts, None, &records).unwrap();
    let ez = report.validation[0]
        .zener
        .as_ref()
        .and_then(|s| s.epsilon())
        .unwrap();
    assert!(!report.candidates.is_empty());
    for c in &report.candidates {
        let eb = c.validation[0].epsilon().unwrap_or(f64::INFINITY);
        assert!(eb > ez, "{:?}: {eb} against the Zener's {ez}", c.route);
    }
    assert_eq!(report.bouc_wen, None);
    assert_eq!(report.bouc_wen_route, None);
    assert!(report.validation[0].bouc_wen.is_none());
    assert!(
        report
            .notes
            .iter()
            .any(|n| n.contains("no Bouc-Wen model is kept") && n.contains("zener_made")),
        "{:?}",
        report.notes
    );
}

/// One record's indirect inference (`levels::bouc_wen_from_one_record`): at the truth its
/// statistics (the Zener fit's four numbers and the amplitude curve's 16) are consistent with
/// the record, and a fit from there keeps every held parameter and improves on the truth's χ².
#[test]
fn one_record_indirect_inference_is_consistent_at_the_truth() {
    use hyst_ident::levels::{
        BoucWenParameter, OneRecord, SimulationOptions, bouc_wen_from_one_record,
    };
    let truth = truth();
    let n = 1 << 16;
    let (_, y) = record(&truth, 20.0, n, 77_000);
    let opts = IdentOptions {
        mass: 1.5,
        ..IdentOptions::default()
    };
    let f = ident::identify(&y, FS, &opts)
        .unwrap()
        .zener_spectrum
        .expect("a white force: step 3b runs");
    let mut copts = ident::amplitude::AmplitudeOptions::default();
    copts.measured = ident::amplitude::Quantity::Displacement;
    let mode = ModeToFollow {
        frequency_hz: f.pair.im / (2.0 * std::f64::consts::PI),
        damping_ratio: -f.pair.re / f.pair.norm(),
        shape: None,
    };
    let curve = ident::amplitude::amplitude_curves(&[&y], FS, &[mode], &[], &copts)
        .unwrap()
        .modes
        .remove(0)
        .points;
    let sopts = SimulationOptions::default();
    let fit = |start: &Oscillator, held: &[BoucWenParameter]| {
        bouc_wen_from_one_record(
            &OneRecord {
                fit: &f,
                y: &y,
                curve_opts: &copts,
            },
            start,
            held,
            &sopts,
            &|_, _| {},
        )
        .unwrap()
    };
    let at_truth = fit(&truth, &BoucWenParameter::ALL);
    assert_eq!(at_truth.residuals, 4 + 2 * curve.len() + 1);
    assert_eq!(at_truth.iterations, 0);
    assert_eq!(at_truth.oscillator, truth);
    // χ² of 20 numbers at the truth: measured 16.4–22.6 over four records of 20 and 50 N
    // (`study_one_record_profile`); 52 is χ²(20)'s 1e-4 upper quantile.
    assert!(at_truth.chi2 < 52.0, "{}", at_truth.chi2);
    let held = [BoucWenParameter::BetaDelta];
    let fitted = fit(&truth, &held);
    assert!(
        fitted.chi2 <= at_truth.chi2,
        "{} vs {}",
        fitted.chi2,
        at_truth.chi2
    );
    let (hyst_model::Restoring::BoucWen(a), hyst_model::Restoring::BoucWen(b)) =
        (fitted.oscillator.restoring, truth.restoring)
    else {
        unreachable!("Bouc-Wen oscillators")
    };
    assert_eq!(a.beta_delta(), b.beta_delta());
    assert!(fitted.se[4].is_nan());
    assert!(
        fitted.se[..4].iter().all(|s| s.is_finite() && *s > 0.0),
        "{:?}",
        fitted.se
    );
    // A start that is no Bouc-Wen oscillator is refused by name.
    let err = fit_err(&f, &y, &copts, &f.oscillator());
    assert!(err.contains("Bouc-Wen"), "{err}");
}

fn fit_err(
    f: &ident::zener_spectrum::ZenerSpectralFit,
    y: &[f64],
    copts: &ident::amplitude::AmplitudeOptions,
    start: &Oscillator,
) -> String {
    ident::levels::bouc_wen_from_one_record(
        &ident::levels::OneRecord {
            fit: f,
            y,
            curve_opts: copts,
        },
        start,
        &[],
        &ident::levels::SimulationOptions::default(),
        &|_, _| {},
    )
    .unwrap_err()
    .to_string()
}

#[test]
#[ignore = "a study: the truth's own validation error under other generators"]
fn study_generator_floor() {
    let truth = truth();
    for level in [20.0, 50.0, 80.0] {
        let u = white_noise(8192, level, 5).unwrap();
        let base = ident::simulate_model(&truth, &u, FS, false).unwrap();
        for (name, o) in [
            (
                "rk4 x80 subsample",
                SimOptions {
                    oversample: 80,
                    ..SimOptions::default()
                },
            ),
            (
                "trap x40 subsample",
                SimOptions {
                    oversample: 40,
                    integrator: Integrator::Trapezoidal,
                    ..SimOptions::default()
                },
            ),
            (
                "trap x200 subsample",
                SimOptions {
                    oversample: 200,
                    integrator: Integrator::Trapezoidal,
                    ..SimOptions::default()
                },
            ),
            (
                "rk4 x40 fir",
                SimOptions {
                    oversample: 40,
                    decimation: Decimation::Fir(vec![2, 4, 5]),
                    ..SimOptions::default()
                },
            ),
            (
                "trap x40 fir",
                SimOptions {
                    oversample: 40,
                    integrator: Integrator::Trapezoidal,
                    decimation: Decimation::Fir(vec![2, 4, 5]),
                    ..SimOptions::default()
                },
            ),
        ] {
            let y = hyst_sim::simulate(&truth, Input::BandLimited(&u), FS, u.len(), &o).unwrap();
            eprintln!(
                "{level} N {name}: {:.2} noise units",
                ident::epsilon(&base, &y).rms / NOISE
            );
        }
    }
}

#[test]
#[ignore = "a study: one record's profile along βδ/βγ at 20, 50 and 80 N in noise units, and the several-level model beside it (minutes)"]
fn study_one_record_profile() {
    use hyst_ident::levels::{
        OneRecord, PROFILE_RATIOS, SimulationOptions, beta_delta_profile, bouc_wen_by_simulation,
        bouc_wen_from_levels,
    };
    let truth = truth();
    let levels = [20.0, 50.0, 80.0];
    let n = 1 << 16;
    let seed0: u64 = std::env::var("SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(73_000);
    let checks: Vec<_> = levels
        .iter()
        .enumerate()
        .map(|(i, &l)| record(&truth, l, 1 << 13, seed0 + 500 + 10 * i as u64))
        .collect();
    let opts = IdentOptions {
        mass: 1.5,
        ..IdentOptions::default()
    };
    let mut copts = ident::amplitude::AmplitudeOptions::default();
    copts.measured = ident::amplitude::Quantity::Displacement;
    let e = |m: &Oscillator| -> Vec<f64> {
        checks
            .iter()
            .map(|(u, y)| error_in_noise(m, u, y))
            .collect()
    };
    eprintln!("[{seed0}] the truth's checks {:.2?}", e(&truth));
    let sopts = SimulationOptions::default();
    let mut fits = Vec::new();
    for (i, &level) in levels.iter().enumerate() {
        let (_, y) = record(&truth, level, n, seed0 + 10 * i as u64);
        let id = ident::identify(&y, FS, &opts).unwrap();
        let Some(f) = id.zener_spectrum.clone() else {
            eprintln!(
                "[{seed0}] {level} N: no Zener spectral fit ({:?})",
                id.models.notes
            );
            continue;
        };
        fits.push(f.clone());
        let rec = OneRecord {
            fit: &f,
            y: &y,
            curve_opts: &copts,
        };
        eprintln!(
            "[{seed0}] {level} N: Zener checks {:.2?}",
            e(&f.oscillator())
        );
        for p in beta_delta_profile(&rec, &PROFILE_RATIOS, &sopts, &|_, _| {}) {
            match p.fit {
                Ok(fit) => eprintln!(
                    "[{seed0}]   βδ/βγ {:5.2}: χ² {:7.1}  checks {:.2?}",
                    p.ratio,
                    fit.chi2,
                    e(&fit.oscillator)
                ),
                Err(err) => eprintln!("[{seed0}]   βδ/βγ {}: {err}", p.ratio),
            }
        }
    }
    if fits.len() >= 2 {
        let refs: Vec<_> = fits.iter().collect();
        let closure = bouc_wen_from_levels(&refs).unwrap();
        let lengths = vec![n; refs.len()];
        match bouc_wen_by_simulation(&refs, &lengths, &closure.oscillator, &sopts, &|_, _| {}) {
            Ok(sim) => eprintln!(
                "[{seed0}] {} levels: closure checks {:.2?}; by simulation checks {:.2?}",
                refs.len(),
                e(&closure.oscillator),
                e(&sim.oscillator)
            ),
            Err(err) => eprintln!("[{seed0}] levels by simulation: {err}"),
        }
    }
}

/// `hyst ident --profile` on one record at `level` (N), validated at 20, 50 and 80 N: the
/// report, and for the points within 4 of the profile's least χ² (about two standard errors
/// of one parameter), the ratio of their largest to their smallest error at 80 N.
fn profile_spread(level: f64, seed: u64) -> (ident::IdentReport, f64) {
    let truth = truth();
    let (_, y) = record(&truth, level, 1 << 16, seed);
    let records: Vec<_> = [20.0, 50.0, 80.0]
        .iter()
        .enumerate()
        .map(|(i, &l)| {
            let (u, y) = record(&truth, l, 1 << 13, seed + 100 + 10 * i as u64);
            ident::ValidationRecord::new(format!("{l} N"), u, y)
        })
        .collect();
    let opts = IdentOptions {
        mass: 1.5,
        profile: true,
        ..IdentOptions::default()
    };
    let report = ident::identify_and_validate(&y, FS, &opts, None, &records).unwrap();
    let fits: Vec<(f64, f64)> = report
        .profile
        .iter()
        .filter_map(|r| {
            let chi2 = r.point.fit.as_ref().ok()?.chi2;
            Some((chi2, r.validation.get(2)?.epsilon()?))
        })
        .collect();
    let least = fits.iter().map(|f| f.0).fold(f64::INFINITY, f64::min);
    let near: Vec<f64> = fits
        .iter()
        .filter(|f| f.0 <= least + 4.0)
        .map(|f| f.1)
        .collect();
    let spread = near.iter().copied().fold(0.0, f64::max)
        / near.iter().copied().fold(f64::INFINITY, f64::min);
    (report, spread)
}

/// `hyst ident --profile` on one 20 N record: every ratio gives a model, validated on every
/// record, and models the record's statistics cannot tell apart (χ² within 4 of the least)
/// predict the 80 N record differently: their errors there differ by more than a factor 1.3
/// (measured 2.5 on this record; 1.47, 3.5, 3.6, 6.4 and 8.8 on five others,
/// `study_profile_spread`).
#[test]
fn the_profile_shows_what_one_record_leaves_free() {
    let (report, spread) = profile_spread(20.0, 78_000);
    eprintln!("{report}");
    assert_eq!(report.profile.len(), ident::levels::PROFILE_RATIOS.len());
    for row in &report.profile {
        let fit = row
            .point
            .fit
            .as_ref()
            .expect("every ratio's closure start is valid here");
        assert!(fit.chi2.is_finite() && fit.residuals == 21, "{fit:?}");
        assert_eq!(row.validation.len(), 3);
    }
    assert!(spread > 1.3, "{spread}");
}

#[test]
#[ignore = "a study: the profile's spread at 80 N over fresh records (a minute each)"]
fn study_profile_spread() {
    for (level, seed) in [
        (20.0, 79_000),
        (20.0, 80_000),
        (50.0, 81_000),
        (50.0, 82_000),
        (20.0, 83_000),
    ] {
        let (r, spread) = profile_spread(level, seed);
        let chi: Vec<String> = r
            .profile
            .iter()
            .map(|p| {
                let e = p
                    .validation
                    .iter()
                    .map(|s| {
                        s.epsilon()
                            .map_or("-".into(), |e| format!("{:.2}", 100.0 * e))
                    })
                    .collect::<Vec<_>>()
                    .join("/");
                format!(
                    "{:.1}: {} [{e}]",
                    p.point.ratio,
                    p.point
                        .fit
                        .as_ref()
                        .map_or("-".into(), |f| format!("{:.1}", f.chi2))
                )
            })
            .collect();
        eprintln!(
            "{level} N seed {seed}: spread {spread:.2}; {}",
            chi.join("; ")
        );
    }
}
