//! The environmental model a mode's baseline regresses on, chosen on the training records:
//! each covariate through a first-order lag (a structure's temperature follows the air's as
//! a lumped heat capacity does, $\tau_j\dot{\tilde x}_j + \tilde x_j = x_j$) and, where
//! the data call for it, with its slope changing below a breakpoint (frozen soil and asphalt
//! stiffen a bridge steeply below 0 °C):
//! $$f = \beta_0 + \sum_j \big(\beta_j\,\tilde x_j(t) + \gamma_j \max(0,\ c_j - \tilde x_j(t))\big),$$
//! or, for a response that bends smoothly rather than at a point, $\gamma_j(\tilde x_j - m_j)^2$
//! about the training mean $m_j$ in place of the hinge.
//! Each covariate's time constant $\tau_j$ (whole hours up to [`MAX_LAG_HOURS`], and no more
//! than a quarter of the training span) and shape (linear; a breakpoint $c_j$ at one of the
//! training values' deciles; or the smooth curvature) are chosen by BIC, $n\ln(\mathrm{RSS}/n) + p\ln n$, counting a lag and
//! a breakpoint or a curvature as a parameter each, so that the linear model stands unless the data pay for
//! more. The lag runs over the covariate's series (every record that has it, in time order),
//! exactly for a covariate linear between records:
//! $\tilde x_i = E\tilde x_{i-1} + (1 - E)x_{i-1} + (x_i - x_{i-1})\big(1 - \tfrac{\tau}{\Delta}(1 - E)\big)$,
//! $E = e^{-\Delta/\tau}$, $\Delta = t_i - t_{i-1}$, from $\tilde x_0 = x_0$.

use nalgebra::{DMatrix, DVector};

/// Longest lag searched (hours).
pub const MAX_LAG_HOURS: usize = 12;

/// One covariate's term of the model.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Term {
    /// Which covariate (0-based, in the covariates' order).
    pub covariate: usize,
    /// Its first-order lag's time constant (s; 0: the covariate as it is).
    pub lag_s: f64,
    /// The breakpoint below which its slope changes, if any (the covariate's unit).
    pub breakpoint: Option<f64>,
    /// A smooth curvature instead: the square of the (lagged) covariate's distance from this
    /// centre (its training mean) as a further regressor, if any.
    #[cfg_attr(feature = "serde", serde(default))]
    pub quadratic_about: Option<f64>,
}

/// The shape of a term beyond its slope.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Shape {
    Linear,
    Hinge(f64),
    Quadratic(f64),
}

/// The environmental model of one mode, and what it gained over the plain linear one.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Environment {
    /// One term per covariate.
    pub terms: Vec<Term>,
    /// The chosen model's BIC minus the linear, unlagged model's (≤ 0).
    pub bic_gain: f64,
    /// Each regressor's training range (min, max), in [`Environment::features`]' order: a
    /// record outside it is extrapolated.
    pub ranges: Vec<(f64, f64)>,
}

/// Every record's covariates in time order, for lagged values.
pub struct Series {
    /// (time, value) of each covariate, finite values only, in time order.
    by_covariate: Vec<Vec<(f64, f64)>>,
    /// Each (covariate, time constant's bits) lagged series made so far.
    lagged: std::sync::Mutex<std::collections::HashMap<(usize, u64), SharedSeries>>,
}

/// A lagged series, shared between the modes that read it.
type SharedSeries = std::sync::Arc<Vec<(f64, f64)>>;

impl Series {
    /// The series of `records` ((time, covariates) each, any order).
    pub fn new(records: &[(f64, Vec<f64>)]) -> Series {
        let q = records.iter().map(|r| r.1.len()).max().unwrap_or(0);
        let by_covariate = (0..q)
            .map(|j| {
                let mut s: Vec<(f64, f64)> = records
                    .iter()
                    .filter_map(|(t, x)| {
                        let v = *x.get(j)?;
                        (t.is_finite() && v.is_finite()).then_some((*t, v))
                    })
                    .collect();
                s.sort_by(|a, b| a.0.total_cmp(&b.0));
                s
            })
            .collect();
        Series {
            by_covariate,
            lagged: Default::default(),
        }
    }

    /// Covariate `j` through a first-order lag of time constant `tau` (s), at time `t`
    /// (interpolated between records; NaN without values).
    fn lagged_at(&self, j: usize, tau: f64, t: f64) -> f64 {
        let Some(raw) = self.by_covariate.get(j).filter(|s| !s.is_empty()) else {
            return f64::NAN;
        };
        let s = {
            let Ok(mut cache) = self.lagged.lock() else {
                return f64::NAN;
            };
            cache
                .entry((j, tau.to_bits()))
                .or_insert_with(|| std::sync::Arc::new(first_order_lag(raw, tau)))
                .clone()
        };
        let i = s.partition_point(|p| p.0 <= t);
        match i {
            0 => s[0].1,
            _ if i == s.len() => s[i - 1].1,
            _ => {
                let (a, b) = (s[i - 1], s[i]);
                a.1 + (b.1 - a.1) * (t - a.0) / (b.0 - a.0)
            }
        }
    }
}

impl Term {
    /// This term's covariate at time `t` (the record's own covariates `x`), through its lag.
    fn value(&self, series: &Series, t: f64, x: &[f64]) -> f64 {
        if self.lag_s == 0.0 {
            x.get(self.covariate).copied().unwrap_or(f64::NAN)
        } else {
            series.lagged_at(self.covariate, self.lag_s, t)
        }
    }
}

impl Environment {
    /// The plain model: every covariate unlagged and linear.
    pub fn linear(covariates: usize) -> Environment {
        Environment {
            terms: (0..covariates)
                .map(|covariate| Term {
                    covariate,
                    lag_s: 0.0,
                    breakpoint: None,
                    quadratic_about: None,
                })
                .collect(),
            bic_gain: 0.0,
            ranges: Vec::new(),
        }
    }

    /// The regressors of a record at time `t` with covariates `x`: per term its (lagged)
    /// value, then its hinge when it has a breakpoint.
    pub fn features(&self, series: &Series, t: f64, x: &[f64]) -> Vec<f64> {
        let mut v = Vec::with_capacity(2 * self.terms.len());
        for term in &self.terms {
            let value = term.value(series, t, x);
            v.push(value);
            if let Some(c) = term.breakpoint {
                v.push((c - value).max(0.0));
            }
            if let Some(m) = term.quadratic_about {
                v.push((value - m) * (value - m));
            }
        }
        v
    }

    /// Whether the regressors `features` lie outside the training ranges.
    pub fn extrapolated(&self, features: &[f64]) -> bool {
        features
            .iter()
            .zip(&self.ranges)
            .any(|(v, (lo, hi))| *v < *lo || *v > *hi)
    }

    /// Choose the model on the training records `train` ((time, covariates, frequency)).
    pub fn choose(series: &Series, train: &[(f64, Vec<f64>, f64)]) -> Environment {
        let q = train.first().map_or(0, |r| r.1.len());
        let linear = Environment::linear(q);
        let base_bic = bic(&linear, series, train);
        let span = train.iter().map(|r| r.0).fold(f64::NEG_INFINITY, f64::max)
            - train.iter().map(|r| r.0).fold(f64::INFINITY, f64::min);
        let lags: Vec<f64> = (0..=MAX_LAG_HOURS)
            .map(|h| 3600.0 * h as f64)
            .filter(|l| *l == 0.0 || *l <= span / 4.0)
            .collect();
        // One covariate at a time, the others as chosen so far.
        let mut best = (linear, base_bic);
        for j in 0..q {
            for &lag in &lags {
                let term = |shape| Term {
                    covariate: j,
                    lag_s: lag,
                    breakpoint: match shape {
                        Shape::Hinge(c) => Some(c),
                        _ => None,
                    },
                    quadratic_about: match shape {
                        Shape::Quadratic(m) => Some(m),
                        _ => None,
                    },
                };
                let values: Vec<f64> = train
                    .iter()
                    .map(|r| term(Shape::Linear).value(series, r.0, &r.1))
                    .collect();
                let mut options = vec![Shape::Linear];
                options.extend(deciles(&values).into_iter().map(Shape::Hinge));
                let finite: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
                if !finite.is_empty() {
                    options.push(Shape::Quadratic(
                        finite.iter().sum::<f64>() / finite.len() as f64,
                    ));
                }
                for shape in options {
                    let mut e = best.0.clone();
                    e.terms[j] = term(shape);
                    let extra = usize::from(lag > 0.0) + usize::from(shape != Shape::Linear);
                    let b = bic(&e, series, train) + extra as f64 * (train.len() as f64).ln();
                    if b < best.1 {
                        best = (e, b);
                    }
                }
            }
        }
        let (mut e, b) = best;
        e.bic_gain = b - base_bic;
        let rows: Vec<Vec<f64>> = train
            .iter()
            .map(|r| e.features(series, r.0, &r.1))
            .collect();
        let width = rows.first().map_or(0, Vec::len);
        e.ranges = (0..width)
            .map(|k| {
                rows.iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), r| {
                        (lo.min(r[k]), hi.max(r[k]))
                    })
            })
            .collect();
        e
    }
}

/// `s` ((time, value), in time order) through a first-order lag of time constant `tau`,
/// exact for values linear between the points ([module doc](self)).
fn first_order_lag(s: &[(f64, f64)], tau: f64) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(s.len());
    let mut y = s.first().map_or(f64::NAN, |p| p.1);
    for (i, &(t, x)) in s.iter().enumerate() {
        if i > 0 {
            let (t0, x0) = s[i - 1];
            let d = t - t0;
            if d > 0.0 {
                let e = (-d / tau).exp();
                y = e * y + (1.0 - e) * x0 + (x - x0) * (1.0 - tau / d * (1.0 - e));
            } else {
                y = x;
            }
        }
        out.push((t, y));
    }
    out
}

/// The 10 %, 20 %, …, 90 % points of `v`.
fn deciles(v: &[f64]) -> Vec<f64> {
    let mut s: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if s.len() < 10 {
        return Vec::new();
    }
    s.sort_by(f64::total_cmp);
    (1..10).map(|k| s[k * (s.len() - 1) / 10]).collect()
}

/// BIC of the least-squares fit of the frequencies on `e`'s regressors (∞ when singular).
fn bic(e: &Environment, series: &Series, train: &[(f64, Vec<f64>, f64)]) -> f64 {
    let n = train.len();
    let rows: Vec<Vec<f64>> = train
        .iter()
        .map(|r| e.features(series, r.0, &r.1))
        .collect();
    let p = 1 + rows.first().map_or(0, Vec::len);
    if n <= p || rows.iter().flatten().any(|v| !v.is_finite()) {
        return f64::INFINITY;
    }
    let design = DMatrix::from_fn(n, p, |i, k| if k == 0 { 1.0 } else { rows[i][k - 1] });
    let y = DVector::from_iterator(n, train.iter().map(|r| r.2));
    let Some(beta) = design.clone().svd(true, true).solve(&y, 1e-12).ok() else {
        return f64::INFINITY;
    };
    let rss = (&y - &design * beta).norm_squared().max(f64::MIN_POSITIVE);
    n as f64 * (rss / n as f64).ln() + p as f64 * (n as f64).ln()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    /// Air temperature with a daily cycle and a cold spell below 0 °C; the structure's
    /// temperature follows it through a first-order lag of 4 h, made here by an Euler
    /// integration at one minute (not the module's exact step); the frequency falls
    /// 4 mHz/°C above 0 °C and rises 40 mHz/°C below (frost). The model chosen on 14 days of
    /// hourly records has the time constant within an hour, a breakpoint within 1.5 °C of 0
    /// and beats the linear model; on a record with no effect but a linear one, the linear
    /// model stands.
    #[test]
    fn finds_a_lag_and_a_frost_breakpoint() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(5);
        let noise = Normal::new(0.0, 0.001).unwrap();
        let air = |t: f64| {
            let day = t / 86400.0;
            4.0 + 6.0 * (2.0 * std::f64::consts::PI * day).sin()
                - 8.0 * (-(day - 7.0).powi(2) / 4.0).exp()
        };
        let records: Vec<(f64, Vec<f64>)> = (0..336)
            .map(|h| (3600.0 * h as f64, vec![air(3600.0 * h as f64)]))
            .collect();
        let series = Series::new(&records);
        // The structure's temperature each hour, by Euler steps of one minute.
        let mut structure = Vec::with_capacity(336);
        let mut s = air(0.0);
        for h in 0..336 {
            structure.push(s);
            for m in 0..60 {
                let t = 3600.0 * h as f64 + 60.0 * m as f64;
                s += 60.0 / (4.0 * 3600.0) * (air(t) - s);
            }
        }
        let frost = |s: f64| 2.0 - 0.004 * s + 0.04 * (0.0 - s).max(0.0);
        let train: Vec<(f64, Vec<f64>, f64)> = records
            .iter()
            .zip(&structure)
            .map(|((t, x), s)| (*t, x.clone(), frost(*s) + noise.sample(&mut rng)))
            .collect();
        let e = Environment::choose(&series, &train);
        let t = e.terms[0];
        assert!((t.lag_s - 4.0 * 3600.0).abs() <= 3600.0, "{e:?}");
        assert!(t.breakpoint.is_some_and(|c| c.abs() < 1.5), "{e:?}");
        assert!(e.bic_gain < -50.0, "{e:?}");
        let plain: Vec<(f64, Vec<f64>, f64)> = records
            .iter()
            .map(|(t, x)| (*t, x.clone(), 2.0 - 0.004 * x[0] + noise.sample(&mut rng)))
            .collect();
        let e = Environment::choose(&series, &plain);
        assert_eq!(e.terms, Environment::linear(1).terms, "{e:?}");
    }

    /// A frequency that bends smoothly with the temperature (a parabola, no lag) takes the
    /// curvature, centred on the training mean, not a breakpoint, and beats the linear
    /// model; the frost case above keeps its breakpoint.
    #[test]
    fn a_smooth_bend_takes_the_curvature() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(6);
        let noise = Normal::new(0.0, 0.001).unwrap();
        let records: Vec<(f64, Vec<f64>)> = (0..336)
            .map(|h| {
                let day = h as f64 / 24.0;
                let x = 10.0 + 8.0 * (2.0 * std::f64::consts::PI * day / 5.0).sin();
                (3600.0 * h as f64, vec![x])
            })
            .collect();
        let series = Series::new(&records);
        let train: Vec<(f64, Vec<f64>, f64)> = records
            .iter()
            .map(|(t, x)| {
                let f = 2.0 - 0.004 * x[0] + 0.0004 * (x[0] - 10.0).powi(2);
                (*t, x.clone(), f + noise.sample(&mut rng))
            })
            .collect();
        let e = Environment::choose(&series, &train);
        let t = e.terms[0];
        assert!(
            t.breakpoint.is_none() && t.quadratic_about.is_some_and(|m| (m - 10.0).abs() < 0.5),
            "{e:?}"
        );
        assert!(t.lag_s == 0.0 && e.bic_gain < -50.0, "{e:?}");
    }
}
