//! The crate's error.

use covssi::Complex64;
use hyst_linearize::LinearizeError;
use hyst_sim::SimError;

/// Errors of the pipeline.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum IdentError {
    /// A storey fit's input or step ([`crate::storeys`]).
    #[error("storey fit: {0}")]
    Storey(#[from] crate::storeys::StoreyError),
    /// SSI failed.
    #[error("SSI: {0}")]
    Ssi(#[from] covssi::SsiError),
    /// A linearization step failed.
    #[error("linearization: {0}")]
    Linearize(#[from] LinearizeError),
    /// The amplitude analysis's input or options.
    #[error("amplitude analysis: {0}")]
    Amplitude(#[from] crate::amplitude::AmplitudeError),
    /// A simulation failed.
    #[error("simulation: {0}")]
    Sim(#[from] SimError),
    /// An error in one of several records, named.
    #[error("{record}: {source}")]
    InRecord {
        /// The record.
        record: String,
        /// What went wrong there.
        source: Box<IdentError>,
    },
    /// A record of the levels workflow has no Zener spectral fit (it was not the response to
    /// a broadband random force, or its pair and real pole were not refined).
    #[error(
        "{record}: no Zener spectral fit, so no level for the model ({notes}); each record must be the response to a broadband random force"
    )]
    NoSpectralFit {
        /// The record.
        record: String,
        /// The pipeline's notes on its poles.
        notes: String,
    },
    /// The mass is so large or small that the model's stiffness, m·ω² up to Nyquist, leaves
    /// what double precision computes with.
    #[error(
        "mass {mass:e} kg is beyond what the model can be computed with: its stiffness up to Nyquist would be m·(π·fs)² = {stiffness:e} N/m (double precision works up to about 1e150); give the mass in other units"
    )]
    MassOutOfRange {
        /// The mass (kg).
        mass: f64,
        /// m·(π·fs)² (N/m).
        stiffness: f64,
    },
    /// The mass is not a positive finite number.
    #[error("mass must be > 0 kg, got {mass}")]
    NonPositiveMass {
        /// The mass.
        mass: f64,
    },
    /// The record is too short.
    #[error("the record has {samples} samples; at least {needed} are needed")]
    TooShort {
        /// Samples given.
        samples: usize,
        /// Samples needed.
        needed: usize,
    },
    /// No oscillating pair stable in frequency and damping was found.
    #[error("no oscillating pole pair is stable in frequency and damping near {dominant_hz:.2} Hz")]
    NoStablePair {
        /// The dominant frequency of the spectrum.
        dominant_hz: f64,
    },
    /// The stable pair the stabilization diagram offers is not supported by the record's
    /// likelihood, and the record follows the model without it: a spurious cluster, as white
    /// noise can give.
    #[error(
        "the stable pole pair at {frequency_hz:.2} Hz is not supported by the record: removing it raises the negative log-likelihood by only {evidence:.1}, below the BIC penalty {penalty:.1} of a mode, and the record follows the model without it (misfit {misfit:.3}); the record shows no resonance there"
    )]
    PairNotSupported {
        /// Frequency of the pair's cluster (Hz).
        frequency_hz: f64,
        /// Rise of the negative log-likelihood when the pair is removed.
        evidence: f64,
        /// The BIC penalty of one mode.
        penalty: f64,
        /// Misfit of the model without the pair ([`covssi::Refinement::misfit`]).
        misfit: f64,
    },
    /// The sampling rate is not a positive finite number.
    #[error("sampling rate must be > 0 Hz, got {fs}")]
    BadRate {
        /// The rate given.
        fs: f64,
    },
    /// The excitation's period is too short to hold a band.
    #[error("the excitation's period must be at least 2 samples, got {period}")]
    PeriodTooShort {
        /// Samples per period given.
        period: usize,
    },
    /// The excitation band reaches above the Nyquist frequency.
    #[error(
        "excitation band {low_hz}..{high_hz} Hz reaches above the Nyquist frequency {} Hz of {fs} Hz",
        fs / 2.0
    )]
    BandAboveNyquist {
        /// Lower edge (Hz).
        low_hz: f64,
        /// Upper edge (Hz).
        high_hz: f64,
        /// Sampling rate (Hz).
        fs: f64,
    },
    /// The excitation band holds too few DFT bins of one period.
    #[error(
        "excitation band {low_hz}..{high_hz} Hz holds fewer than 9 DFT bins of a {period}-sample period at {fs} Hz"
    )]
    BadBand {
        /// Lower edge (Hz).
        low_hz: f64,
        /// Upper edge (Hz).
        high_hz: f64,
        /// Sampling rate (Hz).
        fs: f64,
        /// Samples per period.
        period: usize,
    },
    /// The model the flatness fit starts from cannot be used.
    #[error("flatness fit: {reason}")]
    BadStart {
        /// Why.
        reason: String,
    },
    /// The upper edge of a spectral fit's band is not a positive number of Hz.
    #[error("the band's upper edge must be a positive number of Hz, got {f_max}")]
    BadMaxFrequency {
        /// The edge given (Hz).
        f_max: f64,
    },
    /// The poles a Zener spectral fit starts from are not a stable pair and a negative real
    /// pole, or no fit from them gave a valid spectrum.
    #[error(
        "the Zener spectral fit cannot start from the pair {pair} and the real pole {real} rad/s: it needs Re < 0 < Im and a real pole < 0, and a valid spectrum from them"
    )]
    UnstableStart {
        /// The oscillating pole given (rad/s).
        pair: Complex64,
        /// The real pole given (rad/s).
        real: f64,
    },
    /// Records of one structure were given with different masses.
    #[error("the levels' records must share one structure's mass: {first} kg and {other} kg")]
    MassesDiffer {
        /// The first record's mass (kg).
        first: f64,
        /// A record's other mass (kg).
        other: f64,
    },
    /// Input and output records differ in length.
    #[error("input has {input} samples, output {output}")]
    LengthMismatch {
        /// Input length.
        input: usize,
        /// Output length.
        output: usize,
    },
    /// A frequency-response band holds too few excited lines for the fit asked of it.
    #[error(
        "the band {low_hz}..{high_hz} Hz holds {lines} excited lines of the input; the fit needs at least {needed}"
    )]
    FewLines {
        /// Lower edge (Hz).
        low_hz: f64,
        /// Upper edge (Hz).
        high_hz: f64,
        /// Excited lines found there.
        lines: usize,
        /// Lines needed.
        needed: usize,
    },
    /// A frequency-response band is not an interval within 0 Hz and Nyquist.
    #[error(
        "the band {low_hz}..{high_hz} Hz is not an interval within 0..{nyquist_hz} Hz (Nyquist)"
    )]
    BandOutOfRange {
        /// Lower edge (Hz).
        low_hz: f64,
        /// Upper edge (Hz).
        high_hz: f64,
        /// Half the sampling rate (Hz).
        nyquist_hz: f64,
    },
    /// Rows given for estimation or testing are not a range `start < end` within the record.
    #[error(
        "rows {start}:{end} are not a range A:B with A < B <= {samples} (the record's samples)"
    )]
    BadRows {
        /// First row.
        start: usize,
        /// One past the last row.
        end: usize,
        /// Samples in the record.
        samples: usize,
    },
    /// The residual loop's starting model cannot be simulated over the estimation rows, and
    /// no fit from it (or from the equation-error start) converged.
    #[error(
        "the starting model diverges on the estimation rows {start}:{end}, and no fit from it converged: start from a model that follows the record"
    )]
    StartDiverges {
        /// First estimation row.
        start: usize,
        /// One past the last estimation row.
        end: usize,
    },
    /// A test range of the residual loop overlaps the estimation rows: a gain on rows the fit
    /// saw is not held out.
    #[error(
        "test rows {test_start}:{test_end} overlap the estimation rows {estimate_start}:{estimate_end}: the held-out test needs rows the fit never sees"
    )]
    TestOverlapsEstimate {
        /// First test row.
        test_start: usize,
        /// One past the last test row.
        test_end: usize,
        /// First estimation row.
        estimate_start: usize,
        /// One past the last estimation row.
        estimate_end: usize,
    },
    /// A test range of the residual loop is too short for its held-out test.
    #[error(
        "test rows {start}:{end} are {} rows; the held-out test needs at least {needed} (8 blocks of 64)",
        end - start
    )]
    TestTooShort {
        /// First row.
        start: usize,
        /// One past the last row.
        end: usize,
        /// Rows needed.
        needed: usize,
    },
    /// A sample of a record is too large to be squared and summed in double precision.
    #[error(
        "record {channel} (0 = input, then the outputs), sample {index}: value {value:e} is too large to compute spectra with in double precision (above 1e150): rescale the record, e.g. to other units"
    )]
    SampleTooLarge {
        /// 0 for the input, 1.. for the outputs.
        channel: usize,
        /// 0-based sample.
        index: usize,
        /// The value.
        value: f64,
    },
    /// The input does not repeat with the period given.
    #[error(
        "the input does not repeat every {period} samples: {:.0} % of its variance differs from period to period (at most 20 % allowed); is the period right?",
        100.0 * fraction
    )]
    NotPeriodic {
        /// The period given (samples).
        period: usize,
        /// Share of the input's variance that differs between periods.
        fraction: f64,
    },
    /// The rational fit of a response band stopped being finite.
    #[error(
        "the fit of the response over {low_hz}..{high_hz} Hz broke down (its denominator vanished at a line); try another band or number of modes"
    )]
    ResponseFitFailed {
        /// Lower edge (Hz).
        low_hz: f64,
        /// Upper edge (Hz).
        high_hz: f64,
    },
    /// No output channel was given.
    #[error("no output channel was given")]
    NoOutputs,
    /// A response fit was asked for zero modes.
    #[error("a response fit needs at least one mode")]
    NoModesAsked,
    /// A sample of a record is NaN or infinite.
    #[error(
        "record {channel} (0 = input, then the outputs), sample {index}: value {value} is not finite"
    )]
    NonFiniteSample {
        /// 0 for the input, 1.. for the outputs.
        channel: usize,
        /// 0-based sample.
        index: usize,
        /// The value.
        value: f64,
    },
}

impl IdentError {
    /// This error as one of the record `record`'s.
    pub fn in_record(self, record: &str) -> IdentError {
        IdentError::InRecord {
            record: record.to_string(),
            source: Box::new(self),
        }
    }
}
