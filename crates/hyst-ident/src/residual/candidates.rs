//! The candidate effects: their starts, their fits and the evidence for each.

use hyst_model::{BoucWen, Clearance, Coulomb, Oscillator, Restoring, SecondMass};
use rayon::prelude::*;

use super::Effect;
use super::fit::{Prepared, fit_best_of, fit_window, residual, simulate, sse};
use super::heldout::HeldOutGain;
use super::params::{P, free, get, positive, set};
use super::surface::Trace;
use crate::solve;

/// Where the residual's power lies.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Spectrum {
    /// Frequency of the residual's largest spectral peak (Hz).
    pub peak_hz: f64,
    /// Share of the residual power above 1.5× the model's resonance.
    pub above_resonance: f64,
    /// The model's resonance (Hz).
    pub resonance_hz: f64,
}

/// The residual's power at 511 frequencies evenly spaced on (0, fs/2), (Hz, power): a coarse
/// DFT scan (of at most its first 16384 samples) is enough to locate it. The frequencies are
/// p·fs/1024, so they are bins of the FFT of the samples zero-padded to a multiple of 1024
/// (the same sums as the DFT at those frequencies).
pub(super) fn power_scan(r: &[f64], fs: f64) -> Vec<(f64, f64)> {
    let n = r.len().min(16384);
    let padded_len = 1024 * n.div_ceil(1024).max(1);
    let mut padded = vec![0.0; padded_len];
    padded[..n].copy_from_slice(&r[..n]);
    let spectrum = crate::fft::rfft(&padded);
    let per = padded_len / 1024;
    (1..512)
        .map(|p| (fs / 2.0 * p as f64 / 512.0, spectrum[p * per].norm_sqr()))
        .collect()
}

pub(super) fn periodogram_peak(scan: &[(f64, f64)], resonance_hz: f64) -> Spectrum {
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
pub(super) fn second_mass_starts(o: &Oscillator, scan: &[(f64, f64)]) -> Vec<Oscillator> {
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
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Evidence {
    /// The candidate.
    pub effect: Effect,
    /// Share of the residual variance the refitted model explains.
    #[cfg_attr(feature = "serde", serde(with = "crate::nullable"))]
    pub variance_explained: f64,
    /// Change of the BIC (negative favours the effect).
    #[cfg_attr(feature = "serde", serde(with = "crate::nullable"))]
    pub delta_bic: f64,
    /// The refitted model, unless the fit diverged or the candidate was rejected.
    pub model: Option<Oscillator>,
    /// Why the candidate was not considered, or was rejected after its fit, if so.
    pub rejected: Option<String>,
    /// Its fit to convergence against the current model on the test rows, when it was
    /// significant enough to be tried there.
    pub held_out: Option<HeldOutGain>,
}

pub(super) fn resonance_hz(o: &Oscillator) -> f64 {
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
pub(super) fn equation_error_start(
    start: &Oscillator,
    e: Option<Effect>,
    rec: &super::Record<'_>,
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
        Some(Effect::QuadraticStiffness) => x * x,
        Some(Effect::Offset) => 1.0,
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
        // No coefficient, or one of the sign physics forbids (negative damping or
        // friction): the regression has no start to give.
        if x[off + 2] == 0.0 || (positive(p) && x[off + 2] < 0.0) {
            return None;
        }
        set(&mut m, p, x[off + 2]);
    }
    m.validate().is_ok().then_some(m)
}

/// The coefficient of an effect whose force is linear in it.
pub(super) fn linear_coefficient(e: Effect) -> Option<P> {
    match e {
        Effect::CubicStiffness => Some(P::Cubic),
        Effect::QuadraticStiffness => Some(P::QuadStiffness),
        Effect::Offset => Some(P::Offset),
        Effect::QuadraticDamping => Some(P::Quad),
        Effect::CoulombFriction => Some(P::Coulomb),
        _ => None,
    }
}

/// Why the fitted `m` does not have the effect `e` it was fitted with, if it does not: the
/// dissipative effects must dissipate. A Bouc-Wen element with βγ ≤ 0 loses no energy (its
/// describing function's loss is 4αβγA/3π to first order) and is a nonlinear spring, not
/// hysteresis; friction or quadratic damping with a coefficient ≤ 0 feeds energy in.
pub(super) fn not_dissipating(e: Effect, m: &Oscillator) -> Option<String> {
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
pub(super) fn already_has(o: &Oscillator, effect: Effect) -> Option<&'static str> {
    let x = &o.extras;
    match effect {
        Effect::CubicStiffness if x.cubic_stiffness != 0.0 => {
            Some("the model already has a cubic spring")
        }
        Effect::QuadraticStiffness if x.quadratic_stiffness != 0.0 => {
            Some("the model already has a quadratic spring")
        }
        Effect::Clearance if x.clearance.is_some() => {
            Some("the model already has a clearance spring")
        }
        Effect::RestoringSurface if x.surface.is_some() => {
            Some("the model already has a force surface")
        }
        Effect::QuadraticDamping if x.quadratic_damping != 0.0 => {
            Some("the model already has quadratic damping")
        }
        Effect::CoulombFriction if x.coulomb.is_some() => {
            Some("the model already has Coulomb friction")
        }
        Effect::Offset if x.offset != 0.0 => Some("the model already has an offset"),
        Effect::SecondMode if x.second_mass.is_some() => {
            Some("the model already has a second mass (one is supported)")
        }
        Effect::OutputDelay if o.chain.is_some_and(|c| c.delay != 0.0) => {
            Some("the model already has an output delay")
        }
        Effect::SensorLag if o.chain.is_some_and(|c| c.lag != 0.0) => {
            Some("the model already has a sensor lag")
        }
        _ => None,
    }
}

/// Add `effect` to `o` with a starting value sized from the record (σ of x and ẋ).
pub(super) fn with_effect(o: &Oscillator, effect: Effect, sx: f64, sv: f64) -> Option<Oscillator> {
    let mut m = *o;
    let k = o.stiffness.abs().max(1e-12);
    match effect {
        Effect::CubicStiffness => m.extras.cubic_stiffness = 1e-3 * k / (sx * sx),
        Effect::QuadraticStiffness => m.extras.quadratic_stiffness = 1e-3 * k / sx,
        Effect::Offset => m.extras.offset = 1e-3 * k * sx,
        Effect::QuadraticDamping => {
            m.extras.quadratic_damping = 1e-3 * o.damping.abs().max(1e-9) / sv
        }
        Effect::CoulombFriction => {
            m.extras.coulomb = Some(Coulomb {
                force: 1e-3 * k * sx,
                smoothing_velocity: 0.05 * sv,
            })
        }
        // Started from the residual's peaks ([`second_mass_starts`]), from the current
        // element ([`exponent_starts`]), and from the missing force ([`clearance_starts`],
        // [`surface_start`]).
        Effect::SecondMode
        | Effect::HysteresisExponent
        | Effect::Clearance
        | Effect::RestoringSurface
        | Effect::OutputDelay
        | Effect::SensorLag => return None,
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

/// The start of a measurement chain's delay or lag (`e`) on `o`: to first order both make
/// the output $\hat y(t) - d\,\dot{\hat y}(t)$, so the residual `r0` regressed on the model
/// output's rate gives d (or τ) $= -\langle r, \dot{\hat y}\rangle / \langle\dot{\hat y},
/// \dot{\hat y}\rangle$. A residual that leads the output (d ≤ 0) has no causal chain to
/// start.
pub(super) fn chain_start(
    o: &Oscillator,
    e: Effect,
    r0: &[f64],
    rec: &Prepared<'_>,
    range: (usize, usize),
) -> Result<Oscillator, &'static str> {
    let y = &rec.y[range.0..range.1];
    if r0.len() != y.len() || y.len() < 3 {
        return Err("the model does not simulate on the record");
    }
    let yhat: Vec<f64> = y.iter().zip(r0).map(|(y, r)| y - r).collect();
    let (mut num, mut den) = (0.0, 0.0);
    for i in 1..yhat.len() - 1 {
        let rate = 0.5 * (yhat[i + 1] - yhat[i - 1]) * rec.fs;
        num -= r0[i] * rate;
        den += rate * rate;
    }
    let d = num / den;
    if !(d.is_finite() && d > 0.0) {
        return Err("the residual does not lag the model's output (no causal chain to start)");
    }
    let mut m = *o;
    let mut c = o.chain.unwrap_or_default();
    if e == Effect::OutputDelay {
        c.delay = d;
    } else {
        c.lag = d;
    }
    m.chain = Some(c);
    Ok(m)
}

/// The Bouc-Wen element (ν = 1) to put in place of the Zener element `z` of `o`: for each
/// α on a grid of multiples of the Zener's stiffness K at the model's resonance ω, the
/// (βγ, βδ) whose describing function at amplitude A = σₓ equals the Zener's (K, ωC) there
/// ([`hyst_linearize::bouc_wen_exact`], to first order if that fails), and of those the one
/// whose simulated output is closest to the record. `None` when no α gives a model that
/// simulates.
pub(super) fn bouc_wen_replacing(
    o: &Oscillator,
    z: &hyst_model::ZenerParams,
    sx: f64,
    rec: &Prepared<'_>,
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
pub(super) fn exponent_starts(o: &Oscillator, b: &BoucWen, sx: f64) -> Vec<Oscillator> {
    let pairs: Vec<(f64, f64)> = EXPONENT_STARTS.iter().map(|&nu| (1.0, nu)).collect();
    matched_elements(o, b, sx, &pairs)
}

/// Multiples of α of the other starts of a Bouc-Wen model's fit ([`alpha_starts`]).
const ALPHA_STARTS: [f64; 4] = [0.5, 0.7, 1.4, 2.0];

/// Other starts for the output-error fit of a model with the Bouc-Wen element `b`: the
/// elements of the same ν with α on [`ALPHA_STARTS`] times `b`'s whose describing function
/// at A = σₓ equals `b`'s. A start from the output-only pipeline dissipates and stiffens as
/// the record does at its amplitude but may split the stiffness between k and α wrongly, a
/// local optimum of the output error that these starts avoid.
pub(super) fn alpha_starts(o: &Oscillator, b: &BoucWen, sx: f64) -> Vec<Oscillator> {
    let pairs: Vec<(f64, f64)> = ALPHA_STARTS.iter().map(|&a| (a, b.nu)).collect();
    let mut v = matched_elements(o, b, sx, &pairs);
    // The element's stiffness moved to α or back: keep the total small-amplitude stiffness.
    for m in &mut v {
        if let Restoring::BoucWen(n) = m.restoring {
            m.stiffness = o.stiffness + b.alpha - n.alpha;
        }
    }
    v
}

/// For each (α ratio, ν) of `pairs`, the element of exponent ν and α = ratio·α(b) whose
/// describing function at A = σₓ equals `b`'s ([`hyst_linearize::bouc_wen_exact`]), in `o`
/// in place of `b`; pairs that cannot be matched are left out.
fn matched_elements(o: &Oscillator, b: &BoucWen, sx: f64, pairs: &[(f64, f64)]) -> Vec<Oscillator> {
    let Ok(df) = hyst_linearize::describing_function(b, sx) else {
        return Vec::new();
    };
    // Each inversion is independent (as in `bouc_wen_replacing`); the order is kept.
    pairs
        .par_iter()
        .filter_map(|&(ratio, nu)| {
            let bw = hyst_linearize::bouc_wen_exact(ratio * b.alpha, nu, &df).ok()?;
            let mut m = *o;
            m.restoring = Restoring::BoucWen(bw);
            m.validate().ok().map(|_| m)
        })
        .collect()
}

/// Gaps of the clearance starts, in units of σₓ.
const CLEARANCE_GAPS: [f64; 4] = [0.5, 1.0, 1.5, 2.0];

/// Starts for a clearance spring: for each gap of [`CLEARANCE_GAPS`], the spring whose force
/// k_g dz_g(x) best fits the missing force along the measured motion (with k and c free
/// beside it, so that the linear part of the missing force does not leak into k_g). A gap
/// whose spring comes out negative (a softening stop) is skipped.
pub(super) fn clearance_starts(o: &Oscillator, trace: &Trace, sx: f64) -> Vec<Oscillator> {
    let k = &trace.kinematics;
    CLEARANCE_GAPS
        .iter()
        .filter_map(|&ratio| {
            let g = Clearance {
                stiffness: 1.0,
                gap: ratio * sx,
            };
            let mut a = vec![vec![0.0; 3]; 3];
            let mut b = vec![0.0; 3];
            for ((x, v), r) in k.x.iter().zip(&k.v).zip(&trace.force) {
                let row = [*x, *v, g.force(*x)];
                for i in 0..3 {
                    b[i] += row[i] * r;
                    for j in 0..3 {
                        a[i][j] += row[i] * row[j];
                    }
                }
            }
            let c = solve(a, b)?;
            if c[2].is_nan() || c[2] <= 0.0 {
                return None;
            }
            let mut m = *o;
            m.stiffness += c[0];
            m.extras.clearance = Some(Clearance {
                stiffness: c[2],
                gap: g.gap,
            });
            m.validate().ok().map(|_| m)
        })
        .collect()
}

/// The start of the surface candidate: the model with the terms of the missing force's
/// surface that the trace found present (at most [`SURFACE_CANDIDATE_TERMS`]), and the
/// corrections to k and c fitted beside them. `None` when no term is present.
pub(super) fn surface_start(o: &Oscillator, trace: &Trace) -> Option<Oscillator> {
    let fit = trace.fit.as_ref()?;
    let s = fit.significant_surface(SURFACE_CANDIDATE_TERMS)?;
    let mut m = *o;
    m.stiffness += fit.linear[0] / s.x_scale;
    m.damping = (m.damping + fit.linear[1] / s.v_scale).max(0.0);
    m.extras.surface = Some(s);
    m.validate().ok().map(|_| m)
}

/// Most terms of the surface candidate.
pub const SURFACE_CANDIDATE_TERMS: usize = 4;

/// The start of a fit that adds the effect `e` to the base model, given `small` (the base
/// model with the effect at a small size) and the base model's residual `r0`. For a force
/// term linear in its coefficient: the least-squares projection of the residual `r0` on the
/// output's sensitivity to that coefficient — or better, when the model is a plain
/// oscillator, the equation-error fit of m ÿ + c ẏ + k y + θ g(y, ẏ) = u on the measured
/// record. A regression's start that simulates worse than `small` (the regression does not
/// minimise the output error) gives way to it, so that no candidate starts worse than the
/// model it extends.
pub(super) fn regression_start(
    small: Oscillator,
    e: Effect,
    r0: &[f64],
    rec: &Prepared<'_>,
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
                if t.is_finite() && t != 0.0 && !(positive(p) && t < 0.0) {
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

/// Try every candidate on `o` (already fitted, with residual sum of squares `c0`); `trace`,
/// the missing force along the measured motion, starts the clearance and the surface.
pub fn diagnose(
    o: &Oscillator,
    c0: f64,
    rec: &super::Record<'_>,
    range: (usize, usize),
    fit_mass: bool,
    trace: Option<&Trace>,
) -> (Vec<Evidence>, Spectrum) {
    diagnose_on(o, c0, &Prepared::new(rec), range, fit_mass, trace)
}

/// What the candidates of one step are fitted on.
#[derive(Clone, Copy)]
struct Candidates<'a> {
    /// The current model.
    o: &'a Oscillator,
    /// The output's RMS and a velocity scale (its RMS times the resonance's ω).
    sx: f64,
    sv: f64,
    rec: &'a Prepared<'a>,
    range: (usize, usize),
    fit_mass: bool,
    /// The current model's trace, when it was made.
    trace: Option<&'a Trace>,
    /// The current model's residual on `range`.
    residual: &'a [f64],
    /// Its power scan ([`power_scan`]).
    scan: &'a [(f64, f64)],
}

/// The starts of the effect `e`'s fit from the current model, or why it is not a candidate.
fn candidate_starts(e: Effect, ctx: &Candidates<'_>) -> Result<Vec<Oscillator>, &'static str> {
    let Candidates {
        o,
        sx,
        sv,
        rec,
        range,
        fit_mass,
        trace,
        residual: r0,
        scan,
    } = *ctx;
    match (e, o.restoring) {
        (Effect::Hysteresis, Restoring::Zener(z)) => {
            let mut v: Vec<Oscillator> = bouc_wen_replacing(o, &z, sx, rec, range)
                .into_iter()
                .collect();
            // A Zener element the fit has all but removed (k∞ → 0 on its log scale: 4e-10 N/m
            // on an independently made ν = 2 record) matches only a vanishing element: the
            // element is also started as on a model without one.
            let bare = Oscillator {
                restoring: Restoring::None,
                ..*o
            };
            v.extend(with_effect(&bare, e, sx, sv));
            (!v.is_empty())
                .then_some(v)
                .ok_or("no Bouc-Wen element matching the Zener element simulates on the record")
        }
        (Effect::Hysteresis, Restoring::BoucWen(_)) => {
            Err("the model already has a Bouc-Wen element")
        }
        (Effect::HysteresisExponent, Restoring::BoucWen(b)) if b.nu != 1.0 => {
            Err("the Bouc-Wen element's exponent is free already")
        }
        (Effect::HysteresisExponent, Restoring::BoucWen(b)) => Ok(exponent_starts(o, &b, sx))
            .and_then(|v| {
                (!v.is_empty())
                    .then_some(v)
                    .ok_or("no element of another exponent matches the current one")
            }),
        (Effect::HysteresisExponent, _) => Err("the model has no Bouc-Wen element"),
        _ => match already_has(o, e) {
            Some(why) => Err(why),
            None if e == Effect::Clearance => trace
                .map(|t| clearance_starts(o, t, sx))
                .filter(|v| !v.is_empty())
                .ok_or("no clearance spring fits the missing force"),
            None if e == Effect::RestoringSurface => trace
                .and_then(|t| surface_start(o, t))
                .map(|m| vec![m])
                .ok_or("the missing force's surface has no term present"),
            None if e.is_measurement_chain() => chain_start(o, e, r0, rec, range).map(|m| vec![m]),
            None if e == Effect::SecondMode => Ok(second_mass_starts(o, scan)).and_then(|v| {
                (!v.is_empty())
                    .then_some(v)
                    .ok_or("the residual has no peak")
            }),
            None => with_effect(o, e, sx, sv)
                .map(|m| vec![regression_start(m, e, r0, rec, range, fit_mass)])
                .ok_or("the effect does not apply"),
        },
    }
}

pub(super) fn diagnose_on(
    o: &Oscillator,
    c0: f64,
    rec: &Prepared<'_>,
    range: (usize, usize),
    fit_mass: bool,
    trace: Option<&Trace>,
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
    let ctx = Candidates {
        o,
        sx,
        sv,
        rec,
        range,
        fit_mass,
        trace,
        residual: &r0,
        scan: &scan,
    };
    // The candidates are fitted in parallel, each fit's simulations in lockstep batches.
    let ev = Effect::ALL
        .par_iter()
        .map(|&e| {
            let starts = candidate_starts(e, &ctx);
            let starts = match starts {
                Ok(v) => v,
                Err(why) => {
                    return Evidence {
                        effect: e,
                        variance_explained: 0.0,
                        delta_bic: f64::INFINITY,
                        model: None,
                        rejected: Some(why.into()),
                        held_out: None,
                    };
                }
            };
            // Linear-in-coefficient effects start from a regression and converge in a few
            // iterations; a second mode or a hysteretic element starts far and needs more.
            let iterations = if linear_coefficient(e).is_some() || e.is_measurement_chain() {
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
                        held_out: None,
                    }
                }
                _ => Evidence {
                    effect: e,
                    variance_explained: 0.0,
                    delta_bic: f64::INFINITY,
                    model: None,
                    rejected: Some("the fit diverged with this effect".into()),
                    held_out: None,
                },
            }
        })
        .collect();
    (ev, spec)
}

#[cfg(test)]
mod tests {
    /// The FFT's scan against the DFT with a sine and cosine per sample: the same power to
    /// 1e-10 of the largest (both sum the same terms; they round differently).
    #[test]
    fn the_scan_is_the_direct_dft() {
        let n = 20000;
        let r: Vec<f64> = (0..n)
            .map(|k| (0.37 * k as f64).sin() + 0.2 * ((k * k % 97) as f64 - 48.0) / 48.0)
            .collect();
        let fs = 750.0;
        // A long record (its first 16384 samples scanned) and one of no multiple of 1024.
        for (len, used) in [(n, 16384), (3000, 3000)] {
            let scan = super::power_scan(&r[..len], fs);
            let top = scan.iter().fold(0.0f64, |a, p| a.max(p.1));
            for &(f, p) in &scan {
                let w = 2.0 * std::f64::consts::PI * f / fs;
                let (mut re, mut im) = (0.0, 0.0);
                for (k, v) in r[..used].iter().enumerate() {
                    let (s, c) = (w * k as f64).sin_cos();
                    re += v * c;
                    im -= v * s;
                }
                let direct = re * re + im * im;
                assert!(
                    (p - direct).abs() <= 1e-10 * top,
                    "{len}: {f} Hz: {p} vs {direct}"
                );
            }
        }
    }
}
