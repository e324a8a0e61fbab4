//! `hyst refine`: the residual loop with input and output.

use std::path::PathBuf;

use clap::{Args, ValueEnum};

use super::{Error, InterpolationArg, check_fs, fail, read_record, show, steps_bar};

#[derive(Clone, Copy, ValueEnum, PartialEq, Eq, Debug)]
pub(crate) enum StartArg {
    Linear,
    Zener,
    BoucWen,
}

#[derive(Args, Debug)]
pub(crate) struct RefineArgs {
    /// Record with input and output columns (CSV with a header, or any format `--format`
    /// names).
    #[arg(long)]
    pub(crate) data: PathBuf,
    /// Sampling rate (Hz); a Universal File states its own.
    #[arg(long)]
    pub(crate) fs: Option<f64>,
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
    #[arg(help_heading = "Output files", long)]
    pub(crate) json: Option<PathBuf>,
    /// Write figures (SVG) into this folder: residual spectra before/after, time overlays,
    /// and the restoring-force surface of the baseline's residual with its two sections.
    #[arg(help_heading = "Output files", long)]
    pub(crate) svg_dir: Option<PathBuf>,
}

pub(crate) fn run(a: &RefineArgs) -> Result<(), Error> {
    use hyst::ident::residual::{self, ModelClass, Record};
    if let Some(fs) = a.fs {
        check_fs(fs)?;
    }
    let t = read_record(&a.data)?;
    let fs = check_fs(t.rate(a.fs)?)?;
    let u = t
        .column(&a.input_column)
        .map_err(|e| fail(format!("{e} (refine needs the input too)")))?;
    let y = t.column(&a.output_column)?;
    let n = y.len();
    let (default_estimate, default_tests) = residual::default_rows(n);
    let estimate = match &a.estimate {
        Some(r) => r.within("--estimate", n)?,
        None => default_estimate,
    };
    let tests: Vec<(usize, usize)> = if a.test.is_empty() {
        default_tests
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
        StartArg::Linear => ModelClass::Linear,
        StartArg::Zener => ModelClass::Zener,
        StartArg::BoucWen => ModelClass::BoucWen,
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
    // A bar of the loop's steps on stderr (hidden when stderr is not a terminal).
    let bar = steps_bar();
    let r = residual::refine_report(&rec, a.mass, start, estimate, &tests, &|p| show(&bar, p))
        .map_err(|e| fail(format!("{}: {e}", a.data.display())));
    bar.finish_and_clear();
    let report = hyst::report::FileReport::new(a.data.display().to_string(), r?);
    print!("{}", report.report);
    if let Some(dir) = &a.svg_dir {
        hyst::figures::residual_figures(
            dir,
            &report.report.refinement,
            &rec,
            estimate,
            tests[0],
            a.mass.is_none(),
        )
        .map_err(fail)?;
    }
    if let Some(path) = &a.json {
        report.write_json(path)?;
    }
    Ok(())
}
