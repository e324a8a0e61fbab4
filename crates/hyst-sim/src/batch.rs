//! Many models of one structure simulated on one input in lockstep: the perturbed models of
//! a finite-difference Jacobian, the trial points of a fit.
//!
//! [`simulate_many`] integrates up to [`LANES`] models at once with the classic RK4 of
//! [`simulate`](crate::simulate), each state component held as one array across the models
//! (structure of arrays). One RK4 step is a chain of four dependent evaluations, so a single
//! model leaves the processor waiting on latency; [`LANES`] independent chains fill it, and
//! the compiler turns the per-lane loops into vector instructions. Four Bouc-Wen models take
//! 0.43 of the time of four simulated one after the other, with a cubic spring 0.27 (`cargo
//! xtask bench refine`, its `simulate_many` lines); eight lanes were slower than four (the
//! constants no longer fit the registers).
//!
//! Every model is any [`Oscillator`]: the kernel is compiled for the terms the lanes have
//! (no element, a Zener or a Bouc-Wen element of ν = 1, the polynomial extra forces, or the
//! superset with a second mass and any ν), and a clearance, friction or a force surface,
//! when some lane has them, are computed lane by lane out of line. The outputs agree with [`simulate`](crate::simulate)'s to rounding (the
//! same scheme with the terms summed in another order; this module's tests).

use hyst_model::{Oscillator, Restoring, SURFACE_TERMS};

use crate::{Decimation, Input, Integrator, SimError, SimOptions};

/// Models integrated together.
pub const LANES: usize = 4;

type V = [f64; LANES];

/// `f` of each lane.
#[inline(always)]
fn lanes(f: impl FnMut(usize) -> f64) -> V {
    std::array::from_fn(f)
}

/// Simulate each of `models` from rest on `input`, as [`simulate`](crate::simulate) would
/// one by one: the same outputs to rounding, each model's own error (an invalid model, a
/// divergence) in its place. The models run [`LANES`] at a time in lockstep with RK4 and
/// every-`oversample`-th sub-step output ([`Decimation::Subsample`]) from a sampled,
/// band-limited or interpolated input; other options or inputs are simulated one by one.
pub fn simulate_many(
    models: &[Oscillator],
    input: Input<'_>,
    fs: f64,
    n_samples: usize,
    opts: &SimOptions,
) -> Vec<Result<Vec<f64>, SimError>> {
    let one_by_one = || {
        models
            .iter()
            .map(|m| crate::simulate(m, input, fs, n_samples, opts))
            .collect()
    };
    let lockstep = opts.integrator == Integrator::Rk4
        && opts.decimation == Decimation::Subsample
        && n_samples > 1
        && models.len() > 1;
    if !lockstep {
        return one_by_one();
    }
    let source = match Source::of(input, n_samples, opts.oversample) {
        Ok(Some(s)) => s,
        Ok(None) => return one_by_one(),
        Err(e) => return models.iter().map(|_| Err(e.clone())).collect(),
    };
    let mut out = Vec::with_capacity(models.len());
    for chunk in models.chunks(LANES) {
        let valid: Vec<Result<(), SimError>> = chunk
            .iter()
            .map(|m| crate::check_common(m, fs, opts))
            .collect();
        let Some(first_ok) = valid.iter().position(|v| v.is_ok()) else {
            out.extend(valid.into_iter().map(|v| Err(v.expect_err("none valid"))));
            continue;
        };
        // Invalid models' lanes run a valid one, whose output is dropped.
        let lane_models: [&Oscillator; LANES] = std::array::from_fn(|l| match valid.get(l) {
            Some(Ok(())) => &chunk[l],
            _ => &chunk[first_ok],
        });
        let kernel = LaneKernel::new(&lane_models);
        // A lane with a measurement chain needs the displacement at every sub-step.
        let chains: [Option<hyst_model::MeasurementChain>; LANES] =
            std::array::from_fn(|l| crate::chain::of(lane_models[l]));
        let fine = chains.iter().any(Option::is_some);
        let mut ys = run(&kernel, &source, fs, n_samples, opts, fine);
        if fine {
            let r = opts.oversample;
            let h = 1.0 / (fs * r as f64);
            for (y, c) in ys.iter_mut().zip(&chains) {
                if let Ok(y) = y {
                    let through = match c {
                        Some(c) => crate::chain::apply(y, h, c),
                        None => std::mem::take(y),
                    };
                    *y = through.into_iter().step_by(r).collect();
                }
            }
        }
        for (v, y) in valid.into_iter().zip(ys) {
            out.push(v.and(y));
        }
    }
    out
}

/// The input at each sub-step's start, middle and end.
enum Source<'a> {
    /// Samples, linear in between.
    Sampled(&'a [f64]),
    /// Points every half sub-step.
    Fine(std::borrow::Cow<'a, [f64]>),
}

impl<'a> Source<'a> {
    /// The source for `input`, checked to hold `n` samples; `None` for inputs the lockstep
    /// run does not take.
    fn of(input: Input<'a>, n: usize, r: usize) -> Result<Option<Self>, SimError> {
        crate::check_oversample(r)?;
        Ok(Some(match input {
            Input::Sampled(u) => {
                crate::check_length(u, n)?;
                Source::Sampled(u)
            }
            Input::BandLimited(u) => {
                crate::check_length(u, n)?;
                let used = &u[..(n + crate::resample::SINC_HALF_TAPS).min(u.len())];
                Source::Fine(crate::resample::interpolate_band_limited(used, 2 * r).into())
            }
            Input::Interpolated {
                samples,
                per_sample,
            } => {
                crate::check_interpolated(samples, per_sample, r, n)?;
                Source::Fine(samples.into())
            }
            Input::Periodic(_) | Input::Function(_) => return Ok(None),
        }))
    }

    /// (u at start, middle, end) of sub-step `i` of `r` in sample interval `k`.
    #[inline(always)]
    fn at(&self, k: usize, i: usize, r: usize) -> (f64, f64, f64) {
        match self {
            Source::Sampled(u) => {
                let (a, b) = (u[k], u[k + 1]);
                let d = b - a;
                let inv_r = 1.0 / r as f64;
                let t0 = i as f64 * inv_r;
                (a + d * t0, a + d * (t0 + 0.5 * inv_r), a + d * (t0 + inv_r))
            }
            Source::Fine(f) => {
                let base = k * 2 * r + 2 * i;
                (f[base], f[base + 1], f[base + 2])
            }
        }
    }
}

/// The right-hand sides of [`LANES`] models on the states (x, ẋ, z, x₂, ẋ₂).
struct LaneKernel<'a> {
    models: [&'a Oscillator; LANES],
    inv_m: V,
    c: V,
    k: V,
    k3: V,
    kq: V,
    qd: V,
    f0: V,
    alpha: V,
    bg: V,
    bd: V,
    k_inf: V,
    omega: V,
    nu: V,
    k2: V,
    c2: V,
    inv_m2: V,
    /// The clearance, friction and force surface of the lanes that have them (boxed: the
    /// kernel's other constants stay together).
    rare: Option<Box<RareLanes>>,
    /// Some lane has a Bouc-Wen exponent other than 1.
    powered: bool,
}

impl<'a> LaneKernel<'a> {
    fn new(models: &[&'a Oscillator; LANES]) -> Self {
        let e = |l: usize| &models[l].extras;
        let bw = |l: usize| match &models[l].restoring {
            Restoring::BoucWen(b) => Some(*b),
            _ => None,
        };
        let zener = |l: usize| match &models[l].restoring {
            Restoring::Zener(z) => Some(*z),
            _ => None,
        };
        let sm = |l: usize| e(l).second_mass;
        LaneKernel {
            models: *models,
            inv_m: lanes(|l| 1.0 / models[l].mass),
            c: lanes(|l| models[l].damping),
            k: lanes(|l| models[l].stiffness),
            k3: lanes(|l| e(l).cubic_stiffness),
            kq: lanes(|l| e(l).quadratic_stiffness),
            qd: lanes(|l| e(l).quadratic_damping),
            f0: lanes(|l| e(l).offset),
            alpha: lanes(|l| bw(l).map_or(0.0, |b| b.alpha)),
            bg: lanes(|l| bw(l).map_or(0.0, |b| b.beta_gamma())),
            bd: lanes(|l| bw(l).map_or(0.0, |b| b.beta_delta())),
            k_inf: lanes(|l| zener(l).map_or(0.0, |z| z.k_inf)),
            omega: lanes(|l| zener(l).map_or(0.0, |z| z.omega)),
            nu: lanes(|l| bw(l).map_or(1.0, |b| b.nu)),
            k2: lanes(|l| sm(l).map_or(0.0, |s| s.stiffness)),
            c2: lanes(|l| sm(l).map_or(0.0, |s| s.damping)),
            inv_m2: lanes(|l| sm(l).map_or(0.0, |s| 1.0 / s.mass)),
            rare: RareLanes::of(models),
            powered: (0..LANES).any(|l| bw(l).is_some_and(|b| b.nu != 1.0)),
        }
    }

    /// The rates at states `s` under force `u`, for lanes whose terms are those of `T`.
    #[inline(always)]
    fn f<T: Terms>(&self, s: &[V; 5], u: f64) -> [V; 5] {
        let [x, v, z, x2, v2] = s;
        let coupling = if T::SECOND {
            lanes(|l| self.k2[l] * (x[l] - x2[l]) + self.c2[l] * (v[l] - v2[l]))
        } else {
            [0.0; LANES]
        };
        let mut force = lanes(|l| u - self.c[l] * v[l] - self.k[l] * x[l] - z[l] - coupling[l]);
        if T::POLY {
            force = lanes(|l| {
                force[l]
                    - self.f0[l]
                    - x[l] * x[l] * (self.k3[l] * x[l] + self.kq[l])
                    - self.qd[l] * v[l] * v[l].abs()
            });
        }
        if let Some(rare) = &self.rare {
            rare.subtract(x, v, &mut force);
        }
        let dz = match T::ELEMENT {
            Element::None => [0.0; LANES],
            Element::Zener => lanes(|l| self.k_inf[l] * v[l] - self.omega[l] * z[l]),
            Element::BoucWen1 => lanes(|l| {
                self.alpha[l] * v[l]
                    - self.bg[l] * v[l].abs() * z[l]
                    - self.bd[l] * v[l] * z[l].abs()
            }),
            Element::Any => {
                // |z|^ν and sgn(z)|z|^ν; for ν = 1, |z| and z.
                let (zn, zs) = if self.powered {
                    let zn = lanes(|l| {
                        if self.nu[l] == 1.0 {
                            z[l].abs()
                        } else {
                            z[l].abs().powf(self.nu[l])
                        }
                    });
                    let zs = lanes(|l| {
                        if z[l] > 0.0 {
                            zn[l]
                        } else if z[l] < 0.0 {
                            -zn[l]
                        } else {
                            0.0
                        }
                    });
                    (zn, zs)
                } else {
                    (lanes(|l| z[l].abs()), *z)
                };
                lanes(|l| {
                    (self.alpha[l] + self.k_inf[l]) * v[l]
                        - self.bg[l] * v[l].abs() * zs[l]
                        - self.bd[l] * v[l] * zn[l]
                        - self.omega[l] * z[l]
                })
            }
        };
        [
            *v,
            lanes(|l| force[l] * self.inv_m[l]),
            dz,
            if T::SECOND { *v2 } else { [0.0; LANES] },
            if T::SECOND {
                lanes(|l| coupling[l] * self.inv_m2[l])
            } else {
                [0.0; LANES]
            },
        ]
    }
}

/// The restoring element the lanes share, as far as the kernel needs to know.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Element {
    /// No lane has one.
    None,
    /// Every lane a Zener element.
    Zener,
    /// Every lane a Bouc-Wen element with ν = 1.
    BoucWen1,
    /// Anything else: the superset of the terms.
    Any,
}

/// Which terms the lanes have, fixed at compile time so that the absent ones cost nothing.
trait Terms {
    const SECOND: bool;
    const POLY: bool;
    const ELEMENT: Element;
}

macro_rules! terms {
    ($name:ident, $second:expr, $poly:expr, $element:expr) => {
        struct $name;
        impl Terms for $name {
            const SECOND: bool = $second;
            const POLY: bool = $poly;
            const ELEMENT: Element = $element;
        }
    };
}

terms!(Plain, false, false, Element::None);
terms!(PlainZener, false, false, Element::Zener);
terms!(PlainBoucWen, false, false, Element::BoucWen1);
terms!(Poly, false, true, Element::None);
terms!(PolyZener, false, true, Element::Zener);
terms!(PolyBoucWen, false, true, Element::BoucWen1);
terms!(General, true, true, Element::Any);

impl LaneKernel<'_> {
    /// The element the lanes share.
    fn element(&self) -> Element {
        let kinds = self.models.map(|m| match &m.restoring {
            Restoring::None => Element::None,
            Restoring::Zener(_) => Element::Zener,
            Restoring::BoucWen(b) if b.nu == 1.0 => Element::BoucWen1,
            Restoring::BoucWen(_) => Element::Any,
        });
        if kinds.iter().all(|&k| k == kinds[0]) {
            kinds[0]
        } else {
            Element::Any
        }
    }

    /// Whether some lane has a polynomial extra force or an offset.
    fn poly(&self) -> bool {
        (0..LANES).any(|l| {
            self.k3[l] != 0.0 || self.kq[l] != 0.0 || self.qd[l] != 0.0 || self.f0[l] != 0.0
        })
    }

    /// Whether some lane has a second mass.
    fn second(&self) -> bool {
        (0..LANES).any(|l| self.models[l].extras.second_mass.is_some())
    }
}

/// The extra forces few models have, lane by lane: a clearance's spring, smoothed Coulomb
/// friction and a force surface ([`hyst_model::ExtraForces`]), each zero in the lanes
/// without it and `None` when no lane has it.
struct RareLanes {
    /// Gap and spring.
    clearance: Option<(V, V)>,
    /// Friction force and the inverse of its smoothing velocity.
    coulomb: Option<(V, V)>,
    /// Inverse displacement and velocity scales and the terms' coefficients.
    surface: Option<(V, V, [V; SURFACE_TERMS])>,
}

impl RareLanes {
    fn of(models: &[&Oscillator; LANES]) -> Option<Box<RareLanes>> {
        let e = |l: usize| &models[l].extras;
        let any = |f: &dyn Fn(usize) -> bool| (0..LANES).any(f);
        let clearance = any(&|l| e(l).clearance.is_some()).then(|| {
            let c = |l: usize| e(l).clearance;
            (
                lanes(|l| c(l).map_or(0.0, |c| c.gap)),
                lanes(|l| c(l).map_or(0.0, |c| c.stiffness)),
            )
        });
        let coulomb = any(&|l| e(l).coulomb.is_some()).then(|| {
            let c = |l: usize| e(l).coulomb;
            (
                lanes(|l| c(l).map_or(0.0, |c| c.force)),
                lanes(|l| c(l).map_or(0.0, |c| 1.0 / c.smoothing_velocity)),
            )
        });
        let surface = any(&|l| e(l).surface.is_some()).then(|| {
            let sf = |l: usize| e(l).surface;
            (
                lanes(|l| sf(l).map_or(0.0, |s| 1.0 / s.x_scale)),
                lanes(|l| sf(l).map_or(0.0, |s| 1.0 / s.v_scale)),
                std::array::from_fn(|i| lanes(|l| sf(l).map_or(0.0, |s| s.coefficients[i]))),
            )
        });
        (clearance.is_some() || coulomb.is_some() || surface.is_some()).then(|| {
            Box::new(RareLanes {
                clearance,
                coulomb,
                surface,
            })
        })
    }

    /// `force` less these forces at displacements `x` and velocities `v`. Not inlined: in
    /// the kernel, its code made the common models' loop (no such force) spill its
    /// registers and run at half speed.
    #[inline(never)]
    fn subtract(&self, x: &V, v: &V, force: &mut V) {
        if let Some((gap, k)) = &self.clearance {
            *force = lanes(|l| {
                let beyond = (x[l] - gap[l]).max(0.0) + (x[l] + gap[l]).min(0.0);
                force[l] - k[l] * beyond
            });
        }
        if let Some((fc, inv_v)) = &self.coulomb {
            let t = tanh_lanes(&lanes(|l| v[l] * inv_v[l]));
            *force = lanes(|l| force[l] - fc[l] * t[l]);
        }
        if let Some((ixs, ivs, c)) = &self.surface {
            let (xi, eta) = (lanes(|l| x[l] * ixs[l]), lanes(|l| v[l] * ivs[l]));
            *force = lanes(|l| {
                let (x2, e2) = (xi[l] * xi[l], eta[l] * eta[l]);
                force[l]
                    - x2 * (c[0][l] + xi[l] * (c[1][l] + xi[l] * (c[2][l] + xi[l] * c[3][l])))
                    - e2 * (c[4][l] + c[6][l] * eta[l])
                    - c[5][l] * eta[l] * eta[l].abs()
                    - c[8][l] * x2 * eta[l]
                    - c[9][l] * xi[l] * e2
            });
            for l in 0..LANES {
                if c[7][l] != 0.0 {
                    force[l] -= c[7][l] * hyst_model::ForceSurface::jump(eta[l]);
                }
            }
        }
    }
}

/// tanh of each lane, without a library call (so that the lanes stay in vector registers):
/// $\operatorname{sgn}(a)\,(1 - e)/(1 + e)$ with $e = e^{-2|a|}$, the exponential by
/// $e^t = 2^n e^r$, $n$ the nearest integer to $t/\ln 2$ and $e^r$ ($|r| \le \ln 2 / 2$) by
/// its Taylor series to degree 13 (truncation below 1e-17). Within a few units in the last
/// place of libm's where |tanh| is not small; near 0 the difference 1 − e loses digits, an
/// absolute error of about 1e-16 (this module's tests).
#[inline(always)]
fn tanh_lanes(a: &V) -> V {
    const SATURATED: f64 = 20.0;
    // ln 2 split so that n·LN2_HI is exact (fdlibm's pair).
    const LN2_HI: f64 = f64::from_bits(0x3FE6_2E42_FEE0_0000);
    const LN2_LO: f64 = f64::from_bits(0x3DEA_39EF_3579_3C76);
    const INV: [f64; 14] = {
        let mut v = [0.0; 14];
        let mut k = 1;
        while k < 14 {
            v[k] = 1.0 / k as f64;
            k += 1;
        }
        v
    };
    // Past |a| = 20, 1 − tanh|a| = 2e^{−2|a|} < 1e-17 rounds away: ±1, which the series
    // below also gives. Lanes of one structure move together (sliding friction, most of
    // the time), so all four are often there at once.
    if a.iter().all(|x| x.abs() >= SATURATED) {
        return lanes(|l| 1.0f64.copysign(a[l]));
    }
    lanes(|l| {
        // exp(t), t = −2|a| ≤ 0; below −700 it is under 1e-304 and tanh is ±1.
        let t = (-2.0 * a[l].abs()).max(-700.0);
        let n = (t * std::f64::consts::LOG2_E).round();
        let r = t - n * LN2_HI - n * LN2_LO;
        // 1 + r(1 + r/2(1 + r/3(…))), by the reciprocals (a division per term was slower
        // than libm's tanh).
        let mut p = 1.0;
        for k in (1..=13).rev() {
            p = 1.0 + p * r * INV[k];
        }
        let e = p * f64::from_bits(((n as i64 + 1023) as u64) << 52);
        ((1.0 - e) / (1.0 + e)).copysign(a[l])
    })
}

/// `a + h·b` lane by lane, component by component.
#[inline(always)]
fn axpy(a: &[V; 5], h: f64, b: &[V; 5]) -> [V; 5] {
    std::array::from_fn(|i| lanes(|l| a[i][l] + h * b[i][l]))
}

/// Integrate the kernel's lanes from rest; each lane's outputs (at every sub-step when
/// `fine`, else at the samples) or its divergence.
fn run(
    kern: &LaneKernel<'_>,
    src: &Source<'_>,
    fs: f64,
    n: usize,
    opts: &SimOptions,
    fine: bool,
) -> Vec<Result<Vec<f64>, SimError>> {
    let run = (src, fs, n, opts);
    // Output at every sub-step (a measurement chain's lanes) takes the general terms: the
    // specialised kernels keep their inner loop free of it.
    if fine {
        return run_with::<General, true>(kern, run);
    }
    match (kern.second(), kern.poly(), kern.element()) {
        (false, false, Element::None) => run_with::<Plain, false>(kern, run),
        (false, false, Element::Zener) => run_with::<PlainZener, false>(kern, run),
        (false, false, Element::BoucWen1) => run_with::<PlainBoucWen, false>(kern, run),
        (false, _, Element::None) => run_with::<Poly, false>(kern, run),
        (false, _, Element::Zener) => run_with::<PolyZener, false>(kern, run),
        (false, _, Element::BoucWen1) => run_with::<PolyBoucWen, false>(kern, run),
        _ => run_with::<General, false>(kern, run),
    }
}

/// [`run`] with the lanes' terms those of `T`, the output at every sub-step when `FINE`.
fn run_with<T: Terms, const FINE: bool>(
    kern: &LaneKernel<'_>,
    (src, fs, n, opts): (&Source<'_>, f64, usize, &SimOptions),
) -> Vec<Result<Vec<f64>, SimError>> {
    let r = opts.oversample;
    let h = 1.0 / (fs * r as f64);
    let per = if FINE { r } else { 1 };
    let mut ys = vec![vec![0.0; (n - 1) * per + 1]; LANES];
    let mut failed: [Option<SimError>; LANES] = std::array::from_fn(|_| None);
    let mut s = [[0.0; LANES]; 5];
    const THIRD: f64 = 1.0 / 3.0;
    for k in 0..n - 1 {
        for i in 0..r {
            let (u0, um, u1) = src.at(k, i, r);
            let y2 = axpy(&s, 0.5 * h, &kern.f::<T>(&s, u0));
            let y3 = axpy(&s, 0.5 * h, &kern.f::<T>(&y2, um));
            let y4 = axpy(&s, h, &kern.f::<T>(&y3, um));
            let k4 = kern.f::<T>(&y4, u1);
            s = std::array::from_fn(|c| {
                lanes(|l| {
                    THIRD * (y2[c][l] - s[c][l] + 2.0 * y3[c][l] + y4[c][l]) + (h / 6.0) * k4[c][l]
                })
            });
            if FINE {
                for l in 0..LANES {
                    ys[l][k * r + i + 1] = s[0][l];
                }
            }
        }
        for l in 0..LANES {
            ys[l][(k + 1) * per] = s[0][l];
            if failed[l].is_some() {
                continue;
            }
            if let Some((component, value)) = (0..5)
                .map(|c| (c, s[c][l]))
                .find(|(_, v)| !v.is_finite() || v.abs() > opts.max_abs_state)
            {
                let sample = k + 1;
                failed[l] = Some(SimError::Diverged {
                    sample,
                    time: sample as f64 / fs,
                    component,
                    value,
                });
                // The lane goes on from rest, so that its overflow slows no other.
                for c in s.iter_mut() {
                    c[l] = 0.0;
                }
            }
        }
    }
    ys.into_iter()
        .zip(failed)
        .map(|(y, f)| match f {
            Some(e) => Err(e),
            None => Ok(y),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use hyst_model::{BoucWen, Clearance, Coulomb, SecondMass, ZenerParams};

    fn white(n: usize, seed: u64) -> Vec<f64> {
        // A small linear congruential generator: the test needs a rough force, not quality.
        let mut x = seed;
        (0..n)
            .map(|_| {
                x = x
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((x >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 20.0
            })
            .collect()
    }

    fn models() -> Vec<Oscillator> {
        let w = 2.0 * std::f64::consts::PI * 10.0;
        let lin = Oscillator::linear(1.0, 2.0 * 0.02 * w, w * w);
        let mut v = vec![lin];
        let mut cubic = lin;
        cubic.extras.cubic_stiffness = 1e6;
        cubic.extras.quadratic_damping = 3.0;
        v.push(cubic);
        let mut zen = lin;
        zen.restoring = Restoring::Zener(ZenerParams {
            k_inf: 0.5 * w * w,
            omega: 40.0,
        });
        v.push(zen);
        let bw = |nu: f64| {
            let mut o = lin;
            o.restoring = Restoring::BoucWen(BoucWen {
                alpha: 0.3 * w * w,
                beta: 1.0,
                gamma: 200.0,
                delta: -50.0,
                nu,
            });
            o
        };
        v.extend([bw(1.0), bw(1.4), bw(1.0), bw(0.8)]);
        let mut rare = bw(1.0);
        rare.extras.clearance = Some(Clearance {
            gap: 0.002,
            stiffness: 2e4,
        });
        rare.extras.coulomb = Some(Coulomb {
            force: 0.5,
            smoothing_velocity: 1e-3,
        });
        v.push(rare);
        let mut surf = bw(1.0);
        surf.extras.surface = Some(hyst_model::ForceSurface {
            x_scale: 3e-3,
            v_scale: 0.2,
            coefficients: [0.5, 0.3, 0.1, 0.05, 0.2, 0.4, 0.1, 0.3, 0.2, 0.2],
        });
        v.push(surf);
        // Measurement chains, in a chunk beside lanes without one.
        let mut lagged = bw(1.0);
        lagged.chain = Some(hyst_model::MeasurementChain {
            delay: 3.3e-3,
            lag: 1e-3,
        });
        v.push(lagged);
        let mut delayed = zen;
        delayed.chain = Some(hyst_model::MeasurementChain {
            delay: 7e-3,
            lag: 0.0,
        });
        v.push(delayed);
        let mut two = cubic;
        two.extras.second_mass = Some(SecondMass {
            mass: 0.2,
            stiffness: 3e4,
            damping: 2.0,
        });
        v.push(two);
        v.push(zen);
        v
    }

    /// Every kind of model, more than one chunk of lanes, each input kind the lockstep run
    /// takes: the outputs are `simulate`'s to 1e-9 of the response's largest value (the
    /// same RK4 with the terms summed in another order; the rounding differences grow
    /// slowly over 3000 samples of a stable response, and stay far below this).
    #[test]
    fn lockstep_matches_one_by_one() {
        let ms = models();
        assert!(ms.len() > LANES);
        let u = white(3000, 7);
        let opts = SimOptions {
            oversample: 4,
            ..SimOptions::default()
        };
        let fine = crate::resample::interpolate_band_limited(&u, 8);
        for input in [
            Input::Sampled(&u),
            Input::BandLimited(&u),
            Input::Interpolated {
                samples: &fine,
                per_sample: 8,
            },
        ] {
            let many = simulate_many(&ms, input, 200.0, 2990, &opts);
            for (m, got) in ms.iter().zip(&many) {
                let want = crate::simulate(m, input, 200.0, 2990, &opts).expect("stable");
                let got = got.as_ref().expect("stable");
                let scale = want.iter().fold(0.0f64, |a, v| a.max(v.abs()));
                let worst = want
                    .iter()
                    .zip(got)
                    .fold(0.0f64, |a, (p, q)| a.max((p - q).abs()));
                assert!(worst <= 1e-9 * scale, "{input:?}: {worst} of {scale}");
            }
        }
    }

    /// The lanes' tanh against libm's over the range friction meets: within 4e-16
    /// absolutely (a few units in the last place of values near 1; near 0, where both are
    /// tiny, the rounding of 1 − e).
    #[test]
    fn lane_tanh_matches_the_library() {
        let mut worst = 0.0f64;
        for i in -40000..=40000 {
            let a = i as f64 * 1e-3 + 1e-7;
            let got = tanh_lanes(&[a, -a, 0.5 * a, 1e-9 * a]);
            for (g, x) in got.iter().zip([a, -a, 0.5 * a, 1e-9 * a]) {
                worst = worst.max((g - x.tanh()).abs());
            }
        }
        assert!(worst <= 4e-16, "{worst}");
        assert_eq!(tanh_lanes(&[1e6, -1e6, 0.0, -0.0]), [1.0, -1.0, 0.0, -0.0]);
        // Where all lanes are saturated the shortcut gives what the series and libm give.
        for a in [20.0f64, 20.1, 25.0, 700.0] {
            assert_eq!(a.tanh(), 1.0, "{a}");
            let series = tanh_lanes(&[a, -a, 1.0, a]);
            assert_eq!([series[0], series[1], series[3]], [1.0, -1.0, 1.0], "{a}");
            assert_eq!(tanh_lanes(&[a, -a, a, -a]), [1.0, -1.0, 1.0, -1.0], "{a}");
        }
    }

    /// A model that diverges and one that is invalid get their own errors; the others in
    /// their lanes are unaffected.
    #[test]
    fn each_lane_keeps_its_own_error() {
        let mut ms = models();
        ms[3].stiffness = -1e6; // unstable: grows without bound
        ms[2].mass = -1.0; // invalid
        let u = white(2000, 3);
        let opts = SimOptions {
            oversample: 4,
            max_abs_state: 1e3,
            ..SimOptions::default()
        };
        let many = simulate_many(&ms, Input::Sampled(&u), 200.0, 2000, &opts);
        assert!(matches!(many[3], Err(SimError::Diverged { .. })));
        assert!(matches!(many[2], Err(SimError::Model(_))));
        let want = crate::simulate(&ms[0], Input::Sampled(&u), 200.0, 2000, &opts).unwrap();
        let got = many[0].as_ref().unwrap();
        assert!(want.iter().zip(got).all(|(a, b)| (a - b).abs() <= 1e-9));
    }

    /// Options and inputs the lockstep run does not take are simulated one by one.
    #[test]
    fn other_options_fall_back_to_one_by_one() {
        let ms = models();
        let u = white(500, 5);
        let opts = SimOptions {
            oversample: 2,
            integrator: Integrator::Trapezoidal,
            ..SimOptions::default()
        };
        let many = simulate_many(&ms[..3], Input::Periodic(&u), 200.0, 800, &opts);
        for (m, got) in ms.iter().zip(many) {
            let want = crate::simulate(m, Input::Periodic(&u), 200.0, 800, &opts).unwrap();
            assert_eq!(got.unwrap(), want);
        }
    }
}
