//! `hyst simulate` and `hyst excite`: records made by the simulator.

use std::path::PathBuf;

use clap::{Args, ValueEnum};
use hyst::io::write_csv;
use hyst::model::Oscillator;
use hyst::sim::{self, Decimation, Integrator, SimOptions};

use super::{Error, InterpolationArg, check_fs, fail, read_record};

/// `--oversample`'s and `--noise-seed`'s defaults (`--structure` refuses either changed).
const OVERSAMPLE: usize = 20;
const NOISE_SEED: u64 = 2;

#[derive(Clone, Copy, ValueEnum, PartialEq, Eq, Debug)]
pub(crate) enum IntegratorArg {
    /// Classic fourth-order Runge-Kutta.
    Rk4,
    /// The benchmark's Newmark (a = 1/2, b = 1/4), i.e. the implicit trapezoidal rule.
    Newmark,
}

#[derive(Clone, Copy, ValueEnum, PartialEq, Eq, Debug)]
pub(crate) enum DecimationArg {
    /// Keep the state at each sample instant.
    Sample,
    /// MATLAB's decimate(.., 'fir') in stages (the prime factors of --oversample, ascending).
    Fir,
}

#[derive(Clone, Copy, ValueEnum, PartialEq, Eq, Debug)]
pub(crate) enum ExcitationKind {
    /// Random-phase multisine, flat on [--f-min, --f-max], periodic with --samples samples.
    Multisine,
    /// Gaussian white noise at --fs. `simulate` interpolates it linearly between samples,
    /// which colours the force (its spectrum falls as sinc^4(pi f/fs), 1.6 % down at fs/20);
    /// with --periodic it is interpolated exactly and stays white up to fs/2.
    White,
    /// Linear sine sweep from --f-min to --f-max over the record (amplitude: sqrt(2)·rms).
    Sweep,
}

#[derive(Clone, Copy, ValueEnum, PartialEq, Eq, Debug)]
pub(crate) enum SystemArg {
    /// The Bouc-Wen benchmark: m = 2, c = 10, k = 5e4, alpha = 5e4, beta*gamma = 800, beta*delta = -1100, nu = 1.
    Benchmark,
}

#[derive(Args, Debug)]
pub(crate) struct ExcitationArgs {
    /// Kind of excitation to generate.
    #[arg(long, value_enum, default_value = "multisine")]
    pub(crate) excitation: ExcitationKind,
    #[command(flatten)]
    pub(crate) signal: SignalArgs,
    /// Sampling rate (Hz).
    #[arg(long, default_value_t = 750.0)]
    pub(crate) fs: f64,
    /// Output CSV file.
    #[arg(help_heading = "Output files", long)]
    pub(crate) out: PathBuf,
}

/// The parameters of a generated excitation, shared by `simulate` and `excite`.
#[derive(Args, Debug)]
pub(crate) struct SignalArgs {
    /// RMS of the generated excitation (N).
    #[arg(long, default_value_t = hyst::sim::excitation::ExcitationDesign::default().rms)]
    pub(crate) rms: f64,
    /// Samples of the generated excitation (a multisine: one period).
    #[arg(long, default_value_t = hyst::sim::excitation::ExcitationDesign::default().samples)]
    pub(crate) samples: usize,
    /// Seed of the random generator.
    #[arg(long, default_value_t = hyst::sim::excitation::ExcitationDesign::default().seed)]
    pub(crate) seed: u64,
    /// Lowest excited frequency (Hz).
    #[arg(long, default_value_t = hyst::sim::excitation::ExcitationDesign::default().f_min)]
    pub(crate) f_min: f64,
    /// Highest excited frequency (Hz).
    #[arg(long, default_value_t = hyst::sim::excitation::ExcitationDesign::default().f_max)]
    pub(crate) f_max: f64,
}

#[derive(Args, Debug)]
pub(crate) struct SimulateArgs {
    /// Input CSV file (with a header line). Without it, an excitation is generated.
    #[arg(long)]
    pub(crate) input: Option<PathBuf>,
    /// Sampling rate of the input (Hz); required with --input, default 750 for generated input.
    #[arg(long)]
    pub(crate) fs: Option<f64>,
    /// Column of the input file holding the force.
    #[arg(long, default_value = "u")]
    pub(crate) column: String,
    /// The input is one period of a periodic signal: simulate to steady state and write one
    /// steady-state period (the input is interpolated exactly between samples).
    #[arg(long)]
    pub(crate) periodic: bool,
    /// How a non-periodic input is known between samples. Default: band-limited for an
    /// --input file (a measured force, as `hyst ident --validate` and `hyst refine` take it),
    /// linear for a generated excitation (how the project's synthetic records are made).
    #[arg(long, value_enum)]
    pub(crate) input_interpolation: Option<InterpolationArg>,
    /// Integration sub-steps per sample.
    #[arg(long, default_value_t = OVERSAMPLE)]
    pub(crate) oversample: usize,
    /// Time integrator.
    #[arg(long, value_enum, default_value = "rk4")]
    pub(crate) integrator: IntegratorArg,
    /// How the fine-step output returns to the sampling rate.
    #[arg(long, value_enum, default_value = "sample")]
    pub(crate) decimation: DecimationArg,
    /// Built-in system to simulate (ignored with --params).
    #[arg(long, value_enum, default_value = "benchmark")]
    pub(crate) system: SystemArg,
    /// Oscillator parameters as JSON, in the schema every report writes (`hyst_model::schema`),
    /// instead of --system. `FILE#/POINTER` takes the model at a JSON pointer inside a report,
    /// e.g. `ident.json#/bouc_wen` or `refine.json#/model`.
    #[arg(long)]
    pub(crate) params: Option<PathBuf>,
    /// Generated excitation kind, when there is no --input.
    #[arg(long, value_enum)]
    pub(crate) excitation: Option<ExcitationKind>,
    #[command(flatten)]
    pub(crate) signal: SignalArgs,
    /// Standard deviation of white measurement noise added to y (m).
    #[arg(long, default_value_t = 0.0)]
    pub(crate) noise: f64,
    /// Seed of the measurement noise.
    #[arg(long, default_value_t = NOISE_SEED)]
    pub(crate) noise_seed: u64,
    /// A fitted structure to simulate instead of an oscillator: a storey fit as `hyst levels
    /// --masses --json` writes it (`FILE#/POINTER` for one inside a larger report). It is
    /// driven by --input's --forces columns (one per loaded floor) from rest, and writes its
    /// channels.
    #[arg(long, help_heading = "A structure of several floors")]
    pub(crate) structure: Option<PathBuf>,
    /// With --structure: the --input columns holding each loaded floor's force (N), in the
    /// fit's order of loaded floors.
    #[arg(
        long,
        value_delimiter = ',',
        help_heading = "A structure of several floors"
    )]
    pub(crate) forces: Vec<String>,
    /// With --structure: a record measured under that force, to compare the simulated
    /// channels with (each channel's RMS error beside its deviation).
    #[arg(long, help_heading = "A structure of several floors")]
    pub(crate) measured: Option<PathBuf>,
    /// With --measured: its channel columns, in the fit's order (default: every column but
    /// the time column and the --forces).
    #[arg(
        long,
        value_delimiter = ',',
        help_heading = "A structure of several floors"
    )]
    pub(crate) channels: Option<Vec<String>>,
    /// With --measured: samples at the start left out of the error (the model starts from
    /// rest, the structure did not).
    #[arg(
        long,
        default_value_t = 0,
        help_heading = "A structure of several floors"
    )]
    pub(crate) compare_skip: usize,
    /// Output CSV file (`u,y`; with --structure the forces and one column per channel).
    #[arg(help_heading = "Output files", long)]
    pub(crate) out: PathBuf,
}

/// The excitation the flags describe, generated by the library at `fs` Hz.
pub(crate) fn generate(kind: ExcitationKind, a: &SignalArgs, fs: f64) -> Result<Vec<f64>, Error> {
    use hyst::sim::excitation::{ExcitationDesign, ExcitationKind as Kind};
    let mut design = ExcitationDesign::default();
    design.kind = match kind {
        ExcitationKind::Multisine => Kind::Multisine,
        ExcitationKind::White => Kind::White,
        ExcitationKind::Sweep => Kind::Sweep,
    };
    design.rms = a.rms;
    design.samples = a.samples;
    design.seed = a.seed;
    design.f_min = a.f_min;
    design.f_max = a.f_max;
    Ok(design.generate(fs)?)
}

pub(crate) fn excite(a: &ExcitationArgs) -> Result<(), Error> {
    let fs = check_fs(a.fs)?;
    let u = generate(a.excitation, &a.signal, fs)?;
    write_csv(&a.out, &["u"], &[&u])?;
    println!(
        "wrote {}: {}; u: force (N), RMS {:.4} N",
        a.out.display(),
        span(u.len(), fs),
        rms(&u)
    );
    Ok(())
}

/// `n samples at fs Hz (T s)`.
fn span(n: usize, fs: f64) -> String {
    format!("{n} samples at {fs} Hz ({:.4} s)", n as f64 / fs)
}

fn rms(x: &[f64]) -> f64 {
    (x.iter().map(|v| v * v).sum::<f64>() / x.len().max(1) as f64).sqrt()
}

pub(crate) fn run(a: &SimulateArgs) -> Result<(), Error> {
    if let Some(structure) = &a.structure {
        return run_structure(a, structure);
    }
    if !a.forces.is_empty() || a.measured.is_some() || a.channels.is_some() || a.compare_skip > 0 {
        return Err(fail(
            "--forces, --measured, --channels and --compare-skip go with --structure",
        ));
    }
    let model: Oscillator = match &a.params {
        Some(p) => hyst::io::read_oscillator(p).map_err(|e| fail(e.to_string()))?,
        None => match a.system {
            SystemArg::Benchmark => Oscillator::benchmark(),
        },
    };
    if a.oversample == 0 {
        return Err(fail("--oversample must be at least 1, got 0"));
    }
    let (u, fs, periodic) = match (&a.input, a.excitation) {
        (Some(path), None) => {
            let fs = check_fs(a.fs.ok_or_else(|| fail("--fs is required with --input"))?)?;
            let t = read_record(path)?;
            (t.column(&a.column)?.to_vec(), fs, a.periodic)
        }
        (None, Some(kind)) => {
            let fs = check_fs(a.fs.unwrap_or(750.0))?;
            let u = generate(kind, &a.signal, fs)?;
            (u, fs, a.periodic || kind == ExcitationKind::Multisine)
        }
        (Some(_), Some(_)) => return Err(fail("give either --input or --excitation, not both")),
        (None, None) => return Err(fail("give an --input file or an --excitation to generate")),
    };
    let opts = SimOptions {
        oversample: a.oversample,
        integrator: match a.integrator {
            IntegratorArg::Rk4 => Integrator::Rk4,
            IntegratorArg::Newmark => Integrator::Trapezoidal,
        },
        decimation: match a.decimation {
            DecimationArg::Sample => Decimation::Subsample,
            DecimationArg::Fir => Decimation::fir_stages(a.oversample),
        },
        ..SimOptions::default()
    };
    let kind = match (periodic, a.input_interpolation, &a.input) {
        (true, _, _) => sim::InputKind::Periodic,
        (false, Some(InterpolationArg::BandLimited), _) | (false, None, Some(_)) => {
            sim::InputKind::BandLimited
        }
        (false, Some(InterpolationArg::Linear), _) | (false, None, None) => sim::InputKind::Linear,
    };
    let mut y = sim::response(&model, &u, fs, kind, &opts)?;
    if a.noise != 0.0 {
        sim::excitation::add_noise(&mut y, a.noise, a.noise_seed)?;
    }
    write_csv(&a.out, &["u", "y"], &[&u, &y])?;
    let peak = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    println!(
        "wrote {}: {}{}; u: force (N), RMS {:.4} N; y: displacement (m), RMS {:.4e} m, peak {:.4e} m{}",
        a.out.display(),
        span(u.len(), fs),
        if periodic {
            ", the periodic steady state"
        } else {
            ", from rest"
        },
        rms(&u),
        rms(&y),
        peak,
        if a.noise != 0.0 {
            format!(" (with noise of RMS {:e} m)", a.noise)
        } else {
            String::new()
        }
    );
    Ok(())
}

/// `hyst simulate --structure`: a storey fit driven by measured forces, compared with a
/// measured record when one is given.
fn run_structure(a: &SimulateArgs, structure: &std::path::Path) -> Result<(), Error> {
    use hyst::ident::storeys::{response_errors, simulate_structure};
    structure_flags(a)?;
    let Some(input) = &a.input else {
        return Err(fail(
            "--structure needs the --input file holding its --forces",
        ));
    };
    if a.forces.is_empty() {
        return Err(fail(
            "--structure needs --forces: the --input columns of each loaded floor's force",
        ));
    }
    let fit = super::read_storey_fit("--structure", structure)?;
    let t = read_record(input)?;
    let fs = t.rate(a.fs)?;
    if (fs - fit.building.fs).abs() > 1e-9 * fs {
        return Err(fail(format!(
            "--input {} is at {fs} Hz; the structure was fitted at {} Hz",
            input.display(),
            fit.building.fs
        )));
    }
    let forces = a
        .forces
        .iter()
        .map(|c| Ok(t.column(c)?.to_vec()))
        .collect::<Result<Vec<_>, Error>>()?;
    let y = simulate_structure(&fit, &forces).map_err(|e| match e {
        // A state past any structure's: the forces given are far beyond those it was fitted
        // under (a slip of units, say), said with their size.
        hyst::ident::IdentError::Sim(hyst::sim::SimError::Diverged { .. }) => {
            let (rms, peak) = forces.iter().flatten().fold((0.0, 0.0f64), |(s, p), &v| {
                (s + v * v, p.max(v.abs()))
            });
            let rms = (rms / forces.iter().map(Vec::len).sum::<usize>().max(1) as f64).sqrt();
            fail(format!(
                "--input {}: under its --forces (RMS {rms:.4e} N, peak {peak:.4e} N) the fitted structure's state diverges ({e}): forces so far from those it was fitted under are outside what it holds (check their units)",
                input.display()
            ))
        }
        e => fail(e.to_string()),
    })?;
    let names = channel_columns(&fit);
    let mut cols: Vec<&str> = a.forces.iter().map(String::as_str).collect();
    cols.extend(names.iter().map(String::as_str));
    let mut data: Vec<&[f64]> = forces.iter().map(Vec::as_slice).collect();
    data.extend(y.iter().map(Vec::as_slice));
    write_csv(&a.out, &cols, &data)?;
    println!(
        "wrote {}: {} from rest; the fitted structure's {} under --input's {}",
        a.out.display(),
        span(y.first().map_or(0, Vec::len), fs),
        names.join(", "),
        a.forces.join(", ")
    );
    let Some(measured) = &a.measured else {
        return Ok(());
    };
    let m = read_record(measured)?;
    m.rate(Some(fs))?;
    let besides: Vec<&str> = a.forces.iter().map(String::as_str).collect();
    let channels = super::channel_names(&m, a.channels.as_deref(), &besides)?;
    let record = channels
        .iter()
        .map(|c| Ok(m.column(c)?.to_vec()))
        .collect::<Result<Vec<_>, Error>>()?;
    if record.len() != y.len() {
        return Err(fail(format!(
            "--measured {}: {} channel(s) ({}); the fit has {} sensor(s)",
            measured.display(),
            record.len(),
            channels.join(", "),
            y.len()
        )));
    }
    let samples = record
        .first()
        .map_or(0, Vec::len)
        .min(y.first().map_or(0, Vec::len));
    if a.compare_skip.saturating_add(2) > samples {
        return Err(fail(format!(
            "--compare-skip {}: the records compared have {samples} samples; leave at least two",
            a.compare_skip
        )));
    }
    let errors = response_errors(&y, &record, a.compare_skip).map_err(|e| fail(e.to_string()))?;
    println!(
        "against {} (from sample {}): RMS error per channel, and as a share of the channel's deviation (compare the sensors' noise):",
        measured.display(),
        a.compare_skip
    );
    for (c, e) in channels.iter().zip(&errors) {
        println!(
            "  {c:<12} {:.4e} of {:.4e}: {:.2} %",
            e.rms_error,
            e.measured_sd,
            100.0 * e.share()
        );
    }
    Ok(())
}

/// The flags `--structure` reads, checked before anything is read: the oscillator's flags
/// (which it would ignore) refused, each column named once, and `--measured`'s companions
/// only with it.
fn structure_flags(a: &SimulateArgs) -> Result<(), Error> {
    let design = hyst::sim::excitation::ExcitationDesign::default();
    let s = &a.signal;
    let oscillator = [
        ("--params", a.params.is_some()),
        ("--excitation", a.excitation.is_some()),
        ("--periodic", a.periodic),
        ("--noise", a.noise != 0.0),
        ("--noise-seed", a.noise_seed != NOISE_SEED),
        ("--column", a.column != "u"),
        ("--input-interpolation", a.input_interpolation.is_some()),
        ("--oversample", a.oversample != OVERSAMPLE),
        ("--integrator", a.integrator != IntegratorArg::Rk4),
        ("--decimation", a.decimation != DecimationArg::Sample),
        ("--rms", s.rms != design.rms),
        ("--samples", s.samples != design.samples),
        ("--seed", s.seed != design.seed),
        ("--f-min", s.f_min != design.f_min),
        ("--f-max", s.f_max != design.f_max),
    ];
    if let Some((flag, _)) = oscillator.iter().find(|(_, given)| *given) {
        return Err(fail(format!(
            "{flag} is the oscillator's: --structure is driven by --input's --forces from rest, at the steps its fit chose"
        )));
    }
    let twice = |flag: &str, names: &[String]| match hyst::io::repeated(names) {
        Some(n) => Err(fail(format!(
            "{flag}: `{n}` is named twice (each is its own column)"
        ))),
        None => Ok(()),
    };
    twice("--forces", &a.forces)?;
    if let Some(channels) = &a.channels {
        twice("--channels", channels)?;
        if let Some(c) = channels.iter().find(|c| a.forces.contains(c)) {
            return Err(fail(format!(
                "--channels: `{c}` is one of the --forces; the channels are the measured response"
            )));
        }
    }
    if a.measured.is_none() {
        if a.channels.is_some() {
            return Err(fail(
                "--channels names --measured's columns: give --measured",
            ));
        }
        if a.compare_skip != 0 {
            return Err(fail(
                "--compare-skip leaves samples out of the comparison with --measured: give --measured",
            ));
        }
    }
    Ok(())
}

/// The simulated channels' column names: the quantity's letter and the floor (from 1), and a
/// count after it when a floor has two channels.
fn channel_columns(fit: &hyst::ident::storeys::StoreyFit) -> Vec<String> {
    use hyst::ident::storeys::Quantity;
    let letter = match fit.building.reading {
        Quantity::Displacement => "x",
        Quantity::Velocity => "v",
        Quantity::Acceleration => "a",
    };
    let sensors = &fit.building.sensors;
    sensors
        .iter()
        .enumerate()
        .map(|(i, &s)| {
            let before = sensors[..i].iter().filter(|&&f| f == s).count();
            let twice = sensors.iter().filter(|&&f| f == s).count() > 1;
            if twice {
                format!("{letter}{}_{}", s + 1, before + 1)
            } else {
                format!("{letter}{}", s + 1)
            }
        })
        .collect()
}
