//! The command line's commands: the arguments (clap), one module per subcommand, and the
//! helpers they share (reading records, checking flags, a spinner).

use clap::{Parser, Subcommand, ValueEnum};

pub(crate) mod amplitude;
pub(crate) mod args;
pub(crate) mod follow;
pub(crate) mod frf;
pub(crate) mod ident;
pub(crate) mod levels;
#[cfg(test)]
mod parity;
pub(crate) mod refine;
pub(crate) mod simulate;
pub(crate) mod ssi;
pub(crate) mod track;

use frf as frf_cmd;
use ident::IdentArgs;
use levels::LevelsArgs;
use refine::RefineArgs;
use simulate::{ExcitationArgs, SimulateArgs};
use ssi::SsiArgs;

/// Set how records are read (`--format`, `--delimiter`, `--variable`), once, before any
/// command runs.
pub(crate) fn set_read_options(cli: &Cli) {
    READ_OPTIONS.get_or_init(|| {
        hyst::io::ReadOptions::default()
            .with_format(cli.format)
            .with_delimiter(cli.delimiter)
            .with_variable(cli.variable.clone())
            .with_names(cli.names.clone())
    });
}

#[derive(Parser)]
#[command(
    name = "hyst",
    version,
    about = "Identify stiffness and hysteretic damping of vibrating structures from their response",
    long_about = None,
    after_help = "Equation numbers refer to A. Bajrić and J. Høgsberg, \"Estimation of hysteretic damping of structures by stochastic subspace identification\", Mechanical Systems and Signal Processing 105 (2018) 36-50. Start with `hyst ident` (built-in defaults, no data needed)."
)]
pub(crate) struct Cli {
    #[command(subcommand)]
    pub(crate) command: Command,
    /// Format of every record read: by its extension by default (`.npy`, `.npz`, `.mat`,
    /// `.uff`/`.unv`/`.uf`; anything else delimited text).
    #[arg(long, global = true, help_heading = "Reading records (every command)", default_value = "auto", value_parser = named(hyst::io::Format::NAMES, hyst::io::Format::description))]
    pub(crate) format: hyst::io::Format,
    /// Cell separator of every CSV file read: detected from the header line by default.
    #[arg(long, global = true, help_heading = "Reading records (every command)", default_value = "auto", value_parser = named(hyst::io::Delimiter::NAMES, hyst::io::Delimiter::description))]
    pub(crate) delimiter: hyst::io::Delimiter,
    /// The variable of a `.mat` file or the array of a `.npz` archive to read (needed when it
    /// holds more than one array of more than one element); a dotted path (`rec.p1`) reaches
    /// into a `.mat` struct.
    #[arg(
        long,
        global = true,
        help_heading = "Reading records (every command)",
        value_name = "NAME"
    )]
    pub(crate) variable: Option<String>,
    /// The columns' names, in file order, replacing the file's (a headerless file's are
    /// `0`, `1`, …): one for each column.
    #[arg(
        long,
        global = true,
        help_heading = "Reading records (every command)",
        value_name = "A,B,...",
        value_delimiter = ','
    )]
    pub(crate) names: Option<Vec<String>>,
}

/// A `--format` or `--delimiter` value: one of the library's names, each with its description
/// in the help.
fn named<T>(
    names: &'static [&'static str],
    description: fn(T) -> &'static str,
) -> impl clap::builder::TypedValueParser<Value = T>
where
    T: std::str::FromStr<Err = hyst::io::IoError> + Clone + Send + Sync + 'static,
{
    use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
    let values = names.iter().map(move |&name| {
        let value = PossibleValue::new(name);
        match name.parse::<T>() {
            Ok(t) => value.help(description(t)),
            Err(_) => value,
        }
    });
    PossibleValuesParser::new(values).try_map(|s| s.parse::<T>())
}

/// How records are read, from `--format`, `--delimiter` and `--variable`, set once at start.
static READ_OPTIONS: std::sync::OnceLock<hyst::io::ReadOptions> = std::sync::OnceLock::new();

/// Read a record as `--format`, `--delimiter` and `--variable` say.
/// What the reader assumed (a headerless file's names) is said on stderr.
pub(crate) fn read_record(path: &std::path::Path) -> Result<hyst::io::Table, hyst::io::IoError> {
    let t = hyst::io::read_record(path, READ_OPTIONS.get().unwrap_or(&Default::default()))?;
    for note in &t.notes {
        eprintln!("note: {note}");
    }
    Ok(t)
}

#[derive(Subcommand)]
pub(crate) enum Command {
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
    /// Output only: each mode's natural frequency and damping ratio against its vibration
    /// amplitude (random decrement in amplitude bands of each mode's filtered response), each
    /// point with a standard error, and whether the mode is linear.
    ///
    /// Example (the F-16's wing torsion mode at the highest level, amplitudes as displacement):
    ///   hyst amplitude --input msine_level7.csv --fs 400 --columns acc1,acc2,acc3 --skip 8192 --period 8192 --modes 7.3 --measured acceleration --amplitude-of displacement --svg torsion7.svg
    #[command(verbatim_doc_comment)]
    Amplitude(amplitude::AmplitudeArgs),
    /// With the input: the modes of a periodic record's frequency response over a band (an
    /// input-output second opinion on `hyst ssi`), with several outputs each mode's shape,
    /// and optionally the outputs under a force of flat spectrum.
    ///
    /// Example (the F-16 at its lowest level, the wing torsion mode):
    ///   hyst frf --input msine_level1.csv --fs 400 --force force --period 8192 --skip 8192 --band 6.8:7.8 --json torsion.json --svg torsion.svg
    #[command(verbatim_doc_comment, allow_negative_numbers = true)]
    Frf(frf_cmd::FrfArgs),
    /// Structural health monitoring: many records identified as `hyst ssi` does (in
    /// parallel, resumable), their modes tracked against a reference by frequency and MAC,
    /// each mode's frequency modelled on the covariates over a training period, and a CUSUM
    /// of the standardized residuals raising alarms on changes the covariates and the
    /// estimation noise do not explain.
    ///
    /// Example:
    ///   hyst track --inputs records/ --fs 25 --covariates temperature.csv --out monitoring
    #[command(verbatim_doc_comment, allow_negative_numbers = true)]
    Track(track::TrackArgs),
}

/// The command line's error: a library's, or a message naming the flag or file at fault
/// (`anyhow`, in the binary only).
pub(crate) type Error = anyhow::Error;

pub(crate) fn fail(msg: impl Into<String>) -> Error {
    anyhow::anyhow!(msg.into())
}

/// A storey fit named by `flag` (`hyst levels --masses --json`, perhaps `FILE#/POINTER`),
/// read and checked whole before anything else is read beside it: a field that is wrong is
/// said as the document's (`--structure FILE: ...`), not as the record read next.
pub(crate) fn read_storey_fit(
    flag: &str,
    path: &std::path::Path,
) -> Result<hyst::ident::storeys::StoreyFit, Error> {
    let fit: hyst::ident::storeys::StoreyFit = hyst::io::read_document(
        path,
        "a storey fit must be a JSON object (as `hyst levels --masses --json` writes)",
    )?;
    fit.validate()
        .map_err(|e| fail(format!("{flag} {}: {e}", path.display())))?;
    Ok(fit)
}

/// The channels to analyse: those given, else every column but the time column
/// ([`hyst::io::Table::time_column`]), those in `besides` and those that carry no signal
/// ([`hyst::io::default_channels`]), which are named in one line on stderr.
pub(crate) fn channel_names(
    t: &hyst::io::Table,
    given: Option<&[String]>,
    besides: &[&str],
) -> Result<Vec<String>, Error> {
    if let Some(c) = given {
        return Ok(c.to_vec());
    }
    let (names, dropped) = hyst::io::default_channels(t, besides);
    let list: Vec<String> = dropped.iter().map(ToString::to_string).collect();
    if names.is_empty() && !dropped.is_empty() {
        return Err(fail(format!(
            "{}: no channel carries a signal: {}",
            t.path.display(),
            list.join(", ")
        )));
    }
    if !dropped.is_empty() {
        eprintln!(
            "note: {}: {} channel(s) carry no signal and are left out: {} (name the channels to analyse to choose otherwise)",
            t.path.display(),
            dropped.len(),
            list.join(", ")
        );
    }
    Ok(names)
}

/// Output only means responses only: a default channel list that takes in the force is a
/// mistake the user should hear about (the benchmarks' files hold `u,y`).
pub(crate) fn warn_on_force_like(names: &[String]) {
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

/// A spinner on stderr for a step that may take a while (hidden when stderr is not a
/// terminal); its message says what runs.
pub(crate) fn spinner() -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new_spinner();
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    bar
}

/// A bar of a run's steps on stderr (hidden when stderr is not a terminal), its message
/// saying what runs; the caller sets its length and position as the steps come.
pub(crate) fn steps_bar() -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(1);
    if let Ok(style) =
        indicatif::ProgressStyle::with_template("{spinner} [{elapsed}] {bar:20} {pos}/{len} {msg}")
    {
        bar.set_style(style);
    }
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    bar
}

/// `bar` showing the step `p`: its position among the run's steps and what runs.
pub(crate) fn show(bar: &indicatif::ProgressBar, p: covssi::Progress<'_>) {
    bar.set_length(p.total as u64);
    bar.set_position(p.done as u64);
    bar.set_message(p.what.to_string());
}

pub(crate) fn check_fs(fs: f64) -> Result<f64, Error> {
    if fs.is_finite() && fs > 0.0 {
        Ok(fs)
    } else {
        Err(fail(format!(
            "--fs must be a positive number of Hz, got {fs}"
        )))
    }
}

/// The column `column` of the record `path` after its first `skip` rows, which must leave
/// some; and the sampling rate, `fs` or the file's (which must agree when both are there).
pub(crate) fn output_after_skip(
    path: &std::path::Path,
    column: &str,
    skip: usize,
    fs: Option<f64>,
) -> Result<(Vec<f64>, f64), Error> {
    let t = read_record(path)?;
    let fs = check_fs(t.rate(fs)?)?;
    let col = t.column(column)?;
    if skip >= col.len() {
        return Err(fail(format!(
            "--skip {skip} leaves none of the {} rows of {}",
            col.len(),
            path.display()
        )));
    }
    Ok((col[skip..].to_vec(), fs))
}

#[derive(Clone, Copy, ValueEnum, PartialEq, Eq, Debug)]
pub(crate) enum InterpolationArg {
    /// A measured force behind an anti-aliasing filter: windowed-sinc interpolation.
    BandLimited,
    /// Linear between samples, as `hyst simulate` without --periodic drives its models.
    Linear,
}

/// The files a command will write, with the flag that names each.
pub(crate) fn output_files(c: &Command) -> Vec<(&'static str, &std::path::Path)> {
    let v: Vec<(&'static str, Option<&std::path::Path>)> = match c {
        Command::Simulate(a) => vec![("--out", Some(&a.out))],
        Command::Excite(a) => vec![("--out", Some(&a.out))],
        Command::Ssi(a) => return a.output_files(),
        Command::Ident(a) => vec![("--json", a.json.as_deref())],
        Command::Refine(a) => vec![("--json", a.json.as_deref())],
        Command::Levels(a) => vec![("--json", a.json.as_deref())],
        Command::Amplitude(a) => vec![("--json", a.json.as_deref()), ("--svg", a.svg.as_deref())],
        Command::Frf(a) => a.output_files(),
        Command::Track(a) => vec![("--html", a.html.as_deref())],
    };
    v.into_iter().filter_map(|(f, p)| Some((f, p?))).collect()
}

/// The files a command reads, with the flag that names each.
pub(crate) fn input_files(c: &Command) -> Vec<(&'static str, &std::path::Path)> {
    fn one<'a>(
        flag: &'static str,
        p: Option<&'a std::path::PathBuf>,
    ) -> Option<(&'static str, &'a std::path::Path)> {
        p.map(|p| (flag, p.as_path()))
    }
    fn many<'a>(
        flag: &'static str,
        v: &'a [std::path::PathBuf],
    ) -> Vec<(&'static str, &'a std::path::Path)> {
        v.iter().map(|p| (flag, p.as_path())).collect()
    }
    let mut v: Vec<(&'static str, &std::path::Path)> = Vec::new();
    match c {
        Command::Simulate(a) => {
            v.extend(one("--input", a.input.as_ref()));
            v.extend(one("--params", a.params.as_ref()));
            v.extend(one("--structure", a.structure.as_ref()));
            v.extend(one("--measured", a.measured.as_ref()));
        }
        Command::Excite(_) => {}
        Command::Ssi(a) => {
            v.extend(one("--input", a.input.as_ref()));
            v.extend(one("--setups", a.setups.as_ref()));
            v.extend(one("--geometry", a.geometry.as_ref()));
            v.extend(one("--lines", a.lines.as_ref()));
        }
        Command::Amplitude(a) => {
            v.extend(a.input.iter().map(|p| ("--input", p.as_path())));
            v.extend(one("--model", a.model.as_ref()));
        }
        Command::Ident(a) => {
            v.extend(one("--data", a.data.as_ref()));
            v.extend(many("--validate", &a.validate));
        }
        Command::Refine(a) => v.push(("--data", &a.data)),
        Command::Levels(a) => {
            v.extend(many("--data", &a.data));
            v.extend(many("--validate", &a.validate));
        }
        Command::Frf(a) => v.push(("--input", a.input_file())),
        Command::Track(_) => {}
    }
    v
}

/// An output file that is one of the command's inputs, or another output, is refused before
/// anything is read (writing it would destroy the record); one whose folder does not exist
/// is refused before any work: writing it would otherwise fail only after a refinement or a
/// simulation that can take minutes. (Folders given by `--svg-dir` are made.)
pub(crate) fn check_output_folders(c: &Command) -> Result<(), Error> {
    hyst::io::check_outputs(&input_files(c), &output_files(c))?;
    for (flag, path) in output_files(c) {
        if path.is_dir() {
            return Err(fail(format!(
                "{flag} {}: a folder; give the file to write",
                path.display()
            )));
        }
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
