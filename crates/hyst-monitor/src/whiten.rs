//! A slow effect the covariates leave unexplained, told from the white estimation noise and
//! removed before the residuals are charted (see the crate's documentation).
//!
//! The baseline's standardized residuals are standard normal when nothing changes, but not
//! independent of each other when an effect the covariates do not explain wanders slowly
//! (moisture, the structure's temperature lagging the air's, an unmeasured load): then a
//! CUSUM sums runs of like-signed residuals and alarms far more often than its run length
//! says. Each mode's residuals r_t = f_t − f̂(x_t) are modelled as
//!
//! $$ r_t = \eta_t + e_t, \qquad \eta_t = \varphi\,\eta_{t-1} + u_t, \qquad
//! e_t \sim N(0,\ n_t + w), \quad u_t \sim N\big(0,\ (1-\varphi^2)\,\lambda\big), $$
//!
//! a latent first-order autoregression η over the records (stationary variance λ) under white
//! noise whose variance n_t is known record by record (the estimate's squared standard error
//! plus the baseline's own variance at its covariates) up to w, what else is unexplained. φ,
//! λ and w are fitted over the training records by the Kalman filter's likelihood (φ on a
//! grid, λ and w by golden-section search); BIC keeps the latent effect only when it lowers
//! −2 ln L by more than 2 ln n, its two parameters' penalty, over white residuals. Then the
//! filter runs on through the later records and the chart is given its standardized
//! innovations v_t/√F_t, v_t = r_t − φ η̂_{t−1}, F_t their variance: independent and standard
//! normal when the model holds. A record missing the mode is a gap the filter predicts
//! across; an innovation beyond 5 standard deviations is charted but not let move the
//! filter's estimate (an outlier would otherwise pull it, and the records after it would
//! look off the other way). A lasting change then enters the innovations fully at first and less as the
//! filter takes it for the slow effect: a change is slower to tell from a wandering
//! environment, as it must be.

/// A mode's slow unexplained effect, fitted over the training records.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ResidualModel {
    /// φ, the effect's correlation from one record to the next.
    pub persistence: f64,
    /// λ, its stationary variance (Hz²).
    pub latent_var: f64,
    /// w, the white variance unexplained beyond the standard errors (Hz²).
    pub white_var: f64,
    /// Training residuals the fit used.
    pub records: usize,
    /// How much −2 ln L fell against white residuals (kept when above 2 ln n).
    pub deviance_drop: f64,
    /// The share of a lasting change that still reaches the chart once the filter has
    /// settled on it, (1 − φ)/(1 − φ(1 − K)) with K the filter's steady gain at the training
    /// records' mean variance: the rest is taken for the slow effect. A change enters whole
    /// at first, so a large one is still caught at once; one whose settled share falls below
    /// the chart's reference value (half a standard deviation) may never be.
    pub lasting_change_share: f64,
}

/// Innovations beyond this many standard deviations (a chance of 6·10⁻⁷ under the model)
/// are outliers: charted, but not let move the filter's estimate of the effect.
const GATE: f64 = 5.0;

/// Fewest training residuals for a fit.
const FEWEST: usize = 50;

/// φ tried: 1 − 2^{−k/2}, k = 1 … 20 (0.29 to 0.999: correlation times from under one
/// record to about a thousand).
fn persistence_grid() -> impl Iterator<Item = f64> {
    (1..=20).map(|k| 1.0 - 2f64.powf(-(k as f64) / 2.0))
}

/// The Kalman filter's state: the effect's estimate and its variance.
type State = (f64, f64);

impl ResidualModel {
    /// Fit the model to the training residuals `r` (Hz, in time order, NaN in a gap) with
    /// known variances `n` (Hz²); `None` when BIC prefers white residuals, or with fewer
    /// than 50 residuals.
    pub fn fit(r: &[f64], n: &[f64]) -> Option<ResidualModel> {
        let count = r.iter().filter(|v| v.is_finite()).count();
        if count < FEWEST {
            return None;
        }
        let scale = r
            .iter()
            .filter(|v| v.is_finite())
            .map(|v| v * v)
            .sum::<f64>()
            / count as f64;
        // Variances from 10⁻⁸ of the residuals' mean square (none) to 4 times it, in logs.
        let (lo, hi) = ((1e-8 * scale).ln(), (4.0 * scale).ln());
        let model = |phi: f64, ll: f64, lw: f64| ResidualModel {
            persistence: phi,
            latent_var: ll.exp(),
            white_var: lw.exp(),
            records: count,
            deviance_drop: 0.0,
            lasting_change_share: 1.0,
        };
        let white = golden(lo, hi, |lw| {
            model(0.0, f64::NEG_INFINITY, lw).deviance(r, n)
        })
        .1;
        let mut best: Option<(f64, ResidualModel)> = None;
        for phi in persistence_grid() {
            let (mut ll, mut lw) = ((0.5 * scale).ln(), (0.5 * scale).ln());
            let mut d = f64::INFINITY;
            for _ in 0..3 {
                ll = golden(lo, hi, |x| model(phi, x, lw).deviance(r, n)).0;
                (lw, d) = golden(lo, hi, |x| model(phi, ll, x).deviance(r, n));
            }
            if best.as_ref().is_none_or(|b| d < b.0) {
                best = Some((d, model(phi, ll, lw)));
            }
        }
        let (d, mut m) = best?;
        m.deviance_drop = white - d;
        let mean_n = r
            .iter()
            .zip(n)
            .filter(|(r, n)| r.is_finite() && n.is_finite())
            .map(|(_, n)| n)
            .sum::<f64>()
            / count as f64;
        m.lasting_change_share = m.settled_share(mean_n);
        (m.deviance_drop > 2.0 * (count as f64).ln()).then_some(m)
    }

    /// The standardized innovations of the later residuals `r` (variances `n`), the filter
    /// first run through the training residuals `history` (variances `history_n`); NaN in a
    /// gap.
    pub fn innovations(
        &self,
        (history, history_n): (&[f64], &[f64]),
        r: &[f64],
        n: &[f64],
    ) -> Vec<f64> {
        let mut state = (0.0, self.latent_var);
        self.filter(history, history_n, &mut state, &mut |_| {});
        let mut out = Vec::with_capacity(r.len());
        self.filter(r, n, &mut state, &mut |v| out.push(v));
        out
    }

    /// The share of a lasting change the filter's innovations keep once settled, at known
    /// variance `n`: the prediction error e of a step δ obeys e_{t+1} = δ(1 − φ) +
    /// φ(1 − K)e_t, so e → δ(1 − φ)/(1 − φ(1 − K)), K from the steady Riccati recursion.
    fn settled_share(&self, n: f64) -> f64 {
        let phi = self.persistence;
        let q = self.latent_var * (1.0 - phi * phi);
        let r = n + self.white_var;
        let mut p = self.latent_var;
        for _ in 0..10_000 {
            let next = phi * phi * (p * r / (p + r)) + q;
            if (next - p).abs() <= 1e-12 * p.max(f64::MIN_POSITIVE) {
                break;
            }
            p = next;
        }
        let gain = p / (p + r);
        (1.0 - phi) / (1.0 - phi * (1.0 - gain))
    }

    /// −2 ln L of `r` with known variances `n` from the stationary start.
    fn deviance(&self, r: &[f64], n: &[f64]) -> f64 {
        self.filter(r, n, &mut (0.0, self.latent_var), &mut |_| {})
    }

    /// Run the filter over `r` (variances `n`) from `state`, which it leaves at the end,
    /// telling `innovation` each record's standardized innovation (NaN in a gap); −2 ln L
    /// (less its constant).
    fn filter(
        &self,
        r: &[f64],
        n: &[f64],
        state: &mut State,
        innovation: &mut dyn FnMut(f64),
    ) -> f64 {
        let phi = self.persistence;
        let q = self.latent_var * (1.0 - phi * phi);
        let (mut m, mut p) = *state;
        let mut total = 0.0;
        for (&rt, &nt) in r.iter().zip(n) {
            m *= phi;
            p = phi * phi * p + q;
            if !(rt.is_finite() && nt.is_finite()) {
                innovation(f64::NAN);
                continue;
            }
            let f = p + nt + self.white_var;
            let v = rt - m;
            total += f.ln() + v * v / f;
            innovation(v / f.sqrt());
            // An outlier (a record's estimate far off, with too small a standard error) is
            // charted but does not move the effect's estimate: followed, it would make the
            // next records look off the other way.
            if v * v > GATE * GATE * f {
                continue;
            }
            let gain = p / f;
            m += gain * v;
            p *= 1.0 - gain;
        }
        *state = (m, p);
        total
    }
}

/// The minimum of `f` over [a, b] by golden-section search, and its value (50 steps: the
/// bracket shrinks by 0.618⁵⁰ ≈ 4·10⁻¹¹).
fn golden(mut a: f64, mut b: f64, f: impl Fn(f64) -> f64) -> (f64, f64) {
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let mut c = b - g * (b - a);
    let mut d = a + g * (b - a);
    let (mut fc, mut fd) = (f(c), f(d));
    for _ in 0..50 {
        if fc < fd {
            (b, d, fd) = (d, c, fc);
            c = b - g * (b - a);
            fc = f(c);
        } else {
            (a, c, fc) = (c, d, fd);
            d = a + g * (b - a);
            fd = f(d);
        }
    }
    let x = 0.5 * (a + b);
    (x, f(x))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    /// `count` residuals: a latent AR(1) of persistence `phi` and variance `latent` under
    /// white noise of variance 1, and those variances.
    fn residuals(count: usize, phi: f64, latent: f64, seed: u64) -> (Vec<f64>, Vec<f64>) {
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
        let normal = Normal::new(0.0, 1.0).unwrap();
        let mut eta = latent.sqrt() * normal.sample(&mut rng);
        let r = (0..count)
            .map(|_| {
                eta = phi * eta + ((1.0 - phi * phi) * latent).sqrt() * normal.sample(&mut rng);
                eta + normal.sample(&mut rng)
            })
            .collect();
        (r, vec![1.0; count])
    }

    /// White residuals keep no latent effect on most seeds; a latent effect as large as the
    /// noise, correlated over 24 records, is found with its persistence and variance, and
    /// fresh residuals' innovations are then uncorrelated with unit variance.
    #[test]
    fn finds_a_slow_effect_and_removes_it() {
        // The BIC bar, 2 ln 336 = 11.6 for two parameters, is passed by chance rarely.
        let spurious = (0..20)
            .filter(|&s| {
                let (r, n) = residuals(336, 0.0, 0.0, 100 + s);
                ResidualModel::fit(&r, &n).is_some()
            })
            .count();
        assert!(spurious <= 2, "{spurious} of 20");
        let phi = (-1.0f64 / 24.0).exp();
        for seed in 0..5 {
            let (r, n) = residuals(3000, phi, 1.0, 200 + seed);
            let m = ResidualModel::fit(&r, &n).expect("a latent effect");
            // 3000 residuals are 125 correlation times: λ within about 3 of its relative
            // spread √(2/125) = 0.13; φ on the grid (0.957 or 0.970 beside the true 0.959);
            // w near 0.
            assert!((m.latent_var - 1.0).abs() < 0.4, "{m:?}");
            assert!((m.persistence - phi).abs() < 0.02, "{m:?}");
            assert!(m.white_var < 0.2, "{m:?}");
            let (fresh, fresh_n) = residuals(2000, phi, 1.0, 300 + seed);
            let a = m.innovations((&r, &n), &fresh, &fresh_n);
            let var = a.iter().map(|v| v * v).sum::<f64>() / a.len() as f64;
            let r1 = a.windows(2).map(|w| w[0] * w[1]).sum::<f64>() / a.len() as f64 / var;
            // Unit variance within 4 of its spread √(2/2000) = 0.03; lag-1 correlation within
            // 3 of its spread 1/√2000 = 0.022.
            assert!((var - 1.0).abs() < 0.13, "{var} {m:?}");
            assert!(r1.abs() < 0.067, "{r1} {m:?}");
        }
    }

    /// A gap is predicted across, never charted; too few residuals give no model.
    #[test]
    fn gaps_are_passed_over() {
        let m = ResidualModel {
            persistence: 0.5,
            latent_var: 1.0,
            white_var: 0.0,
            records: 100,
            deviance_drop: 20.0,
            lasting_change_share: 0.5,
        };
        let a = m.innovations((&[], &[]), &[1.0, f64::NAN, 1.0], &[1.0; 3]);
        assert!(
            a[0].is_finite() && a[1].is_nan() && a[2].is_finite(),
            "{a:?}"
        );
        // The first: v = 1, F = λ + n = 2.
        assert!((a[0] - 1.0 / 2f64.sqrt()).abs() < 1e-12, "{a:?}");
        assert_eq!(ResidualModel::fit(&[0.5; 20], &[1.0; 20]), None);
        // An outlier is charted, and the record after it sees the filter as before it.
        let a = m.innovations((&[], &[]), &[0.0, 40.0, 0.0], &[1.0; 3]);
        let b = m.innovations((&[], &[]), &[0.0, f64::NAN, 0.0], &[1.0; 3]);
        assert!(a[1] > 20.0 && a[2] == b[2], "{a:?} {b:?}");
        // The settled share against the filter run on a step: the innovations of a step of
        // 1 after a long run of zeros settle at the share (times √F).
        let steps: Vec<f64> = (0..400).map(|t| if t < 200 { 0.0 } else { 1.0 }).collect();
        let a = m.innovations((&[], &[]), &steps, &[1.0; 400]);
        let mut state_p = m.latent_var;
        for _ in 0..400 {
            let pred = 0.25 * state_p + 0.75;
            state_p = pred * 1.0 / (pred + 1.0);
        }
        let f = 0.25 * state_p + 0.75 + 1.0;
        let share = m.settled_share(1.0);
        assert!(
            (a[399] * f.sqrt() - share).abs() < 1e-9,
            "{} vs {share}",
            a[399] * f.sqrt()
        );
        assert!(share > 0.0 && share < 1.0);
    }
}
