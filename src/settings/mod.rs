//! The settings as a user gives them, one flat set per surface shared by the command line
//! and Python: [`SsiSettings`] (a modal analysis: `hyst ssi`, `hyst track`, `hyst
//! amplitude`, `hyst.ssi`, `hyst.track`) and [`TrackSettings`] (a campaign's tracking:
//! `hyst track`, `hyst.track`, `hyst.track_estimates`). Each field is a flag (`block_rows` is
//! `--block-rows`; a setting on by default is `--no-…`): the command line flattens these
//! types (with the `cli` feature, clap's flags are read into them by a literal naming every
//! field, so a field without its flag does not compile). Each field is a keyword of the
//! Python functions, which pass them as a JSON object that `from_json` reads, refusing a
//! name it does not know; a test of the command line holds the Python signatures to the
//! fields. [`SsiSettings::analysis`] and [`TrackSettings::options`] turn them into covssi's
//! [`AnalysisOptions`] and hyst-monitor's [`TrackOptions`], the one place that does.

#[cfg(feature = "cli")]
mod flags;

use covssi::{
    AnalysisOptions, BlockRows, Decimation, ModeCriteria, RefineOptions, SsiOptions,
    StabilityCriteria,
};
use hyst_monitor::TrackOptions;
use serde::{Deserialize, Serialize};

/// What is wrong with a set of [`SsiSettings`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SettingsError {
    /// Two settings that say the same thing two ways (e.g. `block_rows` and `lag_seconds`).
    #[error("give {first} or {second}, not both")]
    Conflict {
        /// The first setting's name.
        first: &'static str,
        /// The second's.
        second: &'static str,
    },
    /// A count that must be at least `least`.
    #[error("{name} must be at least {least}, got {value}")]
    TooSmall {
        /// The setting's name.
        name: &'static str,
        /// The least value.
        least: usize,
        /// The value given.
        value: usize,
    },
    /// A setting out of range whatever the record ([`AnalysisOptions::check`]).
    #[error(transparent)]
    Ssi(#[from] covssi::SsiError),
    /// Settings that did not parse (an unknown name, a value of the wrong type).
    #[error("settings: {0}")]
    Unreadable(String),
}

/// The settings of one modal analysis (SSI, then its refinement). `None` leaves a choice
/// to the record (the lag, the decimation, the largest order); the thresholds default to
/// [`StabilityCriteria::default`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
#[non_exhaustive]
pub struct SsiSettings {
    /// Block rows of the Toeplitz matrix (lags up to 2·N−1); default: read from the record.
    pub block_rows: Option<usize>,
    /// Instead of `block_rows`: the largest lag in seconds (after any decimation).
    pub lag_seconds: Option<f64>,
    /// Instead of `block_rows`: the largest lag as (count, Hz), count periods of Hz.
    pub lag_periods: Option<(f64, f64)>,
    /// Decimate by this factor first; default: read from the record's spectrum.
    pub decimate: Option<usize>,
    /// Largest model order; default: 40, or four per spectral peak when the record shows
    /// more than ten, at most the Toeplitz rank.
    pub max_order: Option<usize>,
    /// Model order step.
    pub order_step: usize,
    /// Reference channels (0-based); default: all.
    pub references: Option<Vec<usize>>,
    /// Stabilization threshold on the relative frequency change.
    pub df: f64,
    /// Stabilization threshold on the relative damping change.
    pub dzeta: f64,
    /// Stabilization threshold on 1 − MAC.
    pub dmac: f64,
    /// Stabilization threshold of eq. (31) for real poles.
    pub dreal: f64,
    /// Refine the modes and real poles by maximum likelihood (default: no, SSI's modes with
    /// the jackknife's errors; see [`covssi::AnalysisOptions::refine`]).
    pub refine: bool,
    /// Refine on the channels' joint likelihood (their cross-spectra), not each alone.
    pub joint: bool,
    /// Standard errors for SSI's modes: the jackknife over at most this many blocks of the
    /// record ([`covssi::jackknife`]); 0: none. Default (`None`):
    /// [`covssi::JACKKNIFE_BLOCKS`]. The decision of what is a mode reads them
    /// ([`covssi::decision`]).
    pub ssi_errors: Option<usize>,
    /// The largest damping ratio of a mode ([`covssi::ModeCriteria::max_damping_ratio`]);
    /// default (`None`) 0.2.
    pub max_damping: Option<f64>,
}

impl Default for SsiSettings {
    fn default() -> Self {
        let c = StabilityCriteria::default();
        SsiSettings {
            block_rows: None,
            lag_seconds: None,
            lag_periods: None,
            decimate: None,
            max_order: None,
            order_step: SsiOptions::default().order_step,
            references: None,
            df: c.frequency,
            dzeta: c.damping,
            dmac: c.mac,
            dreal: c.real,
            refine: false,
            joint: true,
            ssi_errors: None,
            max_damping: None,
        }
    }
}

impl SsiSettings {
    /// The settings read from a JSON object of them (what the Python package passes): an
    /// unknown name or a value of the wrong type is an error; a name left out keeps its
    /// default.
    pub fn from_json(text: &str) -> Result<Self, SettingsError> {
        read_json(text)
    }

    /// The analysis these settings ask for. Values out of range that covssi checks
    /// (thresholds, references, the lag's size) are its errors, named by
    /// [`covssi::SsiOption`]; here only what covssi cannot see: two ways of giving the lag,
    /// and a decimation factor of 0.
    pub fn analysis(&self) -> Result<AnalysisOptions, SettingsError> {
        let block_rows = match (self.block_rows, self.lag_seconds, self.lag_periods) {
            (Some(_), Some(_), _) => return Err(conflict("block_rows", "lag_seconds")),
            (Some(_), _, Some(_)) => return Err(conflict("block_rows", "lag_periods")),
            (_, Some(_), Some(_)) => return Err(conflict("lag_seconds", "lag_periods")),
            (Some(n), None, None) => BlockRows::Count(n),
            (None, Some(t), None) => BlockRows::Seconds(t),
            (None, None, Some((count, frequency_hz))) => BlockRows::Periods {
                count,
                frequency_hz,
            },
            (None, None, None) => BlockRows::Auto,
        };
        let decimation = match self.decimate {
            Some(0) => {
                return Err(SettingsError::TooSmall {
                    name: "decimate",
                    least: 1,
                    value: 0,
                });
            }
            Some(f) => Decimation::Factor(f),
            None => Decimation::Auto,
        };
        let ssi = SsiOptions {
            block_rows,
            max_order: self.max_order,
            order_step: self.order_step,
            criteria: StabilityCriteria {
                frequency: self.df,
                damping: self.dzeta,
                mac: self.dmac,
                real: self.dreal,
            },
            references: self.references.clone(),
            ..SsiOptions::default()
        };
        let refine = self.refine.then(|| RefineOptions {
            joint: self.joint,
            ..RefineOptions::default()
        });
        let mut modes = ModeCriteria::default();
        if let Some(limit) = self.max_damping {
            modes.max_damping_ratio = limit;
        }
        let blocks = self.ssi_errors.unwrap_or(covssi::JACKKNIFE_BLOCKS);
        let mut opts = AnalysisOptions::default()
            .with_decimation(decimation)
            .with_ssi(ssi)
            .with_refine(refine)
            .with_ssi_errors((blocks > 0).then_some(blocks));
        opts.modes = modes;
        opts.check()?;
        Ok(opts)
    }

    /// The settings' names, in order: the flags and keywords both sides must have.
    pub fn names() -> Vec<String> {
        field_names(&SsiSettings::default())
    }
}

/// How a campaign's modes are tracked, as a user gives it: `hyst track`'s flags
/// (`--training`, `--no-whiten`, `--no-environment-model`, `--level-covariate`,
/// `--no-calibrate`, `--no-joint-chart`) and the
/// keywords of `hyst.track` and `hyst.track_estimates`. [`TrackSettings::options`] makes
/// hyst-monitor's [`TrackOptions`] of them, the one place that does.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
#[non_exhaustive]
pub struct TrackSettings {
    /// The first this many records train the baselines; default (`None`): 336, at most
    /// half the campaign.
    pub training: Option<usize>,
    /// Chart the innovations of a slow effect's model where the training records hold one
    /// ([`TrackOptions::whiten`]).
    pub whiten: bool,
    /// Choose each mode's environmental model on the training records
    /// ([`TrackOptions::environment`]).
    pub environment_model: bool,
    /// Add each record's excitation level as a covariate ([`TrackOptions::level_covariate`]).
    pub level_covariate: bool,
    /// Calibrate each chart's limit on the training records' charted values
    /// ([`TrackOptions::calibrate`]).
    pub calibrate: bool,
    /// Judge the modes together beside each alone ([`TrackOptions::joint`]).
    pub joint_chart: bool,
}

impl Default for TrackSettings {
    fn default() -> Self {
        let o = TrackOptions::default();
        TrackSettings {
            training: None,
            whiten: o.whiten,
            environment_model: o.environment,
            level_covariate: o.level_covariate,
            calibrate: o.calibrate,
            joint_chart: o.joint,
        }
    }
}

impl TrackSettings {
    /// The settings read from a JSON object of them (what the Python package passes): an
    /// unknown name or a value of the wrong type is an error; a name left out keeps its
    /// default.
    pub fn from_json(text: &str) -> Result<Self, SettingsError> {
        read_json(text)
    }

    /// The tracking of a campaign of `records` records these settings ask for.
    pub fn options(&self, records: usize) -> TrackOptions {
        let mut opts =
            TrackOptions::for_campaign(records, self.training, self.whiten, self.environment_model);
        opts.level_covariate = self.level_covariate;
        opts.calibrate = self.calibrate;
        opts.joint = self.joint_chart;
        opts
    }

    /// The settings' names, in order: the flags and keywords both sides must have.
    pub fn names() -> Vec<String> {
        field_names(&TrackSettings::default())
    }
}

/// Settings read from a JSON object of them: an unknown name or a value of the wrong type is
/// [`SettingsError::Unreadable`].
fn read_json<T: serde::de::DeserializeOwned>(text: &str) -> Result<T, SettingsError> {
    serde_json::from_str(text).map_err(|e| SettingsError::Unreadable(e.to_string()))
}

/// The field names of a settings type, in order, as its JSON object has them.
fn field_names<T: Serialize>(settings: &T) -> Vec<String> {
    match serde_json::to_value(settings) {
        Ok(serde_json::Value::Object(map)) => map.keys().cloned().collect(),
        _ => Vec::new(),
    }
}

fn conflict(first: &'static str, second: &'static str) -> SettingsError {
    SettingsError::Conflict { first, second }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_covssis() {
        let a = SsiSettings::default().analysis().unwrap();
        assert_eq!(a, AnalysisOptions::default());
    }

    #[test]
    fn every_setting_reaches_the_analysis() {
        let s = SsiSettings::from_json(
            r#"{"lag_periods": [10, 1.5], "decimate": 4, "max_order": 30, "order_step": 2,
                "references": [0, 2], "df": 0.02, "dzeta": 0.1, "dmac": 0.05, "dreal": 2,
                "refine": true, "joint": false}"#,
        )
        .unwrap();
        let a = s.analysis().unwrap();
        assert_eq!(a.decimation, Decimation::Factor(4));
        assert_eq!(
            a.ssi.block_rows,
            BlockRows::Periods {
                count: 10.0,
                frequency_hz: 1.5
            }
        );
        assert_eq!(a.ssi.max_order, Some(30));
        assert_eq!(a.ssi.order_step, 2);
        assert_eq!(a.ssi.references, Some(vec![0, 2]));
        let c = a.ssi.criteria;
        assert_eq!(
            (c.frequency, c.damping, c.mac, c.real),
            (0.02, 0.1, 0.05, 2.0)
        );
        assert!(!a.refine.unwrap().joint);
        let none = SsiSettings {
            refine: false,
            ..SsiSettings::default()
        };
        assert!(none.analysis().unwrap().refine.is_none());
    }

    #[test]
    fn two_ways_of_one_lag_and_unknown_names_are_refused() {
        let s = SsiSettings::from_json(r#"{"block_rows": 20, "lag_seconds": 2}"#).unwrap();
        assert_eq!(
            s.analysis().unwrap_err().to_string(),
            "give block_rows or lag_seconds, not both"
        );
        let e = SsiSettings::from_json(r#"{"block_row": 20}"#).unwrap_err();
        assert!(e.to_string().contains("unknown field `block_row`"), "{e}");
        let e = SsiSettings::from_json(r#"{"decimate": 0}"#)
            .unwrap()
            .analysis()
            .unwrap_err();
        assert_eq!(e.to_string(), "decimate must be at least 1, got 0");
    }

    #[test]
    fn tracking_defaults_are_hyst_monitors_and_each_setting_reaches_the_options() {
        assert_eq!(TrackSettings::default().options(1000), {
            let mut o = TrackOptions::default();
            o.training = 336;
            o
        });
        // Without `training`, at most half the campaign trains.
        assert_eq!(TrackSettings::default().options(100).training, 50);
        let s = TrackSettings::from_json(
            r#"{"training": 40, "whiten": false, "environment_model": false,
                "level_covariate": true}"#,
        )
        .unwrap();
        let o = s.options(1000);
        assert_eq!(
            (o.training, o.whiten, o.environment, o.level_covariate),
            (40, false, false, true)
        );
        let e = TrackSettings::from_json(r#"{"whitening": false}"#).unwrap_err();
        assert!(e.to_string().contains("unknown field `whitening`"), "{e}");
    }
}
