//! The subspace-based damage test (Basseville et al. 2000; Döhler and Mevel 2013): a second
//! detector that needs no mode picking. A record's output correlations R_k = E[y_{t+k} y_tᵀ]
//! fill a block Hankel matrix H (block (i, j) = R_{i+j+1}, i < p + 1 block rows, j < q block
//! columns), whose column space is the observability matrix's: the structure's modes, and
//! nothing of the excitation but its level. The reference's left null space S (the
//! eigenvectors of H₀H₀ᵀ beyond the model order n, H₀ the training records' mean) is
//! orthogonal to it, so the residual ζ = vec(Sᵀ H V₀) of a record of the same structure is
//! zero up to estimation noise, and moves when the modes do. (V₀, the n leading right
//! singular vectors of H₀, compresses the columns: ζ has (p + 1)r − n by n entries.)
//!
//! - **Excitation level**: each H is divided by its Frobenius norm (the null space does not
//!   depend on the scale; the level would).
//! - **Environmental variability**: the residual's mean and covariance Σ are estimated from
//!   the training records themselves (the scatter within a record, Döhler's usual Σ, would
//!   call every change of temperature a damage), and with the records' environmental
//!   regressors x (the covariates through the lags, breakpoints and curvatures the modes'
//!   environmental models chose, [`crate::environment`]) its mean follows them:
//!   ζ = B [1; x] + e, B fitted by least squares over the training records, as each mode's
//!   frequency is. A frequency moved by ±1.5 % over a season moves ζ nearly linearly, so the
//!   reference no longer has to hold the season's swing in Σ, where a 1 % change of one mode
//!   lay largely within it.
//! - **The test**: Hotelling's T² = eᵀ Σ⁻¹ e / (1 + x̃ᵀ(XᵀX)⁻¹x̃) of a new record (e its
//!   residual from the regression's prediction, x̃ = [1; x]); with m training records, q
//!   regressors with the intercept, ν = m − q and d entries, T² (ν − d + 1)/(d ν) follows
//!   F(d, ν − d + 1) when the records are independent and normal, from which the threshold at
//!   the nominal false-alarm probability α per record. The campaign's records are neither
//!   (temperature cycles, slow effects): the threshold used is fitted to the training
//!   records' own leave-one-out T², and the CUSUM's limit calibrated on their scores
//!   ([`crate::calibration`]).

use nalgebra::{DMatrix, DVector};
use statrs::distribution::{ContinuousCDF, FisherSnedecor, Gamma, Normal};

use crate::calibration::{Calibration, Sides};
use crate::chart::{Cusum, Side};

use crate::MonitorError;

/// A record's output correlations R_1 … R_lags (each channels × channels, row-major in
/// one vector: R_k(a, b) = mean of y_a(t + k) y_b(t), the means removed), kept with the
/// record so that the test can be run on a campaign's records after their identification.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Correlations {
    /// Channels.
    pub channels: usize,
    /// R_1 … R_lags, each `channels²` values, row by row.
    pub values: Vec<f64>,
}

/// Lags kept with each record: enough for block Hankel matrices of up to
/// max(2, ⌈24 / channels⌉) block rows and columns (model orders to about 22).
pub fn lags_kept(channels: usize) -> usize {
    2 * 24usize.div_ceil(channels.max(1)).max(2) - 1
}

impl Correlations {
    /// The correlations of `channels` up to `lags`.
    pub fn of(channels: &[&[f64]], lags: usize) -> Correlations {
        let r = channels.len();
        let n = channels.first().map_or(0, |c| c.len());
        let means: Vec<f64> = channels
            .iter()
            .map(|c| c.iter().sum::<f64>() / n.max(1) as f64)
            .collect();
        let mut values = vec![0.0; lags * r * r];
        for k in 1..=lags.min(n.saturating_sub(1)) {
            for a in 0..r {
                for b in 0..r {
                    let (ya, yb) = (channels[a], channels[b]);
                    let s: f64 = (0..n - k)
                        .map(|t| (ya[t + k] - means[a]) * (yb[t] - means[b]))
                        .sum();
                    values[((k - 1) * r + a) * r + b] = s / (n - k) as f64;
                }
            }
        }
        Correlations {
            channels: r,
            values,
        }
    }

    /// Lags held.
    pub fn lags(&self) -> usize {
        self.values.len() / (self.channels * self.channels).max(1)
    }

    /// The block Hankel matrix of `blocks` block rows and columns (block (i, j) = R_{i+j+1}),
    /// divided by its Frobenius norm; `None` when the lags held do not reach.
    pub fn hankel(&self, blocks: usize) -> Option<DMatrix<f64>> {
        let r = self.channels;
        if 2 * blocks - 1 > self.lags() {
            return None;
        }
        let mut h = DMatrix::<f64>::zeros(blocks * r, blocks * r);
        for i in 0..blocks {
            for j in 0..blocks {
                let k = i + j; // R_{k+1}
                for a in 0..r {
                    for b in 0..r {
                        h[(i * r + a, j * r + b)] = self.values[(k * r + a) * r + b];
                    }
                }
            }
        }
        let norm = h.norm();
        Some(if norm > 0.0 { h / norm } else { h })
    }
}

/// A record's block Hankel matrix of output correlations, `blocks` block rows and columns
/// (lags 1 to 2·blocks − 1), divided by its Frobenius norm.
pub fn hankel(channels: &[&[f64]], blocks: usize) -> DMatrix<f64> {
    let lags = 2 * blocks - 1;
    Correlations::of(channels, lags)
        .hankel(blocks)
        .unwrap_or_else(|| DMatrix::zeros(blocks * channels.len(), blocks * channels.len()))
}

/// The block rows (and columns) for a model of order `order` on `channels` channels, trained
/// on `training` records, within `lags` lags (a Hankel matrix of b block rows needs 2b − 1):
/// the fewest giving at least 2·order + 2 rows — a left null space at least as large as the
/// signal's, whose residual turns with every pole — unless its residual's (rows − order)·order
/// entries exceed a third of the training records (their covariance would be estimated from
/// too few: its inverse's noise then swamps a change), then fewer, down to the fewest with
/// order + 2 rows. On two-mode records (4 channels, order 4, 300 training records) a 1 %
/// change moved T² by 0.68 of its standard deviation with 2 block rows (16 entries) and by
/// 3.6 with 3 (32 entries; 4 and 6 block rows: 2.7 and 1.6).
pub fn blocks_for(order: usize, channels: usize, training: usize, lags: usize) -> usize {
    let channels = channels.max(1);
    let fewest = (order + 2).div_ceil(channels).max(2);
    let ample = (2 * order + 2).div_ceil(channels).max(fewest);
    let entries = |b: usize| (b * channels).saturating_sub(order) * order;
    (fewest..=ample)
        .rev()
        .find(|&b| 3 * entries(b) <= training && 2 * b - 1 <= lags)
        .unwrap_or(fewest)
}

/// The nominal false-alarm probability per record of the single-record threshold
/// `hyst track` reports.
pub const ALPHA: f64 = 0.01;

/// The reference of the subspace test, trained on the training records' Hankel matrices.
#[derive(Debug, Clone)]
pub struct SubspaceTest {
    null: DMatrix<f64>,
    columns: DMatrix<f64>,
    /// B: the residual's regression on [1; x] (entries × regressors).
    coefficients: DMatrix<f64>,
    /// (XᵀX)⁻¹, for the prediction's own variance.
    gram_inverse: DMatrix<f64>,
    /// Σ⁻¹ through its Cholesky factor.
    cholesky: nalgebra::Cholesky<f64, nalgebra::Dyn>,
    /// Entries of ζ.
    pub dof: usize,
    /// Training records.
    pub training: usize,
    /// T² above which a record is alarmed: the (1 − α) quantile of a gamma law fitted by
    /// moments to the training records' leave-one-out T².
    pub threshold: f64,
    /// The same quantile under normal theory (the scaled F law), beside it.
    pub nominal_threshold: f64,
    /// The nominal false-alarm probability per record.
    pub alpha: f64,
    /// The training records' leave-one-out T², as new records' would be.
    pub leave_one_out: Vec<f64>,
    /// The law of an undamaged record's T² (fitted to the leave-one-out values).
    law: Gamma,
}

impl SubspaceTest {
    /// Train on `hankels` (of the training records, each from [`hankel`]) with their
    /// environmental regressors `regressors` (one vector per record, all of one length;
    /// empty: the residual's mean alone) for a model of order `order` (twice the modes),
    /// alarms at the nominal false-alarm probability `alpha` per record.
    pub fn train(
        hankels: &[DMatrix<f64>],
        regressors: &[Vec<f64>],
        order: usize,
        alpha: f64,
    ) -> Result<SubspaceTest, MonitorError> {
        let m = hankels.len();
        let Some(first) = hankels.first() else {
            return Err(MonitorError::TooFewForSubspace {
                records: 0,
                entries: 0,
            });
        };
        let (rows, cols) = first.shape();
        let order = order.min(rows.saturating_sub(1)).min(cols);
        if order == 0 {
            return Err(MonitorError::NoSubspaceOrder);
        }
        let dof = (rows - order) * order;
        let q = 1 + regressors.first().map_or(0, Vec::len);
        if m <= dof + q {
            return Err(MonitorError::TooFewForSubspace {
                records: m,
                entries: dof,
            });
        }
        let mut h0 = DMatrix::<f64>::zeros(rows, cols);
        for h in hankels {
            h0 += h;
        }
        h0 /= m as f64;
        // Left null space: the eigenvectors of H₀H₀ᵀ with the smallest eigenvalues; column
        // compression: those of H₀ᵀH₀ with the largest (the leading right singular vectors).
        let null = eigenvectors(&h0 * h0.transpose(), rows - order, false);
        let columns = eigenvectors(h0.transpose() * &h0, order, true);
        let z = DMatrix::from_columns(
            &hankels
                .iter()
                .map(|h| residual(&null, &columns, h))
                .collect::<Vec<_>>(),
        );
        let x = DMatrix::from_fn(m, q, |i, k| {
            if k == 0 {
                1.0
            } else {
                regressors
                    .get(i)
                    .and_then(|r| r.get(k - 1))
                    .copied()
                    .unwrap_or(f64::NAN)
            }
        });
        let gram_inverse = (x.transpose() * &x)
            .try_inverse()
            .filter(|g| g.iter().all(|v| v.is_finite()))
            .ok_or(MonitorError::Collinear)?;
        let coefficients = &z * &x * &gram_inverse;
        let e = &z - &coefficients * x.transpose();
        let nu = (m - q) as f64;
        let sums = &e * e.transpose();
        let cholesky = (&sums / nu).cholesky().ok_or(MonitorError::Collinear)?;
        let sums_cholesky = sums.cholesky().ok_or(MonitorError::Collinear)?;
        let df = dof as f64;
        let f = FisherSnedecor::new(df, nu - df + 1.0).map_err(|_| MonitorError::Collinear)?;
        let nominal_threshold = f.inverse_cdf(1.0 - alpha) * df * nu / (nu - df + 1.0);
        // Each training record's T² against the others (leave one out): with g = eᵢᵀA⁻¹eᵢ
        // (A = Σ eeᵀ) and its leverage hᵢ, deleting the record leaves A − eᵢeᵢᵀ/(1 − hᵢ),
        // its prediction error is eᵢ/(1 − hᵢ) of variance Σ/(1 − hᵢ), so by Sherman–Morrison
        // T²ᵢ = (ν − 1) g / ((1 − hᵢ) − g), as a new record's.
        let leave_one_out: Vec<f64> = (0..m)
            .map(|i| {
                let g = mahalanobis(&sums_cholesky, e.column(i).into_owned());
                let xi = x.row(i).transpose();
                let h = (xi.transpose() * &gram_inverse * &xi)[(0, 0)];
                (nu - 1.0) * g / ((1.0 - h) - g)
            })
            .collect();
        let law =
            crate::calibration::gamma_by_moments(&leave_one_out).ok_or(MonitorError::Collinear)?;
        let threshold = law.inverse_cdf(1.0 - alpha);
        Ok(SubspaceTest {
            null,
            columns,
            coefficients,
            gram_inverse,
            cholesky,
            dof,
            training: m,
            threshold,
            nominal_threshold,
            alpha,
            leave_one_out,
            law,
        })
    }

    /// A record's T² (from its [`hankel`] and its regressors, as in training).
    pub fn statistic(&self, h: &DMatrix<f64>, regressors: &[f64]) -> f64 {
        let q = self.gram_inverse.nrows();
        let x = DVector::from_fn(q, |k, _| {
            if k == 0 {
                1.0
            } else {
                regressors.get(k - 1).copied().unwrap_or(f64::NAN)
            }
        });
        if x.iter().any(|v| !v.is_finite()) {
            return f64::NAN;
        }
        let leverage = (x.transpose() * &self.gram_inverse * &x)[(0, 0)];
        let e = residual(&self.null, &self.columns, h) - &self.coefficients * x;
        mahalanobis(&self.cholesky, e) / (1.0 + leverage)
    }

    /// A record's T² as a standard normal score, Φ⁻¹(G(T²)) with G the fitted law: standard
    /// normal for undamaged records, larger when the structure changed (±8 at most).
    pub fn score(&self, t2: f64) -> f64 {
        Normal::standard()
            .inverse_cdf(self.law.cdf(t2))
            .clamp(-8.0, 8.0)
    }
}

/// dᵀΣ⁻¹d, Σ given by its Cholesky factor.
fn mahalanobis(cholesky: &nalgebra::Cholesky<f64, nalgebra::Dyn>, d: DVector<f64>) -> f64 {
    cholesky
        .l()
        .solve_lower_triangular(&d)
        .unwrap_or(d)
        .norm_squared()
}

/// The `count` eigenvectors of the symmetric `m` with the largest eigenvalues (`largest`),
/// or the smallest, as columns.
fn eigenvectors(m: DMatrix<f64>, count: usize, largest: bool) -> DMatrix<f64> {
    let eig = m.symmetric_eigen();
    let mut by_size: Vec<usize> = (0..eig.eigenvalues.len()).collect();
    by_size.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    if largest {
        by_size.reverse();
    }
    DMatrix::from_columns(
        &by_size[..count]
            .iter()
            .map(|&i| eig.eigenvectors.column(i).into_owned())
            .collect::<Vec<_>>(),
    )
}

/// The subspace test over a campaign, charted as the modes are.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SubspaceChart {
    /// Each record's time (s).
    #[cfg_attr(feature = "serde", serde(default))]
    pub time: Vec<f64>,
    /// Each record's T² (NaN for a record without a Hankel matrix or regressors).
    pub t2: Vec<f64>,
    /// Its score (standard normal when undamaged), charted.
    pub score: Vec<f64>,
    /// Entries of the residual.
    pub dof: usize,
    /// The records before charting (the training period).
    pub training: usize,
    /// Those of them the reference was trained on (with correlations and regressors, not
    /// skipped).
    pub trained_on: usize,
    /// The environmental model the residual was regressed on (the union of the modes'
    /// terms; `None`: its mean alone, without covariates).
    #[cfg_attr(feature = "serde", serde(default))]
    pub environment: Option<crate::environment::Environment>,
    /// The single-record threshold of T² at the nominal false-alarm probability `alpha`
    /// (fitted), and under normal theory.
    pub threshold: f64,
    /// Under normal theory (the scaled F law).
    pub nominal_threshold: f64,
    /// The nominal false-alarm probability per record.
    pub alpha: f64,
    /// The CUSUM's limit calibrated on the training records' leave-one-out scores (`None`:
    /// not asked, or too few: the nominal limit).
    #[cfg_attr(feature = "serde", serde(default))]
    pub calibration: Option<Calibration>,
    /// The CUSUM's limit charted.
    #[cfg_attr(feature = "serde", serde(default))]
    pub limit: f64,
    /// Records after training whose T² passed `threshold`.
    pub above_threshold: Vec<usize>,
    /// Records at which the CUSUM of the scores (upper side) passed its limit.
    pub alarms: Vec<usize>,
}

/// A record as the subspace test takes it: its Hankel matrix (from [`hankel`]) and its
/// environmental regressors (empty without covariates).
pub type SubspaceRecord = (DMatrix<f64>, Vec<f64>);

/// The subspace test over `records` (each record's [`SubspaceRecord`]; `None` for a record
/// without correlations or covariates; recorded at `time`, s), trained on the first
/// `training`, for a model of order `order`; its scores after training charted by `chart`'s
/// upper side (a change makes T² larger), the limit calibrated on the training records'
/// leave-one-out scores when `calibrate`.
pub fn subspace_chart(
    records: &[Option<SubspaceRecord>],
    time: &[f64],
    training: usize,
    order: usize,
    alpha: f64,
    chart: &Cusum,
    calibrate: bool,
) -> Result<SubspaceChart, MonitorError> {
    let (train, regressors): (Vec<DMatrix<f64>>, Vec<Vec<f64>>) = records
        .iter()
        .take(training)
        .flatten()
        .filter(|(_, x)| x.iter().all(|v| v.is_finite()))
        .cloned()
        .unzip();
    let test = SubspaceTest::train(&train, &regressors, order, alpha)?;
    let t2: Vec<f64> = records
        .iter()
        .map(|r| r.as_ref().map_or(f64::NAN, |(h, x)| test.statistic(h, x)))
        .collect();
    let score: Vec<f64> = t2
        .iter()
        .map(|&t| if t.is_nan() { t } else { test.score(t) })
        .collect();
    let calibration = if calibrate {
        let trained: Vec<f64> = test.leave_one_out.iter().map(|&t| test.score(t)).collect();
        crate::calibration::calibrate(&trained, chart, Sides::Up)
    } else {
        None
    };
    let used = calibration.as_ref().map_or(*chart, |c| c.chart(chart));
    let later: Vec<f64> = score.iter().skip(training).copied().collect();
    let alarms = used
        .alarms(&later)
        .into_iter()
        .filter(|a| a.side == Side::Up)
        .map(|a| a.index + training)
        .collect();
    let above_threshold = (training..records.len())
        .filter(|&i| t2[i] > test.threshold)
        .collect();
    Ok(SubspaceChart {
        time: time.to_vec(),
        t2,
        score,
        dof: test.dof,
        training,
        trained_on: test.training,
        environment: None,
        threshold: test.threshold,
        nominal_threshold: test.nominal_threshold,
        alpha,
        calibration,
        limit: used.h,
        above_threshold,
        alarms,
    })
}

/// ζ = vec(Sᵀ H V₀).
fn residual(null: &DMatrix<f64>, columns: &DMatrix<f64>, h: &DMatrix<f64>) -> DVector<f64> {
    let z = null.transpose() * h * columns;
    DVector::from_column_slice(z.as_slice())
}

#[cfg(test)]
mod tests {
    use super::*;
    use covssi::synth::ModalRecord;

    fn record(f2: f64, level: f64, seed: u64) -> DMatrix<f64> {
        let gains: Vec<Vec<f64>> = (0..4)
            .map(|c| {
                (0..2)
                    .flat_map(|j| {
                        let x = (c + 1) as f64 / 5.0;
                        [
                            level * ((j + 1) as f64 * std::f64::consts::PI * x).sin(),
                            0.0,
                        ]
                    })
                    .collect()
            })
            .collect();
        let y = ModalRecord::new(20.0, &[(1.3, 0.02), (f2, 0.02)])
            .with_gains(gains)
            .with_noise(0.05 / level)
            .generate(6000, seed);
        let views: Vec<&[f64]> = y.iter().map(|c| c.as_slice()).collect();
        hankel(&views, 2)
    }

    /// Trained on 120 records of a 2-mode structure (4 channels, 2 block rows: 16 entries of
    /// ζ), over levels spread by a factor e^{±0.5}: of 300 fresh records of the same
    /// structure, about the nominal 1 % pass the fitted threshold (binomial 3 ± 1.7; at most
    /// 9 taken), while under normal theory's threshold more do (the level's spread makes the
    /// T² heavier-tailed than F); the CUSUM of the scores raises no alarm over them, and
    /// alarms within 60 records of the second mode dropping 2 % (41 here: the change moves
    /// the score by under one standard deviation, and each record alone shows it in under a
    /// third of the records).
    #[test]
    fn a_change_of_one_mode_is_charted_and_noise_is_not() {
        let level = |i: u64| (0.5 * ((i as f64 * 0.7).sin())).exp();
        let with = |h: DMatrix<f64>| Some((h, Vec::new()));
        let mut hankels: Vec<Option<SubspaceRecord>> = (0..120)
            .map(|i| with(record(3.4, level(i), 4_610_000 + i)))
            .collect();
        hankels.extend((0..300).map(|i| with(record(3.4, level(i + 7), 4_620_000 + i))));
        let undamaged = hankels.len();
        hankels.extend((0..60).map(|i| with(record(3.4 * 0.98, level(i + 3), 4_630_000 + i))));
        let time: Vec<f64> = (0..hankels.len()).map(|i| 3600.0 * i as f64).collect();
        let c = subspace_chart(&hankels, &time, 120, 4, 0.01, &Cusum::default(), true).unwrap();
        assert_eq!(c.dof, 16);
        let passed = c.above_threshold.iter().filter(|&&i| i < undamaged).count();
        let nominal = (120..undamaged)
            .filter(|&i| c.t2[i] > c.nominal_threshold)
            .count();
        eprintln!(
            "fitted threshold {:.1}: {passed} of 300; normal theory's {:.1}: {nominal} of 300; alarms {:?}",
            c.threshold, c.nominal_threshold, c.alarms
        );
        assert!(passed <= 9, "{passed} of 300");
        assert!(nominal > passed, "{nominal} against {passed}");
        let first = c.alarms.first().copied().unwrap_or(usize::MAX);
        assert!(
            first >= undamaged && first < undamaged + 60,
            "{:?}",
            c.alarms
        );
        let single = c
            .above_threshold
            .iter()
            .filter(|&&i| i >= undamaged)
            .count();
        assert!(single < 20, "{single} of 60 alone");
    }

    /// The block rows: the fewest with twice the order's rows when the training records
    /// estimate that residual's covariance (three records per entry), else fewer, never
    /// below the fewest with order + 2 rows; within the lags kept.
    #[test]
    fn block_rows_follow_the_order_and_the_training() {
        // 4 channels, order 4: 3 block rows (12 rows, 32 entries) with 96 or more records.
        assert_eq!(blocks_for(4, 4, 300, 11), 3);
        assert_eq!(blocks_for(4, 4, 95, 11), 2);
        // 6 channels, order 8: 3 block rows (18 rows, 80 entries) from 240 records.
        assert_eq!(blocks_for(8, 6, 240, 7), 3);
        assert_eq!(blocks_for(8, 6, 72, 7), 2);
        // Lags kept for 2 block rows only (3 lags): 2 whatever the training.
        assert_eq!(blocks_for(4, 4, 10_000, 3), 2);
    }

    /// The study behind [`blocks_for`]'s rule (ignored: a minute; `cargo test --release -p
    /// hyst-monitor --lib block_rows_sensitivity -- --ignored --nocapture`): two-mode records
    /// (4 channels, order 4), 300 training records, 80 undamaged and 80 with the second mode
    /// 1 % lower, for 2, 3, 4 and 6 block rows: the mean T² shift in the undamaged records'
    /// standard deviations (measured: 0.68, 3.62, 2.69, 1.59).
    #[test]
    #[ignore]
    fn block_rows_sensitivity_study() {
        let rec = |f2: f64, seed: u64, blocks: usize| -> DMatrix<f64> {
            let gains: Vec<Vec<f64>> = (0..4)
                .map(|c| {
                    (0..2)
                        .flat_map(|j| {
                            let x = (c + 1) as f64 / 5.0;
                            [((j + 1) as f64 * std::f64::consts::PI * x).sin(), 0.0]
                        })
                        .collect()
                })
                .collect();
            let y = ModalRecord::new(20.0, &[(1.3, 0.02), (f2, 0.02)])
                .with_gains(gains)
                .with_noise(0.05)
                .generate(6000, seed);
            let views: Vec<&[f64]> = y.iter().map(|c| c.as_slice()).collect();
            hankel(&views, blocks)
        };
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        for blocks in [2usize, 3, 4, 6] {
            let train: Vec<DMatrix<f64>> =
                (0..300).map(|i| rec(3.4, 4_710_000 + i, blocks)).collect();
            let t = SubspaceTest::train(&train, &[], 4, 0.01).unwrap();
            let stat = |f2: f64, seed: u64| -> Vec<f64> {
                (0..80)
                    .map(|i| t.statistic(&rec(f2, seed + i, blocks), &[]))
                    .collect()
            };
            let (a, b) = (stat(3.4, 4_720_000), stat(3.4 * 0.99, 4_730_000));
            let sd = (a.iter().map(|x| (x - mean(&a)).powi(2)).sum::<f64>() / 79.0).sqrt();
            println!(
                "{blocks} block rows: {} entries, mean T² {:.1} (SD {sd:.1}), 1 % lower {:.1}: a shift of {:.2} SD",
                t.dof,
                mean(&a),
                mean(&b),
                (mean(&b) - mean(&a)) / sd
            );
        }
    }

    #[test]
    fn too_few_training_records_are_said() {
        let h: Vec<DMatrix<f64>> = (0..5).map(|i| record(3.4, 1.0, 4_640_000 + i)).collect();
        let e = SubspaceTest::train(&h, &[], 4, 0.01).unwrap_err();
        assert!(
            matches!(
                e,
                MonitorError::TooFewForSubspace {
                    records: 5,
                    entries: 16
                }
            ),
            "{e}"
        );
        // No reference mode: order 0 is said, not a panic on an empty set of vectors.
        let e = SubspaceTest::train(&h, &[], 0, 0.01).unwrap_err();
        assert!(matches!(e, MonitorError::NoSubspaceOrder), "{e}");
    }
}
