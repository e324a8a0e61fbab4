//! The hysteretic storey of a shear structure from output-only records at several load
//! levels: where the element is, what it is, and the response it predicts.
//!
//! Status (issue 60): measured on an independent generator in `docs/storeys.md`; the
//! prediction of an unrecorded level in the time domain is not yet at its target.
//!
//! The model (`model.rs`): floors of known masses joined by storeys of stiffness $k_s$,
//! classical damping of ratio $\zeta_j$ per mode, each level's white force of two-sided
//! density $q_l$ on the loaded floors, and in one storey $s$ a Bouc-Wen element,
//! $g = k_s(1-a)(z-d)$ on the storey's drift $d$ with
//! $\dot z = \dot d - \beta|\dot d||z|^{\nu-1}z - \gamma\dot d|z|^\nu$
//! ([`hyst_sim::building`], which simulates it).
//!
//! What a record says (`statistics.rs`): in each mode's band of the channels' spectra, the
//! centroid, the relative spread, the log summed power and the channels' log power ratios.
//! The
//! parameters are those whose simulated records say the same at every level (indirect
//! inference, as [`crate::levels::bouc_wen_by_simulation`] does for one oscillator): the
//! squared differences, each divided by its statistic's spread over simulated replicates,
//! are minimized by the crate's Levenberg–Marquardt under common random numbers. The
//! standard errors are the sandwich $2(J^\top WJ)^{-1}J^\top W\Sigma WJ(J^\top WJ)^{-1}$ with
//! Σ the statistics' covariance over replicates of the fitted model (the 2 for the one
//! simulated record per measured one).
//!
//! Where the element is: every candidate storey, and none, is cross-validated over the two
//! halves of every record: fitted on one half and judged on the other (held out) by the
//! whitened distance between the held-out half's statistics and the mean of four fresh
//! simulations of the fitted model, both ways, the two scores summed; the element's storey
//! is the element candidate of best score. Whether there is an element at all is a test
//! ([`ElementEvidence`]): its fits must beat the linear structure's by more than chance. The
//! choice is fitted again on the whole records and reported with the others' scores, the
//! runner-up first among them.

mod error;
mod fitting;
mod locate;
mod model;
mod report;
mod setup;
mod statistics;

pub use error::StoreyError;
pub use hyst_sim::building::{Reading as Quantity, ShearBuilding, StoreyHysteresis};

pub use locate::ElementEvidence;

use rayon::prelude::*;

use crate::IdentError;
use fitting::{Fitted, Halves, fit, sandwich, spread};
use model::Layout;
use setup::Setup;
use statistics::Simulator;

/// The structure the records come from: what is known before the fit.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct StoreyStructure {
    /// Floor masses (kg), the lowest floor first.
    pub masses: Vec<f64>,
    /// Each channel's floor (0 = the lowest).
    pub sensors: Vec<usize>,
    /// What the channels read.
    pub quantity: Quantity,
    /// The records' rate (Hz).
    pub fs: f64,
}

impl StoreyStructure {
    /// A structure of these floor masses, each channel on the floor given, read as
    /// `quantity` at `fs` Hz.
    pub fn new(masses: Vec<f64>, sensors: Vec<usize>, quantity: Quantity, fs: f64) -> Self {
        StoreyStructure {
            masses,
            sensors,
            quantity,
            fs,
        }
    }
}

/// Options of [`fit_storeys`].
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
#[non_exhaustive]
pub struct StoreyOptions {
    /// Floors the force acts on (0-based), each its own white noise. Default: every floor.
    pub load_floors: Option<Vec<usize>>,
    /// Storeys that may hold the element (0 = between the ground and the first floor);
    /// "none" is always a candidate. Default: every storey.
    pub candidates: Option<Vec<usize>>,
    /// The Bouc-Wen exponent ν, held. Default 1.
    pub nu: f64,
    /// Most Levenberg–Marquardt iterations of each fit. Default 8.
    pub max_iterations: usize,
    /// Stop when an iteration lowers the weighted sum of squares by less than this share.
    /// Default 1e-3.
    pub tolerance: f64,
    /// Seed of the simulated forces (common random numbers). Default 9100.
    pub seed: u64,
    /// Replicates behind each statistic's spread. Default 16.
    pub replicates: usize,
}

impl Default for StoreyOptions {
    fn default() -> Self {
        StoreyOptions {
            load_floors: None,
            candidates: None,
            nu: 1.0,
            max_iterations: 8,
            tolerance: 1e-3,
            seed: 9100,
            replicates: 16,
        }
    }
}

/// One fitted parameter.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct StoreyParameter {
    /// `k1`… (N/m), `zeta1`…, `q1`… (N²/Hz, two-sided, each loaded floor), `a`, `beta`,
    /// `gamma` (1/m^ν).
    pub name: String,
    /// Its value.
    pub value: f64,
    /// Its standard error (NaN when the fit's Jacobian is singular).
    #[cfg_attr(feature = "serde", serde(with = "crate::nullable"))]
    pub se: f64,
}

/// A candidate location and how well it predicted the held-out halves.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct StoreyCandidate {
    /// The storey (0-based), or none.
    pub storey: Option<usize>,
    /// Whitened squared distance of each half's statistics from the model fitted on the
    /// other half, summed over both (about 2.5 times the statistics' count when the model is
    /// right, plus the fitted parameters' own error).
    #[cfg_attr(feature = "serde", serde(with = "crate::nullable"))]
    pub held_out: f64,
    /// The same on the halves it was fitted to.
    #[cfg_attr(feature = "serde", serde(with = "crate::nullable"))]
    pub fitted: f64,
    /// Why its fit stopped, when it did (its scores are then ∞ and NaN).
    pub failed: Option<String>,
}

/// What a level's record says (or a simulated one's), mode by mode: its band's centroid
/// and relative spread, its channels' summed power and their power ratios (`statistics.rs`).
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct LevelStatistics {
    /// Each mode band's centroid frequency (Hz).
    pub centroid_hz: Vec<f64>,
    /// Each mode band's relative spread (standard deviation over centroid): wider with more
    /// damping.
    pub spread: Vec<f64>,
    /// Each mode band's RMS at each channel (the record's unit), mode by mode.
    pub band_rms: Vec<Vec<f64>>,
    /// The spread of each statistic over replicates of the fitted model (centroids,
    /// spreads, then band by band the log summed power and the other channels' log power
    /// ratios to the first), as a standard error; empty for a simulated level.
    pub se: Vec<f64>,
}

/// What [`fit_storeys`] finds.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct StoreyFit {
    /// The storey holding the element (0-based), or none.
    pub storey: Option<usize>,
    /// The fitted structure (its load is a unit one: see `force_densities`).
    pub building: ShearBuilding,
    /// Each level's force density (N²/Hz, two-sided, on each loaded floor).
    pub force_densities: Vec<f64>,
    /// Floors loaded.
    pub load_floors: Vec<usize>,
    /// The parameters with their standard errors.
    pub parameters: Vec<StoreyParameter>,
    /// Every candidate: the chosen one first, then the others by held-out score (the
    /// runner-up next).
    pub candidates: Vec<StoreyCandidate>,
    /// Whether an element is needed at all ([`ElementEvidence`]); `None` when "none" or
    /// every element candidate could not be fitted.
    pub element_evidence: Option<ElementEvidence>,
    /// Each level's statistics, measured on the whole record.
    pub measured: Vec<LevelStatistics>,
    /// The same from the fitted model's simulated records.
    pub simulated: Vec<LevelStatistics>,
    /// RMS of the whitened differences of the final fit.
    pub residual_rms: f64,
    /// Iterations of the final fit.
    pub iterations: usize,
}

/// A step of the fit, for progress output.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StoreyProgress<'a> {
    /// What is being done.
    pub stage: &'a str,
    /// The iteration (0 before the first).
    pub iteration: usize,
    /// Its weighted sum of squares (NaN when none).
    pub cost: f64,
}

/// Fit the storey model to `records` (one per level: channels × samples, each channel on the
/// floor [`StoreyStructure::sensors`] names), locate the element by held-out evidence, and
/// report it with standard errors and the model's own statistics beside the measured ones.
pub fn fit_storeys(
    records: &[Vec<Vec<f64>>],
    structure: &StoreyStructure,
    opts: &StoreyOptions,
    progress: &(dyn Fn(StoreyProgress<'_>) + Sync),
) -> Result<StoreyFit, IdentError> {
    let floors = setup::check(records, structure, opts)?;
    let setup = setup::setup(records, structure, opts, floors, progress)?;
    let (first, second) = (half(records, true), half(records, false));
    let stats_of = |recs: &[Vec<Vec<f64>>]| -> Vec<Vec<f64>> {
        recs.par_iter().map(|r| setup.reading.of(r)).collect()
    };
    let (m_first, m_second, m_whole) = (stats_of(&first), stats_of(&second), stats_of(records));
    let start_linear = Layout {
        floors,
        levels: setup.levels,
        storey: None,
        folded: setup.folded,
    };
    let (start_building, start_q, start_b) =
        model::building(&setup.template, &start_linear, &setup.start, opts.nu)?;
    // The statistics' spread at half length, from replicates of the linear structure fitted
    // to the first halves (the start's damping, read by SSI from one record, can be far
    // enough off to misstate the spread of what a record shows by a fifth).
    let start_spread = spread(
        &setup,
        &start_building,
        (&start_q, start_b),
        &lengths(&first),
        opts,
    )?
    .0;
    let sim = simulator(&setup, &first, opts.seed);
    let stage = "the linear structure (the statistics' spread)";
    let linear = fit(
        &setup,
        &start_linear,
        &setup.start,
        &sim,
        &m_first,
        &start_spread,
        opts,
        stage,
        progress,
    )?;
    let (linear_building, linear_q, linear_b) =
        model::building(&setup.template, &start_linear, &linear.theta, opts.nu)?;
    let half_spread = spread(
        &setup,
        &linear_building,
        (&linear_q, linear_b),
        &lengths(&first),
        opts,
    )?
    .0;
    let halves = Halves {
        records: [&first, &second],
        measured: [&m_first, &m_second],
        spread: &half_spread,
    };
    let linear = (&start_building, start_q.as_slice());
    let (mut scored, mut fits) = locate::locate(&setup, &halves, linear, records, opts, progress)?;
    let (best, evidence) = locate::choose(&scored, &fits)?;
    let Some((layout, theta_half)) = fits.swap_remove(best) else {
        return Err(StoreyError::NoCandidateFitted {
            reasons: scored.iter().filter_map(|c| c.failed.clone()).collect(),
        }
        .into());
    };
    // The chosen first, then the others by held-out score.
    let chosen = scored.remove(best);
    scored.sort_by(|a, b| a.held_out.total_cmp(&b.held_out));
    scored.insert(0, chosen);
    // The whole records: the spread scales as one over the square root of the length.
    let whole_spread: Vec<Vec<f64>> = half_spread
        .iter()
        .map(|s| s.iter().map(|v| v / 2f64.sqrt()).collect())
        .collect();
    let stage = match layout.storey {
        None => "no element: fitting the whole records".to_string(),
        Some(s) => format!("storey {}: fitting the whole records", s + 1),
    };
    let sim = simulator(&setup, records, opts.seed + 1000);
    let whole = fit(
        &setup,
        &layout,
        &theta_half,
        &sim,
        &m_whole,
        &whole_spread,
        opts,
        &stage,
        progress,
    )?;
    let mut report = finish(
        &setup,
        &layout,
        &whole,
        (&m_whole, &whole_spread),
        records,
        opts,
        progress,
    )?;
    report.candidates = scored;
    report.element_evidence = evidence;
    Ok(report)
}

/// The first or second half of every channel of every record.
fn half(records: &[Vec<Vec<f64>>], first: bool) -> Vec<Vec<Vec<f64>>> {
    records
        .iter()
        .map(|r| {
            r.iter()
                .map(|c| {
                    let m = c.len() / 2;
                    if first {
                        c[..m].to_vec()
                    } else {
                        c[m..].to_vec()
                    }
                })
                .collect()
        })
        .collect()
}

/// Each record's length (samples).
fn lengths(records: &[Vec<Vec<f64>>]) -> Vec<usize> {
    records.iter().map(|r| r[0].len()).collect()
}

/// The simulator of records as long as `records`, its forces drawn from `seed`.
fn simulator(setup: &Setup, records: &[Vec<Vec<f64>>], seed: u64) -> Simulator {
    setup.simulator(&lengths(records), seed)
}

/// The report of the whole records' fit: the structure, the parameters with their standard
/// errors (from replicates of the fitted model), each level's statistics measured and
/// simulated. The candidates and the evidence are the caller's.
fn finish(
    setup: &Setup,
    layout: &Layout,
    whole: &Fitted,
    (measured, weights): (&[Vec<f64>], &[Vec<f64>]),
    records: &[Vec<Vec<f64>>],
    opts: &StoreyOptions,
    progress: &(dyn Fn(StoreyProgress<'_>) + Sync),
) -> Result<StoreyFit, IdentError> {
    let (building, q, folded) = model::building(&setup.template, layout, &whole.theta, opts.nu)?;
    progress(StoreyProgress {
        stage: "the fitted model's replicates (standard errors)",
        iteration: whole.iterations,
        cost: whole.cost,
    });
    let (sd, cov) = spread(setup, &building, (&q, folded), &lengths(records), opts)?;
    let se = sandwich(whole, weights, &cov);
    let parameters = layout
        .names()
        .into_iter()
        .zip(&whole.theta)
        .zip(&se)
        .map(|((name, &value), &se)| StoreyParameter { name, value, se })
        .collect();
    let (n, channels) = (setup.floors, setup.channels);
    let level = |s: &[f64], se: Vec<f64>| LevelStatistics {
        centroid_hz: s[..n].to_vec(),
        spread: s[n..2 * n].to_vec(),
        band_rms: s[2 * n..]
            .chunks(channels)
            .map(|c| {
                // Back from (ln Σ P, ln P_c/P_1 …) to each channel's RMS √P_c.
                let ratios: Vec<f64> = std::iter::once(1.0)
                    .chain(c[1..].iter().map(|r| r.exp()))
                    .collect();
                let first = c[0].exp() / ratios.iter().sum::<f64>();
                ratios.iter().map(|r| (first * r).sqrt()).collect()
            })
            .collect(),
        se,
    };
    Ok(StoreyFit {
        storey: layout.storey,
        building,
        force_densities: q,
        load_floors: setup.load_floors.clone(),
        parameters,
        candidates: vec![],
        element_evidence: None,
        measured: measured
            .iter()
            .zip(sd)
            .map(|(s, sd)| level(s, sd))
            .collect(),
        simulated: whole.simulated.iter().map(|s| level(s, vec![])).collect(),
        residual_rms: (whole.cost / whole.residuals as f64).sqrt(),
        iterations: whole.iterations,
    })
}
