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
    /// The same correlations of the record's [`PARTS`] consecutive parts (empty when a part
    /// would be shorter than 50 times the lags), at single precision: their scatter is the
    /// record's own estimation noise ([`SubspaceTest`]).
    #[cfg_attr(feature = "serde", serde(default))]
    pub parts: Vec<Vec<f32>>,
}

/// The parts a record's correlations are also computed on, for its own estimation noise.
pub const PARTS: usize = 4;

/// Lags kept with each record: enough for block Hankel matrices of up to
/// max(2, ⌈24 / channels⌉) block rows and columns (model orders to about 22).
pub fn lags_kept(channels: usize) -> usize {
    2 * 24usize.div_ceil(channels.max(1)).max(2) - 1
}

impl Correlations {
    /// The correlations of `channels` up to `lags`.
    pub fn of(channels: &[&[f64]], lags: usize) -> Correlations {
        let n = channels.first().map_or(0, |c| c.len());
        let part = n / PARTS;
        let parts = if part >= 50 * lags.max(1) {
            (0..PARTS)
                .map(|p| {
                    let views: Vec<&[f64]> = channels
                        .iter()
                        .map(|c| &c[p * part..(p + 1) * part])
                        .collect();
                    let whole = Correlations::lagged(&views, lags);
                    whole.iter().map(|&v| v as f32).collect()
                })
                .collect()
        } else {
            Vec::new()
        };
        Correlations {
            channels: channels.len(),
            values: Correlations::lagged(channels, lags),
            parts,
        }
    }

    /// R_1 … R_lags of `channels`, their means removed.
    fn lagged(channels: &[&[f64]], lags: usize) -> Vec<f64> {
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
        values
    }

    /// Lags held.
    pub fn lags(&self) -> usize {
        self.values.len() / (self.channels * self.channels).max(1)
    }

    /// The block Hankel matrix of `blocks` block rows and columns (block (i, j) = R_{i+j+1}),
    /// divided by its Frobenius norm; `None` when the lags held do not reach.
    pub fn hankel(&self, blocks: usize) -> Option<DMatrix<f64>> {
        if 2 * blocks - 1 > self.lags() {
            return None;
        }
        let h = self.unscaled(blocks, |i| self.values[i]);
        let norm = h.norm();
        Some(if norm > 0.0 { h / norm } else { h })
    }

    /// The record as the subspace test takes it: its Hankel matrix of `blocks` block rows,
    /// its parts' (each divided by the whole record's norm, so that their scatter is the
    /// whole's estimation noise times √[`PARTS`]) and its environmental `regressors`; `None`
    /// when the lags held do not reach.
    pub fn record(&self, blocks: usize, regressors: Vec<f64>) -> Option<SubspaceRecord> {
        if 2 * blocks - 1 > self.lags() {
            return None;
        }
        let whole = self.unscaled(blocks, |i| self.values[i]);
        let norm = whole.norm();
        let scale = if norm > 0.0 { 1.0 / norm } else { 1.0 };
        let parts = self
            .parts
            .iter()
            .filter(|p| p.len() == self.values.len())
            .map(|p| self.unscaled(blocks, |i| f64::from(p[i])) * scale)
            .collect();
        Some(SubspaceRecord {
            hankel: whole * scale,
            channels: self.channels,
            parts,
            regressors,
        })
    }

    /// The block Hankel matrix of the correlations `value(i)` (indexed as `values`).
    fn unscaled(&self, blocks: usize, value: impl Fn(usize) -> f64) -> DMatrix<f64> {
        let r = self.channels;
        let mut h = DMatrix::<f64>::zeros(blocks * r, blocks * r);
        for i in 0..blocks {
            for j in 0..blocks {
                let k = i + j; // R_{k+1}
                for a in 0..r {
                    for b in 0..r {
                        h[(i * r + a, j * r + b)] = value((k * r + a) * r + b);
                    }
                }
            }
        }
        h
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
    /// How a record's residual covariance scales with its own estimation noise (`None`:
    /// records without parts, or no such dependence found).
    pub scale_model: Option<ScaleModel>,
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
    /// The test focused on the reference modes' frequencies, when they give directions.
    focus: Option<Focus>,
}

/// The reference modes' frequency changes estimated from a record's residual (the test on
/// the modal parameters): with J the residual's sensitivities to a relative change of each
/// mode's frequency ([`crate::sensitivity`]), θ̂ = L e with L = (JᵀJ)⁻¹Jᵀ, of covariance
/// LΣLᵀ(c + leverage); each mode's θ̂ⱼ over its standard deviation is standard normal when
/// undamaged, and moves by the change over it when mode j's frequency changes. A persistent
/// change moves it linearly (a χ² statistic squares it, the full T² spreads it over all of
/// ζ's entries), and its sign and mode are known. Not weighted by Σ⁻¹ (generalized least
/// squares): Σ's smallest directions hold the little of a change that the first-order J
/// misses, and weighted by Σ⁻¹ they pulled a 1 % change's estimate to −0.1 % and −0.5 % on
/// two-mode records (of fixed and of varying noise), where the unweighted one gave −1.02 %
/// and −1.03 %.
#[derive(Debug, Clone)]
struct Focus {
    /// L = (JᵀJ)⁻¹Jᵀ (modes × entries).
    projector: DMatrix<f64>,
    /// LΣLᵀ.
    covariance: DMatrix<f64>,
    /// Each direction's pole frequency (cycles per sample), ascending.
    frequencies: Vec<f64>,
    /// The training records' leave-one-out standardized shifts, per mode then record.
    leave_one_out: Vec<Vec<f64>>,
    /// Their mean and standard deviation per mode, with which every record's is
    /// standardized again (the regression's own misfit included).
    center: Vec<f64>,
    spread: Vec<f64>,
}

/// An alarm of the subspace test's chart of one mode's frequency change.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SubspaceAlarm {
    /// The record that raised it.
    pub record: usize,
    /// The direction (the reference's modes in ascending frequency, from 0).
    pub mode: usize,
    /// Which way the frequency moved.
    pub side: Side,
    /// The record's estimated relative frequency change of that mode.
    pub shift: f64,
}

impl SubspaceTest {
    /// Train on the training `records` (each from [`Correlations::record`], all of one
    /// shape and one regressor count; empty regressors: the residual's mean alone) for a
    /// model of order `order` (twice the modes), alarms at the nominal false-alarm
    /// probability `alpha` per record.
    pub fn train(
        records: &[SubspaceRecord],
        order: usize,
        alpha: f64,
    ) -> Result<SubspaceTest, MonitorError> {
        let m = records.len();
        let Some(first) = records.first() else {
            return Err(MonitorError::TooFewForSubspace {
                records: 0,
                entries: 0,
            });
        };
        let (rows, cols) = first.hankel.shape();
        let order = order.min(rows.saturating_sub(1)).min(cols);
        if order == 0 {
            return Err(MonitorError::NoSubspaceOrder);
        }
        let dof = (rows - order) * order;
        let q = 1 + first.regressors.len();
        if m <= dof + q {
            return Err(MonitorError::TooFewForSubspace {
                records: m,
                entries: dof,
            });
        }
        let mut h0 = DMatrix::<f64>::zeros(rows, cols);
        for r in records {
            h0 += &r.hankel;
        }
        h0 /= m as f64;
        // Left null space: the eigenvectors of H₀H₀ᵀ with the smallest eigenvalues; column
        // compression: those of H₀ᵀH₀ with the largest (the leading right singular vectors).
        let null = eigenvectors(&h0 * h0.transpose(), rows - order, false);
        let columns = eigenvectors(h0.transpose() * &h0, order, true);
        let z = DMatrix::from_columns(
            &records
                .iter()
                .map(|r| residual(&null, &columns, &r.hankel))
                .collect::<Vec<_>>(),
        );
        let x = DMatrix::from_fn(m, q, |i, k| {
            if k == 0 {
                1.0
            } else {
                records[i]
                    .regressors
                    .get(k - 1)
                    .copied()
                    .unwrap_or(f64::NAN)
            }
        });
        let scatter: Option<Vec<f64>> = records
            .iter()
            .map(|r| own_scatter(&null, &columns, r))
            .collect();
        let nu = (m - q) as f64;
        let (fit, scale_model) = fit_scaled(&z, &x, scatter.as_deref(), nu)?;
        let df = dof as f64;
        let f = FisherSnedecor::new(df, nu - df + 1.0).map_err(|_| MonitorError::Collinear)?;
        let nominal_threshold = f.inverse_cdf(1.0 - alpha) * df * nu / (nu - df + 1.0);
        let cholesky = (&fit.sums / nu).cholesky().ok_or(MonitorError::Collinear)?;
        let sums_cholesky = fit.sums.clone().cholesky().ok_or(MonitorError::Collinear)?;
        // Each training record's T² against the others (leave one out), on the records
        // scaled by their own noise (ẽᵢ = eᵢ/√cᵢ, x̃ᵢ = xᵢ/√cᵢ: ordinary least squares): with
        // g = ẽᵢᵀA⁻¹ẽᵢ (A = Σ ẽẽᵀ) and its leverage hᵢ, deleting the record leaves
        // A − ẽᵢẽᵢᵀ/(1 − hᵢ), its prediction error is ẽᵢ/(1 − hᵢ) of variance Σ/(1 − hᵢ),
        // so by Sherman–Morrison T²ᵢ = (ν − 1) g / ((1 − hᵢ) − g), as a new record's.
        let leave_one_out: Vec<f64> = (0..m)
            .map(|i| {
                let g =
                    mahalanobis(&sums_cholesky, fit.errors.column(i).into_owned()) / fit.scale[i];
                let h = fit.leverage(&x, i);
                (nu - 1.0) * g / ((1.0 - h) - g)
            })
            .collect();
        let law =
            crate::calibration::gamma_by_moments(&leave_one_out).ok_or(MonitorError::Collinear)?;
        let threshold = law.inverse_cdf(1.0 - alpha);
        let focus =
            crate::sensitivity::frequency_sensitivity(&h0, first.channels, order, &null, &columns)
                .and_then(|(j, frequencies)| Focus::train(&j, frequencies, &fit, &x, nu));
        Ok(SubspaceTest {
            null,
            columns,
            coefficients: fit.coefficients,
            gram_inverse: fit.gram_inverse,
            cholesky,
            scale_model,
            dof,
            training: m,
            threshold,
            nominal_threshold,
            alpha,
            leave_one_out,
            law,
            focus,
        })
    }

    /// Directions of the focused test (the reference's modes; 0: not focused).
    pub fn directions(&self) -> usize {
        self.focus.as_ref().map_or(0, |f| f.projector.nrows())
    }

    /// Each direction's pole frequency (cycles per sample), ascending (empty: not focused).
    pub fn pole_frequencies(&self) -> &[f64] {
        self.focus.as_ref().map_or(&[], |f| &f.frequencies)
    }

    /// The training records' leave-one-out standardized shifts, per mode then record (empty:
    /// not focused).
    pub fn shift_leave_one_out(&self) -> &[Vec<f64>] {
        self.focus.as_ref().map_or(&[], |f| &f.leave_one_out)
    }

    /// A record's estimated relative frequency change of each mode and its standardized
    /// value (`None` when not focused or without regressors).
    pub fn shifts(&self, record: &SubspaceRecord) -> Option<(Vec<f64>, Vec<f64>)> {
        self.assess(record).shifts
    }

    /// A record's T², scale and shifts, its residual and own scatter computed once.
    fn assess(&self, record: &SubspaceRecord) -> Assessed {
        let scale = self.scale_of(record);
        match self.error(record) {
            Some((e, leverage)) => Assessed {
                shifts: self.focus.as_ref().map(|f| f.shifts(&e, scale + leverage)),
                t2: mahalanobis(&self.cholesky, e) / (scale + leverage),
                scale,
            },
            None => Assessed {
                t2: f64::NAN,
                scale,
                shifts: None,
            },
        }
    }

    /// A record's residual from the regression's prediction and its leverage; `None`
    /// without finite regressors.
    fn error(&self, record: &SubspaceRecord) -> Option<(DVector<f64>, f64)> {
        let q = self.gram_inverse.nrows();
        let x = DVector::from_fn(q, |k, _| {
            if k == 0 {
                1.0
            } else {
                record.regressors.get(k - 1).copied().unwrap_or(f64::NAN)
            }
        });
        if x.iter().any(|v| !v.is_finite()) {
            return None;
        }
        let leverage = (x.transpose() * &self.gram_inverse * &x)[(0, 0)];
        let e = residual(&self.null, &self.columns, &record.hankel) - &self.coefficients * x;
        Some((e, leverage))
    }

    /// A record's T² (as in training): eᵀΣ⁻¹e / (c + x̃ᵀ(X̃ᵀC⁻¹X̃)⁻¹x̃), c its own noise's
    /// scale (1 without a scale model or without its parts).
    pub fn statistic(&self, record: &SubspaceRecord) -> f64 {
        self.assess(record).t2
    }

    /// The scale c of a record's residual covariance (1 without a scale model or without
    /// the record's parts).
    pub fn scale_of(&self, record: &SubspaceRecord) -> f64 {
        match (
            &self.scale_model,
            own_scatter(&self.null, &self.columns, record),
        ) {
            (Some(model), Some(v)) => model.scale(v),
            _ => 1.0,
        }
    }

    /// A record's T² as a standard normal score, Φ⁻¹(G(T²)) with G the fitted law: standard
    /// normal for undamaged records, larger when the structure changed (±8 at most).
    pub fn score(&self, t2: f64) -> f64 {
        Normal::standard()
            .inverse_cdf(self.law.cdf(t2))
            .clamp(-8.0, 8.0)
    }
}

/// What the test makes of one record.
struct Assessed {
    t2: f64,
    scale: f64,
    /// Each mode's estimated change and its standardized value (`None`: not focused, or
    /// no regressors).
    shifts: Option<(Vec<f64>, Vec<f64>)>,
}

impl Focus {
    /// θ̂ = L e of a residual `e` whose covariance is Σ times `scale` (its own scale plus its
    /// leverage), and each mode's standardized value.
    fn shifts(&self, e: &DVector<f64>, scale: f64) -> (Vec<f64>, Vec<f64>) {
        let theta = &self.projector * e;
        let scores = (0..theta.len())
            .map(|j| {
                let z = theta[j] / (self.covariance[(j, j)] * scale).sqrt();
                (z - self.center[j]) / self.spread[j]
            })
            .collect();
        (theta.iter().copied().collect(), scores)
    }

    /// The shifts' test on the sensitivity `j` (poles at `frequencies`), from the training fit
    /// (Σ = A/ν, A = Σ ẽẽᵀ = `fit.sums`). Each training record's standardized shift against
    /// the others: with w = ẽᵢ/√(1 − hᵢ), deleting it leaves A − wwᵀ and its prediction
    /// error ẽᵢ/(1 − hᵢ) of covariance Σ₋/(1 − hᵢ), Σ₋ = (A − wwᵀ)/(ν − 1), so that its θ̂ is
    /// Lw/√(1 − hᵢ) and mode j's standardized shift (Lw)ⱼ√(ν − 1)/√((LALᵀ)ⱼⱼ − (Lw)ⱼ²).
    /// `None` when JᵀJ is singular.
    fn train(
        j: &DMatrix<f64>,
        frequencies: Vec<f64>,
        fit: &ScaledFit,
        x: &DMatrix<f64>,
        nu: f64,
    ) -> Option<Focus> {
        let projector = (j.transpose() * j).try_inverse()? * j.transpose();
        let lal = &projector * &fit.sums * projector.transpose();
        let modes = j.ncols();
        let mut leave_one_out = vec![Vec::with_capacity(x.nrows()); modes];
        for i in 0..x.nrows() {
            let h = fit.leverage(x, i);
            let lw = &projector * fit.errors.column(i) / (fit.scale[i] * (1.0 - h)).sqrt();
            for (k, series) in leave_one_out.iter_mut().enumerate() {
                series.push(lw[k] * (nu - 1.0).sqrt() / (lal[(k, k)] - lw[k] * lw[k]).sqrt());
            }
        }
        let (mut center, mut spread) = (Vec::new(), Vec::new());
        for series in &mut leave_one_out {
            let v: Vec<f64> = series.iter().copied().filter(|v| v.is_finite()).collect();
            let n = v.len() as f64;
            let mean = v.iter().sum::<f64>() / n;
            let sd = (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
            if !(sd.is_finite() && sd > 0.0) {
                return None;
            }
            series.iter_mut().for_each(|z| *z = (*z - mean) / sd);
            center.push(mean);
            spread.push(sd);
        }
        Some(Focus {
            projector,
            covariance: lal / nu,
            frequencies,
            leave_one_out,
            center,
            spread,
        })
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

/// How a record's residual covariance scales with its own estimation noise: cᵢΣ, with
/// cᵢ = `intercept` + `slope` · vᵢ, vᵢ the record's own scatter per entry (the trace of its
/// residual's estimation covariance from its parts, over the entries), scaled so that the
/// training records' mean c is 1. The estimation noise of a record of low excitation, a
/// short or a noisy one is larger (T² of the project's confounded campaigns grew threefold
/// from its most to its least excited fifth), while a change moves every record's residual
/// alike: charted unscaled, the noisy records' T² widen the law a change must stand out of.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ScaleModel {
    /// The part of c every record has (the environment's unexplained part and the rest).
    pub intercept: f64,
    /// c per unit of the record's own scatter.
    pub slope: f64,
}

impl ScaleModel {
    /// The scale c of a record of scatter `v`.
    pub fn scale(&self, v: f64) -> f64 {
        self.intercept + self.slope * v
    }
}

/// A record's own scatter per entry of the residual: Σₚ ‖ζₚ − ζ̄‖² / (P(P − 1)) over its P
/// parts' residuals ζₚ, divided by the entries (the estimated variance of the mean of its
/// parts, which the whole record's residual nearly is); `None` with fewer than two parts.
fn own_scatter(
    null: &DMatrix<f64>,
    columns: &DMatrix<f64>,
    record: &SubspaceRecord,
) -> Option<f64> {
    let p = record.parts.len();
    if p < 2
        || record
            .parts
            .iter()
            .any(|h| h.shape() != record.hankel.shape())
    {
        return None;
    }
    let zs: Vec<DVector<f64>> = record
        .parts
        .iter()
        .map(|h| residual(null, columns, h))
        .collect();
    let mean = zs.iter().fold(DVector::zeros(zs[0].len()), |a, z| a + z) / p as f64;
    let sum: f64 = zs.iter().map(|z| (z - &mean).norm_squared()).sum();
    let v = sum / (p * (p - 1) * mean.len().max(1)) as f64;
    v.is_finite().then_some(v)
}

/// The residual's regression on the regressors, each record weighted by its scale.
struct ScaledFit {
    coefficients: DMatrix<f64>,
    /// (Σ xxᵀ/c)⁻¹.
    gram_inverse: DMatrix<f64>,
    /// The residuals e = z − Bx (unscaled), one per column.
    errors: DMatrix<f64>,
    /// Σ eeᵀ/c.
    sums: DMatrix<f64>,
    /// Each record's c.
    scale: Vec<f64>,
}

impl ScaledFit {
    /// Training record i's leverage on the records scaled by their own noise:
    /// x̃ᵢᵀ(X̃ᵀX̃)⁻¹x̃ᵢ = xᵢᵀ(Σ xxᵀ/c)⁻¹xᵢ / cᵢ (`x`: the regressors, one record per row).
    fn leverage(&self, x: &DMatrix<f64>, i: usize) -> f64 {
        let xi = x.row(i).transpose();
        (xi.transpose() * &self.gram_inverse * &xi)[(0, 0)] / self.scale[i]
    }
}

/// The regression ζ = B[1; x] + e by weighted least squares, each record's weight 1/cᵢ; with
/// the records' own scatter `scatter`, cᵢ = a + b·vᵢ found by alternating: the regression with
/// the current c, then a and b by least squares of each record's gᵢ = eᵢᵀΣ⁻¹eᵢ/(d(1 − hᵢ))
/// (whose mean is cᵢ) on vᵢ, a ≥ 0; no scale model (c = 1) when b is not positive.
fn fit_scaled(
    z: &DMatrix<f64>,
    x: &DMatrix<f64>,
    scatter: Option<&[f64]>,
    nu: f64,
) -> Result<(ScaledFit, Option<ScaleModel>), MonitorError> {
    let m = x.nrows();
    let mut scale = vec![1.0; m];
    let mut model = None;
    let rounds = if scatter.is_some() { 6 } else { 1 };
    for round in 0..rounds {
        let fit = weighted_fit(z, x, &scale)?;
        let Some(v) = scatter.filter(|_| round + 1 < rounds) else {
            return Ok((fit, model));
        };
        let chol = (&fit.sums / nu).cholesky().ok_or(MonitorError::Collinear)?;
        let d = z.nrows() as f64;
        let g: Vec<f64> = (0..m)
            .map(|i| {
                let h = fit.leverage(x, i);
                mahalanobis(&chol, fit.errors.column(i).into_owned()) / (d * (1.0 - h).max(0.05))
            })
            .collect();
        let Some(found) = line_through(v, &g) else {
            return Ok((weighted_fit(z, x, &vec![1.0; m])?, None));
        };
        let mean = v.iter().map(|&vi| found.scale(vi)).sum::<f64>() / m as f64;
        let found = ScaleModel {
            intercept: found.intercept / mean,
            slope: found.slope / mean,
        };
        scale = v.iter().map(|&vi| found.scale(vi)).collect();
        model = Some(found);
    }
    Ok((weighted_fit(z, x, &scale)?, model))
}

/// g ≈ a + b·v by least squares, a ≥ 0 (through the origin when the free line's a < 0);
/// `None` unless b > 0.
fn line_through(v: &[f64], g: &[f64]) -> Option<ScaleModel> {
    let n = v.len() as f64;
    let (mv, mg) = (v.iter().sum::<f64>() / n, g.iter().sum::<f64>() / n);
    let svv: f64 = v.iter().map(|a| (a - mv).powi(2)).sum();
    let svg: f64 = v.iter().zip(g).map(|(a, b)| (a - mv) * (b - mg)).sum();
    let slope = svg / svv;
    let (intercept, slope) = if mg - slope * mv >= 0.0 {
        (mg - slope * mv, slope)
    } else {
        let through =
            v.iter().zip(g).map(|(a, b)| a * b).sum::<f64>() / v.iter().map(|a| a * a).sum::<f64>();
        (0.0, through)
    };
    (slope.is_finite() && slope > 0.0 && intercept.is_finite())
        .then_some(ScaleModel { intercept, slope })
}

/// Weighted least squares of the residuals `z` (one record per column) on `x` (one record
/// per row), record i weighted by 1/`scale`ᵢ.
fn weighted_fit(
    z: &DMatrix<f64>,
    x: &DMatrix<f64>,
    scale: &[f64],
) -> Result<ScaledFit, MonitorError> {
    let weights = DVector::from_iterator(scale.len(), scale.iter().map(|c| 1.0 / c));
    let xw = DMatrix::from_fn(x.nrows(), x.ncols(), |i, k| x[(i, k)] * weights[i]);
    let gram_inverse = (x.transpose() * &xw)
        .try_inverse()
        .filter(|g| g.iter().all(|v| v.is_finite()))
        .ok_or(MonitorError::Collinear)?;
    let coefficients = z * &xw * &gram_inverse;
    let errors = z - &coefficients * x.transpose();
    let ew = DMatrix::from_fn(errors.nrows(), errors.ncols(), |a, i| {
        errors[(a, i)] * weights[i]
    });
    let sums = &ew * errors.transpose();
    Ok(ScaledFit {
        coefficients,
        gram_inverse,
        errors,
        sums,
        scale: scale.to_vec(),
    })
}

/// The `count` eigenvectors of the symmetric `m` with the largest eigenvalues (`largest`),
/// or the smallest, as columns.
pub(crate) fn eigenvectors(m: DMatrix<f64>, count: usize, largest: bool) -> DMatrix<f64> {
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
    /// T²'s score (standard normal when undamaged), charted when `directions` is 0.
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
    /// How a record's residual covariance scales with its own estimation noise
    /// ([`ScaleModel`]; `None`: records without parts, or no dependence found).
    #[cfg_attr(feature = "serde", serde(default))]
    pub scale_model: Option<ScaleModel>,
    /// Each record's scale c (1 without a scale model; NaN without a Hankel matrix).
    #[cfg_attr(feature = "serde", serde(default))]
    pub scale: Vec<f64>,
    /// Modes whose frequency changes are charted (the reference's, in ascending frequency;
    /// 0: none, the full T²'s score charted instead).
    #[cfg_attr(feature = "serde", serde(default))]
    pub directions: usize,
    /// Each direction's pole frequency (cycles per sample).
    #[cfg_attr(feature = "serde", serde(default))]
    pub pole_frequencies: Vec<f64>,
    /// Each record's estimated relative frequency change of each mode (empty for a record
    /// without a Hankel matrix or regressors, and when not focused).
    #[cfg_attr(feature = "serde", serde(default))]
    pub shifts: Vec<Vec<f64>>,
    /// The same standardized (standard normal when undamaged), charted mode by mode.
    #[cfg_attr(feature = "serde", serde(default))]
    pub shift_scores: Vec<Vec<f64>>,
    /// Each mode's chart limit (calibrated on its training records' leave-one-out values,
    /// two-sided, when asked).
    #[cfg_attr(feature = "serde", serde(default))]
    pub mode_limits: Vec<f64>,
    /// Each mode's calibration (`None`: not asked, or too few).
    #[cfg_attr(feature = "serde", serde(default))]
    pub mode_calibrations: Vec<Option<Calibration>>,
    /// The alarms of the modes' charts.
    #[cfg_attr(feature = "serde", serde(default))]
    pub mode_alarms: Vec<SubspaceAlarm>,
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

/// A record as the subspace test takes it ([`Correlations::record`]).
#[derive(Debug, Clone, PartialEq)]
pub struct SubspaceRecord {
    /// Its block Hankel matrix, divided by its Frobenius norm ([`hankel`]).
    pub hankel: DMatrix<f64>,
    /// Its channels (the Hankel matrix's rows per block row).
    pub channels: usize,
    /// Its parts' Hankel matrices on the whole's scale (empty: its own noise unknown).
    pub parts: Vec<DMatrix<f64>>,
    /// Its environmental regressors (empty without covariates).
    pub regressors: Vec<f64>,
}

impl SubspaceRecord {
    /// A record of Hankel matrix `hankel` (from [`hankel`], of `channels` channels) and
    /// environmental `regressors`, its own noise unknown.
    pub fn new(hankel: DMatrix<f64>, channels: usize, regressors: Vec<f64>) -> SubspaceRecord {
        SubspaceRecord {
            hankel,
            channels,
            parts: Vec::new(),
            regressors,
        }
    }
}

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
    let train: Vec<SubspaceRecord> = records
        .iter()
        .take(training)
        .flatten()
        .filter(|r| r.regressors.iter().all(|v| v.is_finite()))
        .cloned()
        .collect();
    let test = SubspaceTest::train(&train, order, alpha)?;
    let assessed: Vec<Option<Assessed>> = records
        .iter()
        .map(|r| r.as_ref().map(|r| test.assess(r)))
        .collect();
    let t2: Vec<f64> = assessed
        .iter()
        .map(|a| a.as_ref().map_or(f64::NAN, |a| a.t2))
        .collect();
    let scale: Vec<f64> = assessed
        .iter()
        .map(|a| a.as_ref().map_or(f64::NAN, |a| a.scale))
        .collect();
    let directions = test.directions();
    let score: Vec<f64> = t2
        .iter()
        .map(|&t| if t.is_nan() { t } else { test.score(t) })
        .collect();
    let modes = if directions > 0 {
        Some(mode_charts(&test, assessed, training, chart, calibrate))
    } else {
        None
    };
    let calibration = if calibrate && modes.is_none() {
        let trained: Vec<f64> = test.leave_one_out.iter().map(|&t| test.score(t)).collect();
        crate::calibration::calibrate(&trained, chart, Sides::Up)
    } else {
        None
    };
    let used = calibration.as_ref().map_or(*chart, |c| c.chart(chart));
    let later: Vec<f64> = score.iter().skip(training).copied().collect();
    let alarms: Vec<usize> = match &modes {
        Some(m) => {
            let mut at: Vec<usize> = m.alarms.iter().map(|a| a.record).collect();
            at.sort_unstable();
            at.dedup();
            at
        }
        None => used
            .alarms(&later)
            .into_iter()
            .filter(|a| a.side == Side::Up)
            .map(|a| a.index + training)
            .collect(),
    };
    let modes = modes.unwrap_or_default();
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
        scale_model: test.scale_model,
        scale,
        directions,
        pole_frequencies: test.pole_frequencies().to_vec(),
        shifts: modes.shifts,
        shift_scores: modes.scores,
        mode_limits: modes.limits,
        mode_calibrations: modes.calibrations,
        mode_alarms: modes.alarms,
        threshold: test.threshold,
        nominal_threshold: test.nominal_threshold,
        alpha,
        calibration,
        limit: used.h,
        above_threshold,
        alarms,
    })
}

/// The charts of the modes' frequency changes over a campaign.
#[derive(Default)]
struct ModeCharts {
    shifts: Vec<Vec<f64>>,
    scores: Vec<Vec<f64>>,
    limits: Vec<f64>,
    calibrations: Vec<Option<Calibration>>,
    alarms: Vec<SubspaceAlarm>,
}

/// Each mode's standardized frequency change charted two-sided after `training`, its limit
/// calibrated on the training records' leave-one-out values when `calibrate`.
fn mode_charts(
    test: &SubspaceTest,
    assessed: Vec<Option<Assessed>>,
    training: usize,
    chart: &Cusum,
    calibrate: bool,
) -> ModeCharts {
    let (shifts, scores): (Vec<Vec<f64>>, Vec<Vec<f64>>) = assessed
        .into_iter()
        .map(|a| a.and_then(|a| a.shifts).unwrap_or_default())
        .unzip();
    let mut out = ModeCharts {
        shifts,
        scores,
        ..ModeCharts::default()
    };
    for (mode, trained) in test.shift_leave_one_out().iter().enumerate() {
        let calibration = if calibrate {
            crate::calibration::calibrate(trained, chart, Sides::Both)
        } else {
            None
        };
        let used = calibration.as_ref().map_or(*chart, |c| c.chart(chart));
        let later: Vec<f64> = out
            .scores
            .iter()
            .skip(training)
            .map(|s| s.get(mode).copied().unwrap_or(f64::NAN))
            .collect();
        for a in used.alarms(&later) {
            let record = a.index + training;
            out.alarms.push(SubspaceAlarm {
                record,
                mode,
                side: a.side,
                shift: out.shifts[record].get(mode).copied().unwrap_or(f64::NAN),
            });
        }
        out.limits.push(used.h);
        out.calibrations.push(calibration);
    }
    out.alarms.sort_by_key(|a| (a.record, a.mode));
    out
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
        let with = |h: DMatrix<f64>| Some(SubspaceRecord::new(h, 4, Vec::new()));
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
    /// 300 s at 20 Hz of two modes (1.3 Hz and `f2`, 2 % damping) on 4 channels, their
    /// sensors' noise `noise` of the response.
    fn two_modes(f2: f64, noise: f64, seed: u64) -> Vec<Vec<f64>> {
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
        ModalRecord::new(20.0, &[(1.3, 0.02), (f2, 0.02)])
            .with_gains(gains)
            .with_noise(noise)
            .generate(6000, seed)
    }

    #[test]
    #[ignore]
    fn block_rows_sensitivity_study() {
        let rec = |f2: f64, seed: u64, blocks: usize| -> DMatrix<f64> {
            let y = two_modes(f2, 0.05, seed);
            let views: Vec<&[f64]> = y.iter().map(|c| c.as_slice()).collect();
            hankel(&views, blocks)
        };
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        for blocks in [2usize, 3, 4, 6] {
            let train: Vec<SubspaceRecord> = (0..300)
                .map(|i| SubspaceRecord::new(rec(3.4, 4_710_000 + i, blocks), 4, Vec::new()))
                .collect();
            let t = SubspaceTest::train(&train, 4, 0.01).unwrap();
            let stat = |f2: f64, seed: u64| -> Vec<f64> {
                (0..80)
                    .map(|i| {
                        t.statistic(&SubspaceRecord::new(
                            rec(f2, seed + i, blocks),
                            4,
                            Vec::new(),
                        ))
                    })
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

    /// Two-mode records (4 channels, 3 block rows, 20 Hz, 300 s) whose sensors' noise
    /// varies from record to record by a factor of 8: the noisier records' T² is far larger,
    /// and the scale model found from the records' own parts (a positive slope) brings the
    /// noisy and the quiet halves of 200 fresh records to within a factor of 2 in mean T²
    /// (measured: unscaled 12.6×, scaled 1.5×; what is left is the noise's scatter estimate
    /// from four parts, which dilutes the slope, and the noise's own shape); and the focused
    /// estimate of each mode's frequency change, whose sensitivity comes from the reference
    /// alone, finds a 1 % loss of the second mode: about −1 % estimated, its standardized
    /// value moved by more than one standard deviation downwards.
    #[test]
    fn own_noise_scales_the_residual_and_the_focus_finds_a_frequency() {
        let rec = |f2: f64, noise: f64, seed: u64| -> SubspaceRecord {
            let y = two_modes(f2, noise, seed);
            let views: Vec<&[f64]> = y.iter().map(|c| c.as_slice()).collect();
            Correlations::of(&views, 5)
                .record(3, Vec::new())
                .expect("5 lags reach 3 block rows")
        };
        let noise = |i: u64| 0.05 * 8f64.powf((i % 10) as f64 / 9.0);
        let train: Vec<SubspaceRecord> = (0..200)
            .map(|i| rec(3.4, noise(i), 4_840_000 + i))
            .collect();
        assert!(train.iter().all(|r| r.parts.len() == PARTS));
        let t = SubspaceTest::train(&train, 4, 0.01).unwrap();
        let model = t.scale_model.expect("a scale model");
        assert!(model.slope > 0.0, "{model:?}");
        assert_eq!(t.directions(), 2);
        let fresh: Vec<(f64, SubspaceRecord)> = (0..200)
            .map(|i| (noise(i + 3), rec(3.4, noise(i + 3), 4_850_000 + i)))
            .collect();
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        let halves = |f: &dyn Fn(&SubspaceRecord) -> f64| {
            let (mut quiet, mut noisy) = (Vec::new(), Vec::new());
            for (n, r) in &fresh {
                if *n < 0.05 * 8f64.sqrt() {
                    &mut quiet
                } else {
                    &mut noisy
                }
                .push(f(r));
            }
            mean(&noisy) / mean(&quiet)
        };
        let scaled = halves(&|r| t.statistic(r));
        let unscaled = halves(&|r| t.statistic(r) * t.scale_of(r));
        eprintln!("noisy/quiet mean T²: scaled {scaled:.2}, unscaled {unscaled:.2}; {model:?}");
        assert!(unscaled > 4.0, "{unscaled}");
        assert!(scaled < 2.0, "{scaled}");
        // Mode 2's estimated relative frequency change and its standardized value, mean
        // over 60 records.
        let shift = |f2: f64, seed: u64| -> (f64, f64) {
            let (theta, z): (Vec<f64>, Vec<f64>) = (0..60)
                .map(|i| {
                    let (theta, z) = t.shifts(&rec(f2, noise(i), seed + i)).expect("focused");
                    (theta[1], z[1])
                })
                .unzip();
            (mean(&theta), mean(&z))
        };
        let (before, after) = (shift(3.4, 4_860_000), shift(3.4 * 0.99, 4_870_000));
        eprintln!("mode 2's estimated change and score: undamaged {before:?}, 1 % lower {after:?}");
        assert!(before.1.abs() < 0.5, "{before:?}");
        // More than the CUSUM's reference value k = 0.5 plus half a standard deviation, and
        // downwards: it accumulates at least 0.5 per record on the lower side.
        assert!(after.1 < -1.0, "{after:?}");
        // The estimate is of the relative change: −1 % within a fifth (first order in the
        // change; its noise over 60 records about 0.1 %).
        assert!(
            (after.0 - before.0 + 0.01).abs() < 0.002,
            "{after:?} {before:?}"
        );
    }

    #[test]
    fn too_few_training_records_are_said() {
        let h: Vec<SubspaceRecord> = (0..5)
            .map(|i| SubspaceRecord::new(record(3.4, 1.0, 4_640_000 + i), 4, Vec::new()))
            .collect();
        let e = SubspaceTest::train(&h, 4, 0.01).unwrap_err();
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
        let e = SubspaceTest::train(&h, 0, 0.01).unwrap_err();
        assert!(matches!(e, MonitorError::NoSubspaceOrder), "{e}");
    }
}
