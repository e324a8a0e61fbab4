//! SSI's options: the block rows, the stabilization thresholds, the rest.

use crate::{SsiError, SsiOption};

/// How many block rows i the Toeplitz matrix has (it uses lags 1 … 2i−1).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum BlockRows {
    /// Read from the record: enough that the largest lag covers ten periods of its lowest
    /// spectral peak, within a size budget ([`survey`](mod@crate::survey) says how). The default.
    Auto,
    /// Exactly this many.
    Count(usize),
    /// Enough that the largest lag 2i−1 covers this many seconds.
    Seconds(f64),
    /// Enough that the largest lag covers `count` periods of `frequency_hz`
    /// (the paper: 10 periods of the dominant mode).
    Periods {
        /// Number of periods.
        count: f64,
        /// Frequency whose period is counted (Hz).
        frequency_hz: f64,
    },
}

impl BlockRows {
    /// What holds at any rate: a count of at least 2, a time or a number of periods and a
    /// frequency positive and finite (each checked on its own, so that the error names the
    /// value at fault). [`resolve`](Self::resolve) checks these first.
    pub fn check(&self) -> Result<(), SsiError> {
        let invalid = |option, value| Err(SsiError::InvalidOption { option, value });
        let positive = |v: f64| v.is_finite() && v > 0.0;
        match *self {
            BlockRows::Auto => Ok(()),
            BlockRows::Count(i) if i < 2 => invalid(SsiOption::BlockRows, i as f64),
            BlockRows::Count(_) => Ok(()),
            BlockRows::Seconds(t) if !positive(t) => invalid(SsiOption::BlockRowsSeconds, t),
            BlockRows::Seconds(_) => Ok(()),
            BlockRows::Periods { count, .. } if !positive(count) => {
                invalid(SsiOption::BlockRowsPeriodsCount, count)
            }
            BlockRows::Periods { frequency_hz, .. } if !positive(frequency_hz) => {
                invalid(SsiOption::BlockRowsPeriodsFrequency, frequency_hz)
            }
            BlockRows::Periods { .. } => Ok(()),
        }
    }

    /// The number of block rows at sampling rate `fs`; `None` for [`BlockRows::Auto`], which
    /// needs the record ([`RecordSurvey::block_rows`](crate::RecordSurvey::block_rows)).
    pub fn resolve(&self, fs: f64) -> Result<Option<usize>, SsiError> {
        self.check()?;
        let i = match *self {
            BlockRows::Auto => return Ok(None),
            BlockRows::Count(i) => i,
            BlockRows::Seconds(t) => ((t * fs + 1.0) / 2.0).ceil() as usize,
            // `as` saturates: a lag beyond any record becomes usize::MAX block rows, which
            // `identify` reports as too short.
            BlockRows::Periods {
                count,
                frequency_hz,
            } => ((count / frequency_hz * fs + 1.0) / 2.0).ceil() as usize,
        };
        // A time or a number of periods too short for the rate.
        if i < 2 {
            return Err(SsiError::InvalidOption {
                option: SsiOption::BlockRows,
                value: i as f64,
            });
        }
        Ok(Some(i))
    }
}

/// Thresholds of the stabilization criteria (eqs. 30–31).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
pub struct StabilityCriteria {
    /// Largest relative change of natural frequency, dω.
    pub frequency: f64,
    /// Largest relative change of damping ratio, dζ.
    pub damping: f64,
    /// Largest 1 − MAC between mode shapes (several channels only).
    pub mac: f64,
    /// Largest relative change of a real pole, eq. (31).
    pub real: f64,
}

impl Default for StabilityCriteria {
    /// dω 1 %, dζ 5 %, 1 − MAC 2 %, real pole 1.5 (the paper's value for eq. 31).
    fn default() -> Self {
        StabilityCriteria {
            frequency: 0.01,
            damping: 0.05,
            mac: 0.02,
            real: 1.5,
        }
    }
}

/// Options of [`identify`](crate::identify()). `SsiOptions::default()` suits most records.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
pub struct SsiOptions {
    /// Block rows of the Toeplitz matrix. Default: [`BlockRows::Auto`], read from the record.
    pub block_rows: BlockRows,
    /// Largest model order; default: the numerical rank of the Toeplitz matrix, at most 40
    /// (with [`BlockRows::Auto`], at most four per spectral peak when there are more than ten).
    pub max_order: Option<usize>,
    /// Orders run `order_step, 2·order_step, …`; 1 keeps odd orders, where a real pole can
    /// appear. Default: 1.
    pub order_step: usize,
    /// Stabilization thresholds.
    pub criteria: StabilityCriteria,
    /// Poles damped more than this are rejected outright. Default: 0.5.
    pub max_damping: f64,
    /// Reference channels (indices); default: all.
    pub references: Option<Vec<usize>>,
    /// Stable poles within this relative distance, |λᵢ − λⱼ| / max(|λᵢ|, |λⱼ|), belong to one
    /// mode (single linkage). Default: 0.02.
    pub cluster_tolerance: f64,
    /// A mode needs at least this many stable poles; default: max(3, orders / 5).
    pub min_cluster_size: Option<usize>,
}

impl Default for SsiOptions {
    fn default() -> Self {
        SsiOptions {
            block_rows: BlockRows::Auto,
            max_order: None,
            order_step: 1,
            criteria: StabilityCriteria::default(),
            max_damping: 0.5,
            references: None,
            cluster_tolerance: 0.02,
            min_cluster_size: None,
        }
    }
}
