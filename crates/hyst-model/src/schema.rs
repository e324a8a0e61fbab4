//! The oscillator's one JSON schema (feature `serde`): what `hyst simulate --params` reads
//! and every report writes.
//!
//! ```json
//! {"mass": 2, "damping": 10, "stiffness": 5e4,
//!  "bouc_wen": {"alpha": 5e4, "beta_gamma": 800, "beta_delta": -1100, "nu": 1},
//!  "cubic_stiffness": 0, "quadratic_stiffness": 0, "quadratic_damping": 0, "offset": 0,
//!  "clearance": {"stiffness": 3e4, "gap": 1e-3},
//!  "coulomb": {"force": 1, "smoothing_velocity": 1e-3},
//!  "surface": {"x_scale": 1e-3, "v_scale": 0.2, "terms": {"xi^3": 4.5, "xi^2 eta": -1}},
//!  "second_mass": {"mass": 0.5, "stiffness": 2e4, "damping": 3},
//!  "chain": {"delay": 1.3e-3, "lag": 2e-4}}
//! ```
//!
//! Only `mass`, `damping` and `stiffness` are required. `bouc_wen` may give `beta`, `gamma`,
//! `delta` in place of the products; `zener: {"k_inf", "omega"}` replaces it for a relaxation
//! element; with neither the oscillator is linear. A surface's terms are named as in
//! [`ForceSurface::TERMS`]; terms not named are 0. Extra terms that are off are not written.
//!
//! The short form earlier reports wrote is read too: `m`, `c`, `k` for the mass, damping and
//! stiffness, and the element's constants at the top level (`alpha`, `beta_gamma`,
//! `beta_delta`, `nu` for Bouc-Wen; `k_inf`, `omega` for Zener). Any other key is an error
//! naming it and the keys allowed, and a model that [`Oscillator::validate`] refuses is an
//! error naming the parameter.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::{
    BoucWen, Clearance, Coulomb, ExtraForces, ForceSurface, MeasurementChain, ModelError,
    Oscillator, Restoring, SURFACE_TERMS, SecondMass, ZenerParams,
};

/// Why a JSON oscillator is not a model (beyond what serde itself reports).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SchemaError {
    /// A field needed by what else is given is missing.
    #[error("`{field}` is missing ({why})")]
    Missing {
        /// The field, with its parent (`bouc_wen.beta_delta`).
        field: &'static str,
        /// What asked for it.
        why: &'static str,
    },
    /// Two forms of one thing are given at once.
    #[error("`{first}` and `{second}` are given together; give one")]
    Conflict {
        /// One form.
        first: &'static str,
        /// The other.
        second: &'static str,
    },
    /// A surface term with a name not in [`ForceSurface::TERMS`].
    #[error("unknown surface term `{name}`, expected one of {allowed}")]
    SurfaceTerm {
        /// The name given.
        name: String,
        /// The names allowed.
        allowed: String,
    },
    /// The parameters do not describe a valid model.
    #[error(transparent)]
    Model(#[from] ModelError),
}

/// A Bouc-Wen element as written: the products, or β, γ, δ apart.
#[derive(Debug, Clone, Copy, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct BoucWenFile {
    alpha: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    beta_gamma: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    beta_delta: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    beta: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    gamma: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    delta: Option<f64>,
    #[serde(default = "one")]
    nu: f64,
}

fn one() -> f64 {
    1.0
}

/// `v`, or the error that `field` is missing, saying what asked for it.
fn need(v: Option<f64>, field: &'static str, why: &'static str) -> Result<f64, SchemaError> {
    v.ok_or(SchemaError::Missing { field, why })
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

impl From<BoucWen> for BoucWenFile {
    fn from(b: BoucWen) -> Self {
        BoucWenFile {
            alpha: b.alpha,
            beta_gamma: Some(b.beta_gamma()),
            beta_delta: Some(b.beta_delta()),
            nu: b.nu,
            ..Default::default()
        }
    }
}

impl TryFrom<BoucWenFile> for BoucWen {
    type Error = SchemaError;
    fn try_from(f: BoucWenFile) -> Result<Self, SchemaError> {
        let products = f.beta_gamma.is_some() || f.beta_delta.is_some();
        let separate = f.beta.is_some() || f.gamma.is_some() || f.delta.is_some();
        let b = match (products, separate) {
            (true, true) => {
                return Err(SchemaError::Conflict {
                    first: "bouc_wen.beta_gamma/beta_delta",
                    second: "bouc_wen.beta/gamma/delta",
                });
            }
            (false, true) => {
                let why = "β, γ, δ are given apart";
                BoucWen {
                    alpha: f.alpha,
                    beta: need(f.beta, "bouc_wen.beta", why)?,
                    gamma: need(f.gamma, "bouc_wen.gamma", why)?,
                    delta: need(f.delta, "bouc_wen.delta", why)?,
                    nu: f.nu,
                }
            }
            _ => {
                let why = "a Bouc-Wen element needs βγ and βδ (or β, γ, δ)";
                BoucWen::from_products(
                    f.alpha,
                    need(f.beta_gamma, "bouc_wen.beta_gamma", why)?,
                    need(f.beta_delta, "bouc_wen.beta_delta", why)?,
                    f.nu,
                )
            }
        };
        b.validate()?;
        Ok(b)
    }
}

/// A force surface as written: its scales and its non-zero terms by name.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SurfaceFile {
    x_scale: f64,
    v_scale: f64,
    #[serde(default)]
    terms: BTreeMap<String, f64>,
}

impl From<ForceSurface> for SurfaceFile {
    fn from(s: ForceSurface) -> Self {
        SurfaceFile {
            x_scale: s.x_scale,
            v_scale: s.v_scale,
            terms: ForceSurface::TERMS
                .iter()
                .zip(&s.coefficients)
                .filter(|(_, c)| **c != 0.0)
                .map(|(n, c)| (n.to_string(), *c))
                .collect(),
        }
    }
}

impl TryFrom<SurfaceFile> for ForceSurface {
    type Error = SchemaError;
    fn try_from(f: SurfaceFile) -> Result<Self, SchemaError> {
        let mut coefficients = [0.0; SURFACE_TERMS];
        for (name, c) in f.terms {
            let i = ForceSurface::TERMS
                .iter()
                .position(|n| *n == name)
                .ok_or_else(|| SchemaError::SurfaceTerm {
                    name: name.clone(),
                    allowed: ForceSurface::TERMS.map(|t| format!("`{t}`")).join(", "),
                })?;
            coefficients[i] = c;
        }
        Ok(ForceSurface {
            x_scale: f.x_scale,
            v_scale: f.v_scale,
            coefficients,
        })
    }
}

/// The oscillator as written. The extras sit at the top level beside the mass (serde's
/// `flatten` would lose `deny_unknown_fields`, so they are listed here).
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct OscillatorFile {
    #[serde(alias = "m")]
    mass: f64,
    #[serde(alias = "c")]
    damping: f64,
    #[serde(alias = "k")]
    stiffness: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    bouc_wen: Option<BoucWenFile>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    zener: Option<ZenerParams>,
    // The short form's element constants, read only.
    #[serde(default, skip_serializing)]
    alpha: Option<f64>,
    #[serde(default, skip_serializing)]
    beta_gamma: Option<f64>,
    #[serde(default, skip_serializing)]
    beta_delta: Option<f64>,
    #[serde(default, skip_serializing)]
    nu: Option<f64>,
    #[serde(default, skip_serializing)]
    k_inf: Option<f64>,
    #[serde(default, skip_serializing)]
    omega: Option<f64>,
    #[serde(default, skip_serializing_if = "is_zero")]
    cubic_stiffness: f64,
    #[serde(default, skip_serializing_if = "is_zero")]
    quadratic_stiffness: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    clearance: Option<Clearance>,
    #[serde(default, skip_serializing_if = "is_zero")]
    quadratic_damping: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    coulomb: Option<Coulomb>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    surface: Option<SurfaceFile>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    second_mass: Option<SecondMass>,
    #[serde(default, skip_serializing_if = "is_zero")]
    offset: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    chain: Option<MeasurementChain>,
}

impl From<Oscillator> for OscillatorFile {
    fn from(o: Oscillator) -> Self {
        let e = o.extras;
        OscillatorFile {
            mass: o.mass,
            damping: o.damping,
            stiffness: o.stiffness,
            bouc_wen: match o.restoring {
                Restoring::BoucWen(b) => Some(b.into()),
                _ => None,
            },
            zener: match o.restoring {
                Restoring::Zener(z) => Some(z),
                _ => None,
            },
            cubic_stiffness: e.cubic_stiffness,
            quadratic_stiffness: e.quadratic_stiffness,
            clearance: e.clearance,
            quadratic_damping: e.quadratic_damping,
            coulomb: e.coulomb,
            surface: e.surface.map(Into::into),
            second_mass: e.second_mass,
            offset: e.offset,
            chain: o.chain,
            ..Default::default()
        }
    }
}

impl OscillatorFile {
    /// The restoring element, from the nested form or the short form's top-level constants.
    fn restoring(&self) -> Result<Restoring, SchemaError> {
        let short_bw = self.alpha.is_some()
            || self.beta_gamma.is_some()
            || self.beta_delta.is_some()
            || self.nu.is_some();
        let short_zener = self.k_inf.is_some() || self.omega.is_some();
        let forms = [
            (self.bouc_wen.is_some(), "bouc_wen"),
            (self.zener.is_some(), "zener"),
            (short_bw, "alpha/beta_gamma/beta_delta/nu"),
            (short_zener, "k_inf/omega"),
        ];
        let mut given = forms.iter().filter(|(on, _)| *on).map(|(_, n)| *n);
        if let (Some(first), Some(second)) = (given.next(), given.next()) {
            return Err(SchemaError::Conflict { first, second });
        }
        if let Some(b) = self.bouc_wen {
            return Ok(Restoring::BoucWen(b.try_into()?));
        }
        if let Some(z) = self.zener {
            z.validate()?;
            return Ok(Restoring::Zener(z));
        }
        if short_bw {
            let why = "the short form of a Bouc-Wen element";
            let b = BoucWenFile {
                alpha: need(self.alpha, "alpha", why)?,
                beta_gamma: Some(need(self.beta_gamma, "beta_gamma", why)?),
                beta_delta: Some(need(self.beta_delta, "beta_delta", why)?),
                nu: self.nu.unwrap_or(1.0),
                ..Default::default()
            };
            return Ok(Restoring::BoucWen(b.try_into()?));
        }
        if short_zener {
            let why = "the short form of a Zener element";
            let z = ZenerParams {
                k_inf: need(self.k_inf, "k_inf", why)?,
                omega: need(self.omega, "omega", why)?,
            };
            z.validate()?;
            return Ok(Restoring::Zener(z));
        }
        Ok(Restoring::None)
    }
}

impl TryFrom<OscillatorFile> for Oscillator {
    type Error = SchemaError;
    fn try_from(f: OscillatorFile) -> Result<Self, SchemaError> {
        let o = Oscillator {
            mass: f.mass,
            damping: f.damping,
            stiffness: f.stiffness,
            restoring: f.restoring()?,
            extras: ExtraForces {
                cubic_stiffness: f.cubic_stiffness,
                quadratic_stiffness: f.quadratic_stiffness,
                clearance: f.clearance,
                quadratic_damping: f.quadratic_damping,
                coulomb: f.coulomb,
                surface: f.surface.map(TryInto::try_into).transpose()?,
                second_mass: f.second_mass,
                offset: f.offset,
            },
            chain: f.chain,
        };
        o.validate()?;
        Ok(o)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ZENER: ZenerParams = ZenerParams {
        k_inf: 81432.0,
        omega: 61.72,
    };

    fn read(text: &str) -> Result<Oscillator, String> {
        serde_json::from_str(text).map_err(|e| e.to_string())
    }

    fn full() -> Oscillator {
        let mut o = Oscillator::benchmark();
        o.extras.second_mass = Some(SecondMass {
            mass: 0.5,
            stiffness: 2e4,
            damping: 3.0,
        });
        o.extras.cubic_stiffness = 1e8;
        o.extras.quadratic_stiffness = -2e6;
        o.extras.quadratic_damping = 4.0;
        o.extras.offset = 0.25;
        o.chain = Some(MeasurementChain {
            delay: 1.3e-3,
            lag: 2e-4,
        });
        o.extras.clearance = Some(Clearance {
            stiffness: 3e4,
            gap: 1e-3,
        });
        o.extras.coulomb = Some(Coulomb {
            force: 1.5,
            smoothing_velocity: 1e-3,
        });
        let mut coefficients = [0.0; SURFACE_TERMS];
        coefficients[3] = 0.25;
        coefficients[8] = -1.5;
        o.extras.surface = Some(ForceSurface {
            x_scale: 1e-3,
            v_scale: 0.2,
            coefficients,
        });
        o
    }

    #[test]
    fn every_part_round_trips() {
        let o = full();
        let back = read(&serde_json::to_string(&o).unwrap()).unwrap();
        // β is normalised to 1 by the products form; only βγ and βδ enter the dynamics.
        let (Restoring::BoucWen(a), Restoring::BoucWen(b)) = (o.restoring, back.restoring) else {
            panic!("lost the Bouc-Wen element");
        };
        assert_eq!(a.beta_gamma(), b.beta_gamma());
        assert_eq!(a.beta_delta(), b.beta_delta());
        assert_eq!((a.alpha, a.nu), (b.alpha, b.nu));
        assert_eq!(o.extras, back.extras);
        let z = Oscillator::zener(2.0, 11.7, 46899.0, ZENER);
        assert_eq!(read(&serde_json::to_string(&z).unwrap()).unwrap(), z);
    }

    #[test]
    fn terms_that_are_off_are_not_written() {
        let v = serde_json::to_value(Oscillator::linear(2.0, 10.0, 5e4)).unwrap();
        assert_eq!(
            v,
            serde_json::json!({"mass": 2.0, "damping": 10.0, "stiffness": 5e4})
        );
    }

    #[test]
    fn the_short_form_is_read_alike() {
        let short = read(
            r#"{"m": 2, "c": 10, "k": 5e4, "alpha": 5e4, "beta_gamma": 800, "beta_delta": -1100, "nu": 1}"#,
        )
        .unwrap();
        let long = read(
            r#"{"mass": 2, "damping": 10, "stiffness": 5e4,
                "bouc_wen": {"alpha": 5e4, "beta_gamma": 800, "beta_delta": -1100}}"#,
        )
        .unwrap();
        assert_eq!(short, long);
        let z = read(r#"{"m": 2, "c": 11.7, "k": 46899, "k_inf": 81432, "omega": 61.72}"#).unwrap();
        assert_eq!(z, Oscillator::zener(2.0, 11.7, 46899.0, ZENER));
    }

    #[test]
    fn unknown_and_missing_keys_are_named() {
        let e =
            read(r#"{"mass": 2, "damping": 1, "stiffness": 3, "cubic_stifness": 5}"#).unwrap_err();
        assert!(
            e.contains("unknown field `cubic_stifness`") && e.contains("`cubic_stiffness`"),
            "{e}"
        );
        let e = read(r#"{"mass": 2, "damping": 1}"#).unwrap_err();
        assert!(e.contains("missing field `stiffness`"), "{e}");
        let e = read(r#"{"mass": -2, "damping": 1, "stiffness": 3}"#).unwrap_err();
        assert!(e.contains("`mass` must be > 0, got -2"), "{e}");
        let e = read(r#"{"mass": 2, "damping": 1, "stiffness": 3, "zener": {"k_inf": 1}}"#)
            .unwrap_err();
        assert!(e.contains("missing field `omega`"), "{e}");
        let e = read(
            r#"{"mass": 2, "damping": 1, "stiffness": 3, "bouc_wen": {"alpha": 1, "beta_gamma": 1}}"#,
        )
        .unwrap_err();
        assert!(e.contains("`bouc_wen.beta_delta` is missing"), "{e}");
        let e = read(
            r#"{"mass": 2, "damping": 1, "stiffness": 3, "surface": {"x_scale": 1, "v_scale": 1, "terms": {"xi^7": 1}}}"#,
        )
        .unwrap_err();
        assert!(
            e.contains("unknown surface term `xi^7`") && e.contains("`xi^2 eta`"),
            "{e}"
        );
        let e = read(
            r#"{"mass": 2, "damping": 1, "stiffness": 3, "zener": {"k_inf": 1, "omega": 2}, "alpha": 4}"#,
        )
        .unwrap_err();
        assert!(e.contains("give one"), "{e}");
        let e = read(r#"{"mass": "two", "damping": 1, "stiffness": 3}"#).unwrap_err();
        assert!(e.contains("invalid type: string \"two\""), "{e}");
    }
}
