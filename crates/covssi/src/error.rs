//! The crate's error, and the option an invalid-option error names.

/// The option an [`SsiError::InvalidOption`] names.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum SsiOption {
    /// `BlockRows::Seconds`: the lag in seconds.
    BlockRowsSeconds,
    /// `BlockRows::Periods`: the count of periods.
    BlockRowsPeriodsCount,
    /// `BlockRows::Periods`: the frequency.
    BlockRowsPeriodsFrequency,
    /// Block rows beyond what the given correlations' lags allow (2·block rows needed).
    BlockRowsLags,
    /// The block rows: fewer than 2.
    BlockRows,
    /// `references`: empty.
    ReferencesEmpty,
    /// `references`: a channel index out of range.
    ReferenceOutOfRange,
    /// `references`: a channel named twice.
    ReferenceRepeated,
    /// `order_step`.
    OrderStep,
    /// `max_order`.
    MaxOrder,
    /// `min_cluster_size`.
    MinClusterSize,
    /// `criteria.frequency`.
    CriteriaFrequency,
    /// `criteria.damping`.
    CriteriaDamping,
    /// `criteria.mac`.
    CriteriaMac,
    /// `criteria.real`.
    CriteriaReal,
    /// `max_damping`.
    MaxDamping,
    /// `cluster_tolerance`.
    ClusterTolerance,
    /// `RefineOptions::max_iterations`.
    MaxIterations,
    /// `RefineOptions::tolerance`.
    Tolerance,
    /// `AnalysisOptions::decimation`: a factor of 0.
    Decimation,
    /// `FddOptions::segment`: under 16 samples or longer than the record.
    FddSegment,
    /// `ModeCriteria::max_damping_ratio`: not between 0 and 1.
    ModeMaxDamping,
}

impl SsiOption {
    /// The option's name as the error prints it (`criteria.damping`, `block_rows (seconds)`).
    pub fn name(self) -> &'static str {
        match self {
            SsiOption::BlockRowsSeconds => "block_rows (seconds)",
            SsiOption::BlockRowsPeriodsCount => "block_rows (periods: count)",
            SsiOption::BlockRowsPeriodsFrequency => "block_rows (periods: frequency_hz)",
            SsiOption::BlockRowsLags => "block_rows (needs 2·block_rows correlation lags)",
            SsiOption::BlockRows => "block_rows",
            SsiOption::ReferencesEmpty => "references (empty)",
            SsiOption::ReferenceOutOfRange => "references (index out of range)",
            SsiOption::ReferenceRepeated => "references (index repeated)",
            SsiOption::OrderStep => "order_step",
            SsiOption::MaxOrder => "max_order",
            SsiOption::MinClusterSize => "min_cluster_size",
            SsiOption::CriteriaFrequency => "criteria.frequency",
            SsiOption::CriteriaDamping => "criteria.damping",
            SsiOption::CriteriaMac => "criteria.mac",
            SsiOption::CriteriaReal => "criteria.real",
            SsiOption::MaxDamping => "max_damping",
            SsiOption::ClusterTolerance => "cluster_tolerance",
            SsiOption::MaxIterations => "max_iterations",
            SsiOption::Tolerance => "tolerance",
            SsiOption::Decimation => "decimation",
            SsiOption::FddSegment => "segment (FDD: 16 samples to the record's length)",
            SsiOption::ModeMaxDamping => "modes.max_damping_ratio",
        }
    }
}

impl std::fmt::Display for SsiOption {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Errors of identification.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SsiError {
    /// No channel was given.
    #[error("no channels given")]
    NoChannels,
    /// Channels differ in length.
    #[error("channel {channel} has {len} samples, channel 0 has {expected}")]
    LengthMismatch {
        /// 0-based channel.
        channel: usize,
        /// Its length.
        len: usize,
        /// Length of channel 0.
        expected: usize,
    },
    /// A sample is NaN or infinite.
    #[error("channel {channel}, sample {index}: value {value} is not finite")]
    NonFinite {
        /// 0-based channel.
        channel: usize,
        /// 0-based sample.
        index: usize,
        /// The value.
        value: f64,
    },
    /// A channel is constant (zero variance): it carries no dynamics.
    #[error("channel {channel} is constant (value {value}): it carries no response")]
    ConstantChannel {
        /// 0-based channel.
        channel: usize,
        /// Its value.
        value: f64,
    },
    /// The correlations are beyond what double precision computes with: the record's values
    /// are of order 1e150 or more, or 1e-145 or less, in its units.
    #[error(
        "the correlations' largest value at lag 0 is {value:e}, beyond what double precision computes with (record values between about 1e-145 and 1e150): rescale the record, e.g. to other units"
    )]
    OutOfRange {
        /// The largest absolute correlation at lag 0 (infinite or NaN if they overflowed).
        value: f64,
    },
    /// The record is too short for the requested lags.
    #[error(
        "{samples} samples are too few for {block_rows} block rows: the correlations need lags up to {lags}, so at least {needed} samples"
    )]
    TooShort {
        /// Samples given.
        samples: usize,
        /// Block rows asked.
        block_rows: usize,
        /// Largest lag needed.
        lags: usize,
        /// Minimum number of samples.
        needed: usize,
    },
    /// The sampling rate is not a positive finite number.
    #[error("sampling rate must be > 0, got {fs}")]
    NonPositiveRate {
        /// The rate (Hz).
        fs: f64,
    },
    /// The maximum model order exceeds the rank of the Toeplitz matrix.
    #[error(
        "model order {order} exceeds the numerical rank {rank} of the block Toeplitz matrix ({rows}×{cols}); lower the maximum order or add block rows"
    )]
    OrderAboveRank {
        /// Order asked.
        order: usize,
        /// Numerical rank.
        rank: usize,
        /// Toeplitz rows.
        rows: usize,
        /// Toeplitz columns.
        cols: usize,
    },
    /// A correlation matrix given to [`identify_from_correlations`](crate::identify_from_correlations) does not have
    /// channels × references entries.
    #[error(
        "the correlation matrix at lag {lag} has {len} entries; {channels} channels × {references} references need {}",
        channels.saturating_mul(*references)
    )]
    CorrelationShape {
        /// The lag whose matrix is wrong.
        lag: usize,
        /// Entries it has.
        len: usize,
        /// Channels l.
        channels: usize,
        /// References r.
        references: usize,
    },
    /// An option is out of range.
    #[error("option `{option}` is invalid: {value}")]
    InvalidOption {
        /// Which option.
        option: SsiOption,
        /// Its value.
        value: f64,
    },
    /// A dense linear-algebra routine failed.
    #[error("linear algebra failed: {0}")]
    LinearAlgebra(String),
    /// The record is too short to refine this many modes by maximum likelihood.
    #[error(
        "{samples} samples are too few to refine {modes} modes: the likelihood needs at least {needed}"
    )]
    TooShortToRefine {
        /// Samples given.
        samples: usize,
        /// Modes to refine.
        modes: usize,
        /// Minimum number of samples.
        needed: usize,
    },
    /// A real pole given to the refinement is not a negative finite number (λ of a decaying
    /// component, rad/s).
    #[error("a real pole to refine must be negative and finite, got {lambda}")]
    NotNegativeRealPole {
        /// The pole λ (rad/s).
        lambda: f64,
    },
    /// The maximum-likelihood refinement could not proceed.
    #[error("refinement failed: {reason}")]
    Refinement {
        /// Why.
        reason: &'static str,
    },
}
