//! The `hyst` command-line program.

use std::path::PathBuf;
use std::process::ExitCode;

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
    #[command(verbatim_doc_comment)]
    Simulate(SimulateArgs),
    /// Generate an excitation record and write it as a one-column CSV `u`.
    Excite(ExcitationArgs),
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
    /// Gaussian white noise.
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
    /// RMS of the excitation (N).
    #[arg(long, default_value_t = 50.0)]
    rms: f64,
    /// Number of samples (for a multisine: one period).
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
    /// Sampling rate (Hz).
    #[arg(long, default_value_t = 750.0)]
    fs: f64,
    /// Output CSV file.
    #[arg(long)]
    out: PathBuf,
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
    /// RMS of the generated excitation (N).
    #[arg(long, default_value_t = 50.0)]
    rms: f64,
    /// Samples of the generated excitation (a multisine: one period, simulated to steady state).
    #[arg(long, default_value_t = 8192)]
    samples: usize,
    /// Seed of the generated excitation.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Lowest excited frequency of the generated excitation (Hz).
    #[arg(long, default_value_t = 5.0)]
    f_min: f64,
    /// Highest excited frequency of the generated excitation (Hz).
    #[arg(long, default_value_t = 150.0)]
    f_max: f64,
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

fn generate(kind: ExcitationKind, a: &ExcitationLike) -> Result<Vec<f64>, Error> {
    Ok(match kind {
        ExcitationKind::Multisine => {
            Multisine::band(a.samples, a.fs, a.f_min, a.f_max, a.rms)?.generate(a.seed)?
        }
        ExcitationKind::White => white_noise(a.samples, a.rms, a.seed)?,
        ExcitationKind::Sweep => Sweep {
            amplitude: a.rms * std::f64::consts::SQRT_2,
            f0: a.f_min,
            f1: a.f_max,
            duration: a.samples as f64 / a.fs,
        }
        .sample(a.samples, a.fs)?,
    })
}

struct ExcitationLike {
    rms: f64,
    samples: usize,
    seed: u64,
    f_min: f64,
    f_max: f64,
    fs: f64,
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
    let u = generate(
        a.excitation,
        &ExcitationLike {
            rms: a.rms,
            samples: a.samples,
            seed: a.seed,
            f_min: a.f_min,
            f_max: a.f_max,
            fs,
        },
    )?;
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
            let u = generate(
                kind,
                &ExcitationLike {
                    rms: a.rms,
                    samples: a.samples,
                    seed: a.seed,
                    f_min: a.f_min,
                    f_max: a.f_max,
                    fs,
                },
            )?;
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
    let mut y = if periodic {
        sim::steady_state_period(&model, &u, fs, &opts, 1e-10, 200)?.y
    } else {
        sim::simulate(&model, Input::Sampled(&u), fs, u.len(), &opts)?
    };
    if a.noise != 0.0 {
        sim::excitation::add_noise(&mut y, a.noise, a.noise_seed)?;
    }
    write_csv(&a.out, &["u", "y"], &[&u, &y])?;
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Simulate(a) => simulate(a),
        Command::Excite(a) => excite(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
