//! Step 4: linear, Zener and Bouc-Wen models from the poles.

use crate::{IdentError, IdentOptions, Linearization, Prepared, SelectedPoles};
use hyst_model::{BoucWen, Oscillator};

/// The identified models.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Models {
    /// Linear oscillator from the pair.
    pub linear: Oscillator,
    /// Zener oscillator, when a real pole was found and the mapping gives Ω > 0.
    pub zener: Option<Oscillator>,
    /// Bouc-Wen oscillator: the flatness fit when the excitation band is known and the fit
    /// succeeded, else the mapped one.
    pub bouc_wen: Option<Oscillator>,
    /// Bouc-Wen oscillator from the poles by the chosen [`Linearization`], when it succeeded.
    pub bouc_wen_mapped: Option<Oscillator>,
    /// Amplitude A used (m).
    pub amplitude: f64,
    /// Remarks.
    pub notes: Vec<String>,
}

/// Step 4: models from the poles.
pub fn build_models(
    sel: &SelectedPoles,
    p: &Prepared,
    opts: &IdentOptions,
) -> Result<Models, IdentError> {
    let m = opts.mass;
    if !(m.is_finite() && m > 0.0) {
        return Err(IdentError::NonPositiveMass { mass: m });
    }
    let linear = Oscillator::linear(m, -2.0 * m * sel.pair.re, m * sel.pair.norm_sqr());
    let amplitude = opts.amplitude.resolve(p.sigma_x)?;
    let mut notes = Vec::new();
    let (zener, bouc_wen) = match sel
        .real
        .map(|r| hyst_linearize::zener_from_poles(m, sel.c, sel.pair, r))
    {
        None => (None, None),
        Some(Err(e)) => {
            notes.push(format!("no Zener model: {e}"));
            (None, None)
        }
        Some(Ok(fit)) => {
            let bw = bouc_wen_from(&fit, sel, m, amplitude, opts.linearization, &mut notes);
            (
                Some(Oscillator::zener(m, sel.c, fit.k, fit.zener)),
                bw.map(|b| Oscillator::bouc_wen(m, sel.c, fit.k, b)),
            )
        }
    };
    Ok(Models {
        linear,
        zener,
        bouc_wen_mapped: bouc_wen,
        bouc_wen,
        amplitude,
        notes,
    })
}

/// The Bouc-Wen element from the identified Zener: α by eq. (37), then (βγ, βδ) by eq. (38)
/// or by exact inversion of the describing function (first order if that fails, noted).
pub(crate) fn bouc_wen_from(
    fit: &hyst_linearize::ZenerFit,
    sel: &SelectedPoles,
    m: f64,
    amplitude: f64,
    linearization: Linearization,
    notes: &mut Vec<String>,
) -> Option<BoucWen> {
    let w = sel.pair.norm();
    let alpha = hyst_linearize::paper::eq37_alpha(m, sel.c, fit.k, sel.pair.im);
    match linearization {
        Linearization::Paper => {
            let (bg, bd) = hyst_linearize::paper::eq38_beta(
                alpha,
                fit.zener.k_inf,
                fit.zener.omega,
                amplitude,
                w,
            );
            Some(BoucWen::from_products(alpha, bg, bd, 1.0))
        }
        Linearization::Harmonic => {
            let df = hyst_linearize::zener_at(&fit.zener, w, amplitude);
            match hyst_linearize::bouc_wen_exact(alpha, 1.0, &df) {
                Ok(b) => Some(b),
                Err(e) => {
                    notes.push(format!(
                        "exact describing-function inversion failed ({e}); first-order closed form used"
                    ));
                    hyst_linearize::bouc_wen_first_order(alpha, 1.0, &df).ok()
                }
            }
        }
    }
}
