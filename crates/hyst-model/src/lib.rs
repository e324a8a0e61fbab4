//! Single-degree-of-freedom oscillators with hysteretic, relaxation and extra force terms.
//!
//! One job: say what force acts on the mass and how the internal state evolves. Everything
//! is written as a first-order system in the state
//! $s = (x, \dot x, z, x_2, \dot x_2)$ so that any fixed-step integrator can drive it.
//!
//! The equation of motion (paper, eq. 1) is
//!
//! $$ m\ddot x + c\dot x + k x + z + f_{\text{extra}}(x, \dot x, x_2, \dot x_2) = u(t) $$
//!
//! with the restoring element $z$ one of
//!
//! * **none** (plain linear oscillator), $z \equiv 0$;
//! * **Bouc-Wen** (eq. 2, with $|z|^{\nu-1}$ where the paper misprints $|\dot z|^{\nu-1}$):
//!   $\dot z = \alpha\dot x - \beta\left(\gamma|\dot x||z|^{\nu-1}z + \delta\dot x|z|^\nu\right)$;
//! * **Zener** relaxation element (eq. 3 with $k_0 = 0$): $\dot z + \Omega z = k_\infty \dot x$,
//!   whose linear state-space form is eq. (25) and characteristic polynomial eq. (32).
//!
//! and the extra forces, each off by default:
//! cubic spring $k_3 x^3$, quadratic (asymmetric) spring $k_q x^2$, a clearance spring
//! $k_g\,\mathrm{dz}_g(x)$ that engages beyond $\pm g$ ($\mathrm{dz}_g(x) = x - g\,\mathrm{sgn}\,x$
//! for $|x| > g$, else 0), quadratic damping $c_2\dot x|\dot x|$, Coulomb friction
//! $F_c\tanh(\dot x/v_\varepsilon)$ (sign function smoothed over the velocity scale
//! $v_\varepsilon$ so that fixed-step integrators stay accurate), a force surface
//! $\sum_i\theta_i\phi_i(x/x_s, \dot x/v_s)$ on a fixed polynomial basis ([`ForceSurface`]),
//! a constant force $f_0$ (a preload, or an offset of the measured input), and a second mass
//! $m_2$ attached to the main mass by a spring $k_2$ and damper $c_2$:
//! $m_2\ddot x_2 = k_2(x - x_2) + c_2(\dot x - \dot x_2)$. The measured output is always $x$.
//!
//! Parameters are checked by [`Oscillator::validate`], which returns a [`ModelError`] naming
//! the offending value. With the `serde` feature the oscillator and its parts read and write
//! one JSON schema ([`schema`]).

#![warn(missing_docs)]

use nalgebra::{Complex, DMatrix, SMatrix, SVector};

pub mod display;
pub mod poly;
#[cfg(feature = "serde")]
pub mod schema;

/// State vector $(x, \dot x, z, x_2, \dot x_2)$: displacement, velocity, restoring-element force,
/// and the second mass's displacement and velocity (zero when there is none).
pub type State = SVector<f64, 5>;

/// Jacobian of the state derivative with respect to the state.
pub type Jacobian = SMatrix<f64, 5, 5>;

/// Errors of invalid model parameters.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ModelError {
    /// A parameter is NaN or infinite.
    #[error("parameter `{name}` is not finite: {value}")]
    NonFinite {
        /// Parameter name.
        name: &'static str,
        /// The offending value.
        value: f64,
    },
    /// A parameter that must be strictly positive is not.
    #[error("parameter `{name}` must be > 0, got {value}")]
    NonPositive {
        /// Parameter name.
        name: &'static str,
        /// The offending value.
        value: f64,
    },
    /// A parameter that must not be negative is.
    #[error("parameter `{name}` must be >= 0, got {value}")]
    Negative {
        /// Parameter name.
        name: &'static str,
        /// The offending value.
        value: f64,
    },
    /// A linear state-space form was asked of a model with nonlinear terms.
    #[error("the model is not linear: it has {what}")]
    NotLinear {
        /// Which nonlinear term is present.
        what: &'static str,
    },
}

fn finite(name: &'static str, value: f64) -> Result<(), ModelError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(ModelError::NonFinite { name, value })
    }
}

fn not_negative(name: &'static str, value: f64) -> Result<(), ModelError> {
    finite(name, value)?;
    if value >= 0.0 {
        Ok(())
    } else {
        Err(ModelError::Negative { name, value })
    }
}

fn positive(name: &'static str, value: f64) -> Result<(), ModelError> {
    finite(name, value)?;
    if value > 0.0 {
        Ok(())
    } else {
        Err(ModelError::NonPositive { name, value })
    }
}

/// Bouc-Wen hysteresis parameters, eq. (2).
///
/// Only the products $\beta\gamma$ and $\beta\delta$ enter the equation; both forms are offered.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(try_from = "schema::BoucWenFile", into = "schema::BoucWenFile")
)]
pub struct BoucWen {
    /// Initial stiffness of the hysteretic element, α (N/m).
    pub alpha: f64,
    /// Scale β (its unit is that of 1/|z|^ν divided by that of γ).
    pub beta: f64,
    /// Shape parameter γ.
    pub gamma: f64,
    /// Shape parameter δ.
    pub delta: f64,
    /// Smoothness exponent ν > 0 (ν = 1 for the benchmark).
    pub nu: f64,
}

impl BoucWen {
    /// The benchmark's hysteresis: α = 5e4 N/m, β = 1e3 m⁻¹, γ = 0.8, δ = −1.1, ν = 1.
    pub fn benchmark() -> Self {
        BoucWen {
            alpha: 5e4,
            beta: 1e3,
            gamma: 0.8,
            delta: -1.1,
            nu: 1.0,
        }
    }

    /// Build from the products the paper identifies: β is set to 1, so γ = βγ and δ = βδ.
    pub fn from_products(alpha: f64, beta_gamma: f64, beta_delta: f64, nu: f64) -> Self {
        BoucWen {
            alpha,
            beta: 1.0,
            gamma: beta_gamma,
            delta: beta_delta,
            nu,
        }
    }

    /// The product βγ.
    pub fn beta_gamma(&self) -> f64 {
        self.beta * self.gamma
    }

    /// The product βδ.
    pub fn beta_delta(&self) -> f64 {
        self.beta * self.delta
    }

    /// Check that every parameter is finite and ν > 0.
    pub fn validate(&self) -> Result<(), ModelError> {
        finite("alpha", self.alpha)?;
        finite("beta", self.beta)?;
        finite("gamma", self.gamma)?;
        finite("delta", self.delta)?;
        positive("nu", self.nu)
    }

    /// $\dot z$ for velocity `v` and hysteretic force `z`.
    #[inline(always)]
    pub fn rate(&self, v: f64, z: f64) -> f64 {
        let (bg, bd) = (self.beta_gamma(), self.beta_delta());
        if self.nu == 1.0 {
            self.alpha * v - bg * v.abs() * z - bd * v * z.abs()
        } else {
            // |z|^(ν-1) z = sgn z |z|^ν: written so, it is 0 at z = 0 for ν < 1 too, where
            // |z|^(ν-1) is infinite (and times z = 0 was NaN).
            let zn = z.abs().powf(self.nu);
            self.alpha * v - bg * v.abs() * sign(z) * zn - bd * v * zn
        }
    }

    /// Partial derivatives of [`BoucWen::rate`] with respect to `v` and `z`.
    pub fn rate_gradient(&self, v: f64, z: f64) -> (f64, f64) {
        let (bg, bd) = (self.beta_gamma(), self.beta_delta());
        let sv = sign(v);
        let sz = sign(z);
        if self.nu == 1.0 {
            (
                self.alpha - bg * sv * z - bd * z.abs(),
                -bg * v.abs() - bd * v * sz,
            )
        } else {
            let az = z.abs();
            let zn = az.powf(self.nu);
            // d(|z|^(ν-1) z)/dz = ν|z|^(ν-1); d(|z|^ν)/dz = ν|z|^(ν-1) sgn z. At z = 0 with
            // ν < 1 these are infinite; 0 is used there (as for ν > 1, where they vanish).
            let dp = if az > 0.0 {
                self.nu * az.powf(self.nu - 1.0)
            } else {
                0.0
            };
            (
                self.alpha - bg * sv * sz * zn - bd * zn,
                -bg * v.abs() * dp - bd * v * dp * sz,
            )
        }
    }
}

#[inline(always)]
fn sign(x: f64) -> f64 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// Zener relaxation element, eq. (3) with $k_0 = 0$: $\dot z + \Omega z = k_\infty\dot x$.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(deny_unknown_fields)
)]
pub struct ZenerParams {
    /// High-frequency stiffness $k_\infty$ (N/m).
    pub k_inf: f64,
    /// Corner frequency Ω (rad/s), > 0.
    pub omega: f64,
}

impl ZenerParams {
    /// Check that both parameters are finite and Ω > 0.
    pub fn validate(&self) -> Result<(), ModelError> {
        finite("k_inf", self.k_inf)?;
        positive("omega", self.omega)
    }
}

/// The restoring element $z$ of eq. (1).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Restoring {
    /// No element: a plain linear oscillator.
    #[default]
    None,
    /// Bouc-Wen hysteresis, eq. (2).
    BoucWen(BoucWen),
    /// Zener relaxation element, eq. (3).
    Zener(ZenerParams),
}

/// Coulomb friction $F_c\tanh(\dot x / v_\varepsilon)$.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(deny_unknown_fields)
)]
pub struct Coulomb {
    /// Friction force level $F_c$ (N).
    pub force: f64,
    /// Smoothing velocity $v_\varepsilon$ (m/s), > 0: below it the force ramps linearly.
    pub smoothing_velocity: f64,
}

/// A second mass attached to the main one by a spring and a damper.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(deny_unknown_fields)
)]
pub struct SecondMass {
    /// Mass $m_2$ (kg), > 0.
    pub mass: f64,
    /// Coupling stiffness $k_2$ (N/m).
    pub stiffness: f64,
    /// Coupling damping $c_2$ (N s/m).
    pub damping: f64,
}

/// A spring that engages only beyond a clearance: force $k_g(x - g\,\mathrm{sgn}\,x)$ for
/// $|x| > g$, none within $\pm g$ (a gap, a stop, a loose joint).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(deny_unknown_fields)
)]
pub struct Clearance {
    /// Stiffness $k_g$ of the spring once engaged (N/m).
    pub stiffness: f64,
    /// Half-width $g$ of the clearance (m), > 0.
    pub gap: f64,
}

impl Clearance {
    /// The force at displacement `x`.
    #[inline(always)]
    pub fn force(&self, x: f64) -> f64 {
        if x > self.gap {
            self.stiffness * (x - self.gap)
        } else if x < -self.gap {
            self.stiffness * (x + self.gap)
        } else {
            0.0
        }
    }

    /// d(force)/dx.
    pub fn slope(&self, x: f64) -> f64 {
        if x.abs() > self.gap {
            self.stiffness
        } else {
            0.0
        }
    }
}

/// Terms of a [`ForceSurface`].
pub const SURFACE_TERMS: usize = 10;

/// A force over the phase plane $(x, \dot x)$ on a fixed basis in the scaled coordinates
/// $\xi = x/x_s$, $\eta = \dot x/v_s$ (the scales are the record's RMS displacement and
/// velocity, so every term is of order one): even and odd parts in $x$ apart
/// ($\xi^2, \xi^3, \xi^4, \xi^5$), in $\dot x$ ($\eta^2, \eta|\eta|, \eta^3$, and a jump
/// at $\dot x = 0$, $\tanh(\eta/0.05)$), and two mixed terms ($\xi^2\eta$, $\xi\eta^2$). The
/// linear terms $\xi$, $\eta$ are the oscillator's own $k$ and $c$. Force
/// $\sum_i\theta_i\phi_i(\xi, \eta)$ with $\theta_i$ in newtons.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(try_from = "schema::SurfaceFile", into = "schema::SurfaceFile")
)]
pub struct ForceSurface {
    /// Displacement scale $x_s$ (m), > 0.
    pub x_scale: f64,
    /// Velocity scale $v_s$ (m/s), > 0.
    pub v_scale: f64,
    /// Coefficient $\theta_i$ (N) of each term of [`ForceSurface::TERMS`]; 0 leaves a term out.
    pub coefficients: [f64; SURFACE_TERMS],
}

/// Smoothing of the surface's jump term, in units of the velocity scale.
const SURFACE_JUMP_WIDTH: f64 = 0.05;

impl ForceSurface {
    /// The terms' names, in the order of [`ForceSurface::coefficients`] (ξ = x/x_s,
    /// η = ẋ/v_s).
    pub const TERMS: [&'static str; SURFACE_TERMS] = [
        "xi^2",
        "xi^3",
        "xi^4",
        "xi^5",
        "eta^2",
        "eta|eta|",
        "eta^3",
        "jump(eta)",
        "xi^2 eta",
        "xi eta^2",
    ];

    /// The basis functions at scaled displacement `xi` and velocity `eta`.
    #[inline(always)]
    pub fn basis(xi: f64, eta: f64) -> [f64; SURFACE_TERMS] {
        let (x2, e2) = (xi * xi, eta * eta);
        [
            x2,
            x2 * xi,
            x2 * x2,
            x2 * x2 * xi,
            e2,
            eta * eta.abs(),
            e2 * eta,
            (eta / SURFACE_JUMP_WIDTH).tanh(),
            x2 * eta,
            xi * e2,
        ]
    }

    /// Partial derivatives of each basis function with respect to `xi` and to `eta`.
    fn basis_gradient(xi: f64, eta: f64) -> ([f64; SURFACE_TERMS], [f64; SURFACE_TERMS]) {
        let (x2, e2) = (xi * xi, eta * eta);
        let t = (eta / SURFACE_JUMP_WIDTH).tanh();
        (
            [
                2.0 * xi,
                3.0 * x2,
                4.0 * x2 * xi,
                5.0 * x2 * x2,
                0.0,
                0.0,
                0.0,
                0.0,
                2.0 * xi * eta,
                e2,
            ],
            [
                0.0,
                0.0,
                0.0,
                0.0,
                2.0 * eta,
                2.0 * eta.abs(),
                3.0 * e2,
                (1.0 - t * t) / SURFACE_JUMP_WIDTH,
                x2,
                2.0 * xi * eta,
            ],
        )
    }

    /// The force at displacement `x` and velocity `v`.
    #[inline(always)]
    pub fn force(&self, x: f64, v: f64) -> f64 {
        let (xi, eta) = (x / self.x_scale, v / self.v_scale);
        let (x2, e2) = (xi * xi, eta * eta);
        let c = &self.coefficients;
        let f = x2 * (c[0] + xi * (c[1] + xi * (c[2] + xi * c[3])))
            + e2 * (c[4] + c[6] * eta)
            + c[5] * eta * eta.abs()
            + c[8] * x2 * eta
            + c[9] * xi * e2;
        // The jump's tanh costs more than the rest together: only when the term is in.
        if c[7] != 0.0 {
            f + c[7] * Self::jump(eta)
        } else {
            f
        }
    }

    /// The jump term at scaled velocity `eta`: $\tanh(\eta/0.05)$.
    #[inline(always)]
    pub fn jump(eta: f64) -> f64 {
        (eta / SURFACE_JUMP_WIDTH).tanh()
    }

    /// Partial derivatives of the force with respect to `x` and `v`.
    pub fn gradient(&self, x: f64, v: f64) -> (f64, f64) {
        let (gx, gv) = Self::basis_gradient(x / self.x_scale, v / self.v_scale);
        let dot = |g: &[f64; SURFACE_TERMS]| -> f64 {
            g.iter().zip(&self.coefficients).map(|(p, c)| p * c).sum()
        };
        (dot(&gx) / self.x_scale, dot(&gv) / self.v_scale)
    }
}

/// What the acquisition does to the measured displacement between the structure and the
/// record: a sensor's first-order lag τ and a delay d (the sensor's, the conditioning's, a skew
/// between the input's and the output's sampling). The record holds
/// $$y_m(t) = \int_0^\infty \tfrac{1}{\tau} e^{-s/\tau}\, x(t - d - s)\, ds,
/// \qquad Y_m(s) = \frac{e^{-sd}}{1 + s\tau}\, X(s),$$
/// $y_m(t) = x(t - d)$ when τ = 0. In the band it also stands for an anti-aliasing filter:
/// to first order in frequency any causal chain is a delay and a lag. It is not structure:
/// it moves no pole and no force, and the linearization ignores it. Since the structure is
/// time-invariant, a delay of the output is the same as one of the input; an output that
/// leads its input (a force channel that lags) is not modelled.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(deny_unknown_fields)
)]
pub struct MeasurementChain {
    /// Delay d (s), ≥ 0.
    #[cfg_attr(feature = "serde", serde(default))]
    pub delay: f64,
    /// The sensor's first-order time constant τ (s), ≥ 0.
    #[cfg_attr(feature = "serde", serde(default))]
    pub lag: f64,
}

impl MeasurementChain {
    /// Whether the chain does nothing (d = τ = 0).
    pub fn is_identity(&self) -> bool {
        self.delay == 0.0 && self.lag == 0.0
    }
}

/// Extra force terms that can be added to any oscillator, and the measurement chain between
/// its displacement and the record ([`MeasurementChain`]). All off by default.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ExtraForces {
    /// Cubic spring coefficient $k_3$ (N/m³): force $k_3x^3$.
    pub cubic_stiffness: f64,
    /// Quadratic spring coefficient $k_q$ (N/m²): force $k_qx^2$, an asymmetric stiffness.
    pub quadratic_stiffness: f64,
    /// A spring beyond a clearance.
    pub clearance: Option<Clearance>,
    /// Quadratic damping coefficient (N s²/m²): force $c_q\dot x|\dot x|$.
    pub quadratic_damping: f64,
    /// Smoothed Coulomb friction.
    pub coulomb: Option<Coulomb>,
    /// A force surface over $(x, \dot x)$.
    pub surface: Option<ForceSurface>,
    /// A second mass (second mode).
    pub second_mass: Option<SecondMass>,
    /// A constant force $f_0$ (N): a static preload, or an offset of the measured input
    /// against the output. It shifts the equilibrium and leaves the dynamics (the poles) as
    /// they are.
    pub offset: f64,
    /// The measurement chain: not a force, but what the acquisition does to the output
    /// ([`MeasurementChain`]); `None` for a record of the displacement itself.
    pub chain: Option<MeasurementChain>,
}

impl ExtraForces {
    /// Whether every extra force term is off (the measurement chain, not a force, is not
    /// counted).
    pub fn is_empty(&self) -> bool {
        self.cubic_stiffness == 0.0
            && self.quadratic_stiffness == 0.0
            && self.clearance.is_none()
            && self.quadratic_damping == 0.0
            && self.coulomb.is_none()
            && self.surface.is_none()
            && self.second_mass.is_none()
            && self.offset == 0.0
    }

    /// The force of every term that is a function of the main mass's $(x, \dot x)$ alone
    /// (all but the second mass).
    #[inline(always)]
    pub fn static_force(&self, x: f64, v: f64) -> f64 {
        let mut f = self.offset;
        if self.cubic_stiffness != 0.0 {
            f += self.cubic_stiffness * x * x * x;
        }
        if self.quadratic_stiffness != 0.0 {
            f += self.quadratic_stiffness * x * x;
        }
        if let Some(g) = &self.clearance {
            f += g.force(x);
        }
        if self.quadratic_damping != 0.0 {
            f += self.quadratic_damping * v * v.abs();
        }
        if let Some(cf) = &self.coulomb {
            f += cf.force * (v / cf.smoothing_velocity).tanh();
        }
        if let Some(s) = &self.surface {
            f += s.force(x, v);
        }
        f
    }

    /// Partial derivatives of [`ExtraForces::static_force`] with respect to `x` and `v`.
    pub fn static_gradient(&self, x: f64, v: f64) -> (f64, f64) {
        let mut dx = 3.0 * self.cubic_stiffness * x * x + 2.0 * self.quadratic_stiffness * x;
        let mut dv = 2.0 * self.quadratic_damping * v.abs();
        if let Some(g) = &self.clearance {
            dx += g.slope(x);
        }
        if let Some(cf) = &self.coulomb {
            let t = (v / cf.smoothing_velocity).tanh();
            dv += cf.force * (1.0 - t * t) / cf.smoothing_velocity;
        }
        if let Some(s) = &self.surface {
            let (a, b) = s.gradient(x, v);
            dx += a;
            dv += b;
        }
        (dx, dv)
    }
}

/// The oscillator $m\ddot x + c\dot x + kx + z + f_{\text{extra}} = u$.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(try_from = "schema::OscillatorFile", into = "schema::OscillatorFile")
)]
pub struct Oscillator {
    /// Mass m (kg), > 0.
    pub mass: f64,
    /// Viscous damping c (N s/m).
    pub damping: f64,
    /// Linear stiffness k (N/m).
    pub stiffness: f64,
    /// Restoring element z.
    pub restoring: Restoring,
    /// Extra force terms.
    pub extras: ExtraForces,
}

/// Linear state-space form $\dot s = A s + B u$, $y = C s$.
#[derive(Debug, Clone, PartialEq)]
pub struct StateSpace {
    /// State matrix A (n × n).
    pub a: DMatrix<f64>,
    /// Input matrix B (n × 1).
    pub b: DMatrix<f64>,
    /// Output matrix C (1 × n), selecting x.
    pub c: DMatrix<f64>,
}

impl StateSpace {
    /// Eigenvalues of A: the continuous-time poles.
    pub fn poles(&self) -> Vec<Complex<f64>> {
        self.a.complex_eigenvalues().iter().copied().collect()
    }

    /// Coefficients of det(λI − A), highest power first (monic), by Faddeev–LeVerrier.
    pub fn characteristic_polynomial(&self) -> Vec<f64> {
        let n = self.a.nrows();
        let mut coeffs = vec![1.0];
        let mut m = DMatrix::<f64>::zeros(n, n);
        let id = DMatrix::<f64>::identity(n, n);
        let mut c_prev = 1.0;
        for k in 1..=n {
            m = &self.a * &m + &id * c_prev;
            let am = &self.a * &m;
            let ck = -am.trace() / k as f64;
            coeffs.push(ck);
            c_prev = ck;
        }
        coeffs
    }
}

impl Oscillator {
    /// A plain linear oscillator $m\ddot x + c\dot x + kx = u$.
    pub fn linear(mass: f64, damping: f64, stiffness: f64) -> Self {
        Oscillator {
            mass,
            damping,
            stiffness,
            restoring: Restoring::None,
            extras: ExtraForces::default(),
        }
    }

    /// A linear oscillator with a Zener element, eq. (25).
    pub fn zener(mass: f64, damping: f64, stiffness: f64, zener: ZenerParams) -> Self {
        Oscillator {
            restoring: Restoring::Zener(zener),
            ..Oscillator::linear(mass, damping, stiffness)
        }
    }

    /// A linear oscillator with a Bouc-Wen element, eqs. (1)–(2).
    pub fn bouc_wen(mass: f64, damping: f64, stiffness: f64, bw: BoucWen) -> Self {
        Oscillator {
            restoring: Restoring::BoucWen(bw),
            ..Oscillator::linear(mass, damping, stiffness)
        }
    }

    /// The hysteretic benchmark system (Noël & Schoukens 2016, Table 1):
    /// m = 2 kg, c = 10 N s/m, k = 5e4 N/m and [`BoucWen::benchmark`].
    pub fn benchmark() -> Self {
        Oscillator::bouc_wen(2.0, 10.0, 5e4, BoucWen::benchmark())
    }

    /// Check every parameter; the error names the first bad one.
    pub fn validate(&self) -> Result<(), ModelError> {
        positive("mass", self.mass)?;
        finite("damping", self.damping)?;
        finite("stiffness", self.stiffness)?;
        match &self.restoring {
            Restoring::None => {}
            Restoring::BoucWen(bw) => bw.validate()?,
            Restoring::Zener(z) => z.validate()?,
        }
        let e = &self.extras;
        finite("cubic_stiffness", e.cubic_stiffness)?;
        finite("quadratic_stiffness", e.quadratic_stiffness)?;
        finite("offset", e.offset)?;
        if let Some(g) = &e.clearance {
            finite("clearance.stiffness", g.stiffness)?;
            positive("clearance.gap", g.gap)?;
        }
        finite("quadratic_damping", e.quadratic_damping)?;
        if let Some(sf) = &e.surface {
            positive("surface.x_scale", sf.x_scale)?;
            positive("surface.v_scale", sf.v_scale)?;
            for c in &sf.coefficients {
                finite("surface.coefficients", *c)?;
            }
        }
        if let Some(cf) = &e.coulomb {
            finite("coulomb.force", cf.force)?;
            positive("coulomb.smoothing_velocity", cf.smoothing_velocity)?;
        }
        if let Some(sm) = &e.second_mass {
            positive("second_mass.mass", sm.mass)?;
            finite("second_mass.stiffness", sm.stiffness)?;
            finite("second_mass.damping", sm.damping)?;
        }
        if let Some(ch) = &e.chain {
            not_negative("chain.delay", ch.delay)?;
            not_negative("chain.lag", ch.lag)?;
        }
        Ok(())
    }

    /// Time derivative of the state under input force `u`.
    #[inline(always)]
    pub fn derivative(&self, s: &State, u: f64) -> State {
        let (x, v, z) = (s[0], s[1], s[2]);
        let e = &self.extras;
        let mut force = u - self.damping * v - self.stiffness * x - z - e.static_force(x, v);
        let (mut dx2, mut dv2) = (0.0, 0.0);
        if let Some(sm) = &e.second_mass {
            let coupling = sm.stiffness * (x - s[3]) + sm.damping * (v - s[4]);
            force -= coupling;
            dx2 = s[4];
            dv2 = coupling / sm.mass;
        }
        let dz = match &self.restoring {
            Restoring::None => 0.0,
            Restoring::BoucWen(bw) => bw.rate(v, z),
            Restoring::Zener(zp) => zp.k_inf * v - zp.omega * z,
        };
        State::new(v, force / self.mass, dz, dx2, dv2)
    }

    /// Jacobian of [`Oscillator::derivative`] with respect to the state (the input enters linearly).
    pub fn jacobian(&self, s: &State) -> Jacobian {
        let (x, v, z) = (s[0], s[1], s[2]);
        let m = self.mass;
        let mut j = Jacobian::zeros();
        j[(0, 1)] = 1.0;
        let mut dfdx = -self.stiffness;
        let mut dfdv = -self.damping;
        let e = &self.extras;
        let (gx, gv) = e.static_gradient(x, v);
        dfdx -= gx;
        dfdv -= gv;
        if let Some(sm) = &e.second_mass {
            dfdx -= sm.stiffness;
            dfdv -= sm.damping;
            j[(1, 3)] = sm.stiffness / m;
            j[(1, 4)] = sm.damping / m;
            j[(3, 4)] = 1.0;
            j[(4, 0)] = sm.stiffness / sm.mass;
            j[(4, 1)] = sm.damping / sm.mass;
            j[(4, 3)] = -sm.stiffness / sm.mass;
            j[(4, 4)] = -sm.damping / sm.mass;
        }
        j[(1, 0)] = dfdx / m;
        j[(1, 1)] = dfdv / m;
        j[(1, 2)] = -1.0 / m;
        match &self.restoring {
            Restoring::None => {}
            Restoring::BoucWen(bw) => {
                let (dv, dz) = bw.rate_gradient(v, z);
                j[(2, 1)] = dv;
                j[(2, 2)] = dz;
            }
            Restoring::Zener(zp) => {
                j[(2, 1)] = zp.k_inf;
                j[(2, 2)] = -zp.omega;
            }
        }
        j
    }

    /// Number of states actually used: 2 (linear), 3 (with z), plus 2 for a second mass.
    pub fn state_dimension(&self) -> usize {
        let base = match self.restoring {
            Restoring::None => 2,
            _ => 3,
        };
        base + if self.extras.second_mass.is_some() {
            2
        } else {
            0
        }
    }

    /// Linear state-space form, eqs. (25)–(26) for a Zener oscillator, for a model without
    /// nonlinear terms. States are (x, ẋ[, z][, x₂, ẋ₂]); the output is x.
    pub fn state_space(&self) -> Result<StateSpace, ModelError> {
        self.validate()?;
        if let Restoring::BoucWen(_) = self.restoring {
            return Err(ModelError::NotLinear {
                what: "a Bouc-Wen element",
            });
        }
        let e = &self.extras;
        if e.cubic_stiffness != 0.0 {
            return Err(ModelError::NotLinear {
                what: "a cubic spring",
            });
        }
        if e.quadratic_damping != 0.0 {
            return Err(ModelError::NotLinear {
                what: "quadratic damping",
            });
        }
        if e.coulomb.is_some() {
            return Err(ModelError::NotLinear {
                what: "Coulomb friction",
            });
        }
        if e.quadratic_stiffness != 0.0 {
            return Err(ModelError::NotLinear {
                what: "a quadratic spring",
            });
        }
        if e.clearance.is_some() {
            return Err(ModelError::NotLinear {
                what: "a clearance spring",
            });
        }
        if e.surface.is_some() {
            return Err(ModelError::NotLinear {
                what: "a force surface",
            });
        }
        // Select the used rows/columns of the full 5-state Jacobian, which is exact for a
        // linear model.
        let used: Vec<usize> = match (&self.restoring, e.second_mass.is_some()) {
            (Restoring::None, false) => vec![0, 1],
            (Restoring::None, true) => vec![0, 1, 3, 4],
            (_, false) => vec![0, 1, 2],
            (_, true) => vec![0, 1, 2, 3, 4],
        };
        let full = self.jacobian(&State::zeros());
        let n = used.len();
        let a = DMatrix::from_fn(n, n, |i, j| full[(used[i], used[j])]);
        let mut b = DMatrix::zeros(n, 1);
        b[(1, 0)] = 1.0 / self.mass;
        let mut c = DMatrix::zeros(1, n);
        c[(0, 0)] = 1.0;
        Ok(StateSpace { a, b, c })
    }

    /// Continuous-time poles of the linear model (eigenvalues of [`Oscillator::state_space`]).
    pub fn poles(&self) -> Result<Vec<Complex<f64>>, ModelError> {
        Ok(self.state_space()?.poles())
    }

    /// Characteristic polynomial written out term by term, highest power first, not monic:
    /// $m\lambda^2 + c\lambda + k$ for a linear oscillator and, for a Zener oscillator, eq. (32)
    /// with its sign flipped: $m\lambda^3 + (\Omega m + c)\lambda^2 + (\Omega c + k + k_\infty)\lambda + k\Omega$.
    pub fn characteristic_polynomial(&self) -> Result<Vec<f64>, ModelError> {
        self.validate()?;
        if !self.extras.is_empty() {
            return Err(ModelError::NotLinear {
                what: "extra force terms (use StateSpace::characteristic_polynomial)",
            });
        }
        let (m, c, k) = (self.mass, self.damping, self.stiffness);
        match &self.restoring {
            Restoring::None => Ok(vec![m, c, k]),
            Restoring::Zener(z) => Ok(vec![
                m,
                z.omega * m + c,
                z.omega * c + k + z.k_inf,
                k * z.omega,
            ]),
            Restoring::BoucWen(_) => Err(ModelError::NotLinear {
                what: "a Bouc-Wen element",
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn benchmark_linear_modal_parameters() {
        // README of the benchmark: stiffness k + α gives 35.59 Hz and 1.12 % damping.
        let bw = Oscillator::benchmark();
        let lin = Oscillator::linear(bw.mass, bw.damping, bw.stiffness + 5e4);
        let p = lin.poles().unwrap();
        let l = p.iter().find(|l| l.im > 0.0).unwrap();
        let f = l.norm() / (2.0 * std::f64::consts::PI);
        let zeta = -l.re / l.norm();
        assert!((f - 35.59).abs() < 0.005, "{f}");
        assert!((zeta - 0.0112).abs() < 5e-5, "{zeta}");
    }

    #[test]
    fn bouc_wen_rate_is_finite_at_rest_for_any_nu_and_its_gradient_matches() {
        for nu in [0.3, 0.7, 1.0, 1.5, 3.0] {
            let bw = BoucWen::from_products(5e4, 800.0, -300.0, nu);
            // From rest, z = 0: ż = αv whatever ν (it was NaN for ν < 1).
            assert_eq!(bw.rate(0.01, 0.0), 5e4 * 0.01, "ν = {nu}");
            // Away from z = 0 the gradient is the rate's central difference (relative step
            // 1e-6: truncation and rounding both well below 1e-6 of the derivative).
            for (v, z) in [(0.01, 3.0), (-0.02, 5.0), (0.03, -2.0), (-0.01, -4.0)] {
                let (dv, dz) = bw.rate_gradient(v, z);
                let hv = 1e-6 * v.abs();
                let hz = 1e-6 * z.abs();
                let nv = (bw.rate(v + hv, z) - bw.rate(v - hv, z)) / (2.0 * hv);
                let nz = (bw.rate(v, z + hz) - bw.rate(v, z - hz)) / (2.0 * hz);
                assert_relative_eq!(dv, nv, max_relative = 1e-6);
                assert_relative_eq!(dz, nz, max_relative = 1e-6);
            }
        }
    }

    #[test]
    fn validation_names_the_bad_value() {
        let mut o = Oscillator::benchmark();
        o.mass = 0.0;
        assert_eq!(
            o.validate(),
            Err(ModelError::NonPositive {
                name: "mass",
                value: 0.0
            })
        );
        let mut o = Oscillator::benchmark();
        if let Restoring::BoucWen(bw) = &mut o.restoring {
            bw.nu = -1.0;
        }
        assert!(matches!(
            o.validate(),
            Err(ModelError::NonPositive { name: "nu", .. })
        ));
        let mut o = Oscillator::benchmark();
        o.stiffness = f64::NAN;
        assert!(matches!(
            o.validate(),
            Err(ModelError::NonFinite {
                name: "stiffness",
                ..
            })
        ));
        let o = Oscillator::zener(
            2.0,
            1.0,
            1.0,
            ZenerParams {
                k_inf: 1.0,
                omega: -3.0,
            },
        );
        assert!(matches!(
            o.validate(),
            Err(ModelError::NonPositive { name: "omega", .. })
        ));
        assert!(matches!(
            Oscillator::benchmark().state_space(),
            Err(ModelError::NotLinear { .. })
        ));
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let mut o = Oscillator::benchmark();
        o.extras = ExtraForces {
            cubic_stiffness: 1e9,
            quadratic_stiffness: -3e6,
            // Engaged at the state below (x = 1e-3): the force's slope is the spring's there.
            clearance: Some(Clearance {
                stiffness: 2e4,
                gap: 5e-4,
            }),
            quadratic_damping: 3.0,
            coulomb: Some(Coulomb {
                force: 2.0,
                smoothing_velocity: 0.05,
            }),
            surface: Some(ForceSurface {
                x_scale: 8e-4,
                v_scale: 0.1,
                coefficients: [1.0, -2.0, 0.5, 0.3, -0.7, 1.1, 0.2, 0.4, -0.9, 0.6],
            }),
            second_mass: Some(SecondMass {
                mass: 0.5,
                stiffness: 2e4,
                damping: 3.0,
            }),
            offset: 0.4,
            chain: None,
        };
        let s = State::new(1e-3, 0.07, 20.0, -2e-4, 0.01);
        let j = o.jacobian(&s);
        for c in 0..5 {
            let h = 1e-6 * s[c].abs().max(1e-3);
            let mut sp = s;
            sp[c] += h;
            let mut sm = s;
            sm[c] -= h;
            let d = (o.derivative(&sp, 0.3) - o.derivative(&sm, 0.3)) / (2.0 * h);
            for r in 0..5 {
                // Central differences: truncation O(h²) relative to the entry's scale.
                assert_relative_eq!(j[(r, c)], d[r], epsilon = 1e-6, max_relative = 1e-6);
            }
        }
    }

    /// The clearance spring is off within its gap and continuous where it engages; the
    /// surface's force is its coefficients times its basis at the scaled state; a model with
    /// either is not linear, and their bad values are named.
    #[test]
    fn clearance_and_surface_forces_are_what_they_say() {
        let g = Clearance {
            stiffness: 3e4,
            gap: 1e-3,
        };
        assert_eq!(g.force(0.5e-3), 0.0);
        assert_eq!(g.force(-1e-3), 0.0);
        assert_relative_eq!(g.force(1.5e-3), 15.0, max_relative = 1e-12);
        assert_relative_eq!(g.force(-3e-3), -60.0, max_relative = 1e-12);
        let mut c = [0.0; SURFACE_TERMS];
        c[1] = 2.0; // ξ³
        c[5] = -1.0; // η|η|
        let sf = ForceSurface {
            x_scale: 1e-3,
            v_scale: 0.2,
            coefficients: c,
        };
        // ξ = 2, η = −0.5: 2·8 − (−0.5·0.5) = 16.25 N.
        assert_relative_eq!(sf.force(2e-3, -0.1), 16.25, max_relative = 1e-12);
        let mut o = Oscillator::linear(1.0, 1.0, 1.0);
        o.extras.surface = Some(sf);
        assert!(matches!(
            o.state_space(),
            Err(ModelError::NotLinear {
                what: "a force surface"
            })
        ));
        o.extras.surface = None;
        o.extras.clearance = Some(Clearance {
            stiffness: 1.0,
            gap: 0.0,
        });
        assert_eq!(
            o.validate(),
            Err(ModelError::NonPositive {
                name: "clearance.gap",
                value: 0.0
            })
        );
    }

    #[test]
    fn zener_polynomial_matches_state_space() {
        let o = Oscillator::zener(
            2.0,
            6.4,
            3334.4,
            ZenerParams {
                k_inf: 122150.0,
                omega: 37.68,
            },
        );
        let p = o.characteristic_polynomial().unwrap();
        let q = o.state_space().unwrap().characteristic_polynomial();
        for (a, b) in p.iter().zip(&q) {
            // q is monic: compare with p / m; Faddeev-LeVerrier is exact up to rounding.
            assert_relative_eq!(a / p[0], *b, max_relative = 1e-12);
        }
    }
}
