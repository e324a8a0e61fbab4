//! SVG drawing of a [`StabilizationDiagram`]: poles over model order, marked by label, with
//! the output spectrum's first singular value (log scale, right axis) drawn behind.

use plotters::prelude::*;

use crate::{PoleStatus, Stability, StabilizationDiagram};

/// A legend entry: its name, colour, and which poles it marks.
type Kind = (&'static str, RGBColor, fn(&PoleStatus) -> bool);

/// Render the diagram as an SVG document. `max_frequency_hz` limits the frequency axis
/// (default: fs/2).
pub fn stabilization_svg(
    d: &StabilizationDiagram,
    max_frequency_hz: Option<f64>,
    title: &str,
) -> String {
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, (900, 560)).into_drawing_area();
        // Drawing into a string cannot fail for I/O reasons; errors would be plotters bugs.
        let _ = draw(&root, d, max_frequency_hz, title);
        let _ = root.present();
    }
    out
}

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    d: &StabilizationDiagram,
    max_frequency_hz: Option<f64>,
    title: &str,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let fmax = max_frequency_hz.unwrap_or(d.fs / 2.0);
    let omax = d.orders.last().map_or(1, |o| o.order) as f64 + 1.0;
    let mut chart = ChartBuilder::on(root)
        .caption(title, ("sans-serif", 20))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d(0.0..fmax, 0.0..omax)?;
    chart
        .configure_mesh()
        .x_desc("frequency (Hz)")
        .y_desc("model order")
        .light_line_style(WHITE)
        .draw()?;
    // Spectrum behind, log scale mapped onto the order axis.
    let sp = &d.spectrum;
    let logs: Vec<(f64, f64)> = sp
        .frequencies_hz
        .iter()
        .zip(&sp.first_singular_value)
        .filter(|(f, v)| **f <= fmax && **v > 0.0)
        .map(|(f, v)| (*f, v.log10()))
        .collect();
    if let (Some(lo), Some(hi)) = (
        logs.iter().map(|p| p.1).min_by(f64::total_cmp),
        logs.iter().map(|p| p.1).max_by(f64::total_cmp),
    ) {
        let span = (hi - lo).max(1e-12);
        chart.draw_series(LineSeries::new(
            logs.iter()
                .map(|(f, v)| (*f, (v - lo) / span * (omax - 1.0) + 0.5)),
            RGBColor(170, 170, 170).stroke_width(2),
        ))?;
    }
    let kinds: [Kind; 5] = [
        ("rejected", RGBColor(210, 210, 210), |s| {
            matches!(s, PoleStatus::Rejected(_))
        }),
        ("stable in frequency", RGBColor(230, 160, 30), |s| {
            matches!(s, PoleStatus::Stable(Stability::Frequency))
        }),
        (
            "stable in frequency and damping",
            RGBColor(40, 120, 220),
            |s| matches!(s, PoleStatus::Stable(Stability::FrequencyDamping)),
        ),
        ("also stable in shape (MAC)", RGBColor(20, 160, 60), |s| {
            matches!(s, PoleStatus::Stable(Stability::FrequencyDampingShape))
        }),
        ("stable real pole", RGBColor(200, 30, 30), |s| {
            matches!(s, PoleStatus::Stable(Stability::Real))
        }),
    ];
    for (name, color, pred) in kinds {
        let pts: Vec<(f64, f64)> = d
            .orders
            .iter()
            .flat_map(|o| {
                o.poles
                    .iter()
                    .filter(move |p| pred(&p.status) && p.frequency_hz <= fmax)
                    .map(move |p| (p.frequency_hz, o.order as f64))
            })
            .collect();
        chart
            .draw_series(
                pts.iter()
                    .map(|&(x, y)| Cross::new((x, y), 4, color.stroke_width(2))),
            )?
            .label(name)
            .legend(move |(x, y)| Cross::new((x, y), 4, color.stroke_width(2)));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}
