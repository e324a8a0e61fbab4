//! Frequency-domain decomposition (FDD) and its enhanced form (EFDD): a second opinion beside
//! SSI, from the output spectral matrix alone.
//!
//! 1. **Spectral matrix.** Welch's estimate: segments of $N_s$ samples overlapping by half,
//!    each channel's mean removed and a Hann window applied,
//!    $G(f_k) = \frac{1}{K}\sum_{\text{segments}} X(f_k) X(f_k)^H$ (one-sided, the scale
//!    common to every line, which FDD does not need).
//! 2. **FDD.** At every line $G(f_k) = U S U^H$ (Hermitian eigen-decomposition): the
//!    singular values $s_1 \ge s_2 \ge \dots$ drawn against frequency; near a mode its
//!    $s_1$ peaks and $u_1$ at the peak is the mode's shape ([`Fdd::mode_near`]).
//! 3. **EFDD.** Around the peak, the lines whose $u_1$ has a MAC of at least
//!    [`FddOptions::mac_threshold`] with the peak's (contiguous, the peak's own bell) keep
//!    their $s_1$, the others are set to 0: the mode's single-degree-of-freedom spectral
//!    bell. Its inverse transform is the mode's free decay (its autocorrelation,
//!    $\propto e^{-\zeta\omega_n t}\cos\omega_d t$). The damped frequency is the slope of its
//!    zero-crossing times ($\tfrac{1}{2 f_d}$ apart); the logarithmic decrement $\delta$ is
//!    the slope of $\ln$ of its extrema's magnitudes over half-periods (between
//!    [`FddOptions::decay_window`] of the first extremum), $\zeta = \delta/\sqrt{\pi^2+\delta^2}$
//!    per half-period, $f_n = f_d/\sqrt{1-\zeta^2}$ ([`efdd`]).
//! 4. **EFDD of a known mode.** Where modes are close, one peak of $s_1$ serves both, and
//!    [`efdd`] gives them one answer. [`efdd_of_mode`] starts from the mode's own shape
//!    (SSI's): at each line the leading singular vector $u_j$ ($j \le$ [`LEADING`]) most
//!    alike it, if its MAC reaches the threshold, keeps its $s_j$; the bell is those lines
//!    around the largest such $s_j$ — the mode's own bell, even where it is the second
//!    singular value. Two modes whose shapes are themselves alike cannot be told apart this
//!    way, and the caller says so.
//!
//! ```
//! use covssi::fdd::{FddOptions, efdd, fdd};
//! use covssi::synth::ModalRecord;
//! let y = ModalRecord::new(20.0, &[(1.5, 0.02)]).generate(65536, 3);
//! let views: Vec<&[f64]> = y.iter().map(|c| c.as_slice()).collect();
//! let spectra = fdd(&views, 20.0, &FddOptions::default()).unwrap();
//! let mode = efdd(&spectra, 1.5, &FddOptions::default()).unwrap();
//! assert!((mode.frequency_hz - 1.5).abs() < 0.01);
//! assert!((mode.damping_ratio - 0.02).abs() < 0.006);
//! ```

use realfft::RealFftPlanner;

use crate::linalg::{C64, hermitian_eigen};
use crate::{SsiError, SsiOption};

/// Options of [`fdd`] and [`efdd`].
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct FddOptions {
    /// Samples per Welch segment; default: the record's length over 16, as a power of two,
    /// 256 to 16 384 (a finer line spacing for a longer record, so that a lightly damped
    /// mode's bell spans several lines).
    pub segment: Option<usize>,
    /// EFDD: least MAC with the peak's shape for a line to belong to the mode's bell.
    /// Default 0.8.
    pub mac_threshold: f64,
    /// EFDD: the decay is fitted over the extrema between these fractions of the first
    /// extremum's magnitude. Default (0.9, 0.3).
    pub decay_window: (f64, f64),
}

impl Default for FddOptions {
    fn default() -> Self {
        FddOptions {
            segment: None,
            mac_threshold: 0.8,
            decay_window: (0.9, 0.3),
        }
    }
}

/// The singular values of the output spectral matrix against frequency, and the first
/// singular vector at each line.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Fdd {
    /// Line frequencies (Hz), 0 to Nyquist.
    pub frequencies_hz: Vec<f64>,
    /// Per line, the singular values, largest first (one per channel).
    pub singular_values: Vec<Vec<f64>>,
    /// Per line, the first singular vector (unit norm, its largest entry real positive).
    pub first_vectors: Vec<Vec<C64>>,
    /// Per line, the leading singular vectors (at most [`LEADING`], phased as the first).
    pub leading_vectors: Vec<Vec<Vec<C64>>>,
    /// Samples per segment used.
    pub segment: usize,
    /// Segments averaged.
    pub segments: usize,
}

/// A mode as FDD reads it: the peak of the first singular value.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct FddMode {
    /// The peak's frequency (Hz): the line's (refined by a parabola through the peak and
    /// its neighbours in log s₁).
    pub frequency_hz: f64,
    /// The first singular vector at the peak line.
    pub shape: Vec<C64>,
    /// The peak's line index.
    pub line: usize,
}

/// A mode as EFDD reads it.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct EfddMode {
    /// Natural frequency (Hz).
    pub frequency_hz: f64,
    /// Damping ratio.
    pub damping_ratio: f64,
    /// The shape: FDD's at the peak.
    pub shape: Vec<C64>,
    /// The bell's edges (Hz).
    pub bell_hz: (f64, f64),
    /// Extrema of the decay fitted.
    pub extrema_fitted: usize,
}

/// The spectral matrix of `y` (channels of equal length, sampled at `fs` Hz) by Welch's
/// method and its decomposition at every line (see the [module](self)).
pub fn fdd(y: &[&[f64]], fs: f64, opts: &FddOptions) -> Result<Fdd, SsiError> {
    crate::checks::check_fs(fs)?;
    let (n, means) = crate::checks::check_channels(y)?;
    let segment = match opts.segment {
        Some(s) if s >= 16 && s <= n => s,
        Some(s) => {
            return Err(SsiError::InvalidOption {
                option: SsiOption::FddSegment,
                value: s as f64,
            });
        }
        None => (n / 16).next_power_of_two().clamp(256, 16_384).min(n),
    };
    let l = y.len();
    let lines = segment / 2 + 1;
    let window: Vec<f64> = (0..segment)
        .map(|i| 0.5 - 0.5 * (2.0 * std::f64::consts::PI * i as f64 / segment as f64).cos())
        .collect();
    let mut planner = RealFftPlanner::<f64>::new();
    let fwd = planner.plan_fft_forward(segment);
    let mut buf = fwd.make_input_vec();
    let mut spec = vec![fwd.make_output_vec(); l];
    // G, line by line, column-major l × l.
    let mut g = vec![C64::new(0.0, 0.0); lines * l * l];
    let step = segment / 2;
    let mut segments = 0;
    let mut start = 0;
    while start + segment <= n {
        for (c, ch) in y.iter().enumerate() {
            for (b, (v, w)) in buf
                .iter_mut()
                .zip(ch[start..start + segment].iter().zip(&window))
            {
                *b = (v - means[c]) * w;
            }
            fwd.process(&mut buf, &mut spec[c])
                .map_err(|e| SsiError::LinearAlgebra(e.to_string()))?;
        }
        for k in 0..lines {
            let gk = &mut g[k * l * l..(k + 1) * l * l];
            for b in 0..l {
                for a in 0..l {
                    gk[b * l + a] += spec[a][k] * spec[b][k].conj();
                }
            }
        }
        segments += 1;
        start += step;
    }
    let mut singular_values = Vec::with_capacity(lines);
    let mut first_vectors = Vec::with_capacity(lines);
    let mut leading_vectors = Vec::with_capacity(lines);
    for k in 0..lines {
        let gk: Vec<C64> = g[k * l * l..(k + 1) * l * l]
            .iter()
            .map(|v| v / segments as f64)
            .collect();
        let (values, vectors) = hermitian_eigen(&gk, l).map_err(SsiError::LinearAlgebra)?;
        singular_values.push(values.iter().map(|v| v.max(0.0)).collect());
        first_vectors.push(phased(&vectors[0]));
        leading_vectors.push(vectors.iter().take(LEADING).map(|v| phased(v)).collect());
    }
    Ok(Fdd {
        frequencies_hz: (0..lines).map(|k| k as f64 * fs / segment as f64).collect(),
        singular_values,
        first_vectors,
        leading_vectors,
        segment,
        segments,
    })
}

/// How many leading singular vectors are kept per line for [`efdd_of_mode`]: a mode of a
/// group of up to this many close modes is found among them.
pub const LEADING: usize = 3;

/// `v` rotated so that its largest entry is real and positive.
fn phased(v: &[C64]) -> Vec<C64> {
    let top = v
        .iter()
        .copied()
        .max_by(|a, b| a.norm().total_cmp(&b.norm()))
        .unwrap_or(C64::new(1.0, 0.0));
    let rot = if top.norm() > 0.0 {
        top.conj() / top.norm()
    } else {
        C64::new(1.0, 0.0)
    };
    v.iter().map(|x| x * rot).collect()
}

/// How far (relative) from a mode EFDD looks for its peak and bell.
pub const EFDD_REACH: f64 = 0.05;

impl Fdd {
    /// The lines within `reach` (relative) of `near_hz`, the first and last lines left out
    /// (a peak needs a neighbour each side); `None` with fewer than two lines.
    fn window(&self, near_hz: f64, reach: f64) -> Option<(usize, usize)> {
        let df = self.frequencies_hz.get(1)? - self.frequencies_hz[0];
        let lo = ((near_hz * (1.0 - reach)) / df).floor().max(1.0) as usize;
        let last = self.frequencies_hz.len().saturating_sub(2);
        let hi = (((near_hz * (1.0 + reach)) / df).ceil() as usize).min(last);
        Some((lo, hi))
    }

    /// The first singular value at every line.
    pub fn first(&self) -> Vec<f64> {
        self.singular_values.iter().map(|s| s[0]).collect()
    }

    /// The peak of the first singular value within `tolerance` (relative) of `near_hz`, or
    /// `None` when the largest value there is at the window's edge (no peak inside).
    pub fn mode_near(&self, near_hz: f64, tolerance: f64) -> Option<FddMode> {
        let s1 = self.first();
        let (lo, hi) = self.window(near_hz, tolerance)?;
        let df = self.frequencies_hz[1] - self.frequencies_hz[0];
        if lo >= hi {
            return None;
        }
        let k = (lo..=hi).max_by(|&a, &b| s1[a].total_cmp(&s1[b]))?;
        if s1[k] <= s1[k - 1] || s1[k] < s1[k + 1] {
            return None;
        }
        // A parabola through the log of the peak and its neighbours.
        let (a, b, c) = (s1[k - 1].ln(), s1[k].ln(), s1[k + 1].ln());
        let denom = a - 2.0 * b + c;
        let shift = if denom < 0.0 {
            0.5 * (a - c) / denom
        } else {
            0.0
        };
        Some(FddMode {
            frequency_hz: (k as f64 + shift.clamp(-0.5, 0.5)) * df,
            shape: self.first_vectors[k].clone(),
            line: k,
        })
    }
}

/// EFDD's mode near `near_hz` (the peak of s₁ within 5 % of it; see the [module](self)),
/// or `None` when there is no peak there or its decay has too few extrema to fit.
pub fn efdd(fdd: &Fdd, near_hz: f64, opts: &FddOptions) -> Option<EfddMode> {
    let peak = fdd.mode_near(near_hz, EFDD_REACH)?;
    let n_lines = fdd.frequencies_hz.len();
    let alike = |k: usize| crate::mac(&fdd.first_vectors[k], &peak.shape) >= opts.mac_threshold;
    let mut lo = peak.line;
    while lo > 1 && alike(lo - 1) {
        lo -= 1;
    }
    let mut hi = peak.line;
    while hi + 2 < n_lines && alike(hi + 1) {
        hi += 1;
    }
    let values: Vec<f64> = fdd.singular_values[lo..=hi].iter().map(|s| s[0]).collect();
    decay_of_bell(fdd, lo, &values, peak.shape, opts)
}

/// EFDD of the mode of shape `shape` near `near_hz` (within 5 %): its own bell among the
/// leading singular values (see the [module](self), step 4); `None` when no line there has a
/// leading vector alike the shape, or the decay has too few extrema to fit.
pub fn efdd_of_mode(fdd: &Fdd, near_hz: f64, shape: &[C64], opts: &FddOptions) -> Option<EfddMode> {
    let n_lines = fdd.frequencies_hz.len();
    // At each line, the leading singular vector that is the shape's (if any is) and its value.
    let own = |k: usize| -> Option<(usize, f64)> {
        let (j, mac) = fdd.leading_vectors[k]
            .iter()
            .map(|v| crate::mac(v, shape))
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(&b.1))?;
        (mac >= opts.mac_threshold).then(|| (j, fdd.singular_values[k][j]))
    };
    let (lo, hi) = fdd.window(near_hz, EFDD_REACH)?;
    let (peak, (best, _)) = (lo..=hi)
        .filter_map(|k| own(k).map(|o| (k, o)))
        .max_by(|a, b| a.1.1.total_cmp(&b.1.1))?;
    let mut first = peak;
    while first > 1 && own(first - 1).is_some() {
        first -= 1;
    }
    let mut last = peak;
    while last + 2 < n_lines && own(last + 1).is_some() {
        last += 1;
    }
    let values: Vec<f64> = (first..=last)
        .map(|k| own(k).map_or(0.0, |(_, s)| s))
        .collect();
    let best = fdd.leading_vectors[peak].get(best)?.clone();
    decay_of_bell(fdd, first, &values, best, opts)
}

/// EFDD's decay fit of a bell of `values` from line `lo` (see the [module](self), step 3),
/// the mode's shape `shape`.
fn decay_of_bell(
    fdd: &Fdd,
    lo: usize,
    values: &[f64],
    shape: Vec<C64>,
    opts: &FddOptions,
) -> Option<EfddMode> {
    let n_lines = fdd.frequencies_hz.len();
    let hi = lo + values.len().checked_sub(1)?;
    // The bell as a one-sided spectrum; its inverse transform is the decay.
    let m = 2 * (n_lines - 1);
    let mut planner = RealFftPlanner::<f64>::new();
    let inv = planner.plan_fft_inverse(m);
    let mut bell = inv.make_input_vec();
    for (b, s) in bell[lo..=hi].iter_mut().zip(values) {
        *b = C64::new(*s, 0.0);
    }
    let mut decay = inv.make_output_vec();
    inv.process(&mut bell, &mut decay).ok()?;
    let df = fdd.frequencies_hz[1];
    let dt = 1.0 / (m as f64 * df);
    let half = &decay[..m / 2];
    let (crossings, extrema) = crossings_and_extrema(half);
    let first = extrema.first()?.1.abs();
    let (upper, lower) = opts.decay_window;
    let fitted: Vec<(f64, f64)> = extrema
        .iter()
        .take_while(|e| e.1.abs() >= lower * first)
        .filter(|e| e.1.abs() <= upper * first)
        .map(|e| (e.0, e.1.abs().ln()))
        .collect();
    if fitted.len() < 3 || crossings.len() < 3 {
        return None;
    }
    // Extrema are half a period apart: the slope of ln|extremum| against their index is
    // the decrement per half-period.
    let index: Vec<(f64, f64)> = fitted
        .iter()
        .enumerate()
        .map(|(i, e)| (i as f64, e.1))
        .collect();
    let delta_half = -slope(&index);
    let zeta = delta_half / (std::f64::consts::PI.powi(2) + delta_half.powi(2)).sqrt();
    // Crossings within the fitted stretch, half a damped period apart.
    let last = fitted.last()?.0;
    let cross: Vec<(f64, f64)> = crossings
        .iter()
        .filter(|&&t| t <= last)
        .enumerate()
        .map(|(i, &t)| (i as f64, t * dt))
        .collect();
    let half_period = slope(if cross.len() >= 3 { &cross } else { &[] });
    if !(half_period > 0.0 && zeta.is_finite() && zeta > 0.0 && zeta < 1.0) {
        return None;
    }
    let fd = 0.5 / half_period;
    Some(EfddMode {
        frequency_hz: fd / (1.0 - zeta * zeta).sqrt(),
        damping_ratio: zeta,
        shape,
        bell_hz: (fdd.frequencies_hz[lo], fdd.frequencies_hz[hi]),
        extrema_fitted: fitted.len(),
    })
}

/// The decay's zero crossings (fractional sample, by linear interpolation) and its extrema
/// (sample index as f64, value) between successive crossings, the first from sample 0.
fn crossings_and_extrema(x: &[f64]) -> (Vec<f64>, Vec<(f64, f64)>) {
    let mut crossings = Vec::new();
    let mut extrema = Vec::new();
    let mut best = (0.0, x.first().copied().unwrap_or(0.0));
    for i in 1..x.len() {
        if x[i].abs() > best.1.abs() && x[i].signum() == best.1.signum() {
            best = (i as f64, x[i]);
        }
        if x[i - 1] != 0.0 && x[i - 1].signum() != x[i].signum() {
            crossings.push(i as f64 - 1.0 + x[i - 1] / (x[i - 1] - x[i]));
            extrema.push(best);
            best = (i as f64, x[i]);
        }
    }
    (crossings, extrema)
}

/// Least-squares slope of y on x.
fn slope(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    if n < 2.0 {
        return f64::NAN;
    }
    let mx = points.iter().map(|p| p.0).sum::<f64>() / n;
    let my = points.iter().map(|p| p.1).sum::<f64>() / n;
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
    sxy / sxx
}
