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

use nalgebra::{SMatrix, SVector};

mod chain;
pub mod display;
mod elements;
mod error;
mod extras;
mod oscillator;
pub mod poly;
#[cfg(feature = "serde")]
pub mod schema;
#[cfg(test)]
mod tests;

pub use chain::MeasurementChain;
pub use elements::{BoucWen, Restoring, ZenerParams};
pub use error::ModelError;
pub use extras::{Clearance, Coulomb, ExtraForces, ForceSurface, SURFACE_TERMS, SecondMass};
pub use oscillator::{Oscillator, StateSpace};

/// State vector $(x, \dot x, z, x_2, \dot x_2)$: displacement, velocity, restoring-element force,
/// and the second mass's displacement and velocity (zero when there is none).
pub type State = SVector<f64, 5>;

/// Jacobian of the state derivative with respect to the state.
pub type Jacobian = SMatrix<f64, 5, 5>;
