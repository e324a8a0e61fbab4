//! Simulate a model on a record's rows, fit it by output error, and its standard errors.

use hyst_model::Oscillator;
use hyst_sim::{Input, SimOptions};
use rayon::prelude::*;

use super::params::{P, free, get, positive, set};
use crate::{Validation, epsilon};

/// How the input force is known between its samples, when the models are simulated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "kebab-case"))]
pub enum InputInterpolation {
    /// A measured force behind an anti-aliasing filter: band-limited, interpolated by a
    /// windowed sinc ([`hyst_sim::Input::BandLimited`]). Linear interpolation of such a
    /// record misstates the force by about 1 % (the benchmark's multisine), enough for the
    /// loop to fit that error with effects the structure does not have.
    #[default]
    BandLimited,
    /// Linear between samples ([`hyst_sim::Input::Sampled`]): for records simulated so.
    Linear,
}

/// A record with input and output, and its sampling rate.
#[derive(Debug, Clone, Copy)]
pub struct Record<'a> {
    /// Input force.
    pub u: &'a [f64],
    /// Measured output.
    pub y: &'a [f64],
    /// Sampling rate (Hz).
    pub fs: f64,
    /// How the input is known between samples.
    pub interpolation: InputInterpolation,
}

/// Samples simulated before a range so that the model's state has forgotten the rest it
/// starts from (the record's state there is unknown).
pub const WARM_UP: usize = 2048;

/// A record made ready for the many simulations of a fit: a band-limited input is
/// interpolated once, over the whole record, to the points the RK4 stages read
/// ([`hyst_sim::Input::Interpolated`]), instead of once per simulation (where it cost more
/// than the integration itself) and over the simulated rows only (whose last samples then
/// lacked their neighbours).
pub(super) struct Prepared<'a> {
    rec: Record<'a>,
    fine: Vec<f64>,
    /// Told of every iteration of every fit on the record (a progress line that moves).
    beat: Option<&'a (dyn Fn() + Sync)>,
}

/// RK4 sub-steps per sample of the loop's simulations.
const OVERSAMPLE: usize = 4;

impl<'a> Prepared<'a> {
    pub(super) fn new(rec: &Record<'a>) -> Self {
        let fine = match rec.interpolation {
            InputInterpolation::BandLimited => {
                hyst_sim::resample::interpolate_band_limited(rec.u, 2 * OVERSAMPLE)
            }
            InputInterpolation::Linear => Vec::new(),
        };
        Prepared {
            rec: *rec,
            fine,
            beat: None,
        }
    }

    /// The record with `beat` told of each fit iteration on it.
    pub(super) fn with_heartbeat(mut self, beat: &'a (dyn Fn() + Sync)) -> Self {
        self.beat = Some(beat);
        self
    }

    /// One fit iteration done.
    fn beat(&self) {
        if let Some(b) = self.beat {
            b();
        }
    }
}

impl<'a> std::ops::Deref for Prepared<'a> {
    type Target = Record<'a>;
    fn deref(&self) -> &Record<'a> {
        &self.rec
    }
}

/// The model's output on rows [a, b), simulated from rest [`WARM_UP`] rows earlier (or at
/// row 0).
pub fn response(o: &Oscillator, rec: &Record<'_>, range: (usize, usize)) -> Option<Vec<f64>> {
    simulate(o, &Prepared::new(rec), range)
}

/// Simulate rows [a, b), starting from rest [`WARM_UP`] rows earlier (or at row 0).
pub(super) fn simulate(
    o: &Oscillator,
    rec: &Prepared<'_>,
    range: (usize, usize),
) -> Option<Vec<f64>> {
    let from = range.0.saturating_sub(WARM_UP);
    let n = range.1 - from;
    let opts = SimOptions {
        oversample: OVERSAMPLE,
        max_abs_state: 1e8,
        ..SimOptions::default()
    };
    let per = 2 * OVERSAMPLE;
    let input = match rec.interpolation {
        InputInterpolation::BandLimited => Input::Interpolated {
            samples: &rec.fine[from * per..=(range.1 - 1) * per],
            per_sample: per,
        },
        InputInterpolation::Linear => Input::Sampled(&rec.u[from..range.1]),
    };
    let y = hyst_sim::simulate(o, input, rec.fs, n, &opts).ok()?;
    Some(y[range.0 - from..].to_vec())
}

/// [`simulate`] for each of `models`, in lockstep batches ([`hyst_sim::simulate_many`]; the
/// batches in parallel): the perturbed models of a Jacobian.
pub(super) fn simulate_batch(
    models: &[Oscillator],
    rec: &Prepared<'_>,
    range: (usize, usize),
) -> Vec<Option<Vec<f64>>> {
    let from = range.0.saturating_sub(WARM_UP);
    let n = range.1 - from;
    let opts = SimOptions {
        oversample: OVERSAMPLE,
        max_abs_state: 1e8,
        ..SimOptions::default()
    };
    let per = 2 * OVERSAMPLE;
    let input = match rec.interpolation {
        InputInterpolation::BandLimited => Input::Interpolated {
            samples: &rec.fine[from * per..=(range.1 - 1) * per],
            per_sample: per,
        },
        InputInterpolation::Linear => Input::Sampled(&rec.u[from..range.1]),
    };
    models
        .par_chunks(hyst_sim::batch::LANES)
        .flat_map_iter(|chunk| {
            hyst_sim::simulate_many(chunk, input, rec.fs, n, &opts)
                .into_iter()
                .map(|y| y.ok().map(|y| y[range.0 - from..].to_vec()))
        })
        .collect()
}

/// Held-out error of a model on rows [a, b).
pub fn test_error(o: &Oscillator, rec: &Record<'_>, range: (usize, usize)) -> Option<Validation> {
    test_error_on(o, &Prepared::new(rec), range)
}

pub(super) fn test_error_on(
    o: &Oscillator,
    rec: &Prepared<'_>,
    range: (usize, usize),
) -> Option<Validation> {
    let yhat = simulate(o, rec, range)?;
    Some(epsilon(&yhat, &rec.y[range.0..range.1]))
}

pub(super) fn residual(
    o: &Oscillator,
    rec: &Prepared<'_>,
    range: (usize, usize),
) -> Option<Vec<f64>> {
    let yhat = simulate(o, rec, range)?;
    Some(
        rec.y[range.0..range.1]
            .iter()
            .zip(&yhat)
            .map(|(a, b)| a - b)
            .collect(),
    )
}

pub(super) fn sse(r: &[f64]) -> f64 {
    r.iter().map(|v| v * v).sum()
}

/// Output-error Levenberg–Marquardt fit of every free parameter of `o` on rows `range`, on
/// growing windows: the first eighth of the rows (at least [`FIRST_WINDOW`]), then twice as
/// many, up to all of them, each fit starting where the last ended (at most `iterations`
/// each). The output error of a long record is a rough function of the parameters (a
/// hardening oscillator's response slips by whole cycles when they move a little: a start
/// 1 % off in c and k₃ ends 7 % from the optimum), that of a short one is smooth; each
/// window's optimum starts the next one near its own. Returns the fitted model and its
/// residual sum of squares on `range`, or `None` if every trial step diverged from the start.
pub fn fit(
    o: &Oscillator,
    rec: &Record<'_>,
    range: (usize, usize),
    fit_mass: bool,
    iterations: usize,
) -> Option<(Oscillator, f64)> {
    fit_on(o, &Prepared::new(rec), range, fit_mass, iterations)
}

pub(super) fn fit_on(
    o: &Oscillator,
    rec: &Prepared<'_>,
    range: (usize, usize),
    fit_mass: bool,
    iterations: usize,
) -> Option<(Oscillator, f64)> {
    fit_best_of(std::slice::from_ref(o), rec, range, fit_mass, iterations)
}

/// [`fit`] from several starts: each is fitted on the first window, where the cost is smooth
/// and the fits are cheap, and only the best of them goes on to the larger windows. `None`
/// when no start simulates.
pub(super) fn fit_best_of(
    starts: &[Oscillator],
    rec: &Prepared<'_>,
    range: (usize, usize),
    fit_mass: bool,
    iterations: usize,
) -> Option<(Oscillator, f64)> {
    let len = range.1 - range.0;
    let mut windows = vec![len];
    while windows.len() < 4 && windows[windows.len() - 1] / 2 >= FIRST_WINDOW {
        windows.push(windows[windows.len() - 1] / 2);
    }
    let mut sizes = windows.iter().rev();
    let first = *sizes.next()?;
    let (mut m, mut c) = starts
        .par_iter()
        .filter_map(|s| fit_window(s, rec, (range.0, range.0 + first), fit_mass, iterations))
        .filter(|(_, c)| c.is_finite())
        .min_by(|a, b| a.1.total_cmp(&b.1))?;
    for &w in sizes {
        (m, c) = fit_window(&m, rec, (range.0, range.0 + w), fit_mass, iterations)?;
    }
    Some((m, c))
}

/// Fewest rows of the first window of [`fit`].
pub const FIRST_WINDOW: usize = 512;

/// How a fit moves one parameter: linearly, scaled by its start, or on a log scale for one
/// physics keeps positive ([`positive`]), so that no step can cross zero.
#[derive(Debug, Clone, Copy)]
enum Scale {
    Linear(f64),
    Log(f64),
}

impl Scale {
    /// The scale of parameter `p` starting at `v`, and its coordinate there.
    fn of(p: P, v: f64) -> (Scale, f64) {
        if positive(p) {
            // A start at or below zero is moved just inside: the fit then follows the
            // record from there.
            (Scale::Log(if v > 0.0 { v } else { 1e-9 }), 0.0)
        } else {
            let s = v.abs().max(1e-12);
            (Scale::Linear(s), v / s)
        }
    }

    fn value(self, x: f64) -> f64 {
        match self {
            Scale::Linear(s) => s * x,
            Scale::Log(r) => r * x.exp(),
        }
    }

    /// Finite-difference step of the coordinate `x`.
    fn step(self, x: f64) -> f64 {
        match self {
            Scale::Linear(_) => 1e-6 * x.abs().max(1e-3),
            Scale::Log(_) => 1e-6,
        }
    }
}

/// A fit has converged when [`CONVERGED_STEPS`] steps in a row each lowered the sum of
/// squares by less than this share of the residual's mean square $c/N$. Near the optimum
/// $c(\theta) - c^* = \delta^2 \hat\sigma^2$ for a parameter $\delta$ standard errors away, so
/// a step that gains less than $0.01\,\hat\sigma^2$ moves it by about a tenth of a standard
/// error or less, and ΔBIC ($N\ln(c_1/c_0)$) by less than 0.01. (It was a relative gain of
/// 1e-9, a thousandth of a standard error on the loop's records, for which the fits ran a
/// third more iterations; `cargo xtask bench refine`.)
const CONVERGED_GAIN: f64 = 0.01;

/// Steps in a row under [`CONVERGED_GAIN`] that end a fit: one alone can be a short step
/// before a longer one (a gain of 4e-7 followed by 2e-5 on a 24576-row fit of the loop).
const CONVERGED_STEPS: usize = 2;

/// Largest change of a log coordinate in one step of the fit (a factor e ≈ 2.7).
const MAX_LOG_STEP: f64 = 1.0;

/// [`fit`] on all of `range` at once.
pub(super) fn fit_window(
    o: &Oscillator,
    rec: &Prepared<'_>,
    range: (usize, usize),
    fit_mass: bool,
    iterations: usize,
) -> Option<(Oscillator, f64)> {
    let ids = free(o, fit_mass);
    let np = ids.len();
    let (scale, mut x): (Vec<Scale>, Vec<f64>) =
        ids.iter().map(|&p| Scale::of(p, get(o, p))).unzip();
    let model_at = |x: &[f64]| {
        let mut m = *o;
        for (i, &p) in ids.iter().enumerate() {
            set(&mut m, p, scale[i].value(x[i]));
        }
        m
    };
    // The model at x and its finite-difference Jacobian: the model and one perturbation per
    // parameter simulated together in lockstep, so that each column's difference is taken
    // between outputs of the same arithmetic. The output at x comes with its Jacobian;
    // `None` for the Jacobian when a perturbed model does not simulate.
    let at = |x: &[f64], m: &Oscillator| -> Option<(Vec<f64>, Option<Jacobian>)> {
        let steps: Vec<f64> = (0..np).map(|j| scale[j].step(x[j])).collect();
        let models: Vec<Oscillator> = std::iter::once(*m)
            .chain((0..np).map(|j| {
                let mut xj = x.to_vec();
                xj[j] += steps[j];
                model_at(&xj)
            }))
            .collect();
        let mut outs = simulate_batch(&models, rec, range).into_iter();
        let y0 = outs.next()??;
        // r = y − ŷ, so ∂r/∂x_j = −∂ŷ/∂x_j.
        let cols = outs
            .zip(&steps)
            .map(|(yj, h)| Some(yj?.iter().zip(&y0).map(|(a, b)| (b - a) / h).collect()))
            .collect::<Option<Jacobian>>();
        let r = rec.y[range.0..range.1]
            .iter()
            .zip(&y0)
            .map(|(a, b)| a - b)
            .collect();
        Some((r, cols))
    };
    let mut cur = model_at(&x);
    let (mut r, mut jac) = at(&x, &cur)?;
    let mut c = sse(&r);
    let mut lambda = 1e-3;
    let rows = (range.1 - range.0) as f64;
    let mut small_steps = 0;
    for _ in 0..iterations {
        rec.beat();
        let Some(cols) = jac.take() else {
            break;
        };
        let (a, g) = crate::normal_equations(&cols, &r);
        let improved = crate::lm_step(&a, &g, &mut lambda, |step| {
            // A log coordinate moves by at most MAX_LOG_STEP a step (the whole step is
            // shortened to keep its direction): a parameter sent towards zero in one step
            // has no sensitivity left to come back with (a second mode's damper once went
            // from 1.5 to 1e-118 N s/m in one step and stayed there).
            let longest = step
                .iter()
                .zip(&scale)
                .filter(|(_, s)| matches!(s, Scale::Log(_)))
                .fold(0.0f64, |m, (d, _)| m.max(d.abs()));
            let shrink = if longest > MAX_LOG_STEP {
                MAX_LOG_STEP / longest
            } else {
                1.0
            };
            let xn: Vec<f64> = x.iter().zip(step).map(|(a, b)| a - shrink * b).collect();
            let mn = model_at(&xn);
            mn.validate().ok()?;
            // The trial is simulated with the Jacobian it will need if accepted: most
            // trials are, and the next iteration then starts with its Jacobian made.
            let (rn, jn) = at(&xn, &mn)?;
            let cn = sse(&rn);
            (cn < c).then(|| {
                let significant = c - cn > CONVERGED_GAIN * c / rows;
                (x, cur, r, c, jac) = (xn, mn, rn, cn, jn);
                significant
            })
        });
        // λ past its largest: no step lowers the cost from here. Otherwise a step was
        // accepted, with the Jacobian at its point (none if a perturbed model diverged,
        // which ends the fit at the next iteration).
        if lambda >= crate::numerics::LmSchedule::default().max {
            break;
        }
        small_steps = if improved { 0 } else { small_steps + 1 };
        if small_steps == CONVERGED_STEPS {
            break;
        }
    }
    Some((cur, c))
}

/// A Jacobian's columns, one per free parameter: the residual's derivative on each row.
type Jacobian = Vec<Vec<f64>>;

/// A fitted parameter with its standard error.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Estimate {
    /// The parameter's name, as in the JSON of `hyst refine` (`damping`, `alpha`, …).
    #[cfg_attr(
        feature = "serde",
        serde(deserialize_with = "super::params::deserialize_name")
    )]
    pub name: std::borrow::Cow<'static, str>,
    /// Its fitted value.
    pub value: f64,
    /// Its standard error (NaN when the sensitivities are singular).
    #[cfg_attr(feature = "serde", serde(with = "crate::nullable"))]
    pub se: f64,
}

/// Rows per block of the standard errors' covariance (see [`standard_errors`]).
pub const SE_BLOCK_ROWS: usize = 512;

/// Standard errors of the free parameters of `o`, fitted by output error on rows `range`:
/// the sandwich $(J^TJ)^{-1}\,S\,(J^TJ)^{-1}$, $J$ the simulated output's sensitivity to each
/// parameter (central differences) and $S = \sum_b g_b g_b^T$ the outer products of the
/// scores $g_b = \sum_{t\in b} J_t r_t$ summed over blocks of [`SE_BLOCK_ROWS`] rows. With a
/// white residual this is $\sigma^2(J^TJ)^{-1}$; a coloured one (an effect the model misses,
/// coloured noise) correlates neighbouring scores, which the blocks keep and the white
/// formula would drop (making the errors too small). `None` when the model does not simulate.
pub fn standard_errors(
    o: &Oscillator,
    rec: &Record<'_>,
    range: (usize, usize),
    fit_mass: bool,
) -> Option<Vec<Estimate>> {
    standard_errors_on(o, &Prepared::new(rec), range, fit_mass)
}

pub(super) fn standard_errors_on(
    o: &Oscillator,
    rec: &Prepared<'_>,
    range: (usize, usize),
    fit_mass: bool,
) -> Option<Vec<Estimate>> {
    let ids = free(o, fit_mass);
    let r = residual(o, rec, range)?;
    let cols: Vec<Vec<f64>> = ids
        .par_iter()
        .map(|&p| {
            let v = get(o, p);
            let h = 1e-5 * v.abs().max(1e-12);
            let (mut a, mut b) = (*o, *o);
            set(&mut a, p, v + h);
            set(&mut b, p, v - h);
            let (ya, yb) = (simulate(&a, rec, range)?, simulate(&b, rec, range)?);
            Some(
                ya.iter()
                    .zip(&yb)
                    .map(|(x, y)| (x - y) / (2.0 * h))
                    .collect(),
            )
        })
        .collect::<Option<_>>()?;
    let np = ids.len();
    let (jtj, _) = crate::normal_equations(&cols, &r);
    let mut meat = vec![vec![0.0; np]; np];
    for start in (0..r.len()).step_by(SE_BLOCK_ROWS) {
        let end = (start + SE_BLOCK_ROWS).min(r.len());
        let g: Vec<f64> = cols
            .iter()
            .map(|c| {
                c[start..end]
                    .iter()
                    .zip(&r[start..end])
                    .map(|(a, b)| a * b)
                    .sum()
            })
            .collect();
        for i in 0..np {
            for j in 0..np {
                meat[i][j] += g[i] * g[j];
            }
        }
    }
    // The bread's columns: (JᵀJ)⁻¹ eᵢ.
    let bread: Option<Vec<Vec<f64>>> = (0..np)
        .map(|i| {
            let mut e = vec![0.0; np];
            e[i] = 1.0;
            crate::solve(jtj.clone(), e)
        })
        .collect();
    Some(
        ids.iter()
            .enumerate()
            .map(|(i, &p)| {
                let var = bread.as_ref().map_or(f64::NAN, |b| {
                    let bi = &b[i];
                    (0..np)
                        .map(|k| (0..np).map(|l| bi[k] * meat[k][l] * bi[l]).sum::<f64>())
                        .sum()
                });
                Estimate {
                    name: p.name().into(),
                    value: get(o, p),
                    se: if var >= 0.0 { var.sqrt() } else { f64::NAN },
                }
            })
            .collect(),
    )
}
