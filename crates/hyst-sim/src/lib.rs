//! Fixed-step simulation of the oscillators of [`hyst_model`], excitations and resampling.
//!
//! One job: turn an input force record into the displacement output, the way the Bouc-Wen
//! benchmark made its records, and fast enough for long Monte-Carlo studies.
//!
//! * [`Integrator::Rk4`]: classic fourth-order Runge–Kutta with `oversample` sub-steps per
//!   sample ($h = 1/(r f_s)$); the input at the sub-step ends and midpoints comes from the
//!   chosen [`Input`] interpolation. The inner loop allocates nothing.
//! * [`Integrator::Trapezoidal`]: the benchmark's own integrator, Newmark with
//!   $a = \tfrac12, b = \tfrac14$ on $(x, \dot x)$ and the trapezoid on $z$ — together the
//!   implicit trapezoidal rule $s_{n+1} = s_n + \tfrac h2\,(f(s_n,u_n) + f(s_{n+1},u_{n+1}))$,
//!   solved by Newton's method with the analytic Jacobian.
//!
//! The fine-rate output goes back to the sample rate by plain subsampling or by MATLAB's
//! FIR decimation ([`resample::decimate`]). A state that becomes non-finite or larger than
//! [`SimOptions::max_abs_state`] stops the run with [`SimError::Diverged`] naming the sample.

#![warn(missing_docs)]

use hyst_model::{ModelError, Oscillator, State};

pub mod batch;
pub mod building;
mod chain;
pub mod corpus;
pub mod deck;
mod drift;
pub mod excitation;
mod kernel;

pub use batch::simulate_many;
pub use drift::simulate_drifting;
mod record;
pub use record::{
    InputKind, STEADY_STATE_MAX_PERIODS, STEADY_STATE_TOLERANCE, SensorNoise, WhiteForceRecord,
    response,
};
pub mod resample;

/// A field's value as a message shows it: a count as an integer, anything else as Rust's
/// shortest round trip (`1e300`, not three hundred digits).
fn shown(value: f64) -> String {
    if value.fract() == 0.0 && value.abs() < 1e15 {
        format!("{value:.0}")
    } else {
        format!("{value:?}")
    }
}

/// Errors of simulation and signal generation.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SimError {
    /// The model's parameters are invalid.
    #[error("invalid model: {0}")]
    Model(#[from] ModelError),
    /// The sampling rate is not a positive finite number.
    #[error("sampling rate must be > 0, got {fs}")]
    NonPositiveRate {
        /// The offending rate (Hz).
        fs: f64,
    },
    /// Zero sub-steps per sample.
    #[error("oversampling factor must be at least 1, got {factor}")]
    ZeroOversample {
        /// The offending factor.
        factor: usize,
    },
    /// More sub-steps per sample than [`MAX_OVERSAMPLE`].
    #[error(
        "oversampling factor {factor} is more than {max} sub-steps per sample: beyond them RK4's error is below rounding, and the run only grows"
    )]
    OversampleTooLarge {
        /// The offending factor.
        factor: usize,
        /// [`MAX_OVERSAMPLE`].
        max: usize,
    },
    /// The input record is empty.
    #[error("the input record is empty")]
    EmptyInput,
    /// The input holds a NaN or infinite value.
    #[error("input sample {index} is not finite: {value}")]
    NonFiniteInput {
        /// 0-based sample index.
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// More output samples were asked than a sampled (non-periodic) input holds.
    #[error("asked for {requested} samples but the input has only {available}")]
    InputTooShort {
        /// Samples requested.
        requested: usize,
        /// Samples available.
        available: usize,
    },
    /// A function asks for an input it cannot take.
    #[error(
        "{what} is not an input this simulation takes (it needs a periodic or band-limited record)"
    )]
    UnsupportedInput {
        /// The kind of input given.
        what: &'static str,
    },
    /// The FIR decimation stages do not multiply to the oversampling factor.
    #[error("decimation stages multiply to {product}, but the oversampling factor is {oversample}")]
    DecimationMismatch {
        /// Product of the stages.
        product: usize,
        /// Oversampling factor.
        oversample: usize,
    },
    /// The state became non-finite or exceeded the allowed magnitude.
    #[error(
        "simulation diverged at sample {sample} (t = {time} s): state component {component} = {value}"
    )]
    Diverged {
        /// 0-based output sample at which the state was found bad.
        sample: usize,
        /// Its time (s).
        time: f64,
        /// Index of the state component (0 = x, 1 = ẋ, 2 = z, 3 = x₂, 4 = ẋ₂).
        component: usize,
        /// The bad value.
        value: f64,
    },
    /// Newton's method did not converge in the implicit trapezoidal step.
    #[error("Newton iteration did not converge at sample {sample} (residual {residual})")]
    NewtonFailed {
        /// 0-based output sample.
        sample: usize,
        /// Final residual norm.
        residual: f64,
    },
    /// A signal parameter is invalid.
    #[error("invalid signal parameter `{what}`: {value}")]
    InvalidSignal {
        /// Which parameter.
        what: &'static str,
        /// The offending value.
        value: f64,
    },
    /// A building's field holds a value no building has.
    #[error("building: `{field}` = {}: {why}", shown(*value))]
    InvalidBuilding {
        /// The field, as its document names it (`hysteresis.storey`, `masses[2]`).
        field: String,
        /// Its value.
        value: f64,
        /// What it must be.
        why: &'static str,
    },
    /// More samples were asked for than memory can hold.
    #[error("{samples} samples do not fit in memory")]
    TooLong {
        /// Samples asked for.
        samples: usize,
    },
    /// A multisine's band holds no DFT bin of its period below the Nyquist frequency.
    #[error(
        "no DFT bin of a {period}-sample period at {fs} Hz (spacing {} Hz) lies in the band {low_hz}–{high_hz} Hz below the Nyquist frequency {} Hz",
        fs / *period as f64,
        fs / 2.0
    )]
    EmptyBand {
        /// Lower edge (Hz).
        low_hz: f64,
        /// Upper edge (Hz).
        high_hz: f64,
        /// Sampling rate (Hz).
        fs: f64,
        /// Samples per period.
        period: usize,
    },
    /// The periodic steady state was not reached.
    #[error("no periodic steady state after {periods} periods (change between periods {change})")]
    NoSteadyState {
        /// Periods simulated.
        periods: usize,
        /// Relative RMS change between the last two periods.
        change: f64,
    },
}

/// Time-stepping scheme.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum Integrator {
    /// Classic explicit fourth-order Runge–Kutta.
    #[default]
    Rk4,
    /// Implicit trapezoidal rule (the benchmark's Newmark a = ½, b = ¼), Newton-solved.
    Trapezoidal,
}

/// How the fine-rate output returns to the sampling rate.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum Decimation {
    /// Keep the state at every sample instant.
    #[default]
    Subsample,
    /// MATLAB `decimate(·, r, 'fir')` stage by stage; the stages multiply to the oversampling
    /// factor (the benchmark: `[2, 2, 5]` for multisines, `[20]` for the sweep).
    Fir(Vec<usize>),
}

/// The most sub-steps per sample a simulation takes. RK4's local error goes as (ωh)⁵: for
/// the highest frequency a record resolves (Nyquist, ωh = π per sample), 4096 sub-steps give
/// (π/4096)⁵ ≈ 3·10⁻¹⁶, below double rounding; more add rounding error and time (and a
/// band-limited input is held at 2 points per sub-step), never accuracy.
pub const MAX_OVERSAMPLE: usize = 4096;

/// Options of a simulation.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
pub struct SimOptions {
    /// Sub-steps per sample (1 to [`MAX_OVERSAMPLE`]).
    pub oversample: usize,
    /// Integration scheme.
    pub integrator: Integrator,
    /// Return to the sampling rate.
    pub decimation: Decimation,
    /// Largest magnitude any state component may reach before the run is declared diverged.
    pub max_abs_state: f64,
}

impl Default for SimOptions {
    fn default() -> Self {
        SimOptions {
            oversample: 20,
            integrator: Integrator::Rk4,
            decimation: Decimation::Subsample,
            max_abs_state: 1e12,
        }
    }
}

/// The input force, and how it is known between samples.
#[derive(Clone, Copy)]
pub enum Input<'a> {
    /// Samples at the sampling rate, linearly interpolated in between.
    Sampled(&'a [f64]),
    /// Samples of a band-limited record (a measured force behind an anti-aliasing filter),
    /// interpolated in between by a windowed sinc ([`resample::interpolate_band_limited`]).
    BandLimited(&'a [f64]),
    /// One period of a periodic, band-limited signal at the sampling rate, repeated as often
    /// as needed and interpolated exactly (DFT zero-padding).
    Periodic(&'a [f64]),
    /// The force as a function of time (s), evaluated at every sub-step.
    Function(&'a (dyn Fn(f64) -> f64 + Sync)),
    /// A band-limited record already interpolated to `2·oversample` points per sample
    /// (its samples every `2·oversample`-th, as [`resample::interpolate_band_limited`]
    /// gives): the RK4 stages read it directly. For many simulations of one record, which
    /// [`Input::BandLimited`] would interpolate again each time.
    Interpolated {
        /// The fine samples; sample k of the record is `samples[k · per_sample]`.
        samples: &'a [f64],
        /// Fine points per sample: twice the oversampling factor.
        per_sample: usize,
    },
}

impl std::fmt::Debug for Input<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Input::Sampled(u) => write!(f, "Sampled({} samples)", u.len()),
            Input::BandLimited(u) => write!(f, "BandLimited({} samples)", u.len()),
            Input::Periodic(u) => write!(f, "Periodic({} samples)", u.len()),
            Input::Function(_) => write!(f, "Function"),
            Input::Interpolated {
                samples,
                per_sample,
            } => write!(
                f,
                "Interpolated({} points, {per_sample} a sample)",
                samples.len()
            ),
        }
    }
}

/// A sampled input record that is valid and holds the `n_samples` the run needs.
fn check_length(u: &[f64], n_samples: usize) -> Result<(), SimError> {
    check_record(u)?;
    if u.len() < n_samples {
        return Err(SimError::InputTooShort {
            requested: n_samples,
            available: u.len(),
        });
    }
    Ok(())
}

/// An interpolated input ([`Input::Interpolated`]) whose points match `r` sub-steps and
/// cover `n_samples` samples.
fn check_interpolated(
    samples: &[f64],
    per_sample: usize,
    r: usize,
    n_samples: usize,
) -> Result<(), SimError> {
    if per_sample != 2 * r {
        return Err(SimError::UnsupportedInput {
            what: "an interpolated record whose points per sample are not twice the oversampling",
        });
    }
    check_length(samples, (n_samples - 1) * per_sample + 1)
}

fn check_record(u: &[f64]) -> Result<(), SimError> {
    if u.is_empty() {
        return Err(SimError::EmptyInput);
    }
    if let Some((index, &value)) = u.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(SimError::NonFiniteInput { index, value });
    }
    Ok(())
}

/// The sub-steps per sample decimation `stages` make: their product, or `usize::MAX` past
/// it (past [`MAX_OVERSAMPLE`] too).
fn stages_product(stages: &[usize]) -> usize {
    stages
        .iter()
        .try_fold(1usize, |p, &s| p.checked_mul(s))
        .unwrap_or(usize::MAX)
}

/// Sub-steps per sample: 1 to [`MAX_OVERSAMPLE`].
fn check_oversample(factor: usize) -> Result<(), SimError> {
    if factor == 0 {
        return Err(SimError::ZeroOversample { factor });
    }
    if factor > MAX_OVERSAMPLE {
        return Err(SimError::OversampleTooLarge {
            factor,
            max: MAX_OVERSAMPLE,
        });
    }
    Ok(())
}

fn check_common(model: &Oscillator, fs: f64, opts: &SimOptions) -> Result<(), SimError> {
    model.validate()?;
    if !(fs.is_finite() && fs > 0.0) {
        return Err(SimError::NonPositiveRate { fs });
    }
    check_oversample(opts.oversample)?;
    if let Decimation::Fir(stages) = &opts.decimation {
        let product = stages_product(stages);
        if product != opts.oversample || stages.contains(&0) {
            return Err(SimError::DecimationMismatch {
                product,
                oversample: opts.oversample,
            });
        }
    }
    Ok(())
}

/// Where the driver writes outputs: every sample, or every fine step.
struct Sink<'a> {
    out: &'a mut Vec<f64>,
    fine: bool,
}

/// Fixed parameters of one integration run.
struct Run {
    n_intervals: usize,
    r: usize,
    h: f64,
    max_abs: f64,
    fs: f64,
}

impl Run {
    /// The divergence check after each sample interval `k`.
    #[inline(always)]
    fn check(&self, k: usize, s: &[f64]) -> Result<(), SimError> {
        if let Some((component, &value)) = s
            .iter()
            .enumerate()
            .find(|(_, v)| !v.is_finite() || v.abs() > self.max_abs)
        {
            let sample = k + 1;
            return Err(SimError::Diverged {
                sample,
                time: sample as f64 / self.fs,
                component,
                value,
            });
        }
        Ok(())
    }
}

/// Integrate `run.n_intervals` sample intervals of `run.r` sub-steps each from state `s`.
/// `input(k, i)` gives (u at start, u at midpoint, u at end) of sub-step `i` of interval `k`.
fn drive<F>(
    model: &Oscillator,
    s: State,
    integrator: Integrator,
    run: &Run,
    mut input: F,
    sink: &mut Sink<'_>,
) -> Result<State, SimError>
where
    F: FnMut(usize, usize) -> (f64, f64, f64),
{
    use kernel::Choice;
    match integrator {
        Integrator::Trapezoidal => drive_trapezoidal(model, s, run, &mut input, sink),
        Integrator::Rk4 => match kernel::choose(model) {
            Choice::Linear(k) => drive_rk4(&k, s, run, &mut input, sink),
            Choice::BoucWen1(k) => drive_rk4(&k, s, run, &mut input, sink),
            Choice::Zener(k) => drive_rk4(&k, s, run, &mut input, sink),
            Choice::Static(k) => drive_rk4(&k, s, run, &mut input, sink),
            Choice::WithMass(k) => drive_rk4(&k, s, run, &mut input, sink),
        },
    }
}

#[inline(always)]
fn drive_rk4<const N: usize, K, F>(
    kern: &K,
    s0: State,
    run: &Run,
    input: &mut F,
    sink: &mut Sink<'_>,
) -> Result<State, SimError>
where
    K: kernel::Kernel<N>,
    F: FnMut(usize, usize) -> (f64, f64, f64),
{
    let mut s = K::load(&s0);
    let rk4 = kernel::Rk4::new(kern, run.h);
    // The output is written by index into a buffer sized up front: no call (a `push` that
    // might grow the vector) in the loop, so the state and the kernel's constants can stay
    // in registers across sub-steps instead of being saved around a possible call.
    let start = sink.out.len();
    let per = if sink.fine { run.r } else { 1 };
    sink.out.resize(start + run.n_intervals * per, 0.0);
    let out = &mut sink.out[start..];
    for k in 0..run.n_intervals {
        if sink.fine {
            let row = &mut out[k * per..(k + 1) * per];
            for (i, o) in row.iter_mut().enumerate() {
                let (u0, um, u1) = input(k, i);
                s = rk4.step(&s, u0, um, u1);
                *o = s[0];
            }
        } else {
            for i in 0..run.r {
                let (u0, um, u1) = input(k, i);
                s = rk4.step(&s, u0, um, u1);
            }
            out[k] = s[0];
        }
        run.check(k, &s)?;
    }
    Ok(K::store(&s))
}

fn drive_trapezoidal<F>(
    model: &Oscillator,
    mut s: State,
    run: &Run,
    input: &mut F,
    sink: &mut Sink<'_>,
) -> Result<State, SimError>
where
    F: FnMut(usize, usize) -> (f64, f64, f64),
{
    for k in 0..run.n_intervals {
        for i in 0..run.r {
            let (u0, _, u1) = input(k, i);
            s = trapezoidal_step(model, &s, u0, u1, run.h).map_err(|residual| {
                SimError::NewtonFailed {
                    sample: k + 1,
                    residual,
                }
            })?;
            if sink.fine {
                sink.out.push(s[0]);
            }
        }
        run.check(k, s.as_slice())?;
        if !sink.fine {
            sink.out.push(s[0]);
        }
    }
    Ok(s)
}

/// One implicit trapezoidal step, Newton-solved. Returns the residual norm on failure.
fn trapezoidal_step(model: &Oscillator, s: &State, u0: f64, u1: f64, h: f64) -> Result<State, f64> {
    let f0 = model.derivative(s, u0);
    let mut g = s + f0 * h;
    let id = hyst_model::Jacobian::identity();
    let mut last = f64::INFINITY;
    for _ in 0..60 {
        let res = g - s - (f0 + model.derivative(&g, u1)) * (0.5 * h);
        let j = id - model.jacobian(&g) * (0.5 * h);
        let delta = match j.lu().solve(&res) {
            Some(d) => d,
            None => return Err(res.norm()),
        };
        g -= delta;
        let converged = delta
            .iter()
            .zip(g.iter().zip(s.iter()))
            .all(|(d, (a, b))| d.abs() <= 1e-15 * a.abs().max(b.abs()) + 1e-300);
        last = res.norm();
        if converged {
            return Ok(g);
        }
    }
    // Accept a step whose update has stalled at rounding level (non-smooth |ẋ| near 0).
    let res = g - s - (f0 + model.derivative(&g, u1)) * (0.5 * h);
    let scale = g.norm().max(s.norm());
    if res.norm() <= 1e-13 * scale {
        Ok(g)
    } else {
        Err(last)
    }
}

/// Simulate `n_samples` output samples (at `fs`) from the zero state, driven by `input`.
///
/// Output sample `k` is $x$ at $t = k/f_s$ (sample 0 is the initial state) after the chosen
/// decimation. A [`Input::Sampled`] or [`Input::BandLimited`] record must hold at least
/// `n_samples` samples.
pub fn simulate(
    model: &Oscillator,
    input: Input<'_>,
    fs: f64,
    n_samples: usize,
    opts: &SimOptions,
) -> Result<Vec<f64>, SimError> {
    simulate_from(model, State::zeros(), input, fs, n_samples, opts).map(|(y, _)| y)
}

/// As [`simulate`] but from the given initial state; also returns the final state. A
/// measurement chain ([`hyst_model::MeasurementChain`]) holds the initial displacement
/// before t = 0 (exact from rest); its own state is not part of the returned one.
pub fn simulate_from(
    model: &Oscillator,
    s0: State,
    input: Input<'_>,
    fs: f64,
    n_samples: usize,
    opts: &SimOptions,
) -> Result<(Vec<f64>, State), SimError> {
    check_common(model, fs, opts)?;
    if n_samples == 0 {
        return Ok((Vec::new(), s0));
    }
    let r = opts.oversample;
    let h = 1.0 / (fs * r as f64);
    let chain = chain::of(model);
    let fine = matches!(opts.decimation, Decimation::Fir(_)) || chain.is_some();
    let mut out = Vec::with_capacity(if fine {
        (n_samples - 1) * r + 1
    } else {
        n_samples
    });
    out.push(s0[0]);
    let mut sink = Sink {
        out: &mut out,
        fine,
    };
    let run = Run {
        n_intervals: n_samples - 1,
        r,
        h,
        max_abs: opts.max_abs_state,
        fs,
    };
    let s_end = drive_input(
        model,
        s0,
        opts.integrator,
        &run,
        input,
        n_samples,
        &mut sink,
    )?;
    if let Some(c) = &chain {
        out = chain::apply(&out, h, c);
    }
    let y = match &opts.decimation {
        Decimation::Subsample if fine => out.into_iter().step_by(r).collect(),
        Decimation::Subsample => out,
        Decimation::Fir(stages) => resample::decimate_stages(&out, stages),
    };
    Ok((y, s_end))
}

/// Integrate over the run's intervals with the input `input` known at each sub-step's
/// start, middle and end as its kind says; returns the final state.
fn drive_input(
    model: &Oscillator,
    s0: State,
    integ: Integrator,
    run: &Run,
    input: Input<'_>,
    n_samples: usize,
    sink: &mut Sink<'_>,
) -> Result<State, SimError> {
    let (r, h, fs) = (run.r, run.h, run.fs);
    let run = &run;
    Ok(match input {
        Input::Sampled(u) => {
            check_length(u, n_samples)?;
            let inv_r = 1.0 / r as f64;
            drive(
                model,
                s0,
                integ,
                run,
                |k, i| {
                    let (a, b) = (u[k], u[k + 1]);
                    let d = b - a;
                    let t0 = i as f64 * inv_r;
                    (a + d * t0, a + d * (t0 + 0.5 * inv_r), a + d * (t0 + inv_r))
                },
                sink,
            )?
        }
        Input::BandLimited(u) => {
            check_length(u, n_samples)?;
            // Samples past the last needed still shape the interpolation near it.
            let used = &u[..(n_samples + resample::SINC_HALF_TAPS).min(u.len())];
            let fine_u = resample::interpolate_band_limited(used, 2 * r);
            drive(
                model,
                s0,
                integ,
                run,
                |k, i| {
                    let base = k * 2 * r + 2 * i;
                    (fine_u[base], fine_u[base + 1], fine_u[base + 2])
                },
                sink,
            )?
        }
        Input::Periodic(p) => {
            check_record(p)?;
            let fine_u = resample::upsample_periodic(p, 2 * r);
            let len = fine_u.len();
            let per = 2 * r;
            drive(
                model,
                s0,
                integ,
                run,
                |k, i| {
                    let base = (k % p.len()) * per + 2 * i;
                    let end = if base + 2 == len { 0 } else { base + 2 };
                    (fine_u[base], fine_u[base + 1], fine_u[end])
                },
                sink,
            )?
        }
        Input::Interpolated {
            samples,
            per_sample,
        } => {
            check_interpolated(samples, per_sample, r, n_samples)?;
            drive(
                model,
                s0,
                integ,
                run,
                |k, i| {
                    let base = k * per_sample + 2 * i;
                    (samples[base], samples[base + 1], samples[base + 2])
                },
                sink,
            )?
        }
        Input::Function(f) => {
            let dt = 1.0 / fs;
            drive(
                model,
                s0,
                integ,
                run,
                |k, i| {
                    let t0 = k as f64 * dt + i as f64 * h;
                    (f(t0), f(t0 + 0.5 * h), f(t0 + h))
                },
                sink,
            )?
        }
    })
}

/// One period of the periodic steady-state response to one period of a periodic input.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SteadyState {
    /// The output over one period (same length as the input period).
    pub y: Vec<f64>,
    /// Periods simulated before the change between successive periods fell under the tolerance.
    pub periods: usize,
    /// Relative RMS change between the last two simulated periods.
    pub change: f64,
}

/// Simulate the periodic repetition of `period` from rest until two successive periods of the
/// output differ by less than `tol` (relative RMS), at most `max_periods` periods, and return
/// one steady-state period.
///
/// With FIR decimation the whole run is decimated at once (the ends mirrored, as MATLAB does)
/// and the second-to-last period is returned, so that neither end of it sees a mirrored sample.
pub fn steady_state_period(
    model: &Oscillator,
    period: &[f64],
    fs: f64,
    opts: &SimOptions,
    tol: f64,
    max_periods: usize,
) -> Result<SteadyState, SimError> {
    check_common(model, fs, opts)?;
    check_record(period)?;
    let n = period.len();
    let sub = SimOptions {
        decimation: Decimation::Subsample,
        ..opts.clone()
    };
    // Phase 1: find how many periods it takes (subsampled output, periods chained).
    let mut s = State::zeros();
    let mut prev: Option<Vec<f64>> = None;
    let mut periods = 0;
    let mut change = f64::INFINITY;
    while periods < max_periods.max(2) {
        let (y, s_end) = simulate_from(model, s, Input::Periodic(period), fs, n + 1, &sub)?;
        s = s_end;
        periods += 1;
        let cur = y[..n].to_vec();
        if let Some(p) = &prev {
            let num: f64 = cur.iter().zip(p).map(|(a, b)| (a - b).powi(2)).sum();
            let den: f64 = cur.iter().map(|a| a * a).sum();
            change = (num / den.max(f64::MIN_POSITIVE)).sqrt();
            if change <= tol {
                break;
            }
        }
        prev = Some(cur);
    }
    if change > tol {
        return Err(SimError::NoSteadyState { periods, change });
    }
    // A measurement chain's memory reaches into the previous period: the last period of a
    // run over all of them, as for the FIR decimation.
    match &opts.decimation {
        Decimation::Subsample if chain::of(model).is_none() => Ok(SteadyState {
            y: prev.unwrap_or_default(),
            periods,
            change,
        }),
        _ => {
            // Phase 2: the full-rate run over periods+1 periods, decimated as a whole.
            let total = (periods + 1) * n;
            let y = simulate(model, Input::Periodic(period), fs, total, opts)?;
            let start = (periods - 1) * n;
            Ok(SteadyState {
                y: y[start..start + n].to_vec(),
                periods,
                change,
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use hyst_model::Oscillator;

    fn free_decay(integ: Integrator, r: usize) -> (Vec<f64>, f64) {
        // Undamped oscillator released from x0 = 1: x(t) = cos(ω t).
        let o = Oscillator::linear(1.0, 0.0, 100.0);
        let fs = 100.0;
        let opts = SimOptions {
            oversample: r,
            integrator: integ,
            ..SimOptions::default()
        };
        let zero = |_t: f64| 0.0;
        let (y, _) = simulate_from(
            &o,
            State::new(1.0, 0.0, 0.0, 0.0, 0.0),
            Input::Function(&zero),
            fs,
            201,
            &opts,
        )
        .unwrap();
        let err = y
            .iter()
            .enumerate()
            .map(|(k, v)| (v - (10.0 * k as f64 / fs).cos()).abs())
            .fold(0.0, f64::max);
        (y, err)
    }

    /// A sampled force that is band-limited (two sines below 0.4 of Nyquist) drives the
    /// benchmark as the continuous force does when interpolated band-limited: the output
    /// agrees with the run on the exact force (Input::Function) to 1e-4 of its RMS past the
    /// first 100 samples (6.4e-6 when written), where linear interpolation errs by 5.7e-3
    /// (the benchmark's README: 1.1e-2 for its multisine).
    /// A record interpolated once and given as such simulates exactly as the band-limited
    /// record it came from (which interpolates it on every call).
    #[test]
    fn an_interpolated_record_is_the_band_limited_one() {
        let u = crate::excitation::band_limited_noise(3000, 750.0, 5.0, 150.0, 50.0, 2).unwrap();
        let opts = SimOptions {
            oversample: 4,
            ..SimOptions::default()
        };
        let o = Oscillator::benchmark();
        let a = simulate(&o, Input::BandLimited(&u), 750.0, u.len(), &opts).unwrap();
        let fine = resample::interpolate_band_limited(&u, 8);
        let input = Input::Interpolated {
            samples: &fine,
            per_sample: 8,
        };
        assert_eq!(simulate(&o, input, 750.0, u.len(), &opts).unwrap(), a);
        let wrong = Input::Interpolated {
            samples: &fine,
            per_sample: 4,
        };
        assert!(matches!(
            simulate(&o, wrong, 750.0, u.len(), &opts),
            Err(SimError::UnsupportedInput { .. })
        ));
    }

    #[test]
    fn band_limited_input_matches_the_continuous_force() {
        let o = Oscillator::benchmark();
        let fs = 750.0;
        let n = 3000;
        let w = |f: f64| 2.0 * std::f64::consts::PI * f;
        let force = |t: f64| 30.0 * (w(35.0) * t).sin() + 20.0 * (w(140.0) * t + 0.5).cos();
        let u: Vec<f64> = (0..n).map(|k| force(k as f64 / fs)).collect();
        let opts = SimOptions::default();
        let exact = simulate(&o, Input::Function(&force), fs, n, &opts).unwrap();
        let rel = |y: &[f64]| {
            let (mut e, mut p) = (0.0, 0.0);
            for (a, b) in y[100..].iter().zip(&exact[100..]) {
                e += (a - b) * (a - b);
                p += b * b;
            }
            (e / p).sqrt()
        };
        let band = rel(&simulate(&o, Input::BandLimited(&u), fs, n, &opts).unwrap());
        let linear = rel(&simulate(&o, Input::Sampled(&u), fs, n, &opts).unwrap());
        assert!(band < 1e-4, "band-limited {band:.2e}");
        assert!(linear > 1e-3, "linear {linear:.2e}");
    }

    #[test]
    fn rk4_is_fourth_order() {
        let (_, e1) = free_decay(Integrator::Rk4, 2);
        let (_, e2) = free_decay(Integrator::Rk4, 4);
        let ratio = e1 / e2;
        // Halving the step divides the global error by 2⁴ = 16 for a fourth-order method.
        assert!((ratio - 16.0).abs() < 1.0, "ratio {ratio}");
    }

    #[test]
    fn trapezoid_is_second_order_and_conserves_energy() {
        let (y1, e1) = free_decay(Integrator::Trapezoidal, 2);
        let (_, e2) = free_decay(Integrator::Trapezoidal, 4);
        assert!((e1 / e2 - 4.0).abs() < 0.2, "ratio {}", e1 / e2);
        // The trapezoidal rule preserves the quadratic invariant exactly: the amplitude of
        // the undamped oscillation stays 1 (only the phase drifts).
        let max = y1.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(max <= 1.0 + 1e-12);
    }

    #[test]
    fn rk4_energy_balance_undamped() {
        // Energy E = ½ m v² + ½ k x² of the undamped oscillator is conserved by the exact
        // flow; RK4 at 40 steps per period loses it only at O(h⁴) per period.
        let o = Oscillator::linear(2.0, 0.0, 5e4);
        let fs = 750.0;
        let opts = SimOptions::default();
        let zero = |_t: f64| 0.0;
        let s0 = State::new(1e-3, 0.0, 0.0, 0.0, 0.0);
        let (_, s) = simulate_from(&o, s0, Input::Function(&zero), fs, 751, &opts).unwrap();
        let e = |s: &State| 0.5 * 2.0 * s[1] * s[1] + 0.5 * 5e4 * s[0] * s[0];
        assert_relative_eq!(e(&s), e(&s0), max_relative = 1e-6);
    }

    #[test]
    fn divergence_is_reported_with_its_sample() {
        // Negative stiffness: x grows as e^{√(k/m) t}.
        let o = Oscillator::linear(1.0, 0.0, -1e4);
        let u = vec![1.0; 2000];
        let opts = SimOptions {
            max_abs_state: 1e3,
            ..SimOptions::default()
        };
        let err = simulate(&o, Input::Sampled(&u), 100.0, 2000, &opts).unwrap_err();
        assert!(matches!(err, SimError::Diverged { sample, .. } if sample > 1 && sample < 100));
    }

    #[test]
    fn bad_input_is_rejected() {
        let o = Oscillator::benchmark();
        let opts = SimOptions::default();
        assert_eq!(
            simulate(&o, Input::Sampled(&[]), 750.0, 1, &opts),
            Err(SimError::EmptyInput)
        );
        assert!(matches!(
            simulate(&o, Input::Sampled(&[0.0, f64::NAN]), 750.0, 2, &opts),
            Err(SimError::NonFiniteInput { index: 1, .. })
        ));
        assert!(matches!(
            simulate(&o, Input::Sampled(&[0.0; 4]), 0.0, 4, &opts),
            Err(SimError::NonPositiveRate { .. })
        ));
        let zero = SimOptions {
            oversample: 0,
            ..SimOptions::default()
        };
        assert!(matches!(
            simulate(&o, Input::Sampled(&[0.0; 4]), 750.0, 4, &zero),
            Err(SimError::ZeroOversample { .. })
        ));
        // A factor past the bound is refused before any sub-step is taken or held (the
        // batch path interpolates a band-limited input first, the single path integrates).
        let huge = SimOptions {
            oversample: usize::MAX,
            ..SimOptions::default()
        };
        let models = [o, o];
        for r in [
            simulate(&o, Input::BandLimited(&[0.0; 4]), 750.0, 4, &huge),
            batch::simulate_many(&models, Input::BandLimited(&[0.0; 4]), 750.0, 4, &huge).remove(0),
        ] {
            assert!(matches!(
                r,
                Err(SimError::OversampleTooLarge {
                    max: MAX_OVERSAMPLE,
                    ..
                })
            ));
        }
        assert!(matches!(
            simulate(&o, Input::Sampled(&[0.0; 4]), 750.0, 5, &opts),
            Err(SimError::InputTooShort { .. })
        ));
        let mut bad = o;
        bad.mass = -1.0;
        assert!(matches!(
            simulate(&bad, Input::Sampled(&[0.0; 4]), 750.0, 4, &opts),
            Err(SimError::Model(_))
        ));
    }
}
