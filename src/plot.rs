//! Line charts as SVG (plotters), for the figures the commands draw.

use std::path::Path;

use plotters::prelude::*;

/// One curve: its legend name, its points, and its colour (r, g, b).
pub type Series = (String, Vec<(f64, f64)>, RGBColor);

/// Colours used across the figures.
pub mod colors {
    use plotters::style::RGBColor;
    /// Black: measured data, truth.
    pub const BLACK: RGBColor = RGBColor(0, 0, 0);
    /// Blue.
    pub const BLUE: RGBColor = RGBColor(40, 100, 200);
    /// Red.
    pub const RED: RGBColor = RGBColor(200, 40, 40);
    /// Grey.
    pub const GREY: RGBColor = RGBColor(150, 150, 150);
    /// Green.
    pub const GREEN: RGBColor = RGBColor(30, 150, 60);
    /// Orange.
    pub const ORANGE: RGBColor = RGBColor(230, 140, 20);
}

/// Draw `series` as lines (with point markers when a series has at most 50 points) into an
/// SVG file. Non-finite points are skipped; with `log_y` the y values are drawn as log10.
pub fn chart(
    path: &Path,
    title: &str,
    xl: &str,
    yl: &str,
    series: &[Series],
) -> Result<(), String> {
    draw(path, title, xl, yl, series, false, false)
}

/// As [`chart`], each series as points only (a scatter of many records).
pub fn scatter(
    path: &Path,
    title: &str,
    xl: &str,
    yl: &str,
    series: &[Series],
) -> Result<(), String> {
    draw(path, title, xl, yl, series, false, true)
}

/// As [`chart`], with a log10 y axis (non-positive values skipped).
pub fn chart_log_y(
    path: &Path,
    title: &str,
    xl: &str,
    yl: &str,
    series: &[Series],
) -> Result<(), String> {
    draw(path, title, xl, yl, series, true, false)
}

fn draw(
    path: &Path,
    title: &str,
    xl: &str,
    yl: &str,
    series: &[Series],
    log_y: bool,
    points_only: bool,
) -> Result<(), String> {
    let tf = |y: f64| if log_y { y.log10() } else { y };
    let keep = |p: &(f64, f64)| p.0.is_finite() && p.1.is_finite() && (!log_y || p.1 > 0.0);
    let pts: Vec<(f64, f64)> = series
        .iter()
        .flat_map(|s| s.1.iter().copied())
        .filter(keep)
        .map(|p| (p.0, tf(p.1)))
        .collect();
    if pts.is_empty() {
        return Ok(());
    }
    let (x0, x1) = pts.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |a, p| {
        (a.0.min(p.0), a.1.max(p.0))
    });
    let (y0, y1) = pts.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |a, p| {
        (a.0.min(p.1), a.1.max(p.1))
    });
    let (dx, dy) = (
        (x1 - x0).max(1e-12) * 0.05,
        (y1 - y0).max(1e-12 * y1.abs().max(1.0)) * 0.1,
    );
    let root = SVGBackend::new(path, (640, 420)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let mut c = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 18))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(x0 - dx..x1 + dx, y0 - dy..y1 + dy)
        .map_err(|e| e.to_string())?;
    let ylabel = if log_y {
        format!("log10 {yl}")
    } else {
        yl.to_string()
    };
    c.configure_mesh()
        .x_desc(xl)
        .y_desc(ylabel)
        .draw()
        .map_err(|e| e.to_string())?;
    for (name, data, color) in series {
        let color = *color;
        let data: Vec<(f64, f64)> = data
            .iter()
            .copied()
            .filter(keep)
            .map(|p| (p.0, tf(p.1)))
            .collect();
        if points_only {
            c.draw_series(data.iter().map(|&p| Circle::new(p, 2, color.filled())))
                .map_err(|e| e.to_string())?
                .label(name.as_str())
                .legend(move |(x, y)| Circle::new((x + 7, y), 3, color.filled()));
            continue;
        }
        c.draw_series(LineSeries::new(data.clone(), color.stroke_width(2)))
            .map_err(|e| e.to_string())?
            .label(name.as_str())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 15, y)], color.stroke_width(2))
            });
        if data.len() <= 50 {
            c.draw_series(data.iter().map(|&p| Circle::new(p, 3, color.filled())))
                .map_err(|e| e.to_string())?;
        }
    }
    c.configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(|e| e.to_string())?;
    root.present().map_err(|e| e.to_string())
}

/// A map of values over a grid of cells (`mean[i][j]` over x edges `i..i+1` and y edges
/// `j..j+1`; `None` cells left blank), blue for negative through white to red for positive,
/// scaled to the largest magnitude.
pub fn cell_map(
    path: &Path,
    title: &str,
    xl: &str,
    yl: &str,
    x_edges: &[f64],
    y_edges: &[f64],
    mean: &[Vec<Option<f64>>],
) -> Result<(), String> {
    let (Some(&x0), Some(&x1), Some(&y0), Some(&y1)) = (
        x_edges.first(),
        x_edges.last(),
        y_edges.first(),
        y_edges.last(),
    ) else {
        return Ok(());
    };
    let top = mean
        .iter()
        .flatten()
        .flatten()
        .fold(0.0f64, |a, v| a.max(v.abs()))
        .max(1e-300);
    let root = SVGBackend::new(path, (640, 520)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let mut c = ChartBuilder::on(&root)
        .caption(
            format!("{title} (red +, blue −, ±{top:.3e} at full colour)"),
            ("sans-serif", 16),
        )
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(|e| e.to_string())?;
    c.configure_mesh()
        .x_desc(xl)
        .y_desc(yl)
        .disable_mesh()
        .draw()
        .map_err(|e| e.to_string())?;
    let shade = |v: f64| {
        let t = (v / top).clamp(-1.0, 1.0);
        let fade = |a: u8| (255.0 - (255.0 - a as f64) * t.abs()) as u8;
        if t >= 0.0 {
            RGBColor(fade(200), fade(40), fade(40))
        } else {
            RGBColor(fade(40), fade(100), fade(200))
        }
    };
    let cells = mean.iter().enumerate().flat_map(|(i, row)| {
        row.iter().enumerate().filter_map(move |(j, v)| {
            let v = (*v)?;
            Some(Rectangle::new(
                [(x_edges[i], y_edges[j]), (x_edges[i + 1], y_edges[j + 1])],
                shade(v).filled(),
            ))
        })
    });
    c.draw_series(cells).map_err(|e| e.to_string())?;
    root.present().map_err(|e| e.to_string())
}
