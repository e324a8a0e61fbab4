//! `hyst frf`: the modes of a periodic record's frequency response, with the input.

use std::path::PathBuf;

use clap::Args;
use hyst::ident::frf::{self, PeriodicRecord};
use hyst::io::write_csv;

use super::read_csv;
use hyst::plot::colors;

use super::{Error, channel_names, check_fs, fail};

#[derive(Args, Debug)]
pub struct FrfArgs {
    /// CSV file with a header: the input (force) and the outputs.
    #[arg(long)]
    input: PathBuf,
    /// Sampling rate of the file (Hz).
    #[arg(long)]
    fs: f64,
    /// Column of the input (force).
    #[arg(long)]
    force: String,
    /// Output columns, comma-separated; default: every column except the force, `t` and
    /// `time`.
    #[arg(long, value_delimiter = ',')]
    columns: Option<Vec<String>>,
    /// Samples per period of the (periodic) excitation.
    #[arg(long)]
    period: usize,
    /// Skip this many leading rows (the start-up transient; whole periods are used after it).
    #[arg(long, default_value_t = 0)]
    skip: usize,
    /// The band to fit, LOW:HIGH in Hz.
    #[arg(long)]
    band: super::args::Band,
    /// Modes to fit in the band together (the fit reports those inside the band).
    #[arg(long, default_value_t = 1)]
    modes: usize,
    /// Write the modes, their standard errors and the fit's misfit as JSON here.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Draw the measured and fitted response magnitudes over the band (SVG) here.
    #[arg(long)]
    svg: Option<PathBuf>,
    /// Write the outputs as they would be under a force of flat spectrum (CSV, the same
    /// column names), e.g. to compare `hyst ssi` on them with `hyst ssi` on the measured ones.
    #[arg(long)]
    write_flat: Option<PathBuf>,
}

impl FrfArgs {
    /// The files this command will write, with the flag that names each.
    pub(crate) fn output_files(&self) -> Vec<(&'static str, Option<&std::path::Path>)> {
        vec![
            ("--json", self.json.as_deref()),
            ("--svg", self.svg.as_deref()),
            ("--write-flat", self.write_flat.as_deref()),
        ]
    }
}

pub fn run(a: &FrfArgs) -> Result<(), Error> {
    use serde_json::json;
    let fs = check_fs(a.fs)?;
    let band = (a.band.low_hz, a.band.high_hz);
    if a.period < 4 {
        return Err(fail(format!(
            "--period must be at least 4 samples, got {}",
            a.period
        )));
    }
    let t = read_csv(&a.input)?;
    let names = channel_names(&t, a.columns.as_deref(), &[a.force.as_str()]);
    if names.is_empty() {
        return Err(fail(format!(
            "{}: no output column besides the force `{}`",
            a.input.display(),
            a.force
        )));
    }
    if let Some(n) = hyst::io::repeated(&names) {
        return Err(fail(format!(
            "--columns names `{n}` twice: each channel once"
        )));
    }
    if names.contains(&a.force) {
        return Err(fail(format!(
            "--columns includes the force column `{}`",
            a.force
        )));
    }
    if a.skip.saturating_add(a.period) > t.len() {
        return Err(fail(format!(
            "{}: {} rows after --skip {} hold no whole period of {} samples",
            a.input.display(),
            t.len().saturating_sub(a.skip),
            a.skip,
            a.period
        )));
    }
    let force = &t.column(&a.force)?[a.skip..];
    let outs: Vec<&[f64]> = names
        .iter()
        .map(|n| t.column(n).map(|c| &c[a.skip..]))
        .collect::<Result<_, _>>()?;
    let rec = PeriodicRecord {
        input: force,
        outputs: &outs,
        fs,
        period: a.period,
    };
    let context = |e: hyst::ident::IdentError| {
        fail(format!(
            "{}: force {}, columns {}: {e}",
            a.input.display(),
            a.force,
            names.join(",")
        ))
    };
    let fit = frf::modes_from_frf(&rec, band, a.modes).map_err(context)?;
    println!(
        "{} whole periods, {} excited lines in {}–{} Hz, {} channel(s)",
        fit.periods,
        fit.frequency_hz.len(),
        band.0,
        band.1,
        names.len()
    );
    if fit.modes.is_empty() {
        println!("no stable oscillating pole inside the band: try another band or more modes");
    }
    // The band's share of the uncertainty, which the standard errors (noise alone) do not
    // hold.
    let spread = frf::band_spread(&rec, band, a.modes, &fit);
    for (m, d) in fit.modes.iter().zip(&spread) {
        println!(
            "mode {:9.4} ± {:.4} Hz (band {:.4})  damping {:.5} ± {:.5} (band {:.5})",
            m.frequency_hz,
            m.frequency_se_hz,
            d.frequency_hz,
            m.damping_ratio,
            m.damping_se,
            d.damping
        );
    }
    if names.len() > 1 {
        for m in &fit.modes {
            println!(
                "shape at {:.4} Hz ({}): {}  MPC {:.4}",
                m.frequency_hz,
                names.join(", "),
                hyst::shape_text(&m.shape, "  "),
                hyst::covssi::mpc(&m.shape)
            );
        }
    }
    if !fit.modes.is_empty() {
        println!(
            "± one standard error (the noise); band: the largest move of the mode when the band is \
             narrowed or widened by a tenth of its width at each end"
        );
    }
    // With one period there is no noise estimate and the misfit has unit weights.
    if fit.periods >= 2 {
        println!("misfit {:.3} (1 when the fit is at the noise)", fit.misfit);
        if fit.misfit > 3.0 {
            println!(
                "note: the response departs from the fitted model by more than its noise (a \
                 nonlinear structure's periodic distortions, or modes near the band left out); \
                 the ± describe the noise alone, and the band's share is given beside them: \
                 compare fits with more modes too"
            );
        }
    } else {
        println!("one period only: no noise estimate, so no standard errors");
    }
    if let Some(path) = &a.json {
        let num = |v: f64| if v.is_finite() { json!(v) } else { json!(null) };
        let doc = json!({
            "band_hz": [band.0, band.1],
            "periods": fit.periods,
            "lines": fit.frequency_hz.len(),
            "misfit": num(fit.misfit),
            "modes": fit.modes.iter().zip(&spread).map(|(m, d)| json!({
                "frequency_hz": m.frequency_hz,
                "damping_ratio": m.damping_ratio,
                "frequency_band_spread_hz": num(d.frequency_hz),
                "damping_band_spread": num(d.damping),
                "frequency_se_hz": num(m.frequency_se_hz),
                "damping_se": num(m.damping_se),
                "shape": m.shape.iter().map(|c| json!([c.re, c.im])).collect::<Vec<_>>(),
                "shape_se": m.shape_se.iter().map(|&v| num(v)).collect::<Vec<_>>(),
                "mpc": hyst::covssi::mpc(&m.shape),
            })).collect::<Vec<_>>(),
        });
        std::fs::write(path, serde_json::to_string_pretty(&doc)?)
            .map_err(|e| fail(format!("{}: {e}", path.display())))?;
    }
    if let Some(path) = &a.svg {
        let palette = [colors::BLUE, colors::GREEN, colors::ORANGE, colors::BLACK];
        let mut series = Vec::new();
        for (c, name) in names.iter().enumerate() {
            let colour = palette[c % palette.len()];
            let pts = |v: &[hyst::ident::Complex64]| -> Vec<(f64, f64)> {
                fit.frequency_hz
                    .iter()
                    .zip(v)
                    .map(|(f, h)| (*f, h.norm()))
                    .collect()
            };
            series.push((format!("{name}, measured"), pts(&fit.response[c]), colour));
            series.push((format!("{name}, fitted"), pts(&fit.fitted[c]), colors::RED));
        }
        hyst::plot::chart_log_y(
            path,
            &format!("response to {} over the band", a.force),
            "frequency (Hz)",
            "|response / force| (log10)",
            &series,
        )
        .map_err(|e| fail(format!("{}: {e}", path.display())))?;
    }
    if let Some(path) = &a.write_flat {
        let flat = frf::outputs_under_flat_input(&rec).map_err(context)?;
        let cols: Vec<&[f64]> = flat.iter().map(|c| c.as_slice()).collect();
        let header: Vec<&str> = names.iter().map(String::as_str).collect();
        write_csv(path, &header, &cols)?;
    }
    Ok(())
}
