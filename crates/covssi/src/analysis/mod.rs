//! The whole modal analysis of a record in one call: SSI ([`identify`](crate::identify())), the MAC between its
//! modes, then the maximum-likelihood refinement ([`refine_with_real_poles`]), as one report
//! that prints as text ([`std::fmt::Display`], in `text`) and serializes (feature `serde`).

#[cfg(feature = "serde")]
mod document;
mod text;

pub use text::shape_text;

use crate::decision::{Evidence, ModeCriteria, ModeDecision, ModeSource, ReportedMode};
use crate::plausibility::{NotReported, not_physical};
use crate::progress::Progress;
use crate::{
    RecordSurvey, RefineOptions, Refinement, SsiError, SsiOption, SsiOptions, SsiResult, mac,
};

/// Whether the record is decimated before the analysis.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum Decimation {
    /// Read from the record's spectrum ([`RecordSurvey::decimation`]): by the largest factor
    /// that keeps 2.5 times the band holding 99 % of its power, and every spectral peak,
    /// below the new Nyquist. The default.
    #[default]
    Auto,
    /// By this factor (1: not decimated).
    Factor(usize),
}

/// Options of [`analyze`]: the decimation, SSI's, and the refinement's (`None`: SSI alone).
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
#[non_exhaustive]
pub struct AnalysisOptions {
    /// The decimation before SSI ([`crate::decimate`]). Default: [`Decimation::Auto`].
    pub decimation: Decimation,
    /// SSI's options.
    pub ssi: SsiOptions,
    /// The refinement's options; `None` skips it. Default: `None`, SSI's modes with the
    /// jackknife's errors: on the loads users have (coloured, band-limited, modulated) the
    /// refinement's model (a white load) rarely holds, the answer is then SSI's anyway, and
    /// the refinement's fits cost half as much again as the rest (docs/covssi.md, "Where the
    /// refinement gains"). Ask for it (`Some(RefineOptions::default())`) on records under a
    /// broadband white load, where it gains most.
    pub refine: Option<RefineOptions>,
    /// Standard errors for SSI's modes: the jackknife over at most this many blocks of the
    /// record ([`crate::jackknife`]). They are the reported errors where SSI's modes are the
    /// answer, and the decision of what is a mode reads them ([`crate::decision`]). Default
    /// [`JACKKNIFE_BLOCKS`]; `None` leaves SSI's modes without errors and the decision
    /// without its rules 2 and 3.
    pub ssi_errors: Option<usize>,
    /// The rules that set candidates apart as not modes ([`crate::decision`]).
    pub modes: ModeCriteria,
    /// The frequency-domain decomposition of the record analysed (after the decimation, so
    /// the record is decimated once) with these options, for a page to draw behind the
    /// stabilization diagram and EFDD's second opinion ([`ModalAnalysis::fdd`]). Default
    /// `None`: not computed.
    pub fdd: Option<crate::fdd::FddOptions>,
}

/// The jackknife's blocks by default ([`AnalysisOptions::ssi_errors`]).
pub const JACKKNIFE_BLOCKS: usize = 10;

impl Default for AnalysisOptions {
    fn default() -> Self {
        AnalysisOptions {
            decimation: Decimation::Auto,
            ssi: SsiOptions::default(),
            refine: None,
            ssi_errors: Some(JACKKNIFE_BLOCKS),
            modes: ModeCriteria::default(),
            fdd: None,
        }
    }
}

/// The decimation factor `decimation` gives for the checked channels `y` (`checked`: their
/// length and means) at `fs` Hz, and the survey that chose it ([`Decimation::Auto`]).
fn decimation_of(
    y: &[&[f64]],
    fs: f64,
    (n, means): &(usize, Vec<f64>),
    decimation: Decimation,
) -> Result<(usize, Option<RecordSurvey>), SsiError> {
    match decimation {
        Decimation::Factor(0) => Err(SsiError::InvalidOption {
            option: SsiOption::Decimation,
            value: 0.0,
        }),
        Decimation::Factor(r) => Ok((r, None)),
        Decimation::Auto => {
            let s = crate::survey::surveyed(y, fs, means, *n);
            Ok((s.decimation(*n), Some(s)))
        }
    }
}

/// What a decimation by `r` the options gave filters out: the spectral peaks of the record
/// (`y` at `fs` Hz) above the new Nyquist less the low-pass's taper, said with the largest
/// factor that keeps them. A note, not an error: decimating to study a band below other
/// modes is an analyst's choice (the F-16's torsion mode, below a peak at 50 Hz), but it
/// must not pass silently.
fn peaks_filtered_out(
    y: &[&[f64]],
    fs: f64,
    (n, means): &(usize, Vec<f64>),
    r: usize,
) -> Option<String> {
    let s = crate::survey::surveyed(y, fs, means, *n);
    let kept = |r: usize| (1.0 - crate::decimate::TAPER) * fs / (2.0 * r as f64);
    let lost: Vec<String> = s
        .peaks_hz
        .iter()
        .filter(|&&p| p > kept(r))
        .map(|p| format!("{p:.4}"))
        .collect();
    let top = *s.peaks_hz.last()?;
    let largest = (1..r).rev().find(|&k| top <= kept(k)).unwrap_or(1);
    (!lost.is_empty()).then(|| {
        format!(
            "decimating by {r} puts Nyquist at {:.4} Hz: the record's spectral peak(s) at {} Hz are filtered out, and any mode there is not analysed (decimating by {largest} at most keeps them)",
            fs / (2.0 * r as f64),
            lost.join(", ")
        )
    })
}

/// How the record was decimated before the analysis.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct DecimationReport {
    /// The factor (1: not decimated).
    pub factor: usize,
    /// The record's own rate (Hz); [`ModalAnalysis::fs_hz`] is this over `factor`.
    pub recorded_fs_hz: f64,
    /// The survey of the record at its own rate that chose the factor
    /// ([`Decimation::Auto`]); `None` when the options gave it.
    pub survey: Option<RecordSurvey>,
}

impl AnalysisOptions {
    /// These options with the decimation set to `decimation`.
    pub fn with_decimation(mut self, decimation: Decimation) -> Self {
        self.decimation = decimation;
        self
    }

    /// These options with what they leave to the record ([`Decimation::Auto`],
    /// [`BlockRows::Auto`](crate::BlockRows::Auto)) read from `y` sampled at `fs` Hz, as
    /// [`analyze`] would read them, and fixed: for a campaign of records of one structure,
    /// read once (from its first record) and kept for every record, so that each record is
    /// analysed alike. (A largest order left open stays at most 40: the four per spectral
    /// peak that [`BlockRows::Auto`](crate::BlockRows::Auto) allows beyond ten peaks is
    /// not carried over.)
    pub fn resolved_for(&self, y: &[&[f64]], fs: f64) -> Result<AnalysisOptions, SsiError> {
        crate::checks::check_fs(fs)?;
        let checked = crate::checks::check_channels(y)?;
        let (factor, survey) = decimation_of(y, fs, &checked, self.decimation)?;
        let mut opts = self.clone();
        opts.decimation = Decimation::Factor(factor);
        if self.ssi.block_rows == crate::BlockRows::Auto {
            let decimated = crate::decimate::decimate_channels(y, factor);
            let choice = if factor > 1 {
                let views: Vec<&[f64]> = decimated.iter().map(|c| c.as_slice()).collect();
                let (n, means) = crate::checks::check_channels(&views)?;
                let fs = fs / factor as f64;
                let known = survey.map(|s| s.decimated(factor));
                crate::identify::block_rows_for(&views, fs, (n, &means), &self.ssi, known)?
            } else {
                let (n, means) = &checked;
                crate::identify::block_rows_for(y, fs, (*n, means), &self.ssi, survey)?
            };
            opts.ssi.block_rows = crate::BlockRows::Count(choice.block_rows);
            if choice.chosen.is_some() {
                opts.ssi.references = Some(choice.references);
            }
        }
        Ok(opts)
    }

    /// The options that are wrong whatever the record, checked before one is read (as
    /// [`analyze`] checks them): the counts and thresholds, a lag given as a time or as
    /// periods, the modes' damping limit. A campaign checks them once, up front, rather than
    /// skipping every record for the same option.
    pub fn check(&self) -> Result<(), SsiError> {
        crate::checks::check_options(&self.ssi)?;
        self.ssi.block_rows.check()?;
        let limit = self.modes.max_damping_ratio;
        if !(limit > 0.0 && limit < 1.0) {
            return Err(SsiError::InvalidOption {
                option: SsiOption::ModeMaxDamping,
                value: limit,
            });
        }
        Ok(())
    }

    /// These options with SSI's set to `ssi`.
    pub fn with_ssi(mut self, ssi: SsiOptions) -> Self {
        self.ssi = ssi;
        self
    }

    /// These options with the refinement's set to `refine` (`None`: SSI alone).
    pub fn with_refine(mut self, refine: Option<RefineOptions>) -> Self {
        self.refine = refine;
        self
    }

    /// These options with SSI's modes given jackknife errors over at most `blocks` blocks
    /// when they are reported (`None`: no errors).
    pub fn with_ssi_errors(mut self, blocks: Option<usize>) -> Self {
        self.ssi_errors = blocks;
        self
    }

    /// These options with the record's FDD computed with `fdd` (`None`: not computed).
    pub fn with_fdd(mut self, fdd: Option<crate::fdd::FddOptions>) -> Self {
        self.fdd = fdd;
        self
    }
}

/// What [`analyze`] finds: SSI's result, the MAC between its modes, the refinement, and the
/// decision of what is a mode. In JSON (feature `serde`) the answer is `modes`, SSI's
/// clusters `ssi_modes`, SSI's other fields at the top level, and `decision` the answer's
/// source and what it set apart (`document`; the `hyst` crate's report reader takes the
/// layout before it too).
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(
    feature = "serde",
    serde(
        into = "document::ModalAnalysisDocument",
        from = "document::ModalAnalysisDocument"
    )
)]
pub struct ModalAnalysis {
    /// The channels' names, in the order given: their indices from [`analyze`]; a caller
    /// that knows their names sets them (they head the shapes in the text).
    pub channels: Vec<String>,
    /// The sampling rate analysed (Hz): the record's over the decimation factor.
    pub fs_hz: f64,
    /// How the record was decimated first.
    pub decimation: DecimationReport,
    /// SSI's result.
    pub ssi: SsiResult,
    /// MAC between SSI's modes (1 on the diagonal).
    pub mac: Vec<Vec<f64>>,
    /// The refinement; `None` when it was not asked for, SSI found nothing to refine, or it
    /// failed (`not_refined` says why).
    pub refined: Option<Refinement>,
    /// Why the refinement asked for gave no result (e.g. a record too short for the modes SSI
    /// found): SSI's result stands, and the report says so rather than failing.
    pub not_refined: Option<String>,
    /// The refined modes and real poles that are not physical (damped at the limit, at
    /// Nyquist or 0 Hz, a real pole outside the band, a standard error above the value):
    /// kept in the fit, not reported ([`crate::plausibility`]).
    pub not_reported: Vec<NotReported>,
    /// Jackknife errors of SSI's modes ([`AnalysisOptions::ssi_errors`]); `None` when not
    /// asked for, or when the record is too short for the blocks.
    pub ssi_errors: Option<crate::jackknife::SsiErrors>,
    /// Why the errors asked for were not made: the record is too short for the jackknife's
    /// blocks (its modes then go unconfirmed, and the report says so).
    #[cfg_attr(feature = "serde", serde(default))]
    pub no_errors: Option<String>,
    /// What is a mode: the answer, which list it is, and what was set apart and why
    /// ([`crate::decision`]).
    pub decision: ModeDecision,
    /// The FDD of the record analysed, when asked for ([`AnalysisOptions::fdd`]) and the
    /// record long enough for its segments, with the options it was made with (EFDD reads
    /// them). A page's, not the report's: not serialized.
    pub fdd: Option<(crate::fdd::Fdd, crate::fdd::FddOptions)>,
}

/// The channels `y` sampled at `fs` Hz decimated as `opts.decimation` says, SSI on them,
/// then the refinement of its modes and real poles when `opts.refine` asks for it and SSI
/// found any. An error of SSI is this function's; an error of the refinement leaves SSI's
/// result, with [`ModalAnalysis::not_refined`] saying why.
pub fn analyze(y: &[&[f64]], fs: f64, opts: &AnalysisOptions) -> Result<ModalAnalysis, SsiError> {
    analyze_with_progress(y, fs, opts, &|_| {})
}

/// [`analyze`], telling `progress` of each step as it starts: SSI, then the refinement's
/// steps ([`crate::refine::refine_with_progress`]).
pub fn analyze_with_progress(
    y: &[&[f64]],
    fs: f64,
    opts: &AnalysisOptions,
    progress: &(dyn Fn(Progress) + Sync),
) -> Result<ModalAnalysis, SsiError> {
    crate::checks::check_fs(fs)?;
    opts.check()?;
    let checked = crate::checks::check_channels(y)?;
    let (factor, survey) = decimation_of(y, fs, &checked, opts.decimation)?;
    let decimated = crate::decimate::decimate_channels(y, factor);
    let views: Vec<&[f64]> = if factor > 1 {
        decimated.iter().map(|c| c.as_slice()).collect()
    } else {
        y.to_vec()
    };
    let y_recorded = y;
    let y = views.as_slice();
    let recorded_fs = fs;
    let fs = fs / factor as f64;
    // The survey that chose the factor is the one SSI's lag is read from, restated at the
    // new rate: not made twice, and not at a coarser resolution.
    let known = survey.as_ref().map(|s| s.decimated(factor));
    let (mut ssi, basis) =
        crate::identify::identify_surveyed_with_basis(y, fs, &opts.ssi, known, progress)?;
    if let Decimation::Factor(r) = opts.decimation
        && r > 1
    {
        ssi.notes
            .extend(peaks_filtered_out(y_recorded, recorded_fs, &checked, r));
    }
    // The refinement's steps follow SSI's on one count.
    let before = crate::identify::SSI_STEPS_BEFORE_ORDERS + ssi.diagram.orders.len();
    let after_ssi = |p: Progress| {
        progress(Progress {
            done: before + p.done,
            total: before + p.total,
            what: p.what,
        })
    };
    let mac = ssi
        .modes
        .iter()
        .map(|a| ssi.modes.iter().map(|b| mac(&a.shape, &b.shape)).collect())
        .collect();
    let (refined, not_refined) = match &opts.refine {
        Some(r) if !(ssi.modes.is_empty() && ssi.real_poles.is_empty()) => {
            match crate::refine::refine_with_progress(
                y,
                fs,
                &ssi.modes,
                &ssi.real_poles,
                r,
                &after_ssi,
            ) {
                Ok(refined) => (Some(refined), None),
                // An option of the refinement out of range is the caller's to hear.
                Err(e @ SsiError::InvalidOption { .. }) => return Err(e),
                Err(e) => (None, Some(e.to_string())),
            }
        }
        _ => (None, None),
    };
    let samples = y.first().map_or(0, |c| c.len());
    let not_reported = refined.as_ref().map_or_else(Vec::new, |r| {
        not_physical(r, fs, samples, opts.ssi.max_damping)
    });
    let ssi_errors = match opts.ssi_errors {
        Some(blocks) => {
            let refs = ssi.references.clone();
            let (_, means) = crate::checks::check_channels(y)?;
            crate::jackknife::ssi_errors(y, fs, (&refs, &means), (&ssi, &basis), &opts.ssi, blocks)?
        }
        None => None,
    };
    let no_errors = opts
        .ssi_errors
        .and_then(|_| too_short_for_errors(samples, ssi.block_rows, fs));
    let evidence = Evidence {
        y,
        fs,
        ssi: &ssi,
        errors: ssi_errors.as_ref(),
    };
    let reasons = crate::decision::ssi_reasons(&evidence, &opts.modes);
    let decision = crate::decision::decide(
        &ssi,
        ssi_errors.as_ref(),
        reasons,
        refined.as_ref(),
        &not_reported,
        &opts.modes,
    );
    // A record too short for the FDD's segments still has its modes: the page goes without.
    let fdd = opts
        .fdd
        .as_ref()
        .and_then(|o| crate::fdd::fdd(y, fs, o).ok().map(|f| (f, o.clone())));
    Ok(ModalAnalysis {
        channels: (0..y.len()).map(|c| c.to_string()).collect(),
        fs_hz: fs,
        decimation: DecimationReport {
            factor,
            recorded_fs_hz: recorded_fs,
            survey,
        },
        ssi,
        mac,
        refined,
        not_refined,
        not_reported,
        ssi_errors,
        no_errors,
        decision,
        fdd,
    })
}

/// Why a record of `samples` at `fs` Hz, SSI's lag `block_rows`, is too short for the
/// jackknife's errors, with the shortest record they need; `None` when it is long enough.
fn too_short_for_errors(samples: usize, block_rows: usize, fs: f64) -> Option<String> {
    use crate::jackknife::{MIN_BLOCK_LAGS, MIN_BLOCKS, samples_needed};
    let lags = 2 * block_rows;
    let needed = samples_needed(block_rows);
    (samples < needed).then(|| format!(
        "the record is too short to confirm modes: {samples} samples ({:.1} s) hold {} of SSI's lags ({lags} samples), and the jackknife's errors need {MIN_BLOCKS} blocks of {MIN_BLOCK_LAGS} lags, {needed} samples ({:.1} s) at least; any mode reported is unconfirmed, without errors",
        samples as f64 / fs,
        samples / lags.max(1),
        needed as f64 / fs
    ))
}

impl ModalAnalysis {
    /// The refinement when its modes are the answer ([`ModalAnalysis::decision`]); `None`
    /// when SSI's modes are.
    pub fn reported_refinement(&self) -> Option<&Refinement> {
        self.refined
            .as_ref()
            .filter(|_| self.decision.source == ModeSource::Refined)
    }

    /// Whether the refined mode (`real_pole` false) or real pole `index` is physical
    /// (see [`ModalAnalysis::not_reported`]).
    pub fn is_reported(&self, index: usize, real_pole: bool) -> bool {
        !self
            .not_reported
            .iter()
            .any(|n| n.index == index && n.real_pole == real_pole)
    }

    /// The modes to report: the decision's answer ([`crate::decision`]), by frequency.
    pub fn reported_modes(&self) -> Vec<ReportedMode> {
        self.decision.modes.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::refine_with_real_poles;

    /// A decaying 3 Hz oscillation at 50 Hz with a little deterministic noise, and options
    /// of at most 10 model orders.
    /// The default options with the refinement asked for.
    fn refined() -> AnalysisOptions {
        AnalysisOptions::default().with_refine(Some(RefineOptions::default()))
    }

    /// By default the answer is SSI's with the jackknife's errors: no refinement is run.
    #[test]
    fn the_default_is_ssi_with_its_errors_not_the_refinement() {
        let d = AnalysisOptions::default();
        assert!(d.refine.is_none());
        assert_eq!(d.ssi_errors, Some(JACKKNIFE_BLOCKS));
    }

    fn decay_record() -> (f64, Vec<f64>, AnalysisOptions) {
        let fs = 50.0;
        let y: Vec<f64> = (0..6000)
            .map(|n| {
                let t = n as f64 / fs;
                (-0.4 * t).exp() * (2.0 * std::f64::consts::PI * 3.0 * t).cos()
                    + 0.01 * ((n * 7919) % 97) as f64 / 97.0
            })
            .collect();
        let opts = refined().with_ssi(SsiOptions {
            max_order: Some(10),
            ..SsiOptions::default()
        });
        (fs, y, opts)
    }

    /// A decimation that filters out a mode the spectrum shows is said, with the largest
    /// factor that keeps it: by 5, Nyquist is 5 Hz, below the 6 Hz mode; by 4 it is
    /// 6.25 Hz, the low-pass flat to 6.125 Hz, and nothing is said.
    #[test]
    fn a_decimation_below_a_peak_is_said() {
        let y = crate::synth::two_modes(20_000, 5_800_001);
        let views: Vec<&[f64]> = y.iter().map(|c| c.as_slice()).collect();
        let opts = AnalysisOptions::default().with_decimation(Decimation::Factor(5));
        let a = analyze(&views, 50.0, &opts).unwrap();
        let said = |a: &ModalAnalysis| {
            a.ssi
                .notes
                .iter()
                .find(|n| n.starts_with("decimating by"))
                .cloned()
        };
        let note = said(&a).unwrap_or_default();
        assert!(
            note.contains("Nyquist at 5.0000 Hz") && note.contains("decimating by 4 at most"),
            "{a}"
        );
        // The peak named within the survey's resolution (50/1024 Hz) of the mode.
        assert!(note.contains("at 5.9") || note.contains("at 6.0"), "{note}");
        let opts = AnalysisOptions::default().with_decimation(Decimation::Factor(4));
        let a = analyze(&views, 50.0, &opts).unwrap();
        assert_eq!(said(&a), None, "{a}");
    }

    /// A record too short for the jackknife's blocks says so: the errors asked for are not
    /// made, and why (not "give more block rows").
    #[test]
    fn a_record_too_short_for_errors_says_so() {
        let y = crate::synth::two_modes(300, 5_800_002);
        let views: Vec<&[f64]> = y.iter().map(|c| c.as_slice()).collect();
        let a = analyze(&views, 50.0, &AnalysisOptions::default()).unwrap();
        assert!(a.ssi_errors.is_none());
        let why = a.no_errors.as_deref().unwrap_or_default();
        assert!(
            why.contains("too short to confirm modes: 300 samples"),
            "{a}"
        );
        assert!(
            a.to_string()
                .contains("no standard errors: the record is too short")
        );
        let long = crate::synth::two_modes(30_000, 5_800_003);
        let views: Vec<&[f64]> = long.iter().map(|c| c.as_slice()).collect();
        let a = analyze(&views, 50.0, &AnalysisOptions::default()).unwrap();
        assert!(a.no_errors.is_none() && a.ssi_errors.is_some());
    }

    /// The analysis is SSI then the refinement, nothing more: the same modes as the two
    /// calls made by hand, and without refinement none.
    #[test]
    fn analysis_is_identify_then_refine() {
        let (fs, y, opts) = decay_record();
        let a = analyze(&[&y], fs, &opts).unwrap();
        let ssi = crate::identify(&[&y], fs, &opts.ssi).unwrap();
        assert_eq!(a.ssi, ssi);
        assert_eq!(a.channels, vec!["0".to_string()]);
        assert_eq!(a.mac.len(), ssi.modes.len());
        assert!(!ssi.modes.is_empty());
        let by_hand = refine_with_real_poles(
            &[&y],
            fs,
            &ssi.modes,
            &ssi.real_poles,
            &RefineOptions::default(),
        )
        .unwrap();
        assert_eq!(a.refined.as_ref(), Some(&by_hand));
        let text = a.to_string();
        // The decimation and the lag read from the record, said first.
        assert!(
            text.starts_with("not decimated: 99 % of the record's power"),
            "{text}"
        );
        let i = a.ssi.block_rows;
        assert!(
            text.contains(&format!(
                "{i} block rows: correlations up to lag {}",
                2 * i - 1
            )),
            "{text}"
        );
        assert!(
            text.contains("periods of the record's lowest spectral peak"),
            "{text}"
        );
        let none = analyze(&[&y], fs, &opts.clone().with_refine(None)).unwrap();
        assert!(none.refined.is_none() && none.not_refined.is_none());
    }

    /// Progress moves on every step: the correlations, the SVD, each of the 10 model orders,
    /// then the refinement's steps on the same count; never backwards, never past the total,
    /// and each order told once.
    #[test]
    fn progress_counts_every_order_and_the_refinement_after_them() {
        let (fs, y, opts) = decay_record();
        let seen = std::sync::Mutex::new(Vec::new());
        analyze_with_progress(&[&y], fs, &opts, &|p| {
            seen.lock()
                .unwrap()
                .push((p.done, p.total, p.what.to_string()))
        })
        .unwrap();
        let seen = seen.into_inner().unwrap();
        // "poles of 0 of 10" as the orders start, then one line as each is done.
        let orders = seen
            .iter()
            .filter(|s| s.2.starts_with("SSI: poles of"))
            .count();
        assert_eq!(orders, 1 + 10, "{seen:?}");
        assert!(
            seen.iter().all(|(done, total, _)| done <= total),
            "{seen:?}"
        );
        // Orders finish in any order on rayon's threads: SSI's counts are 0 … 12, each once.
        let mut ssi: Vec<usize> = seen
            .iter()
            .filter(|s| s.2.starts_with("SSI"))
            .map(|s| s.0)
            .collect();
        ssi.sort_unstable();
        assert_eq!(ssi, (0..=12).collect::<Vec<_>>(), "{seen:?}");
        let refining: Vec<usize> = seen
            .iter()
            .filter(|s| s.2.starts_with("refining"))
            .map(|s| s.0)
            .collect();
        assert!(!refining.is_empty(), "{seen:?}");
        assert!(refining[0] >= 12, "{seen:?}");
        assert!(refining.windows(2).all(|w| w[0] <= w[1]), "{seen:?}");
    }

    /// The options resolved on a record give that record the very analysis the automatic
    /// ones give it (the same decimation and block rows, the same modes), and fix them for
    /// the next record.
    #[test]
    fn resolved_options_analyse_the_record_as_the_automatic_ones() {
        // A 3 Hz resonance (damping 2 %) at 200 Hz driven by a pseudo-random sequence.
        let fs = 200.0;
        let mut state = 99u64;
        let mut y = vec![0.0; 40000];
        let w = 2.0 * std::f64::consts::PI * 3.0 / fs;
        let r = (-0.02 * w).exp();
        for k in 2..y.len() {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let e = (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
            y[k] = 2.0 * r * w.cos() * y[k - 1] - r * r * y[k - 2] + e;
        }
        let auto = AnalysisOptions::default().with_refine(None);
        let fixed = auto.resolved_for(&[&y], fs).unwrap();
        let a = analyze(&[&y], fs, &auto).unwrap();
        assert_eq!(fixed.decimation, Decimation::Factor(a.decimation.factor));
        assert_eq!(
            fixed.ssi.block_rows,
            crate::BlockRows::Count(a.ssi.block_rows)
        );
        assert!(
            a.decimation.factor > 1,
            "a 3 Hz record at 200 Hz is decimated"
        );
        let b = analyze(&[&y], fs, &fixed).unwrap();
        assert_eq!(b.ssi.modes, a.ssi.modes);
    }

    /// A record long enough for SSI but too short to refine its modes: SSI's result stands,
    /// and the report says why there is no refinement.
    #[test]
    fn a_refinement_that_cannot_run_leaves_ssi_and_says_why() {
        let fs = 50.0;
        let y: Vec<f64> = (0..150)
            .map(|n| {
                let t = n as f64 / fs;
                (-0.4 * t).exp() * (2.0 * std::f64::consts::PI * 3.0 * t).cos()
                    + (-0.3 * t).exp() * (2.0 * std::f64::consts::PI * 7.0 * t).sin()
            })
            .collect();
        let opts = refined().with_ssi(SsiOptions {
            max_order: Some(10),
            min_cluster_size: Some(2),
            ..SsiOptions::default()
        });
        let a = analyze(&[&y], fs, &opts).unwrap();
        assert!(!a.ssi.modes.is_empty(), "{a}");
        assert!(a.refined.is_none());
        let why = a.not_refined.as_deref().unwrap_or_default();
        assert!(why.contains("samples"), "{why}");
        assert!(a.to_string().contains("not refined: "));
    }
}
