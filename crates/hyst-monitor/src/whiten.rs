//! The standardized residuals' own correlation from record to record, and its removal before
//! they are charted (see the crate's documentation).
//!
//! The baseline's z are standard normal when nothing changes, but not independent when the
//! covariates leave a slow effect unexplained (the structure's temperature lagging the air's,
//! moisture, an unmeasured load): then a CUSUM sums runs of like-signed z and raises alarms
//! far more often than its run length says. Over the training records the z are fitted an
//! autoregression z_t = Σ_{k=1}^{p} φ_k z_{t−k} + a_t, its order p ≤ [`MAX_ORDER`] chosen by
//! BIC (p = 0 when they are independent), and the chart is given the standardized
//! innovations a_t / s_a, which are independent and standard normal when the model holds.
//! A permanent shift δ of z then enters the innovations as δ (1 − Σφ_k) / s_a after its first
//! p records: a change is slower to tell from a correlated environment, as it should be.

use nalgebra::{DMatrix, DVector};

/// Highest autoregressive order tried.
pub const MAX_ORDER: usize = 8;

/// The autoregression of a mode's standardized residuals over the training records.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ResidualModel {
    /// φ_1 … φ_p (empty: the residuals are taken as independent).
    pub coefficients: Vec<f64>,
    /// s_a, the innovations' standard deviation (1 when p = 0: the z are standardized
    /// already).
    pub innovation_sd: f64,
    /// Residuals the fit used (those with p finite predecessors).
    pub records: usize,
}

impl Default for ResidualModel {
    /// Independent residuals: the chart is given the z themselves.
    fn default() -> Self {
        ResidualModel {
            coefficients: Vec::new(),
            innovation_sd: 1.0,
            records: 0,
        }
    }
}

impl ResidualModel {
    /// Fit the autoregression to the training residuals `z` in time order (NaN where a record
    /// had none: no prediction is made across it), its order chosen by BIC over the same
    /// residuals for every order; too few residuals give p = 0.
    pub fn fit(z: &[f64]) -> ResidualModel {
        // Every order is compared on the residuals that have MAX_ORDER finite predecessors.
        let common: Vec<usize> = (MAX_ORDER..z.len())
            .filter(|&t| z[t - MAX_ORDER..=t].iter().all(|v| v.is_finite()))
            .collect();
        let n = common.len();
        if n < 10 * MAX_ORDER {
            return ResidualModel::default();
        }
        let bic = |p: usize| -> f64 {
            let rss = if p == 0 {
                // The z are standardized: their model is unit variance, not a fitted one.
                common.iter().map(|&t| z[t] * z[t]).sum::<f64>()
            } else {
                match least_squares(z, &common, p) {
                    Some((_, rss)) => rss,
                    None => return f64::INFINITY,
                }
            };
            n as f64 * (rss / n as f64).ln() + p as f64 * (n as f64).ln()
        };
        let p = (0..=MAX_ORDER)
            .map(|p| (p, bic(p)))
            .fold(
                (0, f64::INFINITY),
                |best, c| if c.1 < best.1 { c } else { best },
            );
        let p = p.0;
        if p == 0 {
            return ResidualModel {
                records: n,
                ..ResidualModel::default()
            };
        }
        // Refitted on every residual with p finite predecessors.
        let rows: Vec<usize> = (p..z.len())
            .filter(|&t| z[t - p..=t].iter().all(|v| v.is_finite()))
            .collect();
        match least_squares(z, &rows, p) {
            Some((phi, rss)) if rows.len() > p => ResidualModel {
                coefficients: phi,
                innovation_sd: (rss / (rows.len() - p) as f64).sqrt(),
                records: rows.len(),
            },
            _ => ResidualModel::default(),
        }
    }

    /// The standardized innovations of `z` (in time order, NaN where a record has none),
    /// `history` the residuals just before them (the training's, say): a_t / s_a where the p
    /// residuals before t are finite, else z_t itself (its marginal standardization).
    pub fn innovations(&self, history: &[f64], z: &[f64]) -> Vec<f64> {
        let p = self.coefficients.len();
        let all: Vec<f64> = history.iter().chain(z).copied().collect();
        let h = history.len();
        (0..z.len())
            .map(|i| {
                let t = h + i;
                let v = all[t];
                if !v.is_finite() || p == 0 {
                    return v;
                }
                if t < p || !all[t - p..t].iter().all(|x| x.is_finite()) {
                    return v;
                }
                let predicted: f64 = (1..=p).map(|k| self.coefficients[k - 1] * all[t - k]).sum();
                (v - predicted) / self.innovation_sd
            })
            .collect()
    }
}

/// The least-squares AR(p) coefficients on the rows `t` of `z`, and the residual sum of
/// squares.
fn least_squares(z: &[f64], rows: &[usize], p: usize) -> Option<(Vec<f64>, f64)> {
    let a = DMatrix::from_fn(rows.len(), p, |i, k| z[rows[i] - k - 1]);
    let b = DVector::from_iterator(rows.len(), rows.iter().map(|&t| z[t]));
    let svd = a.clone().svd(true, true);
    let phi = svd.solve(&b, 1e-12).ok()?;
    let rss = (&b - &a * &phi).norm_squared();
    rss.is_finite()
        .then(|| (phi.iter().copied().collect(), rss))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    fn ar1(n: usize, phi: f64, seed: u64) -> Vec<f64> {
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
        let normal = Normal::new(0.0, 1.0).unwrap();
        let scale = (1.0 - phi * phi).sqrt();
        let mut z = Vec::with_capacity(n);
        let mut prev = normal.sample(&mut rng);
        for _ in 0..n {
            prev = phi * prev + scale * normal.sample(&mut rng);
            z.push(prev);
        }
        z
    }

    /// Independent residuals get p = 0 on most seeds; an AR(1) of φ = 0.8 gets φ back within
    /// its standard error from two weeks of hourly records, and from a longer training its
    /// innovations are uncorrelated with unit variance.
    #[test]
    fn finds_the_correlation_and_removes_it() {
        // BIC's chance of a spurious order on 336 independent values is a few per cent
        // per order; over 20 seeds at most a few may pick one.
        let spurious = (0..20)
            .filter(|&s| {
                !ResidualModel::fit(&ar1(336, 0.0, 100 + s))
                    .coefficients
                    .is_empty()
            })
            .count();
        assert!(spurious <= 3, "{spurious} of 20");
        for seed in 0..5 {
            let m = ResidualModel::fit(&ar1(336, 0.8, 200 + seed));
            // SE of φ̂ ≈ √((1 − φ²)/n) = 0.033, and a downward bias of about (1 + 3φ)/n =
            // 0.01: 0.12 is 3.3 SE beyond it. BIC may add a small second lag.
            assert!((m.coefficients[0] - 0.8).abs() < 0.12, "{m:?}");
            let z = ar1(3000, 0.8, 400 + seed);
            let m = ResidualModel::fit(&z);
            // Fresh values after the training's: innovations of unit variance (spread of the
            // estimate √(2/2000) = 0.03), lag-1 correlation within 3 of its spread 1/√2000
            // plus what φ̂'s error from 3000 values (SE 0.011) leaves in them, at most about
            // 3 · 0.011 · 0.8 = 0.03 (a_t = w_t + (φ − φ̂) z_{t−1}).
            let fresh = ar1(2000, 0.8, 300 + seed);
            let a = m.innovations(&z, &fresh);
            let var = a.iter().map(|v| v * v).sum::<f64>() / a.len() as f64;
            let r1 = a.windows(2).map(|w| w[0] * w[1]).sum::<f64>() / a.len() as f64 / var;
            assert!((var - 1.0).abs() < 0.12, "{var} {m:?}");
            assert!(r1.abs() < 3.0 / (2000f64).sqrt() + 0.03, "{r1} {m:?}");
        }
    }

    /// A NaN (a record without the mode) is never predicted across: the value after it is
    /// passed as it is, and the NaN stays NaN.
    #[test]
    fn gaps_are_not_predicted_across() {
        let m = ResidualModel {
            coefficients: vec![0.5],
            innovation_sd: 0.5,
            records: 100,
        };
        let a = m.innovations(&[1.0], &[2.0, f64::NAN, 3.0, 1.0]);
        assert_eq!(a[0], (2.0 - 0.5) / 0.5);
        assert!(a[1].is_nan());
        assert_eq!(a[2], 3.0);
        assert_eq!(a[3], (1.0 - 1.5) / 0.5);
        // Too few residuals: independent.
        assert_eq!(ResidualModel::fit(&[0.5; 20]), ResidualModel::default());
    }
}
