//! The figure of `hyst amplitude --svg`: each mode's frequency and damping ratio against its
//! amplitude, ± one standard error.

use plotters::prelude::*;

use crate::ident::amplitude::{AmplitudeReport, ModeCurve};
use crate::plot::colors;

/// One row per mode: its natural frequency (left) and damping ratio (right) against its
/// amplitude, each point with a bar of ± one standard error; the SVG as a string.
pub fn amplitude_svg(r: &AmplitudeReport, title: &str) -> String {
    let rows = r.modes.len().max(1);
    let mut svg = String::new();
    {
        let root =
            SVGBackend::with_string(&mut svg, (900, 60 + 300 * rows as u32)).into_drawing_area();
        if draw(&root, r, title).is_err() {
            // A failed drawing leaves what was drawn; there is nothing to recover here.
        }
        let _ = root.present();
    }
    svg
}

type Area<'a> = DrawingArea<SVGBackend<'a>, plotters::coord::Shift>;

fn draw(root: &Area<'_>, r: &AmplitudeReport, title: &str) -> Result<(), String> {
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let root = root
        .titled(title, ("sans-serif", 20))
        .map_err(|e| e.to_string())?;
    let rows = root.split_evenly((r.modes.len().max(1), 2));
    let unit = format!("amplitude ({})", r.amplitude_of.name());
    for (j, c) in r.modes.iter().enumerate() {
        let f = |p: &crate::ident::amplitude::AmplitudePoint| (p.frequency_hz, p.frequency_se_hz);
        let z = |p: &crate::ident::amplitude::AmplitudePoint| {
            (100.0 * p.damping_ratio, 100.0 * p.damping_se)
        };
        panel(
            &rows[2 * j],
            c,
            &unit,
            &format!("{:.3} Hz: frequency (Hz)", c.mode.frequency_hz),
            &f,
        )?;
        panel(
            &rows[2 * j + 1],
            c,
            &unit,
            &format!("{:.3} Hz: damping ratio (%)", c.mode.frequency_hz),
            &z,
        )?;
    }
    Ok(())
}

fn panel(
    area: &Area<'_>,
    c: &ModeCurve,
    xl: &str,
    yl: &str,
    value: &dyn Fn(&crate::ident::amplitude::AmplitudePoint) -> (f64, f64),
) -> Result<(), String> {
    let pts: Vec<(f64, f64, f64)> = c
        .points
        .iter()
        .map(|p| {
            let (v, se) = value(p);
            (p.amplitude, v, se)
        })
        .filter(|p| p.0.is_finite() && p.1.is_finite() && p.2.is_finite())
        .collect();
    if pts.is_empty() {
        return Ok(());
    }
    let (x0, x1) = pts.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |a, p| {
        (a.0.min(p.0), a.1.max(p.0))
    });
    let (y0, y1) = pts.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |a, p| {
        (a.0.min(p.1 - p.2), a.1.max(p.1 + p.2))
    });
    let (dx, dy) = (
        (x1 - x0).max(1e-12 * x1.abs().max(1e-300)) * 0.08,
        (y1 - y0).max(1e-9 * y1.abs().max(1.0)) * 0.1,
    );
    let mut chart = ChartBuilder::on(area)
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(x0 - dx..x1 + dx, y0 - dy..y1 + dy)
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc(xl)
        .y_desc(yl)
        .x_label_formatter(&|v| format!("{v:.2e}"))
        .draw()
        .map_err(|e| e.to_string())?;
    chart
        .draw_series(pts.iter().map(|&(x, y, se)| {
            ErrorBar::new_vertical(x, y - se, y, y + se, colors::BLUE.filled(), 8)
        }))
        .map_err(|e| e.to_string())?;
    chart
        .draw_series(
            pts.iter()
                .map(|&(x, y, _)| Circle::new((x, y), 3, colors::BLUE.filled())),
        )
        .map_err(|e| e.to_string())?;
    Ok(())
}
