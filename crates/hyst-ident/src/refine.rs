//! Closing the loop with measured input and output: refine a model by output error, find in
//! its residual the effect it lacks, add that effect, refit, and report the held-out error
//! before and after.
//!
//! * **Output-error fit** ([`fit`]): simulate the model with the measured input (RK4, from
//!   rest [`WARM_UP`] samples before the range, the input interpolated as
//!   [`Record::interpolation`] says), minimise $\sum (y - \hat y)^2$ over the model's free
//!   parameters by Levenberg–Marquardt, the Jacobian by finite differences computed in
//!   parallel (rayon).
//! * **Diagnosis** ([`diagnose`]): each candidate effect ([`Effect`]) is added to the model
//!   in turn and the whole model refitted. Evidence per candidate: the residual variance it
//!   explains, the change of the Bayesian information criterion
//!   $\Delta\text{BIC} = N\ln(\sigma^2_{new}/\sigma^2_{old}) + \Delta p\,\ln N$, and where the
//!   residual lives in frequency (its spectral peak, and the share of its power above 1.5× the
//!   resonance, where harmonics of a nonlinearity fall). The best candidate is added if its
//!   ΔBIC is below −10 (strong evidence); noise alone cannot meet that, so it gives `none`.
//! * **Loop** ([`refine`]): repeat while an effect is significant (at most three steps).

use hyst_model::{BoucWen, Coulomb, Oscillator, Restoring, SecondMass};
use hyst_sim::{Input, SimOptions};
use rayon::prelude::*;

use crate::{IdentError, Validation, epsilon, solve};

/// An effect the loop can add.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Effect {
    /// Cubic spring $k_3x^3$.
    CubicStiffness,
    /// Quadratic damping $c_q\dot x|\dot x|$.
    QuadraticDamping,
    /// Coulomb friction $F_c\tanh(\dot x/v_\varepsilon)$.
    CoulombFriction,
    /// A second mass on a spring and damper.
    SecondMode,
    /// A Bouc-Wen hysteretic element: added to a model without a restoring element, or in
    /// place of a Zener element (its linearization), started from the Bouc-Wen elements
    /// whose describing function equals the Zener's at the model's resonance.
    Hysteresis,
    /// The Bouc-Wen element's exponent ν freed (ν = 1 until then): how sharply the element
    /// turns from stiff to slipping. Started from elements of several ν whose describing
    /// function at A = σₓ equals the current element's.
    HysteresisExponent,
}

impl Effect {
    /// The name used in reports.
    pub fn name(&self) -> &'static str {
        match self {
            Effect::CubicStiffness => "cubic_stiffness",
            Effect::QuadraticDamping => "quadratic_damping",
            Effect::CoulombFriction => "coulomb_friction",
            Effect::SecondMode => "second_mode",
            Effect::Hysteresis => "hysteresis",
            Effect::HysteresisExponent => "hysteresis_exponent",
        }
    }

    /// Every candidate.
    pub const ALL: [Effect; 6] = [
        Effect::CubicStiffness,
        Effect::QuadraticDamping,
        Effect::CoulombFriction,
        Effect::SecondMode,
        Effect::Hysteresis,
        Effect::HysteresisExponent,
    ];
}

/// The free parameters of a model, in a fixed order. A Bouc-Wen element's exponent ν is
/// free when it differs from 1 (the elements the loop builds have ν = 1 until
/// [`Effect::HysteresisExponent`] frees it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum P {
    Mass,
    Damping,
    Stiffness,
    KInf,
    Omega,
    Alpha,
    BetaGamma,
    BetaDelta,
    Nu,
    Cubic,
    Quad,
    Coulomb,
    M2,
    K2,
    C2,
}

fn free(o: &Oscillator, fit_mass: bool) -> Vec<P> {
    let mut v = Vec::new();
    if fit_mass {
        v.push(P::Mass);
    }
    v.extend([P::Damping, P::Stiffness]);
    match o.restoring {
        Restoring::None => {}
        Restoring::Zener(_) => v.extend([P::KInf, P::Omega]),
        Restoring::BoucWen(b) => {
            v.extend([P::Alpha, P::BetaGamma, P::BetaDelta]);
            if b.nu != 1.0 {
                v.push(P::Nu);
            }
        }
    }
    let e = &o.extras;
    if e.cubic_stiffness != 0.0 {
        v.push(P::Cubic);
    }
    if e.quadratic_damping != 0.0 {
        v.push(P::Quad);
    }
    if e.coulomb.is_some() {
        v.push(P::Coulomb);
    }
    if e.second_mass.is_some() {
        v.extend([P::M2, P::K2, P::C2]);
    }
    v
}

fn get(o: &Oscillator, p: P) -> f64 {
    match (p, &o.restoring) {
        (P::Mass, _) => o.mass,
        (P::Damping, _) => o.damping,
        (P::Stiffness, _) => o.stiffness,
        (P::KInf, Restoring::Zener(z)) => z.k_inf,
        (P::Omega, Restoring::Zener(z)) => z.omega,
        (P::Alpha, Restoring::BoucWen(b)) => b.alpha,
        (P::BetaGamma, Restoring::BoucWen(b)) => b.beta_gamma(),
        (P::BetaDelta, Restoring::BoucWen(b)) => b.beta_delta(),
        (P::Nu, Restoring::BoucWen(b)) => b.nu,
        (P::Cubic, _) => o.extras.cubic_stiffness,
        (P::Quad, _) => o.extras.quadratic_damping,
        (P::Coulomb, _) => o.extras.coulomb.map_or(0.0, |c| c.force),
        (P::M2, _) => o.extras.second_mass.map_or(0.0, |s| s.mass),
        (P::K2, _) => o.extras.second_mass.map_or(0.0, |s| s.stiffness),
        (P::C2, _) => o.extras.second_mass.map_or(0.0, |s| s.damping),
        _ => 0.0,
    }
}

fn set(o: &mut Oscillator, p: P, v: f64) {
    match p {
        P::Mass => o.mass = v,
        P::Damping => o.damping = v,
        P::Stiffness => o.stiffness = v,
        P::KInf | P::Omega => {
            if let Restoring::Zener(z) = &mut o.restoring {
                if p == P::KInf {
                    z.k_inf = v
                } else {
                    z.omega = v
                }
            }
        }
        P::Alpha | P::BetaGamma | P::BetaDelta | P::Nu => {
            if let Restoring::BoucWen(b) = &mut o.restoring {
                let (mut a, mut bg, mut bd, mut nu) =
                    (b.alpha, b.beta_gamma(), b.beta_delta(), b.nu);
                match p {
                    P::Alpha => a = v,
                    P::BetaGamma => bg = v,
                    P::BetaDelta => bd = v,
                    _ => nu = v,
                }
                *b = BoucWen::from_products(a, bg, bd, nu);
            }
        }
        P::Cubic => o.extras.cubic_stiffness = v,
        P::Quad => o.extras.quadratic_damping = v,
        P::Coulomb => {
            if let Some(c) = &mut o.extras.coulomb {
                c.force = v
            }
        }
        P::M2 | P::K2 | P::C2 => {
            if let Some(s) = &mut o.extras.second_mass {
                match p {
                    P::M2 => s.mass = v,
                    P::K2 => s.stiffness = v,
                    _ => s.damping = v,
                }
            }
        }
    }
}

/// How the input force is known between its samples, when the models are simulated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
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

/// The model's output on rows [a, b), simulated from rest [`WARM_UP`] rows earlier (or at
/// row 0).
pub fn response(o: &Oscillator, rec: &Record<'_>, range: (usize, usize)) -> Option<Vec<f64>> {
    simulate(o, rec, range)
}

/// Simulate rows [a, b), starting from rest [`WARM_UP`] rows earlier (or at row 0).
fn simulate(o: &Oscillator, rec: &Record<'_>, range: (usize, usize)) -> Option<Vec<f64>> {
    let from = range.0.saturating_sub(WARM_UP);
    let u = &rec.u[from..range.1];
    let opts = SimOptions {
        oversample: 4,
        max_abs_state: 1e8,
        ..SimOptions::default()
    };
    let input = match rec.interpolation {
        InputInterpolation::BandLimited => Input::BandLimited(u),
        InputInterpolation::Linear => Input::Sampled(u),
    };
    let y = hyst_sim::simulate(o, input, rec.fs, u.len(), &opts).ok()?;
    Some(y[range.0 - from..].to_vec())
}

/// Held-out error of a model on rows [a, b).
pub fn test_error(o: &Oscillator, rec: &Record<'_>, range: (usize, usize)) -> Option<Validation> {
    let yhat = simulate(o, rec, range)?;
    Some(epsilon(&yhat, &rec.y[range.0..range.1]))
}

fn residual(o: &Oscillator, rec: &Record<'_>, range: (usize, usize)) -> Option<Vec<f64>> {
    let yhat = simulate(o, rec, range)?;
    Some(
        rec.y[range.0..range.1]
            .iter()
            .zip(&yhat)
            .map(|(a, b)| a - b)
            .collect(),
    )
}

fn sse(r: &[f64]) -> f64 {
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
    fit_best_of(std::slice::from_ref(o), rec, range, fit_mass, iterations)
}

/// [`fit`] from several starts: each is fitted on the first window, where the cost is smooth
/// and the fits are cheap, and only the best of them goes on to the larger windows. `None`
/// when no start simulates.
fn fit_best_of(
    starts: &[Oscillator],
    rec: &Record<'_>,
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
        .iter()
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

/// [`fit`] on all of `range` at once.
fn fit_window(
    o: &Oscillator,
    rec: &Record<'_>,
    range: (usize, usize),
    fit_mass: bool,
    iterations: usize,
) -> Option<(Oscillator, f64)> {
    let ids = free(o, fit_mass);
    let np = ids.len();
    let scale: Vec<f64> = ids.iter().map(|&p| get(o, p).abs().max(1e-12)).collect();
    let model_at = |x: &[f64]| {
        let mut m = *o;
        for (i, &p) in ids.iter().enumerate() {
            set(&mut m, p, x[i] * scale[i]);
        }
        m
    };
    let mut x = vec![1.0; np];
    for (i, &p) in ids.iter().enumerate() {
        x[i] = get(o, p) / scale[i];
    }
    let mut cur = model_at(&x);
    let mut r = residual(&cur, rec, range)?;
    let mut c = sse(&r);
    let mut lambda = 1e-3;
    for _ in 0..iterations {
        // Finite-difference Jacobian, one simulation per parameter, in parallel.
        let cols: Vec<Option<Vec<f64>>> = (0..np)
            .into_par_iter()
            .map(|j| {
                let h = 1e-6 * x[j].abs().max(1e-3);
                let mut xj = x.clone();
                xj[j] += h;
                let rj = residual(&model_at(&xj), rec, range)?;
                Some(rj.iter().zip(&r).map(|(a, b)| (a - b) / h).collect())
            })
            .collect();
        let Some(cols) = cols.into_iter().collect::<Option<Vec<Vec<f64>>>>() else {
            break;
        };
        let (a, g) = crate::normal_equations(&cols, &r);
        let improved = crate::lm_step(&a, &g, &mut lambda, |step| {
            let xn: Vec<f64> = x.iter().zip(step).map(|(a, b)| a - b).collect();
            let mn = model_at(&xn);
            mn.validate().ok()?;
            let rn = residual(&mn, rec, range)?;
            let cn = sse(&rn);
            (cn < c).then(|| {
                let significant = c - cn > 1e-9 * c;
                (x, cur, r, c) = (xn, mn, rn, cn);
                significant
            })
        });
        if !improved {
            break;
        }
    }
    Some((cur, c))
}

impl P {
    fn name(self) -> &'static str {
        match self {
            P::Mass => "mass",
            P::Damping => "damping",
            P::Stiffness => "stiffness",
            P::KInf => "k_inf",
            P::Omega => "omega",
            P::Alpha => "alpha",
            P::BetaGamma => "beta_gamma",
            P::BetaDelta => "beta_delta",
            P::Nu => "nu",
            P::Cubic => "cubic_stiffness",
            P::Quad => "quadratic_damping",
            P::Coulomb => "coulomb_force",
            P::M2 => "second_mass",
            P::K2 => "second_stiffness",
            P::C2 => "second_damping",
        }
    }
}

/// A fitted parameter with its standard error.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    /// The parameter's name, as in the JSON of `hyst refine` (`damping`, `alpha`, …).
    pub name: &'static str,
    /// Its fitted value.
    pub value: f64,
    /// Its standard error (NaN when the sensitivities are singular).
    pub se: f64,
}

/// Standard errors of the free parameters of `o`, fitted by output error on rows `range`:
/// the diagonal of σ²(JᵀJ)⁻¹, J the simulated output's sensitivity to each parameter (central
/// differences) and σ² = Σr²/(N − p), the residual taken as white noise. A residual that is
/// not white (an effect the model misses, coloured noise) makes them too small. `None` when
/// the model does not simulate.
pub fn standard_errors(
    o: &Oscillator,
    rec: &Record<'_>,
    range: (usize, usize),
    fit_mass: bool,
) -> Option<Vec<Estimate>> {
    let ids = free(o, fit_mass);
    let r = residual(o, rec, range)?;
    let dof = r.len().saturating_sub(ids.len()).max(1) as f64;
    let sigma2 = sse(&r) / dof;
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
    let (jtj, _) = crate::normal_equations(&cols, &r);
    Some(
        ids.iter()
            .enumerate()
            .map(|(i, &p)| {
                let mut e = vec![0.0; ids.len()];
                e[i] = 1.0;
                let var = crate::solve(jtj.clone(), e).map_or(f64::NAN, |c| c[i] * sigma2);
                Estimate {
                    name: p.name(),
                    value: get(o, p),
                    se: if var >= 0.0 { var.sqrt() } else { f64::NAN },
                }
            })
            .collect(),
    )
}

/// Where the residual's power lies.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spectrum {
    /// Frequency of the residual's largest spectral peak (Hz).
    pub peak_hz: f64,
    /// Share of the residual power above 1.5× the model's resonance.
    pub above_resonance: f64,
    /// The model's resonance (Hz).
    pub resonance_hz: f64,
}

/// The residual's power at 511 frequencies evenly spaced on (0, fs/2), (Hz, power): a coarse
/// DFT scan (of at most its first 16384 samples) is enough to locate it.
fn power_scan(r: &[f64], fs: f64) -> Vec<(f64, f64)> {
    let n = r.len().min(16384);
    let r = &r[..n];
    (1..512)
        .map(|p| {
            let f = fs / 2.0 * p as f64 / 512.0;
            let w = 2.0 * std::f64::consts::PI * f / fs;
            let (mut re, mut im) = (0.0, 0.0);
            for (k, v) in r.iter().enumerate() {
                let (s, c) = (w * k as f64).sin_cos();
                re += v * c;
                im -= v * s;
            }
            (f, re * re + im * im)
        })
        .collect()
}

fn periodogram_peak(scan: &[(f64, f64)], resonance_hz: f64) -> Spectrum {
    let total: f64 = scan.iter().map(|p| p.1).sum();
    let high: f64 = scan
        .iter()
        .filter(|p| p.0 > 1.5 * resonance_hz)
        .map(|p| p.1)
        .sum();
    let best = scan
        .iter()
        .copied()
        .fold((0.0, 0.0), |b, p| if p.1 > b.1 { p } else { b });
    Spectrum {
        peak_hz: best.0,
        above_resonance: if total > 0.0 { high / total } else { 0.0 },
        resonance_hz,
    }
}

/// The second masses to start `second_mode` fits from: 10 % of the main mass with 2 %
/// damping, tuned to each of the residual's three strongest peaks that lie at least 20 %
/// apart in frequency. The residual's strongest peak is often the misfit main resonance, not
/// the missing mode, and one start at it can end in a poor local optimum.
fn second_mass_starts(o: &Oscillator, scan: &[(f64, f64)]) -> Vec<Oscillator> {
    let mut peaks: Vec<(f64, f64)> = scan
        .windows(3)
        .filter(|w| w[1].1 > w[0].1 && w[1].1 >= w[2].1)
        .map(|w| w[1])
        .collect();
    peaks.sort_by(|a, b| b.1.total_cmp(&a.1));
    let mut chosen: Vec<f64> = Vec::new();
    for (f, _) in peaks {
        if chosen.len() == 3 {
            break;
        }
        if chosen.iter().all(|&g| f.max(g) / f.min(g) >= 1.2) {
            chosen.push(f);
        }
    }
    chosen
        .into_iter()
        .map(|f| {
            let w = 2.0 * std::f64::consts::PI * f.max(1e-3);
            let m2 = 0.1 * o.mass;
            let mut m = *o;
            m.extras.second_mass = Some(SecondMass {
                mass: m2,
                stiffness: m2 * w * w,
                damping: 2.0 * 0.02 * m2 * w,
            });
            m
        })
        .collect()
}

/// The evidence for one candidate effect.
#[derive(Debug, Clone, PartialEq)]
pub struct Evidence {
    /// The candidate.
    pub effect: Effect,
    /// Share of the residual variance the refitted model explains.
    pub variance_explained: f64,
    /// Change of the BIC (negative favours the effect).
    pub delta_bic: f64,
    /// The refitted model, unless the fit diverged or the candidate was rejected.
    pub model: Option<Oscillator>,
    /// Why the candidate was not considered, or was rejected after its fit, if so.
    pub rejected: Option<String>,
}

fn resonance_hz(o: &Oscillator) -> f64 {
    let k = o.stiffness
        + match o.restoring {
            Restoring::BoucWen(b) => b.alpha,
            Restoring::Zener(z) => z.k_inf,
            Restoring::None => 0.0,
        };
    (k.max(0.0) / o.mass).sqrt() / (2.0 * std::f64::consts::PI)
}

/// Linear least squares of u = m ÿ + c ẏ + k y + θ g(y, ẏ) on the measured output
/// (derivatives by the five-point stencil), for a plain oscillator plus one effect whose force
/// is linear in θ. `None` when it does not apply or the regression is singular.
fn equation_error_start(
    start: &Oscillator,
    e: Option<Effect>,
    rec: &Record<'_>,
    range: (usize, usize),
    fit_mass: bool,
) -> Option<Oscillator> {
    let p = match e {
        Some(e) => Some(linear_coefficient(e)?),
        None => None,
    };
    if start.restoring != Restoring::None || start.extras.second_mass.is_some() {
        return None;
    }
    let y = &rec.y[range.0..range.1];
    let n = y.len();
    if n < 16 {
        return None;
    }
    let h = 1.0 / rec.fs;
    let vs = start.extras.coulomb.map_or(1.0, |c| c.smoothing_velocity);
    let g = |x: f64, v: f64| match e {
        Some(Effect::CubicStiffness) => x * x * x,
        Some(Effect::QuadraticDamping) => v * v.abs(),
        _ => (v / vs).tanh(),
    };
    // Regressors: [ÿ (if the mass is fitted), ẏ, y, g (with an effect)]; target u (− m ÿ if
    // the mass is known).
    let np = usize::from(fit_mass) + 2 + usize::from(p.is_some());
    let mut a = vec![vec![0.0; np]; np];
    let mut b = vec![0.0; np];
    for i in 2..n - 2 {
        let v = (y[i - 2] - 8.0 * y[i - 1] + 8.0 * y[i + 1] - y[i + 2]) / (12.0 * h);
        let acc = (-y[i - 2] + 16.0 * y[i - 1] - 30.0 * y[i] + 16.0 * y[i + 1] - y[i + 2])
            / (12.0 * h * h);
        let mut row = Vec::with_capacity(np);
        if fit_mass {
            row.push(acc);
        }
        row.extend([v, y[i]]);
        if p.is_some() {
            row.push(g(y[i], v));
        }
        let target = rec.u[range.0 + i] - if fit_mass { 0.0 } else { start.mass * acc };
        for r in 0..np {
            b[r] += row[r] * target;
            for c in 0..np {
                a[r][c] += row[r] * row[c];
            }
        }
    }
    let x = solve(a, b)?;
    let mut m = *start;
    let off = if fit_mass {
        if x[0] <= 0.0 {
            return None;
        }
        m.mass = x[0];
        1
    } else {
        0
    };
    m.damping = x[off];
    m.stiffness = x[off + 1];
    if let Some(p) = p {
        if x[off + 2] == 0.0 {
            return None;
        }
        set(&mut m, p, x[off + 2]);
    }
    m.validate().is_ok().then_some(m)
}

/// The coefficient of an effect whose force is linear in it.
fn linear_coefficient(e: Effect) -> Option<P> {
    match e {
        Effect::CubicStiffness => Some(P::Cubic),
        Effect::QuadraticDamping => Some(P::Quad),
        Effect::CoulombFriction => Some(P::Coulomb),
        _ => None,
    }
}

/// Why the fitted `m` does not have the effect `e` it was fitted with, if it does not: the
/// dissipative effects must dissipate. A Bouc-Wen element with βγ ≤ 0 loses no energy (its
/// describing function's loss is 4αβγA/3π to first order) and is a nonlinear spring, not
/// hysteresis; friction or quadratic damping with a coefficient ≤ 0 feeds energy in.
fn not_dissipating(e: Effect, m: &Oscillator) -> Option<String> {
    let x = &m.extras;
    match (e, m.restoring) {
        (Effect::Hysteresis | Effect::HysteresisExponent, Restoring::BoucWen(b))
            if b.beta_gamma() <= 0.0 =>
        {
            Some(format!(
                "the fitted Bouc-Wen element does not dissipate (βγ = {:.3e} ≤ 0): a nonlinear spring, not hysteresis",
                b.beta_gamma()
            ))
        }
        (Effect::CoulombFriction, _) => match x.coulomb {
            Some(c) if c.force <= 0.0 => Some(format!(
                "the fitted friction force is {:.3e} ≤ 0: it feeds energy in",
                c.force
            )),
            _ => None,
        },
        (Effect::QuadraticDamping, _) if x.quadratic_damping <= 0.0 => Some(format!(
            "the fitted quadratic damping is {:.3e} ≤ 0: it feeds energy in",
            x.quadratic_damping
        )),
        _ => None,
    }
}

/// Why `effect` cannot be added to `o` again, if `o` has it already (one of each).
fn already_has(o: &Oscillator, effect: Effect) -> Option<&'static str> {
    let x = &o.extras;
    match effect {
        Effect::CubicStiffness if x.cubic_stiffness != 0.0 => {
            Some("the model already has a cubic spring")
        }
        Effect::QuadraticDamping if x.quadratic_damping != 0.0 => {
            Some("the model already has quadratic damping")
        }
        Effect::CoulombFriction if x.coulomb.is_some() => {
            Some("the model already has Coulomb friction")
        }
        Effect::SecondMode if x.second_mass.is_some() => {
            Some("the model already has a second mass (one is supported)")
        }
        _ => None,
    }
}

/// Add `effect` to `o` with a starting value sized from the record (σ of x and ẋ).
fn with_effect(o: &Oscillator, effect: Effect, sx: f64, sv: f64) -> Option<Oscillator> {
    let mut m = *o;
    let k = o.stiffness.abs().max(1e-12);
    match effect {
        Effect::CubicStiffness => m.extras.cubic_stiffness = 1e-3 * k / (sx * sx),
        Effect::QuadraticDamping => {
            m.extras.quadratic_damping = 1e-3 * o.damping.abs().max(1e-9) / sv
        }
        Effect::CoulombFriction => {
            m.extras.coulomb = Some(Coulomb {
                force: 1e-3 * k * sx,
                smoothing_velocity: 0.05 * sv,
            })
        }
        // Started from the residual's peaks ([`second_mass_starts`]) and from the current
        // element ([`exponent_starts`]).
        Effect::SecondMode | Effect::HysteresisExponent => return None,
        Effect::Hysteresis => {
            if o.restoring != Restoring::None {
                return None;
            }
            let alpha = 0.2 * k;
            m.stiffness = 0.8 * o.stiffness;
            // βδ starts off zero: the fit scales each parameter by its start, and one that
            // starts at zero could not move.
            m.restoring =
                Restoring::BoucWen(BoucWen::from_products(alpha, 0.2 / sx, 0.02 / sx, 1.0));
        }
    }
    Some(m)
}

/// The Bouc-Wen element (ν = 1) to put in place of the Zener element `z` of `o`: for each
/// α on a grid of multiples of the Zener's stiffness K at the model's resonance ω, the
/// (βγ, βδ) whose describing function at amplitude A = σₓ equals the Zener's (K, ωC) there
/// ([`hyst_linearize::bouc_wen_exact`], to first order if that fails), and of those the one
/// whose simulated output is closest to the record. `None` when no α gives a model that
/// simulates.
fn bouc_wen_replacing(
    o: &Oscillator,
    z: &hyst_model::ZenerParams,
    sx: f64,
    rec: &Record<'_>,
    range: (usize, usize),
) -> Option<Oscillator> {
    let w = 2.0 * std::f64::consts::PI * resonance_hz(o);
    let df = hyst_linearize::zener_at(z, w, sx);
    // α is the element's stiffness at small amplitude, K its secant stiffness at A: a
    // hardening element (βδ < 0) has α below K, a softening one above.
    [0.4, 0.55, 0.7, 0.85, 1.0, 1.2, 1.5]
        .par_iter()
        .filter_map(|&ratio| {
            let alpha = ratio * df.stiffness;
            let bw = hyst_linearize::bouc_wen_exact(alpha, 1.0, &df)
                .or_else(|_| hyst_linearize::bouc_wen_first_order(alpha, 1.0, &df))
                .ok()?;
            let mut m = *o;
            m.restoring = Restoring::BoucWen(bw);
            m.validate().ok()?;
            let cost = sse(&residual(&m, rec, range)?);
            cost.is_finite().then_some((m, cost))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(m, _)| m)
}

/// Exponents the fit of [`Effect::HysteresisExponent`] starts from.
const EXPONENT_STARTS: [f64; 6] = [0.5, 0.8, 1.02, 1.25, 2.0, 3.0];

/// Starts for freeing the exponent of the Bouc-Wen element `b` of `o`: for each ν of
/// [`EXPONENT_STARTS`], the element with the same α whose describing function at A = σₓ
/// equals `b`'s ([`hyst_linearize::bouc_wen_exact`] with that ν), so that each start
/// dissipates and stiffens as the fitted model does at the record's amplitude and differs in
/// how the loop's shape changes with amplitude.
fn exponent_starts(o: &Oscillator, b: &BoucWen, sx: f64) -> Vec<Oscillator> {
    let Ok(df) = hyst_linearize::describing_function(b, sx) else {
        return Vec::new();
    };
    // Each inversion is independent (as in `bouc_wen_replacing`); the order is kept.
    EXPONENT_STARTS
        .par_iter()
        .filter_map(|&nu| {
            let bw = hyst_linearize::bouc_wen_exact(b.alpha, nu, &df).ok()?;
            let mut m = *o;
            m.restoring = Restoring::BoucWen(bw);
            m.validate().ok().map(|_| m)
        })
        .collect()
}

/// The start of a fit that adds the effect `e` to the base model, given `small` (the base
/// model with the effect at a small size) and the base model's residual `r0`. For a force
/// term linear in its coefficient: the least-squares projection of the residual `r0` on the
/// output's sensitivity to that coefficient — or better, when the model is a plain
/// oscillator, the equation-error fit of m ÿ + c ẏ + k y + θ g(y, ẏ) = u on the measured
/// record. A regression's start that simulates worse than `small` (the regression does not
/// minimise the output error) gives way to it, so that no candidate starts worse than the
/// model it extends.
fn regression_start(
    small: Oscillator,
    e: Effect,
    r0: &[f64],
    rec: &Record<'_>,
    range: (usize, usize),
    fit_mass: bool,
) -> Oscillator {
    let mut start = small;
    if let Some(eq) = equation_error_start(&start, Some(e), rec, range, fit_mass) {
        start = eq;
    } else if let Some(p) = linear_coefficient(e) {
        let theta = get(&start, p);
        // The base model's output is y − r0: no need to simulate it again.
        let y = &rec.y[range.0..range.1];
        if let (Some(y1), true) = (simulate(&start, rec, range), r0.len() == y.len()) {
            let sens: Vec<f64> = y1
                .iter()
                .zip(y.iter().zip(r0))
                .map(|(a, (yi, ri))| (a - (yi - ri)) / theta)
                .collect();
            let ss: f64 = sens.iter().map(|v| v * v).sum();
            if ss > 0.0 {
                let t = sens.iter().zip(r0).map(|(a, b)| a * b).sum::<f64>() / ss;
                if t.is_finite() && t != 0.0 {
                    set(&mut start, p, t);
                }
            }
        }
    }
    let cost = |m: &Oscillator| residual(m, rec, range).map_or(f64::INFINITY, |r| sse(&r));
    if start != small && cost(&start) > cost(&small) {
        small
    } else {
        start
    }
}

/// Try every candidate on `o` (already fitted, with residual sum of squares `c0`).
pub fn diagnose(
    o: &Oscillator,
    c0: f64,
    rec: &Record<'_>,
    range: (usize, usize),
    fit_mass: bool,
) -> (Vec<Evidence>, Spectrum) {
    let n = (range.1 - range.0) as f64;
    let y = &rec.y[range.0..range.1];
    let sx = (y.iter().map(|v| v * v).sum::<f64>() / n)
        .sqrt()
        .max(1e-300);
    let sv = sx * 2.0 * std::f64::consts::PI * resonance_hz(o).max(1e-6);
    let r0 = residual(o, rec, range).unwrap_or_default();
    let scan = power_scan(&r0, rec.fs);
    let spec = periodogram_peak(&scan, resonance_hz(o));
    let p0 = free(o, fit_mass).len();
    let ev = Effect::ALL
        .iter()
        .map(|&e| {
            let starts = match (e, o.restoring) {
                (Effect::Hysteresis, Restoring::Zener(z)) => bouc_wen_replacing(
                    o, &z, sx, rec, range,
                )
                .map(|m| vec![m])
                .ok_or("no Bouc-Wen element matching the Zener element simulates on the record"),
                (Effect::Hysteresis, Restoring::BoucWen(_)) => {
                    Err("the model already has a Bouc-Wen element")
                }
                (Effect::HysteresisExponent, Restoring::BoucWen(b)) if b.nu != 1.0 => {
                    Err("the Bouc-Wen element's exponent is free already")
                }
                (Effect::HysteresisExponent, Restoring::BoucWen(b)) => {
                    Ok(exponent_starts(o, &b, sx)).and_then(|v| {
                        (!v.is_empty())
                            .then_some(v)
                            .ok_or("no element of another exponent matches the current one")
                    })
                }
                (Effect::HysteresisExponent, _) => Err("the model has no Bouc-Wen element"),
                _ => match already_has(o, e) {
                    Some(why) => Err(why),
                    None if e == Effect::SecondMode => {
                        Ok(second_mass_starts(o, &scan)).and_then(|v| {
                            (!v.is_empty())
                                .then_some(v)
                                .ok_or("the residual has no peak")
                        })
                    }
                    None => with_effect(o, e, sx, sv)
                        .map(|m| vec![regression_start(m, e, &r0, rec, range, fit_mass)])
                        .ok_or("the effect does not apply"),
                },
            };
            let starts = match starts {
                Ok(v) => v,
                Err(why) => {
                    return Evidence {
                        effect: e,
                        variance_explained: 0.0,
                        delta_bic: f64::INFINITY,
                        model: None,
                        rejected: Some(why.into()),
                    };
                }
            };
            // Linear-in-coefficient effects start from a regression and converge in a few
            // iterations; a second mode or a hysteretic element starts far and needs more.
            let iterations = if linear_coefficient(e).is_some() {
                25
            } else {
                60
            };
            let mut best = fit_best_of(&starts, rec, range, fit_mass, iterations);
            // The exponent's candidate holds the base model itself (ν = 1): when the far
            // starts do not beat the base, also fit it from there, on the whole range where
            // the base is already at its optimum, so that the candidate never scores worse than
            // the model it extends (from the far starts alone a ν = 1 element's candidate ended
            // 0.3 % above it, at ν = 1 + 4e-12).
            let beaten = best.as_ref().is_some_and(|b| b.1 < c0);
            if let (Effect::HysteresisExponent, Restoring::BoucWen(b), false) =
                (e, o.restoring, beaten)
            {
                let mut near = *o;
                near.restoring = Restoring::BoucWen(BoucWen {
                    nu: 1.0 + 1e-9,
                    ..b
                });
                if let Some(f) = fit_window(&near, rec, range, fit_mass, iterations)
                    && best.as_ref().is_none_or(|b| f.1 < b.1)
                {
                    best = Some(f);
                }
            }
            let best = best.filter(|(_, c1)| c1.is_finite());
            match best {
                Some((m, c1)) => {
                    let dp = (free(&m, fit_mass).len() - p0) as f64;
                    let rejected = not_dissipating(e, &m);
                    Evidence {
                        effect: e,
                        variance_explained: 1.0 - c1 / c0,
                        delta_bic: n * (c1 / c0).ln() + dp * n.ln(),
                        model: rejected.is_none().then_some(m),
                        rejected,
                    }
                }
                _ => Evidence {
                    effect: e,
                    variance_explained: 0.0,
                    delta_bic: f64::INFINITY,
                    model: None,
                    rejected: Some("the fit diverged with this effect".into()),
                },
            }
        })
        .collect();
    (ev, spec)
}

/// One step of the loop.
#[derive(Debug, Clone, PartialEq)]
pub struct Step {
    /// The effect added, or `None` when nothing was significant.
    pub effect: Option<Effect>,
    /// Evidence for every candidate.
    pub evidence: Vec<Evidence>,
    /// Where the residual lay before this step.
    pub spectrum: Spectrum,
    /// Held-out errors (one per test range) before and after.
    pub before: Vec<Validation>,
    /// See `before`.
    pub after: Vec<Validation>,
}

/// The whole loop's result.
#[derive(Debug, Clone, PartialEq)]
pub struct Refinement {
    /// The baseline model after the output-error fit.
    pub baseline: Oscillator,
    /// Steps in order; the last has `effect: None` unless the step limit was reached.
    pub steps: Vec<Step>,
    /// The final model.
    pub model: Oscillator,
    /// Held-out errors of the final model.
    pub tests: Vec<Validation>,
    /// The final model's free parameters with their standard errors ([`standard_errors`];
    /// empty if they could not be computed).
    pub estimates: Vec<Estimate>,
}

/// Most iterations of the fits of the baseline and of each model the loop accepts: enough to
/// converge (the fit stops earlier when an iteration gains less than 1e-9 of the sum of
/// squares), so that each step's candidates are judged by what they add, not by what more
/// iterations of the model they extend would have given.
const CONVERGED_ITERATIONS: usize = 300;

/// ΔBIC below which an effect counts as significant (strong evidence).
pub const SIGNIFICANT_BIC: f64 = -10.0;

/// `start < end <= samples`, or the error that names the rows.
fn check_rows((start, end): (usize, usize), samples: usize) -> Result<(), IdentError> {
    if start < end && end <= samples {
        Ok(())
    } else {
        Err(IdentError::BadRows {
            start,
            end,
            samples,
        })
    }
}

/// Refine `start` on the estimation rows and report on the test rows.
///
/// Each step adds the candidate with the lowest ΔBIC below [`SIGNIFICANT_BIC`] that does not
/// make the held-out error worse on any test range; a significant candidate that does is
/// reported as rejected with the two errors, and the next one is tried. Without test ranges
/// the estimation rows alone decide.
pub fn refine(
    start: &Oscillator,
    rec: &Record<'_>,
    estimate: (usize, usize),
    tests: &[(usize, usize)],
    fit_mass: bool,
) -> Result<Refinement, IdentError> {
    if rec.u.len() != rec.y.len() {
        return Err(IdentError::LengthMismatch {
            input: rec.u.len(),
            output: rec.y.len(),
        });
    }
    for &range in std::iter::once(&estimate).chain(tests) {
        check_rows(range, rec.y.len())?;
    }
    let errs = |m: &Oscillator| -> Vec<Validation> {
        tests
            .iter()
            .map(|&r| {
                test_error(m, rec, r).unwrap_or(Validation {
                    epsilon: f64::INFINITY,
                    rms: f64::INFINITY,
                })
            })
            .collect()
    };
    // A plain oscillator's (m, c, k) also follow from the equation-error regression on the
    // record, which fixes the input gain at once; start the output-error fit from whichever
    // of the two starts simulates closer.
    let eq = equation_error_start(start, None, rec, estimate, fit_mass);
    let start = match eq {
        Some(e) => {
            let cost =
                |m: &Oscillator| residual(m, rec, estimate).map_or(f64::INFINITY, |r| sse(&r));
            if cost(&e) < cost(start) { e } else { *start }
        }
        None => *start,
    };
    let (mut model, mut c) = fit(&start, rec, estimate, fit_mass, CONVERGED_ITERATIONS).ok_or(
        IdentError::StartDiverges {
            start: estimate.0,
            end: estimate.1,
        },
    )?;
    let baseline = model;
    let mut steps = Vec::new();
    for _ in 0..3 {
        let (mut evidence, spectrum) = diagnose(&model, c, rec, estimate, fit_mass);
        let before = errs(&model);
        // Significant candidates, strongest first. Each is fitted to convergence (its fit in
        // `diagnose` stopped after a few iterations) and must then pass the held-out check;
        // the first that does is added.
        let mut order: Vec<usize> = (0..evidence.len())
            .filter(|&i| evidence[i].model.is_some() && evidence[i].delta_bic < SIGNIFICANT_BIC)
            .collect();
        order.sort_by(|&a, &b| evidence[a].delta_bic.total_cmp(&evidence[b].delta_bic));
        let mut added = None;
        for i in order {
            let Some(m) = evidence[i].model else { continue };
            let (m, c1) = fit(&m, rec, estimate, fit_mass, CONVERGED_ITERATIONS)
                .unwrap_or((m, c * (1.0 - evidence[i].variance_explained)));
            let after = errs(&m);
            if let Some(why) = held_out_worse(tests, &before, &after) {
                evidence[i].model = None;
                evidence[i].rejected = Some(why);
                continue;
            }
            added = Some((evidence[i].effect, m, c1, after));
            break;
        }
        match added {
            Some((e, m, c1, after)) => {
                c = c1;
                model = m;
                steps.push(Step {
                    effect: Some(e),
                    evidence,
                    spectrum,
                    before,
                    after,
                });
            }
            None => {
                let after = before.clone();
                steps.push(Step {
                    effect: None,
                    evidence,
                    spectrum,
                    before,
                    after,
                });
                break;
            }
        }
    }
    let tests_err = errs(&model);
    let estimates = standard_errors(&model, rec, estimate, fit_mass).unwrap_or_default();
    Ok(Refinement {
        baseline,
        steps,
        model,
        tests: tests_err,
        estimates,
    })
}

/// The held-out check a significant candidate must pass before it is added: its model,
/// fitted to convergence on the estimation rows, may not simulate worse than the current
/// model on any test range (a larger ε, eq. 39, or a simulation that diverges there). The
/// estimation rows alone cannot tell an effect that is there from one that fits their noise
/// or their particular trajectory; rows the fit never saw can. `Some(reason)` when it fails.
fn held_out_worse(
    tests: &[(usize, usize)],
    before: &[Validation],
    after: &[Validation],
) -> Option<String> {
    tests
        .iter()
        .zip(before.iter().zip(after))
        .find(|(_, (b, a))| a.epsilon > b.epsilon || (a.epsilon.is_nan() && !b.epsilon.is_nan()))
        .map(|(r, (b, a))| {
            format!(
                "held out: ε rose from {:.4} % to {:.4} % on rows {}:{}",
                100.0 * b.epsilon,
                100.0 * a.epsilon,
                r.0,
                r.1
            )
        })
}

/// Which model the loop starts from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Start {
    /// The linear oscillator from the dominant pole pair.
    #[default]
    Linear,
    /// The Zener oscillator (falls back to linear without a real pole).
    Zener,
    /// The Bouc-Wen oscillator (falls back as above).
    BoucWen,
}

/// The whole loop on a record: the output-only pipeline on the estimation rows gives the
/// starting model (mass 1 and fitted when `mass` is `None`), then [`refine`].
pub fn refine_record(
    rec: &Record<'_>,
    mass: Option<f64>,
    start: Start,
    estimate: (usize, usize),
    tests: &[(usize, usize)],
) -> Result<Refinement, IdentError> {
    if rec.u.len() != rec.y.len() {
        return Err(IdentError::LengthMismatch {
            input: rec.u.len(),
            output: rec.y.len(),
        });
    }
    check_rows(estimate, rec.y.len())?;
    let opts = crate::IdentOptions {
        mass: mass.unwrap_or(1.0),
        ..crate::IdentOptions::default()
    };
    let id = crate::identify(&rec.y[estimate.0..estimate.1], rec.fs, &opts)?;
    let m = match start {
        Start::Linear => id.models.linear,
        Start::Zener => id.models.zener.unwrap_or(id.models.linear),
        Start::BoucWen => id.models.bouc_wen.unwrap_or(id.models.linear),
    };
    refine(&m, rec, estimate, tests, mass.is_none())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A candidate fitted with the sign that feeds energy in is rejected, and the evidence
    /// says so. The record is made with negative quadratic damping, so that the equation-error
    /// start of quadratic damping is strongly negative: its simulation explodes (once the
    /// candidate's fit diverged here), the fit starts from the small coefficient instead and
    /// follows the record to a negative one, which no damper has.
    #[test]
    fn an_effect_that_feeds_energy_in_is_rejected_with_the_reason() {
        let fs = 100.0;
        let n = 4000;
        let w = 2.0 * std::f64::consts::PI * 2.0;
        let (m, c, k, q) = (1.0, 1.0, w * w, 50.0);
        let t = |i: usize| i as f64 / fs;
        let y: Vec<f64> = (0..n).map(|i| 0.1 * (w * t(i)).sin()).collect();
        let u: Vec<f64> = (0..n)
            .map(|i| {
                let (x, v, a) = (
                    0.1 * (w * t(i)).sin(),
                    0.1 * w * (w * t(i)).cos(),
                    -0.1 * w * w * (w * t(i)).sin(),
                );
                m * a + c * v + k * x - q * v * v.abs()
            })
            .collect();
        let rec = Record {
            u: &u,
            y: &y,
            fs,
            interpolation: InputInterpolation::Linear,
        };
        let base = Oscillator::linear(m, c, k);
        let c0 = sse(&residual(&base, &rec, (0, n)).expect("the linear model is stable"));
        let (evidence, _) = diagnose(&base, c0, &rec, (0, n), false);
        let quad = evidence
            .iter()
            .find(|e| e.effect == Effect::QuadraticDamping)
            .expect("every candidate is reported");
        assert!(
            quad.rejected
                .as_deref()
                .is_some_and(|r| r.starts_with("the fitted quadratic damping is -")
                    && r.ends_with("≤ 0: it feeds energy in")),
            "{quad:?}"
        );
        assert!(quad.model.is_none());
    }

    /// Rows that are no range within the record are named, whichever of the estimation or
    /// test ranges they are; so is a start that no fit can follow.
    #[test]
    fn bad_rows_and_a_diverging_start_are_named() {
        let fs = 100.0;
        let n = 400;
        let u: Vec<f64> = (0..n).map(|i| (0.3 * i as f64).sin()).collect();
        let y: Vec<f64> = (0..n).map(|i| 1e-3 * (0.3 * i as f64).cos()).collect();
        let rec = Record {
            u: &u,
            y: &y,
            fs,
            interpolation: InputInterpolation::Linear,
        };
        let base = Oscillator::linear(1.0, 1.0, 100.0);
        for (estimate, tests, bad) in [
            ((50, 10), &[][..], (50, 10)),
            ((0, 401), &[], (0, 401)),
            ((0, 200), &[(300, 300)], (300, 300)),
        ] {
            assert_eq!(
                refine(&base, &rec, estimate, tests, false).unwrap_err(),
                IdentError::BadRows {
                    start: bad.0,
                    end: bad.1,
                    samples: n
                }
            );
        }
        // Hysteresis with γ, δ < 0 feeds energy in: ż grows with |z|·z and the simulation
        // blows up within the record, from the start and from every step of the fit.
        let wild = Oscillator::bouc_wen(
            1.0,
            1.0,
            100.0,
            hyst_model::BoucWen::from_products(100.0, -1e9, -1e9, 1.0),
        );
        assert!(residual(&wild, &rec, (0, n)).is_none());
        assert_eq!(
            refine(&wild, &rec, (0, n), &[], false).unwrap_err(),
            IdentError::StartDiverges { start: 0, end: n }
        );
    }

    /// The held-out check fails on the first test range where the candidate is worse or
    /// diverges, and says where and by how much; equal errors, or a range where both
    /// diverge, pass.
    #[test]
    fn the_held_out_check_names_the_range_that_got_worse() {
        let v = |e: f64| Validation { epsilon: e, rms: e };
        let tests = [(10, 20), (30, 40)];
        assert_eq!(held_out_worse(&[], &[], &[]), None);
        assert_eq!(
            held_out_worse(&tests, &[v(0.02), v(0.03)], &[v(0.01), v(0.03)]),
            None
        );
        assert_eq!(
            held_out_worse(&tests, &[v(0.02), v(0.03)], &[v(0.01), v(0.031)]).as_deref(),
            Some("held out: ε rose from 3.0000 % to 3.1000 % on rows 30:40")
        );
        let inf = f64::INFINITY;
        assert!(held_out_worse(&tests, &[v(0.02), v(0.03)], &[v(inf), v(0.01)]).is_some());
        assert!(held_out_worse(&tests, &[v(0.02), v(0.03)], &[v(f64::NAN), v(0.01)]).is_some());
        assert_eq!(
            held_out_worse(&tests, &[v(inf), v(0.03)], &[v(inf), v(0.02)]),
            None
        );
    }

    /// The loop names an effect only if the fitted model has it: a dissipative effect fitted
    /// with the sign that feeds energy in is no such effect, and no effect is added twice.
    #[test]
    fn effects_are_named_only_when_the_model_has_them() {
        let bw = |bg: f64| {
            Oscillator::bouc_wen(1.0, 1.0, 1e3, BoucWen::from_products(1e3, bg, -1.0, 1.0))
        };
        assert!(not_dissipating(Effect::Hysteresis, &bw(5.0)).is_none());
        let why = not_dissipating(Effect::Hysteresis, &bw(-0.003)).unwrap();
        assert!(why.contains("does not dissipate"), "{why}");
        let mut o = Oscillator::linear(1.0, 1.0, 1e3);
        o.extras.coulomb = Some(Coulomb {
            force: -1.0,
            smoothing_velocity: 0.1,
        });
        assert!(not_dissipating(Effect::CoulombFriction, &o).is_some());
        o.extras.coulomb = Some(Coulomb {
            force: 1.0,
            smoothing_velocity: 0.1,
        });
        assert!(not_dissipating(Effect::CoulombFriction, &o).is_none());
        assert_eq!(
            already_has(&o, Effect::CoulombFriction),
            Some("the model already has Coulomb friction")
        );
        assert_eq!(already_has(&o, Effect::CubicStiffness), None);
    }
}
