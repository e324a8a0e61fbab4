//! Does the structure change over the record? The model is fitted again on each half of the
//! estimation rows, and each parameter's two values are compared with their standard errors
//! (the sandwich of [`super::standard_errors`], which holds for coloured residuals): a
//! stiffness or damping that drifts gives halves that differ by many standard errors, where
//! a stationary record, even one the model misses something of, gives the same pseudo-true
//! values in both.

use hyst_model::Oscillator;

use super::fit::{Prepared, fit_on, standard_errors_on};

/// |z| above which a parameter's halves differ: the false-alarm rate of one parameter is
/// 6e-5 for a calibrated standard error, under 1e-3 over the up to 16 parameters of a model.
pub const DRIFT_Z: f64 = 4.0;

/// Iterations of each half's fit: it starts at the whole range's optimum.
const HALF_ITERATIONS: usize = 60;

/// One parameter fitted on each half of the estimation rows.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct HalfChange {
    /// The parameter's name (as in [`super::Estimate::name`]).
    #[cfg_attr(
        feature = "serde",
        serde(deserialize_with = "super::params::deserialize_name")
    )]
    pub name: std::borrow::Cow<'static, str>,
    /// Its value and standard error on the first half.
    #[cfg_attr(feature = "serde", serde(with = "crate::nullable"))]
    pub first: (f64, f64),
    /// Its value and standard error on the second half.
    #[cfg_attr(feature = "serde", serde(with = "crate::nullable"))]
    pub second: (f64, f64),
    /// The difference in combined standard errors, (second − first) / √(se₁² + se₂²).
    #[cfg_attr(feature = "serde", serde(with = "crate::nullable"))]
    pub z: f64,
}

/// Every parameter of `o` fitted on each half of `range`, with their z. `None` when a half
/// does not simulate.
pub(super) fn halves(
    o: &Oscillator,
    rec: &Prepared<'_>,
    range: (usize, usize),
    fit_mass: bool,
) -> Option<Vec<HalfChange>> {
    let mid = range.0 + (range.1 - range.0) / 2;
    let half = |r: (usize, usize)| {
        let (m, _) = fit_on(o, rec, r, fit_mass, HALF_ITERATIONS)?;
        standard_errors_on(&m, rec, r, fit_mass)
    };
    let (a, b) = rayon::join(|| half((range.0, mid)), || half((mid, range.1)));
    let (a, b) = (a?, b?);
    Some(
        a.iter()
            .zip(&b)
            .map(|(a, b)| HalfChange {
                name: a.name.clone(),
                first: (a.value, a.se),
                second: (b.value, b.se),
                z: (b.value - a.value) / (a.se * a.se + b.se * b.se).sqrt(),
            })
            .collect(),
    )
}

/// The parameters whose halves differ by more than [`DRIFT_Z`].
pub fn drifting(changes: &[HalfChange]) -> Vec<&HalfChange> {
    changes.iter().filter(|c| c.z.abs() > DRIFT_Z).collect()
}
