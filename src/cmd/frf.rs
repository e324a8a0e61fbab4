//! `hyst frf`: the modes of a periodic record's frequency response, with the input.

use std::path::PathBuf;

use clap::Args;
use hyst::ident::frf::{self, PeriodicRecord};
use hyst::io::write_csv;

use super::read_record;
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
    #[arg(help_heading = "Output files", long)]
    json: Option<PathBuf>,
    /// Draw the measured and fitted response magnitudes over the band (SVG) here.
    #[arg(help_heading = "Output files", long)]
    svg: Option<PathBuf>,
    /// Write the outputs as they would be under a force of flat spectrum (CSV, the same
    /// column names), e.g. to compare `hyst ssi` on them with `hyst ssi` on the measured ones.
    #[arg(help_heading = "Output files", long)]
    write_flat: Option<PathBuf>,
}

impl FrfArgs {
    /// The record this command reads.
    pub(crate) fn input_file(&self) -> &std::path::Path {
        &self.input
    }

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
    let fs = check_fs(a.fs)?;
    let band = (a.band.low_hz, a.band.high_hz);
    if a.period < 4 {
        return Err(fail(format!(
            "--period must be at least 4 samples, got {}",
            a.period
        )));
    }
    let t = read_record(&a.input)?;
    let names = channel_names(&t, a.columns.as_deref(), &[a.force.as_str()])?;
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
    let report = frf::frf_report(&rec, &names, band, a.modes).map_err(context)?;
    print!("{report}");
    if let Some(path) = &a.json {
        hyst::report::write_json(&report, path)?;
    }
    let fit = &report.fit;
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
