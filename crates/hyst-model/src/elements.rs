//! The restoring element $z$: Bouc-Wen hysteresis (eq. 2) or the Zener relaxation element
//! (eq. 3), each with its state equation.

use crate::ModelError;
use crate::error::{finite, positive};
#[cfg(feature = "serde")]
use crate::schema;

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
pub(crate) fn sign(x: f64) -> f64 {
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
