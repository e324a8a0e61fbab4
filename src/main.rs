//! The `hyst` command-line program.

use std::path::PathBuf;
use std::process::ExitCode;

mod frf_cmd;

use clap::{Args, Parser, Subcommand, ValueEnum};
use hyst::io::{read_csv, write_csv};
use hyst::model::Oscillator;
use hyst::sim::excitation::{Multisine, Sweep, white_noise};
use hyst::sim::{self, Decimation, Input, Integrator, SimOptions};

#[derive(Parser)]
#[command(
    name = "hyst",
    version,
    about = "Identify stiffness and hysteretic damping of vibrating structures from their response",
    long_about = None
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Simulate an oscillator driven by an input record or a generated excitation; write `u,y`.
    ///
    /// Examples:
    ///   hyst simulate --input multisine_val.csv --fs 750 --periodic --integrator newmark --decimation fir --out y.csv
    ///   hyst simulate --excitation multisine --rms 50 --samples 8192 --seed 1 --out y.csv
    #[command(verbatim_doc_comment, allow_negative_numbers = true)]
    Simulate(SimulateArgs),
    /// Generate an excitation record and write it as a one-column CSV `u`.
    #[command(allow_negative_numbers = true)]
    Excite(ExcitationArgs),
    /// Output-only modal analysis (covariance-driven SSI) of one or more channels: modes with
    /// their spread, then refined by maximum likelihood with standard errors; with several
    /// channels, each mode's shape with its MPC and the MAC between the modes.
    ///
    /// Example:
    ///   hyst ssi --input data_3dof.csv --fs 20 --columns y1,y2,y3 --max-order 40 --json modes.json --svg diagram.svg
    #[command(verbatim_doc_comment, allow_negative_numbers = true)]
    Ssi(SsiArgs),
    /// Output-only identification of linear, Zener and Bouc-Wen models (the paper's pipeline).
    ///
    /// Without --data, runs on a built-in default: the Bouc-Wen benchmark driven by its 50 N
    /// multisine (5 periods, the first dropped) with the benchmark's measurement noise,
    /// validated on a fresh multisine realization.
    ///
    /// Example:
    ///   hyst ident --data multisine_train.csv --fs 750 --mass 2 --skip 8192 --validate multisine_val.csv --json id.json
    #[command(verbatim_doc_comment, allow_negative_numbers = true)]
    Ident(IdentArgs),
    /// Close the loop with input and output: refine a model by output error, trace the
    /// residual to the effect the model lacks, add it, refit, and report the held-out error
    /// before and after, the noise level, and what is left.
    ///
    /// Example (Silverbox: estimate on the multisine part, test on the arrow head):
    ///   hyst refine --data SNLS80mV.csv --fs 610.3515625 --start linear --estimate 40650:105712 --test 100:40575 --test 100:32100 --json refine.json
    #[command(verbatim_doc_comment, allow_negative_numbers = true)]
    Refine(RefineArgs),
    /// One Bouc-Wen model from records of the same structure at several force levels, each
    /// under a random (white) force: the Zener oscillator fitted to each record's spectrum,
    /// mapped to Bouc-Wen through the statistical linearization of all levels together.
    ///
    /// Example:
    ///   hyst levels --data bw10.csv bw50.csv bw90.csv --fs 750 --mass 2 --data-periodic --validate bw50v.csv --periodic --json levels.json
    #[command(verbatim_doc_comment, allow_negative_numbers = true)]
    Levels(LevelsArgs),
    /// With the input: the modes of a periodic record's frequency response over a band (an
    /// input-output second opinion on `hyst ssi`), with several outputs each mode's shape,
    /// and optionally the outputs under a force of flat spectrum.
    ///
    /// Example (the F-16 at its lowest level, the wing torsion mode):
    ///   hyst frf --input msine_level1.csv --fs 400 --force force --period 8192 --skip 8192 --band 6.8:7.8 --json torsion.json --svg torsion.svg
    #[command(verbatim_doc_comment, allow_negative_numbers = true)]
    Frf(frf_cmd::FrfArgs),
}

#[derive(Args, Debug)]
struct LevelsArgs {
    /// Records with the measured output (CSV with a header), two or more, one per force level.
    #[arg(long, num_args = 2.., required = true)]
    data: Vec<PathBuf>,
    /// Sampling rate of the records (Hz).
    #[arg(long)]
    fs: f64,
    /// Mass of the oscillator (kg), assumed known.
    #[arg(long)]
    mass: f64,
    /// Column of the output (displacement).
    #[arg(long, default_value = "y")]
    output_column: String,
    /// Column of the input force (only used by --validate files).
    #[arg(long, default_value = "u")]
    input_column: String,
    /// Skip this many leading rows of each --data record (e.g. a start-up transient).
    #[arg(long, default_value_t = 0)]
    skip: usize,
    /// Validation records (input and output columns): the model is simulated with the input
    /// and compared with the output.
    #[arg(long, num_args = 1..)]
    validate: Vec<PathBuf>,
    /// The validation records are one steady-state period of a periodic force (else the
    /// model is simulated from rest).
    #[arg(long)]
    periodic: bool,
    /// The --data records are each one steady-state period of a periodic force (as `hyst
    /// simulate --periodic` writes them); --by-simulation then simulates them so. Without
    /// it they are taken as measured: simulated from rest, the warm-up dropped.
    #[arg(long)]
    data_periodic: bool,
    /// Write the results as JSON here.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Write figures (SVG) into this folder: each level's k∞ and Ω beside the model's.
    #[arg(long)]
    svg_dir: Option<PathBuf>,
    /// Then fit the model by simulation (indirect inference): the Bouc-Wen model whose
    /// simulated records give the same Zener fits as the records. Removes the Gaussian
    /// closure's bias; each iteration simulates every level six times (for three records of 2¹⁷
    /// samples on two cores: about 7 s, 30 s with --data-periodic).
    #[arg(long)]
    by_simulation: bool,
    /// Fit the Bouc-Wen exponent ν too (three or more --data records), instead of ν = 1;
    /// with --by-simulation, there as well (slower: ν < 1 or > 1 costs a power per step).
    #[arg(long)]
    fit_exponent: bool,
}

#[derive(Clone, Copy, ValueEnum, PartialEq, Eq, Debug)]
enum InterpolationArg {
    /// A measured force behind an anti-aliasing filter: windowed-sinc interpolation.
    BandLimited,
    /// Linear between samples, as `hyst simulate` without --periodic drives its models.
    Linear,
}

#[derive(Clone, Copy, ValueEnum, PartialEq, Eq, Debug)]
enum StartArg {
    Linear,
    Zener,
    BoucWen,
}

#[derive(Args, Debug)]
struct RefineArgs {
    /// Record with input and output columns (CSV with a header).
    #[arg(long)]
    data: PathBuf,
    /// Sampling rate (Hz).
    #[arg(long)]
    fs: f64,
    /// Mass (kg); without it the mass is estimated too (and the missing force is traced with
    /// the estimate).
    #[arg(long)]
    mass: Option<f64>,
    /// Input column.
    #[arg(long, default_value = "u")]
    input_column: String,
    /// Output column.
    #[arg(long, default_value = "y")]
    output_column: String,
    /// Starting model class. A start the output-only pipeline cannot give, or whose fit
    /// diverges, falls back to the next simpler one (bouc-wen, zener, linear), and the
    /// report says so.
    #[arg(long, value_enum, default_value = "linear")]
    start: StartArg,
    /// How the input is known between samples when the models are simulated.
    #[arg(long, value_enum, default_value = "band-limited")]
    input_interpolation: InterpolationArg,
    /// Estimation rows A:B (0-based, B excluded); default the first 75 %.
    #[arg(long)]
    estimate: Option<String>,
    /// Test rows C:D (repeatable, at least 512 rows each); default the last 25 %. An effect
    /// is added only if it lowers the held-out mean squared error significantly (a paired
    /// test over 8 blocks of each range, p < 0.01) and by at least 1 %.
    #[arg(long)]
    test: Vec<String>,
    /// Write the report as JSON here.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Write figures (SVG) into this folder: residual spectra before/after, time overlays,
    /// and the restoring-force surface of the baseline's residual with its two sections.
    #[arg(long)]
    svg_dir: Option<PathBuf>,
}

#[derive(Clone, Copy, ValueEnum, PartialEq, Eq, Debug)]
enum DampingArg {
    /// From the Zener oscillator fitted to the record's spectrum (white force assumed) when
    /// the record follows the stationary model; else as `cluster`.
    Spectrum,
    /// The paper's guess: a cluster of lightly damped poles near the pair.
    Cluster,
}

#[derive(Clone, Copy, ValueEnum, PartialEq, Eq, Debug)]
enum LinearizationArg {
    /// Eqs. (37)-(38) as printed.
    Paper,
    /// Alpha from eq. (37), then exact inversion of the describing function.
    Harmonic,
}

#[derive(Args, Debug)]
struct IdentArgs {
    /// Record with the measured output (CSV with a header). Without it: the built-in default.
    #[arg(long)]
    data: Option<PathBuf>,
    /// Sampling rate of --data (Hz).
    #[arg(long)]
    fs: Option<f64>,
    /// Mass of the oscillator (kg), assumed known.
    #[arg(long)]
    mass: Option<f64>,
    /// Column of the output (displacement).
    #[arg(long, default_value = "y")]
    output_column: String,
    /// Column of the input force (only used by --validate files).
    #[arg(long, default_value = "u")]
    input_column: String,
    /// Skip this many leading rows of --data (e.g. a start-up transient).
    #[arg(long, default_value_t = 0)]
    skip: usize,
    /// Validation records (input and output columns): each identified model is simulated with
    /// the input and compared with the output. Files named *multisine* are taken as one
    /// steady-state period; others are simulated from rest.
    #[arg(long, num_args = 1..)]
    validate: Vec<PathBuf>,
    /// Mapping from the poles to Bouc-Wen parameters (default: whichever validates better;
    /// harmonic without validation data).
    #[arg(long, value_enum)]
    linearization: Option<LinearizationArg>,
    /// Where the viscous damping c of the Zener and Bouc-Wen models comes from.
    #[arg(long, value_enum, default_value = "spectrum", conflicts_with = "c")]
    damping: DampingArg,
    /// A known viscous damping c (N s/m), in place of --damping.
    #[arg(long)]
    c: Option<f64>,
    /// The band LO:HI (Hz) on which the excitation's amplitude spectrum was flat (a
    /// multisine's design; needs --period). The Bouc-Wen model is then fitted by flatness of
    /// its implied input, and kept when it validates better than the mapped one (or when
    /// there is nothing to validate on). The built-in default job uses 5:150.1.
    #[arg(long)]
    excitation_band: Option<String>,
    /// Samples per period of the excitation (with --excitation-band); --data must hold whole
    /// periods of the steady state (use --skip to drop a start-up transient).
    #[arg(long)]
    period: Option<usize>,
    /// Write the results as JSON here.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Write figures (SVG) into this folder.
    #[arg(long)]
    svg_dir: Option<PathBuf>,
}

#[derive(Args, Debug)]
struct SsiArgs {
    /// Input CSV file with a header line.
    #[arg(long)]
    input: PathBuf,
    /// Sampling rate of the file (Hz).
    #[arg(long)]
    fs: f64,
    /// Channels to analyse, comma-separated; default: every column except `t` and `time` (with
    /// a warning for columns named like a force: `u`, `force`, `input`, `excitation`, `load`).
    #[arg(long, value_delimiter = ',')]
    columns: Option<Vec<String>>,
    /// Decimate by this factor first (MATLAB-style FIR decimation).
    #[arg(long, default_value_t = 1)]
    decimate: usize,
    /// Skip this many leading rows (e.g. a start-up transient).
    #[arg(long, default_value_t = 0)]
    skip: usize,
    /// Block rows of the Toeplitz matrix (lags up to 2·N−1).
    #[arg(long, default_value_t = 20)]
    block_rows: usize,
    /// Instead of --block-rows: as many block rows as make the largest lag cover this many
    /// seconds (after --decimate).
    #[arg(
        long,
        value_name = "SECONDS",
        conflicts_with_all = ["block_rows", "lag_periods"]
    )]
    lag_seconds: Option<f64>,
    /// Instead of --block-rows: as many block rows as make the largest lag cover COUNT periods
    /// of HZ, e.g. `--lag-periods 10 1.5` for ten periods of a 1.5 Hz mode (the paper's
    /// choice: ten periods of the dominant mode).
    #[arg(
        long,
        num_args = 2,
        value_names = ["COUNT", "HZ"],
        conflicts_with = "block_rows"
    )]
    lag_periods: Option<Vec<f64>>,
    /// Largest model order (default: the Toeplitz rank, at most 40).
    #[arg(long)]
    max_order: Option<usize>,
    /// Model order step.
    #[arg(long, default_value_t = 1)]
    order_step: usize,
    /// Stabilization threshold on the relative frequency change.
    #[arg(long, default_value_t = 0.01)]
    df: f64,
    /// Stabilization threshold on the relative damping change.
    #[arg(long, default_value_t = 0.05)]
    dzeta: f64,
    /// Stabilization threshold on 1 − MAC (several channels).
    #[arg(long, default_value_t = 0.02)]
    dmac: f64,
    /// Stabilization threshold of eq. (31) for real poles.
    #[arg(long, default_value_t = 1.5)]
    dreal: f64,
    /// Reference channels (0-based indices among --columns), comma-separated; default: all.
    #[arg(long, value_delimiter = ',')]
    references: Option<Vec<usize>>,
    /// Write the modes, real poles and per-order poles as JSON here.
    #[arg(long)]
    json: PathBuf,
    /// Draw the stabilization diagram as SVG here.
    #[arg(long)]
    svg: Option<PathBuf>,
    /// Skip the maximum-likelihood refinement of the modes and real poles (on by default: it
    /// fits them to the whole record, gives each a standard error, and drops those the record
    /// does not support).
    #[arg(long)]
    no_refine: bool,
    /// Refine with each channel's likelihood alone, not the joint likelihood of all channels
    /// (which uses their cross-spectra; on by default for 2 to 4 channels, and above 4 through 4
    /// combinations of them, band by band when there are more than 4 modes).
    #[arg(long)]
    no_joint: bool,
}

#[derive(Clone, Copy, ValueEnum, PartialEq, Eq, Debug)]
enum IntegratorArg {
    /// Classic fourth-order Runge-Kutta.
    Rk4,
    /// The benchmark's Newmark (a = 1/2, b = 1/4), i.e. the implicit trapezoidal rule.
    Newmark,
}

#[derive(Clone, Copy, ValueEnum, PartialEq, Eq, Debug)]
enum DecimationArg {
    /// Keep the state at each sample instant.
    Sample,
    /// MATLAB's decimate(.., 'fir') in stages (the prime factors of --oversample, ascending).
    Fir,
}

#[derive(Clone, Copy, ValueEnum, PartialEq, Eq, Debug)]
enum ExcitationKind {
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
enum SystemArg {
    /// The Bouc-Wen benchmark: m = 2, c = 10, k = 5e4, alpha = 5e4, beta*gamma = 800, beta*delta = -1100, nu = 1.
    Benchmark,
}

#[derive(Args, Debug)]
struct ExcitationArgs {
    /// Kind of excitation to generate.
    #[arg(long, value_enum, default_value = "multisine")]
    excitation: ExcitationKind,
    #[command(flatten)]
    signal: SignalArgs,
    /// Sampling rate (Hz).
    #[arg(long, default_value_t = 750.0)]
    fs: f64,
    /// Output CSV file.
    #[arg(long)]
    out: PathBuf,
}

/// The parameters of a generated excitation, shared by `simulate` and `excite`.
#[derive(Args, Debug)]
struct SignalArgs {
    /// RMS of the generated excitation (N).
    #[arg(long, default_value_t = 50.0)]
    rms: f64,
    /// Samples of the generated excitation (a multisine: one period).
    #[arg(long, default_value_t = 8192)]
    samples: usize,
    /// Seed of the random generator.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Lowest excited frequency (Hz).
    #[arg(long, default_value_t = 5.0)]
    f_min: f64,
    /// Highest excited frequency (Hz).
    #[arg(long, default_value_t = 150.0)]
    f_max: f64,
}

#[derive(Args, Debug)]
struct SimulateArgs {
    /// Input CSV file (with a header line). Without it, an excitation is generated.
    #[arg(long)]
    input: Option<PathBuf>,
    /// Sampling rate of the input (Hz); required with --input, default 750 for generated input.
    #[arg(long)]
    fs: Option<f64>,
    /// Column of the input file holding the force.
    #[arg(long, default_value = "u")]
    column: String,
    /// The input is one period of a periodic signal: simulate to steady state and write one
    /// steady-state period (the input is interpolated exactly between samples).
    #[arg(long)]
    periodic: bool,
    /// How a non-periodic input is known between samples. Default: band-limited for an
    /// --input file (a measured force, as `hyst ident --validate` and `hyst refine` take it),
    /// linear for a generated excitation (how the project's synthetic records are made).
    #[arg(long, value_enum)]
    input_interpolation: Option<InterpolationArg>,
    /// Integration sub-steps per sample.
    #[arg(long, default_value_t = 20)]
    oversample: usize,
    /// Time integrator.
    #[arg(long, value_enum, default_value = "rk4")]
    integrator: IntegratorArg,
    /// How the fine-step output returns to the sampling rate.
    #[arg(long, value_enum, default_value = "sample")]
    decimation: DecimationArg,
    /// Built-in system to simulate (ignored with --params).
    #[arg(long, value_enum, default_value = "benchmark")]
    system: SystemArg,
    /// Oscillator parameters as JSON (see the `params` module docs), instead of --system.
    #[arg(long)]
    params: Option<PathBuf>,
    /// Generated excitation kind, when there is no --input.
    #[arg(long, value_enum)]
    excitation: Option<ExcitationKind>,
    #[command(flatten)]
    signal: SignalArgs,
    /// Standard deviation of white measurement noise added to y (m).
    #[arg(long, default_value_t = 0.0)]
    noise: f64,
    /// Seed of the measurement noise.
    #[arg(long, default_value_t = 2)]
    noise_seed: u64,
    /// Output CSV file (`u,y`).
    #[arg(long)]
    out: PathBuf,
}

type Error = Box<dyn std::error::Error>;

fn fail(msg: impl Into<String>) -> Error {
    msg.into().into()
}

fn generate(kind: ExcitationKind, a: &SignalArgs, fs: f64) -> Result<Vec<f64>, Error> {
    Ok(match kind {
        ExcitationKind::Multisine => {
            Multisine::band(a.samples, fs, a.f_min, a.f_max, a.rms)?.generate(a.seed)?
        }
        ExcitationKind::White => white_noise(a.samples, a.rms, a.seed)?,
        ExcitationKind::Sweep => Sweep {
            amplitude: a.rms * std::f64::consts::SQRT_2,
            f0: a.f_min,
            f1: a.f_max,
            duration: a.samples as f64 / fs,
        }
        .sample(a.samples, fs)?,
    })
}

/// The channels to analyse: those given, else every column but a time column (`t`, `time`)
/// and those in `besides`.
fn channel_names(t: &hyst::io::Table, given: Option<&[String]>, besides: &[&str]) -> Vec<String> {
    match given {
        Some(c) => c.to_vec(),
        None => t
            .names
            .iter()
            .filter(|n| {
                !besides.contains(&n.as_str())
                    && !matches!(n.to_ascii_lowercase().as_str(), "t" | "time")
            })
            .cloned()
            .collect(),
    }
}

/// Output only means responses only: a default channel list that takes in the force is a
/// mistake the user should hear about (the benchmarks' files hold `u,y`).
fn warn_on_force_like(names: &[String]) {
    let looks_input = |n: &str| {
        matches!(
            n.to_ascii_lowercase().as_str(),
            "u" | "force" | "input" | "excitation" | "load"
        )
    };
    let (inputs, responses): (Vec<&String>, Vec<&String>) =
        names.iter().partition(|n| looks_input(n));
    if inputs.is_empty() {
        return;
    }
    let list = |v: &[&String]| v.iter().map(|s| s.as_str()).collect::<Vec<_>>().join(",");
    let (what, is) = if inputs.len() == 1 {
        (
            format!("column `{}` looks like the input (a force)", inputs[0]),
            "it is analysed as a response",
        )
    } else {
        (
            format!("columns {} look like inputs (forces)", list(&inputs)),
            "they are analysed as responses",
        )
    };
    eprintln!(
        "warning: {what}, and output-only analysis takes responses only; {is} because --columns was not given{}",
        if responses.is_empty() {
            String::new()
        } else {
            format!(" (for the responses alone: --columns {})", list(&responses))
        }
    );
}

fn check_fs(fs: f64) -> Result<f64, Error> {
    if fs.is_finite() && fs > 0.0 {
        Ok(fs)
    } else {
        Err(fail(format!(
            "--fs must be a positive number of Hz, got {fs}"
        )))
    }
}

fn prime_factors(mut n: usize) -> Vec<usize> {
    let mut f = Vec::new();
    let mut p = 2;
    while n > 1 {
        while n.is_multiple_of(p) {
            f.push(p);
            n /= p;
        }
        p += 1;
    }
    f
}

fn excite(a: &ExcitationArgs) -> Result<(), Error> {
    let fs = check_fs(a.fs)?;
    let u = generate(a.excitation, &a.signal, fs)?;
    write_csv(&a.out, &["u"], &[&u])?;
    Ok(())
}

fn simulate(a: &SimulateArgs) -> Result<(), Error> {
    let model: Oscillator = match &a.params {
        Some(p) => {
            let text =
                std::fs::read_to_string(p).map_err(|e| fail(format!("{}: {e}", p.display())))?;
            hyst::params::oscillator_from_json(&text)
                .map_err(|e| fail(format!("{}: {e}", p.display())))?
        }
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
            let t = read_csv(path)?;
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
            DecimationArg::Fir => Decimation::Fir(prime_factors(a.oversample)),
        },
        ..SimOptions::default()
    };
    let band_limited = match (a.input_interpolation, &a.input) {
        (Some(i), _) => i == InterpolationArg::BandLimited,
        (None, from_file) => from_file.is_some(),
    };
    let mut y = if periodic {
        sim::steady_state_period(&model, &u, fs, &opts, 1e-10, 200)?.y
    } else if band_limited {
        sim::simulate(&model, Input::BandLimited(&u), fs, u.len(), &opts)?
    } else {
        sim::simulate(&model, Input::Sampled(&u), fs, u.len(), &opts)?
    };
    if a.noise != 0.0 {
        sim::excitation::add_noise(&mut y, a.noise, a.noise_seed)?;
    }
    write_csv(&a.out, &["u", "y"], &[&u, &y])?;
    Ok(())
}

fn c64(v: hyst::covssi::Complex64) -> serde_json::Value {
    serde_json::json!([v.re, v.im])
}

fn ssi(a: &SsiArgs) -> Result<(), Error> {
    use hyst::covssi::{self, BlockRows, PoleStatus, Rejection, SsiOptions, StabilityCriteria};
    use serde_json::json;
    let fs = check_fs(a.fs)?;
    if a.decimate == 0 {
        return Err(fail("--decimate must be at least 1, got 0"));
    }
    let t = read_csv(&a.input)?;
    let names = channel_names(&t, a.columns.as_deref(), &[]);
    if a.columns.is_none() {
        warn_on_force_like(&names);
    }
    if let Some(n) = hyst::io::repeated(&names) {
        return Err(fail(format!(
            "--columns names `{n}` twice: each channel once"
        )));
    }
    if a.skip >= t.len() {
        return Err(fail(format!(
            "--skip {} leaves no rows of the {} in {}",
            a.skip,
            t.len(),
            a.input.display()
        )));
    }
    let mut channels = Vec::new();
    for n in &names {
        let c = &t.column(n)?[a.skip..];
        channels.push(hyst::sim::resample::decimate(c, a.decimate));
    }
    let fs_used = fs / a.decimate as f64;
    let views: Vec<&[f64]> = channels.iter().map(|c| c.as_slice()).collect();
    let block_rows = match (a.lag_seconds, a.lag_periods.as_deref()) {
        (Some(t), _) => BlockRows::Seconds(t),
        (None, Some(&[count, frequency_hz])) => BlockRows::Periods {
            count,
            frequency_hz,
        },
        _ => BlockRows::Count(a.block_rows),
    };
    let opts = SsiOptions {
        block_rows,
        max_order: a.max_order,
        order_step: a.order_step,
        criteria: StabilityCriteria {
            frequency: a.df,
            damping: a.dzeta,
            mac: a.dmac,
            real: a.dreal,
        },
        references: a.references.clone(),
        ..SsiOptions::default()
    };
    // Errors of covssi name the file and the columns they came from; an option out of
    // range is named by the flag that set it.
    let lag_too_short = |flag: &str, rows: f64| {
        fail(format!(
            "{flag} gives {rows} block row(s) at {fs_used} Hz; SSI needs at least 2: give a longer lag"
        ))
    };
    let context = |e: covssi::SsiError| {
        if let covssi::SsiError::InvalidOption { name, value } = &e {
            let flag = match *name {
                // A lag given as a time is too short for the rate: say what it gave.
                "block_rows" => match block_rows {
                    BlockRows::Count(_) => Some(("--block-rows", "at least 2")),
                    BlockRows::Seconds(_) => return lag_too_short("--lag-seconds", *value),
                    BlockRows::Periods { .. } => return lag_too_short("--lag-periods", *value),
                },
                "block_rows (seconds)" => Some(("--lag-seconds", "positive and finite")),
                "block_rows (periods: count)" => {
                    Some(("--lag-periods COUNT", "positive and finite"))
                }
                "block_rows (periods: frequency_hz)" => {
                    Some(("--lag-periods HZ", "positive and finite"))
                }
                "references (index out of range)" => {
                    return fail(format!(
                        "--references {value} is out of range: {} channel(s), numbered from 0",
                        names.len()
                    ));
                }
                "references (index repeated)" => {
                    return fail(format!("--references names channel {value} twice"));
                }
                "max_order" => Some(("--max-order", "at least 1")),
                "order_step" => Some(("--order-step", "at least 1")),
                "criteria.frequency" => Some(("--df", "positive and finite")),
                "criteria.damping" => Some(("--dzeta", "positive and finite")),
                "criteria.mac" => Some(("--dmac", "positive and finite")),
                "criteria.real" => Some(("--dreal", "positive and finite")),
                _ => None,
            };
            if let Some((flag, needed)) = flag {
                return fail(format!("{flag} must be {needed}, got {value}"));
            }
        }
        // An error about the record after decimation says so: "too short" or "constant"
        // may be the decimation's doing, not the file's.
        let decimated = if a.decimate > 1 {
            format!(
                ", decimated by {} to {} of {} rows",
                a.decimate,
                views.first().map_or(0, |c| c.len()),
                t.len() - a.skip
            )
        } else {
            String::new()
        };
        fail(format!(
            "{}: columns {}{decimated}: {e}",
            a.input.display(),
            names.join(",")
        ))
    };
    let res = covssi::identify(&views, fs_used, &opts).map_err(context)?;
    let modes: Vec<_> = res
        .modes
        .iter()
        .map(|m| {
            json!({
                "frequency_hz": m.frequency_hz,
                "damping_ratio": m.damping_ratio,
                "frequency_std_hz": m.frequency_std_hz,
                "damping_std": m.damping_std,
                "poles": m.members.len(),
                "members": m.members,
                "shape": m.shape.iter().map(|v| c64(*v)).collect::<Vec<_>>(),
                "shape_std": m.shape_std,
                "mpc": covssi::mpc(&m.shape),
                "lambda": c64(m.lambda),
            })
        })
        .collect();
    let real: Vec<_> = res
        .real_poles
        .iter()
        .map(|r| json!({"lambda": r.lambda, "lambda_std": r.lambda_std, "poles": r.members.len()}))
        .collect();
    let orders: Vec<_> = res
        .diagram
        .orders
        .iter()
        .map(|o| {
            let poles: Vec<_> = o
                .poles
                .iter()
                .map(|p| {
                    let why = match p.status {
                        PoleStatus::Rejected(Rejection::Frequency { change, threshold })
                        | PoleStatus::Rejected(Rejection::RealPole { change, threshold }) => {
                            json!({"change": change, "threshold": threshold})
                        }
                        PoleStatus::Rejected(Rejection::DampingAboveLimit { damping, limit }) => {
                            json!({"damping": damping, "limit": limit})
                        }
                        PoleStatus::Rejected(Rejection::Unstable { real_part }) => {
                            json!({"real_part": real_part})
                        }
                        _ => serde_json::Value::Null,
                    };
                    json!({
                        "lambda": c64(p.lambda),
                        "frequency_hz": p.frequency_hz,
                        "damping_ratio": p.damping_ratio,
                        "real": p.is_real,
                        "label": p.status.name(),
                        "why": why,
                        "d_frequency": p.d_frequency,
                        "d_damping": p.d_damping,
                        "d_mac": p.d_mac,
                        "d_real": p.d_real,
                    })
                })
                .collect();
            json!({"order": o.order, "poles": poles})
        })
        .collect();
    // The block rows first: given as a lag time or periods they are worked out here.
    let largest_lag = 2 * res.block_rows - 1;
    println!(
        "{} block rows: correlations up to lag {largest_lag} ({:.4} s at {fs_used} Hz)",
        res.block_rows,
        largest_lag as f64 / fs_used
    );
    // The SSI result first: the refinement can take a minute on many channels and modes.
    if !res.modes.is_empty() || !res.real_poles.is_empty() {
        println!("SSI (± is the spread over each cluster's poles, not a standard error):");
    }
    for m in &res.modes {
        // Members come by increasing order: the first and last give the span of orders.
        let span = match (m.members.first(), m.members.last()) {
            (Some(lo), Some(hi)) => format!(", orders {}–{}", lo.0, hi.0),
            _ => String::new(),
        };
        println!(
            "mode {:>9.4} ± {:.4} Hz  damping {:.4} ± {:.4}  ({} poles{span})",
            m.frequency_hz,
            m.frequency_std_hz,
            m.damping_ratio,
            m.damping_std,
            m.members.len()
        );
    }
    // Shapes say something with several channels only (a one-channel shape is a number).
    let mac: Vec<Vec<f64>> = res
        .modes
        .iter()
        .map(|a| {
            res.modes
                .iter()
                .map(|b| covssi::mac(&a.shape, &b.shape))
                .collect()
        })
        .collect();
    if views.len() > 1 && !res.modes.is_empty() {
        println!(
            "shapes (channels {}; magnitude∠phase, the largest entry 1; MPC 1 for a real mode):",
            names.join(", ")
        );
        for m in &res.modes {
            println!(
                "  {:>9.4} Hz  {}  MPC {:.3}",
                m.frequency_hz,
                hyst::shape_text(&m.shape, "  "),
                covssi::mpc(&m.shape)
            );
        }
        println!(
            "MAC between the modes (1 on the diagonal; near 0 where the channels tell two modes apart):"
        );
        for (m, row) in res.modes.iter().zip(&mac) {
            let cells: Vec<String> = row.iter().map(|v| format!("{v:.3}")).collect();
            println!("  {:>9.4} Hz  {}", m.frequency_hz, cells.join("  "));
        }
    }
    for r in &res.real_poles {
        println!(
            "real pole {:.4} ± {:.4} rad/s ({} poles)",
            r.lambda,
            r.lambda_std,
            r.members.len()
        );
    }
    for n in &res.notes {
        println!("note: {n}");
    }
    let refined = if a.no_refine || (res.modes.is_empty() && res.real_poles.is_empty()) {
        None
    } else {
        eprintln!(
            "refining {} SSI mode(s) and {} real pole(s) by maximum likelihood on {} channel(s) of {} samples…",
            res.modes.len(),
            res.real_poles.len(),
            views.len(),
            views.first().map_or(0, |v| v.len())
        );
        Some(
            covssi::refine_with_real_poles(
                &views,
                fs_used,
                &res.modes,
                &res.real_poles,
                &covssi::RefineOptions {
                    joint: !a.no_joint,
                    ..Default::default()
                },
            )
            .map_err(context)?,
        )
    };
    let refined_json = refined.as_ref().map(|r| {
        json!({
            "modes": r.modes.iter().map(|m| json!({
                "frequency_hz": m.frequency_hz,
                "damping_ratio": m.damping_ratio,
                "frequency_se_hz": m.frequency_se_hz,
                "damping_se": m.damping_se,
                "lambda": c64(m.lambda),
                "shape": m.shape.as_ref().map(|v| v.iter().map(|c| c64(*c)).collect::<Vec<_>>()),
                "shape_se": m.shape_se,
                "mpc": m.shape.as_ref().map(|v| covssi::mpc(v)),
                "evidence": m.evidence,
                "ssi_mode": m.source,
            })).collect::<Vec<_>>(),
            "dropped": r.dropped.iter().map(|d| json!({
                "ssi_mode": d.source,
                "frequency_hz": d.frequency_hz,
                "evidence": d.evidence,
            })).collect::<Vec<_>>(),
            "penalty": r.penalty,
            "real_poles": r.real_poles.iter().map(|p| json!({
                "lambda": p.lambda,
                "lambda_se": p.lambda_se,
                "evidence": p.evidence,
                "ssi_real_pole": p.source,
            })).collect::<Vec<_>>(),
            "dropped_real_poles": r.dropped_real_poles.iter().map(|d| json!({
                "ssi_real_pole": d.source,
                "lambda": d.lambda,
                "evidence": d.evidence,
            })).collect::<Vec<_>>(),
            "real_pole_penalty": r.real_pole_penalty,
            "neg_log_likelihood": r.neg_log_likelihood,
            "misfit": r.misfit,
            "misfit_limit": covssi::refine::MISFIT_LIMIT,
            "frequencies": r.frequencies,
            "iterations": r.iterations,
            "joint": r.joint,
            "combinations": r.combinations,
            "bands": r.bands,
        })
    });
    let doc = json!({
        "input": a.input.display().to_string(),
        "channels": names,
        "fs_hz": fs_used,
        "block_rows": res.block_rows,
        "modes": modes,
        "mac": mac,
        "refined": refined_json,
        "real_poles": real,
        "notes": res.notes,
        "orders": orders,
    });
    std::fs::write(&a.json, serde_json::to_string_pretty(&doc)?)
        .map_err(|e| fail(format!("{}: {e}", a.json.display())))?;
    if let Some(svg) = &a.svg {
        let title = format!("Stabilization diagram: {}", a.input.display());
        std::fs::write(
            svg,
            covssi::svg::stabilization_svg(&res.diagram, None, &title),
        )
        .map_err(|e| fail(format!("{}: {e}", svg.display())))?;
    }
    if let Some(r) = &refined {
        println!(
            "refined by maximum likelihood ({} frequencies, {}; a mode needs evidence above {:.1}; ± one standard error):",
            r.frequencies,
            r.fitted_by(),
            r.penalty
        );
        // A standard error beyond 1e5 (a real pole far outside the band, say) in exponent
        // form: thirty digits say nothing more than that the record does not determine it.
        let se = |v: Option<f64>| {
            v.map_or("?".to_string(), |v| {
                if v.abs() < 1e5 {
                    format!("{v:.4}")
                } else {
                    format!("{v:.1e}")
                }
            })
        };
        for m in &r.modes {
            let ssi = m.source.map_or_else(
                || {
                    format!(
                        "no SSI mode within {:.0} % of its pole",
                        100.0 * covssi::refine::SAME_MODE_DISTANCE
                    )
                },
                |i| format!("SSI mode at {:.4} Hz", res.modes[i].frequency_hz),
            );
            println!(
                "mode {:>9.4} ± {} Hz  damping {:.4} ± {}  (evidence {:.0}; {ssi})",
                m.frequency_hz,
                se(m.frequency_se_hz),
                m.damping_ratio,
                se(m.damping_se),
                m.evidence,
            );
            if let (Some(shape), Some(sd)) = (&m.shape, &m.shape_se) {
                // Two digits whatever the size; the entry scaled to 1 has none.
                let se: Vec<String> = sd
                    .iter()
                    .map(|&v| {
                        if v == 0.0 {
                            "0".into()
                        } else {
                            format!("{v:.1e}")
                        }
                    })
                    .collect();
                println!(
                    "     shape {}  (standard errors {}; MPC {:.3})",
                    hyst::shape_text(shape, "  "),
                    se.join(", "),
                    covssi::mpc(shape)
                );
            }
        }
        for d in &r.dropped {
            println!(
                "dropped the SSI mode at {:.4} Hz: evidence {:.1}",
                d.frequency_hz, d.evidence
            );
        }
        for p in &r.real_poles {
            println!(
                "real pole {:.4} ± {} rad/s  (evidence {:.0}, above {:.1}; SSI real pole at {:.4})",
                p.lambda,
                se(p.lambda_se),
                p.evidence,
                r.real_pole_penalty,
                res.real_poles[p.source].lambda
            );
        }
        for d in &r.dropped_real_poles {
            println!(
                "dropped the SSI real pole at {:.4} rad/s: evidence {:.1}, below {:.1}",
                d.lambda, d.evidence, r.real_pole_penalty
            );
        }
        if r.misfit > covssi::refine::MISFIT_LIMIT {
            println!(
                "warning: the record does not follow the refinement's model (misfit {:.3} > {}): \
                 the excitation may not be broadband random (e.g. a multisine), or the record \
                 holds what the model lacks; trust the SSI modes above instead",
                r.misfit,
                covssi::refine::MISFIT_LIMIT
            );
        } else {
            println!("misfit {:.3} (the record follows the model)", r.misfit);
        }
    }
    Ok(())
}

/// The built-in default record: the benchmark system driven by its 50 N multisine over five
/// periods from rest (the first dropped), with white measurement noise of 7.4e-6 m (the level
/// measured between the periods of the benchmark's own training record); and a validation
/// period of a fresh realization.
/// The default job's records: training output, validation input and output.
struct DefaultRecords {
    y: Vec<f64>,
    val_u: Vec<f64>,
    val_y: Vec<f64>,
}

fn default_records() -> Result<DefaultRecords, Error> {
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

/// `v` to six significant digits: fixed-point for magnitudes in [1e-3, 1e6), else exponent.
fn six_digits(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 || !a.is_finite() {
        format!("{v}")
    } else if (1e-3..1e6).contains(&a) {
        let decimals = (5 - a.log10().floor() as i32).max(0) as usize;
        format!("{v:.decimals$}")
    } else {
        format!("{v:.5e}")
    }
}

/// The oscillator in the reports' short form (m, c, k, the restoring element's parameters),
/// with any extra force terms that are on.
fn osc_json(o: &Oscillator) -> serde_json::Value {
    use hyst::model::Restoring;
    use serde_json::json;
    let mut v = match &o.restoring {
        Restoring::None => json!({"m": o.mass, "c": o.damping, "k": o.stiffness}),
        Restoring::Zener(z) => {
            json!({"m": o.mass, "c": o.damping, "k": o.stiffness, "k_inf": z.k_inf, "omega": z.omega})
        }
        Restoring::BoucWen(b) => {
            json!({"m": o.mass, "c": o.damping, "k": o.stiffness, "alpha": b.alpha,
            "beta_gamma": b.beta_gamma(), "beta_delta": b.beta_delta(), "nu": b.nu})
        }
    };
    if let Some(m) = v.as_object_mut() {
        hyst::params::insert_extras(m, &o.extras);
    }
    v
}

/// The amplitude spectrum of the force each Bouc-Wen candidate implies, over the
/// excitation's band (dB re 1 N): the flatness fit is flat where the mapped models are not.
fn implied_input_figure(
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

/// Figures like the paper's 3(a) (the correlation function) and 5 (time and PSD overlays of
/// the identified models on the first validation record).
/// The record's PSD (Welch, 4096-sample segments) beside the Zener spectral fit's, over the
/// fitted band, with the fit's noise floor.
fn zener_spectrum_figure(
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

fn ident_figures(
    dir: &std::path::Path,
    id: &hyst::ident::Identification,
    bouc_wen: Option<&Oscillator>,
    validations: &[(String, Vec<f64>, Vec<f64>, bool)],
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
    let Some((name, u, y, periodic)) = validations.first() else {
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
fn excitation_band(a: &IdentArgs) -> Result<Option<hyst::ident::flatness::ExcitationBand>, Error> {
    use hyst::ident::flatness::ExcitationBand;
    match (&a.excitation_band, a.period) {
        (None, None) if a.data.is_none() => Ok(Some(ExcitationBand::benchmark())),
        (None, None) => Ok(None),
        (None, Some(_)) => Err(fail("--period needs --excitation-band LO:HI")),
        (Some(_), None) => Err(fail(
            "--excitation-band needs --period (samples per period of the excitation)",
        )),
        (Some(b), Some(period)) => {
            let bad = || {
                fail(format!(
                    "--excitation-band `{b}` is not LO:HI with 0 <= LO < HI (Hz)"
                ))
            };
            let (lo, hi) = b.split_once(':').ok_or_else(bad)?;
            let (lo, hi): (f64, f64) = (
                lo.trim().parse().map_err(|_| bad())?,
                hi.trim().parse().map_err(|_| bad())?,
            );
            if !(lo.is_finite() && hi.is_finite() && lo >= 0.0 && lo < hi) {
                return Err(bad());
            }
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

/// The column `column` of the CSV record `path` after its first `skip` rows, which must
/// leave some.
fn output_after_skip(path: &std::path::Path, column: &str, skip: usize) -> Result<Vec<f64>, Error> {
    let t = read_csv(path)?;
    let col = t.column(column)?;
    if skip >= col.len() {
        return Err(fail(format!(
            "--skip {skip} leaves none of the {} rows of {}",
            col.len(),
            path.display()
        )));
    }
    Ok(col[skip..].to_vec())
}

fn ident(a: &IdentArgs) -> Result<(), Error> {
    use hyst::ident::{self, DampingGuess, IdentOptions, Linearization};
    use serde_json::json;
    let mass = a.mass.unwrap_or(2.0);
    // (name, u, y, periodic)
    let mut validations: Vec<(String, Vec<f64>, Vec<f64>, bool)> = Vec::new();
    let (y, fs, source) = match &a.data {
        Some(path) => {
            let fs = check_fs(a.fs.ok_or_else(|| fail("--fs is required with --data"))?)?;
            if a.mass.is_none() {
                return Err(fail(
                    "--mass is required with --data: the mapping from poles to stiffness needs the mass",
                ));
            }
            let y = output_after_skip(path, &a.output_column, a.skip)?;
            (y, fs, path.display().to_string())
        }
        None => {
            let d = default_records()?;
            validations.push((
                "built-in: benchmark, fresh 50 N multisine".into(),
                d.val_u,
                d.val_y,
                true,
            ));
            (
                d.y,
                750.0,
                "built-in: benchmark, 50 N multisine, 4 periods, noise 7.4e-6 m".to_string(),
            )
        }
    };
    for v in &a.validate {
        let t = read_csv(v)?;
        let name = v.display().to_string();
        let periodic = v
            .file_name()
            .map(|f| f.to_string_lossy().contains("multisine"))
            .unwrap_or(false);
        validations.push((
            name,
            t.column(&a.input_column)?.to_vec(),
            t.column(&a.output_column)?.to_vec(),
            periodic,
        ));
    }
    let choices: Vec<Linearization> = match a.linearization {
        Some(LinearizationArg::Paper) => vec![Linearization::Paper],
        Some(LinearizationArg::Harmonic) => vec![Linearization::Harmonic],
        None if validations.is_empty() => vec![Linearization::Harmonic],
        None => vec![Linearization::Harmonic, Linearization::Paper],
    };
    let excitation = excitation_band(a)?;
    let t0 = std::time::Instant::now();
    let damping_guess = match (a.c, a.damping) {
        (Some(c), _) if c.is_finite() && c >= 0.0 => DampingGuess::Value(c),
        (Some(c), _) => return Err(fail(format!("--c must be a number >= 0 N s/m, got {c}"))),
        (None, DampingArg::Spectrum) => DampingGuess::ZenerSpectrum,
        (None, DampingArg::Cluster) => DampingGuess::LowDampingCluster,
    };
    let opts = IdentOptions {
        mass,
        linearization: choices[0],
        excitation,
        damping_guess,
        ..IdentOptions::default()
    };
    let id = match ident::identify(&y, fs, &opts) {
        Ok(id) => id,
        Err(
            e @ (ident::IdentError::NoStablePair { .. }
            | ident::IdentError::PairNotSupported { .. }),
        ) => {
            // Save the diagram the user needs to see why.
            let path = a
                .svg_dir
                .clone()
                .unwrap_or_else(|| PathBuf::from("."))
                .join("stabilization.svg");
            let saved = ident::prepare(&y, fs, &opts)
                .and_then(|p| ident::run_ssi(&p, &opts).map(|r| (p, r)))
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
            return Err(fail(match saved {
                Some(()) => format!("{source}: {e}; diagram saved to {}", path.display()),
                None => format!("{source}: {e}"),
            }));
        }
        Err(e) => return Err(fail(format!("{source}: {e}"))),
    };
    // The other mappings share steps 1-3: only the models are built again.
    let mut mapped = vec![(choices[0], id.models.bouc_wen_mapped)];
    for lin in &choices[1..] {
        let o = IdentOptions {
            linearization: *lin,
            ..opts.clone()
        };
        let models = ident::build_models(&id.poles, &id.prepared, &o)
            .map_err(|e| fail(format!("{source}: {e}")))?;
        mapped.push((*lin, models.bouc_wen_mapped));
    }
    let ident_seconds = t0.elapsed().as_secs_f64();
    let lin_name = |l: &Linearization| match l {
        Linearization::Paper => "paper",
        Linearization::Harmonic => "harmonic",
    };
    // Bouc-Wen candidates: the flatness fit (if any), then each mapping.
    let mut candidates: Vec<(String, Oscillator)> = Vec::new();
    if let Some(f) = &id.flatness {
        candidates.push(("flatness".into(), f.model));
    }
    for (lin, b) in &mapped {
        if let Some(b) = b {
            candidates.push((lin_name(lin).into(), *b));
        }
    }
    let validate_on = |m: Option<&Oscillator>| -> Vec<serde_json::Value> {
        validations
            .iter()
            .map(|(name, u, yv, periodic)| match m {
                None => json!({"file": name, "epsilon": null}),
                Some(m) => match ident::validate(m, u, yv, fs, *periodic) {
                    Ok(v) => json!({"file": name, "epsilon": v.epsilon, "rms": v.rms}),
                    Err(e) => json!({"file": name, "error": e.to_string()}),
                },
            })
            .collect()
    };
    let cand_rows: Vec<Vec<serde_json::Value>> = candidates
        .iter()
        .map(|(_, m)| validate_on(Some(m)))
        .collect();
    // Keep the candidate that validates best on the first record; without validation data,
    // the first (the flatness fit when the band is known, else the harmonic mapping).
    let score = |rows: &Vec<serde_json::Value>| {
        rows.first()
            .and_then(|r| r["epsilon"].as_f64())
            .unwrap_or(f64::INFINITY)
    };
    let best = (0..candidates.len())
        .min_by(|&i, &j| score(&cand_rows[i]).total_cmp(&score(&cand_rows[j])))
        .unwrap_or(0);
    let bouc_wen = candidates.get(best).map(|c| c.1);
    let route = candidates
        .get(best)
        .map_or("none".to_string(), |c| c.0.clone());
    let lin_rows = validate_on(Some(&id.models.linear));
    let zen_rows = validate_on(id.models.zener.as_ref());
    let table: Vec<serde_json::Value> = validations
        .iter()
        .enumerate()
        .map(|(i, (name, ..))| {
            json!({"file": name, "linear": lin_rows[i], "zener": zen_rows[i],
                "bouc_wen": cand_rows.get(best).map(|r| r[i].clone())})
        })
        .collect();
    let eps = |v: &serde_json::Value| {
        v["epsilon"]
            .as_f64()
            .map_or("-".to_string(), |e| format!("{:.3} %", 100.0 * e))
    };
    println!("record: {source}");
    println!(
        "prepared: fs {} Hz (decimation {}), dominant {:.2} Hz, sigma_x {:.3e}, skewness {:.3}, kurtosis {:.3}",
        id.prepared.fs,
        id.prepared.decimation,
        id.prepared.dominant_hz,
        id.prepared.sigma_x,
        id.prepared.skewness,
        id.prepared.kurtosis
    );
    let real = id
        .poles
        .real
        .map_or("none".to_string(), |r| format!("{r:.4} rad/s"));
    println!(
        "pair {:.4} rad/s, real pole {real}, c = {:.3} ({})",
        id.poles.pair, id.poles.c, id.poles.c_source
    );
    println!("linear: {}", osc_json(&id.models.linear));
    if let Some(z) = &id.models.zener {
        println!("zener: {}", osc_json(z));
    }
    if let Some(f) = &id.zener_spectrum {
        println!(
            "zener spectral fit (white force, {} frequencies up to {:.1} Hz, misfit {:.3}): c = {:.3} ± {:.3} N s/m{}, k = {:.1} ± {:.1} N/m, k_inf = {:.1} ± {:.1} N/m, omega = {:.3} ± {:.3} rad/s; force density {:.4e} ± {:.1e} N^2 s, noise std {:.3e}",
            f.bins,
            f.max_frequency_hz,
            f.misfit,
            f.c,
            f.se[0],
            f.unconstrained_c.map_or(String::new(), |[c, se]| format!(
                " (held at 0: the most likely c is {c:.3} ± {se:.3})"
            )),
            f.k,
            f.se[1],
            f.k_inf,
            f.se[2],
            f.omega,
            f.se[3],
            f.force_density,
            f.force_density_se,
            f.noise_std
        );
    }
    if let Some(f) = &id.flatness {
        println!(
            "flatness fit: {} periods averaged (aperiodicity {}), bins {}..={}, spread of |U| over the band {:.3} dB -> {:.3} dB in {} iterations, implied input RMS {:.3} N",
            f.periods,
            f.aperiodicity
                .map_or("-".to_string(), |a| format!("{a:.3}")),
            f.bins.0,
            f.bins.1,
            f.start_spread_db,
            f.spread_db,
            f.iterations,
            f.input_rms
        );
    }
    for ((name, m), rows) in candidates.iter().zip(&cand_rows) {
        let tag = if name == &route { " (kept)" } else { "" };
        println!("bouc_wen [{name}]{tag}: {}", osc_json(m));
        for r in rows {
            println!(
                "  validation {}: {}",
                r["file"].as_str().unwrap_or(""),
                eps(r)
            );
        }
    }
    for r in &table {
        println!(
            "validation {}: linear {}, zener {}, bouc_wen [{route}] {}",
            r["file"].as_str().unwrap_or(""),
            eps(&r["linear"]),
            eps(&r["zener"]),
            eps(&r["bouc_wen"])
        );
    }
    for n in id
        .poles
        .notes
        .iter()
        .chain(&id.models.notes)
        .chain(&id.ssi.notes)
    {
        println!("note: {n}");
    }
    if id.zener_spectrum.is_some() && a.excitation_band.is_none() {
        println!(
            "note: one record maps to Bouc-Wen through one amplitude; records of the same \
             structure at several force levels map to one Bouc-Wen model together: hyst levels"
        );
    }
    println!("identification time: {:.3} s", ident_seconds);
    if let Some(path) = &a.json {
        let doc = json!({
            "record": source,
            "linearization": lin_name(&choices[0]),
            "bouc_wen_route": route,
            "prepared": {"fs_hz": id.prepared.fs, "decimation": id.prepared.decimation, "dominant_hz": id.prepared.dominant_hz,
                "sigma_x": id.prepared.sigma_x, "skewness": id.prepared.skewness, "kurtosis": id.prepared.kurtosis},
            "poles": {"pair": [id.poles.pair.re, id.poles.pair.im], "real": id.poles.real, "c_source": id.poles.c_source},
            "amplitude": id.models.amplitude,
            "linear": osc_json(&id.models.linear),
            "zener": id.models.zener.as_ref().map(osc_json),
            "zener_spectrum": id.zener_spectrum.as_ref().map(|f| json!({"c": f.c, "k": f.k, "k_inf": f.k_inf, "omega": f.omega,
                "se": {"c": f.se[0], "k": f.se[1], "k_inf": f.se[2], "omega": f.se[3]}, "unconstrained_c": f.unconstrained_c,
                "force_density": f.force_density, "force_density_se": f.force_density_se, "noise_std": f.noise_std,
                "misfit": f.misfit, "frequencies": f.bins, "max_frequency_hz": f.max_frequency_hz})),
            "bouc_wen": bouc_wen.as_ref().map(osc_json),
            "bouc_wen_candidates": candidates.iter().zip(&cand_rows).map(|((n, m), r)| json!({"route": n, "model": osc_json(m), "validation": r})).collect::<Vec<_>>(),
            "flatness": id.flatness.as_ref().map(|f| json!({"periods": f.periods, "aperiodicity": f.aperiodicity, "bins": [f.bins.0, f.bins.1],
                "start_spread_db": f.start_spread_db, "spread_db": f.spread_db, "iterations": f.iterations, "input_rms": f.input_rms})),
            "validation": table,
            "notes": id.poles.notes.iter().chain(&id.models.notes).chain(&id.ssi.notes).collect::<Vec<_>>(),
            "identification_seconds": ident_seconds,
        });
        std::fs::write(path, serde_json::to_string_pretty(&doc)?)
            .map_err(|e| fail(format!("{}: {e}", path.display())))?;
    }
    if let Some(dir) = &a.svg_dir {
        std::fs::create_dir_all(dir).map_err(|e| fail(format!("{}: {e}", dir.display())))?;
        let p = dir.join("stabilization.svg");
        let svg = hyst::covssi::svg::stabilization_svg(
            &id.ssi.diagram,
            Some(4.0 * id.prepared.dominant_hz),
            "Stabilization diagram (output only)",
        );
        std::fs::write(&p, svg).map_err(|e| fail(format!("{}: {e}", p.display())))?;
        ident_figures(dir, &id, bouc_wen.as_ref(), &validations)?;
        if let Some(f) = &id.zener_spectrum {
            zener_spectrum_figure(&dir.join("zener_spectrum.svg"), &y, fs, f)?;
        }
        if let Some(band) = excitation.filter(|_| id.flatness.is_some()) {
            implied_input_figure(dir, &candidates, &y, fs, &band)?;
        }
    }
    Ok(())
}

fn parse_rows(s: &str, what: &str, len: usize) -> Result<(usize, usize), Error> {
    let bad = || {
        fail(format!(
            "{what} `{s}` is not A:B with 0 <= A < B <= {len} (the record's rows)"
        ))
    };
    let (a, b) = s.split_once(':').ok_or_else(bad)?;
    let (a, b): (usize, usize) = (
        a.trim().parse().map_err(|_| bad())?,
        b.trim().parse().map_err(|_| bad())?,
    );
    if a >= b || b > len {
        return Err(bad());
    }
    Ok((a, b))
}

/// Residual spectra (estimation rows) of the baseline and the final model, both models
/// against the measured output over the first second of the first test range, and the
/// restoring-force surface of the baseline's residual (its map over the phase plane and its
/// two sections, the final model's sections beside them).
fn refine_figures(
    dir: &std::path::Path,
    r: &hyst::ident::refine::Refinement,
    rec: &hyst::ident::refine::Record<'_>,
    estimate: (usize, usize),
    test: (usize, usize),
    fit_mass: bool,
) -> Result<(), Error> {
    use hyst::ident::refine::{response, surface};
    use hyst::plot::{cell_map, chart, chart_log_y, colors};
    std::fs::create_dir_all(dir).map_err(|e| fail(format!("{}: {e}", dir.display())))?;
    let y = &rec.y[estimate.0..estimate.1];
    let resid = |m: &hyst::model::Oscillator| -> Vec<f64> {
        response(m, rec, estimate)
            .map(|h| y.iter().zip(&h).map(|(a, b)| a - b).collect())
            .unwrap_or_default()
    };
    let psd = |v: &[f64]| -> Vec<(f64, f64)> {
        let (f, s) = hyst::ident::welch_psd(v, rec.fs, 512);
        f.into_iter().zip(s).collect()
    };
    chart_log_y(
        &dir.join("residual_spectra.svg"),
        "Residual spectra (estimation rows)",
        "f (Hz)",
        "PSD",
        &[
            ("baseline".into(), psd(&resid(&r.baseline)), colors::BLUE),
            ("after the loop".into(), psd(&resid(&r.model)), colors::RED),
        ],
    )?;
    let n = ((rec.fs) as usize).min(test.1 - test.0);
    let t = |v: &[f64]| -> Vec<(f64, f64)> {
        v.iter()
            .take(n)
            .enumerate()
            .map(|(k, x)| (k as f64 / rec.fs, *x))
            .collect()
    };
    let mut series = vec![(
        "measured".to_string(),
        t(&rec.y[test.0..test.1]),
        colors::BLACK,
    )];
    for (label, m, c) in [
        ("baseline", &r.baseline, colors::BLUE),
        ("after the loop", &r.model, colors::RED),
    ] {
        if let Some(h) = response(m, rec, test) {
            series.push((label.to_string(), t(&h), c));
        }
    }
    chart(
        &dir.join("time_overlay.svg"),
        &format!("Test rows {}:{} (first second)", test.0, test.1),
        "t (s)",
        "y",
        &series,
    )?;
    let first = surface::trace(&r.baseline, rec, estimate, fit_mass);
    let g = surface::grid(&first, 24);
    cell_map(
        &dir.join("residual_force_cells.svg"),
        "Force the baseline misses over (x, dx/dt), binned",
        "x",
        "dx/dt",
        &g.x_edges,
        &g.v_edges,
        &g.mean,
    )
    .map_err(fail)?;
    if let Some(f) = &first.fit {
        // The fit on the same cells: the shape, without the noise of the binned means.
        let centre = |e: &[f64], i: usize| 0.5 * (e[i] + e[i + 1]);
        let fitted: Vec<Vec<Option<f64>>> = (0..g.x_edges.len() - 1)
            .map(|i| {
                (0..g.v_edges.len() - 1)
                    .map(|j| {
                        g.mean[i][j].map(|_| f.fitted(centre(&g.x_edges, i), centre(&g.v_edges, j)))
                    })
                    .collect()
            })
            .collect();
        cell_map(
            &dir.join("residual_force_surface.svg"),
            "Fitted surface of the force the baseline misses",
            "x",
            "dx/dt",
            &g.x_edges,
            &g.v_edges,
            &fitted,
        )
        .map_err(fail)?;
    }
    let sections = |stiffness: bool| {
        let mut series = Vec::new();
        for (label, f, c) in [
            ("baseline", first.fit.as_ref(), colors::BLUE),
            ("after the loop", r.trace.fit.as_ref(), colors::RED),
        ] {
            let Some(f) = f else { continue };
            let fitted = f.fitted_sections(41);
            let (binned, fitted) = if stiffness {
                (f.stiffness_section.clone(), fitted.stiffness)
            } else {
                (f.damping_section.clone(), fitted.damping)
            };
            series.push((format!("{label}, fitted"), fitted, c));
            // The baseline's binned means, to show what the fit averages.
            if label == "baseline" {
                series.push(("baseline, binned".to_string(), binned, colors::GREY));
            }
        }
        series
    };
    chart(
        &dir.join("residual_force_stiffness.svg"),
        "Missing force where dx/dt ≈ 0 (a stiffness curve)",
        "x",
        "force (N)",
        &sections(true),
    )?;
    chart(
        &dir.join("residual_force_damping.svg"),
        "Missing force where x ≈ 0 (a damping curve)",
        "dx/dt",
        "force (N)",
        &sections(false),
    )?;
    Ok(())
}

fn refine(a: &RefineArgs) -> Result<(), Error> {
    use hyst::ident::refine::{self, Record, Start, noise::NoiseMethod};
    use serde_json::json;
    let fs = check_fs(a.fs)?;
    let t = read_csv(&a.data)?;
    let u = t
        .column(&a.input_column)
        .map_err(|e| fail(format!("{e} (refine needs the input too)")))?;
    let y = t.column(&a.output_column)?;
    let n = y.len();
    let estimate = match &a.estimate {
        Some(s) => parse_rows(s, "--estimate", n)?,
        None => (0, 3 * n / 4),
    };
    let tests: Vec<(usize, usize)> = if a.test.is_empty() {
        vec![(3 * n / 4, n)]
    } else {
        a.test
            .iter()
            .map(|s| parse_rows(s, "--test", n))
            .collect::<Result<_, _>>()?
    };
    if let Some(m) = a.mass
        && !(m.is_finite() && m > 0.0)
    {
        return Err(fail(format!("--mass must be > 0 kg, got {m}")));
    }
    let start = match a.start {
        StartArg::Linear => Start::Linear,
        StartArg::Zener => Start::Zener,
        StartArg::BoucWen => Start::BoucWen,
    };
    let rec = Record {
        u,
        y,
        fs,
        interpolation: match a.input_interpolation {
            InterpolationArg::BandLimited => refine::InputInterpolation::BandLimited,
            InterpolationArg::Linear => refine::InputInterpolation::Linear,
        },
    };
    let t0 = std::time::Instant::now();
    // One line per step on stderr while the loop runs (hidden when stderr is not a terminal).
    let bar = indicatif::ProgressBar::new_spinner();
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    let say = |m: &str| bar.set_message(format!("{:.0} s: {m}", t0.elapsed().as_secs_f64()));
    let r = refine::refine_record_with(&rec, a.mass, start, estimate, &tests, &say)
        .map_err(|e| fail(format!("{}: {e}", a.data.display())));
    bar.finish_and_clear();
    let r = r?;
    let secs = t0.elapsed().as_secs_f64();
    let pct = |v: f64| format!("{:.3} %", 100.0 * v);
    println!(
        "start: {} (asked for {})",
        r.start.used.name(),
        r.start.requested.name()
    );
    for note in &r.start.notes {
        println!("  {note}");
    }
    if a.mass.is_none() {
        println!(
            "  no --mass: the mass is fitted ({:.6e} kg); the missing force is traced with it",
            r.model.mass
        );
    }
    println!(
        "baseline (output-only start, refined with the input): {}",
        osc_json(&r.baseline)
    );
    for s in &r.steps {
        let name = s.effect.map_or("none", |e| e.name());
        println!(
            "step: {name}  (residual peak {:.2} Hz, share above 1.5x resonance {:.2})",
            s.spectrum.peak_hz, s.spectrum.above_resonance
        );
        if let Some(f) = &s.trace {
            println!("    trace: {}", f.signature());
        }
        for e in &s.evidence {
            // The exponent's candidate says which ν it fitted.
            let nu = match (e.effect, e.model.map(|m| m.restoring)) {
                (refine::Effect::HysteresisExponent, Some(hyst::model::Restoring::BoucWen(b))) => {
                    format!("  (ν = {:.3})", b.nu)
                }
                _ => String::new(),
            };
            let held = e.held_out.map_or(String::new(), |g| {
                format!(
                    "  held out {:+.2} % (p {:.1e})",
                    -100.0 * g.relative_gain(),
                    g.p_value
                )
            });
            println!(
                "    {:<19} dBIC {:>12.1}  variance explained {:>7.3}{held}{nu}{}",
                e.effect.name(),
                e.delta_bic,
                e.variance_explained,
                e.rejected
                    .as_ref()
                    .map_or(String::new(), |w| format!("  ({w})"))
            );
        }
        for ((rows, b), af) in tests.iter().zip(&s.before).zip(&s.after) {
            println!(
                "    test {}:{}  eps {} -> {}  rms {:.4e} -> {:.4e}",
                rows.0,
                rows.1,
                pct(b.epsilon),
                pct(af.epsilon),
                b.rms,
                af.rms
            );
        }
    }
    println!("final model: {}", osc_json(&r.model));
    if !r.estimates.is_empty() {
        let list: Vec<String> = r
            .estimates
            .iter()
            .map(|e| format!("{} {} ± {:.2e}", e.name, six_digits(e.value), e.se))
            .collect();
        println!(
            "  with standard errors (output error, blocks of {} rows, coloured residual allowed): {}",
            refine::SE_BLOCK_ROWS,
            list.join(", ")
        );
    }
    match &r.noise {
        Ok(nl) => {
            let how = match nl.method {
                NoiseMethod::PeriodToPeriod { period, pairs } => {
                    format!("from the output one period ({period} samples) apart, {pairs} pairs")
                }
                NoiseMethod::OutOfBand { share } => format!(
                    "from the residual's spectrum where the input has no power ({:.0} % of the band; white noise assumed)",
                    100.0 * share
                ),
                NoiseMethod::Residual { out_of_band } => format!(
                    "the residual itself: above the level out of band ({out_of_band:.4e}) but no function of (x, dx/dt), of time or of the input, so coloured noise"
                ),
            };
            let eps: Vec<String> = r.noise_epsilon.iter().map(|e| pct(*e)).collect();
            println!(
                "noise level: {:.4e} (eps {} on the test rows), {how}",
                nl.std,
                eps.join(", ")
            );
        }
        Err(why) => println!("noise level: unknown ({why})"),
    }
    if r.nonstationary {
        println!("nonstationary: the halves of the estimation rows differ:");
        for h in refine::drift::drifting(&r.halves) {
            println!(
                "    {} {} ± {:.2e} then {} ± {:.2e} (z = {:.1})",
                h.name,
                six_digits(h.first.0),
                h.first.1,
                six_digits(h.second.0),
                h.second.1,
                h.z
            );
        }
    }
    match &r.unexplained {
        Some(u) => println!(
            "unexplained: the held-out residual is {:.2} × the noise level; the missing force: {}",
            u.residual_to_noise, u.signature
        ),
        None if r.noise.is_ok() => println!("the held-out residual is at the noise level"),
        None => {}
    }
    if let Some(dir) = &a.svg_dir {
        refine_figures(dir, &r, &rec, estimate, tests[0], a.mass.is_none())?;
    }
    println!("time: {secs:.1} s");
    if let Some(path) = &a.json {
        let first = r
            .steps
            .iter()
            .find_map(|s| s.effect)
            .map_or("none", |e| e.name());
        let base_err: Vec<_> = r
            .steps
            .first()
            .map(|s| s.before.clone())
            .unwrap_or_default();
        let finite = |v: f64| if v.is_finite() { json!(v) } else { json!(null) };
        let steps: Vec<_> = r
            .steps
            .iter()
            .map(|s| {
                json!({
                    "effect": s.effect.map_or("none", |e| e.name()),
                    "evidence": s.evidence.iter().map(|e| json!({
                        "effect": e.effect.name(), "delta_bic": finite(e.delta_bic),
                        "variance_explained": e.variance_explained, "rejected": e.rejected,
                        "held_out_p_value": e.held_out.map(|g| g.p_value),
                        "held_out_gain": e.held_out.map(|g| finite(g.relative_gain())),
                    })).collect::<Vec<_>>(),
                    "residual_peak_hz": s.spectrum.peak_hz,
                    "residual_share_above_resonance": s.spectrum.above_resonance,
                    "trace_signature": s.trace.as_ref().map(|f| f.signature()),
                    "p_value": s.gain.map(|g| g.p_value),
                    "held_out_gain": s.gain.map(|g| g.relative_gain()),
                    "error_before": s.before.first().map(|v| v.epsilon),
                    "error_after": s.after.first().map(|v| v.epsilon),
                })
            })
            .collect();
        let test_rows: Vec<_> = tests
            .iter()
            .enumerate()
            .map(|(i, rows)| {
                json!({
                    "rows": [rows.0, rows.1],
                    "rms_before": base_err.get(i).map(|v| v.rms),
                    "rms_after": r.tests.get(i).map(|v| v.rms),
                    "error_before": base_err.get(i).map(|v| v.epsilon),
                    "error_after": r.tests.get(i).map(|v| v.epsilon),
                    "noise_error": r.noise_epsilon.get(i).copied().map(finite),
                })
            })
            .collect();
        let noise = match &r.noise {
            Ok(nl) => json!({
                "std": nl.std,
                "epsilon": r.noise_epsilon.first().copied().map(finite),
                "method": match nl.method {
                    NoiseMethod::PeriodToPeriod { .. } => "period_to_period",
                    NoiseMethod::OutOfBand { .. } => "out_of_band",
                    NoiseMethod::Residual { .. } => "residual",
                },
            }),
            Err(_) => json!(null),
        };
        let doc = json!({
            "effect": first,
            "error_before": base_err.first().map(|v| v.epsilon),
            "error_after": r.tests.first().map(|v| v.epsilon),
            "steps": steps,
            "tests": test_rows,
            "model": hyst::params::oscillator_to_json(&r.model),
            "standard_errors": r.estimates.iter().map(|e| (e.name.to_string(), json!(e.se))).collect::<serde_json::Map<_, _>>(),
            "baseline": hyst::params::oscillator_to_json(&r.baseline),
            "start": {"requested": r.start.requested.name(), "used": r.start.used.name(), "notes": r.start.notes},
            "noise_level": noise,
            "noise_unknown": r.noise.as_ref().err(),
            "nonstationary": r.nonstationary,
            "halves": r.halves.iter().map(|h| json!({
                "name": h.name, "first": finite(h.first.0), "first_se": finite(h.first.1),
                "second": finite(h.second.0), "second_se": finite(h.second.1), "z": finite(h.z),
            })).collect::<Vec<_>>(),
            "unexplained": r.unexplained.as_ref().map(|u| json!({
                "residual_to_noise": u.residual_to_noise, "signature": u.signature,
            })),
            "seconds": secs,
        });
        std::fs::write(path, serde_json::to_string_pretty(&doc)?)
            .map_err(|e| fail(format!("{}: {e}", path.display())))?;
    }
    Ok(())
}

/// One line of a Bouc-Wen model: c, k, α, βγ, βδ with their standard errors `se`, βγ and
/// βδ in their unit (they multiply |z|^ν: 1/m only at ν = 1), then `tail` in parentheses;
/// and a line with ν ± `nu_se` when ν was fitted.
fn print_bouc_wen(
    label: &str,
    o: &hyst::model::Oscillator,
    bw: &hyst::model::BoucWen,
    se: &[f64; 5],
    tail: &str,
    nu_se: Option<f64>,
) {
    let unit = if bw.nu == 1.0 {
        "1/m".to_string()
    } else {
        format!("1/(m·N^{:.3})", bw.nu - 1.0)
    };
    println!(
        "{label}: c {:.2} ± {:.2} N s/m, k {:.0} ± {:.0} N/m, α {:.0} ± {:.0} N/m, βγ {:.1} ± {:.1} {unit}, βδ {:.1} ± {:.1} {unit} ({tail})",
        o.damping,
        se[0],
        o.stiffness,
        se[1],
        bw.alpha,
        se[2],
        bw.beta_gamma(),
        se[3],
        bw.beta_delta(),
        se[4],
    );
    if let Some(nu_se) = nu_se {
        println!("  exponent ν {:.3} ± {nu_se:.3}", bw.nu);
    }
}

fn levels(a: &LevelsArgs) -> Result<(), Error> {
    use hyst::ident::{self, IdentOptions};
    use serde_json::json;
    let fs = check_fs(a.fs)?;
    if !(a.mass.is_finite() && a.mass > 0.0) {
        return Err(fail(format!("--mass must be > 0 kg, got {}", a.mass)));
    }
    let opts = IdentOptions {
        mass: a.mass,
        ..IdentOptions::default()
    };
    let mut fits = Vec::with_capacity(a.data.len());
    let mut sigma_x = Vec::with_capacity(a.data.len());
    let mut lengths = Vec::with_capacity(a.data.len());
    let mut rows = Vec::new();
    for path in &a.data {
        let name = path.display().to_string();
        let y = output_after_skip(path, &a.output_column, a.skip)?;
        let id = ident::identify(&y, fs, &opts).map_err(|e| fail(format!("{name}: {e}")))?;
        sigma_x.push(id.prepared.sigma_x);
        lengths.push(y.len());
        let f = id.zener_spectrum.ok_or_else(|| {
            fail(format!(
                "{name}: no Zener spectral fit, so no level for the model ({}); each record must \
                 be the response to a broadband random force",
                id.poles.notes.join("; ")
            ))
        })?;
        println!(
            "{name}: c {:.2} ± {:.2} N s/m, k {:.0} ± {:.0} N/m, k∞ {:.0} ± {:.0} N/m, Ω {:.2} ± {:.2} rad/s, force density {:.4} N² s",
            f.c, f.se[0], f.k, f.se[1], f.k_inf, f.se[2], f.omega, f.se[3], f.force_density
        );
        rows.push(
            json!({"file": name, "c": f.c, "k": f.k, "k_inf": f.k_inf, "omega": f.omega,
            "se": f.se, "force_density": f.force_density, "misfit": f.misfit}),
        );
        fits.push(f);
    }
    let refs: Vec<_> = fits.iter().collect();
    let model = if a.fit_exponent {
        ident::levels::bouc_wen_and_exponent_from_levels(&refs)
    } else {
        ident::levels::bouc_wen_from_levels(&refs)
    }
    .map_err(|e| fail(e.to_string()))?;
    let o = &model.oscillator;
    let hyst::model::Restoring::BoucWen(bw) = &o.restoring else {
        return Err(fail("the levels' model has no Bouc-Wen element"));
    };
    let se = model.se;
    print_bouc_wen(
        "Bouc-Wen of all levels",
        o,
        bw,
        &se,
        &format!("χ² per degree of freedom {:.2}", model.chi2_per_dof),
        a.fit_exponent.then_some(model.nu_se),
    );
    let values = [bw.alpha, bw.beta_gamma(), bw.beta_delta()];
    if values
        .iter()
        .zip(&se[2..])
        .any(|(v, s)| s.partial_cmp(&v.abs()) != Some(std::cmp::Ordering::Less))
    {
        println!(
            "warning: the levels do not determine α, βγ and βδ (a standard error as large as \
             its value): their response levels are too close together; record levels further apart"
        );
    }
    // The model's own statistical linearization at each level's force density, beside the
    // Zener identified there: how well one element explains every level.
    let own: Vec<Option<hyst::model::ZenerParams>> = fits
        .iter()
        .map(|f| {
            hyst::linearize::statistical::equivalent_zener(
                o.mass,
                o.damping,
                o.stiffness,
                bw,
                f.force_density,
            )
            .ok()
            .map(|(z, _)| z)
        })
        .collect();
    let show = |v: Option<f64>, digits: usize| v.map_or("—".into(), |v| format!("{v:.digits$}"));
    for ((r, m), (f, z)) in rows
        .iter_mut()
        .zip(&model.moments)
        .zip(fits.iter().zip(&own))
    {
        r["sigma_v"] = json!(m.sigma_v);
        r["sigma_z"] = json!(m.sigma_z);
        r["rho"] = json!(m.rho);
        r["model_k_inf"] = json!(z.map(|z| z.k_inf));
        r["model_omega"] = json!(z.map(|z| z.omega));
        println!(
            "  {}: k∞ {:.0} ± {:.0} (model {}), Ω {:.2} ± {:.2} (model {})",
            r["file"].as_str().unwrap_or(""),
            f.k_inf,
            f.se[2],
            show(z.map(|z| z.k_inf), 0),
            f.omega,
            f.se[3],
            show(z.map(|z| z.omega), 2)
        );
    }
    if let Some(dir) = &a.svg_dir {
        use hyst::plot::{chart, colors};
        std::fs::create_dir_all(dir).map_err(|e| fail(format!("{}: {e}", dir.display())))?;
        let at = |v: &dyn Fn(usize) -> Option<f64>| -> Vec<(f64, f64)> {
            (0..fits.len())
                .filter_map(|i| v(i).map(|y| (sigma_x[i], y)))
                .collect()
        };
        for (j, file, title, yl) in [
            (
                2,
                "levels_kinf.svg",
                "Zener stiffness k∞ by level",
                "k∞ (N/m)",
            ),
            (
                3,
                "levels_omega.svg",
                "Corner frequency Ω by level",
                "Ω (rad/s)",
            ),
        ] {
            let value = |i: usize| if j == 2 { fits[i].k_inf } else { fits[i].omega };
            let model = |i: usize| own[i].map(|z| if j == 2 { z.k_inf } else { z.omega });
            chart(
                &dir.join(file),
                title,
                "σₓ of the record (m)",
                yl,
                &[
                    ("identified".into(), at(&|i| Some(value(i))), colors::BLUE),
                    (
                        "− SE".into(),
                        at(&|i| Some(value(i) - fits[i].se[j])),
                        colors::GREY,
                    ),
                    (
                        "+ SE".into(),
                        at(&|i| Some(value(i) + fits[i].se[j])),
                        colors::GREY,
                    ),
                    (
                        "the model's statistical linearization".into(),
                        at(&model),
                        colors::BLACK,
                    ),
                ],
            )
            .map_err(fail)?;
        }
    }
    let mut validation = Vec::new();
    let by_sim = if a.by_simulation {
        eprintln!("fitting by simulation…");
        let t0 = std::time::Instant::now();
        let report = |it: usize, cost: f64| {
            eprintln!(
                "  iteration {it}: weighted sum of squares {cost:.2} ({:.1} s)",
                t0.elapsed().as_secs_f64()
            )
        };
        let s = ident::levels::bouc_wen_by_simulation(
            &refs,
            &lengths,
            o,
            &ident::levels::SimulationOptions {
                periodic: a.data_periodic,
                fit_exponent: a.fit_exponent,
                ..Default::default()
            },
            &report,
        )
        .map_err(|e| fail(format!("fit by simulation: {e}")))?;
        let hyst::model::Restoring::BoucWen(b) = &s.oscillator.restoring else {
            return Err(fail("the fit by simulation has no Bouc-Wen element"));
        };
        print_bouc_wen(
            "Bouc-Wen by simulation",
            &s.oscillator,
            b,
            &s.se,
            &format!(
                "whitened residual RMS {:.2}, {} iterations",
                s.residual_rms, s.iterations
            ),
            a.fit_exponent.then_some(s.nu_se),
        );
        Some(s)
    } else {
        None
    };
    for v in &a.validate {
        let name = v.display().to_string();
        let t = read_csv(v)?;
        let (u, yv) = (t.column(&a.input_column)?, t.column(&a.output_column)?);
        let r =
            ident::validate(o, u, yv, fs, a.periodic).map_err(|e| fail(format!("{name}: {e}")))?;
        println!("validation on {name}: ε = {:.3} %", 100.0 * r.epsilon);
        let mut row = json!({"file": name, "epsilon": r.epsilon, "rms": r.rms});
        if let Some(s) = &by_sim {
            let r = ident::validate(&s.oscillator, u, yv, fs, a.periodic)
                .map_err(|e| fail(format!("{name}: {e}")))?;
            println!(
                "validation on {name}, model by simulation: ε = {:.3} %",
                100.0 * r.epsilon
            );
            row["epsilon_by_simulation"] = json!(r.epsilon);
        }
        validation.push(row);
    }
    if let Some(path) = &a.json {
        let doc = json!({
            "levels": rows,
            "model": osc_json(o),
            "se": {"c": se[0], "k": se[1], "alpha": se[2], "beta_gamma": se[3], "beta_delta": se[4],
                   "nu": a.fit_exponent.then_some(model.nu_se)},
            "chi2_per_dof": model.chi2_per_dof,
            "by_simulation": by_sim.as_ref().map(|s| json!({
                "model": osc_json(&s.oscillator),
                "se": {"c": s.se[0], "k": s.se[1], "alpha": s.se[2], "beta_gamma": s.se[3], "beta_delta": s.se[4],
                       "nu": a.fit_exponent.then_some(s.nu_se)},
                "residual_rms": s.residual_rms,
                "iterations": s.iterations,
                "simulated": s.simulated,
            })),
            "validation": validation,
        });
        std::fs::write(path, serde_json::to_string_pretty(&doc)?)
            .map_err(|e| fail(format!("{}: {e}", path.display())))?;
    }
    Ok(())
}

/// The files a command will write, with the flag that names each.
fn output_files(c: &Command) -> Vec<(&'static str, &std::path::Path)> {
    let v: Vec<(&'static str, Option<&std::path::Path>)> = match c {
        Command::Simulate(a) => vec![("--out", Some(&a.out))],
        Command::Excite(a) => vec![("--out", Some(&a.out))],
        Command::Ssi(a) => vec![("--json", Some(&a.json)), ("--svg", a.svg.as_deref())],
        Command::Ident(a) => vec![("--json", a.json.as_deref())],
        Command::Refine(a) => vec![("--json", a.json.as_deref())],
        Command::Levels(a) => vec![("--json", a.json.as_deref())],
        Command::Frf(a) => a.output_files(),
    };
    v.into_iter().filter_map(|(f, p)| Some((f, p?))).collect()
}

/// An output file whose folder does not exist is refused before any work: writing it would
/// otherwise fail only after a refinement or a simulation that can take minutes. (Folders
/// given by `--svg-dir` are made.)
fn check_output_folders(c: &Command) -> Result<(), Error> {
    for (flag, path) in output_files(c) {
        let folder = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => std::path::Path::new("."),
        };
        if !folder.is_dir() {
            return Err(fail(format!(
                "{flag} {}: the folder {} does not exist",
                path.display(),
                folder.display()
            )));
        }
    }
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    if let Err(e) = check_output_folders(&cli.command) {
        eprintln!("error: {e}");
        return ExitCode::FAILURE;
    }
    let result = match &cli.command {
        Command::Simulate(a) => simulate(a),
        Command::Excite(a) => excite(a),
        Command::Ssi(a) => ssi(a),
        Command::Ident(a) => ident(a),
        Command::Refine(a) => refine(a),
        Command::Levels(a) => levels(a),
        Command::Frf(a) => frf_cmd::run(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
