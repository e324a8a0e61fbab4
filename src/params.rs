//! Oscillator parameters as JSON, for `--params FILE.json` and for reports.
//!
//! ```json
//! {"mass": 2, "damping": 10, "stiffness": 5e4,
//!  "bouc_wen": {"alpha": 5e4, "beta_gamma": 800, "beta_delta": -1100, "nu": 1},
//!  "cubic_stiffness": 0, "quadratic_stiffness": 0, "quadratic_damping": 0, "offset": 0,
//!  "clearance": {"stiffness": 3e4, "gap": 1e-3},
//!  "coulomb": {"force": 1, "smoothing_velocity": 1e-3},
//!  "surface": {"x_scale": 1e-3, "v_scale": 0.2, "terms": {"xi^3": 4.5, "xi^2 eta": -1}},
//!  "second_mass": {"mass": 0.5, "stiffness": 2e4, "damping": 3}}
//! ```
//! `bouc_wen` may instead give `beta`, `gamma`, `delta`; `zener: {"k_inf", "omega"}` replaces it
//! for a relaxation element; with neither the oscillator is linear. A surface's terms are
//! named as in [`hyst_model::ForceSurface::TERMS`] (ξ = x/x_scale, η = ẋ/v_scale, force in
//! N); terms not named are 0. Only `mass`, `damping` and `stiffness` are required.

use hyst_model::{
    BoucWen, Clearance, Coulomb, ExtraForces, ForceSurface, Oscillator, Restoring, SURFACE_TERMS,
    SecondMass, ZenerParams,
};
use serde_json::{Map, Value, json};

/// Errors of reading parameters from JSON.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ParamsError {
    /// The text is not JSON.
    #[error("not valid JSON: {0}")]
    Json(#[from] serde_json::Error),
    /// A required field is missing or not a number.
    #[error("field `{0}` is missing or not a number")]
    Field(String),
    /// The parameters do not describe a valid model.
    #[error("{0}")]
    Model(#[from] hyst_model::ModelError),
}

fn num(obj: &Map<String, Value>, prefix: &str, key: &str) -> Result<f64, ParamsError> {
    obj.get(key)
        .and_then(Value::as_f64)
        .ok_or_else(|| ParamsError::Field(format!("{prefix}{key}")))
}

fn opt_num(
    obj: &Map<String, Value>,
    prefix: &str,
    key: &str,
    default: f64,
) -> Result<f64, ParamsError> {
    match obj.get(key) {
        None => Ok(default),
        Some(_) => num(obj, prefix, key),
    }
}

fn object<'a>(v: &'a Value, name: &str) -> Result<&'a Map<String, Value>, ParamsError> {
    v.as_object()
        .ok_or_else(|| ParamsError::Field(name.to_string()))
}

/// Parse and validate an oscillator from JSON text.
pub fn oscillator_from_json(text: &str) -> Result<Oscillator, ParamsError> {
    let v: Value = serde_json::from_str(text)?;
    let o = object(&v, "(top level object)")?;
    let mut osc = Oscillator::linear(
        num(o, "", "mass")?,
        num(o, "", "damping")?,
        num(o, "", "stiffness")?,
    );
    if let Some(bw) = o.get("bouc_wen") {
        let b = object(bw, "bouc_wen")?;
        let nu = opt_num(b, "bouc_wen.", "nu", 1.0)?;
        let alpha = num(b, "bouc_wen.", "alpha")?;
        let p = if b.contains_key("beta_gamma") || b.contains_key("beta_delta") {
            BoucWen::from_products(
                alpha,
                num(b, "bouc_wen.", "beta_gamma")?,
                num(b, "bouc_wen.", "beta_delta")?,
                nu,
            )
        } else {
            BoucWen {
                alpha,
                beta: num(b, "bouc_wen.", "beta")?,
                gamma: num(b, "bouc_wen.", "gamma")?,
                delta: num(b, "bouc_wen.", "delta")?,
                nu,
            }
        };
        osc.restoring = Restoring::BoucWen(p);
    } else if let Some(z) = o.get("zener") {
        let z = object(z, "zener")?;
        osc.restoring = Restoring::Zener(ZenerParams {
            k_inf: num(z, "zener.", "k_inf")?,
            omega: num(z, "zener.", "omega")?,
        });
    }
    let mut extras = ExtraForces {
        cubic_stiffness: opt_num(o, "", "cubic_stiffness", 0.0)?,
        quadratic_stiffness: opt_num(o, "", "quadratic_stiffness", 0.0)?,
        quadratic_damping: opt_num(o, "", "quadratic_damping", 0.0)?,
        offset: opt_num(o, "", "offset", 0.0)?,
        ..ExtraForces::default()
    };
    if let Some(g) = o.get("clearance") {
        let g = object(g, "clearance")?;
        extras.clearance = Some(Clearance {
            stiffness: num(g, "clearance.", "stiffness")?,
            gap: num(g, "clearance.", "gap")?,
        });
    }
    if let Some(sf) = o.get("surface") {
        let sf = object(sf, "surface")?;
        let mut coefficients = [0.0; SURFACE_TERMS];
        if let Some(t) = sf.get("terms") {
            let t = object(t, "surface.terms")?;
            for name in t.keys() {
                let i = ForceSurface::TERMS
                    .iter()
                    .position(|n| n == name)
                    .ok_or_else(|| ParamsError::Field(format!("surface.terms.{name}")))?;
                coefficients[i] = num(t, "surface.terms.", name)?;
            }
        }
        extras.surface = Some(ForceSurface {
            x_scale: num(sf, "surface.", "x_scale")?,
            v_scale: num(sf, "surface.", "v_scale")?,
            coefficients,
        });
    }
    if let Some(c) = o.get("coulomb") {
        let c = object(c, "coulomb")?;
        extras.coulomb = Some(Coulomb {
            force: num(c, "coulomb.", "force")?,
            smoothing_velocity: num(c, "coulomb.", "smoothing_velocity")?,
        });
    }
    if let Some(s) = o.get("second_mass") {
        let s = object(s, "second_mass")?;
        extras.second_mass = Some(SecondMass {
            mass: num(s, "second_mass.", "mass")?,
            stiffness: num(s, "second_mass.", "stiffness")?,
            damping: num(s, "second_mass.", "damping")?,
        });
    }
    osc.extras = extras;
    osc.validate()?;
    Ok(osc)
}

/// The oscillator as JSON, in the form [`oscillator_from_json`] reads.
pub fn oscillator_to_json(o: &Oscillator) -> Value {
    let mut v = json!({"mass": o.mass, "damping": o.damping, "stiffness": o.stiffness});
    let m = v.as_object_mut().expect("built as an object");
    match &o.restoring {
        Restoring::None => {}
        Restoring::BoucWen(b) => {
            m.insert(
                "bouc_wen".into(),
                json!({"alpha": b.alpha, "beta_gamma": b.beta_gamma(), "beta_delta": b.beta_delta(), "nu": b.nu}),
            );
        }
        Restoring::Zener(z) => {
            m.insert("zener".into(), json!({"k_inf": z.k_inf, "omega": z.omega}));
        }
    }
    insert_extras(m, &o.extras);
    v
}

/// Add the extra force terms that are on to the JSON object `m` (keys as
/// [`oscillator_from_json`] reads them).
pub fn insert_extras(m: &mut Map<String, Value>, e: &ExtraForces) {
    if e.cubic_stiffness != 0.0 {
        m.insert("cubic_stiffness".into(), json!(e.cubic_stiffness));
    }
    if e.quadratic_stiffness != 0.0 {
        m.insert("quadratic_stiffness".into(), json!(e.quadratic_stiffness));
    }
    if e.offset != 0.0 {
        m.insert("offset".into(), json!(e.offset));
    }
    if let Some(g) = &e.clearance {
        m.insert(
            "clearance".into(),
            json!({"stiffness": g.stiffness, "gap": g.gap}),
        );
    }
    if e.quadratic_damping != 0.0 {
        m.insert("quadratic_damping".into(), json!(e.quadratic_damping));
    }
    if let Some(sf) = &e.surface {
        let terms: Map<String, Value> = ForceSurface::TERMS
            .iter()
            .zip(&sf.coefficients)
            .filter(|(_, c)| **c != 0.0)
            .map(|(n, c)| (n.to_string(), json!(c)))
            .collect();
        m.insert(
            "surface".into(),
            json!({"x_scale": sf.x_scale, "v_scale": sf.v_scale, "terms": terms}),
        );
    }
    if let Some(c) = &e.coulomb {
        m.insert(
            "coulomb".into(),
            json!({"force": c.force, "smoothing_velocity": c.smoothing_velocity}),
        );
    }
    if let Some(s) = &e.second_mass {
        m.insert(
            "second_mass".into(),
            json!({"mass": s.mass, "stiffness": s.stiffness, "damping": s.damping}),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip() {
        let mut o = Oscillator::benchmark();
        o.extras.second_mass = Some(SecondMass {
            mass: 0.5,
            stiffness: 2e4,
            damping: 3.0,
        });
        o.extras.cubic_stiffness = 1e8;
        o.extras.quadratic_stiffness = -2e6;
        o.extras.offset = 0.25;
        o.extras.clearance = Some(Clearance {
            stiffness: 3e4,
            gap: 1e-3,
        });
        let mut coefficients = [0.0; SURFACE_TERMS];
        coefficients[3] = 0.25;
        coefficients[8] = -1.5;
        o.extras.surface = Some(ForceSurface {
            x_scale: 1e-3,
            v_scale: 0.2,
            coefficients,
        });
        let text = oscillator_to_json(&o).to_string();
        let back = oscillator_from_json(&text).unwrap();
        // β is normalised to 1 by the products form; the dynamics are identical.
        if let (Restoring::BoucWen(a), Restoring::BoucWen(b)) = (o.restoring, back.restoring) {
            assert_eq!(a.beta_gamma(), b.beta_gamma());
            assert_eq!(a.beta_delta(), b.beta_delta());
        } else {
            panic!("lost the Bouc-Wen element");
        }
        assert_eq!(o.extras, back.extras);
    }

    #[test]
    fn errors_name_the_field() {
        let e = oscillator_from_json(r#"{"mass": 2, "damping": 1}"#).unwrap_err();
        assert_eq!(
            e.to_string(),
            "field `stiffness` is missing or not a number"
        );
        let e = oscillator_from_json(r#"{"mass": -2, "damping": 1, "stiffness": 3}"#).unwrap_err();
        assert!(e.to_string().contains("mass"), "{e}");
        let e = oscillator_from_json(
            r#"{"mass": 2, "damping": 1, "stiffness": 3, "zener": {"k_inf": 1}}"#,
        )
        .unwrap_err();
        assert!(e.to_string().contains("zener.omega"), "{e}");
        let e = oscillator_from_json(
            r#"{"mass": 2, "damping": 1, "stiffness": 3, "surface": {"x_scale": 1, "v_scale": 1, "terms": {"xi^7": 1}}}"#,
        )
        .unwrap_err();
        assert_eq!(
            e.to_string(),
            "field `surface.terms.xi^7` is missing or not a number"
        );
    }
}
