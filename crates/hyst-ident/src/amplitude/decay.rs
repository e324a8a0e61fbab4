//! A band's signature fitted by the signature a linear mode would give through the same
//! band-pass: for a mode of natural frequency $\omega_n$ and damping ratio ζ under a white
//! force, the measured quantity (the $p$-th derivative of displacement) has the spectrum
//! $S(\omega) = \omega^{2p}/[(\omega_n^2-\omega^2)^2 + (2\zeta\omega_n\omega)^2]$, the filter
//! passes $W(\omega)^2 S(\omega)$, and the analytic signal's correlation is
//! $m(\tau) = \int W^2 S\,e^{i\omega\tau}\,d\omega$ (a sum over a frequency grid across the
//! band). The signature $D$ is fitted as $c\,m(\tau)$, $c$ complex by linear least squares
//! for each $(\omega_n, \zeta)$ and those two by Levenberg–Marquardt. (A term for white
//! measurement noise, its signature through the filter, was tried: over a few cycles it
//! trades with the decay, and the fit slides to an undamped tone beside a noise pulse.)
//! Fitting the filtered
//! model rather than a bare exponential keeps the fit unbiased however narrow the band is
//! against the mode's bandwidth, or short the window against its decay.

use crate::fft::C;

/// The smallest damping ratio a fit may reach.
const ZETA_FLOOR: f64 = 1e-5;

/// What a signature's fit gives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Decay {
    /// Natural frequency (Hz).
    pub frequency_hz: f64,
    /// Damping ratio.
    pub damping_ratio: f64,
    /// The fitted signature's magnitude at the window's middle, in the record's unit.
    pub amplitude: f64,
}

/// The linear mode's signature through the band-pass, on a grid of frequencies.
pub(super) struct FilteredMode {
    /// Grid frequencies (rad/s).
    omega: Vec<f64>,
    /// W² at each, times the grid step.
    gain: Vec<f64>,
    /// e^{iωτ}, grid point × lag.
    phasor: Vec<Vec<C>>,
    /// White noise's signature through the filter over its value at lag 0.
    noise: Vec<C>,
    /// The share of the band's variance that is white noise (measurement noise, a force's
    /// direct share in accelerations), from the record's spectrum ([`noise_share`]).
    noise_share: f64,
    /// Time derivatives of displacement the record measures.
    order: i32,
    /// Lags.
    len: usize,
}

impl FilteredMode {
    /// The model for `len` lags at `fs`, through the band `(lo, hi)` Hz with the gain
    /// `weight(f)`, on a grid fine enough for damping ratios down to `zeta_min` at `f0`.
    pub(super) fn new(
        fs: f64,
        len: usize,
        band: (f64, f64),
        weight: &dyn Fn(f64) -> f64,
        order: i32,
        f0: f64,
        zeta_min: f64,
    ) -> Self {
        // A quarter of the half-power half-width, and a tenth of a cycle over the window.
        let step = (0.25 * zeta_min * f0).min(0.1 * fs / len as f64);
        let points = (((band.1 - band.0) / step).ceil() as usize).clamp(64, 8192);
        let df = (band.1 - band.0) / points as f64;
        let tau: Vec<f64> = (0..len).map(|k| k as f64 / fs).collect();
        let (mut omega, mut gain, mut phasor) = (Vec::new(), Vec::new(), Vec::new());
        for i in 0..points {
            let f = band.0 + (i as f64 + 0.5) * df;
            let w = weight(f);
            if w <= 0.0 {
                continue;
            }
            let om = 2.0 * std::f64::consts::PI * f;
            omega.push(om);
            gain.push(w * w * df);
            phasor.push(tau.iter().map(|t| C::from_polar(1.0, om * t)).collect());
        }
        let mut noise = vec![C::new(0.0, 0.0); len];
        for (g, ph) in gain.iter().zip(&phasor) {
            noise.iter_mut().zip(ph).for_each(|(a, p)| *a += p * *g);
        }
        let n0 = noise.first().map_or(1.0, |v| v.re).max(f64::MIN_POSITIVE);
        noise.iter_mut().for_each(|v| *v /= n0);
        FilteredMode {
            omega,
            gain,
            phasor,
            noise,
            noise_share: 0.0,
            order,
            len,
        }
    }

    /// The share of the band's variance that is white noise.
    pub(super) fn noise_share(&self) -> f64 {
        self.noise_share
    }

    /// The model with `share` of the band's variance white noise (0 ≤ share < 1).
    pub(super) fn with_noise_share(mut self, share: f64) -> Self {
        self.noise_share = share.clamp(0.0, 0.95);
        self
    }

    /// The mode's spectrum (up to scale) at `om` rad/s.
    fn spectrum(&self, wn: f64, zeta: f64, om: f64) -> f64 {
        om.powi(2 * self.order) / ((wn * wn - om * om).powi(2) + (2.0 * zeta * wn * om).powi(2))
    }

    /// m(τ) for natural frequency `wn` (rad/s) and damping ratio `zeta`.
    fn signature(&self, wn: f64, zeta: f64) -> Vec<C> {
        let mut m = vec![C::new(0.0, 0.0); self.len];
        for ((om, g), ph) in self.omega.iter().zip(&self.gain).zip(&self.phasor) {
            let s = g * self.spectrum(wn, zeta, *om);
            m.iter_mut().zip(ph).for_each(|(a, p)| *a += p * s);
        }
        m
    }

    /// The residual of `d` against the best complex multiple of m(wn, ζ) (for a real
    /// signature, of its real part), stacked real and imaginary, with the fitted model.
    fn residual(&self, d: &[C], real: bool, wn: f64, zeta: f64) -> Option<(Vec<f64>, Vec<C>)> {
        // A linear mode with white noise in its band: the noise's share q of the variance
        // adds q·n(τ) to the mode's (1 − q)·m(τ), each normalized at lag 0.
        let mut m = self.signature(wn, zeta);
        let m0 = m.first().map_or(1.0, |v| v.re).max(f64::MIN_POSITIVE);
        let q = self.noise_share;
        m.iter_mut()
            .zip(&self.noise)
            .for_each(|(v, n)| *v = *v * ((1.0 - q) / m0) + n * q);
        let stack = |v: &[C]| -> Vec<f64> {
            if real {
                v.iter().map(|c| c.re).collect()
            } else {
                v.iter().flat_map(|c| [c.re, c.im]).collect()
            }
        };
        let turn = |v: &[C]| -> Vec<C> { v.iter().map(|c| c * C::new(0.0, 1.0)).collect() };
        let target = stack(d);
        let cols = [stack(&m), stack(&turn(&m))];
        let (mut a, g) = crate::normal_equations(&cols, &target);
        let scale = a[0][0].max(a[1][1]).max(1e-300);
        // A tiny ridge keeps a real signature's system solvable (Im m vanishes at lag 0).
        (0..2).for_each(|i| a[i][i] += 1e-12 * scale);
        let coef = crate::solve(a, g)?;
        let r: Vec<f64> = (0..target.len())
            .map(|k| cols.iter().zip(&coef).map(|(c, x)| c[k] * x).sum::<f64>() - target[k])
            .collect();
        let c = C::new(coef[0], coef[1]);
        Some((r, m.iter().map(|v| v * c).collect()))
    }

    /// Fit `d` (a complex signature, or a real one with `real`) from `(f0, zeta0)`.
    pub(super) fn fit(&self, d: &[C], real: bool, f0: f64, zeta0: f64) -> Option<Decay> {
        if d.len() != self.len || self.omega.is_empty() {
            return None;
        }
        // x = (ln ωn, ln ζ): both stay positive.
        let x0 = [(2.0 * std::f64::consts::PI * f0).ln(), zeta0.ln()];
        let x = self.least_squares(d, real, x0)?;
        let (wn, zeta) = (x[0].exp(), x[1].exp());
        let (_, fitted) = self.residual(d, real, wn, zeta)?;
        let mid = fitted.get(self.len / 2)?.norm();
        // A fit at the floor found no decay the window can measure.
        (zeta > 2.0 * ZETA_FLOOR && zeta < 1.0 && mid.is_finite()).then(|| Decay {
            frequency_hz: wn / (2.0 * std::f64::consts::PI),
            damping_ratio: zeta,
            amplitude: mid,
        })
    }

    /// Levenberg–Marquardt on (ln ωn, ln ζ) from `x`.
    fn least_squares(&self, d: &[C], real: bool, x: [f64; 2]) -> Option<[f64; 2]> {
        fit_frequency_and_damping(x, 100, &|x| {
            self.residual(d, real, x[0].exp(), x[1].exp()).map(|r| r.0)
        })
    }
}

/// Levenberg–Marquardt (the crate's) on x = (ln ωn, ln ζ) from `x`, over at most `iterations`
/// steps, for the residuals `residual(x)` (`None`: no value there); a step moves ln ωn by at
/// most 0.2 and ln ζ by at most 1, and keeps ζ in [ZETA_FLOOR, 1]. `None` when the start has
/// no value.
fn fit_frequency_and_damping(
    mut x: [f64; 2],
    iterations: usize,
    residual: &dyn Fn(&[f64; 2]) -> Option<Vec<f64>>,
) -> Option<[f64; 2]> {
    let cost_at = |x: &[f64; 2]| {
        let r = residual(x)?;
        let c: f64 = r.iter().map(|v| v * v).sum();
        Some((r, c))
    };
    let (mut r, mut cost) = cost_at(&x)?;
    let mut lambda = 1e-3;
    for _ in 0..iterations {
        let cols = (0..2)
            .map(|j| {
                let h = 1e-6;
                let mut xj = x;
                xj[j] += h;
                let (rj, _) = cost_at(&xj)?;
                Some(rj.iter().zip(&r).map(|(a, b)| (a - b) / h).collect())
            })
            .collect::<Option<Vec<Vec<f64>>>>();
        let Some(cols) = cols else { break };
        let (a, g) = crate::normal_equations(&cols, &r);
        let improved = crate::lm_step(&a, &g, &mut lambda, |step| {
            let xn = [
                x[0] - step[0].clamp(-0.2, 0.2),
                x[1] - step[1].clamp(-1.0, 1.0),
            ];
            if xn.iter().any(|v| !v.is_finite()) || xn[1] > 0.0 || xn[1] < ZETA_FLOOR.ln() {
                return None;
            }
            let (rn, cn) = cost_at(&xn)?;
            (cn < cost).then(|| {
                let significant = cost - cn > 1e-10 * cost;
                (x, r, cost) = (xn, rn, cn);
                significant
            })
        });
        if !improved {
            break;
        }
    }
    Some(x)
}

/// The share of `q`'s variance inside `band`, after the band-pass `weight`, that is white:
/// its Welch spectrum (segments resolving the mode's half-power width, at most an eighth of
/// the record) fitted in the band as c·S(f; fn, ζ) + d, relative errors (residuals over the
/// spectrum), c and d by linear least squares for each (fn, ζ) and those by
/// Levenberg–Marquardt from (f0, ζ0); the share is d·ΣW² / ΣW²P.
pub(super) fn noise_share(
    q: &[f64],
    fs: f64,
    band: (f64, f64),
    weight: &dyn Fn(f64) -> f64,
    model: &FilteredMode,
    f0: f64,
    zeta0: f64,
) -> f64 {
    let resolve = fs / (0.5 * zeta0.max(1e-4) * f0);
    let segment = (resolve.ceil() as usize)
        .next_power_of_two()
        .min(((q.len() / 8).max(16)).next_power_of_two())
        .min(q.len());
    let (f, p) = crate::welch_psd(q, fs, segment);
    let inside: Vec<(f64, f64, f64)> = f
        .iter()
        .zip(&p)
        .filter(|(f, p)| **f > band.0 && **f < band.1 && weight(**f) > 0.0 && **p > 0.0)
        .map(|(f, p)| (weight(*f).powi(2), 2.0 * std::f64::consts::PI * f, *p))
        .collect();
    if inside.len() < 6 {
        return 0.0;
    }
    // For (ln ωn, ln ζ): the relative residuals, c and d.
    let fit = |x: &[f64; 2]| -> Option<(Vec<f64>, f64, f64)> {
        let s: Vec<f64> = inside
            .iter()
            .map(|(_, om, p)| model.spectrum(x[0].exp(), x[1].exp(), *om) / p)
            .collect();
        let one: Vec<f64> = inside.iter().map(|(_, _, p)| 1.0 / p).collect();
        let target = vec![1.0; inside.len()];
        let (a, g) = crate::normal_equations(&[s.clone(), one.clone()], &target);
        let coef = crate::solve(a, g)?;
        let r = s
            .iter()
            .zip(&one)
            .map(|(s, o)| coef[0] * s + coef[1] * o - 1.0)
            .collect();
        Some((r, coef[0], coef[1]))
    };
    let start = [(2.0 * std::f64::consts::PI * f0).ln(), zeta0.ln()];
    let Some(x) = fit_frequency_and_damping(start, 50, &|x| fit(x).map(|f| f.0)) else {
        return 0.0;
    };
    let Some((_, c, d)) = fit(&x) else {
        return 0.0;
    };
    let total: f64 = inside.iter().map(|(g, _, p)| g * p).sum();
    let white: f64 = inside.iter().map(|(g, _, _)| g * d.max(0.0)).sum();
    if c > 0.0 && total > 0.0 {
        (white / total).clamp(0.0, 0.95)
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The model's own signature, scaled and turned, is fitted back to its parameters from a
    /// start 3 % and a factor 2 off; through a band narrow against the mode (± 3 half-power
    /// half-widths) as well.
    #[test]
    fn the_filtered_model_fits_itself() {
        let (fs, f, zeta) = (200.0, 7.3, 0.02);
        for half in [0.3, 3.0 * zeta] {
            let band = (f * (1.0 - half), f * (1.0 + half));
            let w = |x: f64| if x > band.0 && x < band.1 { 1.0 } else { 0.0 };
            let model = FilteredMode::new(fs, 80, band, &w, 2, f, zeta);
            let wn = 2.0 * std::f64::consts::PI * f;
            let c = C::from_polar(3.0, 0.4);
            let d: Vec<C> = model.signature(wn, zeta).iter().map(|v| v * c).collect();
            let r = model.fit(&d, false, 1.03 * f, 2.0 * zeta).expect("a fit");
            assert!((r.frequency_hz - f).abs() < 1e-6 * f, "{half}: {r:?}");
            assert!(
                (r.damping_ratio - zeta).abs() < 1e-6 * zeta,
                "{half}: {r:?}"
            );
            assert!((r.amplitude - d[40].norm()).abs() < 1e-6 * d[40].norm());
            let real: Vec<C> = d.iter().map(|v| C::new(v.re, 0.0)).collect();
            let r = model.fit(&real, true, 1.03 * f, 2.0 * zeta).expect("a fit");
            assert!((r.frequency_hz - f).abs() < 1e-6 * f, "{half} real: {r:?}");
            assert!(
                (r.damping_ratio - zeta).abs() < 1e-5 * zeta,
                "{half} real: {r:?}"
            );
        }
    }
}
