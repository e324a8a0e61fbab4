//! An output-only route to the Bouc-Wen parameters that does not pass through one amplitude:
//! the *implied input* of a candidate model must be as flat as the excitation was designed.
//!
//! Given the measured displacement $x(t)$ and a candidate oscillator (mass m known, ν = 1),
//! the force that must have acted is
//! $$\hat u(t) = m\ddot x + c\dot x + kx + \alpha\,w(t),\qquad
//!   \dot w = \dot x - \beta\gamma\,|\dot x|\,w - \beta\delta\,\dot x\,|w|,$$
//! since for ν = 1 the Bouc-Wen state scales as $z = \alpha w$ with $w$ independent of α.
//! When the excitation is a multisine whose amplitude spectrum is flat on a known band of DFT
//! bins (the benchmark's design: bins 55–1639 of an 8192-sample period, 5–150 Hz), the true
//! parameters make $|\hat U_k|$ the same on every excited bin, whatever the random phases.
//! We therefore minimise the spread of $\ln|\hat U_k|$ over the band,
//! $$J(c, k, \alpha, \beta\gamma, \beta\delta) = \sum_{k \in \text{band}}
//!   \Big(\ln|\hat U_k| - \overline{\ln|\hat U|}\Big)^2,$$
//! by Levenberg–Marquardt (analytic derivatives in c, k, α; finite differences of $w$ in βγ,
//! βδ). The known mass fixes the scale. Nothing of the input record is used: only what the
//! experimenter knew when designing the excitation (its band and period), the same kind of
//! knowledge as SSI-COV's white-noise assumption, used to the end. The amplitude dependence
//! that one equivalent linearization cannot see is all in the record, because the multisine's
//! envelope sweeps the amplitudes.
//!
//! Derivatives: $\dot x$ and $\ddot x$ by exact spectral differentiation of the period
//! (averaged over the record's whole periods, which also averages the measurement noise);
//! $w$ by RK4 on an 8× finer grid with $\dot x$ interpolated band-limited, one period of
//! warm-up from $w = x$ (the small-βγ limit).

use hyst_model::{BoucWen, Oscillator, Restoring};

use crate::IdentError;

use crate::fft::{C, irfft, rfft};

/// What is known of the excitation's design (not its record).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct ExcitationBand {
    /// Lowest excited frequency (Hz).
    pub low_hz: f64,
    /// Highest excited frequency (Hz).
    pub high_hz: f64,
    /// Samples per period of the (periodic) excitation.
    pub period: usize,
}

impl ExcitationBand {
    /// The benchmark's multisine at 750 Hz: 8192 samples per period, 5–150 Hz.
    pub fn benchmark() -> Self {
        Self {
            low_hz: 5.0,
            high_hz: 150.1,
            period: 8192,
        }
    }

    /// The DFT bins of one period that the band holds at `fs` Hz (rounded inward), or why the
    /// band can never give a flatness fit: a period under 2 samples, a rate that is not
    /// positive, edges not finite and ordered, an upper edge above the Nyquist frequency, or
    /// fewer than 9 bins.
    pub fn check(&self, fs: f64) -> Result<(usize, usize), IdentError> {
        if self.period < 2 {
            return Err(IdentError::PeriodTooShort {
                period: self.period,
            });
        }
        if !(fs.is_finite() && fs > 0.0) {
            return Err(IdentError::BadRate { fs });
        }
        if self.high_hz > fs / 2.0 {
            return Err(IdentError::BandAboveNyquist {
                low_hz: self.low_hz,
                high_hz: self.high_hz,
                fs,
            });
        }
        let (lo, hi) = self.bins(fs);
        let ordered =
            self.low_hz.is_finite() && self.high_hz.is_finite() && self.low_hz < self.high_hz;
        if !ordered || hi < lo + 8 {
            return Err(IdentError::BadBand {
                low_hz: self.low_hz,
                high_hz: self.high_hz,
                fs,
                period: self.period,
            });
        }
        Ok((lo, hi))
    }

    /// The DFT bins of one period lying inside the band (rounded inward).
    pub fn bins(&self, fs: f64) -> (usize, usize) {
        let df = fs / self.period as f64;
        let lo = (self.low_hz / df).ceil().max(1.0) as usize;
        let hi = ((self.high_hz / df).floor() as usize).min((self.period / 2).saturating_sub(1));
        (lo, hi)
    }
}

/// The fitted Bouc-Wen oscillator and how flat its implied input is.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct FlatnessFit {
    /// The fitted model (ν = 1).
    pub model: Oscillator,
    /// RMS spread of $20\log_{10}|\hat U_k|$ over the band for the starting model (dB).
    pub start_spread_db: f64,
    /// The same for the fitted model (dB).
    pub spread_db: f64,
    /// RMS of the implied input over the band (N): the excitation level the model implies.
    pub input_rms: f64,
    /// Whole periods averaged.
    pub periods: usize,
    /// RMS difference between the record's last and first whole periods over the averaged
    /// period's RMS (`None` with one period): near 0 when the record is periodic with the
    /// given period (measurement noise only), of order 1 or more when it is not.
    pub aperiodicity: Option<f64>,
    /// The band's DFT bins (inclusive).
    pub bins: (usize, usize),
    /// Levenberg–Marquardt iterations taken.
    pub iterations: usize,
}

/// One averaged period of the record, in the frequency domain, and the velocity on the fine
/// grid the hysteresis state is integrated on.
struct Period {
    n: usize,
    fs: f64,
    x: Vec<C>,
    v: Vec<C>,
    a: Vec<C>,
    /// Velocity at 2·UP samples per sample (RK4 nodes and midpoints).
    v_fine: Vec<f64>,
    /// Displacement at the first fine node (warm-up start).
    x0: f64,
    /// RMS of (last period − first period) over the averaged period's RMS; `None` with one
    /// period.
    aperiodicity: Option<f64>,
}

const UP: usize = 8;

impl Period {
    fn new(y: &[f64], fs: f64, period: usize) -> Result<(Self, usize), IdentError> {
        let n = period;
        let p = y.len() / n;
        if n < 16 || p == 0 {
            return Err(IdentError::TooShort {
                samples: y.len(),
                needed: n.max(16),
            });
        }
        let mut avg = vec![0.0; n];
        for k in 0..p {
            for (a, v) in avg.iter_mut().zip(&y[k * n..(k + 1) * n]) {
                *a += v / p as f64;
            }
        }
        let mean = avg.iter().sum::<f64>() / n as f64;
        avg.iter_mut().for_each(|v| *v -= mean);
        let rms =
            |it: &mut dyn Iterator<Item = f64>| (it.map(|v| v * v).sum::<f64>() / n as f64).sqrt();
        let aperiodicity = (p >= 2).then(|| {
            let (first, last) = (&y[..n], &y[(p - 1) * n..p * n]);
            rms(&mut first.iter().zip(last).map(|(a, b)| b - a)) / rms(&mut avg.iter().copied())
        });
        let x = rfft(&avg);
        let w = |i: usize| 2.0 * std::f64::consts::PI * i as f64 * fs / n as f64;
        let v: Vec<C> = x
            .iter()
            .enumerate()
            .map(|(i, xi)| xi * C::new(0.0, w(i)))
            .collect();
        let a: Vec<C> = x
            .iter()
            .enumerate()
            .map(|(i, xi)| -xi * w(i) * w(i))
            .collect();
        // Band-limited interpolation of the velocity (Nyquist bin dropped).
        let nf = 2 * UP * n;
        let mut s = vec![C::new(0.0, 0.0); nf / 2 + 1];
        for (si, vi) in s.iter_mut().zip(v.iter().take(n.div_ceil(2))) {
            *si = vi * (nf as f64 / n as f64);
        }
        let v_fine = irfft(&s, nf);
        Ok((
            Self {
                n,
                fs,
                x,
                v,
                a,
                v_fine,
                x0: avg[0],
                aperiodicity,
            },
            p,
        ))
    }

    /// Bin `i` of the implied input of θ = `q` with mass `m`, given w's spectrum `ws`.
    fn implied_at(&self, i: usize, m: f64, q: &[f64; 5], ws: &[C]) -> C {
        self.a[i] * m + self.v[i] * q[0] + self.x[i] * q[1] + ws[i] * q[2]
    }

    /// The spectrum (bins 0..=n/2) of w for (βγ, βδ), or None if w is not finite.
    fn w_spectrum(&self, bg: f64, bd: f64) -> Option<Vec<C>> {
        let steps = UP * self.n;
        let h = 1.0 / (self.fs * UP as f64);
        let f = |w: f64, v: f64| v - bg * v.abs() * w - bd * v * w.abs();
        let vf = &self.v_fine;
        let nf = vf.len();
        let mut w = self.x0;
        let mut out = vec![0.0; steps];
        for pass in 0..2 {
            for j in 0..steps {
                if pass == 1 {
                    out[j] = w;
                }
                let (v0, v1, v2) = (vf[2 * j], vf[2 * j + 1], vf[(2 * j + 2) % nf]);
                let k1 = f(w, v0);
                let k2 = f(w + 0.5 * h * k1, v1);
                let k3 = f(w + 0.5 * h * k2, v1);
                let k4 = f(w + h * k3, v2);
                w += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
            }
            if !w.is_finite() || w.abs() > 1e6 {
                return None;
            }
        }
        let spec = rfft(&out);
        Some(
            spec.iter()
                .take(self.n / 2 + 1)
                .map(|s| s / UP as f64)
                .collect(),
        )
    }
}

fn not_bouc_wen(o: &Oscillator) -> IdentError {
    IdentError::BadStart {
        reason: format!(
            "the model must be linear or Bouc-Wen with ν = 1 and no extra forces, got {:?}",
            o.restoring
        ),
    }
}

/// Parameters θ = (c, k, α, βγ, βδ).
fn theta(o: &Oscillator) -> Option<[f64; 5]> {
    if !o.extras.is_empty() {
        return None;
    }
    match o.restoring {
        Restoring::BoucWen(b) if b.nu == 1.0 => Some([
            o.damping,
            o.stiffness,
            b.alpha,
            b.beta_gamma(),
            b.beta_delta(),
        ]),
        Restoring::None => Some([o.damping, o.stiffness, 0.0, 0.0, 0.0]),
        _ => None,
    }
}

struct Eval {
    /// ln|Û| minus its mean over the band.
    r: Vec<f64>,
    /// Û over the band.
    u: Vec<C>,
    /// W over the band.
    w: Vec<C>,
}

fn evaluate(p: &Period, m: f64, q: &[f64; 5], band: (usize, usize)) -> Option<Eval> {
    let ws = p.w_spectrum(q[3], q[4])?;
    let (lo, hi) = band;
    let u: Vec<C> = (lo..=hi).map(|i| p.implied_at(i, m, q, &ws)).collect();
    let mut r: Vec<f64> = u.iter().map(|x| x.norm().ln()).collect();
    if r.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let mean = r.iter().sum::<f64>() / r.len() as f64;
    r.iter_mut().for_each(|v| *v -= mean);
    Some(Eval {
        r,
        u,
        w: ws[lo..=hi].to_vec(),
    })
}

fn spread_db(r: &[f64]) -> f64 {
    let ms = r.iter().map(|v| v * v).sum::<f64>() / r.len() as f64;
    20.0 / std::f64::consts::LN_10 * ms.sqrt()
}

/// Fit the Bouc-Wen oscillator (ν = 1, mass fixed) to the output record `y` (sampled at `fs`,
/// in periodic steady state; where a period starts does not matter, since |Û_k| does not
/// change with a time shift; whole periods are averaged, a partial one at the end is ignored)
/// by flatness of its implied input over `band`, from each of `starts` (Bouc-Wen oscillators
/// with ν = 1 or linear ones; in parallel, on one averaged period). The flattest fit that ends
/// on a valid oscillator wins; if none does, the last start's error is returned.
pub fn fit(
    y: &[f64],
    fs: f64,
    band: &ExcitationBand,
    starts: &[Oscillator],
) -> Result<FlatnessFit, IdentError> {
    use rayon::prelude::*;
    let (lo, hi) = band.check(fs)?;
    let (p, periods) = Period::new(y, fs, band.period)?;
    let fits: Vec<Result<FlatnessFit, IdentError>> = starts
        .par_iter()
        .map(|start| {
            let f = fit_from(&p, periods, (lo, hi), start)?;
            f.model.validate().map_err(|e| IdentError::BadStart {
                reason: format!("the fit ended on an invalid model ({e})"),
            })?;
            Ok(f)
        })
        .collect();
    let mut best: Option<FlatnessFit> = None;
    let mut last_err = IdentError::BadStart {
        reason: "no starting model given".to_string(),
    };
    for f in fits {
        match f {
            Ok(f) if best.as_ref().is_none_or(|b| f.spread_db < b.spread_db) => best = Some(f),
            Ok(_) => {}
            Err(e) => last_err = e,
        }
    }
    best.ok_or(last_err)
}

/// Levenberg–Marquardt from one start on the prepared period.
fn fit_from(
    p: &Period,
    periods: usize,
    band: (usize, usize),
    start: &Oscillator,
) -> Result<FlatnessFit, IdentError> {
    let m = start.mass;
    if !(m.is_finite() && m > 0.0) {
        return Err(IdentError::NonPositiveMass { mass: m });
    }
    let (lo, _) = band;
    let mut q = theta(start).ok_or_else(|| not_bouc_wen(start))?;
    if q[2] == 0.0 {
        // A linear start: split its stiffness evenly, hysteresis scale from the record.
        let sx = (p.x.iter().skip(1).map(|x| 2.0 * x.norm_sqr()).sum::<f64>()).sqrt() / p.n as f64;
        q = [q[0], 0.5 * q[1], 0.5 * q[1], 0.5 / sx, 0.0];
    }
    let cost = |e: &Eval| e.r.iter().map(|v| v * v).sum::<f64>();
    let mut cur = evaluate(p, m, &q, band).ok_or_else(|| IdentError::BadStart {
        reason: format!(
            "the implied input of the starting model {q:?} (c, k, α, βγ, βδ) is not finite"
        ),
    })?;
    let start_spread_db = spread_db(&cur.r);
    let mut c = cost(&cur);
    let mut lambda = 1e-3;
    let mut iterations = 0;
    for _ in 0..100 {
        iterations += 1;
        // Columns: ∂ln|Û|/∂θ = Re(conj(Û) ∂Û/∂θ)/|Û|², then centred.
        let mut cols: Vec<Vec<f64>> = Vec::with_capacity(5);
        let d = |du: &dyn Fn(usize) -> C| -> Vec<f64> {
            let mut col: Vec<f64> = cur
                .u
                .iter()
                .enumerate()
                .map(|(i, u)| (u.conj() * du(i)).re / u.norm_sqr())
                .collect();
            let mean = col.iter().sum::<f64>() / col.len() as f64;
            col.iter_mut().for_each(|v| *v -= mean);
            col
        };
        cols.push(d(&|i| p.v[lo + i]));
        cols.push(d(&|i| p.x[lo + i]));
        cols.push(d(&|i| cur.w[i]));
        let mut fd_ok = true;
        for j in 3..5 {
            let h = 1e-6 * q[j].abs().max(1.0);
            let mut qj = q;
            qj[j] += h;
            match p.w_spectrum(qj[3], qj[4]) {
                Some(ws) => {
                    let dw: Vec<C> = (0..cur.w.len())
                        .map(|i| (ws[lo + i] - cur.w[i]) * (q[2] / h))
                        .collect();
                    cols.push(d(&|i| dw[i]));
                }
                None => fd_ok = false,
            }
        }
        if !fd_ok {
            break;
        }
        let (a, g) = crate::normal_equations(&cols, &cur.r);
        let improved = crate::lm_step(&a, &g, &mut lambda, |step| {
            let mut qn = q;
            for (v, s) in qn.iter_mut().zip(step) {
                *v -= s;
            }
            let e = evaluate(p, m, &qn, band)?;
            let cn = cost(&e);
            (cn < c).then(|| {
                let significant = c - cn > 1e-10 * c;
                (q, cur, c) = (qn, e, cn);
                significant
            })
        });
        if !improved {
            break;
        }
    }
    let input_rms = (cur.u.iter().map(|u| 2.0 * u.norm_sqr()).sum::<f64>()).sqrt() / p.n as f64;
    let model = Oscillator::bouc_wen(m, q[0], q[1], BoucWen::from_products(q[2], q[3], q[4], 1.0));
    Ok(FlatnessFit {
        model,
        start_spread_db,
        spread_db: spread_db(&cur.r),
        input_rms,
        periods,
        aperiodicity: p.aperiodicity,
        bins: band,
        iterations,
    })
}

/// The implied input's spectrum, bins 0..=n/2 of one averaged period, zero outside the band;
/// and the period length.
fn implied(
    model: &Oscillator,
    y: &[f64],
    fs: f64,
    band: &ExcitationBand,
) -> Result<(Vec<C>, usize), IdentError> {
    let q = theta(model).ok_or_else(|| not_bouc_wen(model))?;
    let (p, _) = Period::new(y, fs, band.period)?;
    let (lo, hi) = band.bins(fs);
    let ws = p
        .w_spectrum(q[3], q[4])
        .ok_or_else(|| IdentError::BadStart {
            reason: format!(
                "the hysteresis state of {q:?} (c, k, α, βγ, βδ) diverges on this record"
            ),
        })?;
    let spec = (0..=p.n / 2)
        .map(|i| {
            if (lo..=hi).contains(&i) {
                p.implied_at(i, model.mass, &q, &ws)
            } else {
                C::new(0.0, 0.0)
            }
        })
        .collect();
    Ok((spec, p.n))
}

/// The implied input $\hat u(t)$ of a Bouc-Wen (ν = 1) or linear oscillator over one period of
/// the record (whole periods averaged): the force that, applied to the model, would produce
/// the measured output, on the excitation's band (bins outside it, where the measurement
/// noise amplified by $m\omega^2$ would dominate, are set to zero).
pub fn implied_input(
    model: &Oscillator,
    y: &[f64],
    fs: f64,
    band: &ExcitationBand,
) -> Result<Vec<f64>, IdentError> {
    let (spec, n) = implied(model, y, fs, band)?;
    Ok(irfft(&spec, n))
}

/// The implied input's amplitude spectrum over the band: (frequency in Hz, amplitude in N of
/// each line) for every DFT bin of one (averaged) period inside the band. Flat at the
/// excitation's line amplitude when the model is right.
pub fn implied_spectrum(
    model: &Oscillator,
    y: &[f64],
    fs: f64,
    band: &ExcitationBand,
) -> Result<Vec<(f64, f64)>, IdentError> {
    let (spec, n) = implied(model, y, fs, band)?;
    let (lo, hi) = band.bins(fs);
    Ok((lo..=hi)
        .map(|i| (i as f64 * fs / n as f64, 2.0 * spec[i].norm() / n as f64))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use hyst_model::ZenerParams;
    use hyst_sim::SimOptions;
    use hyst_sim::excitation::Multisine;
    use proptest::prelude::*;

    const FS: f64 = 750.0;

    /// A short multisine period (1024 samples, 5–150 Hz) and the periodic steady-state
    /// response of `model`, repeated `periods` times.
    fn record(
        model: &Oscillator,
        rms: f64,
        periods: usize,
        seed: u64,
    ) -> (Vec<f64>, Vec<f64>, ExcitationBand) {
        record_at(model, rms, periods, seed, FS, 1024, &SimOptions::default())
    }

    /// A steady-state record of `model` under the 5–150 Hz multisine of period `n` at `fs`,
    /// simulated with `opts`.
    fn record_at(
        model: &Oscillator,
        rms: f64,
        periods: usize,
        seed: u64,
        fs: f64,
        n: usize,
        opts: &SimOptions,
    ) -> (Vec<f64>, Vec<f64>, ExcitationBand) {
        let ms = Multisine::band(n, fs, 5.0, 150.0, rms).unwrap();
        let u = ms.generate(seed).unwrap();
        let one = hyst_sim::steady_state_period(model, &u, fs, opts, 1e-12, 400)
            .unwrap()
            .y;
        let y = one.repeat(periods);
        let band = ExcitationBand {
            low_hz: 5.0,
            high_hz: 150.0,
            period: n,
        };
        (u, y, band)
    }

    fn rel_rms(a: &[f64], b: &[f64]) -> f64 {
        let e: f64 = a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum();
        let r: f64 = b.iter().map(|y| y * y).sum();
        (e / r).sqrt()
    }

    /// From a linear start (k + α lumped) on a noiseless record, the fit returns the true
    /// parameters. Tolerance 1e-3 relative: the record is simulated by RK4 at 20 sub-steps
    /// and sub-sampled, the fit integrates w at 4 sub-steps from a band-limited velocity;
    /// both discretizations differ from the exact flow by about 1e-4.
    #[test]
    fn recovers_the_benchmark_from_a_linear_start() {
        let truth = Oscillator::benchmark();
        let (_, y, band) = record(&truth, 40.0, 2, 5);
        let start = Oscillator::linear(2.0, 60.0, 1.2e5);
        let f = fit(&y, FS, &band, &[start]).unwrap();
        let Restoring::BoucWen(b) = f.model.restoring else {
            panic!("{f:?}")
        };
        let got = [
            f.model.damping,
            f.model.stiffness,
            b.alpha,
            b.beta_gamma(),
            b.beta_delta(),
        ];
        let want = [10.0, 5e4, 5e4, 800.0, -1100.0];
        for (g, w) in got.iter().zip(&want) {
            assert!(((g - w) / w).abs() < 1e-3, "{got:?} vs {want:?}");
        }
        assert!(f.spread_db < 0.01 * f.start_spread_db, "{f:?}");
        assert_eq!(f.periods, 2);
    }

    /// A periodic record folded with its own period has an aperiodicity of rounding size;
    /// folded with a wrong one, of order 1.
    #[test]
    fn aperiodicity_flags_a_wrong_period() {
        let truth = Oscillator::benchmark();
        let (_, y, band) = record(&truth, 30.0, 3, 2);
        let right = fit(&y, FS, &band, &[truth]).unwrap();
        assert!(right.aperiodicity.unwrap() < 1e-9, "{right:?}");
        let wrong = ExcitationBand {
            period: 1000,
            ..band
        };
        let w = fit(&y, FS, &wrong, &[truth]).unwrap();
        assert!(w.aperiodicity.unwrap() > 0.5, "{w:?}");
    }

    #[test]
    fn bad_input_is_named() {
        let truth = Oscillator::benchmark();
        let (_, y, band) = record(&truth, 20.0, 1, 1);
        // Shorter than one period.
        assert!(matches!(
            fit(&y[..1000], FS, &band, &[truth]),
            Err(IdentError::TooShort { samples: 1000, .. })
        ));
        // A band with too few bins.
        let narrow = ExcitationBand {
            low_hz: 40.0,
            high_hz: 43.0,
            ..band
        };
        assert!(matches!(
            fit(&y, FS, &narrow, &[truth]),
            Err(IdentError::BadBand { .. })
        ));
        assert!(matches!(
            fit(&y, 0.0, &band, &[truth]),
            Err(IdentError::BadRate { .. })
        ));
        let short = ExcitationBand { period: 1, ..band };
        assert_eq!(
            short.check(FS),
            Err(IdentError::PeriodTooShort { period: 1 })
        );
        let high = ExcitationBand {
            high_hz: 400.0,
            ..band
        };
        let e = high.check(FS).unwrap_err();
        assert_eq!(
            e.to_string(),
            format!(
                "excitation band {}..400 Hz reaches above the Nyquist frequency 375 Hz of 750 Hz",
                band.low_hz
            )
        );
        assert_eq!(band.check(FS), Ok(band.bins(FS)));
        let zener = Oscillator::zener(
            2.0,
            10.0,
            5e4,
            ZenerParams {
                k_inf: 5e4,
                omega: 50.0,
            },
        );
        let e = fit(&y, FS, &band, &[zener]).unwrap_err();
        assert!(e.to_string().contains("Bouc-Wen with ν = 1"), "{e}");
        let massless = Oscillator { mass: 0.0, ..truth };
        assert!(matches!(
            fit(&y, FS, &band, &[massless]),
            Err(IdentError::NonPositiveMass { .. })
        ));
    }

    /// The round trip's error at the benchmark's 750 Hz is set by the sampling, not by the
    /// algebra: the hysteretic output has harmonics above the Nyquist frequency, and the
    /// implied input is built from band-limited derivatives of the sampled output. At the
    /// strongest corner of the property test's domain (found by it: α = 62942, βγ = 1484,
    /// βδ = −1.40βγ, 85 N RMS) the error is 5.4e-4 at 750 Hz and falls about sixfold each
    /// time the rate doubles (7.0e-5 at 1500 Hz, 1.4e-5 at 3000 Hz), while four times the
    /// RK4 sub-steps move it by about 1 %. Asserted here: below 1e-3 at 750 Hz, at least
    /// four times smaller at each doubling, and within 10 % with 80 sub-steps instead of 20.
    #[test]
    fn round_trip_error_is_the_sampling_rate_s() {
        let model = Oscillator::bouc_wen(
            2.0,
            10.0,
            5e4,
            BoucWen::from_products(62942.15, 1484.41, -1.39758 * 1484.41, 1.0),
        );
        let error = |fs: f64, n: usize, oversample: usize| {
            let opts = SimOptions {
                oversample,
                ..SimOptions::default()
            };
            let (u, y, band) = record_at(&model, 85.2156, 1, 2, fs, n, &opts);
            rel_rms(&implied_input(&model, &y, fs, &band).unwrap(), &u)
        };
        let e = [
            error(750.0, 1024, 20),
            error(1500.0, 2048, 20),
            error(3000.0, 4096, 20),
        ];
        let e_fine = error(750.0, 1024, 80);
        eprintln!("round trip at 750, 1500, 3000 Hz: {e:?}; at 750 Hz with 80 sub-steps: {e_fine}");
        assert!(e[0] < 1e-3, "{e:?}");
        assert!(e[1] < e[0] / 4.0 && e[2] < e[1] / 4.0, "{e:?}");
        assert!((e_fine - e[0]).abs() < 0.1 * e[0], "{e_fine} vs {}", e[0]);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        /// Round trip: the implied input of the true model, computed from its simulated output
        /// alone, is the input that drove it. Sampled at 1500 Hz (twice the benchmark's rate)
        /// so that the test checks the computation rather than the sampling (see
        /// `round_trip_error_is_the_sampling_rate_s`): with the case count raised to 1000 by
        /// hand the largest error was 5.6e-5, and the corner that failed at 750 Hz measures
        /// 7.0e-5; bound 5e-4.
        #[test]
        fn implied_input_of_the_true_model_is_the_input(
            alpha in 2e4..8e4f64,
            bg in 200.0..1500.0f64,
            bd_over_bg in -1.4..0.9f64,
            rms in 5.0..90.0f64,
            seed in 0u64..1000,
        ) {
            let model = Oscillator::bouc_wen(2.0, 10.0, 5e4, BoucWen::from_products(alpha, bg, bd_over_bg * bg, 1.0));
            let (u, y, band) = record_at(&model, rms, 1, seed, 2.0 * FS, 2048, &SimOptions::default());
            let uh = implied_input(&model, &y, 2.0 * FS, &band).unwrap();
            let e = rel_rms(&uh, &u);
            prop_assert!(e < 5e-4, "relative error {e}");
        }
    }
}
