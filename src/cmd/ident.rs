//! `hyst ident`: the paper's output-only pipeline to linear, Zener and Bouc-Wen models.

use std::path::PathBuf;

use clap::{Args, ValueEnum};
use hyst::model::Oscillator;
use hyst::sim::excitation::Multisine;
use hyst::sim::{self, Input, SimOptions};

use super::{Error, check_fs, fail, output_after_skip, read_record, spinner};

#[derive(Clone, Copy, ValueEnum, PartialEq, Eq, Debug)]
pub(crate) enum DampingArg {
    /// From the Zener oscillator fitted to the record's spectrum (white force assumed) when
    /// the record follows the stationary model; else as `cluster`.
    Spectrum,
    /// The paper's guess: a cluster of lightly damped poles near the pair.
    Cluster,
}

#[derive(Clone, Copy, ValueEnum, PartialEq, Eq, Debug)]
pub(crate) enum LinearizationArg {
    /// Eqs. (37)-(38) of the paper (Bajrić & Høgsberg 2018) as printed.
    Paper,
    /// Alpha from the paper's eq. (37), then exact inversion of the describing function.
    Harmonic,
}

#[derive(Clone, Copy, Debug, PartialEq, ValueEnum)]
pub(crate) enum ValidationKindArg {
    /// Periodic when the input is, from rest otherwise.
    Auto,
    /// One steady-state period.
    Periodic,
    /// Simulated from rest.
    FromRest,
}

#[derive(Args, Debug)]
pub(crate) struct IdentArgs {
    /// Record with the measured output (CSV with a header, or any format `--format` names).
    /// Without it: the built-in default.
    #[arg(long)]
    pub(crate) data: Option<PathBuf>,
    /// Sampling rate of --data (Hz); a Universal File states its own.
    #[arg(long)]
    pub(crate) fs: Option<f64>,
    /// Mass of the oscillator (kg), assumed known.
    #[arg(long)]
    pub(crate) mass: Option<f64>,
    #[command(flatten)]
    pub(crate) columns: super::args::RecordColumns,
    /// Validation records (input and output columns): each identified model is simulated with
    /// the input and compared with the output, to its steady state when the record's input
    /// is periodic over it, else from rest (see --validation-kind).
    #[arg(long, num_args = 1..)]
    pub(crate) validate: Vec<PathBuf>,
    /// How the --validate records are simulated: told from each record's input by default
    /// (`hyst_ident::periodic`: a whole number of periods, or one period of a band-limited
    /// signal), or given.
    #[arg(long, value_enum, default_value = "auto")]
    pub(crate) validation_kind: ValidationKindArg,
    /// Mapping from the poles to Bouc-Wen parameters (default: whichever validates better;
    /// harmonic without validation data).
    #[arg(long, value_enum)]
    pub(crate) linearization: Option<LinearizationArg>,
    /// Where the viscous damping c of the Zener and Bouc-Wen models comes from.
    #[arg(long, value_enum, default_value = "spectrum", conflicts_with = "c")]
    pub(crate) damping: DampingArg,
    /// A known viscous damping c (N s/m), in place of --damping.
    #[arg(long)]
    pub(crate) c: Option<f64>,
    /// The band LO:HI (Hz) on which the excitation's amplitude spectrum was flat (a
    /// multisine's design; needs --period). The Bouc-Wen model is then fitted by flatness of
    /// its implied input, and kept when it validates better than the mapped one (or when
    /// there is nothing to validate on). The built-in default job uses 5:150.1.
    #[arg(long)]
    pub(crate) excitation_band: Option<super::args::Band>,
    /// Samples per period of the excitation (with --excitation-band); --data must hold whole
    /// periods of the steady state (use --skip to drop a start-up transient).
    #[arg(long)]
    pub(crate) period: Option<usize>,
    /// Also show what one record under a white force leaves free (it starts from the Zener
    /// fit to the record's spectrum): at each ratio βδ/βγ, the Bouc-Wen model that
    /// best reproduces the record's statistics (its Zener fit, amplitude curve and kurtosis;
    /// fitted by simulation), with its χ² and its validation errors: models the record cannot
    /// tell apart that predict other force levels differently (about a minute).
    #[arg(long)]
    pub(crate) profile: bool,
    /// Write the results as JSON here.
    #[arg(help_heading = "Output files", long)]
    pub(crate) json: Option<PathBuf>,
    /// Write figures (SVG) into this folder.
    #[arg(help_heading = "Output files", long)]
    pub(crate) svg_dir: Option<PathBuf>,
}

/// The built-in default record: the benchmark system driven by its 50 N multisine over five
/// periods from rest (the first dropped), with white measurement noise of 7.4e-6 m (the level
/// measured between the periods of the benchmark's own training record); and a validation
/// period of a fresh realization.
/// The default job's records: training output, validation input and output.
pub(crate) struct DefaultRecords {
    pub(crate) y: Vec<f64>,
    pub(crate) val_u: Vec<f64>,
    pub(crate) val_y: Vec<f64>,
}

pub(crate) fn default_records() -> Result<DefaultRecords, Error> {
    let ms = Multisine::benchmark(50.0);
    let train_u = ms.generate(11)?;
    let model = Oscillator::benchmark();
    let opts = SimOptions::default();
    let n = train_u.len();
    let mut y = sim::simulate(&model, Input::Periodic(&train_u), 750.0, 5 * n, &opts)?;
    let mut y = y.split_off(n);
    sim::excitation::add_noise(&mut y, 7.4e-6, 12)?;
    let val_u = ms.generate(13)?;
    let val_y = sim::steady_state_period(&model, &val_u, 750.0, &opts, 1e-10, 50)?.y;
    Ok(DefaultRecords { y, val_u, val_y })
}

/// The excitation's design from --excitation-band/--period; the built-in job's when neither
/// --data nor a band is given.
pub(crate) fn excitation_band(
    a: &IdentArgs,
) -> Result<Option<hyst::ident::flatness::ExcitationBand>, Error> {
    use hyst::ident::flatness::ExcitationBand;
    match (&a.excitation_band, a.period) {
        (None, None) if a.data.is_none() => Ok(Some(ExcitationBand::benchmark())),
        (None, None) => Ok(None),
        (None, Some(_)) => Err(fail("--period needs --excitation-band LO:HI")),
        (Some(_), None) => Err(fail(
            "--excitation-band needs --period (samples per period of the excitation)",
        )),
        (Some(b), Some(period)) => {
            let band = ExcitationBand {
                low_hz: b.low_hz,
                high_hz: b.high_hz,
                period,
            };
            // Options that can never give a flatness fit are refused before the record is
            // read when the rate is given (the pipeline checks again with the file's rate).
            if let Some(fs) = a.fs.filter(|f| f.is_finite() && *f > 0.0) {
                band.check(fs)
                    .map_err(|e| fail(format!("--excitation-band {b} --period {period}: {e}")))?;
            }
            Ok(Some(band))
        }
    }
}

/// The record to identify: `--data` after `--skip`, else the built-in default (whose fresh
/// validation period joins the records); its name; its rate.
fn record(
    a: &IdentArgs,
    validations: &mut Vec<hyst::ident::ValidationRecord>,
) -> Result<(Vec<f64>, f64, String), Error> {
    match &a.data {
        Some(path) => {
            if a.mass.is_none() {
                return Err(fail(
                    "--mass is required with --data: the mapping from poles to stiffness needs the mass",
                ));
            }
            if let Some(fs) = a.fs {
                check_fs(fs)?;
            }
            let (y, fs) = output_after_skip(path, &a.columns.output_column, a.columns.skip, a.fs)?;
            Ok((y, fs, path.display().to_string()))
        }
        None => {
            let d = default_records()?;
            validations.push(hyst::ident::ValidationRecord {
                name: "built-in: benchmark, fresh 50 N multisine".into(),
                u: d.val_u,
                y: d.val_y,
                periodic: true,
            });
            Ok((
                d.y,
                750.0,
                "built-in: benchmark, 50 N multisine, 4 periods, noise 7.4e-6 m".to_string(),
            ))
        }
    }
}

/// The `--validate` records, each simulated as `--validation-kind` says.
fn validation_records(a: &IdentArgs) -> Result<Vec<hyst::ident::ValidationRecord>, Error> {
    let mut out = Vec::new();
    for v in &a.validate {
        let t = read_record(v)?;
        let mut record = hyst::ident::ValidationRecord::new(
            v.display().to_string(),
            t.column(&a.columns.input_column)?.to_vec(),
            t.column(&a.columns.output_column)?.to_vec(),
        );
        match a.validation_kind {
            ValidationKindArg::Periodic => record.periodic = true,
            ValidationKindArg::FromRest => record.periodic = false,
            ValidationKindArg::Auto => {}
        }
        out.push(record);
    }
    Ok(out)
}

/// The pipeline's options from the flags.
fn options(a: &IdentArgs) -> Result<hyst::ident::IdentOptions, Error> {
    use hyst::ident::{DampingGuess, IdentOptions};
    let damping_guess = match (a.c, a.damping) {
        (Some(c), _) if c.is_finite() && c >= 0.0 => DampingGuess::Value(c),
        (Some(c), _) => return Err(fail(format!("--c must be a number >= 0 N s/m, got {c}"))),
        (None, DampingArg::Spectrum) => DampingGuess::ZenerSpectrum,
        (None, DampingArg::Cluster) => DampingGuess::LowDampingCluster,
    };
    Ok(IdentOptions {
        mass: a.mass.unwrap_or(2.0),
        excitation: excitation_band(a)?,
        damping_guess,
        profile: a.profile,
        ..IdentOptions::default()
    })
}

/// When no supported pair was found, the stabilization diagram that shows why, saved where
/// the figures go (or here); the error names it.
fn no_pair_error(
    a: &IdentArgs,
    e: hyst::ident::IdentError,
    y: &[f64],
    fs: f64,
    opts: &hyst::ident::IdentOptions,
    source: &str,
) -> Error {
    use hyst::ident::{self, IdentError};
    if !matches!(
        e,
        IdentError::NoStablePair { .. } | IdentError::PairNotSupported { .. }
    ) {
        return fail(format!("{source}: {e}"));
    }
    let path = a
        .svg_dir
        .clone()
        .unwrap_or_else(|| PathBuf::from("."))
        .join("stabilization.svg");
    let saved = ident::prepare(y, fs, opts)
        .and_then(|p| ident::run_ssi(&p, opts).map(|r| (p, r)))
        .ok()
        .and_then(|(p, r)| {
            let svg = hyst::covssi::svg::stabilization_svg(
                &r.diagram,
                Some(4.0 * p.dominant_hz),
                "Stabilization diagram (no supported stable pair)",
            );
            std::fs::create_dir_all(path.parent()?).ok()?;
            std::fs::write(&path, svg).ok()
        });
    fail(match saved {
        Some(()) => format!("{source}: {e}; diagram saved to {}", path.display()),
        None => format!("{source}: {e}"),
    })
}

pub(crate) fn run(a: &IdentArgs) -> Result<(), Error> {
    use hyst::ident::{self, Linearization};
    let mut validations = Vec::new();
    let (y, fs, source) = record(a, &mut validations)?;
    validations.extend(validation_records(a)?);
    let opts = options(a)?;
    let mapping = a.linearization.map(|l| match l {
        LinearizationArg::Paper => Linearization::Paper,
        LinearizationArg::Harmonic => Linearization::Harmonic,
    });
    let bar = spinner();
    bar.set_message("identifying");
    let report = ident::identify_and_validate(&y, fs, &opts, mapping, &validations);
    bar.finish_and_clear();
    let report = report.map_err(|e| no_pair_error(a, e, &y, fs, &opts, &source))?;
    let report = hyst::report::FileReport::new(source, report);
    print!("{report}");
    if let Some(path) = &a.json {
        report.write_json(path)?;
    }
    if let Some(dir) = &a.svg_dir {
        hyst::figures::ident_figures(dir, &report.report, &y, fs, &validations).map_err(fail)?;
    }
    Ok(())
}
