//! Equivalent linearization of Bouc-Wen hysteresis by a Zener relaxation element: the paper's
//! relations ([`paper`]) and the ones that hold, checked against each other by property tests.
//!
//! # What holds
//!
//! **Poles → (k, k∞, Ω).** The Zener oscillator (eq. 25) has the characteristic polynomial
//! (eq. 32, sign flipped) $m\lambda^3 + (\Omega m + c)\lambda^2 + (\Omega c + k + k_\infty)\lambda + k\Omega$.
//! Matching its coefficients with $m\prod(\lambda-\lambda_i)$ gives, with
//! $s_1 = -\sum\lambda_i$, $s_2 = \sum_{i<j}\lambda_i\lambda_j$, $s_3 = -\prod\lambda_i$:
//! $\Omega = s_1 - c/m$, $k = m s_3/\Omega$, $k_\infty = m s_2 - \Omega c - k$
//! ([`zener_from_poles`]). The paper's eqs. (33)–(34) agree; eq. (35) has the wrong sign.
//!
//! **Describing function.** Drive $\dot z$ of eq. (2) with $x = A\cos\theta$. Because
//! $\dot z = \dot x\,g(z, \operatorname{sgn}\dot x)$, the loop $z(x)$ does not depend on the
//! frequency (Bouc-Wen is rate-independent). The periodic loop is odd:
//! $z(\theta+\pi) = -z(\theta)$, so it is found by shooting over half a cycle (where
//! $\dot x$ keeps its sign and the right-hand side is smooth, so RK4 converges at fourth order)
//! and its first harmonic $z_1 = K_{eq}x + C_{eq}\dot x$ by Simpson's rule:
//! $K_{eq} = \frac{1}{\pi A}\oint z\cos\theta\,d\theta$ and the loss stiffness
//! $\omega C_{eq} = -\frac{1}{\pi A}\oint z\sin\theta\,d\theta$ ([`describing_function`]).
//! To first order in the nonlinearity ($z = \alpha x + z_1$, so $|z|^\nu \approx (\alpha|x|)^\nu$):
//! $K_{eq} \approx \alpha - \tfrac{2}{\pi}B(\tfrac32, \tfrac{\nu+1}{2})\,\beta\delta\,(\alpha A)^\nu$
//! and $\omega C_{eq} \approx \tfrac{4}{\pi(\nu+2)}\,\beta\gamma\,(\alpha A)^\nu$, B the Beta
//! function; for ν = 1, $K_{eq} \approx \alpha\,(1 - \tfrac{4\beta\delta A}{3\pi})$ and
//! $\omega C_{eq} \approx \tfrac{4\alpha\beta\gamma A}{3\pi}$
//! ([`describing_function_first_order`]): the loss depends on βγ only, the stiffness change on
//! βδ only, and at small amplitude the loss stiffness grows as $A^\nu$. The loss follows from
//! the energy: $\oint z\,dx = -\oint x\,dz$, of which only the γ term survives, giving
//! $4\beta\gamma\alpha^\nu\int_0^A x^{\nu+1}dx$ per cycle.
//!
//! **Zener matching.** A Zener element has, at frequency ω,
//! $K = k_\infty\frac{\omega^2}{\Omega^2+\omega^2}$ and $\omega C = k_\infty\frac{\omega\Omega}{\Omega^2+\omega^2}$;
//! it matches a given $(K, \omega C)$ exactly at ω with $\Omega = \omega^2 C/K$ and
//! $k_\infty = K(1 + (\omega C/K)^2)$ ([`zener_matching`], inverse [`zener_at`]).
//!
//! **Back to Bouc-Wen.** One amplitude gives two numbers $(K, \omega C)$ for three unknowns
//! (α, βγ, βδ), so α must come from elsewhere (the paper: eq. 37). Given α:
//! closed form to first order (ν = 1: $\beta\delta = \frac{3\pi}{4A}(1 - K/\alpha)$,
//! $\beta\gamma = \frac{3\pi\,\omega C}{4\alpha A}$; any ν: the two expressions above
//! solved for βδ and βγ) ([`bouc_wen_first_order`]), or the exact numerical inversion of the
//! describing function by Newton's method ([`bouc_wen_exact`]), ν given with α.
//!
//! **Energy per cycle.** $\oint z\,dx = \pi A^2\,\omega C_{eq}$: only the first harmonic
//! dissipates, so a Zener element matched to the describing function dissipates exactly the
//! Bouc-Wen loop's energy at every amplitude ([`loop_energy_bouc_wen`], [`loop_energy_zener`]).

#![warn(missing_docs)]

pub mod paper;
pub mod statistical;

use hyst_model::{BoucWen, ZenerParams};
use nalgebra::Complex;

/// Errors of linearization.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum LinearizeError {
    /// The amplitude is not a positive finite number.
    #[error("amplitude must be > 0, got {amplitude}")]
    NonPositiveAmplitude {
        /// The amplitude (m).
        amplitude: f64,
    },
    /// The frequency is not a positive finite number.
    #[error("angular frequency must be > 0, got {omega} rad/s")]
    NonPositiveFrequency {
        /// The frequency (rad/s).
        omega: f64,
    },
    /// The poles hold no complex-conjugate (oscillating) pair.
    #[error("the poles {poles} hold no oscillating (complex-conjugate) pair")]
    NoOscillatingPair {
        /// The poles, formatted.
        poles: String,
    },
    /// The mapping gave a corner frequency Ω ≤ 0, which is no dissipative Zener element.
    #[error(
        "the mapping gives a corner frequency Ω = {omega} rad/s ≤ 0 (the poles' sum −{sum} is below c/m = {c_over_m}): no dissipative Zener element matches"
    )]
    NonPositiveOmega {
        /// The Ω obtained.
        omega: f64,
        /// −(λ₁+λ₂+λ₃).
        sum: f64,
        /// c/m.
        c_over_m: f64,
    },
    /// The statistical linearization gives a Zener element that adds energy on average.
    #[error(
        "the statistical linearization gives Ω = {omega} rad/s ≤ 0 (βγ + ρβδ ≤ 0): the element adds energy on average, no Zener element matches"
    )]
    NonDissipative {
        /// The Ω obtained.
        omega: f64,
    },
    /// Fewer force levels than the three unknowns (α, βγ, βδ) need.
    #[error("{levels} level(s) given: two or more are needed for α, βγ and βδ")]
    TooFewLevels {
        /// Levels given.
        levels: usize,
    },
    /// Fewer force levels than fitting ν beside α, βγ and βδ needs.
    #[error("{levels} level(s) given: three or more are needed to fit the exponent ν too")]
    TooFewLevelsForExponent {
        /// Levels given.
        levels: usize,
    },
    /// The levels' equations do not separate α, βγ and βδ (the same moments twice, say).
    #[error(
        "the levels do not determine α, βγ and βδ: their scaled normal matrix has smallest eigenvalue {smallest_eigenvalue:.3e}"
    )]
    LevelsDegenerate {
        /// Smallest eigenvalue of the normal matrix scaled to a unit diagonal.
        smallest_eigenvalue: f64,
    },
    /// The describing function has no positive stiffness to match.
    #[error("equivalent stiffness K = {stiffness} ≤ 0: no Zener element matches")]
    NonPositiveStiffness {
        /// K.
        stiffness: f64,
    },
    /// A parameter is not finite or out of range.
    #[error("parameter `{name}` is invalid: {value}")]
    Invalid {
        /// Name.
        name: &'static str,
        /// Value.
        value: f64,
    },
    /// The hysteresis loop diverged (z unbounded at this amplitude).
    #[error("the Bouc-Wen loop diverges at amplitude {amplitude} m (z reached {z})")]
    LoopDiverges {
        /// Amplitude (m).
        amplitude: f64,
        /// The value z reached.
        z: f64,
    },
    /// Newton's method did not converge.
    #[error("the inversion did not converge after {iterations} iterations (residual {residual})")]
    NoConvergence {
        /// Iterations done.
        iterations: usize,
        /// Final relative residual.
        residual: f64,
    },
}

/// Bouc-Wen parameters checked, the error naming the first bad one.
fn check_bouc_wen(bw: &BoucWen) -> Result<(), LinearizeError> {
    bw.validate().map_err(|e| match e {
        hyst_model::ModelError::NonFinite { name, value }
        | hyst_model::ModelError::NonPositive { name, value } => {
            LinearizeError::Invalid { name, value }
        }
        _ => LinearizeError::Invalid {
            name: "Bouc-Wen parameters",
            value: f64::NAN,
        },
    })
}

/// `value` checked finite and positive, the error naming it.
pub(crate) fn positive(name: &'static str, value: f64) -> Result<(), LinearizeError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(LinearizeError::Invalid { name, value })
    }
}

fn check_amplitude(a: f64) -> Result<(), LinearizeError> {
    if a.is_finite() && a > 0.0 {
        Ok(())
    } else {
        Err(LinearizeError::NonPositiveAmplitude { amplitude: a })
    }
}

fn check_frequency(w: f64) -> Result<(), LinearizeError> {
    if w.is_finite() && w > 0.0 {
        Ok(())
    } else {
        Err(LinearizeError::NonPositiveFrequency { omega: w })
    }
}

/// A Zener oscillator's parameters identified from poles.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ZenerFit {
    /// Linear (static) stiffness k (N/m).
    pub k: f64,
    /// The relaxation element.
    pub zener: ZenerParams,
}

/// (k, k∞, Ω) from the oscillating pair λ₁,₂ and the real pole λ₃, with known m and c, by
/// matching the coefficients of eq. (32). `poles` may list the pair once or twice.
pub fn zener_from_poles(
    m: f64,
    c: f64,
    pair: Complex<f64>,
    real: f64,
) -> Result<ZenerFit, LinearizeError> {
    if !(m.is_finite() && m > 0.0) {
        return Err(LinearizeError::Invalid {
            name: "mass",
            value: m,
        });
    }
    if !c.is_finite() {
        return Err(LinearizeError::Invalid {
            name: "damping",
            value: c,
        });
    }
    if pair.im == 0.0 || !pair.re.is_finite() || !pair.im.is_finite() {
        return Err(LinearizeError::NoOscillatingPair {
            poles: format!("[{pair}, {real}]"),
        });
    }
    if !real.is_finite() {
        return Err(LinearizeError::Invalid {
            name: "real pole",
            value: real,
        });
    }
    let s1 = -(2.0 * pair.re + real);
    let s2 = pair.norm_sqr() + 2.0 * pair.re * real;
    let s3 = -(pair.norm_sqr() * real);
    let omega = s1 - c / m;
    if omega <= 0.0 {
        return Err(LinearizeError::NonPositiveOmega {
            omega,
            sum: s1,
            c_over_m: c / m,
        });
    }
    let k = m * s3 / omega;
    let k_inf = m * s2 - omega * c - k;
    Ok(ZenerFit {
        k,
        zener: ZenerParams { k_inf, omega },
    })
}

/// First-harmonic equivalent of a hysteretic element at amplitude A:
/// $z_1 = K x + C\dot x$ with loss stiffness $\omega C$ independent of ω.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct DescribingFunction {
    /// Amplitude A (m).
    pub amplitude: f64,
    /// Equivalent stiffness $K_{eq}$ (N/m).
    pub stiffness: f64,
    /// Loss stiffness $\omega C_{eq}$ (N/m).
    pub loss: f64,
}

impl DescribingFunction {
    /// Equivalent viscous damping $C_{eq}$ at angular frequency ω (N s/m).
    pub fn damping(&self, omega: f64) -> f64 {
        self.loss / omega
    }
}

/// Steps of RK4 per half cycle in [`describing_function`].
const HALF_STEPS: usize = 2000;

/// z(θ) over θ ∈ [0, π] for x = A cos θ from z(0) = z0 (ẋ ≤ 0 throughout).
fn half_loop(bw: &BoucWen, a: f64, z0: f64, out: Option<&mut Vec<f64>>) -> f64 {
    let h = std::f64::consts::PI / HALF_STEPS as f64;
    // dz/dθ = (dx/dθ) g(z), dx/dθ = −A sin θ; with ẋ ≤ 0, sgn ẋ = −1.
    let f = |th: f64, z: f64| {
        let dx = -a * th.sin();
        bw.rate(dx, z)
    };
    let mut z = z0;
    let mut out = out;
    if let Some(o) = out.as_deref_mut() {
        o.clear();
        o.push(z);
    }
    for i in 0..HALF_STEPS {
        let th = i as f64 * h;
        let k1 = f(th, z);
        let k2 = f(th + 0.5 * h, z + 0.5 * h * k1);
        let k3 = f(th + 0.5 * h, z + 0.5 * h * k2);
        let k4 = f(th + h, z + h * k3);
        z += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
        if let Some(o) = out.as_deref_mut() {
            o.push(z);
        }
    }
    z
}

/// The periodic loop over a half cycle: z(θ) at θ = iπ/2000, i = 0..=2000, with z(π) = −z(0).
pub fn periodic_half_loop(bw: &BoucWen, a: f64) -> Result<Vec<f64>, LinearizeError> {
    check_amplitude(a)?;
    check_bouc_wen(bw)?;
    // Solve G(z0) = z(π; z0) + z0 = 0 by the secant method, started at the top of the loop
    // of the linear element (z0 ≈ αA) and slightly below, or at the level where the loading
    // branch saturates, (α/β(γ+δ))^(1/ν), if that is lower: far above it, |z|^ν makes the
    // half cycle stiff enough for RK4 to blow up when ν > 1 (ν = 4 at (βγ)^(1/ν)A ≈ 50).
    let g = |z0: f64| half_loop(bw, a, z0, None) + z0;
    let saturation = bw.beta * (bw.gamma + bw.delta);
    let mut top = bw.alpha * a;
    if saturation > 0.0 {
        top = top.min((bw.alpha / saturation).powf(1.0 / bw.nu));
    }
    let (mut x0, mut x1) = (top, 0.9 * top);
    let (mut g0, mut g1) = (g(x0), g(x1));
    for _ in 0..60 {
        if !g1.is_finite() {
            return Err(LinearizeError::LoopDiverges {
                amplitude: a,
                z: g1,
            });
        }
        if g1 == 0.0 || (x1 - x0).abs() <= 1e-15 * x1.abs() {
            break;
        }
        let x2 = x1 - g1 * (x1 - x0) / (g1 - g0);
        x0 = x1;
        g0 = g1;
        x1 = x2;
        g1 = g(x1);
    }
    if g1.is_nan() || g1.abs() > 1e-10 * x1.abs().max(f64::MIN_POSITIVE) {
        return Err(LinearizeError::NoConvergence {
            iterations: 60,
            residual: g1 / x1,
        });
    }
    let mut out = Vec::with_capacity(HALF_STEPS + 1);
    half_loop(bw, a, x1, Some(&mut out));
    if let Some(z) = out.iter().find(|z| !z.is_finite()) {
        return Err(LinearizeError::LoopDiverges {
            amplitude: a,
            z: *z,
        });
    }
    Ok(out)
}

/// Simpson's rule of samples `f` on [0, π] (an even number of intervals).
fn simpson_pi(f: impl Fn(usize) -> f64) -> f64 {
    let n = HALF_STEPS;
    let h = std::f64::consts::PI / n as f64;
    let mut s = f(0) + f(n);
    for i in 1..n {
        s += if i % 2 == 1 { 4.0 } else { 2.0 } * f(i);
    }
    s * h / 3.0
}

/// The numerical describing function of a Bouc-Wen element at amplitude `a` (any ν > 0).
pub fn describing_function(bw: &BoucWen, a: f64) -> Result<DescribingFunction, LinearizeError> {
    let z = periodic_half_loop(bw, a)?;
    let h = std::f64::consts::PI / HALF_STEPS as f64;
    // Half-wave symmetry doubles the half-cycle integrals.
    let ca = 2.0 * simpson_pi(|i| z[i] * (i as f64 * h).cos()) / std::f64::consts::PI;
    let sb = 2.0 * simpson_pi(|i| z[i] * (i as f64 * h).sin()) / std::f64::consts::PI;
    Ok(DescribingFunction {
        amplitude: a,
        stiffness: ca / a,
        loss: -sb / a,
    })
}

/// ln Γ(x) for x ≥ 1/2 by Lanczos' approximation (g = 7, nine terms; relative error
/// below 1e-14 there).
pub(crate) fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    let x = x - 1.0;
    let t = x + G + 0.5;
    let s = C[1..]
        .iter()
        .enumerate()
        .fold(C[0], |s, (i, c)| s + c / (x + 1.0 + i as f64));
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + s.ln()
}

/// The first-order coefficients of the describing function for exponent ν:
/// $K \approx \alpha - s(\nu)\,\beta\delta(\alpha A)^\nu$, $\omega C \approx l(\nu)\,\beta\gamma(\alpha A)^\nu$,
/// returned as (s, l); both are 4/(3π) at ν = 1.
fn first_order_coefficients(nu: f64) -> (f64, f64) {
    let p = 0.5 * (nu + 1.0);
    // (2/π) B(3/2, p) = (2/π) Γ(3/2) Γ(p) / Γ(p + 3/2), with Γ(3/2) = √π/2.
    let beta = (0.5 * std::f64::consts::PI.ln() - std::f64::consts::LN_2 + ln_gamma(p)
        - ln_gamma(p + 1.5))
    .exp();
    (
        2.0 * beta / std::f64::consts::PI,
        4.0 / (std::f64::consts::PI * (nu + 2.0)),
    )
}

/// First-order closed form, any ν > 0:
/// $K = \alpha - \tfrac{2}{\pi}B(\tfrac32, \tfrac{\nu+1}{2})\,\beta\delta(\alpha A)^\nu$,
/// $\omega C = \tfrac{4}{\pi(\nu+2)}\beta\gamma(\alpha A)^\nu$; for ν = 1,
/// $K = \alpha(1 - \frac{4\beta\delta A}{3\pi})$, $\omega C = \frac{4\alpha\beta\gamma A}{3\pi}$.
pub fn describing_function_first_order(
    bw: &BoucWen,
    a: f64,
) -> Result<DescribingFunction, LinearizeError> {
    check_amplitude(a)?;
    check_bouc_wen(bw)?;
    let (s, l) = first_order_coefficients(bw.nu);
    let q = (bw.alpha * a).powf(bw.nu);
    Ok(DescribingFunction {
        amplitude: a,
        stiffness: bw.alpha - s * bw.beta_delta() * q,
        loss: l * bw.beta_gamma() * q,
    })
}

/// The Zener element that has stiffness K and loss stiffness ωC at frequency ω.
pub fn zener_matching(df: &DescribingFunction, w: f64) -> Result<ZenerParams, LinearizeError> {
    check_frequency(w)?;
    if df.stiffness.is_nan() || df.stiffness <= 0.0 {
        return Err(LinearizeError::NonPositiveStiffness {
            stiffness: df.stiffness,
        });
    }
    let ratio = df.loss / df.stiffness; // = Ω/ω
    if ratio.is_nan() || ratio <= 0.0 {
        return Err(LinearizeError::NonPositiveOmega {
            omega: ratio * w,
            sum: f64::NAN,
            c_over_m: f64::NAN,
        });
    }
    Ok(ZenerParams {
        k_inf: df.stiffness * (1.0 + ratio * ratio),
        omega: ratio * w,
    })
}

/// Stiffness and loss stiffness of a Zener element at frequency ω (amplitude-independent;
/// `amplitude` is carried along).
pub fn zener_at(z: &ZenerParams, w: f64, amplitude: f64) -> DescribingFunction {
    let d = z.omega * z.omega + w * w;
    DescribingFunction {
        amplitude,
        stiffness: z.k_inf * w * w / d,
        loss: z.k_inf * w * z.omega / d,
    }
}

/// Bouc-Wen products (βγ, βδ) from (K, ωC) at amplitude A with α and ν given, to first order
/// (the closed form of [`describing_function_first_order`] solved for them).
pub fn bouc_wen_first_order(
    alpha: f64,
    nu: f64,
    df: &DescribingFunction,
) -> Result<BoucWen, LinearizeError> {
    check_amplitude(df.amplitude)?;
    positive("alpha", alpha)?;
    positive("nu", nu)?;
    let (s, l) = first_order_coefficients(nu);
    let q = (alpha * df.amplitude).powf(nu);
    Ok(BoucWen::from_products(
        alpha,
        df.loss / (l * q),
        (alpha - df.stiffness) / (s * q),
        nu,
    ))
}

/// Bouc-Wen products (βγ, βδ) whose numerical describing function at `df.amplitude` equals
/// (K, ωC), with α and ν given: Newton's method from the first-order solution.
pub fn bouc_wen_exact(
    alpha: f64,
    nu: f64,
    df: &DescribingFunction,
) -> Result<BoucWen, LinearizeError> {
    let start = bouc_wen_first_order(alpha, nu, df)?;
    let a = df.amplitude;
    let scale = df.stiffness.abs().max(df.loss.abs());
    let eval = |bg: f64, bd: f64| -> Result<(f64, f64), LinearizeError> {
        let d = describing_function(&BoucWen::from_products(alpha, bg, bd, nu), a)?;
        Ok((d.stiffness - df.stiffness, d.loss - df.loss))
    };
    let (mut bg, mut bd) = (start.beta_gamma(), start.beta_delta());
    let mut res = eval(bg, bd)?;
    // The products enter as β·(αA)^ν: steps in units of 1/(αA)^ν, times α.
    let unit = alpha / (alpha * a).powf(nu);
    for it in 0..40 {
        let norm = res.0.hypot(res.1) / scale;
        if norm <= 1e-10 {
            return Ok(BoucWen::from_products(alpha, bg, bd, nu));
        }
        // Finite-difference Jacobian.
        let h = 1e-6 * unit;
        let rg = eval(bg + h, bd)?;
        let rd = eval(bg, bd + h)?;
        let j = [
            [(rg.0 - res.0) / h, (rd.0 - res.0) / h],
            [(rg.1 - res.1) / h, (rd.1 - res.1) / h],
        ];
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        if det == 0.0 || !det.is_finite() {
            return Err(LinearizeError::NoConvergence {
                iterations: it,
                residual: norm,
            });
        }
        let dg = (j[1][1] * res.0 - j[0][1] * res.1) / det;
        let dd = (-j[1][0] * res.0 + j[0][0] * res.1) / det;
        bg -= dg;
        bd -= dd;
        res = eval(bg, bd)?;
    }
    Err(LinearizeError::NoConvergence {
        iterations: 40,
        residual: res.0.hypot(res.1) / scale,
    })
}

/// Energy dissipated per cycle by the Bouc-Wen element, $\oint z\,dx$, by direct quadrature
/// of the periodic loop (independent of the Fourier projection).
pub fn loop_energy_bouc_wen(bw: &BoucWen, a: f64) -> Result<f64, LinearizeError> {
    let z = periodic_half_loop(bw, a)?;
    let h = std::f64::consts::PI / HALF_STEPS as f64;
    // ∮ z dx = 2 ∫_0^π z (dx/dθ) dθ with dx/dθ = −A sin θ (half-wave symmetry).
    Ok(2.0 * simpson_pi(|i| -z[i] * a * (i as f64 * h).sin()))
}

/// Energy dissipated per cycle by a Zener element at amplitude A and frequency ω:
/// $\pi A^2 k_\infty\,\omega\Omega/(\Omega^2+\omega^2)$.
pub fn loop_energy_zener(z: &ZenerParams, a: f64, w: f64) -> f64 {
    std::f64::consts::PI * a * a * zener_at(z, w, a).loss
}

/// The amplitude A used to linearize, relative to the record's σₓ.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum Amplitude {
    /// A = σₓ (the default, as in the paper).
    #[default]
    SigmaX,
    /// A = 2σₓ.
    TwoSigmaX,
    /// A = σₓ/2.
    HalfSigmaX,
    /// A given value (m).
    Value(f64),
}

impl Amplitude {
    /// The amplitude for a record of standard deviation `sigma_x`.
    pub fn resolve(&self, sigma_x: f64) -> Result<f64, LinearizeError> {
        let a = match *self {
            Amplitude::SigmaX => sigma_x,
            Amplitude::TwoSigmaX => 2.0 * sigma_x,
            Amplitude::HalfSigmaX => 0.5 * sigma_x,
            Amplitude::Value(v) => v,
        };
        check_amplitude(a)?;
        Ok(a)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn ln_gamma_matches_known_values() {
        // Γ(1/2) = √π, Γ(1) = Γ(2) = 1, Γ(3/2) = √π/2, Γ(5) = 24, Γ(10.5) = 1133278.3889487856;
        // the Lanczos form is good to ~1e-15 relative there, the log to ~1e-14 absolute.
        let pi = std::f64::consts::PI;
        for (x, g) in [
            (0.5, pi.sqrt()),
            (1.0, 1.0),
            (1.5, 0.5 * pi.sqrt()),
            (2.0, 1.0),
            (5.0, 24.0),
            (10.5, 1_133_278.388_948_785_6),
        ] {
            assert_relative_eq!(ln_gamma(x).exp(), g, max_relative = 1e-13);
        }
    }

    #[test]
    fn first_order_coefficients_at_nu_one_and_two() {
        let pi = std::f64::consts::PI;
        let (s, l) = first_order_coefficients(1.0);
        assert_relative_eq!(s, 4.0 / (3.0 * pi), max_relative = 1e-13);
        assert_relative_eq!(l, 4.0 / (3.0 * pi), max_relative = 1e-13);
        // ν = 2: (1/π)∫₀^{2π} sin²θ cos²θ dθ = (2/π)·B(3/2, 3/2) = 1/4, and 4/(4π) = 1/π.
        let (s, l) = first_order_coefficients(2.0);
        assert_relative_eq!(s, 0.25, max_relative = 1e-13);
        assert_relative_eq!(l, 1.0 / pi, max_relative = 1e-13);
    }
}
