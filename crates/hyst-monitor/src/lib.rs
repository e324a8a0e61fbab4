//! Structural health monitoring: the modes of many records of one structure tracked over
//! time, and a change in them told from estimation noise and the environment's effect.
//!
//! One job, in four steps, each its own module, which [`track()`](fn@track) runs over a campaign's
//! records (each identified by [`identify_record`], as `hyst ssi` does):
//!
//! * [`matching`]: a record's modes assigned one-to-one to a reference set, by frequency and
//!   MAC. A pair is admissible when |f − f_ref| / f_ref ≤ Δf and MAC ≥ MAC_min; among
//!   admissible pairs the assignment minimizes Σ (|f − f_ref| / (f_ref Δf) + (1 − MAC) /
//!   (1 − MAC_min)) (Kuhn–Munkres), so a mode missing from a record, or one the reference does
//!   not have, is said rather than forced onto another.
//! * [`baseline`]: over a training period, each mode's frequency regressed on the covariates
//!   (temperature, say): f_i = β₀ + Σ_j β_j x_ij + e_i with e_i = ε_i + η_i, ε_i the
//!   estimation error (its standard error s_i known from the refinement) and η_i what the
//!   covariates leave unexplained, of variance σ² estimated by the method of moments. A new
//!   record's standardized residual is z = (f − f̂) / √(s² + σ² + x̃ᵀ Cov(β̂) x̃), where the last
//!   term is the fit's own uncertainty at the record's covariates.
//! * [`whiten`]: a slow effect the covariates leave unexplained, which makes the residuals
//!   correlated from record to record, modelled over the training period as a latent
//!   first-order autoregression under the white estimation noise (whose variance each
//!   record's standard error gives), fitted by the Kalman filter's likelihood and kept when
//!   BIC says so; the filter's standardized innovations are then passed on instead of the z.
//! * [`chart`]: a two-sided CUSUM of those values v, S⁺ = max(0, S⁺ + v − k),
//!   S⁻ = max(0, S⁻ − v − k), an alarm when either passes h; its in-control average run
//!   length (the false-alarm rate's inverse) from Siegmund's approximation, which holds for
//!   independent standard normal values.

#![warn(missing_docs)]

pub mod baseline;
pub mod calibration;
#[cfg(feature = "synth")]
pub mod campaign;
pub mod chart;
pub mod environment;
pub mod estimates;
pub mod joint;
pub mod matching;
pub mod records;
mod report;
pub mod screen;
mod sensitivity;
pub mod subspace;
pub mod track;
pub mod training;
pub mod whiten;

pub use baseline::{Baseline, fit_baseline};
pub use chart::{Alarm, Cusum, Side};
pub use estimates::{RecordEstimates, track_estimates};
pub use matching::{Assignment, MatchOptions, ModeEstimate, match_modes};
pub use records::{
    Harmonic, Identified, Loaded, RecordModes, campaign_analysis, identify_record,
    identify_records, reported_modes,
};
pub use track::{ModeAlarm, TrackOptions, TrackReport, TrackRow, track};
pub use training::{OutlierRule, TrainingOutlier};
pub use whiten::ResidualModel;

/// Errors of monitoring.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MonitorError {
    /// Too few training records for the regression on the covariates.
    #[error(
        "{records} training record(s) for {parameters} regression coefficients; need more records than coefficients"
    )]
    TooFewRecords {
        /// Training records with the mode.
        records: usize,
        /// Coefficients of the regression (intercept and one per covariate).
        parameters: usize,
    },
    /// Covariates that do not determine the regression (a constant or repeated covariate).
    #[error(
        "the covariates are collinear over the training period (a covariate constant, or one a combination of others)"
    )]
    Collinear,
    /// A value that is not finite, or a standard error that is negative.
    #[error("{what} of training record {index} is {value}")]
    BadValue {
        /// Which value.
        what: &'static str,
        /// 0-based record among those given.
        index: usize,
        /// The value.
        value: f64,
    },
    /// Records and covariate rows of different counts.
    #[error("{records} records but {rows} rows of covariates")]
    CovariateRows {
        /// Records.
        records: usize,
        /// Covariate rows.
        rows: usize,
    },
    /// Too few training records for the subspace test's residual covariance.
    #[error(
        "{records} training record(s) with correlations for a residual of {entries} entries; the subspace test needs more records than entries (a longer training period, or fewer modes)"
    )]
    TooFewForSubspace {
        /// Training records with correlations.
        records: usize,
        /// Entries of the residual.
        entries: usize,
    },
    /// The subspace test asked for order 0: no reference mode to test.
    #[error(
        "no reference mode (order 0): the subspace test compares each record with the reference's modes"
    )]
    NoSubspaceOrder,
    /// A record not fit to be identified (a NaN burst, a stuck or clipped channel).
    #[error(transparent)]
    Unfit(#[from] screen::Unfit),
    /// A record's identification failed.
    #[error(transparent)]
    Ssi(#[from] covssi::SsiError),
    /// Every record was skipped: nothing to track (the first's reason is likely all's).
    #[error("none of the {records} record(s) could be identified; the first, {first}: {why}")]
    NoneIdentified {
        /// Records given.
        records: usize,
        /// The first record's name.
        first: String,
        /// Why it was skipped.
        why: String,
    },
    /// The joint chart needs two modes or more.
    #[error("{modes} mode(s) with a baseline: the joint chart judges two modes or more together")]
    TooFewModesForJoint {
        /// Modes with a baseline.
        modes: usize,
    },
    /// Too few training records hold every mode for the joint chart's model.
    #[error(
        "{records} training record(s) hold all {modes} modes; the joint chart needs at least 20 and five per mode (a longer training period)"
    )]
    TooFewForJoint {
        /// Training records holding every mode.
        records: usize,
        /// Modes judged.
        modes: usize,
    },
    /// A CUSUM parameter out of range.
    #[error("CUSUM {parameter} must be positive and finite, got {value}")]
    ChartParameter {
        /// `k` or `h`.
        parameter: &'static str,
        /// The value.
        value: f64,
    },
}
