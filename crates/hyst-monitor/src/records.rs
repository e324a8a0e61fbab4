//! Each record of a campaign identified: screened, its machine's lines subtracted, its modes
//! by SSI and the refinement as `hyst ssi` finds them ([`identify_record`]), many in parallel
//! ([`identify_records`]), with the analysis the campaign keeps read from its first record
//! ([`campaign_analysis`]).

use crate::MonitorError;
use crate::matching::ModeEstimate;

/// One record's identification, as the campaign's tracking takes it.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct RecordModes {
    /// The record's name (a file, or a window of one).
    pub name: String,
    /// When it was recorded (s, on the campaign's clock).
    pub time: f64,
    /// The covariates at that time (the same ones, in the same order, for every record).
    pub covariates: Vec<f64>,
    /// The modes it gave, or why it gave none (a dead channel, a record too short).
    pub outcome: Result<Identified, String>,
}

/// The version of what [`identify_record`] keeps of a record (2: its correlations' parts
/// too); a store keyed by it identifies a record kept by an earlier version again.
pub const IDENTIFIED_VERSION: u32 = 2;

/// The modes a record gave.
#[derive(Debug, Clone, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Identified {
    /// The reported modes.
    pub modes: Vec<ModeEstimate>,
    /// The refinement's misfit (above `covssi::MISFIT_LIMIT` the record does not follow the
    /// model, and the modes are SSI's).
    pub misfit: Option<f64>,
    /// Poles taken for harmonics (a machine's, not the structure's; see
    /// [`covssi::harmonic`]): not among the modes.
    #[cfg_attr(feature = "serde", serde(default))]
    pub harmonics: Vec<Harmonic>,
    /// The record's length (samples; 0 when not known), to tell a record far shorter than
    /// the campaign's others.
    #[cfg_attr(feature = "serde", serde(default))]
    pub samples: usize,
    /// The record's RMS response: the root of its channels' mean variance (0 when not
    /// known).
    #[cfg_attr(feature = "serde", serde(default))]
    pub rms: f64,
    /// The record's output correlations, for the subspace damage test
    /// ([`crate::subspace`]).
    #[cfg_attr(feature = "serde", serde(default))]
    pub correlations: Option<crate::subspace::Correlations>,
}

/// A pole taken for a harmonic.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Harmonic {
    /// Its frequency (Hz).
    pub frequency_hz: f64,
    /// The kurtosis of the response band-passed around it (1.5 for a sinusoid, 3 for a
    /// mode under random loads).
    pub kurtosis: f64,
}

/// The modes of one record, identified by SSI-COV and refined as `hyst ssi` does, once the
/// record has passed [`screen`](crate::screen::screen) (no value that is not a number, no
/// stuck or clipped channel); a machine's steady spectral lines subtracted first and the
/// poles the analysis's decision takes for harmonics ([`covssi::decision`]), both named in
/// `harmonics`.
pub fn identify_record(
    channels: &[&[f64]],
    fs: f64,
    opts: &covssi::AnalysisOptions,
) -> Result<Identified, MonitorError> {
    crate::screen::screen(channels)?;
    // A machine's steady lines taken out before the analysis: left in, a line bends the
    // refinement's fit into spurious poles beside the modes.
    let mut harmonics = Vec::new();
    let raw = covssi::harmonic::HarmonicTest::new(channels, fs);
    let lines = raw.harmonic_lines();
    let cleaned: Option<Vec<Vec<f64>>> = (!lines.is_empty()).then(|| {
        let mut data: Vec<Vec<f64>> = channels.iter().map(|c| c.to_vec()).collect();
        for &(f, kurtosis) in &lines {
            let frequency_hz = covssi::harmonic::subtract_sinusoid(&mut data, fs, f);
            harmonics.push(Harmonic {
                frequency_hz,
                kurtosis,
            });
        }
        data
    });
    let views: Vec<&[f64]> = match &cleaned {
        Some(data) => data.iter().map(|c| c.as_slice()).collect(),
        None => channels.to_vec(),
    };
    let analysis = covssi::analyze(&views, fs, opts)?;
    let modes = reported_modes(&analysis);
    // The poles the analysis's decision set apart as harmonics (covssi::decision), named.
    for s in &analysis.decision.set_apart {
        for r in &s.reasons {
            if let covssi::NotAMode::Harmonic { kurtosis } = r {
                harmonics.push(Harmonic {
                    frequency_hz: s.frequency_hz,
                    kurtosis: *kurtosis,
                });
            }
        }
    }
    Ok(Identified {
        modes,
        misfit: analysis.refined.as_ref().map(|r| r.misfit),
        harmonics,
        samples: channels.first().map_or(0, |c| c.len()),
        rms: rms(&views),
        correlations: Some(crate::subspace::Correlations::of(
            &views,
            crate::subspace::lags_kept(views.len()),
        )),
    })
}

/// The root of the channels' mean variance.
fn rms(channels: &[&[f64]]) -> f64 {
    let var = |c: &[f64]| {
        let n = c.len().max(1) as f64;
        let mean = c.iter().sum::<f64>() / n;
        c.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n
    };
    (channels.iter().map(|c| var(c)).sum::<f64>() / channels.len().max(1) as f64).sqrt()
}

/// The modes an analysis reports (the refined ones when the refinement holds, else SSI's),
/// as tracking takes them: a record's, or a reference's (`hyst ssi --json` read back).
pub fn reported_modes(analysis: &covssi::ModalAnalysis) -> Vec<ModeEstimate> {
    analysis
        .reported_modes()
        .into_iter()
        .map(|m| ModeEstimate {
            frequency_hz: m.frequency_hz,
            frequency_se_hz: m.frequency_se_hz,
            damping_ratio: m.damping_ratio,
            damping_se: m.damping_se,
            shape: m.shape,
        })
        .collect()
}

/// The campaign's analysis: `opts` with what it leaves to the record (the decimation, the
/// lag) read from the first of the first 24 records that `resolve` can read it from
/// (`resolve(i)`: record i's [`covssi::AnalysisOptions::resolved_for`], `None` when it cannot
/// be read or analysed), and kept for every record, so that each is analysed alike; with the
/// record it came from. `opts` as given when none can.
pub fn campaign_analysis(
    opts: &covssi::AnalysisOptions,
    records: usize,
    resolve: &dyn Fn(usize) -> Option<covssi::AnalysisOptions>,
) -> (covssi::AnalysisOptions, Option<usize>) {
    (0..records.min(24))
        .find_map(|i| resolve(i).map(|o| (o, Some(i))))
        .unwrap_or_else(|| (opts.clone(), None))
}

/// A record as loaded for identification.
#[derive(Debug, Clone, PartialEq)]
pub struct Loaded {
    /// The channels.
    pub channels: Vec<Vec<f64>>,
    /// The sampling rate (Hz).
    pub fs: f64,
    /// When it was recorded (s).
    pub time: f64,
    /// Its covariates (NaN where missing).
    pub covariates: Vec<f64>,
}

/// Identify the records `names` in parallel (rayon), one loaded at a time per worker:
/// `load(i)` gives record i or why it cannot be read, and is called at most once for each i
/// (so it may hand over data it holds). A record named in `done` (an earlier, interrupted
/// run's) is taken from there, not identified again; `finished` hears each newly identified
/// record as it completes (to append it to a resumable output). The records come back in the
/// order of `names`.
pub fn identify_records(
    names: &[String],
    load: &(dyn Fn(usize) -> Result<Loaded, String> + Sync),
    opts: &covssi::AnalysisOptions,
    done: &[RecordModes],
    finished: &(dyn Fn(&RecordModes) + Sync),
) -> Vec<RecordModes> {
    use rayon::prelude::*;
    names
        .par_iter()
        .enumerate()
        .map(|(i, name)| {
            if let Some(r) = done.iter().find(|r| &r.name == name) {
                return r.clone();
            }
            let r = match load(i) {
                Ok(l) => {
                    let views: Vec<&[f64]> = l.channels.iter().map(|c| c.as_slice()).collect();
                    RecordModes {
                        name: name.clone(),
                        time: l.time,
                        covariates: l.covariates,
                        outcome: identify_record(&views, l.fs, opts).map_err(|e| e.to_string()),
                    }
                }
                Err(why) => RecordModes {
                    name: name.clone(),
                    time: f64::NAN,
                    covariates: Vec::new(),
                    outcome: Err(why),
                },
            };
            finished(&r);
            r
        })
        .collect()
}
