//! Statistical (Gaussian) linearization of Bouc-Wen hysteresis under a random force, and
//! Bouc-Wen from the Zener equivalents of several force levels.
//!
//! The describing function linearizes at one sinusoidal amplitude; a random response has
//! none. Statistical linearization (Wen, 1980; Atalik and Utku, 1976) replaces
//! $f(\dot x, z) = \alpha\dot x - \beta\gamma|\dot x|z - \beta\delta\,\dot x|z|$ (ν = 1) by the
//! linear $k_\infty\dot x - \Omega z$ closest in mean square, whose coefficients for jointly
//! Gaussian, zero-mean $(\dot x, z)$ are $E[\partial f/\partial\dot x]$ and
//! $-E[\partial f/\partial z]$. With $\sigma_v$, $\sigma_z$ the standard deviations and ρ the
//! correlation of $\dot x$ and $z$, and $E|\dot x| = \sqrt{2/\pi}\,\sigma_v$,
//! $E[z\operatorname{sgn}\dot x] = \sqrt{2/\pi}\,\rho\sigma_z$:
//!
//! $$ k_\infty = \alpha - \sqrt{2/\pi}\,\sigma_z(\rho\,\beta\gamma + \beta\delta), \qquad
//!    \Omega = \sqrt{2/\pi}\,\sigma_v(\beta\gamma + \rho\,\beta\delta). $$
//!
//! That is a Zener element $\dot z + \Omega z = k_\infty\dot x$ exactly, with the oscillator's
//! c and k unchanged ([`zener_from_bouc_wen`]). For any exponent ν,
//! $f = \alpha\dot x - \beta\gamma|\dot x|\operatorname{sgn}(z)|z|^\nu - \beta\delta\,\dot x|z|^\nu$
//! and, with standard normals $g_v$, $g_z$ of correlation ρ,
//!
//! $$ k_\infty = \alpha - \sigma_z^\nu\left(\beta\gamma\,E[\operatorname{sgn}g_v\operatorname{sgn}g_z|g_z|^\nu] + \beta\delta\,E|g_z|^\nu\right), $$
//! $$ \Omega = \nu\,\sigma_v\sigma_z^{\nu-1}\left(\beta\gamma\,E[|g_v||g_z|^{\nu-1}] + \beta\delta\,\rho\,E|g_z|^\nu\right), $$
//!
//! $E|g|^\nu = 2^{\nu/2}\Gamma(\tfrac{\nu+1}{2})/\sqrt\pi$; the two mixed moments are
//! $E[r^\nu]$ of the Rayleigh radius times an integral over the angle, computed by
//! double-exponential quadrature. At ν = 1 they are $\sqrt{2/\pi}\,\rho$
//! and $\sqrt{2/\pi}$, the formulas above. The moments are those of the linear Zener
//! oscillator under a white force of two-sided density q (N²/Hz, $E[u(t)u(t+\tau)] =
//! q\,\delta(\tau)$), from its Lyapunov equation ([`zener_response_moments`]); iterating the
//! two to a fixed point predicts the equivalent Zener of a Bouc-Wen oscillator at a level
//! ([`equivalent_zener`]).
//!
//! **Back to Bouc-Wen.** At one level the two relations hold three unknowns (α, βγ, βδ), as
//! the describing function's do. But they are *linear* in all three, with coefficients from
//! that level's moments, so the Zener equivalents identified at two or more levels give them
//! by weighted least squares ([`bouc_wen_from_levels`], ν given), with standard errors and a
//! χ² that says whether the levels agree with one Bouc-Wen element. With three or more levels
//! ν can be fitted too: for each ν the rest is that linear fit, so ν minimizes the profile
//! χ²(ν) ([`exponent_from_levels`]).

use hyst_model::{BoucWen, ZenerParams};
use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use crate::{LinearizeError, check_bouc_wen, positive};

/// √(2/π): E|g| for a standard normal g.
const SQRT_2_OVER_PI: f64 = 0.797_884_560_802_865_4;

/// Stationary second moments of the velocity and the hysteretic (or Zener) force.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ResponseMoments {
    /// Standard deviation of the displacement (m).
    pub sigma_x: f64,
    /// Standard deviation of the velocity (m/s).
    pub sigma_v: f64,
    /// Standard deviation of the element's force z (N).
    pub sigma_z: f64,
    /// Correlation of velocity and z, E[ẋ z]/(σ_v σ_z).
    pub rho: f64,
}

fn check_moments(m: &ResponseMoments) -> Result<(), LinearizeError> {
    positive("sigma_v", m.sigma_v)?;
    positive("sigma_z", m.sigma_z)?;
    if !(m.rho.is_finite() && m.rho.abs() < 1.0) {
        return Err(LinearizeError::Invalid {
            name: "rho",
            value: m.rho,
        });
    }
    Ok(())
}

/// ∫ₐᵇ f by the tanh-sinh (double-exponential) rule, good to ~1e-13 for a function analytic
/// inside the interval whatever its (integrable) singularities at the ends. `f` gets the
/// point's distances from a and from b, so that it can evaluate near an end without the
/// cancellation of b − x.
fn tanh_sinh(a: f64, b: f64, f: impl Fn(f64, f64) -> f64) -> f64 {
    const H: f64 = 1.0 / 32.0;
    const T: f64 = 3.5;
    let half = std::f64::consts::FRAC_PI_2;
    let len = b - a;
    let mut sum = 0.0;
    let steps = (T / H) as i32;
    for i in -steps..=steps {
        let t = i as f64 * H;
        let u = half * t.sinh();
        // Distances from the ends: len/(1 + e^{2u}) from b, len/(1 + e^{-2u}) from a.
        let from_a = len / (1.0 + (-2.0 * u).exp());
        let from_b = len / (1.0 + (2.0 * u).exp());
        let w = half * t.cosh() / u.cosh().powi(2);
        if from_a > 0.0 && from_b > 0.0 && w.is_finite() {
            sum += w * f(from_a, from_b);
        }
    }
    sum * H * len / 2.0
}

/// The Gaussian moments the statistical linearization of a Bouc-Wen element with exponent ν
/// needs, for standard normals $g_v$, $g_z$ of correlation ρ.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct GaussianMoments {
    /// $E|g_z|^\nu$.
    pub abs_z: f64,
    /// $E[\operatorname{sgn}g_v\operatorname{sgn}g_z|g_z|^\nu]$.
    pub sign_sign: f64,
    /// $E[|g_v||g_z|^{\nu-1}]$.
    pub abs_v_abs_z: f64,
}

impl GaussianMoments {
    /// The moments for exponent ν > 0 and correlation |ρ| < 1. Write $g_z = r\cos\theta$,
    /// $g_v = r\cos(\theta - \psi)$ with cos ψ = ρ and r Rayleigh: each moment is
    /// $E r^\nu = 2^{\nu/2}\Gamma(1 + \nu/2)$ times an angular mean over θ ∈ (−π/2, π/2)
    /// (the other half turn repeats it), split where cos(θ − ψ) changes sign.
    pub(crate) fn new(nu: f64, rho: f64) -> Self {
        let pi = std::f64::consts::PI;
        let half = std::f64::consts::FRAC_PI_2;
        let abs_z = (0.5 * nu * std::f64::consts::LN_2 + crate::ln_gamma(0.5 * (nu + 1.0))).exp()
            / pi.sqrt();
        let radial = (0.5 * nu * std::f64::consts::LN_2 + crate::ln_gamma(1.0 + 0.5 * nu)).exp();
        let psi = rho.acos();
        let kink = psi - half;
        // cos θ on (a, b) ⊂ [−π/2, π/2], accurate near ±π/2: sin of the distance to the
        // nearer of them.
        let cos_at = |a: f64, from_a: f64, b: f64, from_b: f64| {
            ((a + half) + from_a).min((half - b) + from_b).sin()
        };
        let piece = |a: f64, b: f64, g: &dyn Fn(f64, f64) -> f64| {
            tanh_sinh(a, b, |fa, fb| {
                let theta = if fa < fb { a + fa } else { b - fb };
                g(theta, cos_at(a, fa, b, fb))
            })
        };
        let sign_sign = radial / pi
            * (piece(kink, half, &|_, c| c.powf(nu)) - piece(-half, kink, &|_, c| c.powf(nu)));
        let mixed = |th: f64, c: f64| (th - psi).cos().abs() * c.powf(nu - 1.0);
        let abs_v_abs_z = radial / pi * (piece(-half, kink, &mixed) + piece(kink, half, &mixed));
        GaussianMoments {
            abs_z,
            sign_sign,
            abs_v_abs_z,
        }
    }
}

/// The Zener element that replaces a Bouc-Wen element (any ν) whose velocity and force have
/// the Gaussian moments `moments`. Ω may come out ≤ 0 (a Bouc-Wen element that adds energy
/// on average, βγ + ρβδ < 0 for ν = 1); that is reported as
/// [`LinearizeError::NonDissipative`].
pub fn zener_from_bouc_wen(
    bw: &BoucWen,
    moments: &ResponseMoments,
) -> Result<ZenerParams, LinearizeError> {
    check_bouc_wen(bw)?;
    check_moments(moments)?;
    let (bg, bd) = (bw.beta_gamma(), bw.beta * bw.delta);
    let (a, b) = coefficients(bw.nu, moments);
    let k_inf = bw.alpha - a[0] * bg - a[1] * bd;
    let omega = b[0] * bg + b[1] * bd;
    if omega.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Err(LinearizeError::NonDissipative { omega });
    }
    Ok(ZenerParams { k_inf, omega })
}

/// The statistical linearization's coefficients: $k_\infty = \alpha - a_0\beta\gamma - a_1\beta\delta$
/// and $\Omega = b_0\beta\gamma + b_1\beta\delta$, returned as (a, b). Closed form at ν = 1.
fn coefficients(nu: f64, m: &ResponseMoments) -> ([f64; 2], [f64; 2]) {
    if nu == 1.0 {
        let (a, b) = (SQRT_2_OVER_PI * m.sigma_z, SQRT_2_OVER_PI * m.sigma_v);
        return ([a * m.rho, a], [b, b * m.rho]);
    }
    let g = GaussianMoments::new(nu, m.rho);
    let zn = m.sigma_z.powf(nu);
    let w = nu * m.sigma_v * m.sigma_z.powf(nu - 1.0);
    (
        [zn * g.sign_sign, zn * g.abs_z],
        [w * g.abs_v_abs_z, w * m.rho * g.abs_z],
    )
}

/// Stationary moments of the Zener oscillator $m\ddot x + c\dot x + kx + z = u$,
/// $\dot z + \Omega z = k_\infty\dot x$, under a white force of two-sided density `q`
/// (N²/Hz): the state covariance P solves $AP + PA^T + q\,bb^T = 0$.
pub fn zener_response_moments(
    mass: f64,
    c: f64,
    k: f64,
    zener: &ZenerParams,
    q: f64,
) -> Result<ResponseMoments, LinearizeError> {
    positive("mass", mass)?;
    positive("force density q", q)?;
    for (name, v) in [
        ("damping", c),
        ("stiffness", k),
        ("k_inf", zener.k_inf),
        ("omega", zener.omega),
    ] {
        if !v.is_finite() {
            return Err(LinearizeError::Invalid { name, value: v });
        }
    }
    let a = Matrix3::new(
        0.0,
        1.0,
        0.0,
        -k / mass,
        -c / mass,
        -1.0 / mass,
        0.0,
        zener.k_inf,
        -zener.omega,
    );
    // Routh–Hurwitz for mλ³ + (Ωm + c)λ² + (Ωc + k + k∞)λ + kΩ: a stationary response needs
    // every coefficient positive and a₂a₁ > a₃a₀.
    let (a2, a1, a0) = (
        zener.omega * mass + c,
        zener.omega * c + k + zener.k_inf,
        k * zener.omega,
    );
    if !(a2 > 0.0 && a1 > 0.0 && a0 > 0.0 && a2 * a1 > mass * a0) {
        return Err(LinearizeError::Invalid {
            name: "stability (the Zener oscillator has no stationary response)",
            value: a2 * a1 - mass * a0,
        });
    }
    // vec(AP + PAᵀ) = (I ⊗ A + A ⊗ I) vec P, column-major vec.
    let mut kron = SMatrix::<f64, 9, 9>::zeros();
    for i in 0..3 {
        for j in 0..3 {
            for r in 0..3 {
                kron[(3 * j + i, 3 * j + r)] += a[(i, r)];
                kron[(3 * j + i, 3 * r + i)] += a[(j, r)];
            }
        }
    }
    let mut rhs = SVector::<f64, 9>::zeros();
    rhs[4] = -q / (mass * mass); // the (1, 1) entry of q b bᵀ, b = (0, 1/m, 0)
    let p = kron.lu().solve(&rhs).ok_or(LinearizeError::Invalid {
        name: "stability (singular Lyapunov equation)",
        value: a0,
    })?;
    let at = |i: usize, j: usize| p[3 * j + i];
    let (sx, sv, sz) = (at(0, 0).sqrt(), at(1, 1).sqrt(), at(2, 2).sqrt());
    Ok(ResponseMoments {
        sigma_x: sx,
        sigma_v: sv,
        sigma_z: sz,
        rho: at(1, 2) / (sv * sz),
    })
}

/// The equivalent Zener element of the Bouc-Wen oscillator $m\ddot x + c\dot x + kx + z = u$
/// under a white force of two-sided density `q`: the fixed point of
/// [`zener_response_moments`] and [`zener_from_bouc_wen`], started from the moments of the
/// linear oscillator of stiffness k + α (with at least 1 % of critical damping: c may be 0,
/// the element dissipating alone).
pub fn equivalent_zener(
    mass: f64,
    c: f64,
    k: f64,
    bw: &BoucWen,
    q: f64,
) -> Result<(ZenerParams, ResponseMoments), LinearizeError> {
    check_bouc_wen(bw)?;
    positive("mass", mass)?;
    if !(c.is_finite() && c >= 0.0) {
        return Err(LinearizeError::Invalid {
            name: "damping",
            value: c,
        });
    }
    positive("stiffness k + α", k + bw.alpha)?;
    positive("force density q", q)?;
    // Linear oscillator of stiffness k + α: σ_x² = q/(2c(k+α)), σ_v² = q/(2cm).
    let c0 = c.max(0.02 * ((k + bw.alpha) * mass).sqrt());
    let sx = (q / (2.0 * c0 * (k + bw.alpha))).sqrt();
    let mut moments = ResponseMoments {
        sigma_x: sx,
        sigma_v: (q / (2.0 * c0 * mass)).sqrt(),
        sigma_z: bw.alpha * sx,
        rho: 0.0,
    };
    let mut zener = zener_from_bouc_wen(bw, &moments)?;
    const MAX_ITERATIONS: usize = 500;
    let mut change = f64::INFINITY;
    for _ in 0..MAX_ITERATIONS {
        let next = zener_response_moments(mass, c, k, &zener, q)?;
        // Half steps: the plain iteration can oscillate at high levels.
        moments = ResponseMoments {
            sigma_x: next.sigma_x,
            sigma_v: 0.5 * (moments.sigma_v + next.sigma_v),
            sigma_z: 0.5 * (moments.sigma_z + next.sigma_z),
            rho: 0.5 * (moments.rho + next.rho),
        };
        let z = zener_from_bouc_wen(bw, &moments)?;
        change = ((z.k_inf - zener.k_inf) / zener.k_inf)
            .abs()
            .max(((z.omega - zener.omega) / zener.omega).abs());
        zener = z;
        if change < 1e-12 {
            let moments = zener_response_moments(mass, c, k, &zener, q)?;
            return Ok((zener, moments));
        }
    }
    Err(LinearizeError::NoConvergence {
        iterations: MAX_ITERATIONS,
        residual: change,
    })
}

/// The Zener equivalent identified at one force level, with the moments it implies (from
/// [`zener_response_moments`] with the level's identified c, k and force density) and the
/// standard errors of k∞ and Ω that weigh it.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct LevelEquivalent {
    /// The identified Zener element.
    pub zener: ZenerParams,
    /// Standard error of k∞ (N/m).
    pub k_inf_se: f64,
    /// Standard error of Ω (rad/s).
    pub omega_se: f64,
    /// The response moments at this level.
    pub moments: ResponseMoments,
}

/// The Bouc-Wen element (β = 1, ν as given) that best explains the Zener equivalents of
/// several levels, with what the least squares say of it.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct BoucWenFromLevels {
    /// The element.
    pub bouc_wen: BoucWen,
    /// Standard errors of (α, βγ, βδ), from the levels' standard errors.
    pub se: [f64; 3],
    /// χ² of the fit per degree of freedom (2·levels − 3): near 1 when the levels agree with
    /// one Bouc-Wen element within their standard errors, NaN with two levels (no freedom).
    pub chi2_per_dof: f64,
    /// χ² itself.
    pub chi2: f64,
}

/// (α, βγ, βδ) for exponent ν by weighted least squares from two or more levels' Zener
/// equivalents: each level gives $k_\infty = \alpha - a_0\beta\gamma - a_1\beta\delta$ and
/// $\Omega = b_0\beta\gamma + b_1\beta\delta$ (for ν = 1, $a_0 = a\rho$, $a_1 = a$,
/// $b_0 = b$, $b_1 = b\rho$ with $a = \sqrt{2/\pi}\,\sigma_z$, $b = \sqrt{2/\pi}\,\sigma_v$),
/// weighted by the inverse standard errors.
pub fn bouc_wen_from_levels(
    levels: &[LevelEquivalent],
    nu: f64,
) -> Result<BoucWenFromLevels, LinearizeError> {
    positive("nu", nu)?;
    if levels.len() < 2 {
        return Err(LinearizeError::TooFewLevels {
            levels: levels.len(),
        });
    }
    let mut normal = Matrix3::<f64>::zeros();
    let mut rhs = Vector3::<f64>::zeros();
    let mut rows = Vec::with_capacity(2 * levels.len());
    for lv in levels {
        check_moments(&lv.moments)?;
        positive("k_inf standard error", lv.k_inf_se)?;
        positive("omega standard error", lv.omega_se)?;
        for (name, v) in [("k_inf", lv.zener.k_inf), ("omega", lv.zener.omega)] {
            if !v.is_finite() {
                return Err(LinearizeError::Invalid { name, value: v });
            }
        }
        let (a, b) = coefficients(nu, &lv.moments);
        rows.push((
            Vector3::new(1.0, -a[0], -a[1]) / lv.k_inf_se,
            lv.zener.k_inf / lv.k_inf_se,
        ));
        rows.push((
            Vector3::new(0.0, b[0], b[1]) / lv.omega_se,
            lv.zener.omega / lv.omega_se,
        ));
    }
    for (j, y) in &rows {
        normal += j * j.transpose();
        rhs += j * *y;
    }
    // Columns of very different scale (α in N/m, βγ in 1/m): solve in scaled variables.
    let scale = Vector3::from_fn(|i, _| normal[(i, i)].sqrt().recip());
    let scaled = Matrix3::from_fn(|i, j| normal[(i, j)] * scale[i] * scale[j]);
    // Unit diagonal: its smallest eigenvalue is the reciprocal of its condition number, up
    // to a factor of three. Below 1e-10 the levels do not separate the three unknowns (the
    // same moments twice, say) and the solution would be round-off.
    let smallest = scaled.symmetric_eigenvalues().min();
    let inverse = (smallest > 1e-10)
        .then(|| scaled.try_inverse())
        .flatten()
        .ok_or(LinearizeError::LevelsDegenerate {
            smallest_eigenvalue: smallest,
        })?;
    let cov = Matrix3::from_fn(|i, j| inverse[(i, j)] * scale[i] * scale[j]);
    let x = cov * rhs;
    let chi2: f64 = rows.iter().map(|(j, y)| (j.dot(&x) - y).powi(2)).sum();
    let dof = rows.len() as f64 - 3.0;
    Ok(BoucWenFromLevels {
        bouc_wen: BoucWen::from_products(x[0], x[1], x[2], nu),
        se: [0, 1, 2].map(|i| cov[(i, i)].max(0.0).sqrt()),
        chi2_per_dof: if dof > 0.0 { chi2 / dof } else { f64::NAN },
        chi2,
    })
}

/// The exponent ν fitted with (α, βγ, βδ): [`ExponentFromLevels`].
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ExponentFromLevels {
    /// The fit at the best ν (its χ² per degree of freedom over 2·levels − 4).
    pub fit: BoucWenFromLevels,
    /// ν's standard error: the half-width of the profile's χ² ≤ min + 1 interval, NaN if that
    /// interval reaches an end of the range searched.
    pub nu_se: f64,
    /// The profile: (ν, χ² of the best (α, βγ, βδ) at that ν) on the search grid.
    pub profile: Vec<(f64, f64)>,
}

/// The range of ν [`exponent_from_levels`] searches.
pub const EXPONENT_RANGE: (f64, f64) = (0.3, 4.0);

/// ν with (α, βγ, βδ) from three or more levels: for each ν the three are linear
/// ([`bouc_wen_from_levels`]), so ν minimizes the profile χ²(ν), on a grid of 75 points
/// over [`EXPONENT_RANGE`] (uniform in ln ν) refined by golden-section search. A profile whose
/// minimum lies at an end of the range gives that end, with `nu_se` NaN.
pub fn exponent_from_levels(
    levels: &[LevelEquivalent],
) -> Result<ExponentFromLevels, LinearizeError> {
    if levels.len() < 3 {
        return Err(LinearizeError::TooFewLevelsForExponent {
            levels: levels.len(),
        });
    }
    let chi2 = |nu: f64| bouc_wen_from_levels(levels, nu).map(|f| f.chi2);
    let (lo, hi) = (EXPONENT_RANGE.0.ln(), EXPONENT_RANGE.1.ln());
    const GRID: usize = 75;
    let mut profile = Vec::with_capacity(GRID);
    for i in 0..GRID {
        let nu = (lo + (hi - lo) * i as f64 / (GRID - 1) as f64).exp();
        profile.push((nu, chi2(nu)?));
    }
    let best = (0..GRID)
        .min_by(|&a, &b| profile[a].1.total_cmp(&profile[b].1))
        .unwrap_or(0);
    // Golden section between the grid neighbours of the best point (in ln ν).
    let (mut a, mut b) = (
        profile[best.saturating_sub(1)].0.ln(),
        profile[(best + 1).min(GRID - 1)].0.ln(),
    );
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let (mut x1, mut x2) = (b - g * (b - a), a + g * (b - a));
    let (mut f1, mut f2) = (chi2(x1.exp())?, chi2(x2.exp())?);
    for _ in 0..60 {
        if f1 < f2 {
            (b, x2, f2) = (x2, x1, f1);
            x1 = b - g * (b - a);
            f1 = chi2(x1.exp())?;
        } else {
            (a, x1, f1) = (x1, x2, f2);
            x2 = a + g * (b - a);
            f2 = chi2(x2.exp())?;
        }
    }
    let nu = (0.5 * (a + b)).exp();
    let mut fit = bouc_wen_from_levels(levels, nu)?;
    let dof = 2.0 * levels.len() as f64 - 4.0;
    fit.chi2_per_dof = fit.chi2 / dof;
    // Where the profile crosses min + 1 on each side: bracketed by the first grid point
    // beyond it, then bisected in ln ν.
    let target = fit.chi2 + 1.0;
    let crossing = |outside: Option<f64>| -> Result<Option<f64>, LinearizeError> {
        let Some(out) = outside else {
            return Ok(None);
        };
        let (mut inside, mut out) = (nu.ln(), out.ln());
        for _ in 0..60 {
            let mid = 0.5 * (inside + out);
            if chi2(mid.exp())? < target {
                inside = mid;
            } else {
                out = mid;
            }
        }
        Ok(Some((0.5 * (inside + out)).exp()))
    };
    let beyond = |above: bool| {
        let hit = |&&(x, c): &&(f64, f64)| (x > nu) == above && c >= target;
        if above {
            profile.iter().find(hit)
        } else {
            profile.iter().rev().find(hit)
        }
        .map(|(x, _)| *x)
    };
    let upper = crossing(beyond(true))?;
    let lower = crossing(beyond(false))?;
    let nu_se = match (upper, lower) {
        (Some(u), Some(l)) => 0.5 * (u - l),
        _ => f64::NAN,
    };
    Ok(ExponentFromLevels {
        fit,
        nu_se,
        profile,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use rand::rngs::Xoshiro256PlusPlus;
    use rand::{RngExt, SeedableRng};
    use rand_distr::StandardNormal;

    /// The benchmark's oscillator: m = 2 kg, c = 10 N s/m, k = 5e4 N/m.
    const M: f64 = 2.0;
    const C: f64 = 10.0;
    const K: f64 = 5e4;

    /// The quadrature against the closed forms at ν = 1 and ν = 2: E|g| = √(2/π),
    /// E[sgn g_v |g_z|·sgn g_z] = √(2/π)ρ, E|g_v| = √(2/π); E g² = 1,
    /// E[sgn g_v sgn g_z g_z²] = (2/π)(asin ρ + ρ√(1−ρ²)), E|g_v g_z| = (2/π)(√(1−ρ²) + ρ asin ρ).
    #[test]
    fn gaussian_moments_match_closed_forms() {
        let c = SQRT_2_OVER_PI;
        let pi = std::f64::consts::PI;
        for rho in [-0.95, -0.5, 0.0, 0.3, 0.8, 0.999] {
            let s = (1.0f64 - rho * rho).sqrt();
            let one = GaussianMoments::new(1.0, rho);
            let two = GaussianMoments::new(2.0, rho);
            for (got, want) in [
                (one.abs_z, c),
                (one.sign_sign, c * rho),
                (one.abs_v_abs_z, c),
                (two.abs_z, 1.0),
                (two.sign_sign, 2.0 / pi * (rho.asin() + rho * s)),
                (two.abs_v_abs_z, 2.0 / pi * (s + rho * rho.asin())),
            ] {
                // The double-exponential rule at step 1/32 is good to ~1e-14 here.
                assert!((got - want).abs() < 1e-12, "ρ = {rho}: {got} vs {want}");
            }
        }
    }

    #[test]
    fn a_vanishing_element_leaves_the_linear_oscillator() {
        // k∞ → 0: the oscillator is m ẍ + c ẋ + k x = u, σ_x² = q/(2ck), σ_v² = q/(2cm).
        let q = 0.7;
        let z = ZenerParams {
            k_inf: 1e-9,
            omega: 30.0,
        };
        let mo = zener_response_moments(M, C, K, &z, q).unwrap();
        // The element changes the moments by O(k∞/k) = 2e-14; 1e-10 is round-off headroom
        // for a 9×9 solve whose entries span eight decades.
        approx::assert_relative_eq!(mo.sigma_x, (q / (2.0 * C * K)).sqrt(), max_relative = 1e-10);
        approx::assert_relative_eq!(mo.sigma_v, (q / (2.0 * C * M)).sqrt(), max_relative = 1e-10);
    }

    proptest! {
        /// Power balance of the stationary response, a relation the Lyapunov solve does not
        /// use: the force's power q/(2m) is what the dashpot and the element take,
        /// c σ_v² + E[ẋ z].
        #[test]
        fn the_moments_balance_power(
            c in 0.5f64..50.0,
            k in 1e3f64..1e5,
            k_inf in 1e3f64..1e5,
            omega in 1.0f64..300.0,
            q in 1e-3f64..10.0,
        ) {
            let z = ZenerParams { k_inf, omega };
            let mo = zener_response_moments(M, c, k, &z, q).unwrap();
            let taken = c * mo.sigma_v.powi(2) + mo.rho * mo.sigma_v * mo.sigma_z;
            // The solve's relative round-off, amplified by the spread of the entries.
            prop_assert!((taken / (q / (2.0 * M)) - 1.0).abs() < 1e-8, "{taken}");
        }

        /// The fixed point's levels, mapped back from their exact Zener equivalents, give the
        /// Bouc-Wen element again.
        #[test]
        fn levels_round_trip(
            alpha in 1e4f64..1e5,
            bg in 100.0f64..2000.0,
            bd in -1500.0f64..1500.0,
        ) {
            let bw = BoucWen::from_products(alpha, bg, bd, 1.0);
            let mut levels = Vec::new();
            for f in [10.0, 40.0, 90.0] {
                let Ok((zener, moments)) = equivalent_zener(M, C, K, &bw, f * f / 750.0) else {
                    continue;
                };
                levels.push(LevelEquivalent { zener, k_inf_se: 1e3, omega_se: 1.0, moments });
            }
            prop_assume!(levels.len() >= 2);
            let back = bouc_wen_from_levels(&levels, 1.0).unwrap();
            // The fixed point stops at a relative change of 1e-12; the 3×3 solve loses a few
            // digits more to the scale of α against βγ.
            prop_assert!((back.bouc_wen.alpha / alpha - 1.0).abs() < 1e-8);
            prop_assert!((back.bouc_wen.beta_gamma() / bg - 1.0).abs() < 1e-6);
            prop_assert!((back.bouc_wen.beta * back.bouc_wen.delta - bd).abs() < 1e-6 * bg);
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(12))]

        /// Levels of an element of any exponent, mapped back from their exact Zener
        /// equivalents with ν unknown, give ν and the element again; the same levels read
        /// with ν = 1 do not fit (unless the element's ν is near 1).
        #[test]
        fn levels_round_trip_with_the_exponent(
            nu in 0.5f64..3.0,
            s in 0.1f64..1.0,
            ratio in -0.8f64..0.5,
        ) {
            // Sized so that at the middle level (40 N, σ_z ≈ 25 N) βγ|z|^ν is s·α/10.
            let alpha = 5e4;
            let bg = s * 0.1 * alpha / 25f64.powf(nu);
            let bw = BoucWen::from_products(alpha, bg, ratio * bg, nu);
            let mut levels = Vec::new();
            for f in [10.0, 25.0, 40.0, 70.0] {
                let Ok((zener, moments)) = equivalent_zener(M, C, K, &bw, f * f / 750.0) else {
                    continue;
                };
                // Standard errors of 0.1 % of each.
                levels.push(LevelEquivalent {
                    zener,
                    k_inf_se: 1e-3 * zener.k_inf,
                    omega_se: 1e-3 * zener.omega,
                    moments,
                });
            }
            prop_assume!(levels.len() >= 3);
            let e = exponent_from_levels(&levels).unwrap();
            // The golden section stops at 1e-12 in ln ν; the fixed points at 1e-12.
            prop_assert!((e.fit.bouc_wen.nu / nu - 1.0).abs() < 1e-6, "{} vs {nu}", e.fit.bouc_wen.nu);
            prop_assert!((e.fit.bouc_wen.beta_gamma() / bg - 1.0).abs() < 1e-4);
            prop_assert!(e.fit.chi2 < 1e-6, "χ² {}", e.fit.chi2);
            prop_assert!(e.nu_se > 0.0 && e.nu_se < 0.1 * nu, "se {}", e.nu_se);
            if (nu - 1.0).abs() > 0.2 {
                let one = bouc_wen_from_levels(&levels, 1.0).unwrap();
                prop_assert!(one.chi2 > 100.0, "ν = 1 fits with χ² {}", one.chi2);
            }
        }
    }

    /// The coefficients against their definition: the least-squares regression of
    /// f(ẋ, z) = αẋ − βγ|ẋ|sgn(z)|z|^ν − βδẋ|z|^ν on (ẋ, z) over Gaussian samples, for the
    /// benchmark's element (ν = 1) and for elements of ν = 0.5 and 2 of βγ as strong at
    /// |z| = 30 N and a smaller βδ (with the benchmark's, Ω < 0 at ρ = 0.7 for ν = 2).
    #[test]
    fn gaussian_coefficients_are_the_mean_square_best() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(7);
        for nu in [1.0, 0.5, 2.0] {
            let scale = 30f64.powf(1.0 - nu);
            let bd = if nu == 1.0 { -1100.0 } else { -400.0 };
            let bw = BoucWen::from_products(5e4, 800.0 * scale, bd * scale, nu);
            for (sv, sz, rho) in [(0.1, 30.0, 0.2), (0.05, 10.0, -0.5), (0.2, 60.0, 0.7)] {
                let mo = ResponseMoments {
                    sigma_x: f64::NAN,
                    sigma_v: sv,
                    sigma_z: sz,
                    rho,
                };
                let want = zener_from_bouc_wen(&bw, &mo).unwrap();
                let n = 400_000;
                let (mut vv, mut vz, mut zz, mut fv, mut fz) = (0.0, 0.0, 0.0, 0.0, 0.0);
                let mut samples = Vec::with_capacity(n);
                for _ in 0..n {
                    let (g1, g2): (f64, f64) =
                        (rng.sample(StandardNormal), rng.sample(StandardNormal));
                    let v = sv * g1;
                    let z = sz * (rho * g1 + (1.0 - rho * rho).sqrt() * g2);
                    let f = bw.rate(v, z);
                    (vv, vz, zz, fv, fz) =
                        (vv + v * v, vz + v * z, zz + z * z, fv + f * v, fz + f * z);
                    samples.push((v, z, f));
                }
                let det = vv * zz - vz * vz;
                let a = (fv * zz - fz * vz) / det;
                let b = (fz * vv - fv * vz) / det;
                // Standard errors of the regression coefficients from its residuals.
                let s2 = samples
                    .iter()
                    .map(|(v, z, f)| (f - a * v - b * z).powi(2))
                    .sum::<f64>()
                    / (n - 2) as f64;
                let (se_a, se_b) = ((s2 * zz / det).sqrt(), (s2 * vv / det).sqrt());
                // Five standard errors: a false alarm once in ~10⁶ draws.
                assert!(
                    (a - want.k_inf).abs() < 5.0 * se_a,
                    "k∞ {a} vs {} ± {se_a}",
                    want.k_inf
                );
                assert!(
                    (-b - want.omega).abs() < 5.0 * se_b,
                    "Ω {} vs {} ± {se_b}",
                    -b,
                    want.omega
                );
            }
        }
    }

    /// Without a dashpot the element dissipates alone: the fixed point exists, and the
    /// power balance holds with c = 0 (all of q/(2m) taken by the element).
    #[test]
    fn no_dashpot_is_a_fixed_point_too() {
        let q = 50.0 * 50.0 / 750.0;
        let (z, mo) = equivalent_zener(M, 0.0, K, &BoucWen::benchmark(), q).unwrap();
        assert!(z.omega > 0.0 && z.k_inf > 0.0, "{z:?}");
        let taken = mo.rho * mo.sigma_v * mo.sigma_z;
        // As in the_moments_balance_power.
        assert!((taken / (q / (2.0 * M)) - 1.0).abs() < 1e-8, "{taken}");
        assert!(matches!(
            equivalent_zener(M, -1.0, K, &BoucWen::benchmark(), q),
            Err(LinearizeError::Invalid {
                name: "damping",
                ..
            })
        ));
    }

    /// Under the benchmark's drives the fixed point is a Zener element that stiffens and
    /// relaxes faster with the level.
    #[test]
    fn the_benchmark_stiffens_with_the_level() {
        let bw = BoucWen::benchmark();
        let mut last = (0.0, 0.0);
        for f in [10.0, 50.0, 90.0] {
            let (z, mo) = equivalent_zener(M, C, K, &bw, f * f / 750.0).unwrap();
            // The moments are the element's own fixed point.
            let again = zener_from_bouc_wen(&bw, &mo).unwrap();
            approx::assert_relative_eq!(again.k_inf, z.k_inf, max_relative = 1e-10);
            approx::assert_relative_eq!(again.omega, z.omega, max_relative = 1e-10);
            assert!(z.k_inf > last.0 && z.omega > last.1, "{f} N: {z:?}");
            last = (z.k_inf, z.omega);
        }
    }

    #[test]
    fn bad_input_is_named() {
        let bw = BoucWen::benchmark();
        let mo = ResponseMoments {
            sigma_x: 1e-4,
            sigma_v: 0.1,
            sigma_z: 30.0,
            rho: 0.2,
        };
        let z = ZenerParams {
            k_inf: 6e4,
            omega: 40.0,
        };
        let nu0 = BoucWen { nu: 0.0, ..bw };
        assert!(matches!(
            zener_from_bouc_wen(&nu0, &mo),
            Err(LinearizeError::Invalid { name: "nu", .. })
        ));
        let rho1 = ResponseMoments { rho: 1.0, ..mo };
        assert!(matches!(
            zener_from_bouc_wen(&bw, &rho1),
            Err(LinearizeError::Invalid { name: "rho", .. })
        ));
        let heating = BoucWen::from_products(5e4, -800.0, 0.0, 1.0);
        assert!(matches!(
            zener_from_bouc_wen(&heating, &mo),
            Err(LinearizeError::NonDissipative { .. })
        ));
        assert!(matches!(
            zener_response_moments(M, C, K, &z, 0.0),
            Err(LinearizeError::Invalid {
                name: "force density q",
                ..
            })
        ));
        assert!(matches!(
            zener_response_moments(-1.0, C, K, &z, 1.0),
            Err(LinearizeError::Invalid { name: "mass", .. })
        ));
        let unstable = ZenerParams {
            k_inf: 6e4,
            omega: -40.0,
        };
        assert!(zener_response_moments(M, C, K, &unstable, 1.0).is_err());
        let one = LevelEquivalent {
            zener: z,
            k_inf_se: 1e3,
            omega_se: 1.0,
            moments: mo,
        };
        assert!(matches!(
            bouc_wen_from_levels(&[one], 1.0),
            Err(LinearizeError::TooFewLevels { levels: 1 })
        ));
        // Two levels with the same moments cannot separate α from βδ.
        assert!(matches!(
            bouc_wen_from_levels(&[one, one], 1.0),
            Err(LinearizeError::LevelsDegenerate { .. })
        ));
        let nan = LevelEquivalent {
            k_inf_se: f64::NAN,
            ..one
        };
        assert!(matches!(
            bouc_wen_from_levels(&[one, nan], 1.0),
            Err(LinearizeError::Invalid {
                name: "k_inf standard error",
                ..
            })
        ));
        // The exponent: positive, and three levels to fit it.
        assert!(matches!(
            bouc_wen_from_levels(&[one, one], -1.0),
            Err(LinearizeError::Invalid { name: "nu", .. })
        ));
        assert!(matches!(
            exponent_from_levels(&[one, one]),
            Err(LinearizeError::TooFewLevelsForExponent { levels: 2 })
        ));
    }
}
