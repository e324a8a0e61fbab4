//! One Bouc-Wen model from records at several force levels (step 6).
//!
//! Each record under a white force gives, by step 3b ([`crate::zener_spectrum`]), a Zener
//! oscillator (c, k, k∞, Ω) and the force density q. The Zener element is the statistical
//! linearization of a Bouc-Wen element ([`hyst_linearize::statistical`]):
//! $k_\infty = \alpha - \sqrt{2/\pi}\,\sigma_z(\rho\,\beta\gamma + \beta\delta)$ and
//! $\Omega = \sqrt{2/\pi}\,\sigma_v(\beta\gamma + \rho\,\beta\delta)$, with the moments
//! (σ_v, σ_z, ρ) of the fitted Zener oscillator under q. These are linear in (α, βγ, βδ), so
//! two or more levels give all three by weighted least squares, where one level cannot (the
//! paper's mapping needs eq. 37's α, which does not hold). The linearization leaves c and k
//! as they are: the model's c and k are the levels' inverse-variance weighted means.

use hyst_linearize::LinearizeError;
use hyst_linearize::statistical::{self, LevelEquivalent, ResponseMoments};
use hyst_model::{Oscillator, ZenerParams};

use crate::IdentError;
use crate::zener_spectrum::ZenerSpectralFit;

/// The Bouc-Wen model of several levels.
#[derive(Debug, Clone, PartialEq)]
pub struct LevelsBoucWen {
    /// The oscillator: the fits' mass, c and k their weighted means, the Bouc-Wen element
    /// (ν = 1, β = 1) from the least squares.
    pub oscillator: Oscillator,
    /// Standard errors of (c, k, α, βγ, βδ), from the fits' standard errors.
    pub se: [f64; 5],
    /// χ² per degree of freedom of (α, βγ, βδ) against the levels' (k∞, Ω): near 1 when the
    /// levels agree with one Bouc-Wen element within their standard errors; NaN for two levels.
    pub chi2_per_dof: f64,
    /// Each level's response moments under its fitted model, in the order given.
    pub moments: Vec<ResponseMoments>,
}

/// One Bouc-Wen model from the Zener spectral fits of records at two or more force levels of
/// the same structure (same mass).
pub fn bouc_wen_from_levels(fits: &[&ZenerSpectralFit]) -> Result<LevelsBoucWen, IdentError> {
    let first = match fits {
        [first, _, ..] => first,
        _ => return Err(LinearizeError::TooFewLevels { levels: fits.len() }.into()),
    };
    if let Some(f) = fits.iter().find(|f| f.mass != first.mass) {
        return Err(IdentError::MassesDiffer {
            first: first.mass,
            other: f.mass,
        });
    }
    let mut levels = Vec::with_capacity(fits.len());
    for f in fits {
        let zener = ZenerParams {
            k_inf: f.k_inf,
            omega: f.omega,
        };
        let moments =
            statistical::zener_response_moments(f.mass, f.c, f.k, &zener, f.force_density)?;
        levels.push(LevelEquivalent {
            zener,
            k_inf_se: f.se[2],
            omega_se: f.se[3],
            moments,
        });
    }
    let fit = statistical::bouc_wen_from_levels(&levels)?;
    // A fit held at c = 0 weighs with its most likely c's standard error.
    let c_se = |f: &ZenerSpectralFit| f.unconstrained_c.map_or(f.se[0], |[_, se]| se);
    let (c, c_se) = weighted_mean(fits.iter().map(|f| (f.c, c_se(f))));
    let (k, k_se) = weighted_mean(fits.iter().map(|f| (f.k, f.se[1])));
    if !(c.is_finite() && k.is_finite()) {
        return Err(LinearizeError::Invalid {
            name: "c and k (no level has a finite standard error of them)",
            value: if c.is_finite() { k } else { c },
        }
        .into());
    }
    let oscillator = Oscillator::bouc_wen(first.mass, c, k, fit.bouc_wen);
    Ok(LevelsBoucWen {
        oscillator,
        se: [c_se, k_se, fit.se[0], fit.se[1], fit.se[2]],
        chi2_per_dof: fit.chi2_per_dof,
        moments: levels.iter().map(|l| l.moments).collect(),
    })
}

/// Inverse-variance weighted mean of (value, standard error) pairs with a finite positive
/// standard error, and its standard error; NaN when there is none.
fn weighted_mean(pairs: impl Iterator<Item = (f64, f64)>) -> (f64, f64) {
    let (mut sw, mut swx) = (0.0, 0.0);
    for (x, se) in pairs {
        let w = se.powi(-2);
        if w.is_finite() && w > 0.0 && x.is_finite() {
            sw += w;
            swx += w * x;
        }
    }
    if sw > 0.0 {
        (swx / sw, sw.sqrt().recip())
    } else {
        (f64::NAN, f64::NAN)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fit with the given (c, k, k∞, Ω) and q, the other fields unused here.
    fn fit(c: f64, k: f64, zener: ZenerParams, q: f64, se: [f64; 4]) -> ZenerSpectralFit {
        ZenerSpectralFit {
            mass: 2.0,
            fs: 750.0,
            c,
            k,
            k_inf: zener.k_inf,
            omega: zener.omega,
            se,
            unconstrained_c: None,
            pair: crate::Complex64::new(-1.0, 200.0),
            real: -50.0,
            force_density: q,
            force_density_se: 0.0,
            noise_std: 0.0,
            misfit: 0.0,
            bins: 1000,
            max_frequency_hz: 100.0,
        }
    }

    /// Fits that are the benchmark's exact statistical linearization at three levels give
    /// the benchmark back.
    #[test]
    fn exact_levels_give_the_benchmark() {
        let truth = Oscillator::benchmark();
        let hyst_model::Restoring::BoucWen(bw) = truth.restoring else {
            unreachable!("the benchmark is a Bouc-Wen oscillator")
        };
        let fits: Vec<ZenerSpectralFit> = [10.0, 50.0, 90.0]
            .iter()
            .map(|f: &f64| {
                let q = f * f / 750.0;
                let (z, _) = statistical::equivalent_zener(2.0, 10.0, 5e4, &bw, q).unwrap();
                fit(10.0, 5e4, z, q, [1.0, 1e3, 1e3, 1.0])
            })
            .collect();
        let refs: Vec<&ZenerSpectralFit> = fits.iter().collect();
        let got = bouc_wen_from_levels(&refs).unwrap();
        let o = &got.oscillator;
        let hyst_model::Restoring::BoucWen(b) = o.restoring else {
            panic!("{o:?}")
        };
        assert_eq!((o.mass, o.damping, o.stiffness), (2.0, 10.0, 5e4));
        // The fixed point stops at a relative change of 1e-12; the least squares lose a few
        // digits to the scale of α against βγ.
        approx::assert_relative_eq!(b.alpha, bw.alpha, max_relative = 1e-8);
        approx::assert_relative_eq!(b.beta_gamma(), bw.beta_gamma(), max_relative = 1e-6);
        approx::assert_relative_eq!(b.beta * b.delta, bw.beta * bw.delta, max_relative = 1e-6);
        assert!(got.chi2_per_dof < 1e-6, "{got:?}");
        assert_eq!(got.moments.len(), 3);
        // Bad input: one level, two masses, none.
        assert!(matches!(
            bouc_wen_from_levels(&refs[..1]),
            Err(IdentError::Linearize(LinearizeError::TooFewLevels {
                levels: 1
            }))
        ));
        let other = ZenerSpectralFit {
            mass: 3.0,
            ..fits[0].clone()
        };
        assert!(matches!(
            bouc_wen_from_levels(&[&fits[1], &other]),
            Err(IdentError::MassesDiffer {
                first: 2.0,
                other: 3.0
            })
        ));
        assert!(matches!(
            bouc_wen_from_levels(&[]),
            Err(IdentError::Linearize(LinearizeError::TooFewLevels {
                levels: 0
            }))
        ));
    }

    #[test]
    fn weighted_mean_skips_what_has_no_weight() {
        let (m, se) =
            weighted_mean([(1.0, 1.0), (3.0, 1.0), (100.0, f64::NAN), (7.0, 0.0)].into_iter());
        assert_eq!(m, 2.0);
        // 1/√2 two ways: one rounding apart.
        approx::assert_relative_eq!(se, 0.5f64.sqrt(), max_relative = 1e-15);
        assert!(weighted_mean(std::iter::empty()).0.is_nan());
    }
}
