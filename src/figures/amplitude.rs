//! The figure of `hyst amplitude --svg`: each mode's frequency and damping ratio against its
//! amplitude, ± one standard error.

use plotters::prelude::*;

use crate::ident::amplitude::{AmplitudePoint, AmplitudeReport, ModeCurve};
use crate::plot::colors;

/// One row per mode: its natural frequency (left) and damping ratio (right) against its
/// amplitude, each point with a bar of ± one standard error, one colour per record (the
/// records following the same modes in the same order); the SVG as a string.
pub fn amplitude_svg(records: &[(String, &AmplitudeReport)], title: &str) -> String {
    let rows = records.first().map_or(1, |r| r.1.modes.len().max(1));
    let mut svg = String::new();
    {
        let root =
            SVGBackend::with_string(&mut svg, (900, 60 + 300 * rows as u32)).into_drawing_area();
        if draw(&root, records, title).is_err() {
            // A failed drawing leaves what was drawn; there is nothing to recover here.
        }
        let _ = root.present();
    }
    svg
}

type Area<'a> = DrawingArea<SVGBackend<'a>, plotters::coord::Shift>;

const PALETTE: [RGBColor; 6] = [
    colors::BLUE,
    colors::RED,
    colors::GREEN,
    colors::ORANGE,
    colors::BLACK,
    colors::GREY,
];

/// How the records of a model drawn beside the measured ones are named: the measured
/// record's name and this.
pub const MODEL_SUFFIX: &str = " (model)";

type Value = dyn Fn(&AmplitudePoint) -> (f64, f64);

/// A point with its bar: (amplitude, value, standard error).
type Bar = (f64, f64, f64);

fn draw(
    root: &Area<'_>,
    records: &[(String, &AmplitudeReport)],
    title: &str,
) -> Result<(), String> {
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let root = root
        .titled(title, ("sans-serif", 20))
        .map_err(|e| e.to_string())?;
    let Some(first) = records.first() else {
        return Ok(());
    };
    let rows = root.split_evenly((first.1.modes.len().max(1), 2));
    let unit = format!("amplitude ({})", first.1.amplitude_of.name());
    let f: &Value = &|p| (p.frequency_hz, p.frequency_se_hz);
    let z: &Value = &|p| (100.0 * p.damping_ratio, 100.0 * p.damping_se);
    for (j, c) in first.1.modes.iter().enumerate() {
        let curves: Vec<(&str, Option<&ModeCurve>)> = records
            .iter()
            .map(|(n, r)| (n.as_str(), r.modes.get(j)))
            .collect();
        let hz = c.mode.frequency_hz;
        panel(
            &rows[2 * j],
            &curves,
            &unit,
            &format!("{hz:.3} Hz: frequency (Hz)"),
            f,
        )?;
        panel(
            &rows[2 * j + 1],
            &curves,
            &unit,
            &format!("{hz:.3} Hz: damping ratio (%)"),
            z,
        )?;
    }
    Ok(())
}

fn panel(
    area: &Area<'_>,
    curves: &[(&str, Option<&ModeCurve>)],
    xl: &str,
    yl: &str,
    value: &Value,
) -> Result<(), String> {
    let series: Vec<(&str, Vec<Bar>)> = curves
        .iter()
        .map(|(name, c)| {
            let pts = c
                .map(|c| {
                    c.points
                        .iter()
                        .map(|p| {
                            let (v, se) = value(p);
                            (p.amplitude, v, se)
                        })
                        .filter(|p| p.0.is_finite() && p.1.is_finite() && p.2.is_finite())
                        .collect()
                })
                .unwrap_or_default();
            (*name, pts)
        })
        .collect();
    let all: Vec<&Bar> = series.iter().flat_map(|s| s.1.iter()).collect();
    if all.is_empty() {
        return Ok(());
    }
    let (x0, x1) = all.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |a, p| {
        (a.0.min(p.0), a.1.max(p.0))
    });
    let (y0, y1) = all.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |a, p| {
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
    // A model's records (named "… (model)", after the measured ones) are drawn as lines
    // through hollow points, in the colour of the measured record they stand beside.
    let measured = series
        .iter()
        .filter(|(n, _)| !n.ends_with(MODEL_SUFFIX))
        .count();
    for (k, (name, pts)) in series.iter().enumerate() {
        let model = name.ends_with(MODEL_SUFFIX);
        let color = PALETTE[if model { k - measured } else { k } % PALETTE.len()];
        let label: String = name.rsplit('/').next().unwrap_or(name).to_string();
        if model {
            let mut line: Vec<(f64, f64)> = pts.iter().map(|&(x, y, _)| (x, y)).collect();
            line.sort_by(|a, b| a.0.total_cmp(&b.0));
            chart
                .draw_series(pts.iter().map(|&(x, y, _)| Circle::new((x, y), 3, color)))
                .map_err(|e| e.to_string())?;
            chart
                .draw_series(LineSeries::new(line, color.stroke_width(2)))
                .map_err(|e| e.to_string())?
                .label(label)
                .legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 14, y)], color.stroke_width(2))
                });
            continue;
        }
        chart
            .draw_series(
                pts.iter().map(|&(x, y, se)| {
                    ErrorBar::new_vertical(x, y - se, y, y + se, color.filled(), 8)
                }),
            )
            .map_err(|e| e.to_string())?;
        let drawn = chart
            .draw_series(
                pts.iter()
                    .map(|&(x, y, _)| Circle::new((x, y), 3, color.filled())),
            )
            .map_err(|e| e.to_string())?;
        if series.len() > 1 {
            drawn
                .label(label)
                .legend(move |(x, y)| Circle::new((x + 7, y), 3, color.filled()));
        }
    }
    if series.len() > 1 {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(|e| e.to_string())?;
    }
    Ok(())
}
