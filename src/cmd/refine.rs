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

/// Residual spectra (estimation rows) of the baseline and the final model, both models
/// against the measured output over the first second of the first test range, and the
/// restoring-force surface of the baseline's residual (its map over the phase plane and its
/// two sections, the final model's sections beside them).
pub(crate) fn refine_figures(
    dir: &std::path::Path,
    r: &hyst::ident::residual::Refinement,
    rec: &hyst::ident::residual::Record<'_>,
    estimate: (usize, usize),
    test: (usize, usize),
    fit_mass: bool,
) -> Result<(), Error> {
    use hyst::ident::residual::{response, surface};
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
    use hyst::ident::residual::{self, Record, Start};
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
            InterpolationArg::BandLimited => residual::InputInterpolation::BandLimited,
            InterpolationArg::Linear => residual::InputInterpolation::Linear,
        },
    };
    // One line per step on stderr while the loop runs (hidden when stderr is not a terminal).
    let t0 = std::time::Instant::now();
    let bar = spinner();
    let say = |m: &str| bar.set_message(format!("{:.0} s: {m}", t0.elapsed().as_secs_f64()));
    let r = residual::refine_report(&rec, a.mass, start, estimate, &tests, &say)
        .map_err(|e| fail(format!("{}: {e}", a.data.display())));
    bar.finish_and_clear();
    let report = hyst::report::FileReport::new(a.data.display().to_string(), r?);
    print!("{}", report.report);
    if let Some(dir) = &a.svg_dir {
        refine_figures(
            dir,
            &report.report.refinement,
            &rec,
            estimate,
            tests[0],
            a.mass.is_none(),
        )?;
    }
    if let Some(path) = &a.json {
        report.write_json(path)?;
    }
    Ok(())
}
