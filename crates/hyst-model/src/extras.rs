//! The extra force terms $f_{\text{extra}}(x, \dot x, x_2, \dot x_2)$ (springs, damping,
//! friction, a force surface, a preload, a second mass), each off by default.

#[cfg(feature = "serde")]
use crate::schema;

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

/// Extra force terms that can be added to any oscillator. All off by default.
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
}

impl ExtraForces {
    /// Whether every extra force term is off.
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
