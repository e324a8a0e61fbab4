//! `hyst refine`: the residual loop with input and output.

use std::path::PathBuf;

use clap::{Args, ValueEnum};

use super::*;

#[derive(Clone, Copy, ValueEnum, PartialEq, Eq, Debug)]
pub(crate) enum StartArg {
    Linear,
    Zener,
    BoucWen,
}

#[derive(Args, Debug)]
pub(crate) struct RefineArgs {
    /// Record with input and output columns (CSV with a header).
    #[arg(long)]
    pub(crate) data: PathBuf,
    /// Sampling rate (Hz).
    #[arg(long)]
    pub(crate) fs: f64,
    /// Mass (kg); without it the mass is estimated too (and the missing force is traced with
    /// the estimate).
    #[arg(long)]
    pub(crate) mass: Option<f64>,
    /// Input column.
    #[arg(long, default_value = "u")]
    pub(crate) input_column: String,
    /// Output column.
    #[arg(long, default_value = "y")]
    pub(crate) output_column: String,
    /// Starting model class. A start the output-only pipeline cannot give, or whose fit
    /// diverges, falls back to the next simpler one (bouc-wen, zener, linear), and the
    /// report says so.
    #[arg(long, value_enum, default_value = "linear")]
    pub(crate) start: StartArg,
    /// How the input is known between samples when the models are simulated.
    #[arg(long, value_enum, default_value = "band-limited")]
    pub(crate) input_interpolation: InterpolationArg,
    /// Estimation rows A:B (0-based, B excluded); default the first 75 %.
    #[arg(long)]
    pub(crate) estimate: Option<super::args::RowRange>,
    /// Test rows C:D (repeatable, at least 512 rows each); default the last 25 %. An effect
    /// is added only if it lowers the held-out mean squared error significantly (a paired
    /// test over 8 blocks of each range, p < 0.01) and by at least 1 %.
    #[arg(long)]
    pub(crate) test: Vec<super::args::RowRange>,
    /// Write the report as JSON here.
    #[arg(long)]
    pub(crate) json: Option<PathBuf>,
    /// Write figures (SVG) into this folder: residual spectra before/after, time overlays,
    /// and the restoring-force surface of the baseline's residual with its two sections.
    #[arg(long)]
    pub(crate) svg_dir: Option<PathBuf>,
}

/// `v` to six significant digits: fixed-point for magnitudes in [1e-3, 1e6), else exponent.
pub(crate) fn six_digits(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 || !a.is_finite() {
        format!("{v}")
    } else if (1e-3..1e6).contains(&a) {
        let decimals = (5 - a.log10().floor() as i32).max(0) as usize;
        format!("{v:.decimals$}")
    } else {
        format!("{v:.5e}")
    }
}

/// Residual spectra (estimation rows) of the baseline and the final model, both models
/// against the measured output over the first second of the first test range, and the
/// restoring-force surface of the baseline's residual (its map over the phase plane and its
/// two sections, the final model's sections beside them).
pub(crate) fn refine_figures(
    dir: &std::path::Path,
    r: &hyst::ident::refine::Refinement,
    rec: &hyst::ident::refine::Record<'_>,
    estimate: (usize, usize),
    test: (usize, usize),
    fit_mass: bool,
) -> Result<(), Error> {
    use hyst::ident::refine::{response, surface};
    use hyst::plot::{cell_map, chart, chart_log_y, colors};
    std::fs::create_dir_all(dir).map_err(|e| fail(format!("{}: {e}", dir.display())))?;
    let y = &rec.y[estimate.0..estimate.1];
    let resid = |m: &hyst::model::Oscillator| -> Vec<f64> {
        response(m, rec, estimate)
            .map(|h| y.iter().zip(&h).map(|(a, b)| a - b).collect())
            .unwrap_or_default()
    };
    let psd = |v: &[f64]| -> Vec<(f64, f64)> {
        let (f, s) = hyst::ident::welch_psd(v, rec.fs, 512);
        f.into_iter().zip(s).collect()
    };
    chart_log_y(
        &dir.join("residual_spectra.svg"),
        "Residual spectra (estimation rows)",
        "f (Hz)",
        "PSD",
        &[
            ("baseline".into(), psd(&resid(&r.baseline)), colors::BLUE),
            ("after the loop".into(), psd(&resid(&r.model)), colors::RED),
        ],
    )?;
    let n = ((rec.fs) as usize).min(test.1 - test.0);
    let t = |v: &[f64]| -> Vec<(f64, f64)> {
        v.iter()
            .take(n)
            .enumerate()
            .map(|(k, x)| (k as f64 / rec.fs, *x))
            .collect()
    };
    let mut series = vec![(
        "measured".to_string(),
        t(&rec.y[test.0..test.1]),
        colors::BLACK,
    )];
    for (label, m, c) in [
        ("baseline", &r.baseline, colors::BLUE),
        ("after the loop", &r.model, colors::RED),
    ] {
        if let Some(h) = response(m, rec, test) {
            series.push((label.to_string(), t(&h), c));
        }
    }
    chart(
        &dir.join("time_overlay.svg"),
        &format!("Test rows {}:{} (first second)", test.0, test.1),
        "t (s)",
        "y",
        &series,
    )?;
    let first = surface::trace(&r.baseline, rec, estimate, fit_mass);
    let g = surface::grid(&first, 24);
    cell_map(
        &dir.join("residual_force_cells.svg"),
        "Force the baseline misses over (x, dx/dt), binned",
        "x",
        "dx/dt",
        &g.x_edges,
        &g.v_edges,
        &g.mean,
    )
    .map_err(fail)?;
    if let Some(f) = &first.fit {
        // The fit on the same cells: the shape, without the noise of the binned means.
        let centre = |e: &[f64], i: usize| 0.5 * (e[i] + e[i + 1]);
        let fitted: Vec<Vec<Option<f64>>> = (0..g.x_edges.len() - 1)
            .map(|i| {
                (0..g.v_edges.len() - 1)
                    .map(|j| {
                        g.mean[i][j].map(|_| f.fitted(centre(&g.x_edges, i), centre(&g.v_edges, j)))
                    })
                    .collect()
            })
            .collect();
        cell_map(
            &dir.join("residual_force_surface.svg"),
            "Fitted surface of the force the baseline misses",
            "x",
            "dx/dt",
            &g.x_edges,
            &g.v_edges,
            &fitted,
        )
        .map_err(fail)?;
    }
    let sections = |stiffness: bool| {
        let mut series = Vec::new();
        for (label, f, c) in [
            ("baseline", first.fit.as_ref(), colors::BLUE),
            ("after the loop", r.trace.as_ref(), colors::RED),
        ] {
            let Some(f) = f else { continue };
            let fitted = f.fitted_sections(41);
            let (binned, fitted) = if stiffness {
                (f.stiffness_section.clone(), fitted.stiffness)
            } else {
                (f.damping_section.clone(), fitted.damping)
            };
            series.push((format!("{label}, fitted"), fitted, c));
            // The baseline's binned means, to show what the fit averages.
            if label == "baseline" {
                series.push(("baseline, binned".to_string(), binned, colors::GREY));
            }
        }
        series
    };
    chart(
        &dir.join("residual_force_stiffness.svg"),
        "Missing force where dx/dt ≈ 0 (a stiffness curve)",
        "x",
        "force (N)",
        &sections(true),
    )?;
    chart(
        &dir.join("residual_force_damping.svg"),
        "Missing force where x ≈ 0 (a damping curve)",
        "dx/dt",
        "force (N)",
        &sections(false),
    )?;
    Ok(())
}

pub(crate) fn run(a: &RefineArgs) -> Result<(), Error> {
    use hyst::ident::refine::{self, Record, Start, noise::NoiseMethod};
    use serde_json::json;
    let fs = check_fs(a.fs)?;
    let t = read_csv(&a.data)?;
    let u = t
        .column(&a.input_column)
        .map_err(|e| fail(format!("{e} (refine needs the input too)")))?;
    let y = t.column(&a.output_column)?;
    let n = y.len();
    let estimate = match &a.estimate {
        Some(r) => r.within("--estimate", n)?,
        None => (0, 3 * n / 4),
    };
    let tests: Vec<(usize, usize)> = if a.test.is_empty() {
        vec![(3 * n / 4, n)]
    } else {
        a.test
            .iter()
            .map(|r| r.within("--test", n))
            .collect::<Result<_, _>>()?
    };
    if let Some(m) = a.mass
        && !(m.is_finite() && m > 0.0)
    {
        return Err(fail(format!("--mass must be > 0 kg, got {m}")));
    }
    let start = match a.start {
        StartArg::Linear => Start::Linear,
        StartArg::Zener => Start::Zener,
        StartArg::BoucWen => Start::BoucWen,
    };
    let rec = Record {
        u,
        y,
        fs,
        interpolation: match a.input_interpolation {
            InterpolationArg::BandLimited => refine::InputInterpolation::BandLimited,
            InterpolationArg::Linear => refine::InputInterpolation::Linear,
        },
    };
    let t0 = std::time::Instant::now();
    // One line per step on stderr while the loop runs (hidden when stderr is not a terminal).
    let bar = indicatif::ProgressBar::new_spinner();
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    let say = |m: &str| bar.set_message(format!("{:.0} s: {m}", t0.elapsed().as_secs_f64()));
    let r = refine::refine_record_with(&rec, a.mass, start, estimate, &tests, &say)
        .map_err(|e| fail(format!("{}: {e}", a.data.display())));
    bar.finish_and_clear();
    let r = r?;
    let secs = t0.elapsed().as_secs_f64();
    let pct = |v: f64| format!("{:.3} %", 100.0 * v);
    println!(
        "start: {} (asked for {})",
        r.start.used.name(),
        r.start.requested.name()
    );
    for note in &r.start.notes {
        println!("  {note}");
    }
    if a.mass.is_none() {
        println!(
            "  no --mass: the mass is fitted ({:.6e} kg); the missing force is traced with it",
            r.model.mass
        );
    }
    println!(
        "baseline (output-only start, refined with the input): {}",
        osc_json(&r.baseline)
    );
    for s in &r.steps {
        let name = s.effect.map_or("none", |e| e.name());
        println!(
            "step: {name}  (residual peak {:.2} Hz, share above 1.5x resonance {:.2})",
            s.spectrum.peak_hz, s.spectrum.above_resonance
        );
        if let Some(f) = &s.trace {
            println!("    trace: {}", f.signature());
        }
        for e in &s.evidence {
            // The exponent's candidate says which ν it fitted.
            let nu = match (e.effect, e.model.map(|m| m.restoring)) {
                (refine::Effect::HysteresisExponent, Some(hyst::model::Restoring::BoucWen(b))) => {
                    format!("  (ν = {:.3})", b.nu)
                }
                _ => String::new(),
            };
            let held = e.held_out.map_or(String::new(), |g| {
                format!(
                    "  held out {:+.2} % (p {:.1e})",
                    -100.0 * g.relative_gain(),
                    g.p_value
                )
            });
            println!(
                "    {:<19} dBIC {:>12.1}  variance explained {:>7.3}{held}{nu}{}",
                e.effect.name(),
                e.delta_bic,
                e.variance_explained,
                e.rejected
                    .as_ref()
                    .map_or(String::new(), |w| format!("  ({w})"))
            );
        }
        for ((rows, b), af) in tests.iter().zip(&s.before).zip(&s.after) {
            println!(
                "    test {}:{}  eps {} -> {}  rms {:.4e} -> {:.4e}",
                rows.0,
                rows.1,
                pct(b.epsilon),
                pct(af.epsilon),
                b.rms,
                af.rms
            );
        }
    }
    println!("final model: {}", osc_json(&r.model));
    if !r.estimates.is_empty() {
        let list: Vec<String> = r
            .estimates
            .iter()
            .map(|e| format!("{} {} ± {:.2e}", e.name, six_digits(e.value), e.se))
            .collect();
        println!(
            "  with standard errors (output error, blocks of {} rows, coloured residual allowed): {}",
            refine::SE_BLOCK_ROWS,
            list.join(", ")
        );
    }
    match &r.noise {
        Ok(nl) => {
            let how = match nl.method {
                NoiseMethod::PeriodToPeriod { period, pairs } => {
                    format!("from the output one period ({period} samples) apart, {pairs} pairs")
                }
                NoiseMethod::OutOfBand { share } => format!(
                    "from the residual's spectrum where the input has no power ({:.0} % of the band; white noise assumed)",
                    100.0 * share
                ),
                NoiseMethod::Residual { out_of_band } => format!(
                    "the residual itself: above the level out of band ({out_of_band:.4e}) but no function of (x, dx/dt), of time or of the input, so coloured noise"
                ),
            };
            let eps: Vec<String> = r.noise_epsilon.iter().map(|e| pct(*e)).collect();
            println!(
                "noise level: {:.4e} (eps {} on the test rows), {how}",
                nl.std,
                eps.join(", ")
            );
        }
        Err(why) => println!("noise level: unknown ({why})"),
    }
    if r.nonstationary {
        println!("nonstationary: the halves of the estimation rows differ:");
        for h in refine::drift::drifting(&r.halves) {
            println!(
                "    {} {} ± {:.2e} then {} ± {:.2e} (z = {:.1})",
                h.name,
                six_digits(h.first.0),
                h.first.1,
                six_digits(h.second.0),
                h.second.1,
                h.z
            );
        }
    }
    match &r.unexplained {
        Some(u) => println!(
            "unexplained: the held-out residual is {:.2} × the noise level; the missing force: {}",
            u.residual_to_noise, u.signature
        ),
        None if r.noise.is_ok() => println!("the held-out residual is at the noise level"),
        None => {}
    }
    if let Some(dir) = &a.svg_dir {
        refine_figures(dir, &r, &rec, estimate, tests[0], a.mass.is_none())?;
    }
    println!("time: {secs:.1} s");
    if let Some(path) = &a.json {
        let first = r
            .steps
            .iter()
            .find_map(|s| s.effect)
            .map_or("none", |e| e.name());
        let base_err: Vec<_> = r
            .steps
            .first()
            .map(|s| s.before.clone())
            .unwrap_or_default();
        let finite = |v: f64| if v.is_finite() { json!(v) } else { json!(null) };
        let steps: Vec<_> = r
            .steps
            .iter()
            .map(|s| {
                json!({
                    "effect": s.effect.map_or("none", |e| e.name()),
                    "evidence": s.evidence.iter().map(|e| json!({
                        "effect": e.effect.name(), "delta_bic": finite(e.delta_bic),
                        "variance_explained": e.variance_explained, "rejected": e.rejected,
                        "held_out_p_value": e.held_out.map(|g| g.p_value),
                        "held_out_gain": e.held_out.map(|g| finite(g.relative_gain())),
                    })).collect::<Vec<_>>(),
                    "residual_peak_hz": s.spectrum.peak_hz,
                    "residual_share_above_resonance": s.spectrum.above_resonance,
                    "trace_signature": s.trace.as_ref().map(|f| f.signature()),
                    "p_value": s.gain.map(|g| g.p_value),
                    "held_out_gain": s.gain.map(|g| g.relative_gain()),
                    "error_before": s.before.first().map(|v| v.epsilon),
                    "error_after": s.after.first().map(|v| v.epsilon),
                })
            })
            .collect();
        let test_rows: Vec<_> = tests
            .iter()
            .enumerate()
            .map(|(i, rows)| {
                json!({
                    "rows": [rows.0, rows.1],
                    "rms_before": base_err.get(i).map(|v| v.rms),
                    "rms_after": r.tests.get(i).map(|v| v.rms),
                    "error_before": base_err.get(i).map(|v| v.epsilon),
                    "error_after": r.tests.get(i).map(|v| v.epsilon),
                    "noise_error": r.noise_epsilon.get(i).copied().map(finite),
                })
            })
            .collect();
        let noise = match &r.noise {
            Ok(nl) => json!({
                "std": nl.std,
                "epsilon": r.noise_epsilon.first().copied().map(finite),
                "method": match nl.method {
                    NoiseMethod::PeriodToPeriod { .. } => "period_to_period",
                    NoiseMethod::OutOfBand { .. } => "out_of_band",
                    NoiseMethod::Residual { .. } => "residual",
                },
            }),
            Err(_) => json!(null),
        };
        let doc = json!({
            "effect": first,
            "error_before": base_err.first().map(|v| v.epsilon),
            "error_after": r.tests.first().map(|v| v.epsilon),
            "steps": steps,
            "tests": test_rows,
            "model": osc_json(&r.model),
            "standard_errors": r.estimates.iter().map(|e| (e.name.to_string(), json!(e.se))).collect::<serde_json::Map<_, _>>(),
            "baseline": osc_json(&r.baseline),
            "start": {"requested": r.start.requested.name(), "used": r.start.used.name(), "notes": r.start.notes},
            "noise_level": noise,
            "noise_unknown": r.noise.as_ref().err(),
            "nonstationary": r.nonstationary,
            "halves": r.halves.iter().map(|h| json!({
                "name": h.name, "first": finite(h.first.0), "first_se": finite(h.first.1),
                "second": finite(h.second.0), "second_se": finite(h.second.1), "z": finite(h.z),
            })).collect::<Vec<_>>(),
            "unexplained": r.unexplained.as_ref().map(|u| json!({
                "residual_to_noise": u.residual_to_noise, "signature": u.signature,
            })),
            "seconds": secs,
        });
        std::fs::write(path, serde_json::to_string_pretty(&doc)?)
            .map_err(|e| fail(format!("{}: {e}", path.display())))?;
    }
    Ok(())
}
