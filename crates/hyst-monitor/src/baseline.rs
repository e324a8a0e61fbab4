//! Each mode's frequency regressed on the covariates over a training period, and the
//! standardized residual of a new record (see the crate's documentation).

use nalgebra::{DMatrix, DVector};

use crate::MonitorError;

/// The regression of a mode's frequency on the covariates over the training period.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Baseline {
    /// β₀ (Hz), then one coefficient per covariate (Hz per unit).
    pub coefficients: Vec<f64>,
    /// Their covariance, row-major (p × p).
    pub covariance: Vec<f64>,
    /// σ: the spread (Hz) the covariates leave unexplained beyond the estimation error.
    pub unexplained_sd_hz: f64,
    /// Training records used.
    pub records: usize,
}

impl Baseline {
    /// The frequency the covariates `x` predict, and the prediction's own variance (Hz²).
    pub fn predict(&self, x: &[f64]) -> (f64, f64) {
        let p = self.coefficients.len();
        let row: Vec<f64> = std::iter::once(1.0).chain(x.iter().copied()).collect();
        let f = row.iter().zip(&self.coefficients).map(|(a, b)| a * b).sum();
        let mut var = 0.0;
        for i in 0..p {
            for j in 0..p {
                var += row[i] * self.covariance[i * p + j] * row[j];
            }
        }
        (f, var.max(0.0))
    }

    /// The standardized residual z = (f − f̂) / √(s² + σ² + var f̂) of a record whose
    /// frequency `f` has standard error `se` at covariates `x`.
    pub fn standardized(&self, f: f64, se: f64, x: &[f64]) -> f64 {
        self.residual(f, se, x).2
    }

    /// The residual f − f̂ (Hz), its variance known without σ, s² + var f̂ (Hz²), and the
    /// standardized residual ([`Baseline::standardized`]).
    pub fn residual(&self, f: f64, se: f64, x: &[f64]) -> (f64, f64, f64) {
        let (fit, var) = self.predict(x);
        let r = f - fit;
        let z = r / (se * se + self.unexplained_sd_hz.powi(2) + var).sqrt();
        (r, se * se + var, z)
    }
}

/// Fit the baseline of one mode: frequencies `f` (Hz) with standard errors `se` at the
/// covariate rows `x` (one row per record, the same covariates in each).
pub fn fit_baseline(f: &[f64], se: &[f64], x: &[Vec<f64>]) -> Result<Baseline, MonitorError> {
    let n = f.len();
    if x.len() != n || se.len() != n {
        return Err(MonitorError::CovariateRows {
            records: n,
            rows: x.len().min(se.len()),
        });
    }
    let q = x.first().map_or(0, Vec::len);
    let p = q + 1;
    if n <= p {
        return Err(MonitorError::TooFewRecords {
            records: n,
            parameters: p,
        });
    }
    for i in 0..n {
        let bad = |what, value| {
            Err(MonitorError::BadValue {
                what,
                index: i,
                value,
            })
        };
        if !f[i].is_finite() {
            return bad("the frequency", f[i]);
        }
        if !(se[i].is_finite() && se[i] >= 0.0) {
            return bad("the standard error", se[i]);
        }
        if x[i].len() != q {
            return bad("the covariate count", x[i].len() as f64);
        }
        if let Some(v) = x[i].iter().find(|v| !v.is_finite()) {
            return bad("a covariate", *v);
        }
    }
    let design = DMatrix::from_fn(n, p, |i, j| if j == 0 { 1.0 } else { x[i][j - 1] });
    let y = DVector::from_column_slice(f);
    let xtx = design.transpose() * &design;
    let inverse = xtx.clone().try_inverse().ok_or(MonitorError::Collinear)?;
    // A near-singular design: the inverse does not give back the identity.
    let check = &inverse * &xtx - DMatrix::identity(p, p);
    if !check.iter().all(|v| v.abs() < 1e-6) {
        return Err(MonitorError::Collinear);
    }
    let beta = &inverse * design.transpose() * &y;
    let residuals = &y - &design * &beta;
    let rss = residuals.norm_squared();
    let mean_se2 = se.iter().map(|s| s * s).sum::<f64>() / n as f64;
    // Method of moments: E[RSS / (n − p)] = σ² + mean(s²) (to first order).
    let total = rss / (n - p) as f64;
    let unexplained = (total - mean_se2).max(0.0);
    let covariance = (inverse * total).iter().copied().collect::<Vec<f64>>();
    // nalgebra is column-major; the matrix is symmetric, so the order is the same.
    Ok(Baseline {
        coefficients: beta.iter().copied().collect(),
        covariance,
        unexplained_sd_hz: unexplained.sqrt(),
        records: n,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_distr::{Distribution, Normal};

    /// The regression recovers a temperature coefficient and the unexplained spread, and
    /// the standardized residuals of fresh in-control records have unit variance.
    #[test]
    fn recovers_the_coefficients_and_standardizes_fresh_records() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(11);
        let normal = Normal::new(0.0, 1.0).unwrap();
        let (f0, slope, sigma, se) = (2.0, -0.004, 0.002, 0.001);
        let mut sample = |n: usize| {
            let mut f = Vec::new();
            let mut x = Vec::new();
            for _ in 0..n {
                let t: f64 = rng.random_range(-10.0..25.0);
                f.push(
                    f0 + slope * t + sigma * normal.sample(&mut rng) + se * normal.sample(&mut rng),
                );
                x.push(vec![t]);
            }
            (f, x)
        };
        let (f, x) = sample(400);
        let b = fit_baseline(&f, &vec![se; 400], &x).unwrap();
        // Standard error of the slope ≈ 0.0022 / (sd(t) ≈ 10.1 · √400) ≈ 1.1e-5: 5 of them.
        assert!((b.coefficients[1] - slope).abs() < 5.5e-5, "{b:?}");
        // σ from 400 records: relative spread of the estimate ≈ (total / σ²)/√200 ≈ 9 %.
        assert!((b.unexplained_sd_hz - sigma).abs() < 0.3 * sigma, "{b:?}");
        let (f, x) = sample(2000);
        let z: Vec<f64> = f
            .iter()
            .zip(&x)
            .map(|(f, x)| b.standardized(*f, se, x))
            .collect();
        let mean = z.iter().sum::<f64>() / z.len() as f64;
        let var = z.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / z.len() as f64;
        // 2000 draws: the variance's estimate has a spread of √(2/2000) ≈ 0.03; σ's own
        // error (9 %) moves it by up to ~15 %.
        assert!(
            mean.abs() < 0.15 && (var - 1.0).abs() < 0.25,
            "{mean} {var}"
        );
    }

    #[test]
    fn bad_training_sets_are_refused() {
        let x = vec![vec![1.0]; 5];
        assert_eq!(
            fit_baseline(&[1.0; 5], &[0.1; 5], &x),
            Err(MonitorError::Collinear)
        );
        assert!(matches!(
            fit_baseline(&[1.0; 2], &[0.1; 2], &[vec![1.0], vec![2.0]]),
            Err(MonitorError::TooFewRecords {
                records: 2,
                parameters: 2
            })
        ));
        let x: Vec<Vec<f64>> = (0..5).map(|i| vec![i as f64]).collect();
        assert!(matches!(
            fit_baseline(&[1.0, 1.0, f64::NAN, 1.0, 1.0], &[0.1; 5], &x),
            Err(MonitorError::BadValue { index: 2, .. })
        ));
        // No covariates: the mean and the spread.
        let b = fit_baseline(&[1.0, 2.0, 3.0], &[0.0; 3], &[vec![], vec![], vec![]]).unwrap();
        assert!(
            (b.coefficients[0] - 2.0).abs() < 1e-12 && (b.unexplained_sd_hz - 1.0).abs() < 1e-12
        );
    }
}
