//! `hyst ident`: the paper's output-only pipeline to linear, Zener and Bouc-Wen models.

use std::path::PathBuf;

use clap::{Args, ValueEnum};
use hyst::model::Oscillator;
use hyst::sim::excitation::Multisine;
use hyst::sim::{self, Input, SimOptions};

use super::*;

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
    /// Eqs. (37)-(38) as printed.
    Paper,
    /// Alpha from eq. (37), then exact inversion of the describing function.
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
    /// Record with the measured output (CSV with a header). Without it: the built-in default.
    #[arg(long)]
    pub(crate) data: Option<PathBuf>,
    /// Sampling rate of --data (Hz).
    #[arg(long)]
    pub(crate) fs: Option<f64>,
    /// Mass of the oscillator (kg), assumed known.
    #[arg(long)]
    pub(crate) mass: Option<f64>,
    /// Column of the output (displacement).
    #[arg(long, default_value = "y")]
    pub(crate) output_column: String,
    /// Column of the input force (only used by --validate files).
    #[arg(long, default_value = "u")]
    pub(crate) input_column: String,
    /// Skip this many leading rows of --data (e.g. a start-up transient).
    #[arg(long, default_value_t = 0)]
    pub(crate) skip: usize,
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
    /// Write the results as JSON here.
    #[arg(long)]
    pub(crate) json: Option<PathBuf>,
    /// Write figures (SVG) into this folder.
    #[arg(long)]
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

/// The amplitude spectrum of the force each Bouc-Wen candidate implies, over the
/// excitation's band (dB re 1 N): the flatness fit is flat where the mapped models are not.
pub(crate) fn implied_input_figure(
    dir: &std::path::Path,
    candidates: &[(String, Oscillator)],
    y: &[f64],
    fs: f64,
    band: &hyst::ident::flatness::ExcitationBand,
) -> Result<(), Error> {
    use hyst::plot::{chart, colors};
    let palette = [colors::RED, colors::BLUE, colors::GREEN, colors::BLACK];
    // Drawn in reverse so that the first candidate (the flatness fit) lies on top.
    let series: Vec<_> = candidates
        .iter()
        .enumerate()
        .rev()
        .filter_map(|(i, (name, m))| {
            let col = &palette[i % palette.len()];
            let spec = hyst::ident::flatness::implied_spectrum(m, y, fs, band).ok()?;
            let db = spec
                .iter()
                .map(|&(f, a)| (f, 20.0 * a.max(1e-300).log10()))
                .collect();
            Some((name.clone(), db, *col))
        })
        .collect();
    chart(
        &dir.join("implied_input_spectrum.svg"),
        "Implied input over the excitation band (output only)",
        "f (Hz)",
        "|Û| per line (dB re 1 N)",
        &series,
    )?;
    Ok(())
}

/// The record's PSD (Welch, 4096-sample segments) beside the Zener spectral fit's, over the
/// fitted band, with the fit's noise floor.
pub(crate) fn zener_spectrum_figure(
    path: &std::path::Path,
    y: &[f64],
    fs: f64,
    fit: &hyst::ident::zener_spectrum::ZenerSpectralFit,
) -> Result<(), Error> {
    use hyst::plot::{chart_log_y, colors};
    let mean = y.iter().sum::<f64>() / y.len() as f64;
    let centred: Vec<f64> = y.iter().map(|v| v - mean).collect();
    let (f, s) = hyst::ident::welch_psd(&centred, fs, 4096);
    let (f, s): (Vec<f64>, Vec<f64>) = f
        .into_iter()
        .zip(s)
        .skip(1)
        .take_while(|(f, _)| *f <= fit.max_frequency_hz)
        .unzip();
    let model = fit.psd(&f);
    let floor = 2.0 * fit.noise_std * fit.noise_std / fs;
    chart_log_y(
        path,
        &format!(
            "Zener spectral fit: c = {:.2} ± {:.2}, k = {:.0}, k∞ = {:.0}, Ω = {:.1}",
            fit.c, fit.se[0], fit.k, fit.k_inf, fit.omega
        ),
        "f (Hz)",
        "PSD (units²/Hz)",
        &[
            (
                "record (Welch)".into(),
                f.iter().copied().zip(s).collect(),
                colors::BLACK,
            ),
            (
                "fitted Zener + noise".into(),
                f.iter().copied().zip(model).collect(),
                colors::BLUE,
            ),
            (
                "fitted noise floor".into(),
                f.iter().map(|&f| (f, floor)).collect(),
                colors::GREY,
            ),
        ],
    )?;
    Ok(())
}

/// Every figure of `hyst ident --svg-dir`: the stabilization diagram, figures like the
/// paper's 3(a) and 5, the Zener spectral fit, and the implied input of each Bouc-Wen
/// candidate when the excitation's band is known.
pub(crate) fn ident_figures(
    dir: &std::path::Path,
    r: &hyst::ident::IdentReport,
    y: &[f64],
    fs: f64,
    validations: &[hyst::ident::ValidationRecord],
) -> Result<(), Error> {
    let id = &r.identification;
    std::fs::create_dir_all(dir).map_err(|e| fail(format!("{}: {e}", dir.display())))?;
    let p = dir.join("stabilization.svg");
    let svg = hyst::covssi::svg::stabilization_svg(
        &id.ssi.diagram,
        Some(4.0 * id.prepared.dominant_hz),
        "Stabilization diagram (output only)",
    );
    std::fs::write(&p, svg).map_err(|e| fail(format!("{}: {e}", p.display())))?;
    paper_figures(dir, id, r.bouc_wen.as_ref(), validations)?;
    if let Some(f) = &id.zener_spectrum {
        zener_spectrum_figure(&dir.join("zener_spectrum.svg"), y, fs, f)?;
    }
    if let Some(band) = r.options.excitation.filter(|_| id.flatness.is_some()) {
        let candidates: Vec<(String, Oscillator)> = r
            .candidates
            .iter()
            .map(|c| (c.route.name().to_string(), c.model))
            .collect();
        implied_input_figure(dir, &candidates, y, fs, &band)?;
    }
    Ok(())
}

/// Figures like the paper's 3(a) (the correlation function) and 5 (time and PSD overlays of
/// the identified models on the first validation record).
fn paper_figures(
    dir: &std::path::Path,
    id: &hyst::ident::Identification,
    bouc_wen: Option<&Oscillator>,
    validations: &[hyst::ident::ValidationRecord],
) -> Result<(), Error> {
    use hyst::plot::{chart, chart_log_y, colors};
    let p = &id.prepared;
    let lags = ((20.0 * p.fs / p.dominant_hz).ceil() as usize)
        .min(p.y.len() / 2)
        .max(2);
    let r = hyst::covssi::corr::estimate(&[&p.y], &[0], lags);
    let corr: Vec<(f64, f64)> =
        r.r.iter()
            .enumerate()
            .map(|(k, v)| (k as f64 / p.fs, v[0]))
            .collect();
    chart(
        &dir.join("fig3a_correlation.svg"),
        "Fig. 3(a): unbiased autocorrelation of the output",
        "lag (s)",
        "R(τ) (m²)",
        &[("R̂xx".into(), corr, colors::BLACK)],
    )?;
    let Some(hyst::ident::ValidationRecord {
        name,
        u,
        y,
        periodic,
        ..
    }) = validations.first()
    else {
        return Ok(());
    };
    let fs = p.fs * p.decimation as f64;
    let mut models: Vec<(&str, &hyst::model::Oscillator, plotters::style::RGBColor)> =
        vec![("linear", &id.models.linear, colors::BLUE)];
    if let Some(z) = &id.models.zener {
        models.push(("Zener", z, colors::GREEN));
    }
    if let Some(b) = bouc_wen {
        models.push(("Bouc-Wen", b, colors::RED));
    }
    let n_time = ((0.5 * fs) as usize).min(y.len());
    let t = |v: &[f64]| -> Vec<(f64, f64)> {
        v.iter()
            .take(n_time)
            .enumerate()
            .map(|(k, x)| (k as f64 / fs, *x))
            .collect()
    };
    let psd = |v: &[f64]| -> Vec<(f64, f64)> {
        let (f, s) = hyst::ident::welch_psd(v, fs, 512);
        f.into_iter().zip(s).collect()
    };
    let mut time = vec![("measured".to_string(), t(y), colors::BLACK)];
    let mut spec = vec![("measured".to_string(), psd(y), colors::BLACK)];
    for (label, m, c) in models {
        if let Ok(yhat) = hyst::ident::simulate_model(m, u, fs, *periodic) {
            time.push((label.to_string(), t(&yhat), c));
            spec.push((label.to_string(), psd(&yhat), c));
        }
    }
    chart(
        &dir.join("fig5a_time.svg"),
        &format!("Fig. 5(a): response, {name}"),
        "t (s)",
        "x (m)",
        &time,
    )?;
    chart_log_y(
        &dir.join("fig5b_psd.svg"),
        &format!("Fig. 5(b): PSD, {name}"),
        "f (Hz)",
        "PSD (m²/Hz)",
        &spec,
    )?;
    Ok(())
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
            let (lo, hi) = (b.low_hz, b.high_hz);
            // Options that can never give a flatness fit are refused before the pipeline
            // runs, not reported in a note after it.
            if period < 2 {
                return Err(fail(format!(
                    "--period must be at least 2 samples, got {period}"
                )));
            }
            if let Some(fs) = a.fs.filter(|f| f.is_finite() && *f > 0.0)
                && hi > fs / 2.0
            {
                return Err(fail(format!(
                    "--excitation-band {b}: {hi} Hz is above the Nyquist frequency {} Hz of --fs {fs}",
                    fs / 2.0
                )));
            }
            Ok(Some(ExcitationBand {
                low_hz: lo,
                high_hz: hi,
                period,
            }))
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
            let fs = check_fs(a.fs.ok_or_else(|| fail("--fs is required with --data"))?)?;
            if a.mass.is_none() {
                return Err(fail(
                    "--mass is required with --data: the mapping from poles to stiffness needs the mass",
                ));
            }
            let y = output_after_skip(path, &a.output_column, a.skip)?;
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
        let t = read_csv(v)?;
        let mut record = hyst::ident::ValidationRecord::new(
            v.display().to_string(),
            t.column(&a.input_column)?.to_vec(),
            t.column(&a.output_column)?.to_vec(),
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
        ident_figures(dir, &report.report, &y, fs, &validations)?;
    }
    Ok(())
}
