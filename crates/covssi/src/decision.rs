//! What is a mode: the one decision every command shares (`ssi`, `--setups`, `amplitude`,
//! `track`, `frf` and Python all report [`ModeDecision::modes`]).
//!
//! SSI's stable clusters and the refinement's fitted poles are candidates. A careful analyst
//! keeps a candidate as a structural mode only when the evidence a structure leaves holds for
//! it; each rule below states that evidence, and a candidate that fails one is *set apart*
//! with its reason ([`NotAMode`]), never silently dropped:
//!
//! 1. **Physical damping**: a damping ratio at most [`ModeCriteria::max_damping_ratio`]
//!    (default 0.20). Structures' modes are damped by a few per cent, rarely 10 %; a pole
//!    damped by 30 % is the excitation's roll-off, a filter's edge, or a fit spending a pole
//!    on what its model lacks.
//! 2. **Found again in the record's parts**: the delete-one-block jackknife
//!    ([`crate::jackknife`]) re-runs SSI on each of $B$ replicates, each holding all but one
//!    block of the record. A structural mode is in the record throughout, so it is found in
//!    nearly every replicate; a pole found in fewer than [`ModeCriteria::min_found`] of them
//!    (default 0.8) is an accident of the record's noise.
//! 3. **A determined frequency**: a jackknife standard error at most
//!    [`ModeCriteria::max_frequency_cv`] (default 0.05) of the frequency. A mode's frequency
//!    is known to $\sigma_f/f \approx \sqrt{\zeta/(2\pi f T)}$ from a record of length $T$
//!    (under 1 % for ζ = 10 % over 100 periods); a "mode" known only to ±10 % at 95 % is no
//!    mode. (The damping's error is no such test: the jackknife reads a lightly damped
//!    mode's damping poorly when its blocks are shorter than the mode's decay — the steel
//!    frame's 2.1 Hz mode, 0.10 ± 0.11 % on one setup.)
//! 4. **Random, not steady**: a lightly damped pole whose band-passed response has the
//!    kurtosis of a sinusoid is a machine's harmonic, not a mode ([`crate::harmonic`]).
//! 5. **One shape, one peak**: two candidates within [`ModeCriteria::same_shape_band`]
//!    (default 15 %) of each other with a MAC of at least [`ModeCriteria::same_shape_mac`]
//!    (default 0.9), with two or more channels, are one mode and its shadow (a pole SSI
//!    adds beside a mode whose peak is not a rational spectrum's: nonlinearity, drift, a
//!    coloured load) unless the first singular value of the output spectrum ([`crate::fdd`])
//!    shows a peak at each with a valley below half the lower between them (the half-power
//!    criterion of two resolved modes). The mode is the one nearer the spectrum's peak (when
//!    their distances to it differ by more than a line), else the one stable over more model
//!    orders, else the one where the spectrum is higher.
//!
//! **The refinement replaces SSI only where it agrees.** SSI's modes that pass 1–5 are the
//! reference. The refinement holds when its misfit is within [`crate::MISFIT_LIMIT`] and
//! *each* of those modes has a refined counterpart (its source) that is physical
//! ([`crate::plausibility`]), damped within the limit, and agrees with it: frequency and
//! damping by Hausman's test (their difference within [`HAUSMAN_SIGMAS`] of
//! √(σ²_SSI − σ²_refined), the deviation it has where the likelihood's model holds), shape
//! MAC at least [`crate::jackknife::MIN_MAC`]. Then the
//! answer is those refined modes; a refined mode SSI does not support is set apart. Else the
//! refinement does not hold on the record, the report names the modes it lost, and the
//! answer is SSI's modes with their jackknife errors.

use std::fmt;

use crate::jackknife::SsiErrors;
use crate::plausibility::{NotPhysical, NotReported};
use crate::refine::MISFIT_LIMIT;
use crate::{Refinement, SsiResult, mac};

/// Two estimates of one mode differ by less than this many of the refined estimate's
/// standard errors when SSI's has none (a normal deviate beyond 4 has probability 6·10⁻⁵).
pub const AGREE_SIGMAS: f64 = 4.0;
/// Hausman's test: SSI's and the refinement's estimates differ by at most this many
/// standard deviations of their difference, √(σ²_SSI − σ²_refined). A jackknife over 10
/// blocks has 9 degrees of freedom: Student's t beyond 3 has probability 1.5 %, and a
/// record that fails falls back to SSI's modes, whose errors are calibrated — the test can
/// be strict at the cost of some precision, never of the errors' truth.
pub const HAUSMAN_SIGMAS: f64 = 3.0;
/// Relative frequency difference within which two estimates of one mode agree whatever
/// their errors (SSI's and the likelihood's frequencies differ by their biases, a fraction
/// of a per cent on a stationary record).
pub const FREQUENCY_FLOOR: f64 = 0.01;
/// Damping ratios within this factor of each other agree whatever their errors (SSI's
/// damping is biased by tens of per cent under noise; a factor three is no bias).
pub const DAMPING_FACTOR: f64 = 3.0;
/// Absolute damping-ratio difference that always agrees (half a percentage point: two
/// lightly damped estimates of one mode).
pub const DAMPING_FLOOR: f64 = 0.005;

/// The rules that set candidates apart (see the [module](self)).
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
#[non_exhaustive]
pub struct ModeCriteria {
    /// The largest damping ratio of a mode. Default 0.20.
    pub max_damping_ratio: f64,
    /// The largest jackknife frequency error, as a share of the frequency. Default 0.05.
    pub max_frequency_cv: f64,
    /// The least share of the jackknife's replicates that must find a mode. Default 0.8.
    pub min_found: f64,
    /// The least MAC at which two near candidates have one shape. Default 0.9.
    pub same_shape_mac: f64,
    /// Relative frequency distance within which two candidates of one shape are one mode
    /// and its shadow unless the spectrum shows two peaks. Default 0.15.
    pub same_shape_band: f64,
}

impl Default for ModeCriteria {
    fn default() -> Self {
        ModeCriteria {
            max_damping_ratio: 0.20,
            max_frequency_cv: 0.05,
            min_found: crate::jackknife::MIN_FOUND,
            same_shape_mac: 0.9,
            same_shape_band: 0.15,
        }
    }
}

/// Why a candidate is not a structural mode.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case", tag = "reason"))]
#[non_exhaustive]
pub enum NotAMode {
    /// Damped above [`ModeCriteria::max_damping_ratio`].
    Overdamped {
        /// The damping ratio.
        damping_ratio: f64,
        /// The limit.
        limit: f64,
    },
    /// Found in too few of the jackknife's replicates.
    NotFoundAgain {
        /// Replicates that found it.
        found: usize,
        /// Replicates made.
        replicates: usize,
    },
    /// A frequency error above [`ModeCriteria::max_frequency_cv`] of the frequency.
    FrequencyUndetermined {
        /// The standard error (Hz).
        frequency_se_hz: f64,
        /// The frequency (Hz).
        frequency_hz: f64,
    },
    /// A steady sinusoid (a machine's harmonic), by its band-passed kurtosis.
    Harmonic {
        /// The kurtosis (1.5 a sinusoid, 3 a mode).
        kurtosis: f64,
    },
    /// The shadow of a mode of the same shape nearby, where the spectrum shows one peak.
    Shadow {
        /// The mode's frequency (Hz).
        of_hz: f64,
        /// The MAC between them.
        mac: f64,
    },
    /// A second refined estimate of the SSI mode another refined mode stands for.
    Duplicate {
        /// The SSI mode's frequency (Hz).
        of_hz: f64,
    },
    /// A refined estimate the likelihood does not make physical ([`NotPhysical`]).
    NotPhysical(NotPhysical),
    /// A refined mode whose SSI mode is set apart, or that no SSI mode supports.
    NoSsiSupport {
        /// Its SSI mode's frequency (Hz), when it has one.
        ssi_hz: Option<f64>,
    },
}

impl fmt::Display for NotAMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            NotAMode::Overdamped {
                damping_ratio,
                limit,
            } => write!(
                f,
                "damping ratio {damping_ratio:.3} above {limit} (a roll-off or a fit's spare pole, not a structure's mode; --max-damping)"
            ),
            NotAMode::NotFoundAgain { found, replicates } => write!(
                f,
                "found in {found} of {replicates} parts of the record (the jackknife's replicates): not there throughout"
            ),
            NotAMode::FrequencyUndetermined {
                frequency_se_hz,
                frequency_hz,
            } => write!(
                f,
                "frequency {frequency_hz:.4} ± {frequency_se_hz:.4} Hz: the record does not determine it"
            ),
            NotAMode::Harmonic { kurtosis } => write!(
                f,
                "a steady sinusoid, not a randomly driven mode (band kurtosis {kurtosis:.2}; 1.5 a sinusoid, 3 a mode)"
            ),
            NotAMode::Shadow { of_hz, mac } => write!(
                f,
                "the shadow of the mode at {of_hz:.4} Hz (MAC {mac:.3}; the spectrum shows one peak)"
            ),
            NotAMode::Duplicate { of_hz } => write!(
                f,
                "a second estimate of SSI's mode at {of_hz:.4} Hz, which another refined mode stands for"
            ),
            NotAMode::NotPhysical(n) => write!(f, "{n}"),
            NotAMode::NoSsiSupport { ssi_hz: Some(h) } => {
                write!(f, "SSI's mode at {h:.4} Hz is set apart")
            }
            NotAMode::NoSsiSupport { ssi_hz: None } => write!(f, "no SSI mode supports it"),
        }
    }
}

/// Which list of candidates the answer is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum ModeSource {
    /// SSI's modes (with the jackknife's errors when made).
    Ssi,
    /// The refinement's modes.
    Refined,
}

/// A candidate set apart, and why.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SetApart {
    /// Whose candidate: SSI's mode or the refinement's.
    pub source: ModeSource,
    /// Its index among SSI's modes or the refinement's.
    pub index: usize,
    /// Frequency (Hz).
    pub frequency_hz: f64,
    /// Damping ratio.
    pub damping_ratio: f64,
    /// Every reason that applies.
    pub reasons: Vec<NotAMode>,
}

/// An SSI mode the refinement has no agreeing counterpart for.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct LostMode {
    /// SSI's frequency (Hz).
    pub frequency_hz: f64,
    /// SSI's damping ratio.
    pub damping_ratio: f64,
    /// The refined counterpart's frequency and damping ratio, when there is one (it
    /// disagrees, or is not physical); `None` when the refinement dropped the mode.
    pub refined: Option<(f64, f64)>,
}

/// Whether the refinement's modes are the answer.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case", tag = "verdict"))]
pub enum RefinementVerdict {
    /// Not asked for, or it could not run.
    NotRun,
    /// It holds: its modes are the answer.
    Holds,
    /// The record does not follow its model.
    Misfit {
        /// The misfit.
        misfit: f64,
        /// The limit.
        limit: f64,
    },
    /// It lost modes SSI found (dropped them, or moved them where SSI disagrees).
    LostModes {
        /// The modes lost.
        lost: Vec<LostMode>,
    },
    /// It spent a pole no structure has (damped above the limit) across SSI's modes: the
    /// record holds what its model lacks (a load's colour inside the band), and the modes
    /// under that pole share their peaks with it, so their dampings and errors are not
    /// theirs alone.
    SparePole {
        /// The pole: frequency (Hz) and damping ratio.
        pole: (f64, f64),
        /// SSI's modes within its half-power band (Hz).
        overlaps: Vec<f64>,
    },
}

/// A mode as reported: the refinement's, or SSI's when the refinement does not hold.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ReportedMode {
    /// Natural frequency (Hz).
    pub frequency_hz: f64,
    /// Its standard error (Hz): the refinement's, or for SSI's modes the jackknife's
    /// ([`AnalysisOptions::ssi_errors`](crate::AnalysisOptions::ssi_errors)); `None` when
    /// neither was made.
    pub frequency_se_hz: Option<f64>,
    /// Damping ratio.
    pub damping_ratio: f64,
    /// Its standard error: as `frequency_se_hz`'s.
    pub damping_se: Option<f64>,
    /// The shape, one entry per channel, its largest entry 1; `None` for a refined mode
    /// the refinement gave no shape and SSI no mode near it.
    pub shape: Option<Vec<crate::Complex64>>,
    /// Whether `shape` is SSI's (the mode's SSI mode's, where the refinement gave none).
    pub shape_from_ssi: bool,
    /// Standard error of each entry of `shape` (√E|δ|², 0 for the entry scaled to 1): the
    /// refinement's, or the jackknife's for SSI's shapes; `None` when neither was made.
    pub shape_se: Option<Vec<f64>>,
    /// The SSI mode it is (SSI's answer) or comes from (the refinement's), by its index
    /// among SSI's modes.
    pub ssi_mode: Option<usize>,
}

/// The decision: the modes reported, which list they come from, and what was set apart.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ModeDecision {
    /// Which list the answer is.
    pub source: ModeSource,
    /// The modes reported, by frequency.
    pub modes: Vec<ReportedMode>,
    /// The refinement's verdict.
    pub refinement: RefinementVerdict,
    /// Candidates set apart, each with its reasons (SSI's always; the refinement's when
    /// its modes are the answer).
    pub set_apart: Vec<SetApart>,
    /// SSI's modes the jackknife alone could not confirm (found in too few replicates, or
    /// its frequency undetermined) that an agreeing, physical refined mode confirms: a
    /// second, independent estimator finds them in the record. Only when the refinement
    /// holds; each with the jackknife's reasons.
    #[cfg_attr(feature = "serde", serde(default))]
    pub confirmed: Vec<SetApart>,
}

/// What the SSI-side rules need besides SSI's result: the record (decimated as analysed).
pub(crate) struct Evidence<'a> {
    pub y: &'a [&'a [f64]],
    pub fs: f64,
    pub ssi: &'a SsiResult,
    pub errors: Option<&'a SsiErrors>,
}

/// The reasons (empty for a mode) for each of SSI's modes, rules 1–5.
pub(crate) fn ssi_reasons(e: &Evidence<'_>, c: &ModeCriteria) -> Vec<Vec<NotAMode>> {
    let modes = &e.ssi.modes;
    let mut reasons: Vec<Vec<NotAMode>> = modes
        .iter()
        .enumerate()
        .map(|(i, m)| {
            let mut r = Vec::new();
            if m.damping_ratio > c.max_damping_ratio {
                r.push(NotAMode::Overdamped {
                    damping_ratio: m.damping_ratio,
                    limit: c.max_damping_ratio,
                });
            }
            if let Some(errors) = e.errors {
                let found = errors.found.get(i).copied().unwrap_or(0);
                if (found as f64) < c.min_found * errors.blocks as f64 {
                    r.push(NotAMode::NotFoundAgain {
                        found,
                        replicates: errors.blocks,
                    });
                }
                // A NaN error determines nothing either.
                if let Some(Some(me)) = errors.modes.get(i)
                    && (me.frequency_se_hz.is_nan()
                        || me.frequency_se_hz > c.max_frequency_cv * m.frequency_hz)
                {
                    r.push(NotAMode::FrequencyUndetermined {
                        frequency_se_hz: me.frequency_se_hz,
                        frequency_hz: m.frequency_hz,
                    });
                }
            }
            r
        })
        .collect();
    harmonics(e, &mut reasons);
    shadows(e, c, &mut reasons);
    reasons
}

/// Rule 4: the lightly damped modes that are steady sinusoids.
fn harmonics(e: &Evidence<'_>, reasons: &mut [Vec<NotAMode>]) {
    use crate::harmonic::{HarmonicTest, MAX_HARMONIC_DAMPING};
    let modes = &e.ssi.modes;
    if !modes.iter().any(|m| m.damping_ratio < MAX_HARMONIC_DAMPING) {
        return;
    }
    let test = HarmonicTest::new(e.y, e.fs);
    for (m, r) in modes.iter().zip(reasons.iter_mut()) {
        if let Some(kurtosis) = test.is_harmonic(m.frequency_hz, m.damping_ratio) {
            r.push(NotAMode::Harmonic { kurtosis });
        }
    }
}

/// Rule 5: of two near candidates of one shape, the one the spectrum does not peak at.
/// Only among candidates no other rule set apart.
fn shadows(e: &Evidence<'_>, c: &ModeCriteria, reasons: &mut [Vec<NotAMode>]) {
    let modes = &e.ssi.modes;
    if e.y.len() < 2 {
        return;
    }
    let mut pairs = Vec::new();
    for i in 0..modes.len() {
        for j in i + 1..modes.len() {
            let (a, b) = (&modes[i], &modes[j]);
            let apart =
                (a.frequency_hz - b.frequency_hz).abs() / a.frequency_hz.max(b.frequency_hz);
            let m = mac(&a.shape, &b.shape);
            if reasons[i].is_empty()
                && reasons[j].is_empty()
                && apart <= c.same_shape_band
                && m >= c.same_shape_mac
            {
                pairs.push((i, j, apart, m));
            }
        }
    }
    if pairs.is_empty() {
        return;
    }
    let Ok(spectrum) = crate::fdd::fdd(e.y, e.fs, &crate::fdd::FddOptions::default()) else {
        return;
    };
    let s1 = spectrum.first();
    let df = spectrum.frequencies_hz.get(1).copied().unwrap_or(1.0);
    let level = |f: f64| -> f64 {
        let k = ((f / df).round() as usize).min(s1.len().saturating_sub(1));
        s1.get(k).copied().unwrap_or(0.0)
    };
    // Closest pairs first: a shadow of a shadow is judged against the mode left.
    pairs.sort_by(|x, y| x.2.total_cmp(&y.2));
    for (i, j, apart, m) in pairs {
        if !(reasons[i].is_empty() && reasons[j].is_empty()) {
            continue;
        }
        let (fi, fj) = (modes[i].frequency_hz, modes[j].frequency_hz);
        // Two modes show as two peaks with a valley between them below half the lower
        // one (each peak's half-power band clear of the other's): windows half the
        // distance wide, so each peak found is its own.
        let peak_i = spectrum.mode_near(fi, apart / 2.0);
        let peak_j = spectrum.mode_near(fj, apart / 2.0);
        if let (Some(p), Some(q)) = (&peak_i, &peak_j)
            && p.line != q.line
        {
            let (lo, hi) = (p.line.min(q.line), p.line.max(q.line));
            let valley = s1[lo..=hi].iter().copied().fold(f64::INFINITY, f64::min);
            if valley <= 0.5 * s1[p.line].min(s1[q.line]) {
                continue;
            }
        }
        // The mode is the one nearer the spectrum's peak, when they are more than a line
        // apart from it; else the one stable over more model orders (the shadow comes and
        // goes with the order); else the one where the spectrum is higher.
        let peak = spectrum.mode_near(0.5 * (fi + fj), apart);
        let by_peak = peak.and_then(|p| {
            let (di, dj) = ((fi - p.frequency_hz).abs(), (fj - p.frequency_hz).abs());
            ((di - dj).abs() > df).then_some(di < dj)
        });
        let (ni, nj) = (modes[i].members.len(), modes[j].members.len());
        let i_is_mode = by_peak.unwrap_or(if ni != nj {
            ni > nj
        } else {
            level(fi) >= level(fj)
        });
        let (mode, shadow) = if i_is_mode { (i, j) } else { (j, i) };
        reasons[shadow].push(NotAMode::Shadow {
            of_hz: modes[mode].frequency_hz,
            mac: m,
        });
    }
}

/// Whether SSI's mode with these reasons is set apart only by the jackknife's rules (found
/// in too few replicates, frequency undetermined): rules an independent estimate of the
/// same mode can answer.
fn only_unconfirmed(reasons: &[NotAMode]) -> bool {
    !reasons.is_empty()
        && reasons.iter().all(|r| {
            matches!(
                r,
                NotAMode::NotFoundAgain { .. } | NotAMode::FrequencyUndetermined { .. }
            )
        })
}

/// The decision, given SSI's reasons, the refinement and its physical check.
pub(crate) fn decide(
    ssi: &SsiResult,
    errors: Option<&SsiErrors>,
    reasons: Vec<Vec<NotAMode>>,
    refined: Option<&Refinement>,
    not_reported: &[NotReported],
    c: &ModeCriteria,
) -> ModeDecision {
    let mut set_apart: Vec<SetApart> = ssi
        .modes
        .iter()
        .zip(&reasons)
        .enumerate()
        .filter(|(_, (_, r))| !r.is_empty())
        .map(|(index, (m, r))| SetApart {
            source: ModeSource::Ssi,
            index,
            frequency_hz: m.frequency_hz,
            damping_ratio: m.damping_ratio,
            reasons: r.clone(),
        })
        .collect();
    let kept: Vec<usize> = (0..ssi.modes.len())
        .filter(|&i| reasons[i].is_empty())
        .collect();
    let ssi_modes = || ssi_reported(ssi, errors, &kept);
    let Some(r) = refined else {
        return ModeDecision {
            source: ModeSource::Ssi,
            modes: ssi_modes(),
            refinement: RefinementVerdict::NotRun,
            set_apart,
            confirmed: Vec::new(),
        };
    };
    if r.misfit > MISFIT_LIMIT {
        return ModeDecision {
            source: ModeSource::Ssi,
            modes: ssi_modes(),
            refinement: RefinementVerdict::Misfit {
                misfit: r.misfit,
                limit: MISFIT_LIMIT,
            },
            set_apart,
            confirmed: Vec::new(),
        };
    }
    if let Some((pole, overlaps)) = spare_pole(r, ssi, &kept, c) {
        return ModeDecision {
            source: ModeSource::Ssi,
            modes: ssi_modes(),
            refinement: RefinementVerdict::SparePole { pole, overlaps },
            set_apart,
            confirmed: Vec::new(),
        };
    }
    let refined_reasons = refined_reasons(r, ssi, &reasons, not_reported, c);
    // Each of SSI's modes kept must have an agreeing, acceptable refined counterpart.
    let mut chosen = Vec::new();
    let mut lost = Vec::new();
    for &s in &kept {
        let sm = &ssi.modes[s];
        let se = errors.and_then(|e| e.modes.get(s)).and_then(|e| e.as_ref());
        let candidates: Vec<usize> = (0..r.modes.len())
            .filter(|&i| r.modes[i].source == Some(s))
            .collect();
        let ok = candidates
            .iter()
            .copied()
            .find(|&i| refined_reasons[i].is_empty() && agrees(&r.modes[i], sm, se));
        match ok {
            Some(i) => chosen.push(i),
            None => lost.push(LostMode {
                frequency_hz: sm.frequency_hz,
                damping_ratio: sm.damping_ratio,
                refined: candidates
                    .first()
                    .map(|&i| (r.modes[i].frequency_hz, r.modes[i].damping_ratio)),
            }),
        }
    }
    if !lost.is_empty() {
        return ModeDecision {
            source: ModeSource::Ssi,
            modes: ssi_modes(),
            refinement: RefinementVerdict::LostModes { lost },
            set_apart,
            confirmed: Vec::new(),
        };
    }
    let confirmed = confirm(
        ssi,
        r,
        &reasons,
        &refined_reasons,
        &mut chosen,
        &mut set_apart,
    );
    set_apart_refined(ssi, r, refined_reasons, &chosen, &mut set_apart);
    let mut modes = refined_reported(r, ssi, &chosen);
    modes.sort_by(|a, b| a.frequency_hz.total_cmp(&b.frequency_hz));
    ModeDecision {
        source: ModeSource::Refined,
        modes,
        refinement: RefinementVerdict::Holds,
        set_apart,
        confirmed,
    }
}

/// SSI's modes only the jackknife set apart (rules 2–3), confirmed by an agreeing,
/// acceptable refined mode not yet `chosen` (judged as without SSI's errors: the jackknife
/// gave none it can stand by): each confirmed is taken out of `set_apart` and returned, its
/// refined mode added to `chosen`.
fn confirm(
    ssi: &SsiResult,
    r: &Refinement,
    reasons: &[Vec<NotAMode>],
    refined_reasons: &[Vec<NotAMode>],
    chosen: &mut Vec<usize>,
    set_apart: &mut Vec<SetApart>,
) -> Vec<SetApart> {
    let mut confirmed = Vec::new();
    for s in (0..ssi.modes.len()).filter(|&s| only_unconfirmed(&reasons[s])) {
        let found = (0..r.modes.len()).find(|&i| {
            r.modes[i].source == Some(s)
                && !chosen.contains(&i)
                && refined_reasons[i].is_empty()
                && agrees(&r.modes[i], &ssi.modes[s], None)
        });
        if let Some(i) = found {
            chosen.push(i);
            if let Some(k) = set_apart
                .iter()
                .position(|a| a.source == ModeSource::Ssi && a.index == s)
            {
                confirmed.push(set_apart.remove(k));
            }
        }
    }
    confirmed
}

/// Every refined mode not `chosen`, set apart with its reasons: its own, else that its SSI
/// mode is set apart (and it did not confirm it), else that another refined mode took its
/// SSI mode.
fn set_apart_refined(
    ssi: &SsiResult,
    r: &Refinement,
    refined_reasons: Vec<Vec<NotAMode>>,
    chosen: &[usize],
    set_apart: &mut Vec<SetApart>,
) {
    for (i, (m, mut why)) in r.modes.iter().zip(refined_reasons).enumerate() {
        if chosen.contains(&i) {
            continue;
        }
        let unconfirmed = m.source.filter(|&s| {
            set_apart
                .iter()
                .any(|a| a.source == ModeSource::Ssi && a.index == s)
        });
        if why.is_empty()
            && let Some(s) = unconfirmed
        {
            why.push(NotAMode::NoSsiSupport {
                ssi_hz: Some(ssi.modes[s].frequency_hz),
            });
        }
        if why.is_empty() {
            why.push(NotAMode::Duplicate {
                of_hz: m
                    .source
                    .map_or(m.frequency_hz, |s| ssi.modes[s].frequency_hz),
            });
        }
        set_apart.push(SetApart {
            source: ModeSource::Refined,
            index: i,
            frequency_hz: m.frequency_hz,
            damping_ratio: m.damping_ratio,
            reasons: why,
        });
    }
}

/// SSI's modes `kept`, as reported (with their jackknife errors when made).
fn ssi_reported(ssi: &SsiResult, errors: Option<&SsiErrors>, kept: &[usize]) -> Vec<ReportedMode> {
    kept.iter()
        .map(|&i| {
            let m = &ssi.modes[i];
            let e = errors.and_then(|e| e.modes.get(i)).and_then(|e| e.as_ref());
            ReportedMode {
                frequency_hz: m.frequency_hz,
                frequency_se_hz: e.map(|e| e.frequency_se_hz),
                damping_ratio: m.damping_ratio,
                damping_se: e.map(|e| e.damping_se),
                shape: Some(m.shape.clone()),
                shape_se: e.map(|e| e.shape_se.clone()),
                shape_from_ssi: true,
                ssi_mode: Some(i),
            }
        })
        .collect()
}

/// Each refined mode's reasons: the likelihood's physical check, the damping limit, and
/// SSI's support (`reasons`: SSI's modes').
fn refined_reasons(
    r: &Refinement,
    ssi: &SsiResult,
    reasons: &[Vec<NotAMode>],
    not_reported: &[NotReported],
    c: &ModeCriteria,
) -> Vec<Vec<NotAMode>> {
    r.modes
        .iter()
        .enumerate()
        .map(|(i, m)| {
            let mut why: Vec<NotAMode> = not_reported
                .iter()
                .filter(|n| n.index == i && !n.real_pole)
                .flat_map(|n| n.reasons.iter().cloned().map(NotAMode::NotPhysical))
                .collect();
            if m.damping_ratio > c.max_damping_ratio {
                why.push(NotAMode::Overdamped {
                    damping_ratio: m.damping_ratio,
                    limit: c.max_damping_ratio,
                });
            }
            match m.source {
                Some(s)
                    if reasons
                        .get(s)
                        .is_some_and(|r| r.is_empty() || only_unconfirmed(r)) => {}
                Some(s) => why.push(NotAMode::NoSsiSupport {
                    ssi_hz: Some(ssi.modes[s].frequency_hz),
                }),
                None => why.push(NotAMode::NoSsiSupport { ssi_hz: None }),
            }
            why
        })
        .collect()
}

/// The refined modes `chosen`, as reported (SSI's shape where the refinement gave none).
fn refined_reported(r: &Refinement, ssi: &SsiResult, chosen: &[usize]) -> Vec<ReportedMode> {
    chosen
        .iter()
        .map(|&i| {
            let m = &r.modes[i];
            let ssi_shape = m.source.map(|s| ssi.modes[s].shape.clone());
            ReportedMode {
                frequency_hz: m.frequency_hz,
                frequency_se_hz: m.frequency_se_hz,
                damping_ratio: m.damping_ratio,
                damping_se: m.damping_se,
                shape_from_ssi: m.shape.is_none() && ssi_shape.is_some(),
                shape_se: m.shape.as_ref().and(m.shape_se.clone()),
                shape: m.shape.clone().or(ssi_shape),
                ssi_mode: m.source,
            }
        })
        .collect()
}

/// The refinement's most damped oscillating pole above the damping limit whose half-power
/// band, |f − f_pole| ≤ ζ_pole·f_pole, holds SSI modes kept, with those modes' frequencies.
/// Such a pole models the load's colour, not the structure; where it overlaps a mode the
/// likelihood can trade the mode's damping for the pole's (a 3-storey record under a load
/// resonant at 8.0 Hz, ζ 0.56: a spare pole at 7.87 Hz, 81 %, and mode 2's damping refined
/// to 0.0114 ± 0.0008 against a true 0.022; SSI: 0.0228 ± 0.0042). A pole beyond every
/// mode's band (a low-pass edge above the modes) does not.
fn spare_pole(
    r: &Refinement,
    ssi: &SsiResult,
    kept: &[usize],
    c: &ModeCriteria,
) -> Option<((f64, f64), Vec<f64>)> {
    r.modes
        .iter()
        .filter(|m| {
            m.damping_ratio > c.max_damping_ratio
                && m.damping_ratio.is_finite()
                && m.frequency_hz > 0.0
                && m.frequency_hz.is_finite()
        })
        .filter_map(|m| {
            let reach = m.damping_ratio.min(1.0) * m.frequency_hz;
            let overlaps: Vec<f64> = kept
                .iter()
                .map(|&s| ssi.modes[s].frequency_hz)
                .filter(|f| (f - m.frequency_hz).abs() <= reach)
                .collect();
            (!overlaps.is_empty()).then_some(((m.frequency_hz, m.damping_ratio), overlaps))
        })
        .max_by(|a, b| a.0.1.total_cmp(&b.0.1))
}

/// Whether refined mode `r` and SSI mode `s` (its jackknife errors `se`) are one mode's
/// estimates: frequency, damping and (when its shape has several channels) shape.
///
/// With SSI's errors, by Hausman's test: where the refinement's model holds, its estimate
/// is the efficient one and SSI's differs from it by a deviation of variance
/// σ²_SSI − σ²_refined (taken at least √(2/(B'−1))·σ²_SSI, the precision of the
/// jackknife's own variance over B' replicates, lest two nearly equal errors make the test
/// degenerate); a difference beyond [`HAUSMAN_SIGMAS`] of that says the record
/// holds what the likelihood's model lacks (a coloured or modulated load), and that its
/// errors would read too small. Without SSI's errors, within [`AGREE_SIGMAS`] of the
/// refined error or [`FREQUENCY_FLOOR`], and the damping within a factor
/// [`DAMPING_FACTOR`].
fn agrees(
    r: &crate::RefinedMode,
    s: &crate::Mode,
    se: Option<&crate::jackknife::ModeErrors>,
) -> bool {
    let df = (r.frequency_hz - s.frequency_hz).abs();
    let dd = (r.damping_ratio - s.damping_ratio).abs();
    let (frequency, damping) = match se {
        Some(e) => {
            // The jackknife's variance over B' replicates is known to a relative standard
            // deviation of √(2/(B'−1)) (0.47 for 10): the difference of two variances is
            // no better known than that share of SSI's, so it is not taken below it.
            let known = (2.0 / (e.replicates.max(2) - 1) as f64).sqrt().min(1.0);
            let hausman = |d: f64, ssi: f64, refined: Option<f64>| {
                let refined = refined.filter(|v| v.is_finite()).unwrap_or(0.0);
                let v = (ssi * ssi - refined * refined).max(known * ssi * ssi);
                d <= HAUSMAN_SIGMAS * v.sqrt()
            };
            (
                hausman(df, e.frequency_se_hz, r.frequency_se_hz),
                hausman(dd, e.damping_se, r.damping_se),
            )
        }
        None => {
            let sf = r.frequency_se_hz.filter(|v| v.is_finite()).unwrap_or(0.0);
            let sd = r.damping_se.filter(|v| v.is_finite()).unwrap_or(0.0);
            let (zr, zs) = (r.damping_ratio, s.damping_ratio);
            let ratio = zr.max(zs) / zr.min(zs).max(f64::MIN_POSITIVE);
            (
                df <= (AGREE_SIGMAS * sf).max(FREQUENCY_FLOOR * s.frequency_hz),
                dd <= (AGREE_SIGMAS * sd).max(DAMPING_FLOOR) || ratio <= DAMPING_FACTOR,
            )
        }
    };
    // A one-channel shape is a number: MAC says nothing there.
    let shape = match &r.shape {
        Some(shape) if s.shape.len() >= 2 => mac(shape, &s.shape) >= crate::jackknife::MIN_MAC,
        _ => true,
    };
    frequency && damping && shape
}

impl ModeDecision {
    /// One line: how many modes the answer holds, which list they are, and why.
    pub fn headline(&self) -> String {
        let why = match &self.refinement {
            RefinementVerdict::Holds => {
                "the refined modes: every SSI mode kept has its refined counterpart".to_string()
            }
            RefinementVerdict::NotRun => "SSI's modes (no refinement)".to_string(),
            RefinementVerdict::Misfit { misfit, limit } => format!(
                "SSI's modes: the record does not follow the refinement's model (misfit {misfit:.3} > {limit})"
            ),
            RefinementVerdict::LostModes { lost } => {
                let names: Vec<String> = lost
                    .iter()
                    .map(|l| match l.refined {
                        Some((hz, z)) => format!(
                            "{:.4} Hz (refined to {hz:.4} Hz, damping ratio {z:.3}: disagrees or not physical)",
                            l.frequency_hz
                        ),
                        None => format!("{:.4} Hz (dropped)", l.frequency_hz),
                    })
                    .collect();
                format!(
                    "SSI's modes: the refinement does not hold on this record; it lost {}",
                    names.join(", ")
                )
            }
            RefinementVerdict::SparePole { pole, overlaps } => {
                let f: Vec<String> = overlaps.iter().map(|f| format!("{f:.4}")).collect();
                format!(
                    "SSI's modes: the refinement spent a pole no structure has ({:.4} Hz, damping ratio {:.3}: the load's colour) across the modes at {} Hz, whose dampings it then shares",
                    pole.0,
                    pole.1,
                    f.join(", ")
                )
            }
        };
        format!("the answer ({} modes): {why}", self.modes.len())
    }

    /// Each candidate set apart as one line: whose, frequency, damping and reasons.
    pub fn set_apart_lines(&self) -> Vec<String> {
        self.set_apart
            .iter()
            .map(|s| {
                let whose = match s.source {
                    ModeSource::Ssi => "SSI",
                    ModeSource::Refined => "refined",
                };
                let why: Vec<String> = s.reasons.iter().map(|r| r.to_string()).collect();
                format!(
                    "set apart ({whose}) {:.4} Hz, damping ratio {:.4}: {}",
                    s.frequency_hz,
                    s.damping_ratio,
                    why.join("; ")
                )
            })
            .collect()
    }

    /// Each SSI mode the refinement confirmed as one line, with the jackknife's reasons it
    /// answers.
    pub fn confirmed_lines(&self) -> Vec<String> {
        self.confirmed
            .iter()
            .map(|s| {
                let why: Vec<String> = s.reasons.iter().map(|r| r.to_string()).collect();
                format!(
                    "confirmed by the refinement (SSI) {:.4} Hz, damping ratio {:.4}: {}; its refined estimate agrees",
                    s.frequency_hz,
                    s.damping_ratio,
                    why.join("; ")
                )
            })
            .collect()
    }

    /// The decision as the report prints it: which list is the answer and why, the modes
    /// numbered from 1, and every candidate set apart with its reasons.
    pub(crate) fn fmt_with(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "{}", self.headline())?;
        for (k, m) in self.modes.iter().enumerate() {
            let se = |v: Option<f64>| v.map_or("?".to_string(), |v| format!("{v:.4}"));
            writeln!(
                f,
                "  mode {:>2}  {:>9.4} ± {} Hz  damping ratio {:.4} ± {}",
                k + 1,
                m.frequency_hz,
                se(m.frequency_se_hz),
                m.damping_ratio,
                se(m.damping_se)
            )?;
        }
        if self.modes.iter().any(|m| m.frequency_se_hz.is_none()) {
            writeln!(
                f,
                "  (? : no standard error: the jackknife's need a long enough record and --ssi-errors above 0)"
            )?;
        }
        for line in self
            .confirmed_lines()
            .into_iter()
            .chain(self.set_apart_lines())
        {
            writeln!(f, "{line}")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{AnalysisOptions, analyze};

    use crate::synth::two_modes as record;

    fn refined_mode(frequency_hz: f64, damping_ratio: f64) -> crate::RefinedMode {
        crate::RefinedMode {
            source: Some(0),
            frequency_hz,
            damping_ratio,
            frequency_se_hz: Some(0.01 * frequency_hz),
            damping_se: Some(0.1 * damping_ratio),
            lambda: crate::Complex64::new(0.0, 0.0),
            shape: None,
            shape_se: None,
            mpc: None,
            evidence: 100.0,
        }
    }

    fn ssi_mode(frequency_hz: f64, damping_ratio: f64) -> crate::Mode {
        crate::Mode {
            frequency_hz,
            frequency_std_hz: 0.0,
            damping_ratio,
            damping_std: 0.0,
            shape: vec![crate::Complex64::new(1.0, 0.0)],
            shape_std: vec![0.0],
            members: vec![],
            lambda: crate::Complex64::new(0.0, 0.0),
            mpc: 1.0,
        }
    }

    #[test]
    fn estimates_of_one_mode_agree_and_a_fit_gone_elsewhere_does_not() {
        let s = ssi_mode(4.19, 0.0115);
        // Within the 1 % floor and the damping factor: one mode.
        assert!(agrees(&refined_mode(4.20, 0.012), &s, None));
        // Building test 1 of issue 57: refined to 4.02 Hz at 46.9 % against SSI's 4.19 Hz
        // at 1.15 % — 4 % away with a 1 % refined error (4 σ is 0.16 Hz, 0.17 Hz apart)
        // and a damping 40 times SSI's.
        assert!(!agrees(&refined_mode(4.02, 0.469), &s, None));
        // A damping 3.9 times SSI's and 7 refined errors away is something else's.
        assert!(!agrees(&refined_mode(4.19, 0.045), &s, None));
    }

    #[test]
    fn with_ssis_errors_the_difference_is_judged_by_hausmans_test() {
        let jack = |sf: f64, sd: f64| crate::jackknife::ModeErrors {
            frequency_se_hz: sf,
            damping_se: sd,
            shape_se: vec![0.0],
            replicates: 10,
        };
        let refined = |f: f64, sf: f64, z: f64, sd: f64| crate::RefinedMode {
            frequency_se_hz: Some(sf),
            damping_se: Some(sd),
            ..refined_mode(f, z)
        };
        // 1.2643 ± 0.0030 Hz (SSI) and 1.2549 ± 0.0013 Hz (refined): their difference
        // 0.0094 Hz against √(0.0030² − 0.0013²) = 0.0027 Hz is 3.5 deviations — a refined
        // estimate pulled by what its model lacks, its error too small.
        let s = ssi_mode(1.2643, 0.0149);
        let e = jack(0.0030, 0.0023);
        assert!(!agrees(
            &refined(1.2549, 0.0013, 0.0135, 0.0011),
            &s,
            Some(&e)
        ));
        // 0.0017 Hz apart against 0.0025: one mode.
        // Errors nearly equal (SSI's 0.000701, the refinement's 0.000700): 0.0003 apart is
        // one mode, not a difference against a vanishing deviation.
        let tight = jack(0.000701, 0.000701);
        let s1 = ssi_mode(1.0021, 0.0098);
        assert!(agrees(
            &refined(1.0017, 0.000700, 0.0095, 0.000700),
            &s1,
            Some(&tight)
        ));
        let s = ssi_mode(0.5006, 0.0279);
        let e = jack(0.0027, 0.0076);
        assert!(agrees(
            &refined(0.5023, 0.0011, 0.0229, 0.0022),
            &s,
            Some(&e)
        ));
        // A refined error as large as SSI's or larger: the difference is judged against
        // √0.47 of SSI's own (the precision of a 10-replicate jackknife's variance).
        assert!(agrees(
            &refined(0.5050, 0.0040, 0.0279, 0.0100),
            &s,
            Some(&e)
        ));
        assert!(!agrees(
            &refined(0.5100, 0.0040, 0.0279, 0.0100),
            &s,
            Some(&e)
        ));
    }

    /// A joint refinement of `modes` with misfit `misfit` (nothing dropped).
    fn refinement_of(modes: Vec<crate::RefinedMode>, misfit: f64) -> Refinement {
        Refinement {
            modes,
            dropped: vec![],
            penalty: 16.0,
            real_poles: vec![],
            dropped_real_poles: vec![],
            real_pole_penalty: 8.0,
            neg_log_likelihood: 0.0,
            misfit,
            frequencies: 2999,
            iterations: 1,
            joint: true,
            combinations: None,
            bands: 1,
        }
    }

    /// SSI's modes at 1 and 4 Hz; the jackknife found the 4 Hz one in 4 of 7 replicates.
    fn unconfirmed_case(refined_4hz: crate::RefinedMode) -> ModeDecision {
        let ssi = SsiResult {
            block_rows: 0,
            singular_values: vec![],
            diagram: Default::default(),
            modes: vec![ssi_mode(1.0044, 0.0107), ssi_mode(4.0398, 0.0462)],
            real_poles: vec![],
            notes: vec![],
            auto_lag: None,
            survey: None,
            references: vec![0],
            chosen_references: None,
        };
        let errors = SsiErrors {
            blocks: 7,
            modes: vec![
                Some(crate::jackknife::ModeErrors {
                    frequency_se_hz: 0.003,
                    damping_se: 0.003,
                    shape_se: vec![0.0],
                    replicates: 7,
                }),
                None,
            ],
            found: vec![7, 4],
        };
        let refinement = refinement_of(vec![refined_mode(1.0017, 0.0113), refined_4hz], 0.007);
        let reasons = vec![
            vec![],
            vec![NotAMode::NotFoundAgain {
                found: 4,
                replicates: 7,
            }],
        ];
        let c = ModeCriteria::default();
        decide(&ssi, Some(&errors), reasons, Some(&refinement), &[], &c)
    }

    /// The corpus's 3-storey record under a load resonant at 8.0 Hz (ζ 0.56): SSI's three
    /// modes, and the refinement's with the pole it spent on the load's colour (`spare`,
    /// not from any SSI mode).
    fn coloured_case(spare: (f64, f64)) -> ModeDecision {
        let ssi_modes = [(3.2665, 0.0235), (8.7839, 0.0228), (13.4763, 0.0241)];
        let ssi = SsiResult {
            block_rows: 0,
            singular_values: vec![],
            diagram: Default::default(),
            modes: ssi_modes.iter().map(|&(f, z)| ssi_mode(f, z)).collect(),
            real_poles: vec![],
            notes: vec![],
            auto_lag: None,
            survey: None,
            references: vec![0],
            chosen_references: None,
        };
        let errors = SsiErrors {
            blocks: 10,
            modes: [(0.0138, 0.0026), (0.0425, 0.0042), (0.0676, 0.0024)]
                .iter()
                .map(|&(sf, sz)| {
                    Some(crate::jackknife::ModeErrors {
                        frequency_se_hz: sf,
                        damping_se: sz,
                        shape_se: vec![0.0],
                        replicates: 10,
                    })
                })
                .collect(),
            found: vec![10, 10, 10],
        };
        let refined = [
            (3.3003, 0.0264, 0.0072, 0.0022),
            (8.7586, 0.0114, 0.0073, 0.0008),
            (13.3526, 0.0192, 0.0124, 0.0009),
        ];
        let mut modes: Vec<crate::RefinedMode> = refined
            .iter()
            .enumerate()
            .map(|(i, &(f, z, sf, sz))| crate::RefinedMode {
                source: Some(i),
                frequency_se_hz: Some(sf),
                damping_se: Some(sz),
                ..refined_mode(f, z)
            })
            .collect();
        modes.push(crate::RefinedMode {
            source: None,
            ..refined_mode(spare.0, spare.1)
        });
        let refinement = refinement_of(modes, 0.023);
        let c = ModeCriteria::default();
        decide(
            &ssi,
            Some(&errors),
            vec![vec![]; 3],
            Some(&refinement),
            &[],
            &c,
        )
    }

    /// A pole no structure has, spread across the modes, makes SSI's modes the answer (the
    /// refined damping of mode 2 read 0.0114 ± 0.0008 against a true 0.022); the same pole
    /// beyond every mode's band (a low-pass edge at 40 Hz, 25 %: its band 30–50 Hz) does not.
    #[test]
    fn a_spare_pole_across_the_modes_leaves_the_answer_to_ssi() {
        let d = coloured_case((7.8722, 0.8147));
        assert_eq!(d.source, ModeSource::Ssi);
        match &d.refinement {
            RefinementVerdict::SparePole { pole, overlaps } => {
                assert_eq!(*pole, (7.8722, 0.8147));
                assert_eq!(overlaps, &[3.2665, 8.7839, 13.4763]);
            }
            v => panic!("{v:?}"),
        }
        assert!(
            d.headline().contains("spent a pole no structure has"),
            "{}",
            d.headline()
        );
        let d = coloured_case((40.19, 0.25));
        assert!(
            !matches!(d.refinement, RefinementVerdict::SparePole { .. }),
            "{:?}",
            d.refinement
        );
    }

    #[test]
    fn a_mode_the_jackknife_missed_is_confirmed_only_by_an_agreeing_refined_estimate() {
        // The 3-DOF record's window at 2400–2700 s: 4.0398 Hz found in 4 of 7 replicates,
        // refined to 4.0695 ± 0.0138 Hz at 4.74 % (2.2 refined errors away, the damping
        // within 3 %): a second estimator finds it, and it is reported.
        let agreeing = crate::RefinedMode {
            source: Some(1),
            frequency_se_hz: Some(0.0138),
            ..refined_mode(4.0695, 0.0474)
        };
        let d = unconfirmed_case(agreeing);
        assert_eq!(d.refinement, RefinementVerdict::Holds);
        let f: Vec<f64> = d.modes.iter().map(|m| m.frequency_hz).collect();
        assert_eq!(f, [1.0017, 4.0695]);
        assert_eq!(d.confirmed.len(), 1);
        assert_eq!(d.confirmed[0].index, 1);
        assert!(d.set_apart.is_empty(), "{:?}", d.set_apart);
        // Refined 10 % away (the fit gone to another feature): not confirmed, and the
        // refined estimate is set apart for want of SSI's support.
        let elsewhere = crate::RefinedMode {
            source: Some(1),
            ..refined_mode(4.45, 0.0474)
        };
        let d = unconfirmed_case(elsewhere);
        assert_eq!(d.modes.len(), 1);
        assert!(d.confirmed.is_empty());
        assert!(d.set_apart.iter().any(|a| a.source == ModeSource::Ssi
            && a.index == 1
            && matches!(a.reasons[..], [NotAMode::NotFoundAgain { found: 4, .. }])));
        assert!(d.set_apart.iter().any(|a| a.source == ModeSource::Refined
            && matches!(a.reasons[..], [NotAMode::NoSsiSupport { .. }])));
    }

    #[test]
    fn a_clean_record_keeps_the_refinement_and_every_mode() {
        let y = record(30_000, 5_700_001);
        let views: Vec<&[f64]> = y.iter().map(|c| c.as_slice()).collect();
        let opts = AnalysisOptions::default().with_refine(Some(Default::default()));
        let a = analyze(&views, 50.0, &opts).unwrap();
        let d = &a.decision;
        assert_eq!(d.source, ModeSource::Refined, "{a}");
        assert_eq!(d.refinement, RefinementVerdict::Holds);
        let f: Vec<f64> = d.modes.iter().map(|m| m.frequency_hz).collect();
        assert_eq!(f.len(), 2, "{a}");
        // 600 s of 2 % modes: frequencies known to ~0.2 %; 2 % is far outside.
        assert!(
            (f[0] - 2.0).abs() < 0.04 && (f[1] - 6.0).abs() < 0.12,
            "{f:?}"
        );
        // Every mode reported carries an error.
        assert!(d.modes.iter().all(|m| m.frequency_se_hz.is_some()));
    }

    #[test]
    fn a_machine_and_an_overdamped_pole_are_set_apart_with_their_reasons() {
        // A steady sinusoid at 4 Hz dominating its band on every channel.
        let mut y = record(30_000, 5_700_002);
        for (c, ch) in y.iter_mut().enumerate() {
            for (t, v) in ch.iter_mut().enumerate() {
                *v += (3.0 + c as f64) * (2.0 * std::f64::consts::PI * 4.0 * t as f64 / 50.0).sin();
            }
        }
        let views: Vec<&[f64]> = y.iter().map(|c| c.as_slice()).collect();
        let a = analyze(&views, 50.0, &AnalysisOptions::default()).unwrap();
        let reported: Vec<f64> = a.reported_modes().iter().map(|m| m.frequency_hz).collect();
        assert!(
            reported.iter().all(|f| (f - 4.0).abs() > 0.1),
            "the machine reported as a mode: {a}"
        );
        assert!(
            reported.iter().any(|f| (f - 2.0).abs() < 0.04)
                && reported.iter().any(|f| (f - 6.0).abs() < 0.12),
            "{a}"
        );
        // If SSI took the line for a pole, it is set apart and said.
        for s in a
            .decision
            .set_apart
            .iter()
            .filter(|s| (s.frequency_hz - 4.0).abs() < 0.1)
        {
            assert!(!s.reasons.is_empty());
        }
        // A lower damping limit sets the 2 % modes apart as overdamped, by name.
        let mut opts = AnalysisOptions::default();
        opts.modes.max_damping_ratio = 0.005;
        let a = analyze(&views, 50.0, &opts).unwrap();
        assert!(a.reported_modes().is_empty(), "{a}");
        assert!(
            a.decision.set_apart.iter().any(|s| s
                .reasons
                .iter()
                .any(|r| matches!(r, NotAMode::Overdamped { .. }))),
            "{a}"
        );
    }

    #[test]
    fn a_damping_limit_outside_zero_to_one_is_refused() {
        let y = record(4000, 5_700_003);
        let views: Vec<&[f64]> = y.iter().map(|c| c.as_slice()).collect();
        for bad in [0.0, 1.0, f64::NAN] {
            let mut opts = AnalysisOptions::default();
            opts.modes.max_damping_ratio = bad;
            assert!(matches!(
                analyze(&views, 50.0, &opts),
                Err(crate::SsiError::InvalidOption {
                    option: crate::SsiOption::ModeMaxDamping,
                    ..
                })
            ));
        }
    }
}
