//! The oscillator: its parameters checked, its state derivative and Jacobian for the
//! integrators, and its linear state-space form and poles.

use nalgebra::{Complex, DMatrix};

use crate::error::{finite, not_negative, positive};
#[cfg(feature = "serde")]
use crate::schema;
use crate::{
    BoucWen, ExtraForces, Jacobian, MeasurementChain, ModelError, Restoring, State, ZenerParams,
};

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
    /// The measurement chain: not structure, but what the acquisition does to the output
    /// ([`MeasurementChain`]); `None` for a record of the displacement itself.
    pub chain: Option<MeasurementChain>,
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
            chain: None,
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
        if let Some(ch) = &self.chain {
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
