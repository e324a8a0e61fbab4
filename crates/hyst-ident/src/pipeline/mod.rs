//! The paper's pipeline on one record, one step per module — `prepare` (step 1–2),
//! `poles` (3), [`zener_spectrum`] (3b), `models` (4), [`flatness`] (4b), `validation` (5),
//! [`floor`] (the lowest error a class reaches with the input) — and here the whole of it
//! ([`identify`]); `report` the whole job on one record with its validation
//! ([`identify_and_validate`]).

pub mod flatness;
pub mod floor;
mod models;
mod poles;
mod prepare;
mod report;
mod validation;
pub mod zener_spectrum;

pub use models::{Models, build_models};
pub use poles::{SelectedPoles, select_poles};
pub use prepare::{Prepared, prepare, run_ssi};
pub use report::{
    BoucWenCandidate, BoucWenRoute, IdentReport, ProfileRow, Score, ValidationRow,
    identify_and_validate,
};
pub use validation::{
    Validation, ValidationRecord, best_by_validation, epsilon, simulate_model, validate,
    validate_all,
};

use crate::{DampingGuess, IdentError, IdentOptions};
use covssi::SsiResult;
use hyst_model::Oscillator;

/// Everything the pipeline found.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Identification {
    /// Step 1.
    pub prepared: Prepared,
    /// Step 2.
    pub ssi: SsiResult,
    /// Step 3 (with step 3b's pair, real pole and c when it held).
    pub poles: SelectedPoles,
    /// Step 3b, when it ran ([`DampingGuess::ZenerSpectrum`]): the Zener oscillator fitted to
    /// the record's spectrum; [`SelectedPoles::c_source`] says whether it was used.
    pub zener_spectrum: Option<zener_spectrum::ZenerSpectralFit>,
    /// Step 4.
    pub models: Models,
    /// Step 4b, when the excitation band is known: the flatness fit.
    pub flatness: Option<flatness::FlatnessFit>,
}

/// Above this aperiodicity ([`flatness::FlatnessFit::aperiodicity`]) the pipeline warns: the
/// benchmark's records sit near 0.02 (measurement noise); folded with a wrong period the
/// training record gives 2.8.
pub(crate) const APERIODIC: f64 = 0.1;

/// Above this spread of the implied input over the band (dB RMS) the pipeline warns: the
/// benchmark's fits end near 0.2 dB, the mapped starts near 2 dB.
pub(crate) const NOT_FLAT_DB: f64 = 1.0;

/// Step 4b: fit the Bouc-Wen model by flatness of its implied input over the excitation band
/// ([`flatness::fit`]), from the mapped Bouc-Wen model and from the linear one split evenly
/// into k and α; the flatter of the two wins.
pub fn fit_flatness(
    y: &[f64],
    fs: f64,
    models: &Models,
    band: &flatness::ExcitationBand,
) -> Result<flatness::FlatnessFit, IdentError> {
    // Both starts at once (rayon shares the caller's pool; no nested pools).
    let starts: Vec<Oscillator> = models
        .bouc_wen_mapped
        .into_iter()
        .chain([models.linear])
        .collect();
    flatness::fit(y, fs, band, &starts)
}

/// Run steps 1–4 on an output record `y` sampled at `fs`.
pub fn identify(y: &[f64], fs: f64, opts: &IdentOptions) -> Result<Identification, IdentError> {
    if !(opts.mass.is_finite() && opts.mass > 0.0) {
        return Err(IdentError::NonPositiveMass { mass: opts.mass });
    }
    // --mass 1e300 gave a damping of 1e301, an infinite implied input and a Bouc-Wen model
    // "kept" with it: a mass whose stiffness scale leaves double precision is refused.
    let stiffness = opts.mass * (std::f64::consts::PI * fs).powi(2);
    if !(opts.mass >= 1e-150 && stiffness <= 1e150) {
        return Err(IdentError::MassOutOfRange {
            mass: opts.mass,
            stiffness,
        });
    }
    // A band that can never give a flatness fit is refused before the work, not reported in
    // a note after it.
    if let Some(band) = &opts.excitation {
        band.check(fs)?;
    }
    let prepared = prepare(y, fs, opts)?;
    let ssi = run_ssi(&prepared, opts)?;
    let mut poles = select_poles(&ssi, &prepared, opts)?;
    let zener_spectrum = fit_zener_spectrum(y, fs, &prepared, &mut poles, opts);
    let mut models = build_models(&poles, &prepared, opts)?;
    let flatness = match &opts.excitation {
        None => None,
        Some(band) => match fit_flatness(y, fs, &models, band) {
            Ok(f) => {
                if let Some(a) = f.aperiodicity.filter(|&a| a > APERIODIC) {
                    models.notes.push(format!(
                        "the record's first and last periods of {} samples differ by {:.0} % of its RMS: is it periodic with that period, and in steady state?",
                        band.period,
                        100.0 * a
                    ));
                }
                if f.spread_db > NOT_FLAT_DB {
                    models.notes.push(format!(
                        "the fitted model's implied input still varies by {:.2} dB RMS over the band: check the band and the period, or the model class",
                        f.spread_db
                    ));
                }
                models.bouc_wen = Some(f.model);
                Some(f)
            }
            Err(e) => {
                models.notes.push(format!(
                    "flatness fit failed ({e}); the mapped Bouc-Wen model is kept"
                ));
                None
            }
        },
    };
    Ok(Identification {
        prepared,
        ssi,
        poles,
        zener_spectrum,
        models,
        flatness,
    })
}

/// Step 3b ([`DampingGuess::ZenerSpectrum`]): when the pair and the real pole were refined
/// (the record follows the stationary model), fit the Zener oscillator to the spectrum of
/// the record `y` (sampled at `fs`, undecimated) up to three times the pair's frequency (at
/// most fs/4), and take c, the pair and the real pole from it when it holds: misfit within
/// [`covssi::refine::MISFIT_LIMIT`], k > 0, and a most likely c not below 0 by more than
/// three standard errors (then c is held at 0; see [`zener_spectrum`]). Otherwise c stays
/// the low-damping cluster's and a note says why.
pub fn fit_zener_spectrum(
    y: &[f64],
    fs: f64,
    p: &Prepared,
    sel: &mut SelectedPoles,
    opts: &IdentOptions,
) -> Option<zener_spectrum::ZenerSpectralFit> {
    let real = sel.real.filter(|_| sel.refined)?;
    if opts.damping_guess != DampingGuess::ZenerSpectrum {
        return None;
    }
    let centred: Vec<f64> = y.iter().map(|v| v - p.mean).collect();
    // The band: three times the pair's frequency, and at most a quarter of the sampling rate.
    // The model's force is white at every frequency, so the record's spectrum holds the
    // power aliased from above the Nyquist frequency; a real force (band-limited, or behind an
    // anti-aliasing filter) lacks it near there, and where noise does not hide that the fit
    // is biased. At fs/4 the aliased part is (1/3)⁴ ≈ 1 % of the response's.
    let f_max = (3.0 * sel.pair.norm() / (2.0 * std::f64::consts::PI)).min(fs / 4.0);
    match zener_spectrum::fit(&centred, fs, opts.mass, sel.pair, real, f_max) {
        Ok(f) => {
            let why = if f.misfit > covssi::refine::MISFIT_LIMIT {
                Some(format!(
                    "the record does not follow it (misfit {:.3})",
                    f.misfit
                ))
            } else if let Some([c, se]) = f.unconstrained_c.filter(|[c, se]| *c < -3.0 * se) {
                Some(format!(
                    "its most likely c is {c:.3} ± {se:.3} N s/m, below 0 by more than three standard errors (is the force white over the band?)"
                ))
            } else if f.k <= 0.0 {
                Some(format!("it gives k = {:.1} N/m", f.k))
            } else {
                None
            };
            match why {
                Some(why) => sel.notes.push(format!(
                    "Zener spectral fit not used: {why}; c from the {}",
                    sel.c_source
                )),
                None => {
                    sel.pair = f.pair;
                    sel.real = Some(f.real);
                    sel.c = f.c;
                    sel.c_source = match f.unconstrained_c {
                        None => format!(
                            "Zener spectral fit (white force assumed): c = {:.3} ± {:.3} N s/m",
                            f.c, f.se[0]
                        ),
                        Some([c, se]) => format!(
                            "Zener spectral fit (white force assumed): c held at its bound 0, the most likely c being {c:.3} ± {se:.3} N s/m"
                        ),
                    };
                }
            }
            Some(f)
        }
        Err(e) => {
            sel.notes.push(format!(
                "Zener spectral fit failed ({e}); c from the {}",
                sel.c_source
            ));
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A mass whose stiffness scale leaves double precision is refused before any work (it
    /// gave a damping of 1e301 and an infinite implied input, and a Bouc-Wen model "kept").
    #[test]
    fn an_absurd_mass_is_refused() {
        let y: Vec<f64> = (0..4096).map(|k| (0.3 * k as f64).sin()).collect();
        for mass in [1e300, 1e-200] {
            let opts = IdentOptions {
                mass,
                ..IdentOptions::default()
            };
            let e = identify(&y, 750.0, &opts).unwrap_err();
            assert!(matches!(e, IdentError::MassOutOfRange { .. }), "{e}");
            assert!(
                e.to_string().contains("give the mass in other units"),
                "{e}"
            );
        }
    }
}
