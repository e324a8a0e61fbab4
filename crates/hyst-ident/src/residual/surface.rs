//! Trace the residual to its force: the restoring-force surface of what a model misses
//! (Masri and Caughey, 1979).
//!
//! With the mass and the input known, the force the model lacks is, row by row,
//!
//! $$ r(t) = u - m\ddot x - c\dot x - kx - z - f_{extra}(x, \dot x) - f_{2}, $$
//!
//! with $x$ the measured output and $\dot x$, $\ddot x$ its derivatives taken in the frequency
//! domain (the record mirrored to make it periodic without a jump, multiplied by $i\omega$
//! and $-\omega^2$ up to a cut-off above the input's band, rolled off over its last 10 %;
//! the rows within 2 % of each end, where the mirror's kink rings, are left out). The model's
//! internal states (its hysteretic or Zener force $z$, a second mass's motion giving $f_2$)
//! are integrated along the measured motion, and the trace of the model's own simulated
//! output (the method's artefacts, where nothing is missing) is subtracted ([`trace`]).
//!
//! Drawn over the phase plane $(x, \dot x)$, $r$ is a surface; its two sections show a
//! stiffness curve ($r$ against $x$ where $\dot x \approx 0$) and a damping curve ($r$
//! against $\dot x$ where $x \approx 0$). Its shape names the effect: fitted by least squares
//! on the basis of [`hyst_model::ForceSurface`] (with $x$, $\dot x$, a constant and, when the
//! mass is fitted, $\ddot x$ for the model's own linear terms, and $\tau x$, $\tau\dot x$ with $\tau$
//! running from −1 to 1 over the rows, for a stiffness or damping that changes over the
//! record), each group of terms is tested by a Wald test whose covariance is estimated from
//! blocks of rows ([`BLOCK_ROWS`]), so that the noise that differentiation colours does not
//! make every group look significant.

use hyst_model::{ForceSurface, Oscillator, SURFACE_TERMS, State};
use nalgebra::{DMatrix, DVector};
use statrs::distribution::{ChiSquared, ContinuousCDF};

use super::Record;
use crate::fft::{C, irfft, rfft};

/// Rows per block of the Wald tests' covariance (0.34 s at 750 Hz).
pub const BLOCK_ROWS: usize = 256;

/// Level below which a group of the surface counts as present.
pub const GROUP_SIGNIFICANCE: f64 = 1e-3;

/// The measured motion: displacement, velocity and acceleration on the rows kept.
#[derive(Debug, Clone, PartialEq)]
pub struct Kinematics {
    /// First row kept (absolute).
    pub first_row: usize,
    /// Displacement (the measured output).
    pub x: Vec<f64>,
    /// Velocity.
    pub v: Vec<f64>,
    /// Acceleration.
    pub a: Vec<f64>,
    /// Sampling rate (Hz).
    pub fs: f64,
    /// Frequency above which the derivatives were cut (Hz).
    pub cut_hz: f64,
}

/// The input's band (Hz): the lowest and highest frequencies where its spectrum (Welch,
/// 512-row segments) is above 1e-3 of its peak; (0, fs/2) when it has none.
pub(super) fn input_band(u: &[f64], fs: f64) -> (f64, f64) {
    let (f, s) = crate::welch_psd(u, fs, 512.min(u.len()).max(16));
    let peak = s.iter().cloned().fold(0.0, f64::max);
    let above = |(_, p): &(&f64, &f64)| **p > 1e-3 * peak;
    let lo = f.iter().zip(&s).find(above).map_or(0.0, |(f, _)| *f);
    let hi = f
        .iter()
        .zip(&s)
        .rev()
        .find(above)
        .map_or(fs / 2.0, |(f, _)| *f);
    (lo, hi)
}

/// Derivatives of `y` (rows `range` of the record) in the frequency domain, cut at `cut_hz`.
pub fn kinematics(y: &[f64], fs: f64, range: (usize, usize), cut_hz: f64) -> Kinematics {
    kinematics_of(&y[range.0..range.1], range.0, fs, cut_hz)
}

/// The low-pass of the derivatives: 1 up to 0.9 of `cut_hz`, a raised cosine to 0 at it.
fn taper(f: f64, cut_hz: f64) -> f64 {
    let lo = 0.9 * cut_hz;
    if f <= lo {
        1.0
    } else if f >= cut_hz {
        0.0
    } else {
        0.5 + 0.5 * (std::f64::consts::PI * (f - lo) / (cut_hz - lo)).cos()
    }
}

/// `seg` (sampled at `fs`) differentiated `order` times (0 to 2) in the frequency domain and
/// cut at `cut_hz` ([`taper`]). The segment is extended evenly (mirrored), which makes it
/// periodic with no jump, so the transform has no leakage from its ends.
fn spectral(seg: &[f64], fs: f64, cut_hz: f64, order: u32) -> Vec<f64> {
    let n = seg.len();
    let mut ext = seg.to_vec();
    ext.extend(seg.iter().rev());
    let m = ext.len();
    let df = fs / m as f64;
    let s: Vec<C> = rfft(&ext)
        .iter()
        .enumerate()
        .map(|(k, c)| {
            let f = k as f64 * df;
            let w = 2.0 * std::f64::consts::PI * f;
            let d = match order {
                0 => C::new(1.0, 0.0),
                1 => C::new(0.0, w),
                _ => C::new(-w * w, 0.0),
            };
            c * d * taper(f, cut_hz)
        })
        .collect();
    let mut out = irfft(&s, m);
    out.truncate(n);
    out
}

/// [`kinematics`] of the segment `seg`, whose first row is `first` in the record.
fn kinematics_of(seg: &[f64], first: usize, fs: f64, cut_hz: f64) -> Kinematics {
    let n = seg.len();
    let (x, v, a) = (
        spectral(seg, fs, cut_hz, 0),
        spectral(seg, fs, cut_hz, 1),
        spectral(seg, fs, cut_hz, 2),
    );
    let edge = (n / 50).max(64).min(n / 4);
    let keep = edge..n - edge;
    Kinematics {
        first_row: first + edge,
        x: x[keep.clone()].to_vec(),
        v: v[keep.clone()].to_vec(),
        a: a[keep].to_vec(),
        fs,
        cut_hz,
    }
}

/// The force `o` misses along the measured motion `k` of the record: r = u − m ẍ − the
/// model's forces, its internal states integrated along the measured (x, ẋ) (RK4, four
/// sub-steps per row, the motion linear in between). The model's forces are cut at the
/// derivatives' frequency as ẍ is: a force with corners (a hysteretic element reversing)
/// has harmonics above the cut that ẍ, cut there, cannot balance, and without the same cut
/// they would stand in r as a force the model misses (seen: 1.2 N RMS with every odd group
/// "present" on a noise-free record of the benchmark traced with its own model).
pub fn missing_force(o: &Oscillator, rec: &Record<'_>, k: &Kinematics) -> Vec<f64> {
    let n = k.x.len();
    let h = 1.0 / rec.fs;
    let sub = 4;
    let dt = h / sub as f64;
    let mut s = State::zeros();
    let mut r = Vec::with_capacity(n);
    let at = |i: usize, frac: f64| -> (f64, f64) {
        let j = (i + 1).min(n - 1);
        (
            k.x[i] + frac * (k.x[j] - k.x[i]),
            k.v[i] + frac * (k.v[j] - k.v[i]),
        )
    };
    // The internal states' rates with the motion imposed: components 2.. of the derivative.
    let rate = |s: &State, x: f64, v: f64| -> State {
        let mut full = *s;
        full[0] = x;
        full[1] = v;
        let mut d = o.derivative(&full, 0.0);
        d[0] = 0.0;
        d[1] = 0.0;
        d
    };
    for i in 0..n {
        let (x, v) = (k.x[i], k.v[i]);
        let coupling = o.extras.second_mass.map_or(0.0, |sm| {
            sm.stiffness * (x - s[3]) + sm.damping * (v - s[4])
        });
        let f = o.damping * v + o.stiffness * x + s[2] + o.extras.static_force(x, v) + coupling;
        r.push(rec.u[k.first_row + i] - f);
        for j in 0..sub {
            let f0 = j as f64 / sub as f64;
            let f1 = (j as f64 + 0.5) / sub as f64;
            let f2 = (j as f64 + 1.0) / sub as f64;
            let (x0, v0) = at(i, f0);
            let (x1, v1) = at(i, f1);
            let (x2, v2) = at(i, f2);
            let k1 = rate(&s, x0, v0);
            let k2 = rate(&(s + k1 * (dt / 2.0)), x1, v1);
            let k3 = rate(&(s + k2 * (dt / 2.0)), x1, v1);
            let k4 = rate(&(s + k3 * dt), x2, v2);
            s += (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (dt / 6.0);
        }
    }
    spectral(&r, k.fs, k.cut_hz, 0)
        .iter()
        .zip(&k.a)
        .map(|(f, a)| f - o.mass * a)
        .collect()
}

/// A group of the surface's terms and what it says of the structure.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum Group {
    /// ξ³, ξ⁵: a stiffness odd in x (a cubic spring, a clearance).
    OddStiffness,
    /// ξ², ξ⁴: a stiffness even in x (an asymmetric spring).
    EvenStiffness,
    /// η|η|, η³: damping that grows faster than the velocity (quadratic damping).
    OddDamping,
    /// A jump at ẋ = 0 (friction).
    Jump,
    /// η²: damping even in the velocity.
    EvenDamping,
    /// ξ²η, ξη²: damping that depends on the displacement, or stiffness on the velocity.
    Mixed,
    /// τx, τẋ: a stiffness or damping that changes over the record.
    Time,
}

impl Group {
    /// Every group, in the order of the fit's report.
    pub const ALL: [Group; 7] = [
        Group::OddStiffness,
        Group::EvenStiffness,
        Group::OddDamping,
        Group::Jump,
        Group::EvenDamping,
        Group::Mixed,
        Group::Time,
    ];

    /// What the group says, in words.
    pub fn describe(self) -> &'static str {
        match self {
            Group::OddStiffness => "a stiffness odd in x (cubic spring, clearance)",
            Group::EvenStiffness => "a stiffness even in x (asymmetric spring)",
            Group::OddDamping => "damping growing faster than the velocity (quadratic damping)",
            Group::Jump => "a jump at zero velocity (friction)",
            Group::EvenDamping => "damping even in the velocity",
            Group::Mixed => "damping that depends on the displacement",
            Group::Time => "a stiffness or damping that changes over the record (nonstationary)",
        }
    }

    /// Indices of the group's terms in [`ForceSurface::TERMS`] (none for [`Group::Time`]).
    pub fn terms(self) -> &'static [usize] {
        match self {
            Group::OddStiffness => &[1, 3],
            Group::EvenStiffness => &[0, 2],
            Group::OddDamping => &[5, 6],
            Group::Jump => &[7],
            Group::EvenDamping => &[4],
            Group::Mixed => &[8, 9],
            Group::Time => &[],
        }
    }
}

/// One group's test.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct GroupTest {
    /// The group.
    pub group: Group,
    /// Its Wald statistic (χ² with as many degrees of freedom as terms).
    pub wald: f64,
    /// Its p-value.
    pub p_value: f64,
    /// The share of the missing force's variance (beyond the linear terms) that the whole
    /// fit loses without this group.
    pub share: f64,
}

/// The missing force fitted on the surface basis, its sections and its signature.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SurfaceFit {
    /// The fitted surface (every term; see [`SurfaceFit::significant_surface`]).
    pub surface: ForceSurface,
    /// Each term's t statistic (block covariance).
    pub t: [f64; SURFACE_TERMS],
    /// The fit's linear terms: corrections to the model's k (per unit ξ) and c (per unit η),
    /// to m when it is fitted, and a constant force, in newtons.
    pub linear: Vec<f64>,
    /// Each group's test, most significant first.
    pub groups: Vec<GroupTest>,
    /// Share of the missing force's variance beyond the linear terms that the surface and
    /// time terms explain.
    pub explained: f64,
    /// The stiffness curve: (x, mean r) where |ẋ| < 0.2 σᵥ, in 16 bins over ±2.5 σₓ.
    pub stiffness_section: Vec<(f64, f64)>,
    /// The damping curve: (ẋ, mean r) where |x| < 0.2 σₓ, in 16 bins over ±2.5 σᵥ.
    pub damping_section: Vec<(f64, f64)>,
    /// Rows fitted.
    pub rows: usize,
    /// What the surface says, in words ([`SurfaceFit::signature`]).
    pub signature: String,
}

/// The fitted surface's two sections, as (abscissa, force) points.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct FittedSections {
    /// (x, fitted force at ẋ = 0): a stiffness curve.
    pub stiffness: Vec<(f64, f64)>,
    /// (ẋ, fitted force at x = 0): a damping curve.
    pub damping: Vec<(f64, f64)>,
}

impl SurfaceFit {
    /// The fitted missing force at (x, ẋ): its linear terms (corrections to k and c, and the
    /// constant) and the surface, without the time terms and the mass's.
    pub fn fitted(&self, x: f64, v: f64) -> f64 {
        let s = &self.surface;
        let (xi, eta) = (x / s.x_scale, v / s.v_scale);
        let constant = self.linear.last().copied().unwrap_or(0.0);
        self.linear[0] * xi + self.linear[1] * eta + constant + s.force(x, v)
    }

    /// The fitted sections at `points` points over ±2.5 σ: (x, fitted at ẋ = 0) and
    /// (ẋ, fitted at x = 0), beside the binned [`SurfaceFit::stiffness_section`] and
    /// [`SurfaceFit::damping_section`] (whose means the noise of ẍ scatters: the fit averages
    /// every row).
    pub fn fitted_sections(&self, points: usize) -> FittedSections {
        let s = &self.surface;
        let along = |scale: f64| -> Vec<f64> {
            (0..points.max(2))
                .map(|i| scale * (-2.5 + 5.0 * i as f64 / (points.max(2) - 1) as f64))
                .collect()
        };
        FittedSections {
            stiffness: along(s.x_scale)
                .into_iter()
                .map(|x| (x, self.fitted(x, 0.0)))
                .collect(),
            damping: along(s.v_scale)
                .into_iter()
                .map(|v| (v, self.fitted(0.0, v)))
                .collect(),
        }
    }

    /// The groups present (p below [`GROUP_SIGNIFICANCE`]), most significant first.
    pub fn present(&self) -> impl Iterator<Item = &GroupTest> {
        self.groups
            .iter()
            .filter(|g| g.p_value < GROUP_SIGNIFICANCE)
    }

    /// What the surface says, in words: its present groups, or that the missing force is
    /// no function of (x, ẋ) or of time.
    pub fn signature(&self) -> String {
        self.signature.clone()
    }

    /// The signature of the groups `groups` (those present by [`GROUP_SIGNIFICANCE`]).
    fn signature_of(groups: &[GroupTest]) -> String {
        let v: Vec<&str> = groups
            .iter()
            .filter(|g| g.p_value < GROUP_SIGNIFICANCE)
            .map(|g| g.group.describe())
            .collect();
        if v.is_empty() {
            "no function of (x, ẋ) or of time: noise, or an effect with memory (another mode, hysteresis)".into()
        } else {
            v.join("; ")
        }
    }

    /// Whether the force changes over the record.
    pub fn nonstationary(&self) -> bool {
        self.present().any(|g| g.group == Group::Time)
    }

    /// The surface of the terms of the present groups whose own t is at least 3, at most
    /// `max_terms` of them, largest |t| first; `None` when there are none.
    pub fn significant_surface(&self, max_terms: usize) -> Option<ForceSurface> {
        let mut idx: Vec<usize> = self
            .present()
            .flat_map(|g| g.group.terms().iter().copied())
            .filter(|&i| self.t[i].abs() >= 3.0)
            .collect();
        idx.sort_by(|&a, &b| self.t[b].abs().total_cmp(&self.t[a].abs()));
        idx.truncate(max_terms);
        if idx.is_empty() {
            return None;
        }
        let mut s = self.surface;
        for (i, c) in s.coefficients.iter_mut().enumerate() {
            if !idx.contains(&i) {
                *c = 0.0;
            }
        }
        Some(s)
    }
}

/// Least squares of `r` on the columns `x` (rows × p), with the block covariance of the
/// coefficients: (β, covariance, residual sum of squares). `None` when singular.
fn block_ols(x: &DMatrix<f64>, r: &DVector<f64>) -> Option<(DVector<f64>, DMatrix<f64>, f64)> {
    let xtx = x.transpose() * x;
    let chol = xtx.clone().cholesky()?;
    let beta = chol.solve(&(x.transpose() * r));
    let e = r - x * &beta;
    let p = x.ncols();
    let mut meat = DMatrix::<f64>::zeros(p, p);
    let rows = x.nrows();
    let mut start = 0;
    while start < rows {
        let end = (start + BLOCK_ROWS).min(rows);
        let mut g = DVector::<f64>::zeros(p);
        for t in start..end {
            for j in 0..p {
                g[j] += x[(t, j)] * e[t];
            }
        }
        meat += &g * g.transpose();
        start = end;
    }
    let inv = chol.inverse();
    let cov = &inv * meat * &inv;
    Some((beta, cov, e.norm_squared()))
}

/// Fit the missing force `r` on the surface basis over the motion `k`, test each group, and
/// bin the two sections. `fit_mass` adds ẍ to the linear terms.
pub fn fit_surface(k: &Kinematics, r: &[f64], fit_mass: bool) -> Option<SurfaceFit> {
    let n = r.len();
    if n < 4 * BLOCK_ROWS {
        return None;
    }
    let rms = |v: &[f64]| (v.iter().map(|a| a * a).sum::<f64>() / v.len() as f64).sqrt();
    let (sx, sv) = (rms(&k.x), rms(&k.v));
    if !(sx > 0.0 && sv > 0.0) {
        return None;
    }
    // Linear terms: ξ, η, ẍ when the mass is fitted, and a constant (an offset the model
    // lacks would otherwise stand in the even groups).
    let nl = 3 + usize::from(fit_mass);
    let p = nl + SURFACE_TERMS + 2;
    let mut x = DMatrix::<f64>::zeros(n, p);
    for t in 0..n {
        let (xi, eta) = (k.x[t] / sx, k.v[t] / sv);
        let tau = 2.0 * t as f64 / (n - 1) as f64 - 1.0;
        x[(t, 0)] = xi;
        x[(t, 1)] = eta;
        if fit_mass {
            x[(t, 2)] = k.a[t] / (sv * sv / sx);
        }
        x[(t, nl - 1)] = 1.0;
        for (j, b) in ForceSurface::basis(xi, eta).iter().enumerate() {
            x[(t, nl + j)] = *b;
        }
        x[(t, nl + SURFACE_TERMS)] = tau * xi;
        x[(t, nl + SURFACE_TERMS + 1)] = tau * eta;
    }
    // The nonlinear columns have harmonics above the cut, as the force does: cut them the
    // same way, so that the fit compares like with like.
    for j in nl..p {
        let col: Vec<f64> = x.column(j).iter().copied().collect();
        let cut = spectral(&col, k.fs, k.cut_hz, 0);
        x.column_mut(j).copy_from_slice(&cut);
    }
    let rv = DVector::from_column_slice(r);
    let (beta, cov, sse_full) = block_ols(&x, &rv)?;
    let linear_only = x.columns(0, nl).into_owned();
    let (_, _, sse_lin) = block_ols(&linear_only, &rv)?;
    let beyond = (sse_lin - sse_full).max(0.0);
    let cols_of = |g: Group| -> Vec<usize> {
        match g {
            Group::Time => vec![nl + SURFACE_TERMS, nl + SURFACE_TERMS + 1],
            _ => g.terms().iter().map(|i| nl + i).collect(),
        }
    };
    let mut groups: Vec<GroupTest> = Group::ALL
        .iter()
        .map(|&g| {
            let c = cols_of(g);
            let q = c.len();
            let b = DVector::from_iterator(q, c.iter().map(|&i| beta[i]));
            let v = DMatrix::from_fn(q, q, |i, j| cov[(c[i], c[j])]);
            let wald = v
                .clone()
                .cholesky()
                .map_or(0.0, |ch| (b.transpose() * ch.solve(&b))[(0, 0)]);
            let p_value = ChiSquared::new(q as f64).map_or(1.0, |d| 1.0 - d.cdf(wald));
            // The fit without the group: what it loses.
            let keep: Vec<usize> = (0..p).filter(|i| !c.contains(i)).collect();
            let xr = x.select_columns(keep.iter());
            let share = block_ols(&xr, &rv).map_or(0.0, |(_, _, s)| {
                ((s - sse_full) / sse_lin.max(1e-300)).max(0.0)
            });
            GroupTest {
                group: g,
                wald,
                p_value,
                share,
            }
        })
        .collect();
    groups.sort_by(|a, b| b.wald.total_cmp(&a.wald));
    let mut coefficients = [0.0; SURFACE_TERMS];
    let mut tstat = [0.0; SURFACE_TERMS];
    for j in 0..SURFACE_TERMS {
        coefficients[j] = beta[nl + j];
        let se = cov[(nl + j, nl + j)].sqrt();
        tstat[j] = if se > 0.0 { beta[nl + j] / se } else { 0.0 };
    }
    let signature = SurfaceFit::signature_of(&groups);
    Some(SurfaceFit {
        signature,
        surface: ForceSurface {
            x_scale: sx,
            v_scale: sv,
            coefficients,
        },
        t: tstat,
        linear: (0..nl).map(|i| beta[i]).collect(),
        groups,
        explained: if sse_lin > 0.0 { beyond / sse_lin } else { 0.0 },
        stiffness_section: section(&k.x, &k.v, sx, sv, r),
        damping_section: section(&k.v, &k.x, sv, sx, r),
        rows: n,
    })
}

/// The mean force `r` in 16 bins of `along` over ±2.5 `s_along`, on the rows where `across`
/// is within 0.2 `s_across` of 0: a section of the surface (bins with fewer than 5 rows
/// left out).
fn section(
    along: &[f64],
    across: &[f64],
    s_along: f64,
    s_across: f64,
    r: &[f64],
) -> Vec<(f64, f64)> {
    let bins = 16;
    let (lo, hi) = (-2.5 * s_along, 2.5 * s_along);
    let mut acc = vec![(0.0, 0usize); bins];
    for ((a, c), f) in along.iter().zip(across).zip(r) {
        if c.abs() < 0.2 * s_across && *a > lo && *a < hi {
            let b = (((a - lo) / (hi - lo)) * bins as f64) as usize;
            let e = &mut acc[b.min(bins - 1)];
            e.0 += f;
            e.1 += 1;
        }
    }
    acc.iter()
        .enumerate()
        .filter(|(_, (_, c))| *c >= 5)
        .map(|(b, (s, c))| {
            (
                lo + (b as f64 + 0.5) * (hi - lo) / bins as f64,
                s / *c as f64,
            )
        })
        .collect()
}

/// A model's missing force along the measured motion, and its fit on the surface basis.
#[derive(Debug, Clone, PartialEq)]
pub struct Trace {
    /// The measured motion on the rows kept.
    pub kinematics: Kinematics,
    /// The model's own simulated motion on the same rows, whose trace is subtracted.
    pub motion: Kinematics,
    /// The missing force on those rows.
    pub force: Vec<f64>,
    /// Its fit (`None` when the rows are too few, the model does not simulate, or the fit is
    /// singular).
    pub fit: Option<SurfaceFit>,
}

/// The trace of a model's residual on rows `range`: the missing force and its fit. The
/// derivatives are cut at 1.5 times the input's band edge (at most 0.9 of Nyquist).
///
/// The method has artefacts of its own: the hysteretic force integrated along a sampled,
/// band-cut motion is off by a few per cent near the reversals (0.7–1 N RMS on the benchmark
/// traced with its own true model, noise-free; 0.05 N for a linear oscillator). That error
/// is deterministic, so every group's test found it. The model's own simulated output, where
/// nothing is missing, has the same artefacts along nearly the same motion: its trace is
/// subtracted, which leaves 0.04 N there and no group present on records with white or
/// coloured sensor noise.
pub fn trace(o: &Oscillator, rec: &Record<'_>, range: (usize, usize), fit_mass: bool) -> Trace {
    let cut = (1.5 * input_band(&rec.u[range.0..range.1], rec.fs).1).min(0.9 * rec.fs / 2.0);
    let kinematics = kinematics(rec.y, rec.fs, range, cut);
    let mut force = missing_force(o, rec, &kinematics);
    let simulated = super::response(o, rec, range);
    let motion = match &simulated {
        Some(yhat) => kinematics_of(yhat, range.0, rec.fs, cut),
        None => kinematics.clone(),
    };
    // What the method reports of the model's own output, where nothing is missing: its
    // artefacts (the hysteretic force integrated along a sampled, band-cut motion is off by
    // a few per cent near the reversals: 0.7–1 N RMS on the benchmark traced with its own
    // model, a deterministic error that every group's test would find). The same artefacts
    // stand in the record's trace, whose motion the model follows: subtracting them leaves
    // the force the model misses.
    if simulated.is_some() {
        for (f, a) in force.iter_mut().zip(missing_force(o, rec, &motion)) {
            *f -= a;
        }
    }
    let fit = fit_surface(&kinematics, &force, fit_mass);
    Trace {
        kinematics,
        motion,
        force,
        fit,
    }
}

/// The missing force binned over the phase plane, for drawing the surface.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SurfaceGrid {
    /// Bin edges in x (bins + 1 of them), over ±2.5 σₓ.
    pub x_edges: Vec<f64>,
    /// Bin edges in ẋ, over ±2.5 σᵥ.
    pub v_edges: Vec<f64>,
    /// Mean missing force per bin, `[x bin][ẋ bin]`; `None` where fewer than 5 rows fall.
    pub mean: Vec<Vec<Option<f64>>>,
}

/// The trace's missing force averaged over `bins` × `bins` cells of the phase plane.
pub fn grid(trace: &Trace, bins: usize) -> SurfaceGrid {
    let k = &trace.kinematics;
    let rms = |v: &[f64]| (v.iter().map(|a| a * a).sum::<f64>() / v.len().max(1) as f64).sqrt();
    let (sx, sv) = (rms(&k.x), rms(&k.v));
    let bins = bins.max(1);
    let edges = |s: f64| -> Vec<f64> {
        (0..=bins)
            .map(|i| -2.5 * s + 5.0 * s * i as f64 / bins as f64)
            .collect()
    };
    let mut acc = vec![vec![(0.0, 0usize); bins]; bins];
    let cell = |v: f64, s: f64| -> Option<usize> {
        let f = (v + 2.5 * s) / (5.0 * s);
        (0.0..1.0)
            .contains(&f)
            .then(|| ((f * bins as f64) as usize).min(bins - 1))
    };
    for ((x, v), r) in k.x.iter().zip(&k.v).zip(&trace.force) {
        if let (Some(i), Some(j)) = (cell(*x, sx), cell(*v, sv)) {
            acc[i][j].0 += r;
            acc[i][j].1 += 1;
        }
    }
    SurfaceGrid {
        x_edges: edges(sx),
        v_edges: edges(sv),
        mean: acc
            .iter()
            .map(|row| {
                row.iter()
                    .map(|(s, c)| (*c >= 5).then(|| s / *c as f64))
                    .collect()
            })
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::residual::InputInterpolation;
    use hyst_sim::{Input, SimOptions, excitation::band_limited_noise};

    /// The derivatives of a sum of sines in the band are the analytic ones, away from the
    /// ends, to the accuracy of the mirror's leakage.
    #[test]
    fn derivatives_in_the_band_are_exact() {
        let fs = 750.0;
        let n = 8192;
        let w1 = 2.0 * std::f64::consts::PI * 13.7;
        let w2 = 2.0 * std::f64::consts::PI * 41.3;
        let y: Vec<f64> = (0..n)
            .map(|i| {
                let t = i as f64 / fs;
                (w1 * t).sin() + 0.3 * (w2 * t + 1.0).cos()
            })
            .collect();
        let k = kinematics(&y, fs, (0, n), 200.0);
        let mut worst: f64 = 0.0;
        for (i, a) in k.a.iter().enumerate() {
            let t = (k.first_row + i) as f64 / fs;
            let exact = -w1 * w1 * (w1 * t).sin() - 0.3 * w2 * w2 * (w2 * t + 1.0).cos();
            worst = worst.max((a - exact).abs() / (0.3 * w2 * w2));
        }
        // The even extension's kink at the ends rings into the rows near them; beyond the
        // 2 % left out it stays below 2 % of the acceleration's amplitude.
        assert!(worst < 0.02, "{worst}");
    }

    /// A linear oscillator with an undeclared cubic spring, traced with the linear model:
    /// the odd-stiffness group is the first and the ξ³ coefficient comes back; the same record
    /// traced with the true model shows no group.
    #[test]
    fn a_cubic_spring_is_traced_to_an_odd_stiffness() {
        let fs = 750.0;
        let n = 16384;
        let u = band_limited_noise(n, fs, 5.0, 150.0, 20.0, 3).unwrap();
        let w = 2.0 * std::f64::consts::PI * 30.0;
        let lin = Oscillator::linear(1.0, 2.0 * 0.03 * w, w * w);
        let opts = SimOptions {
            oversample: 20,
            ..SimOptions::default()
        };
        let y0 = hyst_sim::simulate(&lin, Input::BandLimited(&u), fs, n, &opts).unwrap();
        let sx = (y0.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
        let mut truth = lin;
        truth.extras.cubic_stiffness = 0.1 * lin.stiffness / (sx * sx);
        let mut y = hyst_sim::simulate(&truth, Input::BandLimited(&u), fs, n, &opts).unwrap();
        // Sensor noise of 1 % of σₓ, as in the loop's battery.
        hyst_sim::excitation::add_noise(&mut y, 0.01 * sx, 5).unwrap();
        let rec = Record {
            u: &u,
            y: &y,
            fs,
            interpolation: InputInterpolation::BandLimited,
        };
        let f = trace(&lin, &rec, (0, n), false).fit.unwrap();
        assert_eq!(f.groups[0].group, Group::OddStiffness, "{f:?}");
        assert!(f.groups[0].p_value < 1e-6);
        // The ξ³ coefficient is k₃σₓ³ in newtons, on the kept rows' own σₓ.
        let expect = truth.extras.cubic_stiffness * f.surface.x_scale.powi(3);
        assert!(
            (f.surface.coefficients[1] / expect - 1.0).abs() < 0.05,
            "{} against {expect}",
            f.surface.coefficients[1]
        );
        let t = trace(&truth, &rec, (0, n), false).fit.unwrap();
        assert!(t.present().next().is_none(), "{}", t.signature());
    }
}
