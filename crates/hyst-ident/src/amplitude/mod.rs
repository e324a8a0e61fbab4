//! Each mode's natural frequency and damping ratio against its vibration amplitude, output
//! only: the amplitude-dependent equivalent mode that a hysteretic element gives (the
//! paper's eqs. 13, 19 and 20 are its Bouc-Wen case, through the describing function).
//!
//! For each mode $j$ (frequency $f_j$, shape $\phi_j$, from [`covssi`]):
//!
//! 1. **Modal response** (`filter`): $q_j(t) = w_j^\top y(t)$, with $w_j$ the $j$-th row of
//!    the pseudo-inverse of the real shapes when the channels are at least as many as the
//!    modes and tell them apart (a modal filter), else $\phi_j/\lVert\phi_j\rVert$ (a
//!    projection); then band-passed with zero phase to $f_j \pm h_j$,
//!    $h_j = \min(0.3 f_j, \tfrac12 \min_{k\ne j}|f_j - f_k|)$, which removes the other modes
//!    and the element's higher harmonics.
//! 2. **Random decrement at several levels** (`randec`): the extrema of $q_j$ (a minimum
//!    with its sign turned) split by their value into bands of equal count between the 5th
//!    and 99.5th percentiles; in each band the mean of the segments that start at its
//!    extrema, $D_k(\tau) = \overline{\pm q_j(t_i + \tau)}$, is the decay from the band's
//!    amplitude (for a linear mode, the correlation function scaled to it).
//! 3. **Decay fit** (`decay`): $e^{-\sigma\tau}(a\cos\omega_d\tau + b\sin\omega_d\tau)$ over the
//!    first [`AmplitudeOptions::cycles`] cycles of $D_k$; the point is
//!    $(A_k, f_k = |\lambda|/2\pi, \zeta_k = \sigma/|\lambda|)$, $A_k$ the fitted envelope
//!    at the window's middle, converted to the quantity asked for by $\omega^{\pm1,2}$.
//! 4. **Standard errors** by the grouped jackknife: the triggers fall in
//!    [`AmplitudeOptions::groups`] stretches of the record; every estimate is made again with
//!    each stretch left out, $\mathrm{se}^2 = \tfrac{G-1}{G}\sum_g(\theta_{-g} - \bar\theta)^2$.
//! 5. **Linearity test**: the weighted least-squares slope of $f$ and of $\zeta$ on $A$
//!    (weights $1/\mathrm{se}^2$), its standard error by the same jackknife, and Student's
//!    $t$ with $G-1$ degrees of freedom; the mode is called linear when neither slope is
//!    significant at [`LINEARITY_LEVEL`] (Bonferroni over the two).

mod agreement;
mod decay;
mod envelope;
mod filter;
mod physical;
mod randec;
mod report;
pub(crate) mod slope;

pub use agreement::{CurveAgreement, CurvesBesideModel, ModeAgreement, curve_agreement};
pub use report::{
    AmplitudeAnalysis, AmplitudeCampaign, CLIP_RUN, ClippedChannel, PooledMode, amplitude_analysis,
    amplitude_campaign, clipped_channels,
};
pub use slope::pooled_linearity;
use slope::{jackknife_se, linearity};

/// A mode whose band holds more white noise than this share of its variance is said to be
/// weak.
pub const WEAK_MODE_SHARE: f64 = 0.5;

/// Floors a structure may have ([`AmplitudeOptions::floors`]; the tallest building has 163):
/// each point's drifts are listed storey by storey up to the highest floor named.
pub const MAX_FLOORS: usize = 1000;

/// Overall significance of the linearity test (both slopes together).
pub const LINEARITY_LEVEL: f64 = 0.01;

/// The quantity a record measures, or an amplitude is reported in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(rename_all = "snake_case")
)]
pub enum Quantity {
    /// Displacement.
    #[default]
    Displacement,
    /// Velocity.
    Velocity,
    /// Acceleration.
    Acceleration,
}

impl Quantity {
    /// Time derivatives of displacement it is.
    pub(crate) fn order(self) -> i32 {
        match self {
            Quantity::Displacement => 0,
            Quantity::Velocity => 1,
            Quantity::Acceleration => 2,
        }
    }

    /// Its name.
    pub fn name(self) -> &'static str {
        match self {
            Quantity::Displacement => "displacement",
            Quantity::Velocity => "velocity",
            Quantity::Acceleration => "acceleration",
        }
    }

    /// The amplitude of the same harmonic motion at ω rad/s in `to`, from its amplitude `a`
    /// in `self`.
    pub fn convert(self, a: f64, omega: f64, to: Quantity) -> f64 {
        a * omega.powi(to.order() - self.order())
    }
}

/// How each amplitude band's decay is found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(rename_all = "snake_case")
)]
#[non_exhaustive]
pub enum AmplitudeMethod {
    /// Random decrement conditioned on the analytic signal's envelope, every sample a
    /// trigger, the segments turned to zero phase.
    #[default]
    Envelope,
    /// Classical random decrement at the response's extrema in each band (its frequency is
    /// biased at short windows: docs/amplitude.md).
    Extrema,
}

/// How the curves are made. In JSON (what `hyst.amplitude` passes), a field left out keeps
/// its default and an unknown one is an error.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(default, deny_unknown_fields)
)]
#[non_exhaustive]
pub struct AmplitudeOptions {
    /// Amplitude bands (points per curve; default 8).
    pub levels: usize,
    /// Cycles of each signature fitted (default 3): fewer follow the amplitude more closely,
    /// more lower the scatter.
    pub cycles: f64,
    /// Stretches of the record for the jackknife (default 20).
    pub groups: usize,
    /// Fewest triggers a point needs (default 50); a band with fewer is left out, and said.
    pub min_triggers: usize,
    /// Band-pass half-width relative to the mode's frequency; default
    /// $\min(0.3, \max(\tfrac12$ the relative distance to the nearest other mode$, 2ζ))$.
    pub band: Option<f64>,
    /// What the record measures (default displacement).
    pub measured: Quantity,
    /// What the amplitudes are reported in (default: as measured).
    pub report_as: Option<Quantity>,
    /// How each band's decay is found.
    pub method: AmplitudeMethod,
    /// Samples per period when the excitation is periodic (a multisine): the record's whole
    /// periods are averaged into one, which is then read as circular. Without it, a
    /// periodic record's stretches repeat one another and the standard errors are too small.
    pub period: Option<usize>,
    /// Each channel's floor (0 = the lowest above the ground), one channel per floor: the
    /// points then carry each storey's drift. Default none.
    pub floors: Option<Vec<usize>>,
}

impl Default for AmplitudeOptions {
    fn default() -> Self {
        AmplitudeOptions {
            levels: 8,
            cycles: 3.0,
            groups: 20,
            min_triggers: 50,
            band: None,
            measured: Quantity::Displacement,
            report_as: None,
            method: AmplitudeMethod::Envelope,
            period: None,
            floors: None,
        }
    }
}

impl AmplitudeOptions {
    /// Every option in range, or the first that is not, named: what is wrong whatever the
    /// record, to be said before any record is read or analysed.
    pub fn check(&self) -> Result<(), AmplitudeError> {
        let opts = self;
        let bad = |option, value: f64, needs| {
            Err(AmplitudeError::BadOption {
                option,
                value,
                needs,
            })
        };
        if opts.levels == 0 {
            return bad(AmplitudeOption::Levels, 0.0, "at least 1");
        }
        if !(opts.cycles >= 0.5 && opts.cycles <= 50.0) {
            return bad(AmplitudeOption::Cycles, opts.cycles, "between 0.5 and 50");
        }
        if opts.groups < 2 {
            return bad(AmplitudeOption::Groups, opts.groups as f64, "at least 2");
        }
        if opts.period == Some(0) {
            return bad(AmplitudeOption::Period, 0.0, "at least 1 sample");
        }
        if let Some(&f) = opts.floors.iter().flatten().find(|&&f| f >= MAX_FLOORS) {
            // Said as users count floors, from 1.
            return bad(
                AmplitudeOption::Floors,
                f as f64 + 1.0,
                "a floor from 1 to 1000 (no structure has more)",
            );
        }
        if let Some(b) = opts.band
            && !(b > 0.0 && b < 1.0)
        {
            return bad(
                AmplitudeOption::Band,
                b,
                "between 0 and 1 (a share of the frequency)",
            );
        }
        Ok(())
    }
}

/// An option of [`AmplitudeOptions`], named in errors.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum AmplitudeOption {
    /// [`AmplitudeOptions::levels`].
    Levels,
    /// [`AmplitudeOptions::cycles`].
    Cycles,
    /// [`AmplitudeOptions::groups`].
    Groups,
    /// [`AmplitudeOptions::band`].
    Band,
    /// [`AmplitudeOptions::period`].
    Period,
    /// [`AmplitudeOptions::floors`].
    Floors,
}

impl AmplitudeOption {
    /// The field's name: the Python keyword, and the flag without its dashes.
    pub fn name(self) -> &'static str {
        match self {
            AmplitudeOption::Levels => "levels",
            AmplitudeOption::Cycles => "cycles",
            AmplitudeOption::Groups => "groups",
            AmplitudeOption::Band => "band",
            AmplitudeOption::Period => "period",
            AmplitudeOption::Floors => "floors",
        }
    }
}

/// What is wrong with the amplitude analysis's input.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum AmplitudeError {
    /// An option out of range.
    #[error("{} = {value} is out of range: {needs}", option.name())]
    BadOption {
        /// Which.
        option: AmplitudeOption,
        /// Its value.
        value: f64,
        /// What it must be.
        needs: &'static str,
    },
    /// The record is shorter than one period.
    #[error("the record has {samples} samples, fewer than one period of {period}")]
    ShorterThanPeriod {
        /// Samples.
        samples: usize,
        /// The period.
        period: usize,
    },
    /// [`AmplitudeOptions::floors`] names another number of floors than there are channels,
    /// or one floor twice.
    #[error(
        "floors {:?} (from 1) for {channels} channels: give one floor per channel, each floor once",
        floors.iter().map(|f| f + 1).collect::<Vec<_>>()
    )]
    Floors {
        /// The floors given (0-based).
        floors: Vec<usize>,
        /// Channels.
        channels: usize,
    },
    /// A mode's shape has another length than the channels.
    #[error("mode at {frequency_hz} Hz: its shape has {shape} entries for {channels} channels")]
    ShapeLength {
        /// The mode.
        frequency_hz: f64,
        /// Entries.
        shape: usize,
        /// Channels.
        channels: usize,
    },
    /// No channel, or channels of different lengths.
    #[error("channel {channel} has {samples} samples, channel 0 {first}")]
    ChannelLengths {
        /// The channel.
        channel: usize,
        /// Its samples.
        samples: usize,
        /// Channel 0's.
        first: usize,
    },
    /// No channel given.
    #[error("no channel: give at least one")]
    NoChannel,
    /// A sample is NaN or infinite.
    #[error("channel {channel}, sample {index}: value {value} is not finite")]
    NonFinite {
        /// The channel.
        channel: usize,
        /// 0-based sample.
        index: usize,
        /// The value.
        value: f64,
    },
    /// More than the record can hold: more levels or jackknife groups than samples, or a
    /// signature of the slowest mode longer than the record.
    #[error("{} = {value} asks more than the record's {samples} samples hold: at most {most}{why}", option.name())]
    BeyondRecord {
        /// Which option.
        option: AmplitudeOption,
        /// Its value.
        value: f64,
        /// The most the record holds.
        most: f64,
        /// The record's samples.
        samples: usize,
        /// Why that is the most.
        why: String,
    },
    /// A mode's frequency is not inside (0, Nyquist).
    #[error("mode at {frequency_hz} Hz is not inside (0, {nyquist_hz}) Hz")]
    BadModeFrequency {
        /// The mode.
        frequency_hz: f64,
        /// fs/2.
        nyquist_hz: f64,
    },
}

/// A mode to follow: where it is, and its shape when known.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ModeToFollow {
    /// Natural frequency (Hz), e.g. SSI's.
    pub frequency_hz: f64,
    /// Damping ratio, e.g. SSI's.
    pub damping_ratio: f64,
    /// Shape, one entry per channel.
    pub shape: Option<Vec<covssi::Complex64>>,
}

/// One point of a mode's curves.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct AmplitudePoint {
    /// The mode's amplitude (in [`AmplitudeReport::amplitude_of`]; of the modal
    /// coordinate, in the record's unit).
    pub amplitude: f64,
    /// Triggers averaged.
    pub triggers: usize,
    /// Natural frequency (Hz).
    pub frequency_hz: f64,
    /// Its standard error (Hz).
    pub frequency_se_hz: f64,
    /// Damping ratio.
    pub damping_ratio: f64,
    /// Its standard error.
    pub damping_se: f64,
    /// The mode's amplitude at each channel (the same quantity): the amplitude times the
    /// channel's entry of the mode's unit real shape (empty when the shape is not known).
    #[cfg_attr(feature = "serde", serde(default))]
    pub channels: Vec<f64>,
    /// Each storey's drift amplitude (the same quantity), storey 1 (the ground to floor 1)
    /// first, when [`AmplitudeOptions::floors`] places the channels: the difference of the
    /// shape's entries at its two floors times the amplitude (NaN for a storey whose floors
    /// are not both measured; the ground does not move).
    #[cfg_attr(feature = "serde", serde(default, with = "crate::nullable"))]
    pub drifts: Vec<f64>,
}

/// A slope's test.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SlopeTest {
    /// The change over the amplitudes reached: the slope times the range (Hz, or damping
    /// ratio).
    pub change: f64,
    /// Its standard error.
    pub change_se: f64,
    /// Two-sided p-value of no change (Student's t, groups − 1 degrees of freedom).
    pub p_value: f64,
}

/// Whether a mode's frequency and damping change with its amplitude.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Linearity {
    /// The frequency's change.
    pub frequency: SlopeTest,
    /// The damping ratio's change.
    pub damping: SlopeTest,
    /// Neither is significant at [`LINEARITY_LEVEL`] (each at half of it).
    pub linear: bool,
}

/// One mode's curves.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ModeCurve {
    /// The mode followed.
    pub mode: ModeToFollow,
    /// The band its response was filtered to (Hz).
    pub band_hz: (f64, f64),
    /// The points, by increasing amplitude.
    pub points: Vec<AmplitudePoint>,
    /// The test (`None` with fewer than three points).
    pub linearity: Option<Linearity>,
    /// What was left out, and why.
    pub notes: Vec<String>,
}

/// What [`amplitude_curves`] finds.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct AmplitudeReport {
    /// Sampling rate (Hz).
    pub fs_hz: f64,
    /// What the record measures.
    pub measured: Quantity,
    /// What the amplitudes are in.
    pub amplitude_of: Quantity,
    /// The modes' curves.
    pub modes: Vec<ModeCurve>,
}

fn check_channels(y: &[&[f64]]) -> Result<(), AmplitudeError> {
    let first = y.first().ok_or(AmplitudeError::NoChannel)?.len();
    for (channel, c) in y.iter().enumerate() {
        if c.len() != first {
            return Err(AmplitudeError::ChannelLengths {
                channel,
                samples: c.len(),
                first,
            });
        }
        if let Some((index, &value)) = c.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(AmplitudeError::NonFinite {
                channel,
                index,
                value,
            });
        }
    }
    Ok(())
}

/// Each mode's frequency and damping against its amplitude, from `y` (channels, each
/// `samples` long, at `fs` Hz) and the modes to follow.
///
/// `others`: the record's other modes (not followed): their frequencies bound each band,
/// and their shapes join the modal filter. A point is a mode's estimate as
/// [`covssi::ModeCriteria::default`] takes one ([`amplitude_analysis`] judges by the
/// criteria its modes were decided by).
pub fn amplitude_curves(
    y: &[&[f64]],
    fs: f64,
    modes: &[ModeToFollow],
    others: &[ModeToFollow],
    opts: &AmplitudeOptions,
) -> Result<AmplitudeReport, crate::IdentError> {
    curves_judged(
        y,
        fs,
        (modes, others),
        opts,
        &covssi::ModeCriteria::default(),
    )
}

/// [`amplitude_curves`], each point judged by `criteria`.
pub(crate) fn curves_judged(
    y: &[&[f64]],
    fs: f64,
    (modes, others): (&[ModeToFollow], &[ModeToFollow]),
    opts: &AmplitudeOptions,
    criteria: &covssi::ModeCriteria,
) -> Result<AmplitudeReport, crate::IdentError> {
    opts.check()?;
    if !(fs > 0.0 && fs.is_finite()) {
        return Err(crate::IdentError::BadRate { fs });
    }
    check_channels(y)?;
    if let Some(period) = opts.period
        && y[0].len() < period
    {
        return Err(AmplitudeError::ShorterThanPeriod {
            samples: y[0].len(),
            period,
        }
        .into());
    }
    let channels = y.len();
    for m in modes.iter().chain(others) {
        if !(m.frequency_hz > 0.0 && m.frequency_hz < 0.5 * fs) {
            return Err(AmplitudeError::BadModeFrequency {
                frequency_hz: m.frequency_hz,
                nyquist_hz: 0.5 * fs,
            }
            .into());
        }
        if let Some(s) = &m.shape
            && s.len() != channels
        {
            return Err(AmplitudeError::ShapeLength {
                frequency_hz: m.frequency_hz,
                shape: s.len(),
                channels,
            }
            .into());
        }
    }
    within_record(y[0].len(), fs, modes, opts)?;
    physical::check_floors(opts.floors.as_deref(), channels)?;
    let (opts, repeats) = &with_detected_period(y, fs, modes, opts);
    let all: Vec<ModeToFollow> = modes.iter().chain(others).cloned().collect();
    let weights = filter::modal_weights(&all, channels);
    let report_as = opts.report_as.unwrap_or(opts.measured);
    let curves = modes
        .iter()
        .enumerate()
        .map(|(j, m)| {
            let nearest = all
                .iter()
                .enumerate()
                .filter(|(k, _)| *k != j)
                .map(|(_, o)| (o.frequency_hz - m.frequency_hz).abs() / m.frequency_hz)
                .fold(f64::INFINITY, f64::min);
            // Half the way to the nearest other mode, at least twice the mode's half-power
            // half-width (a band narrower than the mode holds none of it: a mode listed
            // twice made it empty), at most 30 %.
            let h = opts
                .band
                .unwrap_or((0.5 * nearest).max(2.0 * m.damping_ratio).min(0.3));
            let band = (
                m.frequency_hz * (1.0 - h),
                (m.frequency_hz * (1.0 + h)).min(0.5 * fs),
            );
            let q = filter::combine(y, &weights[j]);
            let q = match opts.period {
                Some(p) => period_mean(&q, p),
                None => q,
            };
            let mut curve = mode_curve(&q, fs, (m, band), opts, report_as, criteria);
            physical::place(&mut curve, m, channels, opts.floors.as_deref());
            curve.notes.extend(repeats.clone());
            curve
        })
        .collect();
    Ok(AmplitudeReport {
        fs_hz: fs,
        measured: opts.measured,
        amplitude_of: report_as,
        modes: curves,
    })
}

/// The options against what a record of `samples` holds, before anything is allocated by
/// them, so that no option makes the analysis hold more than a few times the record: at most
/// one level and one jackknife group per sample, and a signature (`cycles` periods of the
/// slowest mode) no longer than the record. (A record too short for a level's triggers
/// gets its curve's note, not this error.)
fn within_record(
    samples: usize,
    fs: f64,
    modes: &[ModeToFollow],
    opts: &AmplitudeOptions,
) -> Result<(), AmplitudeError> {
    let n = samples as f64;
    let beyond = |option, value: f64, most: f64, why: String| {
        Err(AmplitudeError::BeyondRecord {
            option,
            value,
            most,
            samples,
            why,
        })
    };
    for (option, value) in [
        (AmplitudeOption::Levels, opts.levels),
        (AmplitudeOption::Groups, opts.groups),
    ] {
        if value > samples {
            return beyond(option, value as f64, n, " (one per sample)".into());
        }
    }
    let slowest = modes
        .iter()
        .map(|m| m.frequency_hz)
        .fold(f64::INFINITY, f64::min);
    if slowest.is_finite() && opts.cycles * fs / slowest > n {
        return beyond(
            AmplitudeOption::Cycles,
            opts.cycles,
            n * slowest / fs,
            format!(" (a signature of the slowest mode, {slowest} Hz, within the record)"),
        );
    }
    Ok(())
}

/// A lag of at least this many cycles of the slowest mode followed is a period only the
/// excitation can make: a mode of damping ratio ζ keeps e^(−2π·50ζ) of its correlation over
/// it (0.73 at ζ = 0.1 %), below [`crate::periodic::PERIODIC_CORRELATION`].
const REPEAT_CYCLES: f64 = 50.0;

/// `opts` with the record's period when none is given and the first channel repeats
/// ([`crate::periodic::repeat_period`], at lags of at least [`REPEAT_CYCLES`] cycles of the
/// slowest mode), and the note that says so. Without it a periodic record's stretches repeat
/// one another and the standard errors come out too small.
fn with_detected_period(
    y: &[&[f64]],
    fs: f64,
    modes: &[ModeToFollow],
    opts: &AmplitudeOptions,
) -> (AmplitudeOptions, Option<String>) {
    let slowest = modes
        .iter()
        .map(|m| m.frequency_hz)
        .fold(f64::INFINITY, f64::min);
    let min_lag = REPEAT_CYCLES * fs / slowest;
    let found = match (opts.period, y.first()) {
        (None, Some(c)) if min_lag.is_finite() => {
            crate::periodic::repeat_period(c, min_lag.ceil() as usize)
        }
        _ => None,
    };
    match found {
        Some(p) => {
            let mut o = opts.clone();
            o.period = Some(p);
            let note = format!(
                "the record repeats itself every {p} samples (a periodic excitation): its whole \
                 periods were averaged into one, as --period {p} does (without it the stretches \
                 repeat one another and the standard errors come out too small)"
            );
            (o, Some(note))
        }
        None => (opts.clone(), None),
    }
}

/// The mean of `q`'s last whole periods of `p` samples.
fn period_mean(q: &[f64], p: usize) -> Vec<f64> {
    let periods = q.len() / p;
    let start = q.len() - periods * p;
    let mut m = vec![0.0; p];
    for k in 0..periods {
        m.iter_mut()
            .zip(&q[start + k * p..start + (k + 1) * p])
            .for_each(|(a, b)| *a += b / periods as f64);
    }
    m
}

/// A mode's amplitude bands, however triggered: their edges (in the record's unit), the
/// triggers in each, and every band's decay with one group left out (`None`: none).
struct Bands {
    edges: Vec<f64>,
    totals: Vec<usize>,
    estimate: Box<dyn Fn(Option<usize>) -> Vec<Option<decay::Decay>> + Sync>,
}

/// The linear mode's signature through `band`, for the fits.
fn filtered_mode(
    q: &[f64],
    fs: f64,
    window: usize,
    band: (f64, f64),
    m: &ModeToFollow,
    opts: &AmplitudeOptions,
) -> decay::FilteredMode {
    let weight = |f: f64| filter::band_weight(f, band.0, band.1);
    let model = decay::FilteredMode::new(
        fs,
        window,
        band,
        &weight,
        opts.measured.order(),
        m.frequency_hz,
        (0.5 * m.damping_ratio).clamp(5e-4, 0.05),
    );
    let share = decay::noise_share(
        q,
        fs,
        band,
        &weight,
        &model,
        m.frequency_hz,
        m.damping_ratio.clamp(1e-4, 0.3),
    );
    model.with_noise_share(share)
}

/// The extrema of the band-passed response as triggers.
fn extrema_bands(
    q: Vec<f64>,
    model: decay::FilteredMode,
    window: usize,
    m: &ModeToFollow,
    opts: &AmplitudeOptions,
) -> Option<Bands> {
    let triggers = randec::extrema(&q, window, opts.period.is_some());
    if triggers.len() < opts.min_triggers {
        return None;
    }
    let values: Vec<f64> = triggers.iter().map(|t| t.1).collect();
    let edges = randec::level_edges(&values, opts.levels, 0.05, 0.995);
    let levels = randec::level_sums(&q, &triggers, &edges, window, opts.groups);
    let (f0, z0) = (m.frequency_hz, m.damping_ratio.clamp(1e-4, 0.3));
    Some(Bands {
        edges,
        totals: levels.iter().map(|l| l.total()).collect(),
        estimate: Box::new(move |skip| {
            levels
                .iter()
                .map(|l| {
                    let (s, _) = l.signature(skip)?;
                    let s: Vec<crate::fft::C> =
                        s.iter().map(|v| crate::fft::C::new(*v, 0.0)).collect();
                    model.fit(&s, true, f0, z0)
                })
                .collect()
        }),
    })
}

/// Every `stride`-th sample as a trigger, by the envelope.
fn envelope_bands(
    q: &[f64],
    fs: f64,
    (band, model): ((f64, f64), decay::FilteredMode),
    window: usize,
    m: &ModeToFollow,
    opts: &AmplitudeOptions,
) -> Option<Bands> {
    let (re, im) = envelope::analytic(q, fs, band.0, band.1);
    // Eight triggers a cycle: neighbours closer than that add little.
    let stride = ((fs / m.frequency_hz) / 8.0).floor().max(1.0) as usize;
    let circular = opts.period.is_some();
    let usable = if circular {
        re.len()
    } else {
        re.len().saturating_sub(window)
    };
    let env: Vec<f64> = (0..usable)
        .step_by(stride)
        .map(|t| re[t].hypot(im[t]))
        .collect();
    if env.len() < opts.min_triggers {
        return None;
    }
    let edges = randec::level_edges(&env, opts.levels, 0.05, 0.995);
    let sums = envelope::band_sums(&re, &im, &edges, window, stride, opts.groups, circular);
    let (f0, z0) = (m.frequency_hz, m.damping_ratio.clamp(1e-4, 0.3));
    Some(Bands {
        edges,
        totals: sums.iter().map(|b| b.total()).collect(),
        estimate: Box::new(move |skip| {
            sums.iter()
                .map(|b| model.fit(&b.signature(skip)?, false, f0, z0))
                .collect()
        }),
    })
}

fn mode_curve(
    q: &[f64],
    fs: f64,
    (m, band): (&ModeToFollow, (f64, f64)),
    opts: &AmplitudeOptions,
    report_as: Quantity,
    criteria: &covssi::ModeCriteria,
) -> ModeCurve {
    let mut notes = Vec::new();
    let window = (opts.cycles * fs / m.frequency_hz).round().max(8.0) as usize;
    let mut curve = ModeCurve {
        mode: m.clone(),
        band_hz: band,
        points: Vec::new(),
        linearity: None,
        notes: Vec::new(),
    };
    // The model each band's decay is fitted by, with the white noise's share read from the
    // unfiltered response's spectrum.
    let model = filtered_mode(q, fs, window, band, m, opts);
    if model.noise_share() > WEAK_MODE_SHARE {
        notes.push(format!(
            "{:.0} % of the band's variance is white noise (sensor noise, or a force's direct share): the mode is weak against it here, and its points' errors are large",
            100.0 * model.noise_share()
        ));
    }
    let bands = match opts.method {
        AmplitudeMethod::Envelope => envelope_bands(q, fs, (band, model), window, m, opts),
        AmplitudeMethod::Extrema => extrema_bands(
            filter::band_pass(q, fs, band.0, band.1),
            model,
            window,
            m,
            opts,
        ),
    };
    let Some(bands) = bands else {
        notes.push(format!(
            "the record holds fewer than the {} triggers one point needs: no curve",
            opts.min_triggers
        ));
        curve.notes = notes;
        return curve;
    };
    let full = (bands.estimate)(None);
    let replicates: Vec<Vec<Option<decay::Decay>>> = (0..opts.groups)
        .map(|g| (bands.estimate)(Some(g)))
        .collect();
    let omega = |d: &decay::Decay| 2.0 * std::f64::consts::PI * d.frequency_hz;
    let amp = |d: &decay::Decay| opts.measured.convert(d.amplitude, omega(d), report_as);
    // A point needs its triggers, and a fit with every group and with each left out; and
    // it is a mode's estimate at its level only as covssi's decision would take one: its
    // frequency known (error within ModeCriteria's share of it) and damped within the limit.
    // Else it is said and left out, not printed as a result.
    let mut rows: Vec<Vec<decay::Decay>> = Vec::new();
    for (k, d) in full.iter().enumerate() {
        let n = bands.totals[k];
        let (lo, hi) = (bands.edges[k], bands.edges[k + 1]);
        if n < opts.min_triggers {
            notes.push(format!(
                "amplitudes {lo:.4e}–{hi:.4e} (record's unit): {n} triggers, fewer than {}: left out",
                opts.min_triggers
            ));
            continue;
        }
        let reps: Option<Vec<decay::Decay>> = replicates.iter().map(|r| r[k]).collect();
        let (Some(d), Some(reps)) = (d, reps) else {
            notes.push(format!(
                "amplitudes {lo:.4e}–{hi:.4e} (record's unit): no decaying oscillation over {} cycles to fit: left out",
                opts.cycles
            ));
            continue;
        };
        let f: Vec<f64> = reps.iter().map(|r| r.frequency_hz).collect();
        let z: Vec<f64> = reps.iter().map(|r| r.damping_ratio).collect();
        let point = AmplitudePoint {
            amplitude: amp(d),
            triggers: n,
            frequency_hz: d.frequency_hz,
            frequency_se_hz: jackknife_se(&f),
            damping_ratio: d.damping_ratio,
            damping_se: jackknife_se(&z),
            channels: vec![],
            drifts: vec![],
        };
        let se = point.frequency_se_hz;
        let why = if se.is_nan() || se > criteria.max_frequency_cv * d.frequency_hz {
            format!(
                "frequency {:.4} ± {se:.4} Hz, its error above {:.0} % of it",
                d.frequency_hz,
                100.0 * criteria.max_frequency_cv
            )
        } else if d.damping_ratio > criteria.max_damping_ratio {
            format!(
                "damping ratio {:.3}, above {}",
                d.damping_ratio, criteria.max_damping_ratio
            )
        } else {
            curve.points.push(point);
            rows.push(reps);
            continue;
        };
        notes.push(format!(
            "amplitudes {lo:.4e}–{hi:.4e} (record's unit): {why}: not a mode's estimate, left out"
        ));
    }
    if rows.len() >= 3 {
        curve.linearity = Some(linearity(&curve.points, &rows, opts.groups, &amp));
    }
    curve.notes = notes;
    curve
}

#[cfg(test)]
mod tests;
