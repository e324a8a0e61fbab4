//! The figures of `hyst refine --svg-dir`.

use crate::ident::residual::{response, surface};
use crate::plot::{cell_map, chart, chart_log_y, colors};

/// Residual spectra (estimation rows) of the baseline and the final model, both models
/// against the measured output over the first second of the first test range, and the
/// restoring-force surface of the baseline's residual (its map over the phase plane and its
/// two sections, the final model's sections beside them).
pub fn residual_figures(
    dir: &std::path::Path,
    r: &crate::ident::residual::Refinement,
    rec: &crate::ident::residual::Record<'_>,
    estimate: (usize, usize),
    test: (usize, usize),
    fit_mass: bool,
) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    residual_spectra(dir, r, rec, estimate)?;
    time_overlay(dir, r, rec, test)?;
    let first = surface::trace(&r.baseline, rec, estimate, fit_mass);
    surface_maps(dir, &first)?;
    sections(dir, first.fit.as_ref(), r.trace.as_ref())
}

/// Residual spectra (estimation rows) of the baseline and the final model.
fn residual_spectra(
    dir: &std::path::Path,
    r: &crate::ident::residual::Refinement,
    rec: &crate::ident::residual::Record<'_>,
    estimate: (usize, usize),
) -> Result<(), String> {
    let y = &rec.y[estimate.0..estimate.1];
    let resid = |m: &crate::model::Oscillator| -> Vec<f64> {
        response(m, rec, estimate)
            .map(|h| y.iter().zip(&h).map(|(a, b)| a - b).collect())
            .unwrap_or_default()
    };
    let psd = |v: &[f64]| -> Vec<(f64, f64)> {
        let (f, s) = crate::ident::welch_psd(v, rec.fs, 512);
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
    )
}

/// Both models against the measured output over the first second of the test rows.
fn time_overlay(
    dir: &std::path::Path,
    r: &crate::ident::residual::Refinement,
    rec: &crate::ident::residual::Record<'_>,
    test: (usize, usize),
) -> Result<(), String> {
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
    )
}

/// The baseline's missing force binned over the phase plane, and its fitted surface on the
/// same cells.
fn surface_maps(dir: &std::path::Path, first: &surface::Trace) -> Result<(), String> {
    let g = surface::grid(first, 24);
    cell_map(
        &dir.join("residual_force_cells.svg"),
        "Force the baseline misses over (x, dx/dt), binned",
        "x",
        "dx/dt",
        &g.x_edges,
        &g.v_edges,
        &g.mean,
    )?;
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
        )?;
    }
    Ok(())
}

/// The missing force's two sections (a stiffness and a damping curve), the baseline's
/// fitted and binned beside the final model's fitted.
fn sections(
    dir: &std::path::Path,
    baseline: Option<&surface::SurfaceFit>,
    after: Option<&surface::SurfaceFit>,
) -> Result<(), String> {
    let sections = |stiffness: bool| {
        let mut series = Vec::new();
        for (label, f, c) in [
            ("baseline", baseline, colors::BLUE),
            ("after the loop", after, colors::RED),
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
