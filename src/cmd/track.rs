//! `hyst track`: many records of one structure identified, their modes tracked, changes
//! told from estimation noise.

use std::collections::{HashMap, HashSet};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use clap::Args;
use hyst::monitor::{Loaded, RecordModes, TrackReport};

use super::{Error, channel_names, check_fs, fail, read_record, steps_bar};

#[derive(Args, Debug)]
pub(crate) struct TrackArgs {
    /// The records: files, or folders whose files are taken in name order.
    #[arg(long, num_args = 1.., conflicts_with = "input")]
    pub(crate) inputs: Vec<PathBuf>,
    /// One long record cut into windows (with --window and --step).
    #[arg(long, requires = "window")]
    pub(crate) input: Option<PathBuf>,
    /// Modal estimates made by another system, instead of records: a delimited table, one
    /// row per record, with `record`, an optional `time` (s) and per tracked mode
    /// `<mode>_hz`, optionally `<mode>_hz_se` (Hz) and `<mode>_damping`; an empty cell is a
    /// mode the record did not have. Without standard errors the estimation noise is read
    /// from the training rows, and the report says so.
    #[arg(long, conflicts_with_all = ["inputs", "input"])]
    pub(crate) estimates: Option<PathBuf>,
    /// Window length (s) of --input.
    #[arg(long, value_name = "SECONDS", requires = "input", conflicts_with_all = ["inputs", "estimates"])]
    pub(crate) window: Option<f64>,
    /// Step between windows (s); default the window (no overlap).
    #[arg(long, value_name = "SECONDS", requires = "input", conflicts_with_all = ["inputs", "estimates"])]
    pub(crate) step: Option<f64>,
    /// Sampling rate (Hz); a Universal File states its own.
    #[arg(long)]
    pub(crate) fs: Option<f64>,
    /// Channels, comma-separated; default every column but `t` and `time`.
    #[arg(long, value_delimiter = ',')]
    pub(crate) columns: Option<Vec<String>>,
    /// SSI's and the refinement's options, as `hyst ssi` takes them.
    #[command(flatten)]
    pub(crate) ssi: hyst::settings::SsiSettings,
    /// Covariates per record: a CSV with a column `record` (the file's name, or the window's
    /// number from 0), an optional `time` (s) and one column per covariate.
    #[arg(long)]
    pub(crate) covariates: Option<PathBuf>,
    /// The reference modes: a `hyst ssi --json` document (its reported modes); default the
    /// record with the most modes among the first 24.
    #[arg(long)]
    pub(crate) reference: Option<PathBuf>,
    /// How the modes are tracked (the training, the chart, the environmental model).
    #[command(flatten)]
    pub(crate) tracking: hyst::settings::TrackSettings,
    /// Folder for the campaign's store `store.sqlite` (each record's modes, committed as
    /// they come: a run interrupted continues where it stopped), the tidy table (record ×
    /// mode) as `table.csv`, `table.parquet` and `table.jsonl`, and `report.json`.
    #[arg(help_heading = "Output files", long)]
    pub(crate) out: PathBuf,
    /// Draw each mode's frequency and damping against time (± standard error, alarms in
    /// red) and its frequency against the first covariate, as SVG into this folder.
    #[arg(help_heading = "Output files", long)]
    pub(crate) svg_dir: Option<PathBuf>,
    /// Write a page a browser opens here: each mode's frequency and damping against time
    /// (± one standard error, the training's end, the alarms; zoomable), the reference modes'
    /// table, shapes and MAC.
    #[arg(help_heading = "Output files", long, value_name = "FILE")]
    pub(crate) html: Option<PathBuf>,
    /// Keep going: take each record file as it lands in the --inputs folders (once its
    /// size and time have held for one poll), or the --estimates table each time it
    /// grows, track the campaign again over everything so far (the store keeps every
    /// record identified) and print each new record and each new alarm as it comes. The
    /// table and report in --out are after each pass those of a batch run over the same
    /// records with the same --training (without it, 336 records train, whatever has
    /// arrived). Safe to stop (Ctrl-C, kill) and start again.
    #[arg(long, conflicts_with = "input")]
    pub(crate) follow: bool,
    /// Seconds between looks at the folders or the table with --follow.
    #[arg(
        long,
        value_name = "SECONDS",
        default_value_t = 10.0,
        requires = "follow"
    )]
    pub(crate) poll: f64,
}

/// The records' names and how to load each.
enum Sources {
    Files(Vec<PathBuf>),
    Windows {
        table: hyst::io::Table,
        fs: f64,
        length: usize,
        step: usize,
        count: usize,
    },
}

/// The records' sources: `--input`'s windows, or `files` (the records of `--inputs`, listed
/// once by [`record_files`]).
fn sources(a: &TrackArgs, files: Vec<PathBuf>) -> Result<Sources, Error> {
    if let Some(path) = &a.input {
        let table = read_record(path)?;
        let fs = check_fs(table.rate(a.fs)?)?;
        let window = a.window.unwrap_or(0.0);
        let step = a.step.unwrap_or(window);
        let (length, step) = ((window * fs).round() as usize, (step * fs).round() as usize);
        if length < 2 || step < 1 {
            return Err(fail(format!(
                "--window {window} s and --step {step} samples give no windows at {fs} Hz"
            )));
        }
        let count = table.len().saturating_sub(length) / step + usize::from(table.len() >= length);
        if count == 0 {
            return Err(fail(format!(
                "{}: {} rows hold no window of {length}",
                path.display(),
                table.len()
            )));
        }
        return Ok(Sources::Windows {
            table,
            fs,
            length,
            step,
            count,
        });
    }
    if files.is_empty() {
        return Err(fail(
            "no records: --inputs names no files (or only empty folders)",
        ));
    }
    Ok(Sources::Files(files))
}

/// The record files of `--inputs`. With `--out` one of their folders, the files an earlier
/// run wrote there (its store beside them) are its own, not records; without that store a
/// record with one of their names is a record, and [`check_paths`] refuses to overwrite it.
pub(super) fn record_files(a: &TrackArgs) -> Result<Vec<PathBuf>, Error> {
    let mut files = hyst::io::list_records(&a.inputs)?;
    if a.out.join(hyst::store::STORE_FILE).is_file() {
        files.retain(|f| !hyst::store::is_output(&a.out, f));
    }
    Ok(files)
}

/// The `files` that are records ([`hyst::io::probe_record`]: a note or a page in a folder
/// of records is not one, and takes no record's place, its training slot included); each
/// other is named once on stderr (`said` remembers which were).
pub(super) fn records_among(files: Vec<PathBuf>, said: &mut HashSet<PathBuf>) -> Vec<PathBuf> {
    files
        .into_iter()
        .filter(|f| match hyst::io::probe_record(f) {
            Ok(()) => true,
            Err(e) => {
                if said.insert(f.clone()) {
                    eprintln!("note: left out, not a record: {e}");
                }
                false
            }
        })
        .collect()
}

/// Every file the run writes (the store and tables in `--out`, the `--html` page) against
/// every file it reads (the records, `--input`, `--estimates`, `--covariates`,
/// `--reference`), before anything is read: a clash is refused, naming both flags.
pub(super) fn check_paths(a: &TrackArgs, records: &[PathBuf]) -> Result<(), Error> {
    let mut inputs: Vec<(&str, &Path)> =
        records.iter().map(|f| ("--inputs", f.as_path())).collect();
    for (flag, p) in [
        ("--input", &a.input),
        ("--estimates", &a.estimates),
        ("--covariates", &a.covariates),
        ("--reference", &a.reference),
    ] {
        if let Some(p) = p {
            inputs.push((flag, p.as_path()));
        }
    }
    let written: Vec<PathBuf> = hyst::store::OUTPUT_FILES
        .iter()
        .map(|n| a.out.join(n))
        .collect();
    let mut outputs: Vec<(&str, &Path)> = written.iter().map(|p| ("--out", p.as_path())).collect();
    if let Some(h) = &a.html {
        outputs.push(("--html", h.as_path()));
    }
    hyst::io::check_outputs(&inputs, &outputs)?;
    // A page written among the records would be read as one on the next look (or run).
    if let Some(h) = &a.html {
        let folder = match h.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        let same = |d: &Path| match (folder.canonicalize(), d.canonicalize()) {
            (Ok(x), Ok(y)) => x == y,
            _ => false,
        };
        if let Some(d) = a.inputs.iter().find(|d| d.is_dir() && same(d)) {
            return Err(fail(format!(
                "--html {}: inside the records folder {}, where the next look (or run) would take the page for a record; write it elsewhere",
                h.display(),
                d.display()
            )));
        }
    }
    if a.out.exists() && !a.out.is_dir() {
        return Err(fail(format!(
            "--out {}: a file, not a folder; give the folder the run's store and tables go to",
            a.out.display()
        )));
    }
    Ok(())
}

/// The reported modes of a `hyst ssi --json` document.
fn reference_modes(path: &Path) -> Result<Vec<hyst::monitor::ModeEstimate>, Error> {
    let text =
        std::fs::read_to_string(path).map_err(|e| fail(format!("{}: {e}", path.display())))?;
    hyst::report::reference_modes(&text)
        .map_err(|e| fail(format!("--reference {}: {e}", path.display())))
}

/// `--inputs`' files put in time order as the covariates file says, with the gaps among them
/// ([`hyst::campaign::order_records`]), and the order said; the gaps.
fn put_in_order(
    sources: &mut Sources,
    covariates: &hyst::io::Covariates,
    verbose: bool,
) -> Vec<String> {
    let Sources::Files(files) = sources else {
        return Vec::new();
    };
    let ordered = hyst::campaign::order_records(std::mem::take(files), covariates);
    if verbose {
        println!(
            "{} records, {}",
            ordered.files.len(),
            if ordered.by_time {
                "in the order of their time in the covariates file"
            } else {
                "in natural order of their names (rec_2 before rec_10)"
            }
        );
    }
    *files = ordered.files;
    ordered.gaps
}

impl Sources {
    /// Each record's name: its file's, or its window's number.
    fn names(&self) -> Vec<String> {
        match self {
            Sources::Files(files) => files
                .iter()
                .map(|f| {
                    f.file_name().map_or_else(
                        || f.display().to_string(),
                        |n| n.to_string_lossy().into_owned(),
                    )
                })
                .collect(),
            Sources::Windows { count, .. } => (0..*count).map(|i| i.to_string()).collect(),
        }
    }

    /// The key of each record's result ([`hyst::store::record_key`]) under `settings`.
    fn keys(&self, a: &TrackArgs, settings: &str) -> Vec<String> {
        match self {
            Sources::Files(files) => files
                .iter()
                .map(|f| hyst::store::record_key(&hyst::store::file_source(f), settings))
                .collect(),
            Sources::Windows {
                length,
                step,
                count,
                ..
            } => {
                let whole = a
                    .input
                    .as_deref()
                    .map(hyst::store::file_source)
                    .unwrap_or_default();
                (0..*count)
                    .map(|i| {
                        hyst::store::record_key(
                            &format!("{whole}|{}|{length}|{step}", i * step),
                            settings,
                        )
                    })
                    .collect()
            }
        }
    }

    /// Record i's channels and rate. A file's channels are `first`'s (the first record's,
    /// without --columns), matched by name: another order is put right, another set is
    /// skipped (its shapes would be compared entry by entry with the wrong channels).
    fn channels(
        &self,
        i: usize,
        a: &TrackArgs,
        first: Option<&[String]>,
    ) -> Result<(Vec<Vec<f64>>, f64), String> {
        match self {
            Sources::Files(files) => {
                let mut t = read_record(&files[i]).map_err(|e| e.to_string())?;
                let fs = t.rate(a.fs).map_err(|e| e.to_string())?;
                let mut cols =
                    channel_names(&t, a.columns.as_deref(), &[]).map_err(|e| e.to_string())?;
                if let Some(first) = first
                    && cols != first
                {
                    let (mut x, mut y) = (cols.clone(), first.to_vec());
                    x.sort();
                    y.sort();
                    if x != y {
                        return Err(format!(
                            "its channels {} differ from the first record's {}: skipped (--columns chooses the channels)",
                            cols.join(","),
                            first.join(",")
                        ));
                    }
                    cols = first.to_vec();
                }
                let data = cols
                    .iter()
                    .map(|c| t.take_column(c).map_err(|e| e.to_string()))
                    .collect::<Result<Vec<_>, _>>()?;
                Ok((data, fs))
            }
            Sources::Windows {
                table,
                fs,
                length,
                step,
                ..
            } => {
                let cols =
                    channel_names(table, a.columns.as_deref(), &[]).map_err(|e| e.to_string())?;
                let from = i * step;
                let data = cols
                    .iter()
                    .map(|c| {
                        table
                            .column(c)
                            .map(|v| v[from..from + length].to_vec())
                            .map_err(|e| e.to_string())
                    })
                    .collect::<Result<Vec<_>, _>>()?;
                Ok((data, *fs))
            }
        }
    }
}

pub(crate) fn run(a: &TrackArgs) -> Result<(), Error> {
    let records = checked_inputs(a)?;
    if let Some(path) = &a.estimates {
        let (report, table) = estimates_pass(a, path, true)?;
        print!("{report}");
        return write_outputs(a, &report, &table);
    }
    let (asked, mut store) = records_setup(a)?;
    let (report, table) = records_pass(a, &asked, &mut store, records, true)?;
    drop(store);
    print!("{report}");
    write_outputs(a, &report, &table)
}

/// The record files of `--inputs` (none without), every output checked against every input
/// before anything is read ([`check_paths`]).
pub(super) fn checked_inputs(a: &TrackArgs) -> Result<Vec<PathBuf>, Error> {
    let records = if a.inputs.is_empty() {
        Vec::new()
    } else {
        records_among(record_files(a)?, &mut HashSet::new())
    };
    check_paths(a, &records)?;
    Ok(records)
}

/// What a run on records needs before the first is read: the rate and the settings checked
/// (wrong whatever the record, else each would be skipped for the same reason), the
/// analysis asked for, and the campaign's store taken.
pub(super) fn records_setup(
    a: &TrackArgs,
) -> Result<(hyst::covssi::AnalysisOptions, hyst::store::CampaignStore), Error> {
    a.fs.map(check_fs).transpose()?;
    let asked = super::ssi::analysis_of(&a.ssi)?;
    let store = hyst::store::CampaignStore::open(&a.out)?;
    Ok((asked, store))
}

/// The options of the tracking: `--training`, or with `--follow` 336 records whatever has
/// arrived (the records a batch run over `records` would train on when given it), not half
/// of those so far.
pub(super) fn track_options(a: &TrackArgs, records: usize) -> hyst::monitor::TrackOptions {
    let mut opts = a.tracking.options(records);
    if a.follow && a.tracking.training.is_none() {
        opts.training = hyst::monitor::TrackOptions::default().training;
    }
    opts
}

/// One pass over the record `files` (or `--input`'s windows): each record identified or
/// served from `store`, the campaign tracked, the store left holding exactly these records
/// and the table; what the records' order and the analysis read from them are said when
/// `verbose`.
pub(super) fn records_pass(
    a: &TrackArgs,
    asked: &hyst::covssi::AnalysisOptions,
    store: &mut hyst::store::CampaignStore,
    files: Vec<PathBuf>,
    verbose: bool,
) -> Result<(TrackReport, hyst::store::TrackTable), Error> {
    let mut sources = sources(a, files)?;
    let (covs, cov_names) = match &a.covariates {
        Some(p) => hyst::io::read_covariates(p)?,
        None => Default::default(),
    };
    let covariates = (covs, cov_names);
    let gaps = put_in_order(&mut sources, &covariates, verbose);
    let names = sources.names();
    if let Some(r) = hyst::io::repeated(&names) {
        return Err(fail(format!("two records named {r}: each file once")));
    }
    let bar = steps_bar();
    bar.set_length(names.len() as u64);
    bar.set_message("records identified");
    // Record i's start: its window's time, or its place among the files.
    let start_of = |i: usize| match &sources {
        Sources::Files(_) => i as f64,
        Sources::Windows { fs, step, .. } => (i * step) as f64 / fs,
    };
    let covariates_of = |name: &str, fallback_time: f64| {
        hyst::campaign::covariates_of(&covariates, name, fallback_time)
    };
    // Without --columns, the first record's channels are every record's.
    let first_channels = match (&sources, &a.columns) {
        (Sources::Files(files), None) => files
            .iter()
            .filter(|f| !gaps.iter().any(|g| f.as_os_str() == g.as_str()))
            .find_map(|f| read_record(f).ok())
            .and_then(|t| channel_names(&t, None, &[]).ok()),
        _ => None,
    };
    let load = |i: usize| -> Result<Loaded, String> {
        if gaps.contains(&names[i]) {
            return Err(hyst::campaign::GAP_REASON.into());
        }
        let (channels, fs) = sources.channels(i, a, first_channels.as_deref())?;
        let (time, covariates) = covariates_of(&names[i], start_of(i));
        Ok(Loaded {
            channels,
            fs,
            time,
            covariates,
        })
    };
    // What the options leave to the record (the decimation, the lag) is read once, from
    // the first record that loads, and kept for every record: each is analysed alike.
    // What makes each record's result: its source, the rate and channels asked for, and the
    // analysis options, and the version of what is kept of it; a stored result made
    // otherwise is identified again.
    let analysis = resolved_analysis(asked, &names, &load, verbose);
    let settings = format!(
        "{:?}|{:?}|{analysis:?}|{}",
        a.fs,
        a.columns,
        hyst_monitor::records::IDENTIFIED_VERSION
    );
    let keys = sources.keys(a, &settings);
    let done: Vec<RecordModes> = names
        .iter()
        .zip(&keys)
        .filter_map(|(n, k)| store.cached(n, k).cloned())
        .collect();
    let store_error = Mutex::new(None);
    let key_of: HashMap<&str, &str> = names
        .iter()
        .zip(&keys)
        .map(|(n, k)| (n.as_str(), k.as_str()))
        .collect();
    let finished = |r: &RecordModes| {
        if let Some(key) = key_of.get(r.name.as_str())
            && let Err(e) = store.append(key, r)
            && let Ok(mut first) = store_error.lock()
        {
            first.get_or_insert(e);
        }
        bar.inc(1);
    };
    bar.set_position(done.iter().filter(|d| names.contains(&d.name)).count() as u64);
    let mut records = hyst::monitor::identify_records(&names, &load, &analysis, &done, &finished);
    // An earlier run's records keep their identification; their time and covariates are
    // this run's (the covariates file may have changed).
    for (i, r) in records.iter_mut().enumerate() {
        (r.time, r.covariates) = covariates_of(&names[i], start_of(i));
    }
    bar.finish_and_clear();
    if let Some(e) = store_error.into_inner().ok().flatten() {
        return Err(e.into());
    }
    let opts = track_options(a, names.len());
    let reference = a.reference.as_deref().map(reference_modes).transpose()?;
    let mut report = hyst::monitor::track(&records, reference.as_deref(), &opts)
        .map_err(|e| fail(e.to_string()))?;
    report.name_covariates(covariates.1);
    let table = hyst::store::TrackTable::of(&report);
    store.finish(&keys, &records, &table)?;
    Ok((report, table))
}

/// `hyst track --estimates`: another system's estimates tracked as records' are, the
/// covariates joined by record name (a record without them is tracked, not charted); what
/// was read is said when `verbose`.
pub(super) fn estimates_pass(
    a: &TrackArgs,
    path: &Path,
    verbose: bool,
) -> Result<(TrackReport, hyst::store::TrackTable), Error> {
    let table = hyst::io::read_estimates(path)?;
    let covariates = match &a.covariates {
        Some(p) => hyst::io::read_covariates(p)?,
        None => Default::default(),
    };
    let records = table.records(&covariates);
    let cov_names = covariates.1;
    let without: Vec<&str> = records
        .iter()
        .filter(|r| r.covariates.iter().any(|v| !v.is_finite()))
        .map(|r| r.name.as_str())
        .collect();
    if verbose {
        println!(
            "{} records of estimates, {} modes ({}), from {}",
            records.len(),
            table.modes.len(),
            table.modes.join(", "),
            path.display()
        );
        if !without.is_empty() && !cov_names.is_empty() {
            println!(
                "{} record(s) without every covariate (tracked, not charted): {}",
                without.len(),
                without.join(", ")
            );
        }
    }
    std::fs::create_dir_all(&a.out).map_err(|e| fail(format!("{}: {e}", a.out.display())))?;
    let opts = track_options(a, records.len());
    let mut report = hyst::monitor::track_estimates(&records, &table.modes, &opts)
        .map_err(|e| fail(e.to_string()))?;
    report.name_covariates(cov_names);
    let table = hyst::store::TrackTable::of(&report);
    Ok((report, table))
}

/// `analysis` with what it leaves to the record read from the campaign's first readable
/// record ([`hyst::monitor::campaign_analysis`]), and said.
fn resolved_analysis(
    analysis: &hyst::covssi::AnalysisOptions,
    names: &[String],
    load: &dyn Fn(usize) -> Result<Loaded, String>,
    verbose: bool,
) -> hyst::covssi::AnalysisOptions {
    let resolve = |i: usize| {
        let l = load(i).ok()?;
        let views: Vec<&[f64]> = l.channels.iter().map(|c| c.as_slice()).collect();
        analysis.resolved_for(&views, l.fs).ok()
    };
    let (fixed, from) = hyst::monitor::campaign_analysis(analysis, names.len(), &resolve);
    if let Some(i) = from.filter(|_| verbose && fixed != *analysis) {
        let factor = match fixed.decimation {
            hyst::covssi::Decimation::Factor(r) => r,
            _ => 1,
        };
        let rows = match fixed.ssi.block_rows {
            hyst::covssi::BlockRows::Count(i) => i.to_string(),
            _ => "the given".into(),
        };
        println!(
            "analysis read from record {}: decimated by {factor}, {rows} block rows; kept for every record",
            names[i]
        );
    }
    fixed
}

/// The report written into `--out` (`table.csv`, `table.parquet`, `table.jsonl`,
/// `report.json`), `--svg-dir` and `--html`.
pub(super) fn write_outputs(
    a: &TrackArgs,
    report: &TrackReport,
    table: &hyst::store::TrackTable,
) -> Result<(), Error> {
    table.write_csv(&a.out.join("table.csv"))?;
    table.write_parquet(&a.out.join("table.parquet"))?;
    write_rows(&a.out.join("table.jsonl"), report)?;
    hyst::report::write_json(report, &a.out.join("report.json"))?;
    if let Some(dir) = &a.svg_dir {
        hyst::figures::track_figures(dir, report).map_err(fail)?;
    }
    if let Some(path) = &a.html {
        std::fs::write(path, hyst::html::track_page(report))
            .map_err(|e| fail(format!("{}: {e}", path.display())))?;
    }
    Ok(())
}

/// The tidy table as JSON lines: one `TrackRow` per line.
fn write_rows(path: &Path, report: &TrackReport) -> Result<(), Error> {
    let err = |e: std::io::Error| fail(format!("{}: {e}", path.display()));
    let mut w = std::io::BufWriter::new(std::fs::File::create(path).map_err(err)?);
    for r in &report.rows {
        serde_json::to_writer(&mut w, r).map_err(|e| fail(format!("{}: {e}", path.display())))?;
        writeln!(w).map_err(err)?;
    }
    w.flush().map_err(err)
}
