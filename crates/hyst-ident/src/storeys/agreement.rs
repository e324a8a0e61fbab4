//! Whether the final fit reached its records: a mode band the model puts outside the
//! measured band's own spread is a fit gone elsewhere (wrong masses, a stalled start), not a
//! model to report; a residual beyond what chance gives under the model is a model that
//! lacks something, said beside its answer.
//!
//! Chance: the whitened residual $r = (s_{sim} - s_{meas})/w$ of one simulated record per
//! measured one has covariance $2C$, with $C = W^{-1}\Sigma W^{-1}$ and Σ the statistics'
//! covariance over replicates of the fitted model (block-diagonal over levels). Its sum of
//! squares is $2\sum_i \lambda_i \chi^2_1$ over C's eigenvalues, taken by Satterthwaite's
//! scaled $g\chi^2_h$ with $g = \sum\lambda^2/\sum\lambda = \lVert C\rVert_F^2/\mathrm{tr}\,C$
//! and $h = (\mathrm{tr}\,C)^2/\lVert C\rVert_F^2$ (no eigenvalues needed). The fitted
//! parameters lower the sum; leaving them out makes the limit conservative.

use nalgebra::DMatrix;
use statrs::distribution::{ChiSquared, ContinuousCDF};

use super::types::{FarBand, FitAgreement, FitVerdict, LevelStatistics};

/// The probability chance exceeds [`FitAgreement::chance_rms`] when the model holds.
pub const CHANCE: f64 = 1e-3;

/// The agreement of a fit whose residual RMS is `residual_rms` over `residuals` whitened
/// statistics (weights `weights`, per level), its statistics `measured` and `simulated`,
/// and the statistics' covariance `cov` over (this many) replicates of the fitted model.
pub(super) fn agreement(
    (residual_rms, residuals): (f64, usize),
    (measured, simulated): (&[LevelStatistics], &[LevelStatistics]),
    weights: &[Vec<f64>],
    cov: (&[DMatrix<f64>], usize),
    converged: bool,
) -> FitAgreement {
    let far = far_bands(measured, simulated);
    let chance_rms = chance_rms(weights, cov, residuals);
    let verdict = if !far.is_empty() || !residual_rms.is_finite() {
        FitVerdict::Far
    } else if residual_rms > chance_rms {
        FitVerdict::Misses
    } else {
        FitVerdict::Explains
    };
    FitAgreement {
        verdict,
        chance_rms,
        converged,
        far,
    }
}

/// The bands whose model centroid lies further from the measured one than the measured
/// band's own spread (its standard deviation in Hz): the model's mode is not the record's.
fn far_bands(measured: &[LevelStatistics], simulated: &[LevelStatistics]) -> Vec<FarBand> {
    let mut far = Vec::new();
    for (level, (m, s)) in measured.iter().zip(simulated).enumerate() {
        for (mode, ((&f, &spread), &model)) in m
            .centroid_hz
            .iter()
            .zip(&m.spread)
            .zip(&s.centroid_hz)
            .enumerate()
        {
            let width = spread * f;
            // NaN (a band the model leaves empty) is far too.
            let within = (model - f).abs() <= width;
            if !within {
                far.push(FarBand {
                    level,
                    mode,
                    measured_hz: f,
                    width_hz: width,
                    model_hz: model,
                });
            }
        }
    }
    far
}

/// The whitened residual RMS chance exceeds with probability [`CHANCE`] when the model
/// holds (the module's doc), NaN when the spread is not known.
fn chance_rms(
    weights: &[Vec<f64>],
    (cov, replicates): (&[DMatrix<f64>], usize),
    residuals: usize,
) -> f64 {
    // A sample covariance's squares are biased up by its own noise (Wishart moments:
    // E ĉ_ab² = c_ab² + (c_aa c_bb + c_ab²)/(R − 1), E ĉ_aa² = c_aa² (R + 1)/(R − 1)); on
    // 16 replicates of 15 statistics uncorrected, the off-diagonal noise alone would double
    // ‖C‖² and put the limit far above what chance reaches.
    let r = replicates.max(3) as f64;
    let (mut trace, mut frobenius) = (0.0, 0.0);
    for (w, c) in weights.iter().zip(cov) {
        let d = w.len().min(c.nrows()).min(c.ncols());
        let at = |a: usize, b: usize| c[(a, b)] / (w[a] * w[b]);
        for a in 0..d {
            trace += at(a, a);
            for b in 0..d {
                let v = at(a, b);
                frobenius += if a == b {
                    v * v * (r - 1.0) / (r + 1.0)
                } else {
                    // Not clamped at 0 entry by entry: most true entries are near 0, and
                    // clamping their noise would bias the sum up again.
                    (v * v - at(a, a) * at(b, b) / (r - 1.0)) * (r - 1.0) / r
                };
            }
        }
    }
    if !(trace > 0.0 && frobenius > 0.0) || residuals == 0 {
        return f64::NAN;
    }
    let (g, h) = (frobenius / trace, trace * trace / frobenius);
    let q = ChiSquared::new(h).map_or(f64::NAN, |d| d.inverse_cdf(1.0 - CHANCE));
    (2.0 * g * q / residuals as f64).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn level(centroid: f64, spread: f64) -> LevelStatistics {
        LevelStatistics {
            centroid_hz: vec![centroid],
            spread: vec![spread],
            band_rms: vec![vec![1.0]],
            se: vec![],
        }
    }

    /// With independent statistics of unit whitened variance, the limit is the χ² point:
    /// 2·χ²₄₅(0.999)/45 = 2·80.08/45 (tables), its root 1.886.
    #[test]
    fn independent_statistics_give_the_chi_square_point() {
        let weights = vec![vec![0.5; 15]; 3];
        let cov = vec![DMatrix::from_diagonal_element(15, 15, 0.25); 3];
        // Known exactly (replicates without end), the χ² point itself.
        let r = chance_rms(&weights, (&cov, usize::MAX / 2), 45);
        assert!((r - (2.0 * 80.077 / 45.0f64).sqrt()).abs() < 1e-3, "{r}");
        // Statistics that move together (one shared swing) leave fewer chances: a wider
        // tail than 45 independent ones.
        let mut together = DMatrix::from_element(15, 15, 0.2);
        together.fill_diagonal(0.25);
        let wider = chance_rms(&weights, (&vec![together; 3], usize::MAX / 2), 45);
        assert!(wider > r, "{wider} vs {r}");
    }

    /// The squares' correction: 16 replicates of 15 independent statistics, sampled, give
    /// about the limit of the true (identity) covariance, where the raw squares would put
    /// it higher. Tolerance: the mean over 200 draws of a limit whose own spread is a few
    /// hundredths.
    #[test]
    fn a_sampled_covariance_gives_the_limit_of_the_true_one() {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let mut rng = rand::rngs::StdRng::seed_from_u64(77_001);
        let (d, reps) = (15, 16);
        let truth = chance_rms(
            &[vec![1.0; d]],
            (&[DMatrix::identity(d, d)], usize::MAX / 2),
            d,
        );
        let mut sum = 0.0;
        for _ in 0..200 {
            let x = DMatrix::<f64>::from_fn(reps, d, |_, _| StandardNormal.sample(&mut rng));
            let mean = x.row_mean();
            let centred = DMatrix::from_fn(reps, d, |i, j| x[(i, j)] - mean[j]);
            let cov = centred.transpose() * &centred / (reps - 1) as f64;
            sum += chance_rms(&[vec![1.0; d]], (&[cov], reps), d);
        }
        let mean = sum / 200.0;
        assert!((mean / truth - 1.0).abs() < 0.04, "{mean} vs {truth}");
    }

    /// A band the model puts outside the measured band's width is far (the fit with
    /// masses 1e6: 3.74 Hz against 2.52 ± 0.46 Hz), and the verdict says it whatever the
    /// residual; within the width, the residual decides.
    #[test]
    fn a_band_outside_its_width_is_far() {
        let m = [level(2.519, 0.1818)];
        let cov = vec![DMatrix::from_diagonal_element(3, 3, 1.0)];
        let cov = (cov.as_slice(), 16);
        let w = vec![vec![1.0; 3]];
        let a = agreement((0.5, 3), (&m, &[level(3.737, 0.11)]), &w, cov, true);
        assert_eq!(a.verdict, FitVerdict::Far);
        assert_eq!(a.far.len(), 1);
        assert!((a.far[0].width_hz - 0.458).abs() < 1e-3);
        let a = agreement((0.5, 3), (&m, &[level(2.6, 0.18)]), &w, cov, true);
        assert_eq!(a.verdict, FitVerdict::Explains);
        let a = agreement((40.0, 3), (&m, &[level(2.6, 0.18)]), &w, cov, true);
        assert_eq!(a.verdict, FitVerdict::Misses);
        let a = agreement((0.5, 3), (&m, &[level(f64::NAN, 0.18)]), &w, cov, true);
        assert_eq!(a.verdict, FitVerdict::Far);
    }
}
