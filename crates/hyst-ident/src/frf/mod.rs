//! Modes from the input too: the frequency response of a periodic record and a rational fit
//! of it over a band. This is the input-output second opinion on what output-only SSI reports
//! (a check, not part of the output-only pipeline).
//!
//! **The response.** A periodic excitation (a multisine) repeated over $P$ whole periods of
//! $M$ samples is transformed period by period, $U_p(k)$, $Y_{c,p}(k)$, and averaged:
//! $H_c(k) = \bar Y_c(k)/\bar U(k)$ at the lines $k$ the input excites (no leakage: whole
//! periods). Its variance comes from the spread over periods,
//! $\sigma^2_{c}(k) = \sum_p |Y_{c,p} - H_c U_p|^2 / \big((P-1) P\,|\bar U|^2\big)$,
//! averaged over the 11 excited lines around $k$ (the noise's variance changes slowly with
//! frequency; one line's, from a few periods, scatters by tens of per cent).
//! For a nonlinear structure $H$ is its best linear approximation at that excitation.
//!
//! **The fit.** One denominator for all channels, $D(s) = s^{q} + \sum_{j<q} a_j s^j$ with
//! $q = 2\times$modes, and a numerator $N_c(s)$ of degree $q$ per channel (acceleration
//! responses are not strictly proper), in $s = i\omega/\omega_0$ scaled by the band's centre.
//! $\sum_{c,k} |N_c - H_c D|^2 / (\sigma_c^2 |D_{\text{prev}}|^2)$ is minimized by
//! Sanathanan–Koerner iterations (a linear least-squares problem each). The poles are the
//! roots of $D$; frequency $|\lambda|/2\pi$, damping $-\operatorname{Re}\lambda/|\lambda|$;
//! the mode's shape is the channels' residues there, $N_c(\lambda)/D'(\lambda)$, whose
//! common factor leaves $N_c(\lambda)$ across the channels (input-output shapes, to compare
//! with output-only SSI's by MAC). Their
//! standard errors come from the jackknife over periods (each period left out in turn). The
//! misfit is the weighted residual's mean square per real equation: near 1 when the model
//! explains the response to its noise. Far above 1 (the periodic distortions of a nonlinear
//! structure are not noise; neighbouring modes left out of the band), the standard errors
//! still describe the noise alone, and the change of the estimates with the band and the
//! number of modes is the larger uncertainty ([`band_spread`] measures the band's share).

use crate::fft::{C, rfft};
use crate::{Complex64, IdentError};
use nalgebra::{DMatrix, DVector};

/// A periodic record: one input and one or more outputs, in steady state from the first
/// sample (drop a start-up transient before). Samples past the last whole period are not used.
#[derive(Debug, Clone, Copy)]
pub struct PeriodicRecord<'a> {
    /// The excitation (e.g. force).
    pub input: &'a [f64],
    /// The responses, one slice per channel, each as long as the input.
    pub outputs: &'a [&'a [f64]],
    /// Sampling rate (Hz).
    pub fs: f64,
    /// Samples per period of the excitation.
    pub period: usize,
}

/// One mode of the fitted response.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct FrfMode {
    /// Natural frequency $|\lambda|/2\pi$ (Hz).
    pub frequency_hz: f64,
    /// Damping ratio $-\operatorname{Re}\lambda/|\lambda|$.
    pub damping_ratio: f64,
    /// Jackknife standard error of the frequency over periods (Hz); NaN with one period (or
    /// when fewer than two of the leave-one-out fits succeeded).
    #[cfg_attr(feature = "serde", serde(with = "crate::nullable"))]
    pub frequency_se_hz: f64,
    /// Jackknife standard error of the damping ratio; NaN with one period.
    #[cfg_attr(feature = "serde", serde(with = "crate::nullable"))]
    pub damping_se: f64,
    /// Each output's residue at the pole, scaled so that the largest is 1: the mode's shape
    /// as the outputs see it.
    pub shape: Vec<Complex64>,
    /// Jackknife standard error of each entry of `shape` over periods, √(E|δ|²) of the
    /// complex entry (each left-out fit's shape scaled by the same entry; 0 for that entry);
    /// NaN with one period.
    #[cfg_attr(feature = "serde", serde(with = "crate::nullable"))]
    pub shape_se: Vec<f64>,
    /// Modal phase collinearity of `shape` ([`covssi::mpc`]): 1 for a real (normal) mode.
    pub mpc: f64,
}

/// The fit of a band of the frequency response.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct FrfFit {
    /// The oscillating poles of the fit inside the band, by frequency.
    pub modes: Vec<FrfMode>,
    /// Whole periods used.
    pub periods: usize,
    /// Frequencies of the excited lines in the band (Hz).
    pub frequency_hz: Vec<f64>,
    /// The input's amplitude at those lines (of its sine component: $2|\bar U|/M$).
    pub input_amplitude: Vec<f64>,
    /// The measured response at those lines, per channel.
    pub response: Vec<Vec<Complex64>>,
    /// The fitted response there, per channel.
    pub fitted: Vec<Vec<Complex64>>,
    /// Weighted residual mean square per real equation (near 1 when the fit is at the noise;
    /// computed with unit weights, and so not comparable to 1, with one period).
    #[cfg_attr(feature = "serde", serde(with = "crate::nullable"))]
    pub misfit: f64,
}

impl FrfFit {
    /// Each channel's RMS within the band, from its measured lines: a line of amplitude
    /// |H|·|U| has mean square |H|²|U|²/2.
    pub fn response_rms(&self) -> Vec<f64> {
        self.response
            .iter()
            .map(|h| {
                h.iter()
                    .zip(&self.input_amplitude)
                    .map(|(h, u)| (h.norm() * u).powi(2) / 2.0)
                    .sum::<f64>()
                    .sqrt()
            })
            .collect()
    }
}

/// Lines whose input amplitude is below this fraction of the largest line's are not excited.
const EXCITED: f64 = 1e-2;
/// An input whose period-to-period differences hold more than this share of its variance is
/// not periodic with the period given. The F-16's measured forces: 1e-6 to 1e-5 at their
/// period, 0.5–0.86 at a wrong one (4096 or 8000 samples for 8192).
const MAX_APERIODIC: f64 = 0.2;
/// The noise variance of a line is averaged over this many lines on either side.
const VARIANCE_LINES: usize = 5;
/// Sanathanan–Koerner iterations at most, and the relative change of the denominator that
/// ends them.
const SK_ITERATIONS: usize = 50;
const SK_TOL: f64 = 1e-12;

/// The modes of the band `low_hz..high_hz` of the record's frequency response, `modes` (≥ 1)
/// of them fitted at once (see the module documentation). Only the oscillating, stable poles
/// inside the band are returned, so there may be fewer than `modes`.
pub fn modes_from_frf(
    rec: &PeriodicRecord<'_>,
    band: (f64, f64),
    modes: usize,
) -> Result<FrfFit, IdentError> {
    if modes == 0 {
        return Err(IdentError::NoModesAsked);
    }
    fit_band(&Spectra::of(rec)?.band(band)?, band, modes)
}

/// [`modes_from_frf`] on the record's spectra at the band's lines.
fn fit_band(spectra: &Spectra, band: (f64, f64), modes: usize) -> Result<FrfFit, IdentError> {
    // Saturating: a count of modes beyond any record is "too few lines", not a wrapped number.
    let q = modes.saturating_mul(2);
    let needed = spectra
        .outputs
        .len()
        .saturating_mul(q.saturating_add(1))
        .saturating_add(q);
    // Two real equations per line and channel.
    let equations = 2 * spectra.lines.len() * spectra.outputs.len();
    if equations < needed.saturating_add(2) {
        return Err(IdentError::FewLines {
            low_hz: band.0,
            high_hz: band.1,
            lines: spectra.lines.len(),
            needed: needed.saturating_add(2).div_ceil(2 * spectra.outputs.len()),
        });
    }
    let p = spectra.periods;
    let all: Vec<usize> = (0..p).collect();
    let (h, sigma) = spectra.response(&all);
    let x = spectra.scaled();
    let fit = sk_fit(&x, &h, &sigma, q).ok_or(IdentError::ResponseFitFailed {
        low_hz: band.0,
        high_hz: band.1,
    })?;
    let centre = spectra.omega0;
    let poles: Vec<C> = roots(&fit.den)
        .into_iter()
        .map(|r| r * centre)
        .filter(|l| l.im > 0.0 && l.re < 0.0)
        .filter(|l| {
            let f = l.norm() / std::f64::consts::TAU;
            f >= band.0 && f <= band.1
        })
        .collect();
    let mut out: Vec<FrfMode> = poles
        .iter()
        .map(|l| {
            let shape = residues_at(&fit, *l / centre, None);
            FrfMode {
                frequency_hz: l.norm() / std::f64::consts::TAU,
                damping_ratio: -l.re / l.norm(),
                frequency_se_hz: f64::NAN,
                damping_se: f64::NAN,
                shape_se: vec![f64::NAN; shape.len()],
                mpc: covssi::mpc(&shape),
                shape,
            }
        })
        .collect();
    if p >= 2 {
        // Leave one period out; match each mode to the nearest pole of that fit.
        let mut f_j = vec![Vec::with_capacity(p); out.len()];
        let mut z_j = vec![Vec::with_capacity(p); out.len()];
        let mut s_j = vec![Vec::with_capacity(p); out.len()];
        // Each left-out fit's shape is scaled by the entry the whole fit's has at 1.
        let at: Vec<usize> = out.iter().map(|m| reference_entry(&m.shape)).collect();
        for leave in 0..p {
            let keep: Vec<usize> = (0..p).filter(|&i| i != leave).collect();
            let (hj, sj) = spectra.response(&keep);
            let Some(fj) = sk_fit(&x, &hj, &sj, q) else {
                continue;
            };
            let pj: Vec<C> = roots(&fj.den).into_iter().map(|r| r * centre).collect();
            for (m, l) in poles.iter().enumerate() {
                if let Some(best) = pj
                    .iter()
                    .filter(|v| v.im > 0.0)
                    .min_by(|a, b| (*a - l).norm().total_cmp(&(*b - l).norm()))
                {
                    f_j[m].push(best.norm() / std::f64::consts::TAU);
                    z_j[m].push(-best.re / best.norm());
                    s_j[m].push(residues_at(&fj, *best / centre, Some(at[m])));
                }
            }
        }
        for (m, mode) in out.iter_mut().enumerate() {
            mode.frequency_se_hz = jackknife_se(&f_j[m]);
            mode.damping_se = jackknife_se(&z_j[m]);
            mode.shape_se = (0..mode.shape.len())
                .map(|c| {
                    let re: Vec<f64> = s_j[m].iter().map(|s| s[c].re).collect();
                    let im: Vec<f64> = s_j[m].iter().map(|s| s[c].im).collect();
                    jackknife_se(&re).hypot(jackknife_se(&im))
                })
                .collect();
        }
    }
    out.sort_by(|a, b| a.frequency_hz.total_cmp(&b.frequency_hz));
    let fitted: Vec<Vec<C>> = fit
        .num
        .iter()
        .map(|b| {
            x.iter()
                .map(|&s| horner(b, s) / monic(&fit.den, s))
                .collect()
        })
        .collect();
    Ok(FrfFit {
        modes: out,
        periods: p,
        frequency_hz: spectra.lines.iter().map(|&k| spectra.hz(k)).collect(),
        input_amplitude: (0..spectra.lines.len())
            .map(|i| {
                let u = spectra.u.iter().map(|u| u[i]).sum::<C>() / p as f64;
                2.0 * u.norm() / spectra.period as f64
            })
            .collect(),
        response: h,
        fitted,
        misfit: fit.misfit,
    })
}

/// How far a mode of a fit moves with the band: the band's share of the uncertainty, which
/// the standard errors (the noise alone) do not hold when the misfit is far above 1.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct BandSpread {
    /// The largest change of the frequency (Hz).
    #[cfg_attr(feature = "serde", serde(with = "crate::nullable"))]
    pub frequency_hz: f64,
    /// The largest change of the damping ratio.
    #[cfg_attr(feature = "serde", serde(with = "crate::nullable"))]
    pub damping: f64,
}

/// For each mode of `fit` (made by [`modes_from_frf`] over `band` with `modes` modes), the
/// largest move of its nearest mode when the same fit is made over the band narrowed and
/// widened by a tenth of its width at each end (widened within 0..Nyquist). NaN when either
/// of those fits fails or finds no mode.
pub fn band_spread(
    rec: &PeriodicRecord<'_>,
    band: (f64, f64),
    modes: usize,
    fit: &FrfFit,
) -> Vec<BandSpread> {
    let width = band.1 - band.0;
    // The record is transformed once for both bands.
    let full = Spectra::of(rec).ok();
    let others: Vec<Option<FrfFit>> = [
        (band.0 + 0.1 * width, band.1 - 0.1 * width),
        (
            (band.0 - 0.1 * width).max(0.0),
            (band.1 + 0.1 * width).min(rec.fs / 2.0),
        ),
    ]
    .iter()
    .map(|&b| {
        let sp = full.as_ref()?.band(b).ok()?;
        (modes > 0).then(|| fit_band(&sp, b, modes).ok()).flatten()
    })
    .collect();
    fit.modes
        .iter()
        .map(|m| {
            let mut d = BandSpread {
                frequency_hz: 0.0,
                damping: 0.0,
            };
            for o in &others {
                let near = o.as_ref().and_then(|o| {
                    o.modes.iter().min_by(|x, y| {
                        (x.frequency_hz - m.frequency_hz)
                            .abs()
                            .total_cmp(&(y.frequency_hz - m.frequency_hz).abs())
                    })
                });
                let Some(n) = near else {
                    return BandSpread {
                        frequency_hz: f64::NAN,
                        damping: f64::NAN,
                    };
                };
                d.frequency_hz = d.frequency_hz.max((n.frequency_hz - m.frequency_hz).abs());
                d.damping = d.damping.max((n.damping_ratio - m.damping_ratio).abs());
            }
            d
        })
        .collect()
}

/// The outputs as they would be under an input of flat amplitude spectrum: in each period,
/// every line the input excites is scaled by (the input's mean line amplitude) / (its
/// amplitude at that line, averaged over periods), and the other lines are zeroed. Output-only
/// methods assume a flat (white) excitation; comparing their estimates on these outputs with
/// those on the measured ones shows what the input's colour (a shaker's force drop-out at a
/// resonance, say) does to them. A diagnostic, not an estimator: it needs the input. The
/// outputs returned hold the record's whole periods.
pub fn outputs_under_flat_input(rec: &PeriodicRecord<'_>) -> Result<Vec<Vec<f64>>, IdentError> {
    let sp = Spectra::of(rec)?;
    if sp.lines.is_empty() {
        return Err(IdentError::FewLines {
            low_hz: 0.0,
            high_hz: rec.fs / 2.0,
            lines: 0,
            needed: 1,
        });
    }
    let n = sp.periods as f64;
    let amp: Vec<f64> = (0..sp.lines.len())
        .map(|i| sp.u.iter().map(|u| u[i].norm()).sum::<f64>() / n)
        .collect();
    let mean = amp.iter().sum::<f64>() / amp.len() as f64;
    let m = sp.period;
    Ok(sp
        .outputs
        .iter()
        .map(|y| {
            let mut out = Vec::with_capacity(sp.periods * m);
            for yp in y {
                let mut full = vec![C::new(0.0, 0.0); m / 2 + 1];
                for (i, &k) in sp.lines.iter().enumerate() {
                    full[k] = yp[i] * (mean / amp[i]);
                }
                out.extend(crate::fft::irfft(&full, m));
            }
            out
        })
        .collect())
}

/// The share of the input's variance (about its mean) that differs from period to period,
/// $\sum_{p,n}(u_p[n] - \bar u[n])^2 / \sum_{p,n}(u_p[n] - \bar u)^2$; 0 with one period.
fn aperiodic_fraction(u: &[f64], m: usize) -> f64 {
    let periods = u.len() / m;
    if periods < 2 {
        return 0.0;
    }
    let mean = u.iter().sum::<f64>() / u.len() as f64;
    let (mut num, mut den) = (0.0, 0.0);
    for n in 0..m {
        let ubar = (0..periods).map(|p| u[p * m + n]).sum::<f64>() / periods as f64;
        for p in 0..periods {
            num += (u[p * m + n] - ubar).powi(2);
            den += (u[p * m + n] - mean).powi(2);
        }
    }
    if den > 0.0 { num / den } else { 0.0 }
}

/// The index of a shape's largest entry.
fn reference_entry(shape: &[Complex64]) -> usize {
    (0..shape.len())
        .max_by(|&a, &b| shape[a].norm().total_cmp(&shape[b].norm()))
        .unwrap_or(0)
}

/// The channels' residues at the scaled root `r` of a fit, scaled so that entry `at` (by
/// default the largest) is 1. The residues N_c(r)/D'(r) share D'(r), so the shape is N_c(r).
fn residues_at(fit: &Rational, r: C, at: Option<usize>) -> Vec<Complex64> {
    let residues: Vec<Complex64> = fit
        .num
        .iter()
        .map(|b| {
            let v = horner(b, r);
            Complex64::new(v.re, v.im)
        })
        .collect();
    let scale = residues[at.unwrap_or_else(|| reference_entry(&residues))];
    if scale.norm() == 0.0 {
        return residues;
    }
    residues.iter().map(|v| v / scale).collect()
}

fn jackknife_se(v: &[f64]) -> f64 {
    let n = v.len() as f64;
    if v.len() < 2 {
        return f64::NAN;
    }
    let mean = v.iter().sum::<f64>() / n;
    ((n - 1.0) / n * v.iter().map(|x| (x - mean).powi(2)).sum::<f64>()).sqrt()
}

/// The periods' spectra at the excited lines (all of them, or a band's).
struct Spectra {
    /// Input spectrum per period, at `lines`.
    u: Vec<Vec<C>>,
    /// Output spectra per channel, per period, at `lines`.
    outputs: Vec<Vec<Vec<C>>>,
    lines: Vec<usize>,
    periods: usize,
    fs: f64,
    period: usize,
    omega0: f64,
}

impl Spectra {
    /// The validated record's spectra at every line the input excites, up to Nyquist.
    fn of(rec: &PeriodicRecord<'_>) -> Result<Self, IdentError> {
        let (fs, m) = (rec.fs, rec.period);
        if !(fs.is_finite() && fs > 0.0) {
            return Err(IdentError::BadRate { fs });
        }
        if rec.outputs.is_empty() {
            return Err(IdentError::NoOutputs);
        }
        for out in rec.outputs {
            if out.len() != rec.input.len() {
                return Err(IdentError::LengthMismatch {
                    input: rec.input.len(),
                    output: out.len(),
                });
            }
        }
        if m < 4 || rec.input.len() < m {
            return Err(IdentError::TooShort {
                samples: rec.input.len(),
                needed: m.max(4),
            });
        }
        for (channel, x) in std::iter::once(rec.input)
            .chain(rec.outputs.iter().copied())
            .enumerate()
        {
            if let Some((index, &value)) = x.iter().enumerate().find(|(_, v)| !v.is_finite()) {
                return Err(IdentError::NonFiniteSample {
                    channel,
                    index,
                    value,
                });
            }
            // Spectra and variances square the values and sum them over a record.
            if let Some((index, &value)) = x.iter().enumerate().find(|(_, v)| v.abs() > 1e150) {
                return Err(IdentError::SampleTooLarge {
                    channel,
                    index,
                    value,
                });
            }
        }
        let periods = rec.input.len() / m;
        let aperiodic = aperiodic_fraction(&rec.input[..periods * m], m);
        if aperiodic > MAX_APERIODIC {
            return Err(IdentError::NotPeriodic {
                period: m,
                fraction: aperiodic,
            });
        }
        let spectra_of = |x: &[f64]| -> Vec<Vec<C>> {
            (0..periods).map(|p| rfft(&x[p * m..(p + 1) * m])).collect()
        };
        let u_all = spectra_of(rec.input);
        let mean_amp = |k: usize| (u_all.iter().map(|u| u[k]).sum::<C>() / periods as f64).norm();
        // Excited relative to the strongest line anywhere (not DC); a line is at rounding
        // level when below 1e-9 of the bound Σ|u| of a period's DFT (a constant input).
        let top = (1..=m / 2).map(mean_amp).fold(0.0, f64::max);
        let bound = rec.input[..m].iter().map(|v| v.abs()).sum::<f64>();
        let lines: Vec<usize> = if top > 1e-9 * bound {
            (1..=m / 2)
                .filter(|&k| mean_amp(k) >= EXCITED * top)
                .collect()
        } else {
            Vec::new()
        };
        let pick = |s: Vec<Vec<C>>| -> Vec<Vec<C>> {
            s.into_iter()
                .map(|v| lines.iter().map(|&k| v[k]).collect())
                .collect()
        };
        let outputs = rec.outputs.iter().map(|y| pick(spectra_of(y))).collect();
        Ok(Spectra {
            u: pick(u_all),
            outputs,
            lines,
            periods,
            fs,
            period: m,
            omega0: std::f64::consts::PI * fs / 2.0,
        })
    }

    /// The lines within `band`, with $\omega_0$ at its centre.
    fn band(&self, band: (f64, f64)) -> Result<Self, IdentError> {
        let nyquist = self.fs / 2.0;
        if !(band.0.is_finite()
            && band.1.is_finite()
            && band.0 >= 0.0
            && band.0 < band.1
            && band.1 <= nyquist)
        {
            return Err(IdentError::BandOutOfRange {
                low_hz: band.0,
                high_hz: band.1,
                nyquist_hz: nyquist,
            });
        }
        let keep: Vec<usize> = (0..self.lines.len())
            .filter(|&i| {
                let f = self.hz(self.lines[i]);
                f >= band.0 && f <= band.1
            })
            .collect();
        let pick = |s: &[Vec<C>]| -> Vec<Vec<C>> {
            s.iter()
                .map(|v| keep.iter().map(|&i| v[i]).collect())
                .collect()
        };
        Ok(Spectra {
            u: pick(&self.u),
            outputs: self.outputs.iter().map(|y| pick(y)).collect(),
            lines: keep.iter().map(|&i| self.lines[i]).collect(),
            periods: self.periods,
            fs: self.fs,
            period: self.period,
            omega0: std::f64::consts::PI * (band.0 + band.1),
        })
    }

    fn hz(&self, k: usize) -> f64 {
        k as f64 * self.fs / self.period as f64
    }

    /// $s = i\omega/\omega_0$ at the lines.
    fn scaled(&self) -> Vec<C> {
        self.lines
            .iter()
            .map(|&k| C::new(0.0, std::f64::consts::TAU * self.hz(k) / self.omega0))
            .collect()
    }

    /// The averaged response over `periods` and its standard deviation per line (ones when
    /// there is a single period).
    fn response(&self, periods: &[usize]) -> (Vec<Vec<C>>, Vec<Vec<f64>>) {
        let n = periods.len() as f64;
        let ubar: Vec<C> = (0..self.lines.len())
            .map(|i| periods.iter().map(|&p| self.u[p][i]).sum::<C>() / n)
            .collect();
        let mut h = Vec::with_capacity(self.outputs.len());
        let mut sd = Vec::with_capacity(self.outputs.len());
        for y in &self.outputs {
            let hc: Vec<C> = (0..self.lines.len())
                .map(|i| periods.iter().map(|&p| y[p][i]).sum::<C>() / n / ubar[i])
                .collect();
            let sc: Vec<f64> = (0..self.lines.len())
                .map(|i| {
                    if periods.len() < 2 {
                        return 1.0;
                    }
                    let ss: f64 = periods
                        .iter()
                        .map(|&p| (y[p][i] - hc[i] * self.u[p][i]).norm_sqr())
                        .sum();
                    (ss / ((n - 1.0) * n * ubar[i].norm_sqr())).sqrt()
                })
                .collect();
            // The variance of one line from P periods is itself uncertain (2(P − 1) degrees of
            // freedom: ±58 % from 4 periods), and weights that scatter that much move the fit
            // wherever the model does not match the response exactly; the noise's variance
            // changes slowly with frequency, so it is averaged over neighbouring lines.
            let sc = smooth_variance(&sc, VARIANCE_LINES);
            // Identical periods (a simulated record) have no spread, or rounding: the weights
            // stay finite at 1e-12 of the response's RMS.
            let rms =
                (hc.iter().map(|v| v.norm_sqr()).sum::<f64>() / hc.len().max(1) as f64).sqrt();
            let floor = (1e-12 * rms).max(f64::MIN_POSITIVE);
            let sc = sc.into_iter().map(|v| v.max(floor)).collect();
            h.push(hc);
            sd.push(sc);
        }
        (h, sd)
    }
}

struct Rational {
    /// Denominator coefficients a_0..a_{q-1} (monic, degree q).
    den: Vec<f64>,
    /// Numerator coefficients b_0..b_q per channel.
    num: Vec<Vec<f64>>,
    misfit: f64,
}

fn horner(c: &[f64], s: C) -> C {
    c.iter().rev().fold(C::new(0.0, 0.0), |acc, &v| acc * s + v)
}

/// $s^q + \sum_{j<q} a_j s^j$.
fn monic(a: &[f64], s: C) -> C {
    let lead = s.powu(a.len() as u32);
    lead + horner(a, s)
}

/// Sanathanan–Koerner: weighted linear least squares, reweighted by the last denominator.
/// Standard deviations whose variances are averaged over `half` lines on either side (fewer
/// at the ends).
fn smooth_variance(sd: &[f64], half: usize) -> Vec<f64> {
    let n = sd.len();
    (0..n)
        .map(|i| {
            let (a, b) = (i.saturating_sub(half), (i + half + 1).min(n));
            (sd[a..b].iter().map(|v| v * v).sum::<f64>() / (b - a) as f64).sqrt()
        })
        .collect()
}

/// `None` when the problem stops being finite (a denominator vanishing at a line).
fn sk_fit(x: &[C], h: &[Vec<C>], sd: &[Vec<f64>], q: usize) -> Option<Rational> {
    let channels = h.len();
    let k = x.len();
    let n_par = q + channels * (q + 1);
    let mut den = vec![0.0; q];
    let mut prev = vec![C::new(1.0, 0.0); k];
    let mut num = vec![vec![0.0; q + 1]; channels];
    for _ in 0..SK_ITERATIONS {
        let rows = 2 * channels * k;
        let mut a = DMatrix::<f64>::zeros(rows, n_par);
        let mut rhs = DVector::<f64>::zeros(rows);
        for c in 0..channels {
            for i in 0..k {
                let w = 1.0 / (sd[c][i].max(f64::MIN_POSITIVE) * prev[i].norm());
                let r = 2 * (c * k + i);
                let mut pow = C::new(1.0, 0.0);
                for j in 0..=q {
                    let col_num = q + c * (q + 1) + j;
                    a[(r, col_num)] = w * pow.re;
                    a[(r + 1, col_num)] = w * pow.im;
                    if j < q {
                        let t = -h[c][i] * pow;
                        a[(r, j)] = w * t.re;
                        a[(r + 1, j)] = w * t.im;
                    } else {
                        let t = h[c][i] * pow;
                        rhs[r] = w * t.re;
                        rhs[r + 1] = w * t.im;
                    }
                    pow *= x[i];
                }
            }
        }
        // Column scaling keeps the normal equations' conditioning in check.
        let scale: Vec<f64> = (0..n_par)
            .map(|j| a.column(j).norm().max(f64::MIN_POSITIVE))
            .collect();
        for (j, s) in scale.iter().enumerate() {
            a.column_mut(j).scale_mut(1.0 / s);
        }
        // nalgebra's SVD does not return on non-finite input.
        if !(a.iter().all(|v| v.is_finite()) && rhs.iter().all(|v| v.is_finite())) {
            return None;
        }
        let sol = a
            .svd(true, true)
            .solve(&rhs, 1e-14)
            .expect("U and V were computed");
        let theta: Vec<f64> = sol.iter().zip(&scale).map(|(v, s)| v / s).collect();
        let new_den = theta[..q].to_vec();
        for (c, b) in num.iter_mut().enumerate() {
            b.copy_from_slice(&theta[q + c * (q + 1)..q + (c + 1) * (q + 1)]);
        }
        let change = new_den
            .iter()
            .zip(&den)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
            / new_den.iter().map(|v| v.abs()).fold(1e-300, f64::max);
        den = new_den;
        prev = x.iter().map(|&s| monic(&den, s)).collect();
        if change < SK_TOL {
            break;
        }
    }
    // The misfit of the rational model itself (not of its linearization).
    let mut ss = 0.0;
    for c in 0..channels {
        for i in 0..k {
            let e = horner(&num[c], x[i]) / prev[i] - h[c][i];
            ss += e.norm_sqr() / sd[c][i].max(f64::MIN_POSITIVE).powi(2);
        }
    }
    let dof = (2 * channels * k).saturating_sub(n_par).max(1);
    Some(Rational {
        den,
        num,
        misfit: ss / dof as f64,
    })
}

/// The roots of $s^q + \sum_{j<q} a_j s^j$ ([`hyst_model::poly::roots`], the workspace's one
/// root finder).
fn roots(a: &[f64]) -> Vec<C> {
    let coeffs: Vec<f64> = std::iter::once(1.0)
        .chain(a.iter().rev().copied())
        .collect();
    hyst_model::poly::roots(&coeffs)
        .into_iter()
        .map(|z| C::new(z.re, z.im))
        .collect()
}

mod report;
pub use report::{FrfReport, frf_report};

#[cfg(test)]
mod tests;
