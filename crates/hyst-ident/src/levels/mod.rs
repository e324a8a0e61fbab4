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
//! as they are: the model's c and k are the levels' inverse-variance weighted means. The
//! relations hold for any exponent ν (with other Gaussian moments), so three or more levels
//! give ν too ([`bouc_wen_and_exponent_from_levels`], and [`SimulationOptions::fit_exponent`]
//! by simulation).

use hyst_linearize::LinearizeError;
use hyst_linearize::statistical::{self, LevelEquivalent, ResponseMoments};
use hyst_model::{BoucWen, Oscillator, ZenerParams};
use nalgebra::{DMatrix, Matrix4, Vector4};

use crate::IdentError;
use crate::zener_spectrum::ZenerSpectralFit;

mod one_record;
mod report;
pub use one_record::{
    BoucWenParameter, OneRecord, OneRecordBoucWen, PROFILE_RATIOS, ProfilePoint,
    beta_delta_profile, bouc_wen_from_one_record,
};
pub use report::{
    Level, LevelsModels, LevelsOptions, LevelsReport, LevelsValidation, fit_levels, levels_report,
};

/// The Bouc-Wen model of several levels.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct LevelsBoucWen {
    /// The oscillator: the fits' mass, c and k their weighted means, the Bouc-Wen element
    /// (β = 1; ν = 1 unless fitted) from the least squares.
    pub oscillator: Oscillator,
    /// Standard errors of (c, k, α, βγ, βδ), from the fits' standard errors (those of α, βγ,
    /// βδ at the fitted ν).
    #[cfg_attr(feature = "serde", serde(with = "crate::nullable"))]
    pub se: [f64; 5],
    /// Standard error of ν from its profile χ² (NaN when ν is held at 1, or when the χ² + 1
    /// interval reaches an end of the range searched).
    #[cfg_attr(feature = "serde", serde(with = "crate::nullable"))]
    pub nu_se: f64,
    /// χ² per degree of freedom of (α, βγ, βδ) against the levels' (k∞, Ω): near 1 when the
    /// levels agree with one Bouc-Wen element within their standard errors; NaN for two levels.
    #[cfg_attr(feature = "serde", serde(with = "crate::nullable"))]
    pub chi2_per_dof: f64,
    /// Each level's response moments under its fitted model, in the order given.
    pub moments: Vec<ResponseMoments>,
}

/// One Bouc-Wen model (ν = 1) from the Zener spectral fits of records at two or more force
/// levels of the same structure (same mass).
pub fn bouc_wen_from_levels(fits: &[&ZenerSpectralFit]) -> Result<LevelsBoucWen, IdentError> {
    from_levels(fits, false)
}

/// [`bouc_wen_from_levels`] with the exponent ν fitted too, from three or more levels
/// ([`statistical::exponent_from_levels`]).
pub fn bouc_wen_and_exponent_from_levels(
    fits: &[&ZenerSpectralFit],
) -> Result<LevelsBoucWen, IdentError> {
    from_levels(fits, true)
}

fn from_levels(
    fits: &[&ZenerSpectralFit],
    fit_exponent: bool,
) -> Result<LevelsBoucWen, IdentError> {
    let mass = shared_mass(fits)?;
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
    let (fit, nu_se) = if fit_exponent {
        let e = statistical::exponent_from_levels(&levels)?;
        (e.fit, e.nu_se)
    } else {
        (statistical::bouc_wen_from_levels(&levels, 1.0)?, f64::NAN)
    };
    let (c, c_se) = weighted_mean(fits.iter().map(|f| (f.c, c_standard_error(f))));
    let (k, k_se) = weighted_mean(fits.iter().map(|f| (f.k, f.se[1])));
    if !(c.is_finite() && k.is_finite()) {
        return Err(LinearizeError::Invalid {
            name: "c and k (no level has a finite standard error of them)",
            value: if c.is_finite() { k } else { c },
        }
        .into());
    }
    let oscillator = Oscillator::bouc_wen(mass, c, k, fit.bouc_wen);
    Ok(LevelsBoucWen {
        oscillator,
        se: [c_se, k_se, fit.se[0], fit.se[1], fit.se[2]],
        nu_se,
        chi2_per_dof: fit.chi2_per_dof,
        moments: levels.iter().map(|l| l.moments).collect(),
    })
}

/// Options of [`bouc_wen_by_simulation`].
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
pub struct SimulationOptions {
    /// Most Levenberg–Marquardt iterations. Default 10.
    pub max_iterations: usize,
    /// Stop when an iteration lowers the weighted sum of squares by less than this fraction of
    /// it. Default 1e-4.
    pub tolerance: f64,
    /// Seed of the simulated forces and noise, the same at every evaluation (common random
    /// numbers, so that the statistics are smooth functions of the parameters). Default 9000.
    pub seed: u64,
    /// The records are each one steady-state period of a periodic force (as `hyst simulate
    /// --periodic` writes them), and are simulated so. Otherwise (the default, as measured
    /// records are) each level is simulated from rest under a sampled white force, and the
    /// first 30 time constants of its fit's slowest pole are dropped: the simulated
    /// periodogram then leaks as the record's does.
    pub periodic: bool,
    /// Fit the exponent ν too (started from the start's). Default false: ν is the start's.
    pub fit_exponent: bool,
}

impl Default for SimulationOptions {
    fn default() -> Self {
        SimulationOptions {
            max_iterations: 10,
            tolerance: 1e-4,
            seed: 9000,
            periodic: false,
            fit_exponent: false,
        }
    }
}

/// What [`bouc_wen_by_simulation`] finds.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SimulatedBoucWen {
    /// The oscillator (β = 1; ν the start's unless fitted).
    pub oscillator: Oscillator,
    /// Each level's (c, k, k∞, Ω) fitted to the model's simulated record, beside the measured
    /// fit's.
    pub simulated: Vec<[f64; 4]>,
    /// RMS of (simulated − measured) over every level's four numbers, in the measured fit's
    /// covariance (whitened): about √2 when the model explains each level within the noise
    /// of both records.
    #[cfg_attr(feature = "serde", serde(with = "crate::nullable"))]
    pub residual_rms: f64,
    /// Levenberg–Marquardt iterations done.
    pub iterations: usize,
    /// Standard errors of (c, k, α, βγ, βδ): 2 (JᵀJ)⁻¹ from the last iteration's Jacobian of
    /// the whitened residuals, the 2 for the simulated records' own noise (one simulation per
    /// measured record); NaN without an iteration.
    #[cfg_attr(feature = "serde", serde(with = "crate::nullable"))]
    pub se: [f64; 5],
    /// Standard error of ν, the same way (NaN when ν is not fitted).
    #[cfg_attr(feature = "serde", serde(with = "crate::nullable"))]
    pub nu_se: f64,
}

/// The Bouc-Wen model whose simulated responses give the same Zener fits as the records
/// (indirect inference, the Zener spectral fit the auxiliary model): at each level a white
/// force of the fitted density drives the model for the record's length (one steady-state
/// period of a periodic force, or after a warm-up from rest: [`SimulationOptions::periodic`]),
/// the fitted measurement noise is added, and the record's fit is repeated;
/// (c, k, α, βγ, βδ) minimize the squared differences from the measured fits, whitened by
/// their covariances (Levenberg–Marquardt, finite differences, common random numbers). This
/// removes the bias the Gaussian closure of [`bouc_wen_from_levels`] carries, from which it
/// starts. `lengths` are the records' lengths (samples); `progress` hears each iteration and
/// its weighted sum of squares. Each evaluation simulates every level (in parallel).
pub fn bouc_wen_by_simulation(
    fits: &[&ZenerSpectralFit],
    lengths: &[usize],
    start: &Oscillator,
    opts: &SimulationOptions,
    progress: &(dyn Fn(usize, f64) + Sync),
) -> Result<SimulatedBoucWen, IdentError> {
    shared_mass(fits)?;
    if lengths.len() != fits.len() {
        return Err(IdentError::LengthMismatch {
            input: lengths.len(),
            output: fits.len(),
        });
    }
    let hyst_model::Restoring::BoucWen(bw) = start.restoring else {
        return Err(LinearizeError::Invalid {
            name: "start (a Bouc-Wen oscillator is needed)",
            value: f64::NAN,
        }
        .into());
    };
    // (c, k, α, βγ, βδ), then ν when it is fitted.
    let osc = |p: &[f64]| {
        Oscillator::bouc_wen(
            start.mass,
            p[0],
            p[1],
            BoucWen::from_products(p[2], p[3], p[4], p.get(5).copied().unwrap_or(bw.nu)),
        )
    };
    let weights = fit_weights(fits)?;
    let resid = |a: &Vec<[f64; 4]>| -> Vec<f64> {
        a.iter()
            .zip(fits)
            .zip(&weights)
            .flat_map(|((a, f), w)| {
                let d = Vector4::new(a[0] - f.c, a[1] - f.k, a[2] - f.k_inf, a[3] - f.omega);
                (w * d).iter().copied().collect::<Vec<_>>()
            })
            .collect()
    };
    let mut p = vec![
        start.damping,
        start.stiffness,
        bw.alpha,
        bw.beta_gamma(),
        bw.beta_delta(),
    ];
    if opts.fit_exponent {
        p.push(bw.nu);
    }
    let aux = |p: &[f64]| simulated_fits(&osc(p), fits, lengths, opts);
    let mut nonnegative = vec![false; p.len()];
    nonnegative[0] = true;
    // c at least 0.1 N s/m: large enough that the fits' own convergence tolerance does not
    // show; the others 1e-3.
    let mut min_step = vec![1e-3; p.len()];
    min_step[0] = 0.1;
    let bounds = ParameterSteps {
        nonnegative: &nonnegative,
        min_step: &min_step,
    };
    let fit = indirect_lm(&mut p, &bounds, &aux, &resid, opts, progress)?;
    let se_of = |k: usize| {
        fit.covariance
            .as_ref()
            .filter(|c| k < c.nrows())
            .map_or(f64::NAN, |c| (2.0 * c[(k, k)]).max(0.0).sqrt())
    };
    Ok(SimulatedBoucWen {
        oscillator: osc(&p),
        residual_rms: (fit.cost / fit.residuals as f64).sqrt(),
        simulated: fit.simulated,
        iterations: fit.iterations,
        se: std::array::from_fn(se_of),
        nu_se: se_of(5),
    })
}

/// The auxiliary statistics of `model`: at each level one simulated record of the level's
/// length ([`simulated_record`]) fitted as the measured one was, (c, k, k∞, Ω). In parallel
/// over levels.
fn simulated_fits(
    model: &Oscillator,
    fits: &[&ZenerSpectralFit],
    lengths: &[usize],
    opts: &SimulationOptions,
) -> Result<Vec<[f64; 4]>, IdentError> {
    use rayon::prelude::*;
    model.validate().map_err(|e| IdentError::Sim(e.into()))?;
    fits.par_iter()
        .zip(lengths)
        .enumerate()
        .map(|(i, (f, &n))| {
            let y = simulated_record(model, f, n, opts, i)?;
            let g =
                crate::zener_spectrum::fit(&y, f.fs, f.mass, f.pair, f.real, f.max_frequency_hz)?;
            Ok([g.c, g.k, g.k_inf, g.omega])
        })
        .collect()
}

/// `model`'s record of `n` samples at the level of fit `f` (the `i`th): a white force of the
/// fit's density, its noise added, common random numbers by the options' seed; mean removed.
fn simulated_record(
    model: &Oscillator,
    f: &ZenerSpectralFit,
    n: usize,
    opts: &SimulationOptions,
    i: usize,
) -> Result<Vec<f64>, IdentError> {
    let seed = opts.seed.wrapping_add(2 * i as u64);
    let rms = (f.force_density * f.fs).sqrt();
    let sim = hyst_sim::SimOptions::default();
    let mut y = if opts.periodic {
        let u = hyst_sim::excitation::white_noise(n, rms, seed)?;
        hyst_sim::steady_state_period(model, &u, f.fs, &sim, 1e-10, 200)?.y
    } else {
        let warm = warm_up_samples(f, n);
        let u = hyst_sim::excitation::white_noise(warm + n, rms, seed)?;
        let mut y = hyst_sim::simulate(model, hyst_sim::Input::Sampled(&u), f.fs, warm + n, &sim)?;
        y.drain(..warm);
        y
    };
    hyst_sim::excitation::add_noise(&mut y, f.noise_std, seed + 1)?;
    let mean = y.iter().sum::<f64>() / n as f64;
    y.iter_mut().for_each(|v| *v -= mean);
    Ok(y)
}

/// Weights of each level's residual: the inverse Cholesky factor of its measured fit's
/// covariance, so that the precise combinations (k + k∞ above all) weigh as much as they
/// are precise. A fit held at c = 0 has no variance in c: [`c_standard_error`] stands in,
/// uncorrelated.
fn fit_weights(fits: &[&ZenerSpectralFit]) -> Result<Vec<Matrix4<f64>>, IdentError> {
    fits.iter()
        .map(|f| {
            let mut cov = Matrix4::from_fn(|i, j| f.covariance[i][j]);
            if f.unconstrained_c.is_some() {
                for j in 0..4 {
                    cov[(0, j)] = 0.0;
                    cov[(j, 0)] = 0.0;
                }
                cov[(0, 0)] = c_standard_error(f).powi(2);
            }
            cov.cholesky()
                .and_then(|l| l.l().try_inverse())
                .filter(|w| w.iter().all(|v| v.is_finite()))
                .ok_or_else(|| {
                    LinearizeError::Invalid {
                        name: "a level's fit covariance (not positive definite)",
                        value: f.k,
                    }
                    .into()
                })
        })
        .collect()
}

/// The auxiliary statistics of a parameter vector (here each level's (c, k, k∞, Ω) fitted
/// to the model's simulated record).
pub(crate) type AuxiliaryStatistics<'a, S> = dyn Fn(&[f64]) -> Result<S, IdentError> + Sync + 'a;

/// Where the indirect-inference fit ended.
pub(crate) struct IndirectFit<S> {
    /// The auxiliary statistics at the optimum.
    pub(crate) simulated: S,
    /// Weighted sum of squares there.
    pub(crate) cost: f64,
    /// Residuals in the sum.
    pub(crate) residuals: usize,
    pub(crate) iterations: usize,
    /// Whether an iteration gained less than the tolerance (else the limit stopped it).
    pub(crate) converged: bool,
    /// (JᵀJ)⁻¹ of the last iteration's Jacobian, when it is invertible.
    pub(crate) covariance: Option<DMatrix<f64>>,
    /// The last iteration's Jacobian of the residuals (one column per parameter).
    pub(crate) jacobian: Option<Vec<Vec<f64>>>,
}

/// How [`indirect_lm`] steps each parameter: which may not go below 0, and the smallest
/// finite-difference step of each.
pub(crate) struct ParameterSteps<'a> {
    pub(crate) nonnegative: &'a [bool],
    pub(crate) min_step: &'a [f64],
}

/// The crate's Levenberg–Marquardt on the simulated statistics: forward differences of
/// 1 % of each parameter (at least its `min_step`), λ from 1e-2, ÷3 on success (at least
/// 1e-7), ×10 on failure up to 1e6; stops when an iteration gains less than the options'
/// tolerance. The `nonnegative` parameters are held at 0 or above.
pub(crate) fn indirect_lm<S>(
    p: &mut Vec<f64>,
    bounds: &ParameterSteps<'_>,
    aux: &AuxiliaryStatistics<'_, S>,
    resid: &(dyn Fn(&S) -> Vec<f64> + Sync),
    opts: &SimulationOptions,
    progress: &(dyn Fn(usize, f64) + Sync),
) -> Result<IndirectFit<S>, IdentError> {
    use rayon::prelude::*;
    const SCHEDULE: crate::LmSchedule = crate::LmSchedule {
        shrink: 1.0 / 3.0,
        grow: 10.0,
        min: 1e-7,
        max: 1e6,
    };
    let sum_sq = |r: &[f64]| r.iter().map(|v| v * v).sum::<f64>();
    let mut sim = aux(p)?;
    let mut r = resid(&sim);
    let mut cost = sum_sq(&r);
    let mut lambda: f64 = 1e-2;
    let mut iterations = 0;
    let mut last_jtj = None;
    let mut last_jacobian = None;
    let mut converged = false;
    while iterations < opts.max_iterations {
        iterations += 1;
        let steps: Vec<f64> = p
            .iter()
            .enumerate()
            .map(|(k, v)| (0.01 * v.abs()).max(bounds.min_step[k]))
            .collect();
        let columns: Vec<Vec<f64>> = (0..p.len())
            .into_par_iter()
            .map(|k| {
                // Forward, or backward where the forward step leaves what the model
                // allows (a share reaching 1, say).
                let at = |h: f64| -> Result<Vec<f64>, IdentError> {
                    let mut q = p.clone();
                    q[k] += h;
                    let rq = resid(&aux(&q)?);
                    Ok(rq.iter().zip(&r).map(|(a, b)| (a - b) / h).collect())
                };
                at(steps[k]).or_else(|_| at(-steps[k]))
            })
            .collect::<Result<_, IdentError>>()?;
        let (jtj, jtr) = crate::normal_equations(&columns, &r);
        last_jtj = Some(DMatrix::from_fn(p.len(), p.len(), |i, j| jtj[i][j]));
        last_jacobian = Some(columns);
        let before = cost;
        crate::lm_step_with(&SCHEDULE, &jtj, &jtr, &mut lambda, |step| {
            let mut q: Vec<f64> = p.iter().zip(step).map(|(a, b)| a - b).collect();
            for (v, _) in q.iter_mut().zip(bounds.nonnegative).filter(|(_, n)| **n) {
                *v = v.max(0.0);
            }
            let s = aux(&q).ok()?;
            let rq = resid(&s);
            let c = sum_sq(&rq);
            (c < cost).then(|| {
                (*p, sim, r, cost) = (q, s, rq, c);
                true
            })
        });
        progress(iterations, cost);
        if before - cost <= opts.tolerance * before {
            converged = true;
            break;
        }
    }
    Ok(IndirectFit {
        simulated: sim,
        cost,
        residuals: r.len(),
        iterations,
        converged,
        covariance: last_jtj.and_then(|m| m.try_inverse()),
        jacobian: last_jacobian,
    })
}

/// Samples to simulate from rest before a level's simulated record starts: 30 time constants
/// of the fit's slowest pole (its transient is then below e⁻³⁰ of where it began), at most
/// the record's length `n` (a pole that slow is not resolved by the record anyway).
fn warm_up_samples(f: &ZenerSpectralFit, n: usize) -> usize {
    let slowest = f.pair.re.abs().min(f.real.abs());
    let warm = 30.0 / slowest * f.fs;
    if warm.is_finite() && warm < n as f64 {
        warm.ceil() as usize
    } else {
        n
    }
}

/// The mass the levels' fits share (two or more of them, of one structure).
fn shared_mass(fits: &[&ZenerSpectralFit]) -> Result<f64, IdentError> {
    let first = match fits {
        [first, _, ..] => first,
        _ => return Err(LinearizeError::TooFewLevels { levels: fits.len() }.into()),
    };
    match fits.iter().find(|f| f.mass != first.mass) {
        Some(f) => Err(IdentError::MassesDiffer {
            first: first.mass,
            other: f.mass,
        }),
        None => Ok(first.mass),
    }
}

/// The standard error of a fit's c; for a fit held at c = 0 (whose own is 0), its most likely
/// c's.
fn c_standard_error(f: &ZenerSpectralFit) -> f64 {
    f.unconstrained_c.map_or(f.se[0], |[_, se]| se)
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
            covariance: std::array::from_fn(|i| {
                std::array::from_fn(|j| if i == j { se[i] * se[i] } else { 0.0 })
            }),
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
