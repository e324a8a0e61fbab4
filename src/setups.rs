//! A modal test of several setups, end to end: each setup's record read and identified alone
//! ([`covssi::analyze`]), then the setups merged on their references
//! ([`covssi::multisetup::merge`]): what `hyst ssi --setups` and `hyst.ssi(setups=...)` run.

use std::fmt;

use covssi::multisetup::{
    MergeError, MergeOptions, MergedModes, SetupModes, SetupRecord, merge, merge_global,
};
use covssi::{AnalysisOptions, ModalAnalysis, SsiError};
use rayon::prelude::*;

use crate::io::{IoError, ReadOptions, SetupSpec};

/// One setup's part of the report.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SetupAnalysis {
    /// The setup's name.
    pub name: String,
    /// Its record.
    pub file: String,
    /// The record's rate (Hz).
    pub fs_hz: f64,
    /// Samples per channel.
    pub samples: usize,
    /// Its own analysis (channels named by the setup file's columns).
    pub analysis: ModalAnalysis,
}

/// What [`analyze_setups`] finds: every setup's analysis and the merged mode set.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SetupsReport {
    /// Each setup, in the setup file's order.
    pub setups: Vec<SetupAnalysis>,
    /// The merged modes.
    pub merged: MergedModes,
    /// The global estimation beside it: SSI once on all setups' correlations
    /// ([`covssi::multisetup::merge_global`]), with the first setup's decimation and the
    /// setups' largest block rows; `None` when it was not run (`global_error` says why).
    #[serde(default)]
    pub global: Option<MergedModes>,
    /// Why there is no global estimation.
    #[serde(default)]
    pub global_error: Option<String>,
    /// What each floor stated rigid says of the channels' factor against the references
    /// ([`crate::rigid_floors`]); empty unless asked for.
    #[serde(default)]
    pub floor_factors: Vec<crate::rigid_floors::FloorFactor>,
    /// Whether each setup's stabilization diagram and singular values were left out
    /// ([`SetupsReport::without_diagrams`]): the setup's modes, errors and decision stay.
    #[serde(default)]
    pub diagrams_left_out: bool,
}

impl SetupsReport {
    /// The report without each setup's stabilization diagram and singular values (nine
    /// tenths of a test's JSON; the page draws them): what `hyst ssi --setups --json`
    /// writes unless asked for the diagrams.
    pub fn without_diagrams(&self) -> SetupsReport {
        let mut compact = self.clone();
        for s in &mut compact.setups {
            s.analysis.ssi.diagram = covssi::StabilizationDiagram::default();
            s.analysis.ssi.singular_values = Vec::new();
        }
        compact.diagrams_left_out = true;
        compact
    }
}

/// Why a multi-setup analysis stopped.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SetupsError {
    /// A record could not be read.
    #[error(transparent)]
    Io(#[from] IoError),
    /// A setup's record could not be identified.
    #[error("setup `{setup}` ({file}): {source}")]
    Analysis {
        /// The setup.
        setup: String,
        /// Its record.
        file: String,
        /// covssi's error.
        source: SsiError,
    },
    /// The setups could not be merged.
    #[error(transparent)]
    Merge(#[from] MergeError),
}

/// What a test of several setups is doing as it runs: how many setups are identified, and
/// the step one of them (or the merge) is at.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SetupsProgress<'a> {
    /// Setups identified so far.
    pub identified: usize,
    /// Setups in all.
    pub setups: usize,
    /// The setup the step is of; `None` for the merge and the global estimation.
    pub setup: Option<&'a str>,
    /// What runs now (the analysis's step, [`covssi::Progress::what`]).
    pub what: &'a str,
}

/// Read and identify every setup of `setups` (in parallel), at `fs` Hz or each file's stated
/// rate, and merge them.
pub fn analyze_setups(
    setups: &[SetupSpec],
    fs: Option<f64>,
    read: &ReadOptions,
    opts: &AnalysisOptions,
    merge_opts: &MergeOptions,
) -> Result<SetupsReport, SetupsError> {
    analyze_setups_with_progress(setups, fs, read, opts, merge_opts, &|_| {})
}

/// [`analyze_setups`], telling `progress` of each setup's steps as they start, of each setup
/// identified, and of the merge.
pub fn analyze_setups_with_progress(
    setups: &[SetupSpec],
    fs: Option<f64>,
    read: &ReadOptions,
    opts: &AnalysisOptions,
    merge_opts: &MergeOptions,
    progress: &(dyn Fn(SetupsProgress<'_>) + Sync),
) -> Result<SetupsReport, SetupsError> {
    use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};
    let identified = AtomicUsize::new(0);
    let tell = |count: usize, setup: Option<&str>, what: &str| {
        progress(SetupsProgress {
            identified: count,
            setups: setups.len(),
            setup,
            what,
        })
    };
    let (analysed, records): (Vec<SetupAnalysis>, Vec<Vec<Vec<f64>>>) = setups
        .par_iter()
        .map(|s| {
            let one = analyze_one(s, fs, read, opts, &|p: covssi::Progress<'_>| {
                tell(identified.load(Relaxed), Some(&s.name), p.what)
            });
            if one.is_ok() {
                tell(
                    identified.fetch_add(1, Relaxed) + 1,
                    Some(&s.name),
                    "identified",
                );
            }
            one
        })
        .collect::<Result<Vec<_>, _>>()?
        .into_iter()
        .unzip();
    let all = setups.len();
    tell(
        all,
        None,
        "the global estimation (SSI on every setup's correlations)",
    );
    let global = global(setups, &analysed, records, (fs, read), opts);
    tell(all, None, "merging the setups on their references");
    let mut report = merge_analysed(setups, analysed, merge_opts)?;
    match global {
        Ok(g) => report.global = Some(g),
        Err(e) => report.global_error = Some(e),
    }
    Ok(report)
}

/// Largest relative difference of two setups' rates that are one rate.
const SAME_RATE: f64 = 1e-6;

/// The global estimation of `setups` at the first setup's decimation and the setups' largest
/// block rows, from their `records` as each setup's analysis decimated them; a setup
/// decimated by another factor is read again (`fs`, `read` as for its analysis) and decimated
/// by the first's.
fn global(
    setups: &[SetupSpec],
    analysed: &[SetupAnalysis],
    mut records: Vec<Vec<Vec<f64>>>,
    (fs, read): (Option<f64>, &ReadOptions),
    opts: &AnalysisOptions,
) -> Result<MergedModes, String> {
    let first = analysed.first().ok_or("no setup")?;
    // Rates that differ by rounding (20 and 20.000000000000004 Hz, from two time columns
    // cut from one record) are one rate: a relative difference of 1e-6 shifts every
    // frequency by a thousandth of the smallest error SSI reports on a real record.
    if let Some(other) = analysed
        .iter()
        .find(|a| (a.fs_hz - first.fs_hz).abs() > SAME_RATE * first.fs_hz)
    {
        return Err(format!(
            "setups `{}` and `{}` have different rates ({} and {} Hz)",
            first.name, other.name, first.fs_hz, other.fs_hz
        ));
    }
    let factor = first.analysis.decimation.factor.max(1);
    for ((s, a), record) in setups.iter().zip(analysed).zip(records.iter_mut()) {
        if a.analysis.decimation.factor.max(1) != factor {
            let (data, _) = read_channels(s, fs, read).map_err(|e| e.to_string())?;
            let views: Vec<&[f64]> = data.iter().map(Vec::as_slice).collect();
            *record = covssi::decimate::decimate_channels(&views, factor);
        }
    }
    let block_rows = analysed
        .iter()
        .map(|a| a.analysis.ssi.block_rows)
        .max()
        .unwrap_or(2);
    let input: Vec<SetupRecord<'_>> = setups
        .iter()
        .zip(&records)
        .map(|(s, record)| SetupRecord {
            name: s.name.clone(),
            channels: s.channels.clone(),
            y: record.iter().map(Vec::as_slice).collect(),
        })
        .collect();
    merge_global(&input, first.fs_hz / factor as f64, block_rows, &opts.ssi)
        .map_err(|e| e.to_string())
}

/// The setups `setups`, already identified (`analysed`, in the same order), merged: for a
/// second merge of the same records under other channel descriptions (a gain found) without
/// identifying them again.
pub fn merge_analysed(
    setups: &[SetupSpec],
    analysed: Vec<SetupAnalysis>,
    merge_opts: &MergeOptions,
) -> Result<SetupsReport, MergeError> {
    let modes: Vec<SetupModes> = setups
        .iter()
        .zip(&analysed)
        .map(|(s, a)| SetupModes {
            name: s.name.clone(),
            channels: s.channels.clone(),
            modes: a.analysis.reported_modes(),
        })
        .collect();
    let merged = merge(&modes, merge_opts)?;
    Ok(SetupsReport {
        setups: analysed,
        merged,
        global: None,
        global_error: None,
        floor_factors: Vec::new(),
        diagrams_left_out: false,
    })
}

/// One setup's analysis, and its channels as the analysis decimated them (for the global
/// estimation: a quarter of the record at the usual factor, rather than all of it kept
/// while the other setups are identified).
fn analyze_one(
    s: &SetupSpec,
    fs: Option<f64>,
    read: &ReadOptions,
    opts: &AnalysisOptions,
    progress: &(dyn Fn(covssi::Progress<'_>) + Sync),
) -> Result<(SetupAnalysis, Vec<Vec<f64>>), SetupsError> {
    let (data, fs) = read_channels(s, fs, read)?;
    let views: Vec<&[f64]> = data.iter().map(Vec::as_slice).collect();
    let file = s.file.display().to_string();
    let mut analysis =
        covssi::analyze_with_progress(&views, fs, opts, progress).map_err(|source| {
            SetupsError::Analysis {
                setup: s.name.clone(),
                file: file.clone(),
                source,
            }
        })?;
    analysis.channels = s.columns.clone();
    let samples = data.first().map_or(0, Vec::len);
    let factor = analysis.decimation.factor;
    let kept = if factor > 1 {
        covssi::decimate::decimate_channels(&views, factor)
    } else {
        data
    };
    let setup = SetupAnalysis {
        name: s.name.clone(),
        file,
        fs_hz: fs,
        samples,
        analysis,
    };
    Ok((setup, kept))
}

/// Setup `s`'s channels read from its record, and the record's rate (`fs`, else the setup's,
/// else the file's).
fn read_channels(
    s: &SetupSpec,
    fs: Option<f64>,
    read: &ReadOptions,
) -> Result<(Vec<Vec<f64>>, f64), IoError> {
    let mut table = crate::io::read_record(&s.file, read)?;
    let fs = table.rate(fs.or(s.fs_hz))?;
    let data = s
        .columns
        .iter()
        .map(|c| table.take_column(c))
        .collect::<Result<Vec<Vec<f64>>, IoError>>()?;
    Ok((data, fs))
}

/// A merged mode's MPC and MPD (degrees) over the entries some setup saw; `None` when none
/// did. The text report's table and the page's give these.
pub(crate) fn phase_quality(mode: &covssi::multisetup::MergedMode) -> Option<(f64, f64)> {
    let seen: Vec<covssi::Complex64> = mode.shape.iter().flatten().copied().collect();
    (!seen.is_empty()).then(|| (covssi::mpc(&seen), covssi::mpd(&seen)))
}

/// A complex entry as magnitude∠phase°.
fn polar(v: covssi::Complex64) -> String {
    format!("{:.3}∠{:.0}°", v.norm(), v.arg().to_degrees() + 0.0)
}

impl fmt::Display for SetupsReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let m = &self.merged;
        writeln!(f, "{} setups, each identified alone:", self.setups.len())?;
        for s in &self.setups {
            writeln!(
                f,
                "  {:<16} {:>2} channels, {} samples at {} Hz: {} modes",
                s.name,
                s.analysis.channels.len(),
                s.samples,
                s.fs_hz,
                s.analysis.reported_modes().len()
            )?;
        }
        let refs: Vec<String> = m
            .dofs
            .iter()
            .filter(|d| d.reference)
            .map(|d| format!("node {} {:?}", d.node, d.direction.map(round3)))
            .collect();
        writeln!(f, "references: {}", refs.join(", "))?;
        writeln!(
            f,
            "\nmerged modes (shapes as displacement, largest entry 1; ± one standard error):"
        )?;
        writeln!(
            f,
            "  mode  frequency (Hz)         damping (%)         setups  scatter  MPC    MPD (°)"
        )?;
        if m.modes.is_empty() {
            writeln!(f, "  no mode found in any setup (the notes below say why)")?;
        }
        for (i, mode) in m.modes.iter().enumerate() {
            let se = |v: Option<f64>, k: f64, d: usize| {
                v.map_or("—".to_string(), |e| format!("{:.*}", d, e * k))
            };
            let (mpc, mpd) = match phase_quality(mode) {
                Some((mpc, mpd)) => (format!("{mpc:.3}"), format!("{mpd:.1}")),
                None => ("—".to_string(), "—".to_string()),
            };
            writeln!(
                f,
                "  {:>4}  {:>9.4} ± {:<8}  {:>6.3} ± {:<8}  {:>3}/{:<3} {:<8} {mpc:<6} {mpd}",
                i + 1,
                mode.frequency_hz,
                se(mode.frequency_se_hz, 1.0, 4),
                100.0 * mode.damping_ratio,
                se(mode.damping_se, 100.0, 3),
                mode.seen_in.len(),
                self.setups.len(),
                mode.scatter_ratio.map_or("—".into(), |r| format!("{r:.2}"))
            )?;
        }
        for floor in &self.floor_factors {
            writeln!(f, "sensors: {}", floor.sentence(&m.setups))?;
        }
        for (i, mode) in m.modes.iter().enumerate() {
            writeln!(
                f,
                "\nmode {} ({:.4} Hz): node  x  y  z (magnitude∠phase ± standard error)",
                i + 1,
                mode.frequency_hz
            )?;
            for node in &mode.nodes {
                let cells: Vec<String> = (0..3)
                    .map(|k| match (node.motion[k], node.se[k]) {
                        (Some(u), Some(e)) => format!("{} ± {:.3}", polar(u), e),
                        (Some(u), None) => polar(u),
                        _ => "—".into(),
                    })
                    .collect();
                writeln!(f, "  {:>6}  {}", node.node, cells.join("  "))?;
            }
        }
        for note in &m.notes {
            writeln!(f, "note: {note}")?;
        }
        // Each setup's own analysis notes (a decimation that filters modes out, say), once
        // for the setups that share one.
        let mut said: Vec<(&str, Vec<&str>)> = Vec::new();
        for s in &self.setups {
            for note in &s.analysis.ssi.notes {
                match said.iter_mut().find(|(n, _)| *n == note.as_str()) {
                    Some((_, names)) => names.push(&s.name),
                    None => said.push((note, vec![&s.name])),
                }
            }
        }
        for (note, names) in said {
            let whose = if names.len() == self.setups.len() && names.len() > 1 {
                "every setup".to_string()
            } else {
                format!("setup {}", names.join(", "))
            };
            writeln!(f, "note ({whose}): {note}")?;
        }
        self.fmt_global(f)
    }
}

impl SetupsReport {
    /// The global estimation's modes, each beside the merged mode nearest it (within 1 %)
    /// and the MAC of their shapes.
    fn fmt_global(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let Some(g) = &self.global else {
            if let Some(e) = &self.global_error {
                writeln!(f, "\nglobal estimation not run: {e}")?;
            }
            return Ok(());
        };
        writeln!(
            f,
            "\nglobal estimation (SSI once on all setups' correlations; no standard errors), beside the merge:"
        )?;
        if g.modes.is_empty() {
            return writeln!(f, "  no mode found");
        }
        writeln!(f, "  frequency (Hz)  damping (%)  merged mode  MAC with it")?;
        for mode in &g.modes {
            let near =
                self.merged.modes.iter().enumerate().find(|(_, m)| {
                    (m.frequency_hz - mode.frequency_hz).abs() <= 0.01 * m.frequency_hz
                });
            let (which, mac) = match near {
                Some((i, m)) => (format!("{}", i + 1), format!("{:.3}", shape_mac(mode, m))),
                None => ("—".into(), "—".into()),
            };
            writeln!(
                f,
                "  {:>14.4}  {:>11.3}  {which:>11}  {mac:>11}",
                mode.frequency_hz,
                100.0 * mode.damping_ratio
            )?;
        }
        Ok(())
    }
}

/// MAC of two merged shapes over the DOFs both have (the DOFs are the same list).
fn shape_mac(a: &covssi::multisetup::MergedMode, b: &covssi::multisetup::MergedMode) -> f64 {
    let (x, y): (Vec<_>, Vec<_>) = a
        .shape
        .iter()
        .zip(&b.shape)
        .filter_map(|(p, q)| Some(((*p)?, (*q)?)))
        .unzip();
    covssi::mac(&x, &y)
}

fn round3(v: f64) -> f64 {
    (v * 1000.0).round() / 1000.0 + 0.0
}
