//! `hyst ssi`: output-only modal analysis by covariance-driven SSI and its refinement.

use std::path::{Path, PathBuf};

use clap::Args;

use super::{
    Error, READ_OPTIONS, channel_names, check_fs, fail, read_record, show, steps_bar,
    warn_on_force_like,
};
use hyst::settings::{SettingsError, SsiSettings};

/// How a record's channels are taken: shared by `hyst ssi` and `hyst amplitude` (each names
/// its own `--input`: one record, or several).
#[derive(Args, Debug)]
pub(crate) struct ChannelArgs {
    /// Sampling rate of the file (Hz); a Universal File states its own, and a time column
    /// gives it (a rate given must agree with the column's step within 1 %).
    #[arg(long)]
    pub(crate) fs: Option<f64>,
    /// Channels to analyse, comma-separated; default: every column except the time column
    /// (`t`, `time`, `Time (s)`, … or one increasing by a constant step), with a warning for
    /// columns named like a force: `u`, `force`, `input`, `excitation`, `load`.
    #[arg(long, value_delimiter = ',')]
    pub(crate) columns: Option<Vec<String>>,
    /// The factor each channel's reading carries, one per channel analysed, in their order
    /// (as a setup file's `gain`): each channel is divided by it, so that a sensor mounted
    /// the other way (-1) or in other units reads the structure's motion. Default: 1 each.
    #[arg(
        long,
        value_delimiter = ',',
        allow_hyphen_values = true,
        value_name = "G1,G2,..."
    )]
    pub(crate) gains: Option<Vec<f64>>,
    /// Skip this many leading rows (e.g. a start-up transient).
    #[arg(long, default_value_t = 0)]
    pub(crate) skip: usize,
}

#[derive(Args, Debug)]
pub(crate) struct SsiArgs {
    /// The record: CSV with a header line (or none: columns 0, 1, …); a NumPy `.npy` array or `.npz` archive, or a
    /// MATLAB `.mat` variable (samples × channels, columns named 0, 1, …); a Universal File
    /// of dataset 58 functions (columns named by their point, `12+Z`).
    #[arg(long, required_unless_present = "setups")]
    pub(crate) input: Option<PathBuf>,
    /// Instead of --input: a setup file (CSV: setup, file, column, node, direction,
    /// quantity, reference, gain; see the README) naming several setups of one test that
    /// share reference channels. Each setup is identified alone, then the modes are merged
    /// on the references, with standard errors.
    #[arg(
        long,
        value_name = "FILE",
        conflicts_with_all = ["input", "columns", "skip", "gains", "references", "svg"]
    )]
    pub(crate) setups: Option<PathBuf>,
    #[command(flatten)]
    pub(crate) record: ChannelArgs,
    #[command(flatten)]
    pub(crate) ssi: SsiSettings,
    /// Write the modes, real poles and per-order poles as JSON here (optional: the report is
    /// printed either way).
    #[arg(help_heading = "Output files", long)]
    pub(crate) json: Option<PathBuf>,
    /// Draw the stabilization diagram as SVG here.
    #[arg(help_heading = "Output files", long)]
    pub(crate) svg: Option<PathBuf>,
    /// Write the reported modes' shapes as Universal File dataset 55 here (one dataset per
    /// mode: its complex eigenvalue and, per node, the X, Y, Z entries; channels of a Universal
    /// File at their nodes and directions, others as nodes 1, 2, … along Z). With --setups:
    /// the merged modes, each node's motion, after a dataset 15 of the nodes' positions when
    /// the geometry is known (--geometry, or a pyOMA folder's grid.txt).
    #[arg(help_heading = "Output files", long, value_name = "FILE")]
    pub(crate) shapes_uff: Option<PathBuf>,
    /// Write a report a browser opens here: one self-contained page (no network needed) with
    /// the stabilization diagram over the FDD singular values (each pole's numbers on hover),
    /// the modes with their errors and EFDD's, each mode shape animated on the structure, and
    /// the MAC matrix.
    #[arg(help_heading = "Output files", long, value_name = "FILE")]
    pub(crate) html: Option<PathBuf>,
    /// With --setups: take each floor (the geometry's nodes at one height, z up) that holds a
    /// reference node as rigid in its plane, and say what factor the other channels on it
    /// read against the references (1 when gains, signs and units are as the setups state).
    /// Needs the nodes' positions (a pyOMA folder's grid.txt, or --geometry)
    #[arg(long, requires = "setups")]
    pub(crate) rigid_floors: bool,
    /// With --setups: keep each setup's stabilization diagram and singular values in the
    /// --json report (left out by default: they are nine tenths of it).
    #[arg(long, requires = "setups")]
    pub(crate) json_diagrams: bool,
    /// With --setups: let the setup file name records outside its own folder (absolute
    /// paths, `..`); by default each record is named by its path from that folder.
    #[arg(long, requires = "setups")]
    pub(crate) records_anywhere: bool,
    /// With --setups: the structure's nodes to draw the shapes on (a header line, then
    /// `name x y z` per line; the steel frame's grid.txt). A pyOMA setup folder's own
    /// grid.txt is read without it.
    #[arg(long, value_name = "FILE", requires = "setups")]
    pub(crate) geometry: Option<PathBuf>,
    /// With --geometry: the lines between its nodes (a header line, then two node names per
    /// line; the steel frame's lines.txt).
    #[arg(long, value_name = "FILE", requires = "geometry")]
    pub(crate) lines: Option<PathBuf>,
}

impl SsiArgs {
    /// The files `hyst ssi` will write, with the flag that names each.
    pub(crate) fn output_files(&self) -> Vec<(&'static str, &Path)> {
        [
            ("--json", self.json.as_deref()),
            ("--svg", self.svg.as_deref()),
            ("--shapes-uff", self.shapes_uff.as_deref()),
            ("--html", self.html.as_deref()),
        ]
        .into_iter()
        .filter_map(|(f, p)| Some((f, p?)))
        .collect()
    }
}

/// The analysis SSI's flags ask for ([`SsiSettings`], whose fields are the flags), a
/// setting out of range named by its flag.
pub(crate) fn analysis_of(ssi: &SsiSettings) -> Result<hyst::covssi::AnalysisOptions, Error> {
    ssi.analysis().map_err(|e| setting_error(ssi, e))
}

/// A setting out of range named by its flag.
fn setting_error(ssi: &SsiSettings, e: SettingsError) -> Error {
    match e {
        SettingsError::TooSmall { name, least, value } => fail(format!(
            "--{} must be at least {least}, got {value}",
            name.replace('_', "-")
        )),
        // No record read: no rate, and no reference checked (that needs its channels).
        SettingsError::Ssi(e) => {
            option_error(ssi, &e, 0, None).unwrap_or_else(|| fail(e.to_string()))
        }
        e => fail(e.to_string()),
    }
}

/// The channels to analyse, after `--skip`.
pub(crate) struct Channels {
    pub(crate) names: Vec<String>,
    pub(crate) data: Vec<Vec<f64>>,
    /// The sampling rate, `--fs` or the file's.
    pub(crate) fs: f64,
    /// Where each channel was measured, if the file says.
    pub(crate) points: Option<Vec<hyst::io::MeasurementPoint>>,
    /// What was read, in one line: the channels by name, the samples, the rate and where it
    /// came from, rows skipped and gains (the first thing a user checks on a new record).
    pub(crate) read: String,
}

/// The channels to analyse, after `--skip`, with their names.
pub(crate) fn channels(input: &Path, a: &ChannelArgs) -> Result<Channels, Error> {
    if let Some(fs) = a.fs {
        check_fs(fs)?;
    }
    let mut t = read_record(input)?;
    let fs = check_fs(t.rate(a.fs)?)?;
    let names = channel_names(&t, a.columns.as_deref(), &[])?;
    if a.columns.is_none() {
        warn_on_force_like(&names);
    }
    if let Some(n) = hyst::io::repeated(&names) {
        return Err(fail(format!(
            "--columns names `{n}` twice: each channel once"
        )));
    }
    let rows = t.len();
    let read = read_line(input, &t, &names, a, fs);
    if a.skip >= rows {
        return Err(fail(format!(
            "--skip {} leaves no rows of the {} in {}",
            a.skip,
            rows,
            input.display()
        )));
    }
    // The columns are taken from the table, not copied: a long record is held once.
    let mut channels = Vec::new();
    for n in &names {
        let mut c = t.take_column(n)?;
        c.drain(..a.skip);
        channels.push(c);
    }
    if let Some(gains) = &a.gains {
        hyst::io::divide_by_gains(&names, &mut channels, gains)?;
    }
    // Every name is the table's now: each channel's point, if the file gives them.
    let points = t.points.as_ref().and_then(|p| {
        names
            .iter()
            .map(|n| t.names.iter().position(|m| m == n).map(|i| p[i]))
            .collect::<Option<Vec<_>>>()
    });
    Ok(Channels {
        names,
        data: channels,
        fs,
        points,
        read,
    })
}

/// The line that says what `channels` read from `t` at `fs` Hz: the channels by name (the
/// first and last four of a long list), the samples, the rate and where it came from, rows
/// skipped and gains.
fn read_line(
    input: &Path,
    t: &hyst::io::Table,
    names: &[String],
    a: &ChannelArgs,
    fs: f64,
) -> String {
    let listed = if names.len() > 8 {
        format!(
            "{}, …, {}",
            names[..4].join(", "),
            names[names.len() - 4..].join(", ")
        )
    } else {
        names.join(", ")
    };
    let rate = match (t.rate_hz, t.time_rate()) {
        (Some(_), _) => "as the file states".to_string(),
        (None, Some((name, r))) if (r - fs).abs() <= 1e-9 * fs => {
            format!("from the time column `{name}`")
        }
        // A --fs within the time column's tolerance is what the analysis uses: said so, with
        // the column's, not credited to the column.
        (None, Some((name, r))) => format!("as --fs gives; the time column `{name}` reads {r} Hz"),
        (None, None) => "as --fs gives".to_string(),
    };
    let skipped = match a.skip {
        0 => String::new(),
        k => format!(", the first {k} rows skipped"),
    };
    let gains = a.gains.as_ref().map_or(String::new(), |g| {
        let g: Vec<String> = g.iter().map(|v| format!("{v}")).collect();
        format!("; divided by the gains {}", g.join(", "))
    });
    format!(
        "read {}: {} channel(s) {listed}; {} samples at {fs} Hz ({rate}){skipped}{gains}",
        input.display(),
        names.len(),
        t.len().saturating_sub(a.skip),
    )
}

/// An option out of range (covssi's [`SsiError::InvalidOption`](hyst::covssi::SsiError))
/// named by the flag that set it, with what it must be; `None` for any other error. `fs_used`
/// is the rate analysed, when a record was read (a lag too short for it is said in samples).
fn option_error(
    ssi: &SsiSettings,
    e: &hyst::covssi::SsiError,
    channels: usize,
    fs_used: Option<f64>,
) -> Option<Error> {
    use hyst::covssi::{SsiError, SsiOption};
    if let SsiError::InvalidOption { option, value } = e {
        let lag_too_short = |flag: &str| {
            let at = fs_used.map_or_else(String::new, |fs| format!(" at {fs} Hz"));
            Some(fail(format!(
                "{flag} gives {value} block row(s){at}; SSI needs at least 2: give a longer lag"
            )))
        };
        let flag = match option {
            // A lag given as a time is too short for the rate: say what it gave.
            SsiOption::BlockRows => {
                if ssi.lag_seconds.is_some() {
                    return lag_too_short("--lag-seconds");
                }
                if ssi.lag_periods.is_some() {
                    return lag_too_short("--lag-periods");
                }
                Some(("--block-rows", "at least 2"))
            }
            SsiOption::BlockRowsSeconds => Some(("--lag-seconds", "positive and finite")),
            SsiOption::BlockRowsPeriodsCount => {
                Some(("--lag-periods COUNT", "positive and finite"))
            }
            SsiOption::BlockRowsPeriodsFrequency => {
                Some(("--lag-periods HZ", "positive and finite"))
            }
            SsiOption::ReferenceOutOfRange => {
                return Some(fail(format!(
                    "--references {value} is out of range: {channels} channel(s), numbered from 0"
                )));
            }
            SsiOption::ReferenceRepeated => {
                return Some(fail(format!("--references names channel {value} twice")));
            }
            SsiOption::MaxOrder => Some(("--max-order", "at least 1")),
            SsiOption::ModeMaxDamping => Some(("--max-damping", "between 0 and 1")),
            SsiOption::OrderStep => Some(("--order-step", "at least 1")),
            SsiOption::CriteriaFrequency => Some(("--df", "positive and finite")),
            SsiOption::CriteriaDamping => Some(("--dzeta", "positive and finite")),
            SsiOption::CriteriaMac => Some(("--dmac", "positive and finite")),
            SsiOption::CriteriaReal => Some(("--dreal", "positive and finite")),
            _ => None,
        };
        if let Some((flag, needed)) = flag {
            return Some(fail(format!("{flag} must be {needed}, got {value}")));
        }
    }
    None
}

/// covssi's error in the words of the command line: an option out of range named by the
/// flag that set it, anything else with the file and columns it came from (and the
/// decimation, which may be what made the record too short or constant).
pub(crate) fn flag_error(
    input: &Path,
    ssi: &SsiSettings,
    e: hyst::covssi::SsiError,
    names: &[String],
    fs_used: f64,
) -> Error {
    if let Some(e) = option_error(ssi, &e, names.len(), Some(fs_used)) {
        return e;
    }
    // A channel by its column's name, not its index among those analysed.
    if let hyst::covssi::SsiError::ConstantChannel { channel, value } = e
        && let Some(name) = names.get(channel)
    {
        return fail(format!(
            "{}: column `{name}` is constant (value {value}): it carries no response; leave it out of --columns",
            input.display()
        ));
    }
    let decimated = match ssi.decimate {
        Some(r) if r > 1 => format!(", decimated by {r} to {fs_used} Hz"),
        _ => String::new(),
    };
    fail(format!(
        "{}: columns {}{decimated}: {e}",
        input.display(),
        names.join(",")
    ))
}

pub(crate) fn run(a: &SsiArgs) -> Result<(), Error> {
    use hyst::covssi;
    // Settings that are wrong whatever the record, before it is read.
    let opts = analysis_of(&a.ssi)?;
    let input = match (&a.input, &a.setups) {
        (_, Some(setups)) => return run_setups(a, setups, &opts),
        (Some(input), None) => input,
        (None, None) => return Err(fail("give --input or --setups".to_string())),
    };
    let Channels {
        names,
        data,
        fs,
        points,
        read,
    } = channels(input, &a.record)?;
    let views: Vec<&[f64]> = data.iter().map(|c| c.as_slice()).collect();
    // The page draws the record's FDD: computed with the analysis, on its decimated record.
    let opts = opts.with_fdd(a.html.is_some().then(covssi::fdd::FddOptions::default));
    let bar = steps_bar();
    let analysis = covssi::analyze_with_progress(&views, fs, &opts, &|p| show(&bar, p));
    bar.finish_and_clear();
    let fs_used = fs / a.ssi.decimate.unwrap_or(1) as f64;
    let mut analysis = analysis.map_err(|e| flag_error(input, &a.ssi, e, &names, fs_used))?;
    analysis.channels = names;
    let report = hyst::report::FileReport::new(input.display().to_string(), analysis);
    println!("{read}");
    print!("{}", report.report);
    if let Some(json) = &a.json {
        report.write_json(json)?;
    }
    if let Some(svg) = &a.svg {
        let title = format!("Stabilization diagram: {}", input.display());
        std::fs::write(
            svg,
            covssi::svg::stabilization_svg(&report.report.ssi.diagram, None, &title),
        )
        .map_err(|e| fail(format!("{}: {e}", svg.display())))?;
    }
    if let Some(path) = &a.shapes_uff {
        write_shapes(path, &report.report, points.as_deref(), input)?;
    }
    if let Some(path) = &a.html {
        let title = format!("hyst ssi: {}", input.display());
        let page = hyst::html::ssi_page(&title, &report.report);
        write_text(path, &page)?;
    }
    Ok(())
}

fn write_text(path: &Path, text: &str) -> Result<(), Error> {
    std::fs::write(path, text).map_err(|e| fail(format!("{}: {e}", path.display())))
}

/// `hyst ssi --setups`: every setup identified, the modes merged, the report printed.
fn run_setups(a: &SsiArgs, path: &Path, opts: &hyst::covssi::AnalysisOptions) -> Result<(), Error> {
    if let Some(fs) = a.record.fs {
        check_fs(fs)?;
    }
    let paths = if a.records_anywhere {
        hyst::io::RecordPaths::Anywhere
    } else {
        hyst::io::RecordPaths::InsideFolder
    };
    let setups = hyst::io::read_setups_with(path, paths)?;
    // The setups' records are inputs too: no output may land on one (checked before any is
    // read, as the command's own inputs are).
    let records: Vec<(&str, &Path)> = setups
        .iter()
        .map(|s| ("--setups", s.file.as_path()))
        .collect();
    hyst::io::check_outputs(&records, &a.output_files())?;
    let read = READ_OPTIONS.get().cloned().unwrap_or_default();
    // Each setup identified moves the bar; its message is the latest step of any setup.
    let bar = steps_bar();
    bar.set_length(setups.len() as u64);
    let report = hyst::setups::analyze_setups_with_progress(
        &setups,
        a.record.fs,
        &read,
        opts,
        &hyst::covssi::multisetup::MergeOptions::default(),
        &|p| {
            bar.set_position(p.identified as u64);
            bar.set_message(match p.setup {
                Some(setup) => format!("setups identified; setup {setup}: {}", p.what),
                None => p.what.to_string(),
            });
        },
    );
    bar.finish_and_clear();
    let mut report = hyst::report::FileReport::new(path.display().to_string(), report?);
    // The nodes' positions, for the outputs that draw or place the shapes and the floors'
    // check.
    // A --geometry given is read (and its faults said) even when nothing asked draws it.
    let geometry =
        if a.html.is_some() || a.shapes_uff.is_some() || a.rigid_floors || a.geometry.is_some() {
            hyst::io::setups_geometry(path, a.geometry.as_deref(), a.lines.as_deref())?
        } else {
            None
        };
    if a.rigid_floors {
        let Some((g, _)) = &geometry else {
            return Err(fail(
                "--rigid-floors needs the nodes' positions: a pyOMA folder's grid.txt, or --geometry"
                    .to_string(),
            ));
        };
        report.report.floor_factors = hyst::rigid_floors::floor_factors(&report.report.merged, g);
        if report.report.floor_factors.is_empty() {
            report.report.merged.notes.push(
                "--rigid-floors: no floor qualifies (a floor needs a reference node and other in-plane motion measured on it, three equations in some mode): the channels' factors are not checked".to_string(),
            );
        }
    }
    print!("{report}");
    if let Some(json) = &a.json {
        if a.json_diagrams {
            report.write_json(json)?;
        } else {
            let compact = report.report.without_diagrams();
            hyst::report::FileReport::new(report.record.clone(), compact).write_json(json)?;
        }
    }
    if let Some(uff) = &a.shapes_uff {
        hyst::io::write_merged_shapes_uff(
            uff,
            &report.report.merged,
            geometry.as_ref().map(|(g, _)| g),
            &path.display().to_string(),
        )?;
        println!(
            "{} merged mode shapes written to {}",
            report.report.merged.modes.len(),
            uff.display()
        );
    }
    if let Some(html) = &a.html {
        let title = format!("hyst ssi --setups {}", path.display());
        let g = geometry.as_ref().map(|(g, p)| (g, p.as_path()));
        write_text(html, &hyst::html::setups_page(&title, &report.report, g)?)?;
    }
    Ok(())
}

/// The reported modes' shapes as dataset 55 at `path`; a mode the refinement gave no shape
/// is left out, and said.
fn write_shapes(
    path: &std::path::Path,
    analysis: &hyst::covssi::ModalAnalysis,
    points: Option<&[hyst::io::MeasurementPoint]>,
    input: &std::path::Path,
) -> Result<(), Error> {
    let modes = analysis.reported_modes();
    let mut written = Vec::new();
    for m in &modes {
        match &m.shape {
            Some(shape) => written.push(hyst::io::ShapeMode {
                frequency_hz: m.frequency_hz,
                damping_ratio: m.damping_ratio,
                shape,
            }),
            None => eprintln!(
                "note: the mode at {:.4} Hz has no refined shape; it is not in {}",
                m.frequency_hz,
                path.display()
            ),
        }
    }
    hyst::io::write_shapes_uff(path, &written, points, &input.display().to_string())?;
    Ok(())
}
