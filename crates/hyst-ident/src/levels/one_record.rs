//! One Bouc-Wen model from ONE record under a white force, by indirect inference on more than
//! the Zener fit.
//!
//! One level's Zener fit (c, k, k∞, Ω) is four numbers, and a Bouc-Wen oscillator of known
//! mass has five (c, k, α, βγ, βδ): one record leaves a family of models. The record holds more
//! than its spectrum, though: how its frequency and damping change with its amplitude
//! ([`crate::amplitude`]'s curves), and how far its distribution departs from a Gaussian's
//! (its excess kurtosis: a softening element spreads the tails). Here the model is the one
//! whose simulated record gives the same Zener fit, the same curve (read at the measured
//! points' amplitudes) and the same kurtosis, each difference in √2 of the measured one's
//! standard error (the simulated record is as long, so as noisy; the Zener fit's four in
//! their covariance). Any parameter can be held, which gives the profile of the
//! fit along it ([`bouc_wen_from_one_record`] with [`BoucWenParameter`]s held): flat where
//! the record cannot tell.

use hyst_model::{BoucWen, Oscillator};

use super::{SimulationOptions, fit_weights, indirect_lm, simulated_record};
use crate::IdentError;
use crate::amplitude::{AmplitudeOptions, AmplitudePoint, ModeToFollow, amplitude_curves};
use crate::zener_spectrum::ZenerSpectralFit;

/// A parameter of the Bouc-Wen oscillator (β = 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
#[non_exhaustive]
pub enum BoucWenParameter {
    /// Viscous damping c (N s/m).
    Damping,
    /// Linear stiffness k (N/m).
    Stiffness,
    /// Initial stiffness of the element α (N/m).
    Alpha,
    /// βγ.
    BetaGamma,
    /// βδ.
    BetaDelta,
}

impl BoucWenParameter {
    /// All five, in the order of [`OneRecordBoucWen::se`].
    pub const ALL: [BoucWenParameter; 5] = [
        BoucWenParameter::Damping,
        BoucWenParameter::Stiffness,
        BoucWenParameter::Alpha,
        BoucWenParameter::BetaGamma,
        BoucWenParameter::BetaDelta,
    ];

    fn index(self) -> usize {
        match self {
            BoucWenParameter::Damping => 0,
            BoucWenParameter::Stiffness => 1,
            BoucWenParameter::Alpha => 2,
            BoucWenParameter::BetaGamma => 3,
            BoucWenParameter::BetaDelta => 4,
        }
    }
}

/// What [`bouc_wen_from_one_record`] finds.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct OneRecordBoucWen {
    /// The oscillator (β = 1, ν the start's).
    pub oscillator: Oscillator,
    /// Weighted sum of squares at the end: the Zener fit's four numbers in their covariance,
    /// the curve's points and the kurtosis in their standard errors.
    pub chi2: f64,
    /// Numbers in it.
    pub residuals: usize,
    /// Levenberg–Marquardt iterations done.
    pub iterations: usize,
    /// Standard errors of (c, k, α, βγ, βδ), 2 (JᵀJ)⁻¹ as in
    /// [`super::SimulatedBoucWen::se`]; NaN for a held parameter, or without an iteration.
    #[cfg_attr(feature = "serde", serde(with = "crate::nullable"))]
    pub se: [f64; 5],
}

/// The record's statistics: its Zener fit's (c, k, k∞, Ω), its curve's points and its
/// excess kurtosis.
type Statistics = ([f64; 4], Vec<AmplitudePoint>, f64);

/// One measured record (a displacement) and its Zener fit.
#[derive(Debug, Clone, Copy)]
pub struct OneRecord<'a> {
    /// The record's Zener spectral fit (step 3b).
    pub fit: &'a ZenerSpectralFit,
    /// The record (displacement).
    pub y: &'a [f64],
    /// The options its amplitude curve is found with ([`amplitude_curves`]; the measured
    /// quantity is taken as displacement).
    pub curve_opts: &'a AmplitudeOptions,
}

/// The Bouc-Wen model whose simulated record (as long as the measured one, under a white
/// force of the fit's density) gives the record's Zener fit and amplitude curve, from
/// `start`, the parameters in `held` kept at the start's values.
pub fn bouc_wen_from_one_record(
    record: &OneRecord<'_>,
    start: &Oscillator,
    held: &[BoucWenParameter],
    opts: &SimulationOptions,
    progress: &(dyn Fn(usize, f64) + Sync),
) -> Result<OneRecordBoucWen, IdentError> {
    let OneRecord { fit, y, curve_opts } = *record;
    let length = y.len();
    let hyst_model::Restoring::BoucWen(bw) = start.restoring else {
        return Err(hyst_linearize::LinearizeError::Invalid {
            name: "start (a Bouc-Wen oscillator is needed)",
            value: f64::NAN,
        }
        .into());
    };
    let all = [
        start.damping,
        start.stiffness,
        bw.alpha,
        bw.beta_gamma(),
        bw.beta_delta(),
    ];
    let free: Vec<usize> = (0..5)
        .filter(|i| !held.iter().any(|h| h.index() == *i))
        .collect();
    let full = |p: &[f64]| {
        let mut a = all;
        for (v, &i) in p.iter().zip(&free) {
            a[i] = *v;
        }
        a
    };
    let osc = |p: &[f64]| {
        let a = full(p);
        Oscillator::bouc_wen(
            start.mass,
            a[0],
            a[1],
            BoucWen::from_products(a[2], a[3], a[4], bw.nu),
        )
    };
    let measured = Measured::new(fit, y, curve_opts)?;
    let aux = |p: &[f64]| -> Result<Statistics, IdentError> {
        let model = osc(p);
        model.validate().map_err(|e| IdentError::Sim(e.into()))?;
        measured.statistics(&simulated_record(&model, fit, length, opts, 0)?)
    };
    let resid = |s: &Statistics| measured.residuals(s);
    let mut p: Vec<f64> = free.iter().map(|&i| all[i]).collect();
    if free.is_empty() {
        // Everything held: the start's statistics, no fit.
        let r = resid(&aux(&p)?);
        return Ok(OneRecordBoucWen {
            oscillator: osc(&p),
            chi2: r.iter().map(|v| v * v).sum(),
            residuals: r.len(),
            iterations: 0,
            se: [f64::NAN; 5],
        });
    }
    let nonnegative: Vec<bool> = free.iter().map(|&i| i == 0).collect();
    // c at least 0.1 N s/m (the fits' own tolerance must not show), the others 1e-3.
    let min_step: Vec<f64> = free
        .iter()
        .map(|&i| if i == 0 { 0.1 } else { 1e-3 })
        .collect();
    let bounds = super::ParameterSteps {
        nonnegative: &nonnegative,
        min_step: &min_step,
    };
    let fitted = indirect_lm(&mut p, &bounds, &aux, &resid, opts, progress)?;
    let mut se = [f64::NAN; 5];
    if let Some(c) = &fitted.covariance {
        for (k, &i) in free.iter().enumerate() {
            se[i] = (2.0 * c[(k, k)]).max(0.0).sqrt();
        }
    }
    Ok(OneRecordBoucWen {
        oscillator: osc(&p),
        chi2: fitted.cost,
        residuals: fitted.residuals,
        iterations: fitted.iterations,
        se,
    })
}

/// One point of [`beta_delta_profile`].
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ProfilePoint {
    /// βδ/βγ, held.
    pub ratio: f64,
    /// The fit with the ratio's βδ held, or why there is none.
    pub fit: Result<OneRecordBoucWen, String>,
}

/// The ratios βδ/βγ [`beta_delta_profile`] holds by default: from a hardening element
/// (the benchmark's is −1.375) to a strongly softening one.
pub const PROFILE_RATIOS: [f64; 6] = [-1.5, -1.0, -0.5, 0.0, 0.5, 0.9];

/// What one record leaves free: at each ratio βδ/βγ, the Bouc-Wen model that best reproduces
/// the record's statistics with that ratio's βδ held ([`bouc_wen_from_one_record`]), started
/// from the Gaussian closure's member with that ratio (the α and βγ that give the fit's k∞
/// and Ω at its level, [`hyst_linearize::statistical`]). A profile whose χ² changes by a few
/// units over ratios whose models predict other levels differently is the record saying it
/// cannot tell them apart. The points run in parallel.
pub fn beta_delta_profile(
    record: &OneRecord<'_>,
    ratios: &[f64],
    opts: &SimulationOptions,
    progress: &(dyn Fn(usize, f64) + Sync),
) -> Vec<ProfilePoint> {
    use rayon::prelude::*;
    let done = std::sync::atomic::AtomicUsize::new(0);
    ratios
        .par_iter()
        .map(|&ratio| {
            let fit = closure_member(record.fit, ratio).and_then(|start| {
                bouc_wen_from_one_record(
                    record,
                    &start,
                    &[BoucWenParameter::BetaDelta],
                    opts,
                    &|_, _| {},
                )
                .map_err(|e| e.to_string())
            });
            let k = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            progress(k, fit.as_ref().map_or(f64::NAN, |f| f.chi2));
            ProfilePoint { ratio, fit }
        })
        .collect()
}

/// The Gaussian closure's one-record Bouc-Wen model with βδ = `ratio`·βγ: with the fitted
/// Zener oscillator's moments (σ_v, σ_z, ρ) under its force density,
/// Ω = √(2/π) σ_v βγ (1 + ρ·ratio) and α = k∞ + √(2/π) σ_z (ρ βγ + βδ); c and k the fit's
/// (c at least 1 % of critical at k, so that the fit can move it).
fn closure_member(f: &ZenerSpectralFit, ratio: f64) -> Result<Oscillator, String> {
    let zener = hyst_model::ZenerParams {
        k_inf: f.k_inf,
        omega: f.omega,
    };
    let m = hyst_linearize::statistical::zener_response_moments(
        f.mass,
        f.c,
        f.k,
        &zener,
        f.force_density,
    )
    .map_err(|e| e.to_string())?;
    let s = (2.0 / std::f64::consts::PI).sqrt();
    let bg = f.omega / (s * m.sigma_v * (1.0 + m.rho * ratio));
    let bd = ratio * bg;
    let alpha = f.k_inf + s * m.sigma_z * (m.rho * bg + bd);
    let c = f.c.max(0.02 * (f.mass * f.k.max(0.0)).sqrt());
    let o = Oscillator::bouc_wen(f.mass, c, f.k, BoucWen::from_products(alpha, bg, bd, 1.0));
    o.validate()
        .map_err(|e| format!("the closure's start is no valid model: {e}"))?;
    Ok(o)
}

/// The measured record's statistics, and how a simulated record's are found and compared.
struct Measured<'a> {
    fit: &'a ZenerSpectralFit,
    /// The inverse Cholesky factor of the fit's covariance.
    weight: nalgebra::Matrix4<f64>,
    mode: ModeToFollow,
    curve_opts: AmplitudeOptions,
    statistics: Statistics,
    /// The kurtosis' standard error.
    kurtosis_se: f64,
}

impl<'a> Measured<'a> {
    fn new(
        fit: &'a ZenerSpectralFit,
        y: &[f64],
        curve_opts: &AmplitudeOptions,
    ) -> Result<Self, IdentError> {
        let mut curve_opts = curve_opts.clone();
        curve_opts.measured = crate::amplitude::Quantity::Displacement;
        curve_opts.report_as = None;
        let mode = ModeToFollow {
            frequency_hz: fit.pair.im / (2.0 * std::f64::consts::PI),
            damping_ratio: (-fit.pair.re / fit.pair.norm()).clamp(0.0, 1.0),
            shape: None,
        };
        let (k, kurtosis_se) = kurtosis(y);
        let mut m = Measured {
            fit,
            weight: fit_weights(&[fit])?[0],
            mode,
            curve_opts,
            statistics: ([fit.c, fit.k, fit.k_inf, fit.omega], Vec::new(), k),
            kurtosis_se,
        };
        m.statistics.1 = m.curve(y)?;
        Ok(m)
    }

    fn curve(&self, y: &[f64]) -> Result<Vec<AmplitudePoint>, IdentError> {
        let mode = std::slice::from_ref(&self.mode);
        let report = amplitude_curves(&[y], self.fit.fs, mode, &[], &self.curve_opts)?;
        Ok(report
            .modes
            .into_iter()
            .next()
            .map(|m| m.points)
            .unwrap_or_default())
    }

    /// A simulated record's statistics, found as the measured record's were.
    fn statistics(&self, y: &[f64]) -> Result<Statistics, IdentError> {
        let f = self.fit;
        let g = crate::zener_spectrum::fit(y, f.fs, f.mass, f.pair, f.real, f.max_frequency_hz)?;
        Ok(([g.c, g.k, g.k_inf, g.omega], self.curve(y)?, kurtosis(y).0))
    }

    /// Simulated minus measured, each in its error (√2 of the measured's for the curve and
    /// the kurtosis: the simulated record is as long); a number that could not be found
    /// counts as 1000 errors.
    fn residuals(&self, s: &Statistics) -> Vec<f64> {
        let ((z, sim, k), (zm, curve, km)) = (s, &self.statistics);
        let d = nalgebra::Vector4::from_fn(|i, _| z[i] - zm[i]);
        let mut r: Vec<f64> = (self.weight * d).iter().copied().collect();
        let sq2 = std::f64::consts::SQRT_2;
        for p in curve {
            let (f, zeta) = read_at(sim, p.amplitude);
            r.push((f - p.frequency_hz) / (sq2 * p.frequency_se_hz));
            r.push((zeta - p.damping_ratio) / (sq2 * p.damping_se));
        }
        r.push((k - km) / (sq2 * self.kurtosis_se));
        r.iter()
            .map(|v| if v.is_finite() { *v } else { 1e3 })
            .collect()
    }
}

/// A curve's (frequency, damping ratio) at `amplitude`: linear in the amplitude between its
/// points, and along its end segments beyond them; NaN without two points.
fn read_at(points: &[AmplitudePoint], amplitude: f64) -> (f64, f64) {
    if points.len() < 2 {
        return (f64::NAN, f64::NAN);
    }
    let j = points
        .windows(2)
        .position(|w| amplitude <= w[1].amplitude)
        .unwrap_or(points.len() - 2);
    let (a, b) = (&points[j], &points[j + 1]);
    let t = (amplitude - a.amplitude) / (b.amplitude - a.amplitude);
    (
        a.frequency_hz + t * (b.frequency_hz - a.frequency_hz),
        a.damping_ratio + t * (b.damping_ratio - a.damping_ratio),
    )
}

/// Stretches of the record the kurtosis' jackknife leaves out one at a time.
const KURTOSIS_GROUPS: usize = 20;

/// The excess kurtosis of `y` (mean removed) and its grouped-jackknife standard error.
fn kurtosis(y: &[f64]) -> (f64, f64) {
    let n = y.len();
    let mean = y.iter().sum::<f64>() / n as f64;
    let g = KURTOSIS_GROUPS.min(n);
    let sums: Vec<(f64, f64, f64)> = (0..g)
        .map(|i| {
            let part = &y[i * n / g..(i + 1) * n / g];
            part.iter()
                .fold((0.0, 0.0, part.len() as f64), |(s2, s4, c), v| {
                    let d = (v - mean).powi(2);
                    (s2 + d, s4 + d * d, c)
                })
        })
        .collect();
    let (s2, s4, c) = sums
        .iter()
        .fold((0.0, 0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1, a.2 + b.2));
    let k = |s2: f64, s4: f64, c: f64| (s4 / c) / (s2 / c).powi(2) - 3.0;
    let left_out: Vec<f64> = sums
        .iter()
        .map(|(a, b, d)| k(s2 - a, s4 - b, c - d))
        .collect();
    (
        k(s2, s4, c),
        crate::amplitude::slope::jackknife_se(&left_out),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(amplitude: f64, f: f64, z: f64) -> AmplitudePoint {
        AmplitudePoint {
            amplitude,
            triggers: 1,
            frequency_hz: f,
            frequency_se_hz: 1.0,
            damping_ratio: z,
            damping_se: 1.0,
            channels: vec![],
            drifts: vec![],
        }
    }

    #[test]
    fn a_curve_is_read_between_and_beyond_its_points() {
        let c = [
            point(1.0, 10.0, 0.01),
            point(2.0, 12.0, 0.03),
            point(4.0, 12.0, 0.07),
        ];
        // Within rounding of the interpolation's arithmetic.
        let near =
            |a: (f64, f64), b: (f64, f64)| (a.0 - b.0).abs() < 1e-12 && (a.1 - b.1).abs() < 1e-12;
        assert!(near(read_at(&c, 1.5), (11.0, 0.02)));
        assert!(near(read_at(&c, 3.0), (12.0, 0.05)));
        // Beyond the ends, along the end segments.
        assert!(near(read_at(&c, 0.0), (8.0, -0.01)));
        assert!(near(read_at(&c, 5.0), (12.0, 0.09)));
        assert!(read_at(&c[..1], 1.0).0.is_nan());
    }

    /// The excess kurtosis against numpy-free closed forms: 0 for Gaussian noise (within its
    /// standard error, which is about √(24/n)), −1.5 for a sinusoid, −1.2 for a uniform
    /// variable.
    #[test]
    fn kurtosis_of_known_distributions() {
        let n = 1 << 16;
        let g = hyst_sim::excitation::white_noise(n, 1.0, 5).unwrap();
        let (k, se) = kurtosis(&g);
        // √(24/n) = 0.019; the jackknife's own error is about 1/√(2·19) of it.
        assert!((se / (24.0 / n as f64).sqrt() - 1.0).abs() < 0.5, "{se}");
        assert!(k.abs() < 4.0 * se, "{k} ± {se}");
        let s: Vec<f64> = (0..n).map(|i| (0.01 * i as f64).sin() + 3.0).collect();
        approx::assert_abs_diff_eq!(kurtosis(&s).0, -1.5, epsilon = 1e-3);
        let u: Vec<f64> = (0..n)
            .map(|i| (i as f64 * 0.618_033_988_7).fract())
            .collect();
        approx::assert_abs_diff_eq!(kurtosis(&u).0, -1.2, epsilon = 1e-3);
    }
}
