//! Statistical (Gaussian) linearization of Bouc-Wen hysteresis under a random force, and
//! Bouc-Wen from the Zener equivalents of several force levels.
//!
//! The describing function linearizes at one sinusoidal amplitude; a random response has
//! none. Statistical linearization (Wen, 1980; Atalik and Utku, 1976) replaces
//! $f(\dot x, z) = \alpha\dot x - \beta\gamma|\dot x|z - \beta\delta\,\dot x|z|$ (ν = 1) by the
//! linear $k_\infty\dot x - \Omega z$ closest in mean square, whose coefficients for jointly
//! Gaussian, zero-mean $(\dot x, z)$ are $E[\partial f/\partial\dot x]$ and
//! $-E[\partial f/\partial z]$. With $\sigma_v$, $\sigma_z$ the standard deviations and ρ the
//! correlation of $\dot x$ and $z$, and $E|\dot x| = \sqrt{2/\pi}\,\sigma_v$,
//! $E[z\operatorname{sgn}\dot x] = \sqrt{2/\pi}\,\rho\sigma_z$:
//!
//! $$ k_\infty = \alpha - \sqrt{2/\pi}\,\sigma_z(\rho\,\beta\gamma + \beta\delta), \qquad
//!    \Omega = \sqrt{2/\pi}\,\sigma_v(\beta\gamma + \rho\,\beta\delta). $$
//!
//! That is a Zener element $\dot z + \Omega z = k_\infty\dot x$ exactly, with the oscillator's
//! c and k unchanged ([`zener_from_bouc_wen`]). The moments are those of the linear Zener
//! oscillator under a white force of two-sided density q (N²/Hz, $E[u(t)u(t+\tau)] =
//! q\,\delta(\tau)$), from its Lyapunov equation ([`zener_response_moments`]); iterating the
//! two to a fixed point predicts the equivalent Zener of a Bouc-Wen oscillator at a level
//! ([`equivalent_zener`]).
//!
//! **Back to Bouc-Wen.** At one level the two relations hold three unknowns (α, βγ, βδ), as
//! the describing function's do. But they are *linear* in all three, with coefficients from
//! that level's moments, so the Zener equivalents identified at two or more levels give them
//! by weighted least squares ([`bouc_wen_from_levels`]), with standard errors and a χ² that
//! says whether the levels agree with one Bouc-Wen element.

use hyst_model::{BoucWen, ZenerParams};
use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use crate::LinearizeError;

/// √(2/π): E|g| for a standard normal g.
const SQRT_2_OVER_PI: f64 = 0.797_884_560_802_865_4;

/// Stationary second moments of the velocity and the hysteretic (or Zener) force.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ResponseMoments {
    /// Standard deviation of the displacement (m).
    pub sigma_x: f64,
    /// Standard deviation of the velocity (m/s).
    pub sigma_v: f64,
    /// Standard deviation of the element's force z (N).
    pub sigma_z: f64,
    /// Correlation of velocity and z, E[ẋ z]/(σ_v σ_z).
    pub rho: f64,
}

fn positive(name: &'static str, value: f64) -> Result<(), LinearizeError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(LinearizeError::Invalid { name, value })
    }
}

fn check_moments(m: &ResponseMoments) -> Result<(), LinearizeError> {
    positive("sigma_v", m.sigma_v)?;
    positive("sigma_z", m.sigma_z)?;
    if !(m.rho.is_finite() && m.rho.abs() < 1.0) {
        return Err(LinearizeError::Invalid {
            name: "rho",
            value: m.rho,
        });
    }
    Ok(())
}

fn check_nu(bw: &BoucWen) -> Result<(), LinearizeError> {
    crate::check_bouc_wen(bw)?;
    if bw.nu != 1.0 {
        return Err(LinearizeError::Invalid {
            name: "nu (statistical linearization is written for ν = 1)",
            value: bw.nu,
        });
    }
    Ok(())
}

/// The Zener element that replaces a Bouc-Wen element (ν = 1) whose velocity and force have
/// the Gaussian moments `moments`. Ω may come out ≤ 0 (a Bouc-Wen element that adds energy
/// on average, βγ + ρβδ < 0); that is reported as [`LinearizeError::NonDissipative`].
pub fn zener_from_bouc_wen(
    bw: &BoucWen,
    moments: &ResponseMoments,
) -> Result<ZenerParams, LinearizeError> {
    check_nu(bw)?;
    check_moments(moments)?;
    let (bg, bd) = (bw.beta_gamma(), bw.beta * bw.delta);
    let k_inf = bw.alpha - SQRT_2_OVER_PI * moments.sigma_z * (moments.rho * bg + bd);
    let omega = SQRT_2_OVER_PI * moments.sigma_v * (bg + moments.rho * bd);
    if omega.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Err(LinearizeError::NonDissipative { omega });
    }
    Ok(ZenerParams { k_inf, omega })
}

/// Stationary moments of the Zener oscillator $m\ddot x + c\dot x + kx + z = u$,
/// $\dot z + \Omega z = k_\infty\dot x$, under a white force of two-sided density `q`
/// (N²/Hz): the state covariance P solves $AP + PA^T + q\,bb^T = 0$.
pub fn zener_response_moments(
    mass: f64,
    c: f64,
    k: f64,
    zener: &ZenerParams,
    q: f64,
) -> Result<ResponseMoments, LinearizeError> {
    positive("mass", mass)?;
    positive("force density q", q)?;
    for (name, v) in [
        ("damping", c),
        ("stiffness", k),
        ("k_inf", zener.k_inf),
        ("omega", zener.omega),
    ] {
        if !v.is_finite() {
            return Err(LinearizeError::Invalid { name, value: v });
        }
    }
    let a = Matrix3::new(
        0.0,
        1.0,
        0.0,
        -k / mass,
        -c / mass,
        -1.0 / mass,
        0.0,
        zener.k_inf,
        -zener.omega,
    );
    // Routh–Hurwitz for mλ³ + (Ωm + c)λ² + (Ωc + k + k∞)λ + kΩ: a stationary response needs
    // every coefficient positive and a₂a₁ > a₃a₀.
    let (a2, a1, a0) = (
        zener.omega * mass + c,
        zener.omega * c + k + zener.k_inf,
        k * zener.omega,
    );
    if !(a2 > 0.0 && a1 > 0.0 && a0 > 0.0 && a2 * a1 > mass * a0) {
        return Err(LinearizeError::Invalid {
            name: "stability (the Zener oscillator has no stationary response)",
            value: a2 * a1 - mass * a0,
        });
    }
    // vec(AP + PAᵀ) = (I ⊗ A + A ⊗ I) vec P, column-major vec.
    let mut kron = SMatrix::<f64, 9, 9>::zeros();
    for i in 0..3 {
        for j in 0..3 {
            for r in 0..3 {
                kron[(3 * j + i, 3 * j + r)] += a[(i, r)];
                kron[(3 * j + i, 3 * r + i)] += a[(j, r)];
            }
        }
    }
    let mut rhs = SVector::<f64, 9>::zeros();
    rhs[4] = -q / (mass * mass); // the (1, 1) entry of q b bᵀ, b = (0, 1/m, 0)
    let p = kron.lu().solve(&rhs).ok_or(LinearizeError::Invalid {
        name: "stability (singular Lyapunov equation)",
        value: a0,
    })?;
    let at = |i: usize, j: usize| p[3 * j + i];
    let (sx, sv, sz) = (at(0, 0).sqrt(), at(1, 1).sqrt(), at(2, 2).sqrt());
    Ok(ResponseMoments {
        sigma_x: sx,
        sigma_v: sv,
        sigma_z: sz,
        rho: at(1, 2) / (sv * sz),
    })
}

/// The equivalent Zener element of the Bouc-Wen oscillator $m\ddot x + c\dot x + kx + z = u$
/// under a white force of two-sided density `q`: the fixed point of
/// [`zener_response_moments`] and [`zener_from_bouc_wen`], started from the moments of the
/// linear oscillator of stiffness k + α (with at least 1 % of critical damping: c may be 0,
/// the element dissipating alone).
pub fn equivalent_zener(
    mass: f64,
    c: f64,
    k: f64,
    bw: &BoucWen,
    q: f64,
) -> Result<(ZenerParams, ResponseMoments), LinearizeError> {
    check_nu(bw)?;
    positive("mass", mass)?;
    if !(c.is_finite() && c >= 0.0) {
        return Err(LinearizeError::Invalid {
            name: "damping",
            value: c,
        });
    }
    positive("stiffness k + α", k + bw.alpha)?;
    positive("force density q", q)?;
    // Linear oscillator of stiffness k + α: σ_x² = q/(2c(k+α)), σ_v² = q/(2cm).
    let c0 = c.max(0.02 * ((k + bw.alpha) * mass).sqrt());
    let sx = (q / (2.0 * c0 * (k + bw.alpha))).sqrt();
    let mut moments = ResponseMoments {
        sigma_x: sx,
        sigma_v: (q / (2.0 * c0 * mass)).sqrt(),
        sigma_z: bw.alpha * sx,
        rho: 0.0,
    };
    let mut zener = zener_from_bouc_wen(bw, &moments)?;
    const MAX_ITERATIONS: usize = 500;
    let mut change = f64::INFINITY;
    for _ in 0..MAX_ITERATIONS {
        let next = zener_response_moments(mass, c, k, &zener, q)?;
        // Half steps: the plain iteration can oscillate at high levels.
        moments = ResponseMoments {
            sigma_x: next.sigma_x,
            sigma_v: 0.5 * (moments.sigma_v + next.sigma_v),
            sigma_z: 0.5 * (moments.sigma_z + next.sigma_z),
            rho: 0.5 * (moments.rho + next.rho),
        };
        let z = zener_from_bouc_wen(bw, &moments)?;
        change = ((z.k_inf - zener.k_inf) / zener.k_inf)
            .abs()
            .max(((z.omega - zener.omega) / zener.omega).abs());
        zener = z;
        if change < 1e-12 {
            let moments = zener_response_moments(mass, c, k, &zener, q)?;
            return Ok((zener, moments));
        }
    }
    Err(LinearizeError::NoConvergence {
        iterations: MAX_ITERATIONS,
        residual: change,
    })
}

/// The Zener equivalent identified at one force level, with the moments it implies (from
/// [`zener_response_moments`] with the level's identified c, k and force density) and the
/// standard errors of k∞ and Ω that weigh it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LevelEquivalent {
    /// The identified Zener element.
    pub zener: ZenerParams,
    /// Standard error of k∞ (N/m).
    pub k_inf_se: f64,
    /// Standard error of Ω (rad/s).
    pub omega_se: f64,
    /// The response moments at this level.
    pub moments: ResponseMoments,
}

/// The Bouc-Wen element (ν = 1, β = 1) that best explains the Zener equivalents of several
/// levels, with what the least squares say of it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoucWenFromLevels {
    /// The element.
    pub bouc_wen: BoucWen,
    /// Standard errors of (α, βγ, βδ), from the levels' standard errors.
    pub se: [f64; 3],
    /// χ² of the fit per degree of freedom (2·levels − 3): near 1 when the levels agree with
    /// one Bouc-Wen element within their standard errors, NaN with two levels (no freedom).
    pub chi2_per_dof: f64,
}

/// (α, βγ, βδ) by weighted least squares from two or more levels' Zener equivalents: each
/// level gives $k_\infty = \alpha - a\rho\,\beta\gamma - a\,\beta\delta$ and
/// $\Omega = b\,\beta\gamma + b\rho\,\beta\delta$ with $a = \sqrt{2/\pi}\,\sigma_z$,
/// $b = \sqrt{2/\pi}\,\sigma_v$, weighted by the inverse standard errors.
pub fn bouc_wen_from_levels(
    levels: &[LevelEquivalent],
) -> Result<BoucWenFromLevels, LinearizeError> {
    if levels.len() < 2 {
        return Err(LinearizeError::TooFewLevels {
            levels: levels.len(),
        });
    }
    let mut normal = Matrix3::<f64>::zeros();
    let mut rhs = Vector3::<f64>::zeros();
    let mut rows = Vec::with_capacity(2 * levels.len());
    for lv in levels {
        check_moments(&lv.moments)?;
        positive("k_inf standard error", lv.k_inf_se)?;
        positive("omega standard error", lv.omega_se)?;
        for (name, v) in [("k_inf", lv.zener.k_inf), ("omega", lv.zener.omega)] {
            if !v.is_finite() {
                return Err(LinearizeError::Invalid { name, value: v });
            }
        }
        let a = SQRT_2_OVER_PI * lv.moments.sigma_z;
        let b = SQRT_2_OVER_PI * lv.moments.sigma_v;
        let rho = lv.moments.rho;
        rows.push((
            Vector3::new(1.0, -a * rho, -a) / lv.k_inf_se,
            lv.zener.k_inf / lv.k_inf_se,
        ));
        rows.push((
            Vector3::new(0.0, b, b * rho) / lv.omega_se,
            lv.zener.omega / lv.omega_se,
        ));
    }
    for (j, y) in &rows {
        normal += j * j.transpose();
        rhs += j * *y;
    }
    // Columns of very different scale (α in N/m, βγ in 1/m): solve in scaled variables.
    let scale = Vector3::from_fn(|i, _| normal[(i, i)].sqrt().recip());
    let scaled = Matrix3::from_fn(|i, j| normal[(i, j)] * scale[i] * scale[j]);
    // Unit diagonal: its smallest eigenvalue is the reciprocal of its condition number, up
    // to a factor of three. Below 1e-10 the levels do not separate the three unknowns (the
    // same moments twice, say) and the solution would be round-off.
    let smallest = scaled.symmetric_eigenvalues().min();
    let inverse = (smallest > 1e-10)
        .then(|| scaled.try_inverse())
        .flatten()
        .ok_or(LinearizeError::LevelsDegenerate {
            smallest_eigenvalue: smallest,
        })?;
    let cov = Matrix3::from_fn(|i, j| inverse[(i, j)] * scale[i] * scale[j]);
    let x = cov * rhs;
    let chi2: f64 = rows.iter().map(|(j, y)| (j.dot(&x) - y).powi(2)).sum();
    let dof = rows.len() as f64 - 3.0;
    Ok(BoucWenFromLevels {
        bouc_wen: BoucWen::from_products(x[0], x[1], x[2], 1.0),
        se: [0, 1, 2].map(|i| cov[(i, i)].max(0.0).sqrt()),
        chi2_per_dof: if dof > 0.0 { chi2 / dof } else { f64::NAN },
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use rand::rngs::Xoshiro256PlusPlus;
    use rand::{RngExt, SeedableRng};
    use rand_distr::StandardNormal;

    /// The benchmark's oscillator: m = 2 kg, c = 10 N s/m, k = 5e4 N/m.
    const M: f64 = 2.0;
    const C: f64 = 10.0;
    const K: f64 = 5e4;

    #[test]
    fn a_vanishing_element_leaves_the_linear_oscillator() {
        // k∞ → 0: the oscillator is m ẍ + c ẋ + k x = u, σ_x² = q/(2ck), σ_v² = q/(2cm).
        let q = 0.7;
        let z = ZenerParams {
            k_inf: 1e-9,
            omega: 30.0,
        };
        let mo = zener_response_moments(M, C, K, &z, q).unwrap();
        // The element changes the moments by O(k∞/k) = 2e-14; 1e-10 is round-off headroom
        // for a 9×9 solve whose entries span eight decades.
        approx::assert_relative_eq!(mo.sigma_x, (q / (2.0 * C * K)).sqrt(), max_relative = 1e-10);
        approx::assert_relative_eq!(mo.sigma_v, (q / (2.0 * C * M)).sqrt(), max_relative = 1e-10);
    }

    proptest! {
        /// Power balance of the stationary response, a relation the Lyapunov solve does not
        /// use: the force's power q/(2m) is what the dashpot and the element take,
        /// c σ_v² + E[ẋ z].
        #[test]
        fn the_moments_balance_power(
            c in 0.5f64..50.0,
            k in 1e3f64..1e5,
            k_inf in 1e3f64..1e5,
            omega in 1.0f64..300.0,
            q in 1e-3f64..10.0,
        ) {
            let z = ZenerParams { k_inf, omega };
            let mo = zener_response_moments(M, c, k, &z, q).unwrap();
            let taken = c * mo.sigma_v.powi(2) + mo.rho * mo.sigma_v * mo.sigma_z;
            // The solve's relative round-off, amplified by the spread of the entries.
            prop_assert!((taken / (q / (2.0 * M)) - 1.0).abs() < 1e-8, "{taken}");
        }

        /// The fixed point's levels, mapped back from their exact Zener equivalents, give the
        /// Bouc-Wen element again.
        #[test]
        fn levels_round_trip(
            alpha in 1e4f64..1e5,
            bg in 100.0f64..2000.0,
            bd in -1500.0f64..1500.0,
        ) {
            let bw = BoucWen::from_products(alpha, bg, bd, 1.0);
            let mut levels = Vec::new();
            for f in [10.0, 40.0, 90.0] {
                let Ok((zener, moments)) = equivalent_zener(M, C, K, &bw, f * f / 750.0) else {
                    continue;
                };
                levels.push(LevelEquivalent { zener, k_inf_se: 1e3, omega_se: 1.0, moments });
            }
            prop_assume!(levels.len() >= 2);
            let back = bouc_wen_from_levels(&levels).unwrap();
            // The fixed point stops at a relative change of 1e-12; the 3×3 solve loses a few
            // digits more to the scale of α against βγ.
            prop_assert!((back.bouc_wen.alpha / alpha - 1.0).abs() < 1e-8);
            prop_assert!((back.bouc_wen.beta_gamma() / bg - 1.0).abs() < 1e-6);
            prop_assert!((back.bouc_wen.beta * back.bouc_wen.delta - bd).abs() < 1e-6 * bg);
        }
    }

    /// The closed form against its definition: the least-squares regression of
    /// f(ẋ, z) = αẋ − βγ|ẋ|z − βδẋ|z| on (ẋ, z) over Gaussian samples.
    #[test]
    fn gaussian_coefficients_are_the_mean_square_best() {
        let bw = BoucWen::benchmark();
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(7);
        for (sv, sz, rho) in [(0.1, 30.0, 0.2), (0.05, 10.0, -0.5), (0.2, 60.0, 0.7)] {
            let mo = ResponseMoments {
                sigma_x: f64::NAN,
                sigma_v: sv,
                sigma_z: sz,
                rho,
            };
            let want = zener_from_bouc_wen(&bw, &mo).unwrap();
            let n = 400_000;
            let (mut vv, mut vz, mut zz, mut fv, mut fz) = (0.0, 0.0, 0.0, 0.0, 0.0);
            let mut samples = Vec::with_capacity(n);
            for _ in 0..n {
                let (g1, g2): (f64, f64) = (rng.sample(StandardNormal), rng.sample(StandardNormal));
                let v = sv * g1;
                let z = sz * (rho * g1 + (1.0 - rho * rho).sqrt() * g2);
                let f = bw.rate(v, z);
                (vv, vz, zz, fv, fz) = (vv + v * v, vz + v * z, zz + z * z, fv + f * v, fz + f * z);
                samples.push((v, z, f));
            }
            let det = vv * zz - vz * vz;
            let a = (fv * zz - fz * vz) / det;
            let b = (fz * vv - fv * vz) / det;
            // Standard errors of the regression coefficients from its residuals.
            let s2 = samples
                .iter()
                .map(|(v, z, f)| (f - a * v - b * z).powi(2))
                .sum::<f64>()
                / (n - 2) as f64;
            let (se_a, se_b) = ((s2 * zz / det).sqrt(), (s2 * vv / det).sqrt());
            // Five standard errors: a false alarm once in ~10⁶ draws.
            assert!(
                (a - want.k_inf).abs() < 5.0 * se_a,
                "k∞ {a} vs {} ± {se_a}",
                want.k_inf
            );
            assert!(
                (-b - want.omega).abs() < 5.0 * se_b,
                "Ω {} vs {} ± {se_b}",
                -b,
                want.omega
            );
        }
    }

    /// Without a dashpot the element dissipates alone: the fixed point exists, and the
    /// power balance holds with c = 0 (all of q/(2m) taken by the element).
    #[test]
    fn no_dashpot_is_a_fixed_point_too() {
        let q = 50.0 * 50.0 / 750.0;
        let (z, mo) = equivalent_zener(M, 0.0, K, &BoucWen::benchmark(), q).unwrap();
        assert!(z.omega > 0.0 && z.k_inf > 0.0, "{z:?}");
        let taken = mo.rho * mo.sigma_v * mo.sigma_z;
        // As in the_moments_balance_power.
        assert!((taken / (q / (2.0 * M)) - 1.0).abs() < 1e-8, "{taken}");
        assert!(matches!(
            equivalent_zener(M, -1.0, K, &BoucWen::benchmark(), q),
            Err(LinearizeError::Invalid {
                name: "damping",
                ..
            })
        ));
    }

    /// Under the benchmark's drives the fixed point is a Zener element that stiffens and
    /// relaxes faster with the level.
    #[test]
    fn the_benchmark_stiffens_with_the_level() {
        let bw = BoucWen::benchmark();
        let mut last = (0.0, 0.0);
        for f in [10.0, 50.0, 90.0] {
            let (z, mo) = equivalent_zener(M, C, K, &bw, f * f / 750.0).unwrap();
            // The moments are the element's own fixed point.
            let again = zener_from_bouc_wen(&bw, &mo).unwrap();
            approx::assert_relative_eq!(again.k_inf, z.k_inf, max_relative = 1e-10);
            approx::assert_relative_eq!(again.omega, z.omega, max_relative = 1e-10);
            assert!(z.k_inf > last.0 && z.omega > last.1, "{f} N: {z:?}");
            last = (z.k_inf, z.omega);
        }
    }

    #[test]
    fn bad_input_is_named() {
        let bw = BoucWen::benchmark();
        let mo = ResponseMoments {
            sigma_x: 1e-4,
            sigma_v: 0.1,
            sigma_z: 30.0,
            rho: 0.2,
        };
        let z = ZenerParams {
            k_inf: 6e4,
            omega: 40.0,
        };
        let nu2 = BoucWen { nu: 2.0, ..bw };
        assert!(matches!(
            zener_from_bouc_wen(&nu2, &mo),
            Err(LinearizeError::Invalid { value, .. }) if value == 2.0
        ));
        let rho1 = ResponseMoments { rho: 1.0, ..mo };
        assert!(matches!(
            zener_from_bouc_wen(&bw, &rho1),
            Err(LinearizeError::Invalid { name: "rho", .. })
        ));
        let heating = BoucWen::from_products(5e4, -800.0, 0.0, 1.0);
        assert!(matches!(
            zener_from_bouc_wen(&heating, &mo),
            Err(LinearizeError::NonDissipative { .. })
        ));
        assert!(matches!(
            zener_response_moments(M, C, K, &z, 0.0),
            Err(LinearizeError::Invalid {
                name: "force density q",
                ..
            })
        ));
        assert!(matches!(
            zener_response_moments(-1.0, C, K, &z, 1.0),
            Err(LinearizeError::Invalid { name: "mass", .. })
        ));
        let unstable = ZenerParams {
            k_inf: 6e4,
            omega: -40.0,
        };
        assert!(zener_response_moments(M, C, K, &unstable, 1.0).is_err());
        let one = LevelEquivalent {
            zener: z,
            k_inf_se: 1e3,
            omega_se: 1.0,
            moments: mo,
        };
        assert!(matches!(
            bouc_wen_from_levels(&[one]),
            Err(LinearizeError::TooFewLevels { levels: 1 })
        ));
        // Two levels with the same moments cannot separate α from βδ.
        assert!(matches!(
            bouc_wen_from_levels(&[one, one]),
            Err(LinearizeError::LevelsDegenerate { .. })
        ));
        let nan = LevelEquivalent {
            k_inf_se: f64::NAN,
            ..one
        };
        assert!(matches!(
            bouc_wen_from_levels(&[one, nan]),
            Err(LinearizeError::Invalid {
                name: "k_inf standard error",
                ..
            })
        ));
    }
}
