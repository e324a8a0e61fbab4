//! The output-only identification pipeline of the paper (Sections 3–4): from a measured
//! displacement record alone to linear, Zener and Bouc-Wen models of a single-degree-of-freedom
//! oscillator of known mass.
//!
//! Each step is a function of its own; [`identify`] runs them all:
//!
//! 1. [`prepare`]: remove the mean, find the dominant frequency from the spectrum, decimate to
//!    about [`IdentOptions::samples_per_period`] samples per period of it, report skewness and
//!    kurtosis (a stationary Gaussian-like response has 0 and 3).
//! 2. [`run_ssi`]: [`covssi`] with block rows spanning [`IdentOptions::periods`] periods of the
//!    dominant mode and the paper's thresholds (Δω = Δζ = 0.05, real-pole criterion 1.5).
//! 3. [`select_poles`]: the oscillating pair (the stable cluster nearest the dominant
//!    frequency, most members first, kept only when the record's likelihood supports it:
//!    its evidence in [`covssi::refine()`] at least the BIC penalty of a mode), the real
//!    pole (the largest stable real cluster, else the median of all stable real poles), and
//!    the viscous damping guess c ([`DampingGuess`]). When the record follows the stationary
//!    model (a random excitation), the pair and the real pole are then refined together by
//!    maximum likelihood ([`covssi::refine_with_real_poles`]) and used in place of SSI's.
//!
//!    Step 3b, [`fit_zener_spectrum`], when they were: the Zener oscillator fitted to the
//!    record's spectrum by maximum likelihood ([`zener_spectrum`]). The spectrum's zero at
//!    $-\Omega$ is the fourth relation the poles lack, so c comes from the record, with a
//!    standard error, instead of the guess (white force assumed; [`DampingGuess`]).
//! 4. [`build_models`]: linear $k = m|\lambda|^2$, $c = -2m\operatorname{Re}\lambda$; Zener
//!    $(k, k_\infty, \Omega)$ by coefficient matching of eq. (32); Bouc-Wen with α from eq. (37)
//!    and (βγ, βδ) from eq. (38) ([`Linearization::Paper`]) or from the exact inversion of the
//!    describing function at $A$ ([`Linearization::Harmonic`]).
//!
//!    Step 4b, [`fit_flatness`], when the excitation's band is known
//!    ([`IdentOptions::excitation`]): the Bouc-Wen parameters that make the implied input flat
//!    over the band ([`flatness`]); this replaces the mapped Bouc-Wen model.
//! 5. [`validate`]: simulate a model with a measured input and report
//!    $\varepsilon = \text{RMS}(\hat y - y)/(\max y - \min y)$ (eq. 39) and the RMS.
//!
//! With the input too, [`frf`] fits the modes of a periodic record's frequency response: the
//! input-output second opinion on what output-only SSI reports.
//!
//! Across records: [`levels::bouc_wen_from_levels`] takes the step-3b fits of records at two
//! or more force levels and gives one Bouc-Wen model for all, through the statistical
//! linearization of [`hyst_linearize::statistical`] ([`levels::bouc_wen_and_exponent_from_levels`]
//! its exponent ν too, from three or more).

#![warn(missing_docs)]

mod fft;
pub mod flatness;
pub mod floor;
pub mod frf;
pub mod levels;
pub mod periodic;
pub mod refine;
pub mod zener_spectrum;

use covssi::{BlockRows, RealPoleCluster, SsiOptions, SsiResult, Stability, StabilityCriteria};
use hyst_linearize::{Amplitude, LinearizeError};
use hyst_model::{BoucWen, Oscillator};
use hyst_sim::{Decimation, Input, SimError, SimOptions};

pub use covssi::Complex64;

/// Errors of the pipeline.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum IdentError {
    /// SSI failed.
    #[error("SSI: {0}")]
    Ssi(#[from] covssi::SsiError),
    /// A linearization step failed.
    #[error("linearization: {0}")]
    Linearize(#[from] LinearizeError),
    /// A simulation failed.
    #[error("simulation: {0}")]
    Sim(#[from] SimError),
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

/// Where the viscous damping c of the Zener and Bouc-Wen models comes from.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum DampingGuess {
    /// From the record, with no guess, when it follows the stationary model (a random
    /// excitation) and SSI's pair and real pole were refined: the Zener oscillator fitted to
    /// the record's spectrum ([`zener_spectrum`], step 3b), which assumes a force white over
    /// the band. Otherwise, or when that fit does not hold (see [`fit_zener_spectrum`]), as
    /// [`DampingGuess::LowDampingCluster`] (a note says why).
    #[default]
    ZenerSpectrum,
    /// The paper's choice: a cluster of lightly damped poles near the dominant frequency,
    /// $c = -2m\operatorname{Re}\lambda$; if there is none, c = 0.
    LowDampingCluster,
    /// A given value (N s/m).
    Value(f64),
}

/// How the Zener element maps to Bouc-Wen parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Linearization {
    /// Eqs. (37)–(38) as printed.
    Paper,
    /// α from eq. (37), (βγ, βδ) by exact inversion of the numerical describing function.
    #[default]
    Harmonic,
}

/// Options of the pipeline.
#[derive(Debug, Clone, PartialEq)]
pub struct IdentOptions {
    /// Mass m (kg), assumed known.
    pub mass: f64,
    /// Target samples per period of the dominant mode after decimation (default 10).
    pub samples_per_period: f64,
    /// The block rows of the Toeplitz matrix span this many periods of the dominant mode
    /// (default 10, as the paper's Section 4).
    pub periods: f64,
    /// Largest model order (default 20).
    pub max_order: usize,
    /// Stabilization thresholds (default: the paper's 0.05, 0.05, real 1.5).
    pub criteria: StabilityCriteria,
    /// Source of c.
    pub damping_guess: DampingGuess,
    /// Mapping to Bouc-Wen.
    pub linearization: Linearization,
    /// Amplitude A for the mapping (default σₓ).
    pub amplitude: Amplitude,
    /// The excitation's design, when known: then the Bouc-Wen model is fitted by flatness of
    /// its implied input ([`flatness`]), starting from the mapped one (default: unknown).
    pub excitation: Option<flatness::ExcitationBand>,
}

impl Default for IdentOptions {
    fn default() -> Self {
        IdentOptions {
            mass: 2.0,
            samples_per_period: 10.0,
            periods: 10.0,
            max_order: 20,
            criteria: StabilityCriteria {
                frequency: 0.05,
                damping: 0.05,
                mac: 0.02,
                real: 1.5,
            },
            damping_guess: DampingGuess::default(),
            linearization: Linearization::default(),
            amplitude: Amplitude::SigmaX,
            excitation: None,
        }
    }
}

/// The prepared output record.
#[derive(Debug, Clone, PartialEq)]
pub struct Prepared {
    /// Centred, decimated record.
    pub y: Vec<f64>,
    /// Its sampling rate (Hz).
    pub fs: f64,
    /// Decimation factor applied.
    pub decimation: usize,
    /// Mean removed.
    pub mean: f64,
    /// Standard deviation σₓ of the (undecimated) record.
    pub sigma_x: f64,
    /// Skewness of the prepared record.
    pub skewness: f64,
    /// Kurtosis of the prepared record (3 for a Gaussian).
    pub kurtosis: f64,
    /// Dominant frequency of the spectrum (Hz).
    pub dominant_hz: f64,
}

/// Mean, standard deviation, skewness and kurtosis. The deviations are divided by the
/// largest of them first, so that their fourth powers neither underflow nor overflow in any
/// units the record may be in.
fn moments(y: &[f64]) -> (f64, f64, f64, f64) {
    let n = y.len() as f64;
    let sum = y.iter().sum::<f64>();
    let mean = if sum.is_finite() {
        sum / n
    } else {
        y.iter().map(|v| v / n).sum()
    };
    let s = y.iter().fold(0.0f64, |m, v| m.max((v - mean).abs()));
    let d = |v: &f64| (v - mean) / s;
    let m2 = y.iter().map(|v| d(v).powi(2)).sum::<f64>() / n;
    let m3 = y.iter().map(|v| d(v).powi(3)).sum::<f64>() / n;
    let m4 = y.iter().map(|v| d(v).powi(4)).sum::<f64>() / n;
    (mean, s * m2.sqrt(), m3 / m2.powf(1.5), m4 / (m2 * m2))
}

/// The frequency of the largest peak of the record's correlation-based spectrum.
fn dominant_frequency(y: &[f64], fs: f64) -> Result<f64, IdentError> {
    let lags = 256.min(y.len() / 2).max(2);
    let c = covssi::corr::estimate(&[y], &[0], lags);
    let mut best = (0.0, f64::MIN);
    let npts = 2048;
    for p in 1..npts {
        let f = fs / 2.0 * p as f64 / npts as f64;
        let w = 2.0 * std::f64::consts::PI * f / fs;
        let mut s = c.r[0][0];
        for (k, rk) in c.r.iter().enumerate().skip(1) {
            let win = 0.5 * (1.0 + (std::f64::consts::PI * k as f64 / lags as f64).cos());
            s += 2.0 * win * rk[0] * (w * k as f64).cos();
        }
        if s > best.1 {
            best = (f, s);
        }
    }
    Ok(best.0)
}

/// Step 1: centre, decimate, describe.
pub fn prepare(y: &[f64], fs: f64, opts: &IdentOptions) -> Result<Prepared, IdentError> {
    if y.len() < 64 {
        return Err(IdentError::TooShort {
            samples: y.len(),
            needed: 64,
        });
    }
    if !(fs.is_finite() && fs > 0.0) {
        return Err(IdentError::Ssi(covssi::SsiError::NonPositiveRate { fs }));
    }
    if let Some((index, &value)) = y.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(IdentError::Ssi(covssi::SsiError::NonFinite {
            channel: 0,
            index,
            value,
        }));
    }
    if y.iter().all(|v| *v == y[0]) {
        return Err(IdentError::Ssi(covssi::SsiError::ConstantChannel {
            channel: 0,
            value: y[0],
        }));
    }
    let (mean, sigma_x, _, _) = moments(y);
    // The correlations SSI works from are of the order of the variance: it must be a normal
    // double with room to spare (covssi's own range), or every later step reads garbage.
    let variance = sigma_x * sigma_x;
    if !(variance.is_finite() && variance >= covssi::MIN_CORRELATION) {
        return Err(IdentError::Ssi(covssi::SsiError::OutOfRange {
            value: variance,
        }));
    }
    let centred: Vec<f64> = y.iter().map(|v| v - mean).collect();
    let dominant_hz = dominant_frequency(&centred, fs)?;
    let r = ((fs / dominant_hz / opts.samples_per_period).floor() as usize).max(1);
    let yd = hyst_sim::resample::decimate(&centred, r);
    let (_, _, skewness, kurtosis) = moments(&yd);
    Ok(Prepared {
        y: yd,
        fs: fs / r as f64,
        decimation: r,
        mean,
        sigma_x,
        skewness,
        kurtosis,
        dominant_hz,
    })
}

/// Step 2: SSI-COV with lags covering `opts.periods` periods of the dominant mode.
pub fn run_ssi(p: &Prepared, opts: &IdentOptions) -> Result<SsiResult, IdentError> {
    // The paper sizes the Toeplitz matrix so that τ = i·Δt spans the periods (its lags then
    // reach twice that).
    let i = (opts.periods * p.fs / p.dominant_hz).ceil().max(2.0) as usize;
    let so = SsiOptions {
        block_rows: BlockRows::Count(i),
        max_order: Some(opts.max_order),
        criteria: opts.criteria,
        ..SsiOptions::default()
    };
    match covssi::identify(&[&p.y], p.fs, &so) {
        // A record with little noise (a simulated one, a free decay) can leave the Toeplitz
        // matrix of lower rank than the order asked for: every order it has is then used.
        Err(covssi::SsiError::OrderAboveRank { order, rank, .. }) if rank >= 2 => {
            let lower = SsiOptions {
                max_order: Some(rank),
                ..so
            };
            let mut res = covssi::identify(&[&p.y], p.fs, &lower)?;
            res.notes.push(format!(
                "the block Toeplitz matrix has rank {rank}, below the maximum order {order}: orders up to {rank} used"
            ));
            Ok(res)
        }
        other => Ok(other?),
    }
}

/// The poles the models are built from.
#[derive(Debug, Clone, PartialEq)]
pub struct SelectedPoles {
    /// The oscillating pair (Im > 0), rad/s: the mean of its cluster, or, when the record
    /// follows the stationary model, the pair refined by maximum likelihood together with
    /// the real pole (a note says so).
    pub pair: Complex64,
    /// Every pole of that cluster (one per model order).
    pub pair_cluster: Vec<Complex64>,
    /// The real pole, if one was found (rad/s): SSI's, or refined with the pair.
    pub real: Option<f64>,
    /// Whether the pair and the real pole are the refined ones (the record follows the
    /// stationary model).
    pub refined: bool,
    /// Viscous damping guess c (N s/m).
    pub c: f64,
    /// Where c came from.
    pub c_source: String,
    /// Remarks (fallbacks taken).
    pub notes: Vec<String>,
}

/// Step 3: choose the pair, the real pole and c.
pub fn select_poles(
    ssi: &SsiResult,
    p: &Prepared,
    opts: &IdentOptions,
) -> Result<SelectedPoles, IdentError> {
    let mut notes = Vec::new();
    let near = |f: f64| (f - p.dominant_hz).abs() / p.dominant_hz;
    let mode = ssi
        .modes
        .iter()
        .filter(|m| near(m.frequency_hz) < 0.3)
        .max_by(|a, b| {
            a.members
                .len()
                .cmp(&b.members.len())
                .then(near(b.frequency_hz).total_cmp(&near(a.frequency_hz)))
        })
        .ok_or(IdentError::NoStablePair {
            dominant_hz: p.dominant_hz,
        })?;
    let (ssi_real, real_candidates) = real_pole(ssi, &mut notes);
    let refined = check_support(mode, &real_candidates, p, &mut notes)?;
    let (pair, real, refined) = match refined {
        Some((pair, real)) => (pair, Some(real), true),
        None => (mode.lambda, ssi_real, false),
    };
    let pair_cluster: Vec<Complex64> = mode
        .members
        .iter()
        .filter_map(|&(order, idx)| {
            ssi.diagram
                .orders
                .iter()
                .find(|o| o.order == order)
                .map(|o| o.poles[idx].lambda)
        })
        .collect();
    let (c, c_source) = match opts.damping_guess {
        DampingGuess::Value(c) => (c, "given".to_string()),
        DampingGuess::LowDampingCluster | DampingGuess::ZenerSpectrum => {
            // Poles at least stable in frequency, within 10 % of the pair's frequency, damped
            // less than half as much as the pair.
            let f0 = mode.frequency_hz;
            let mut re: Vec<f64> = ssi
                .diagram
                .orders
                .iter()
                .flat_map(|o| o.poles.iter())
                .filter(|q| {
                    matches!(q.status, covssi::PoleStatus::Stable(s) if s != Stability::Real)
                        && (q.frequency_hz - f0).abs() < 0.1 * f0
                        && q.damping_ratio < 0.5 * mode.damping_ratio
                })
                .map(|q| q.lambda.re)
                .collect();
            if re.len() >= 3 {
                re.sort_by(f64::total_cmp);
                let med = re[re.len() / 2];
                (
                    -2.0 * opts.mass * med,
                    format!(
                        "low-damping cluster ({} poles, median Re λ = {med:.3})",
                        re.len()
                    ),
                )
            } else {
                notes.push("no low-damping cluster near the pair: c = 0".to_string());
                (0.0, "none found (c = 0)".to_string())
            }
        }
    };
    Ok(SelectedPoles {
        pair,
        pair_cluster,
        real,
        refined,
        c,
        c_source,
        notes,
    })
}

/// SSI's real pole (the largest stable real cluster, else the median of all stable real
/// poles when there are at least three), and the clusters the refinement is to test: SSI's,
/// or the median as a cluster of its own.
fn real_pole(ssi: &SsiResult, notes: &mut Vec<String>) -> (Option<f64>, Vec<RealPoleCluster>) {
    if let Some(r) = ssi.real_poles.iter().max_by_key(|r| r.members.len()) {
        return (Some(r.lambda), ssi.real_poles.clone());
    }
    let mut all: Vec<(f64, (usize, usize))> = ssi
        .diagram
        .orders
        .iter()
        .flat_map(|o| {
            o.poles
                .iter()
                .enumerate()
                .map(move |(i, q)| (o.order, i, q))
        })
        .filter(|(_, _, q)| q.status == covssi::PoleStatus::Stable(Stability::Real))
        .map(|(order, i, q)| (q.lambda.re, (order, i)))
        .collect();
    if all.len() >= 3 {
        all.sort_by(|a, b| a.0.total_cmp(&b.0));
        notes.push(format!(
            "no cluster of stable real poles; using the median of {} stable real poles",
            all.len()
        ));
        let median = all[all.len() / 2].0;
        let cluster = RealPoleCluster {
            lambda: median,
            lambda_std: 0.0,
            members: all.iter().map(|a| a.1).collect(),
        };
        (Some(median), vec![cluster])
    } else {
        notes.push(
            "no stable real pole found: the Zener and Bouc-Wen models fall back to the linear model"
                .to_string(),
        );
        (None, Vec::new())
    }
}

/// Whether the record supports the pair: a stabilization diagram can hold a stable cluster
/// that is a draw of the noise (white noise gives one now and then), and every model would
/// then be built on it. The pair is fitted to the whole record by maximum likelihood
/// ([`covssi::refine()`], one mode) and kept when removing it raises the negative
/// log-likelihood by at least the BIC penalty of a mode; otherwise it is an error when the
/// record follows the model without the pair (misfit within
/// [`covssi::refine::MISFIT_LIMIT`]). When it does not (a free decay, a record with little
/// noise: the stationary model does not apply), or the test cannot run (a record too short
/// for it), a note says so and the pair is kept.
///
/// When the pair is kept and the record follows its model, the pair is fitted once more
/// with the real-pole clusters `reals` ([`covssi::refine_with_real_poles`]); if the record
/// follows that model too and it keeps the pair and a real pole, their refined values are
/// returned (the real pole with the most evidence), to be used in place of SSI's. SSI sees
/// the record only through its correlations: on Zener records under white noise the
/// refined poles are several times closer (`tests/zener_real_pole.rs`). Records that do not
/// follow the model (a multisine's line spectrum) are not refitted.
fn check_support(
    mode: &covssi::Mode,
    reals: &[RealPoleCluster],
    p: &Prepared,
    notes: &mut Vec<String>,
) -> Result<Option<(Complex64, f64)>, IdentError> {
    let opts = covssi::RefineOptions {
        joint: false,
        ..covssi::RefineOptions::default()
    };
    let pair = std::slice::from_ref(mode);
    match covssi::refine(&[&p.y], p.fs, pair, &opts) {
        Ok(r) if r.modes.is_empty() => {
            let evidence = r.dropped.last().map_or(0.0, |d| d.evidence);
            if r.misfit <= covssi::refine::MISFIT_LIMIT {
                // The record follows a model without the pair: it shows no resonance.
                Err(IdentError::PairNotSupported {
                    frequency_hz: mode.frequency_hz,
                    evidence,
                    penalty: r.penalty,
                    misfit: r.misfit,
                })
            } else {
                // Nor does it follow the model without the pair (a free decay, a record with
                // little noise, a non-random excitation): the test says nothing.
                notes.push(format!(
                    "the pair's support by the record could not be tested: its evidence ({evidence:.1}) is below the penalty ({:.1}), but the record does not follow the stationary model without it either (misfit {:.3}); the pair is kept",
                    r.penalty, r.misfit
                ));
                Ok(None)
            }
        }
        Ok(r) if r.misfit <= covssi::refine::MISFIT_LIMIT && !reals.is_empty() => {
            let Ok(r) = covssi::refine_with_real_poles(&[&p.y], p.fs, pair, reals, &opts) else {
                return Ok(None);
            };
            let real = r
                .real_poles
                .iter()
                .max_by(|a, b| a.evidence.total_cmp(&b.evidence));
            match (r.modes.first(), real) {
                (Some(m), Some(q)) if r.misfit <= covssi::refine::MISFIT_LIMIT => {
                    notes.push(format!(
                        "pair and real pole refined by maximum likelihood on the record (misfit {:.3}): {:.3} (SSI {:.3}) and {:.3} rad/s",
                        r.misfit, m.lambda, mode.lambda, q.lambda
                    ));
                    Ok(Some((m.lambda, q.lambda)))
                }
                _ => Ok(None),
            }
        }
        Ok(_) => Ok(None),
        Err(e) => {
            notes.push(format!(
                "the pair's support by the record could not be tested: {e}"
            ));
            Ok(None)
        }
    }
}

/// The identified models.
#[derive(Debug, Clone, PartialEq)]
pub struct Models {
    /// Linear oscillator from the pair.
    pub linear: Oscillator,
    /// Zener oscillator, when a real pole was found and the mapping gives Ω > 0.
    pub zener: Option<Oscillator>,
    /// Bouc-Wen oscillator: the flatness fit when the excitation band is known and the fit
    /// succeeded, else the mapped one.
    pub bouc_wen: Option<Oscillator>,
    /// Bouc-Wen oscillator from the poles by the chosen [`Linearization`], when it succeeded.
    pub bouc_wen_mapped: Option<Oscillator>,
    /// Amplitude A used (m).
    pub amplitude: f64,
    /// Remarks.
    pub notes: Vec<String>,
}

/// Step 4: models from the poles.
pub fn build_models(
    sel: &SelectedPoles,
    p: &Prepared,
    opts: &IdentOptions,
) -> Result<Models, IdentError> {
    let m = opts.mass;
    if !(m.is_finite() && m > 0.0) {
        return Err(IdentError::NonPositiveMass { mass: m });
    }
    let linear = Oscillator::linear(m, -2.0 * m * sel.pair.re, m * sel.pair.norm_sqr());
    let amplitude = opts.amplitude.resolve(p.sigma_x)?;
    let mut notes = Vec::new();
    let (zener, bouc_wen) = match sel
        .real
        .map(|r| hyst_linearize::zener_from_poles(m, sel.c, sel.pair, r))
    {
        None => (None, None),
        Some(Err(e)) => {
            notes.push(format!("no Zener model: {e}"));
            (None, None)
        }
        Some(Ok(fit)) => {
            let bw = bouc_wen_from(&fit, sel, m, amplitude, opts.linearization, &mut notes);
            (
                Some(Oscillator::zener(m, sel.c, fit.k, fit.zener)),
                bw.map(|b| Oscillator::bouc_wen(m, sel.c, fit.k, b)),
            )
        }
    };
    Ok(Models {
        linear,
        zener,
        bouc_wen_mapped: bouc_wen,
        bouc_wen,
        amplitude,
        notes,
    })
}

/// The Bouc-Wen element from the identified Zener: α by eq. (37), then (βγ, βδ) by eq. (38)
/// or by exact inversion of the describing function (first order if that fails, noted).
fn bouc_wen_from(
    fit: &hyst_linearize::ZenerFit,
    sel: &SelectedPoles,
    m: f64,
    amplitude: f64,
    linearization: Linearization,
    notes: &mut Vec<String>,
) -> Option<BoucWen> {
    let w = sel.pair.norm();
    let alpha = hyst_linearize::paper::eq37_alpha(m, sel.c, fit.k, sel.pair.im);
    match linearization {
        Linearization::Paper => {
            let (bg, bd) = hyst_linearize::paper::eq38_beta(
                alpha,
                fit.zener.k_inf,
                fit.zener.omega,
                amplitude,
                w,
            );
            Some(BoucWen::from_products(alpha, bg, bd, 1.0))
        }
        Linearization::Harmonic => {
            let df = hyst_linearize::zener_at(&fit.zener, w, amplitude);
            match hyst_linearize::bouc_wen_exact(alpha, 1.0, &df) {
                Ok(b) => Some(b),
                Err(e) => {
                    notes.push(format!(
                        "exact describing-function inversion failed ({e}); first-order closed form used"
                    ));
                    hyst_linearize::bouc_wen_first_order(alpha, 1.0, &df).ok()
                }
            }
        }
    }
}

/// Everything the pipeline found.
#[derive(Debug, Clone, PartialEq)]
pub struct Identification {
    /// Step 1.
    pub prepared: Prepared,
    /// Step 2.
    pub ssi: SsiResult,
    /// Step 3 (with step 3b's pair, real pole and c when it held).
    pub poles: SelectedPoles,
    /// Step 3b, when it ran ([`DampingGuess::ZenerSpectrum`]): the Zener oscillator fitted to
    /// the record's spectrum; [`SelectedPoles::c_source`] says whether it was used.
    pub zener_spectrum: Option<zener_spectrum::ZenerSpectralFit>,
    /// Step 4.
    pub models: Models,
    /// Step 4b, when the excitation band is known: the flatness fit.
    pub flatness: Option<flatness::FlatnessFit>,
}

/// Above this aperiodicity ([`flatness::FlatnessFit::aperiodicity`]) the pipeline warns: the
/// benchmark's records sit near 0.02 (measurement noise); folded with a wrong period the
/// training record gives 2.8.
const APERIODIC: f64 = 0.1;
/// Above this spread of the implied input over the band (dB RMS) the pipeline warns: the
/// benchmark's fits end near 0.2 dB, the mapped starts near 2 dB.
const NOT_FLAT_DB: f64 = 1.0;

/// Step 4b: fit the Bouc-Wen model by flatness of its implied input over the excitation band
/// ([`flatness::fit`]), from the mapped Bouc-Wen model and from the linear one split evenly
/// into k and α; the flatter of the two wins.
pub fn fit_flatness(
    y: &[f64],
    fs: f64,
    models: &Models,
    band: &flatness::ExcitationBand,
) -> Result<flatness::FlatnessFit, IdentError> {
    // Both starts at once (rayon shares the caller's pool; no nested pools).
    let starts: Vec<Oscillator> = models
        .bouc_wen_mapped
        .into_iter()
        .chain([models.linear])
        .collect();
    flatness::fit(y, fs, band, &starts)
}

/// Run steps 1–4 on an output record `y` sampled at `fs`.
pub fn identify(y: &[f64], fs: f64, opts: &IdentOptions) -> Result<Identification, IdentError> {
    if !(opts.mass.is_finite() && opts.mass > 0.0) {
        return Err(IdentError::NonPositiveMass { mass: opts.mass });
    }
    let prepared = prepare(y, fs, opts)?;
    let ssi = run_ssi(&prepared, opts)?;
    let mut poles = select_poles(&ssi, &prepared, opts)?;
    let zener_spectrum = fit_zener_spectrum(y, fs, &prepared, &mut poles, opts);
    let mut models = build_models(&poles, &prepared, opts)?;
    let flatness = match &opts.excitation {
        None => None,
        Some(band) => match fit_flatness(y, fs, &models, band) {
            Ok(f) => {
                if let Some(a) = f.aperiodicity.filter(|&a| a > APERIODIC) {
                    models.notes.push(format!(
                        "the record's first and last periods of {} samples differ by {:.0} % of its RMS: is it periodic with that period, and in steady state?",
                        band.period,
                        100.0 * a
                    ));
                }
                if f.spread_db > NOT_FLAT_DB {
                    models.notes.push(format!(
                        "the fitted model's implied input still varies by {:.2} dB RMS over the band: check the band and the period, or the model class",
                        f.spread_db
                    ));
                }
                models.bouc_wen = Some(f.model);
                Some(f)
            }
            Err(e) => {
                models.notes.push(format!(
                    "flatness fit failed ({e}); the mapped Bouc-Wen model is kept"
                ));
                None
            }
        },
    };
    Ok(Identification {
        prepared,
        ssi,
        poles,
        zener_spectrum,
        models,
        flatness,
    })
}

/// Step 3b ([`DampingGuess::ZenerSpectrum`]): when the pair and the real pole were refined
/// (the record follows the stationary model), fit the Zener oscillator to the spectrum of
/// the record `y` (sampled at `fs`, undecimated) up to three times the pair's frequency (at
/// most fs/4), and take c, the pair and the real pole from it when it holds: misfit within
/// [`covssi::refine::MISFIT_LIMIT`], k > 0, and a most likely c not below 0 by more than
/// three standard errors (then c is held at 0; see [`zener_spectrum`]). Otherwise c stays
/// the low-damping cluster's and a note says why.
pub fn fit_zener_spectrum(
    y: &[f64],
    fs: f64,
    p: &Prepared,
    sel: &mut SelectedPoles,
    opts: &IdentOptions,
) -> Option<zener_spectrum::ZenerSpectralFit> {
    let real = sel.real.filter(|_| sel.refined)?;
    if opts.damping_guess != DampingGuess::ZenerSpectrum {
        return None;
    }
    let centred: Vec<f64> = y.iter().map(|v| v - p.mean).collect();
    // The band: three times the pair's frequency, and at most a quarter of the sampling rate.
    // The model's force is white at every frequency, so the record's spectrum holds the
    // power aliased from above the Nyquist frequency; a real force (band-limited, or behind an
    // anti-aliasing filter) lacks it near there, and where noise does not hide that the fit
    // is biased. At fs/4 the aliased part is (1/3)⁴ ≈ 1 % of the response's.
    let f_max = (3.0 * sel.pair.norm() / (2.0 * std::f64::consts::PI)).min(fs / 4.0);
    match zener_spectrum::fit(&centred, fs, opts.mass, sel.pair, real, f_max) {
        Ok(f) => {
            let why = if f.misfit > covssi::refine::MISFIT_LIMIT {
                Some(format!(
                    "the record does not follow it (misfit {:.3})",
                    f.misfit
                ))
            } else if let Some([c, se]) = f.unconstrained_c.filter(|[c, se]| *c < -3.0 * se) {
                Some(format!(
                    "its most likely c is {c:.3} ± {se:.3} N s/m, below 0 by more than three standard errors (is the force white over the band?)"
                ))
            } else if f.k <= 0.0 {
                Some(format!("it gives k = {:.1} N/m", f.k))
            } else {
                None
            };
            match why {
                Some(why) => sel.notes.push(format!(
                    "Zener spectral fit not used: {why}; c from the {}",
                    sel.c_source
                )),
                None => {
                    sel.pair = f.pair;
                    sel.real = Some(f.real);
                    sel.c = f.c;
                    sel.c_source = match f.unconstrained_c {
                        None => format!(
                            "Zener spectral fit (white force assumed): c = {:.3} ± {:.3} N s/m",
                            f.c, f.se[0]
                        ),
                        Some([c, se]) => format!(
                            "Zener spectral fit (white force assumed): c held at its bound 0, the most likely c being {c:.3} ± {se:.3} N s/m"
                        ),
                    };
                }
            }
            Some(f)
        }
        Err(e) => {
            sel.notes.push(format!(
                "Zener spectral fit failed ({e}); c from the {}",
                sel.c_source
            ));
            None
        }
    }
}

/// A model's error against a measured output.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Validation {
    /// ε of eq. (39): RMS error divided by the range of the measured output (a fraction).
    pub epsilon: f64,
    /// RMS error in the output's units.
    pub rms: f64,
}

/// ε and RMS of `yhat` against `y`.
pub fn epsilon(yhat: &[f64], y: &[f64]) -> Validation {
    let n = y.len().min(yhat.len()).max(1) as f64;
    let rms = (yhat
        .iter()
        .zip(y)
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f64>()
        / n)
        .sqrt();
    let (lo, hi) = y
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
            (l.min(*v), h.max(*v))
        });
    Validation {
        epsilon: rms / (hi - lo),
        rms,
    }
}

/// The response of `model` to the input `u` (RK4, 20 sub-steps): for a `periodic` record one
/// steady-state period, otherwise from rest. Between samples the input is taken as
/// band-limited, as a measured or designed excitation is: exactly for a periodic record, by a
/// windowed sinc otherwise ([`hyst_sim::Input::BandLimited`]; linear interpolation would
/// misstate the force by about 1 %).
pub fn simulate_model(
    model: &Oscillator,
    u: &[f64],
    fs: f64,
    periodic: bool,
) -> Result<Vec<f64>, IdentError> {
    let opts = SimOptions {
        decimation: Decimation::Subsample,
        ..SimOptions::default()
    };
    Ok(if periodic {
        hyst_sim::steady_state_period(model, u, fs, &opts, 1e-9, 200)?.y
    } else {
        hyst_sim::simulate(model, Input::BandLimited(u), fs, u.len(), &opts)?
    })
}

/// Step 5: simulate `model` with input `u` ([`simulate_model`]) and compare with `y`.
pub fn validate(
    model: &Oscillator,
    u: &[f64],
    y: &[f64],
    fs: f64,
    periodic: bool,
) -> Result<Validation, IdentError> {
    if u.len() != y.len() {
        return Err(IdentError::LengthMismatch {
            input: u.len(),
            output: y.len(),
        });
    }
    Ok(epsilon(&simulate_model(model, u, fs, periodic)?, y))
}

/// One-sided power spectral density by Welch's method (Hann window, `segment` samples, 50 %
/// overlap): (frequencies in Hz, PSD in units²/Hz).
pub fn welch_psd(y: &[f64], fs: f64, segment: usize) -> (Vec<f64>, Vec<f64>) {
    let seg = segment.min(y.len()).max(2);
    let win: Vec<f64> = (0..seg)
        .map(|i| 0.5 - 0.5 * (2.0 * std::f64::consts::PI * i as f64 / seg as f64).cos())
        .collect();
    let u: f64 = win.iter().map(|w| w * w).sum();
    let bins = seg / 2 + 1;
    let mut acc = vec![0.0; bins];
    let mut count = 0usize;
    let mut start = 0;
    while start + seg <= y.len() {
        let windowed: Vec<f64> = y[start..start + seg]
            .iter()
            .zip(&win)
            .map(|(v, w)| v * w)
            .collect();
        for (a, x) in acc.iter_mut().zip(fft::rfft(&windowed)) {
            *a += x.norm_sqr();
        }
        count += 1;
        start += seg / 2;
    }
    let scale = 2.0 / (fs * u * count.max(1) as f64);
    (
        (0..bins).map(|b| b as f64 * fs / seg as f64).collect(),
        acc.iter().map(|v| v * scale).collect(),
    )
}

/// Gauss–Newton matrix JᵀJ and gradient Jᵀr from the Jacobian's columns and the residuals.
pub(crate) fn normal_equations(cols: &[Vec<f64>], r: &[f64]) -> (Vec<Vec<f64>>, Vec<f64>) {
    let np = cols.len();
    let mut a = vec![vec![0.0; np]; np];
    let mut g = vec![0.0; np];
    for i in 0..np {
        g[i] = cols[i].iter().zip(r).map(|(p, q)| p * q).sum();
        for j in i..np {
            let v: f64 = cols[i].iter().zip(&cols[j]).map(|(p, q)| p * q).sum();
            a[i][j] = v;
            a[j][i] = v;
        }
    }
    (a, g)
}

/// One Levenberg–Marquardt step on the normal equations `a·step = g` (Gauss–Newton matrix and
/// gradient of ½‖r‖²): the diagonal is damped by `1 + λ` and `λ` raised tenfold until `try_step`
/// accepts the step (the caller moves to `x − step` when its cost is lower and returns
/// `Some(significant)`, else `None`); on acceptance λ shrinks to 0.3 λ. Returns whether an
/// accepted step lowered the cost significantly; `false` also when λ passes 1e10.
pub(crate) fn lm_step(
    a: &[Vec<f64>],
    g: &[f64],
    lambda: &mut f64,
    mut try_step: impl FnMut(&[f64]) -> Option<bool>,
) -> bool {
    while *lambda < 1e10 {
        let mut m = a.to_vec();
        for (i, row) in m.iter_mut().enumerate() {
            row[i] = row[i] * (1.0 + *lambda) + 1e-300;
        }
        if let Some(step) = solve(m, g.to_vec())
            && let Some(significant) = try_step(&step)
        {
            *lambda = (*lambda * 0.3).max(1e-12);
            return significant;
        }
        *lambda *= 10.0;
    }
    false
}

/// Solve the small dense system `a x = b` by Gaussian elimination with partial pivoting;
/// `None` if it is singular or the result is not finite.
pub(crate) fn solve(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Option<Vec<f64>> {
    let n = b.len();
    for col in 0..n {
        let piv = (col..n).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        a.swap(col, piv);
        b.swap(col, piv);
        if a[col][col] == 0.0 || !a[col][col].is_finite() {
            return None;
        }
        for row in col + 1..n {
            let f = a[row][col] / a[col][col];
            let pivot_row = a[col].clone();
            for (k, v) in a[row].iter_mut().enumerate().skip(col) {
                *v -= f * pivot_row[k];
            }
            b[row] -= f * b[col];
        }
    }
    for col in (0..n).rev() {
        let s: f64 = (col + 1..n).map(|k| a[col][k] * b[k]).sum();
        b[col] = (b[col] - s) / a[col][col];
    }
    b.iter().all(|v| v.is_finite()).then_some(b)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Welch's PSD by FFT against the defining sums, and its level: a white sequence of
    /// variance 1 at 100 Hz has a one-sided density of 2/100 per Hz.
    #[test]
    fn welch_psd_is_the_windowed_dft() {
        let y = hyst_sim::excitation::white_noise(3000, 1.0, 5).unwrap();
        let (f, s) = welch_psd(&y, 100.0, 256);
        assert_eq!(f.len(), 129);
        let win: Vec<f64> = (0..256)
            .map(|i| 0.5 - 0.5 * (2.0 * std::f64::consts::PI * i as f64 / 256.0).cos())
            .collect();
        let u: f64 = win.iter().map(|w| w * w).sum();
        for b in [0usize, 1, 37, 128] {
            let w = 2.0 * std::f64::consts::PI * b as f64 / 256.0;
            let (mut total, mut count, mut start) = (0.0, 0, 0);
            while start + 256 <= y.len() {
                let (mut re, mut im) = (0.0, 0.0);
                for k in 0..256 {
                    re += y[start + k] * win[k] * (w * k as f64).cos();
                    im -= y[start + k] * win[k] * (w * k as f64).sin();
                }
                total += re * re + im * im;
                count += 1;
                start += 128;
            }
            let direct = 2.0 * total / (100.0 * u * count as f64);
            // The FFT against the sums: rounding, 1e-13 of the value or so.
            approx::assert_relative_eq!(s[b], direct, max_relative = 1e-10);
        }
        // 22 half-overlapping segments × 127 bins (about 1500 independent exponential values
        // after the overlap): the mean's standard error is about 3 %, and 10 % is three of them.
        let mean = s[1..128].iter().sum::<f64>() / 127.0;
        approx::assert_relative_eq!(mean, 0.02, max_relative = 0.1);
    }
}
