//! What the storey fit takes and gives: the structure known before it, its options, and
//! its report (the fitted structure with each parameter's standard error, the candidates'
//! scores, each level's statistics) with what a prediction needs to read records as it did.

use hyst_sim::building::{Reading as Quantity, ShearBuilding};

/// The structure the records come from: what is known before the fit.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
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

/// Options of [`super::fit_storeys`].
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
    /// Levels not recorded to predict, each as a force this many times the loudest recorded
    /// level's RMS (its density times the square): [`StoreyFit::predictions`]. Default none.
    pub predict: Vec<f64>,
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
            predict: vec![],
        }
    }
}

/// One fitted parameter.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
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
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
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
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
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

/// What [`super::fit_storeys`] finds.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
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
    /// The covariance of the parameters (rows and columns in `parameters`' order; NaN when
    /// the fit's Jacobian is singular).
    #[cfg_attr(feature = "serde", serde(with = "crate::nullable"))]
    pub covariance: Vec<Vec<f64>>,
    /// The levels not recorded that [`StoreyOptions::predict`] asked for, in its order.
    #[cfg_attr(feature = "serde", serde(default))]
    pub predictions: Vec<super::LevelPrediction>,
    /// The levels asked for that could not be predicted, each with why: the fit stands
    /// without them.
    #[cfg_attr(feature = "serde", serde(default))]
    pub not_predicted: Vec<NotPredicted>,
    /// How the statistics were read and the model simulated (a prediction reads the same).
    pub reading: StoreyReading,
    /// RMS of the whitened differences of the final fit.
    pub residual_rms: f64,
    /// Iterations of the final fit.
    pub iterations: usize,
    /// Whether the final fit reached its records ([`FitAgreement`]); a document written
    /// before it was judged reads as [`FitVerdict::NotJudged`].
    #[cfg_attr(feature = "serde", serde(default))]
    pub agreement: FitAgreement,
}

/// Whether the final fit reached its records (`agreement.rs`).
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct FitAgreement {
    /// The verdict.
    pub verdict: FitVerdict,
    /// The whitened residual RMS chance exceeds 0.1 % of the time when the model holds
    /// (from the statistics' covariance over the fitted model's replicates; NaN when not
    /// known).
    #[cfg_attr(feature = "serde", serde(with = "crate::nullable"))]
    pub chance_rms: f64,
    /// Whether the fit stopped because an iteration gained less than the tolerance (else
    /// at the iteration limit, still gaining).
    pub converged: bool,
    /// The mode bands (each level's) whose model centroid lies outside the measured band's
    /// spread.
    pub far: Vec<FarBand>,
}

impl Default for FitAgreement {
    fn default() -> Self {
        FitAgreement {
            verdict: FitVerdict::NotJudged,
            chance_rms: f64::NAN,
            converged: true,
            far: vec![],
        }
    }
}

/// What the final fit's agreement with its records says.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
#[non_exhaustive]
pub enum FitVerdict {
    /// Every band where the record's is, the residual within chance.
    Explains,
    /// Every band where the record's is, the residual beyond chance: the model lacks
    /// something; its location stands on held-out evidence, its parameters are the nearest
    /// of its form.
    Misses,
    /// A band the model puts outside the record's (or no finite residual): the fit did not
    /// reach its records, and locates nothing.
    Far,
    /// Written by a version that did not judge it.
    NotJudged,
}

/// A mode band the model puts outside the measured band's spread.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct FarBand {
    /// The level (0-based).
    pub level: usize,
    /// The mode band (0-based).
    pub mode: usize,
    /// The measured band's centroid (Hz).
    pub measured_hz: f64,
    /// The measured band's spread (its standard deviation, Hz).
    pub width_hz: f64,
    /// The model's centroid (Hz; NaN where its band is empty).
    #[cfg_attr(feature = "serde", serde(with = "crate::nullable"))]
    pub model_hz: f64,
}

/// A level [`StoreyOptions::predict`] asked for that could not be predicted.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct NotPredicted {
    /// The factor on the loudest level's force asked for.
    pub factor: f64,
    /// Why it was not predicted (the force not representable, the simulation diverged).
    pub reason: String,
}

/// How the fit read its statistics and simulated its model, fixed from the quietest level.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct StoreyReading {
    /// The mode bands' edges (Hz): mode j's band runs from edge j to edge j + 1.
    pub bands_hz: Vec<f64>,
    /// Welch's segment (samples).
    pub segment: usize,
    /// Integration steps per sample of the simulations.
    pub steps_per_sample: usize,
    /// Samples dropped from each simulated record's start (the response from rest).
    pub warm_up: usize,
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

/// Whether the records need an element: the best-placed element's fits (both halves)
/// against the linear structure's. Cross-validation alone cannot say it: a nested model's
/// extra parameters cost its held-out score only about their number, less than the score's
/// own chance swings, so it picks a spurious element with a probability that does not vanish
/// (Shao 1993). Under no element the improvement of the fitted whitened sums is about
/// $2\chi^2_{6}$ (three parameters, two folds; the 2 for the simulated records' own noise);
/// the element is kept when it improves by more than that distribution's 99 % point.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct ElementEvidence {
    /// The best-placed element's storey (0-based).
    pub storey: usize,
    /// The linear structure's fitted sums less the element's.
    pub improvement: f64,
    /// The improvement chance reaches 1 % of the time under no element.
    pub threshold: f64,
}
