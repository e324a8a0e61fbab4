//! `cargo xtask bench refine`: the residual loop's speed (its lockstep simulations against
//! one by one, the bench record, the measured Silverbox).

use hyst_model::Oscillator;
use hyst_sim::excitation::white_noise;
use hyst_sim::{Input, SimOptions, simulate};

use crate::best_of;

/// `hyst_sim::simulate_many` against the same models simulated one by one: a batch of Bouc-Wen
/// models (ν = 1, the benchmark's element scaled to a 10 Hz oscillator, each a little off
/// the others as a finite-difference Jacobian's are) on 32768 samples at 4 sub-steps, the
/// loop's simulations; then with a cubic spring (the general kernel).
fn simulate_many_ratio() {
    use hyst_model::{BoucWen, Restoring};
    let n = 32768;
    let w = 2.0 * std::f64::consts::PI * 10.0;
    let u = white_noise(n, 10.0, 31).expect("valid rms");
    let opts = SimOptions {
        oversample: 4,
        ..SimOptions::default()
    };
    let mut base = Oscillator::linear(1.0, 2.0 * 0.02 * w, w * w);
    base.restoring = Restoring::BoucWen(BoucWen {
        alpha: 0.3 * w * w,
        beta: 1.0,
        gamma: 20.0,
        delta: -5.0,
        nu: 1.0,
    });
    for (name, cubic) in [("bouc_wen", 0.0), ("bouc_wen_cubic", 1e5)] {
        let models: Vec<Oscillator> = (0..hyst_sim::batch::LANES)
            .map(|j| {
                let mut m = base;
                m.stiffness *= 1.0 + 1e-6 * j as f64;
                m.extras.cubic_stiffness = cubic;
                m
            })
            .collect();
        let one = best_of(3, || {
            models
                .iter()
                .map(|m| simulate(m, Input::Sampled(&u), 200.0, n, &opts).expect("stable"))
                .collect::<Vec<_>>()
        });
        let many = best_of(3, || {
            hyst_sim::simulate_many(&models, Input::Sampled(&u), 200.0, n, &opts)
        });
        println!(
            "simulate_many_{name}_{}x32768 {:.1} ms (one by one {:.1} ms, ratio {:.2})",
            models.len(),
            1e3 * many,
            1e3 * one,
            many / one
        );
    }
}

/// `hyst refine`'s loop on a 32768-sample record: a 10 Hz oscillator with an undeclared cubic
/// spring under white noise at 200 Hz, estimate on 75 %, test on 25 %; then on the Silverbox.
pub(crate) fn run() {
    simulate_many_ratio();
    use hyst_ident::residual::{self, ModelClass, Record};
    let n = 32768;
    let w = 2.0 * std::f64::consts::PI * 10.0;
    let mut o = Oscillator::linear(1.0, 2.0 * 0.02 * w, w * w);
    let u = white_noise(n, 10.0, 31).expect("valid rms");
    let y0 = simulate(&o, Input::Sampled(&u), 200.0, n, &SimOptions::default()).expect("stable");
    let sx = (y0.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
    o.extras.cubic_stiffness = 0.1 * o.stiffness / (sx * sx);
    let y = simulate(&o, Input::Sampled(&u), 200.0, n, &SimOptions::default()).expect("stable");
    let rec = Record {
        u: &u,
        y: &y,
        fs: 200.0,
        interpolation: residual::InputInterpolation::Linear,
    };
    let mut r = None;
    let t = best_of(1, || {
        r = Some(
            residual::refine_record(
                &rec,
                Some(1.0),
                ModelClass::Linear,
                (0, 3 * n / 4),
                &[(3 * n / 4, n)],
            )
            .expect("refines"),
        );
    });
    // What the loop did, so that a change of time can be told from a change of path.
    let steps: Vec<String> = r
        .iter()
        .flat_map(|r| &r.steps)
        .map(|s| {
            let refused = s
                .evidence
                .iter()
                .filter(|e| {
                    e.rejected
                        .as_deref()
                        .is_some_and(|w| w.starts_with("held out"))
                })
                .count();
            format!(
                "{} (held-out eps {:.4} -> {:.4} %{})",
                s.effect.map_or("none", |e| e.name()),
                100.0 * s.before[0].epsilon,
                100.0 * s.after[0].epsilon,
                if refused > 0 {
                    format!(", {refused} refused by it")
                } else {
                    String::new()
                }
            )
        })
        .collect();
    println!("refine_s_32768 {t:.2} s (steps: {})", steps.join(", "));
    silverbox();
}

/// The residual loop on the measured Silverbox, as `crates/hyst-ident/tests/integration/refine_silverbox.rs` runs it
/// (linear start, estimate on the first 75 % of the multisine part, test on the arrow head).
fn silverbox() {
    use hyst_ident::residual::{self, ModelClass, Record};
    let Some(dir) = hyst_testkit::data_dir() else {
        println!("refine_silverbox_s skipped: no shared data");
        return;
    };
    let t = match hyst::io::read_csv(&dir.join("silverbox/SNLS80mV.csv")) {
        Ok(t) => t,
        Err(e) => {
            println!("refine_silverbox_s skipped: {e}");
            return;
        }
    };
    let (Ok(u), Ok(y)) = (t.column("u"), t.column("y")) else {
        println!("refine_silverbox_s skipped: no u and y columns");
        return;
    };
    let rec = Record {
        u,
        y,
        fs: 1e7 / 16384.0,
        interpolation: residual::InputInterpolation::BandLimited,
    };
    let estimate = (40650, 40650 + 3 * (127400 - 40650) / 4);
    let mut r = None;
    let secs = best_of(1, || {
        r = Some(residual::refine_record(
            &rec,
            None,
            ModelClass::Linear,
            estimate,
            &[(100, 40575), (100, 32100)],
        ));
    });
    match r {
        Some(Ok(r)) => {
            let steps: Vec<&str> = r
                .steps
                .iter()
                .map(|s| s.effect.map_or("none", |e| e.name()))
                .collect();
            println!(
                "refine_silverbox_s {secs:.1} s (target at most 60; steps: {}; arrow head {:.3} mV)",
                steps.join(", "),
                1e3 * r.tests[0].rms
            );
        }
        Some(Err(e)) => println!("refine_silverbox_s failed: {e}"),
        None => {}
    }
}
