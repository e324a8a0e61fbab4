//! Records of a shear building under random loads, made independently of any modal model:
//! the structure in physical coordinates, integrated in time, its loads filtered noise.
//!
//! A chain of $n$ floors (masses $m_i$) joined by storeys (stiffnesses $k_i$, storey 1 to
//! the ground): $M\ddot x + C\dot x + K x + g(x, z) = f(t)$ with $K$ tridiagonal and
//! classical damping $C = M\Phi\,\mathrm{diag}(2\zeta_j\omega_j)\,\Phi^\top M$ ($\Phi$ the
//! mass-normalized modes of $(K, M)$), so that mode $j$ has exactly the natural frequency
//! $\omega_j$ and damping ratio $\zeta_j$ given — the truth a modal analysis is judged by.
//! One storey may hold a Bouc-Wen element in parallel, $g = k_s(1-a)\,(z - d)$ on its drift
//! $d$, $\dot z = \dot d - \beta|\dot d||z|^{\nu-1}z - \gamma\dot d|z|^\nu$: at small drift
//! $z \approx d$ and the structure is the linear one; larger drifts soften it and dissipate.
//!
//! The state is integrated by the classical fourth-order Runge–Kutta method at `oversample`
//! steps per output sample ($\omega_{\max} h \le 0.1$), the load held linear between steps;
//! the output is read every `oversample` steps. Loads ([`Load`]): Gaussian white noise on
//! chosen floors at the fine rate, coloured by a filter ([`Colour`]: a Butterworth low-pass,
//! a resonance, a first-order roll-off), slowly modulated in amplitude, plus a machine's
//! sinusoid. Sensors read accelerations, velocities or displacements of chosen floors, with
//! white noise of a share of each channel's standard deviation and a slow drift.

use nalgebra::{DMatrix, DVector, SymmetricEigen};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use rand_distr::StandardNormal;

use crate::SimError;

mod validate;

/// A storey's Bouc-Wen element (in parallel with the rest of its stiffness).
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct StoreyHysteresis {
    /// The storey (0: between the ground and floor 1).
    pub storey: usize,
    /// Share of the storey's stiffness that stays linear (the rest is the element's).
    pub linear_share: f64,
    /// β (1/m^ν).
    pub beta: f64,
    /// γ (1/m^ν).
    pub gamma: f64,
    /// ν.
    pub nu: f64,
}

/// What the load's white noise is filtered by.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Colour {
    /// A Butterworth low-pass of this order (1–8) at this corner (Hz).
    LowPass {
        /// Corner (Hz).
        corner_hz: f64,
        /// Order.
        order: usize,
    },
    /// A second-order resonance (a wave or a vortex's spectrum peak).
    Resonance {
        /// Its frequency (Hz).
        frequency_hz: f64,
        /// Its damping ratio.
        damping_ratio: f64,
    },
    /// A first-order roll-off above this corner (Hz): a red spectrum.
    Red {
        /// Corner (Hz).
        corner_hz: f64,
    },
}

/// The loads.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct Load {
    /// Floors loaded (0-based), each by its own noise.
    pub floors: Vec<usize>,
    /// RMS of each floor's load before colouring (N).
    pub rms: f64,
    /// Filters applied in turn.
    pub colours: Vec<Colour>,
    /// Amplitude modulation: the load times 1 + depth·sin(2πt/period).
    pub modulation: Option<(f64, f64)>,
    /// A machine: (floor, frequency Hz, amplitude N).
    pub harmonic: Option<(usize, f64, f64)>,
}

/// What the sensors read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Reading {
    /// Displacement.
    Displacement,
    /// Velocity.
    Velocity,
    /// Acceleration.
    Acceleration,
}

/// A shear building, its loads and its sensors.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct ShearBuilding {
    /// Floor masses (kg), from the first floor up.
    pub masses: Vec<f64>,
    /// Storey stiffnesses (N/m), storey 0 to the ground.
    pub stiffnesses: Vec<f64>,
    /// Each mode's damping ratio, lowest mode first.
    pub damping_ratios: Vec<f64>,
    /// A Bouc-Wen element in one storey.
    pub hysteresis: Option<StoreyHysteresis>,
    /// The loads.
    pub load: Load,
    /// Floors read (0-based).
    pub sensors: Vec<usize>,
    /// What they read.
    pub reading: Reading,
    /// Sensor noise: a share of each channel's standard deviation.
    pub noise: f64,
    /// Sensor drift: a random walk reaching this share of the channel's standard deviation
    /// over the record.
    pub drift: f64,
    /// Output rate (Hz).
    pub fs: f64,
}

/// A mode of the linear structure: the truth.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct TrueMode {
    /// Natural frequency (Hz).
    pub frequency_hz: f64,
    /// Damping ratio.
    pub damping_ratio: f64,
    /// The shape at the sensors (largest entry 1).
    pub shape: Vec<f64>,
}

impl ShearBuilding {
    /// The three-storey chain the storey fit is tested and timed on: floor masses 1000,
    /// 1000 and 800 kg, storeys of 1.2, 1.0 and 0.8 MN/m, modal damping 2, 1.7 and 2 %, a
    /// Bouc-Wen element (a = 0.6, β = 750, γ = 500 m⁻¹, ν = 1) in the storey `element`
    /// (0-based) if any, an independent white force on every floor (its `load.rms` 0: set
    /// it), the three floors' accelerations at 200 Hz with 1 % noise.
    pub fn three_storey_example(element: Option<usize>) -> ShearBuilding {
        ShearBuilding {
            masses: vec![1000.0, 1000.0, 800.0],
            stiffnesses: vec![1.2e6, 1.0e6, 0.8e6],
            damping_ratios: vec![0.02, 0.017, 0.02],
            hysteresis: element.map(|storey| StoreyHysteresis {
                storey,
                linear_share: 0.6,
                beta: 750.0,
                gamma: 500.0,
                nu: 1.0,
            }),
            load: Load {
                floors: vec![0, 1, 2],
                rms: 0.0,
                colours: vec![],
                modulation: None,
                harmonic: None,
            },
            sensors: vec![0, 1, 2],
            reading: Reading::Acceleration,
            noise: 0.01,
            drift: 0.0,
            fs: 200.0,
        }
    }
}

impl ShearBuilding {
    /// The linear structure's modes, lowest first, and the mass-normalized shapes at every
    /// floor (columns).
    fn eigen(&self) -> Result<(Vec<f64>, DMatrix<f64>), SimError> {
        self.validate()?;
        let n = self.masses.len();
        let k = self.stiffness_matrix();
        // M^{-1/2} K M^{-1/2}: symmetric, its eigenvectors give Φ = M^{-1/2} V.
        let inv_sqrt: Vec<f64> = self.masses.iter().map(|m| 1.0 / m.sqrt()).collect();
        let a = DMatrix::from_fn(n, n, |i, j| inv_sqrt[i] * k[(i, j)] * inv_sqrt[j]);
        let eig = SymmetricEigen::new(a);
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&i, &j| eig.eigenvalues[i].total_cmp(&eig.eigenvalues[j]));
        let omegas = order.iter().map(|&i| eig.eigenvalues[i].sqrt()).collect();
        let phi = DMatrix::from_fn(n, n, |r, c| inv_sqrt[r] * eig.eigenvectors[(r, order[c])]);
        Ok((omegas, phi))
    }

    /// Classical damping: C = M Φ diag(2ζω) Φᵀ M, Φ mass-normalized.
    fn damping_matrix(&self, omegas: &[f64], phi: &DMatrix<f64>) -> DMatrix<f64> {
        let n = self.masses.len();
        let m = DMatrix::from_diagonal(&DVector::from_vec(self.masses.clone()));
        let d = DMatrix::from_diagonal(&DVector::from_iterator(
            n,
            omegas
                .iter()
                .zip(&self.damping_ratios)
                .map(|(w, z)| 2.0 * z * w),
        ));
        &m * phi * d * phi.transpose() * &m
    }

    fn stiffness_matrix(&self) -> DMatrix<f64> {
        let n = self.masses.len();
        let mut k = DMatrix::zeros(n, n);
        for (s, &ks) in self.stiffnesses.iter().enumerate() {
            // Storey s joins floor s−1 (the ground for s = 0) and floor s.
            k[(s, s)] += ks;
            if s > 0 {
                k[(s - 1, s - 1)] += ks;
                k[(s - 1, s)] -= ks;
                k[(s, s - 1)] -= ks;
            }
        }
        k
    }

    /// The rate the structure is integrated at (Hz): `fs` times the steps per sample.
    pub fn fine_rate(&self) -> Result<f64, SimError> {
        let (omegas, _) = self.eigen()?;
        Ok(self.fs * oversample(&omegas, self.fs) as f64)
    }

    /// The linear structure's modes at the sensors, lowest first.
    pub fn modes(&self) -> Result<Vec<TrueMode>, SimError> {
        let (omegas, phi) = self.eigen()?;
        Ok(omegas
            .iter()
            .enumerate()
            .map(|(j, w)| {
                let raw: Vec<f64> = self.sensors.iter().map(|&s| phi[(s, j)]).collect();
                let big = raw
                    .iter()
                    .fold(0.0f64, |a, v| if v.abs() > a.abs() { *v } else { a });
                TrueMode {
                    frequency_hz: w / (2.0 * std::f64::consts::PI),
                    damping_ratio: self.damping_ratios[j],
                    shape: raw.iter().map(|v| v / big).collect(),
                }
            })
            .collect())
    }

    /// A record of `samples` samples (one vector per sensor), from noise seeded by `seed`.
    pub fn generate(&self, samples: usize, seed: u64) -> Result<Vec<Vec<f64>>, SimError> {
        let (omegas, phi) = self.eigen()?;
        let oversample = oversample(&omegas, self.fs);
        let h = 1.0 / (self.fs * oversample as f64);
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let warm = (20.0 / (omegas[0] * self.damping_ratios[0].max(1e-3)) * self.fs) as usize;
        let fine = (warm + samples) * oversample + 1;
        let loads = self.loads(fine, h, &mut rng)?;
        let mut out = self.respond_checked(&loads, oversample, warm, (&omegas, &phi))?;
        self.sensor_errors(&mut out, &mut rng);
        Ok(out)
    }

    /// The noise-free sensor readings under given loads: `loads[i]` is floor `i`'s force at
    /// `oversample` steps per output sample (held linear between steps; every column as long,
    /// a multiple of `oversample` plus one), integrated from rest; the first `skip` output
    /// samples are dropped. The building's own [`Load`], noise and drift are not used. A caller
    /// that draws the loads itself can keep them fixed while the structure changes (common
    /// random numbers), which [`ShearBuilding::generate`] cannot: its step and warm-up follow
    /// the structure.
    pub fn respond(
        &self,
        loads: &[Vec<f64>],
        oversample: usize,
        skip: usize,
    ) -> Result<Vec<Vec<f64>>, SimError> {
        let (omegas, phi) = self.eigen()?;
        let n = self.masses.len();
        let fine = loads.first().map_or(0, Vec::len);
        if loads.len() != n || loads.iter().any(|l| l.len() != fine) {
            return Err(SimError::InvalidSignal {
                what: "building: one load column per floor, all as long",
                value: loads.len() as f64,
            });
        }
        if oversample == 0 || fine == 0 || !(fine - 1).is_multiple_of(oversample) {
            return Err(SimError::InvalidSignal {
                what: "building: load columns of a multiple of the steps per sample plus one",
                value: fine as f64,
            });
        }
        self.respond_checked(loads, oversample, skip, (&omegas, &phi))
    }

    /// [`ShearBuilding::respond`] on checked input, with the structure's modes.
    fn respond_checked(
        &self,
        loads: &[Vec<f64>],
        oversample: usize,
        skip: usize,
        (omegas, phi): (&[f64], &DMatrix<f64>),
    ) -> Result<Vec<Vec<f64>>, SimError> {
        let n = self.masses.len();
        let h = 1.0 / (self.fs * oversample as f64);
        let steps = loads[0].len() - 1;
        let step = Dynamics {
            inv_m: self.masses.iter().map(|v| 1.0 / v).collect(),
            c: self.damping_matrix(omegas, phi),
            k: self.stiffness_matrix(),
            hysteresis: self.hysteresis.clone(),
            stiffnesses: self.stiffnesses.clone(),
        };
        let samples = (steps / oversample).saturating_sub(skip);
        let mut state = vec![0.0; 2 * n + 1];
        let mut scratch = RkScratch::new(2 * n + 1);
        let mut out: Vec<Vec<f64>> = vec![Vec::with_capacity(samples); self.sensors.len()];
        let mut f0 = vec![0.0; n];
        let mut fm = vec![0.0; n];
        let mut f1 = vec![0.0; n];
        let mut acc = vec![0.0; 2 * n + 1];
        for t in 0..steps {
            for i in 0..n {
                f0[i] = loads[i][t];
                f1[i] = loads[i][t + 1];
                fm[i] = 0.5 * (f0[i] + f1[i]);
            }
            step.rk4(&mut state, h, (&f0, &fm, &f1), &mut scratch);
            if (t + 1) % oversample == 0 && (t + 1) / oversample > skip {
                if self.reading == Reading::Acceleration {
                    step.derivative(&state, &f1, &mut acc);
                }
                for (o, &s) in out.iter_mut().zip(&self.sensors) {
                    o.push(match self.reading {
                        Reading::Displacement => state[s],
                        Reading::Velocity => state[n + s],
                        Reading::Acceleration => acc[n + s],
                    });
                }
            }
            if let Some(bad) = state.iter().position(|v| !v.is_finite()) {
                return Err(SimError::Diverged {
                    sample: t / oversample,
                    time: t as f64 * h,
                    component: bad,
                    value: state[bad],
                });
            }
        }
        Ok(out)
    }

    /// Each floor's load at the fine rate (`fine` samples, step `h`).
    fn loads(
        &self,
        fine: usize,
        h: f64,
        rng: &mut Xoshiro256PlusPlus,
    ) -> Result<Vec<Vec<f64>>, SimError> {
        let n = self.masses.len();
        let mut loads = vec![vec![0.0; fine]; n];
        let filters: Vec<Vec<Biquad>> = self
            .load
            .colours
            .iter()
            .map(|c| c.sections(1.0 / h))
            .collect::<Result<_, _>>()?;
        for &floor in &self.load.floors {
            let mut sections: Vec<Biquad> = filters.iter().flatten().copied().collect();
            let column = &mut loads[floor];
            for v in column.iter_mut() {
                let mut x = self.load.rms * rng.sample::<f64, _>(StandardNormal);
                for s in sections.iter_mut() {
                    x = s.run(x);
                }
                *v += x;
            }
        }
        let two_pi = 2.0 * std::f64::consts::PI;
        if let Some((depth, period)) = self.load.modulation {
            for column in loads.iter_mut() {
                for (t, v) in column.iter_mut().enumerate() {
                    *v *= 1.0 + depth * (two_pi * t as f64 * h / period).sin();
                }
            }
        }
        if let Some((floor, hz, amplitude)) = self.load.harmonic {
            let column = loads.get_mut(floor).ok_or(SimError::InvalidSignal {
                what: "building: the machine's floor",
                value: floor as f64,
            })?;
            let phase = rng.random::<f64>() * two_pi;
            for (t, v) in column.iter_mut().enumerate() {
                *v += amplitude * (two_pi * hz * t as f64 * h + phase).sin();
            }
        }
        Ok(loads)
    }

    /// White noise and a random-walk drift added to each channel, as shares of its
    /// standard deviation.
    fn sensor_errors(&self, out: &mut [Vec<f64>], rng: &mut Xoshiro256PlusPlus) {
        for channel in out.iter_mut() {
            let len = channel.len().max(1) as f64;
            let mean = channel.iter().sum::<f64>() / len;
            let sd = (channel.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / len).sqrt();
            let step = self.drift * sd / len.sqrt();
            let mut walk = 0.0;
            for v in channel.iter_mut() {
                walk += step * rng.sample::<f64, _>(StandardNormal);
                *v += self.noise * sd * rng.sample::<f64, _>(StandardNormal) + walk;
            }
        }
    }
}

impl Colour {
    /// The analog prototype's power gain |G(iω)|² at `hz`.
    fn power_gain(&self, hz: f64) -> f64 {
        match *self {
            Colour::LowPass { corner_hz, order } => {
                1.0 / (1.0 + (hz / corner_hz).powi(2 * order as i32))
            }
            Colour::Resonance {
                frequency_hz,
                damping_ratio,
            } => {
                let r = hz / frequency_hz;
                1.0 / ((1.0 - r * r).powi(2) + (2.0 * damping_ratio * r).powi(2))
            }
            Colour::Red { corner_hz } => 1.0 / (1.0 + (hz / corner_hz).powi(2)),
        }
    }
}

impl ShearBuilding {
    /// The noise-free response's two-sided spectral density (per rad/s) at each sensor at
    /// `hz`, from the linear structure's frequency response under the random load (the
    /// machine and the modulation left out).
    pub fn response_density(&self, hz: f64) -> Result<Vec<f64>, SimError> {
        use nalgebra::Complex;
        let (omegas, phi) = self.eigen()?;
        let n = self.masses.len();
        let w = 2.0 * std::f64::consts::PI * hz;
        let m = DMatrix::from_diagonal(&DVector::from_vec(self.masses.clone()));
        let c = self.damping_matrix(&omegas, &phi);
        let k = self.stiffness_matrix();
        let z = DMatrix::from_fn(n, n, |i, j| {
            Complex::new(k[(i, j)] - w * w * m[(i, j)], w * c[(i, j)])
        });
        let lu = z.lu();
        let fine = self.fine_rate()?;
        let gain: f64 = self.load.colours.iter().map(|c| c.power_gain(hz)).product();
        let s_f = self.load.rms.powi(2) / (2.0 * std::f64::consts::PI * fine) * gain;
        let power = match self.reading {
            Reading::Displacement => 0,
            Reading::Velocity => 1,
            Reading::Acceleration => 2,
        };
        let mut out = vec![0.0; self.sensors.len()];
        for &l in &self.load.floors {
            let mut e = DVector::from_element(n, Complex::new(0.0, 0.0));
            e[l] = Complex::new(1.0, 0.0);
            let h = lu.solve(&e).ok_or(SimError::InvalidSignal {
                what: "building: a singular frequency response",
                value: hz,
            })?;
            for (o, &s) in out.iter_mut().zip(&self.sensors) {
                *o += h[s].norm_sqr() * s_f * w.powi(2 * power);
            }
        }
        Ok(out)
    }

    /// Each sensor's noise-free standard deviation, by integrating
    /// [`ShearBuilding::response_density`] over ±Nyquist of the output rate (a mode's
    /// half-power band sampled by at least 20 lines).
    pub fn response_deviation(&self) -> Result<Vec<f64>, SimError> {
        let modes = self.modes()?;
        let min_band = modes
            .iter()
            .map(|m| m.frequency_hz * m.damping_ratio)
            .fold(f64::INFINITY, f64::min);
        let nyquist = self.fs / 2.0;
        let dhz = (min_band / 20.0).min(nyquist / 2000.0);
        let lines = (nyquist / dhz).ceil() as usize;
        let mut var = vec![0.0; self.sensors.len()];
        for i in 0..lines {
            let hz = (i as f64 + 0.5) * dhz;
            let s = self.response_density(hz)?;
            // Two-sided density per rad/s over ±ω: twice the positive half, dω = 2π·dhz.
            for (v, x) in var.iter_mut().zip(s) {
                *v += 2.0 * x * 2.0 * std::f64::consts::PI * dhz;
            }
        }
        Ok(var.into_iter().map(f64::sqrt).collect())
    }
}

/// Steps per output sample: ω_max·h at most 0.1, at least 4.
fn oversample(omegas: &[f64], fs: f64) -> usize {
    let w_max = omegas.iter().copied().fold(0.0, f64::max);
    ((10.0 * w_max / fs).ceil() as usize).max(4)
}

/// The equations of motion, state (x, ẋ, z).
struct Dynamics {
    inv_m: Vec<f64>,
    c: DMatrix<f64>,
    k: DMatrix<f64>,
    hysteresis: Option<StoreyHysteresis>,
    stiffnesses: Vec<f64>,
}

/// The stages of one Runge–Kutta step, kept between steps (no allocation per step).
struct RkScratch {
    k: [Vec<f64>; 4],
    trial: Vec<f64>,
}

impl RkScratch {
    fn new(len: usize) -> RkScratch {
        RkScratch {
            k: std::array::from_fn(|_| vec![0.0; len]),
            trial: vec![0.0; len],
        }
    }
}

impl Dynamics {
    /// The state's derivative into `ds` (as long as the state).
    fn derivative(&self, s: &[f64], f: &[f64], ds: &mut [f64]) {
        let n = self.inv_m.len();
        let (x, v) = (&s[..n], &s[n..2 * n]);
        ds[..n].copy_from_slice(v);
        ds[2 * n] = 0.0;
        for i in 0..n {
            let r: f64 = (0..n)
                .map(|j| self.c[(i, j)] * v[j] + self.k[(i, j)] * x[j])
                .sum();
            ds[n + i] = f[i] - r;
        }
        if let Some(hy) = &self.hysteresis {
            let st = hy.storey;
            let drift = x[st] - if st > 0 { x[st - 1] } else { 0.0 };
            let rate = v[st] - if st > 0 { v[st - 1] } else { 0.0 };
            let z = s[2 * n];
            // The element replaces the linear spring's share (1 − a) of the storey.
            let g = self.stiffnesses[st] * (1.0 - hy.linear_share) * (z - drift);
            ds[n + st] -= g;
            if st > 0 {
                ds[n + st - 1] += g;
            }
            let za = z.abs();
            ds[2 * n] = rate
                - hy.beta * rate.abs() * za.powf(hy.nu - 1.0) * z
                - hy.gamma * rate * za.powf(hy.nu);
        }
        for (d, im) in ds[n..2 * n].iter_mut().zip(&self.inv_m) {
            *d *= im;
        }
    }

    fn rk4(
        &self,
        s: &mut [f64],
        h: f64,
        (f0, fm, f1): (&[f64], &[f64], &[f64]),
        w: &mut RkScratch,
    ) {
        let [k1, k2, k3, k4] = &mut w.k;
        let trial = &mut w.trial;
        let add = |out: &mut [f64], a: &[f64], b: &[f64], w: f64| {
            for ((o, x), y) in out.iter_mut().zip(a).zip(b) {
                *o = x + w * y;
            }
        };
        self.derivative(s, f0, k1);
        add(trial, s, k1, h / 2.0);
        self.derivative(trial, fm, k2);
        add(trial, s, k2, h / 2.0);
        self.derivative(trial, fm, k3);
        add(trial, s, k3, h);
        self.derivative(trial, f1, k4);
        for (i, si) in s.iter_mut().enumerate() {
            *si += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
    }
}

/// A second-order section, direct form II transposed.
#[derive(Debug, Clone, Copy)]
struct Biquad {
    b: [f64; 3],
    a: [f64; 2],
    w: [f64; 2],
}

impl Biquad {
    /// The bilinear transform of (b0 + b1 s + b2 s²)/(a0 + a1 s + a2 s²) at rate `fs`,
    /// prewarped at `warp` rad/s.
    fn bilinear(num: [f64; 3], den: [f64; 3], fs: f64, warp: f64) -> Biquad {
        let c = warp / (warp / (2.0 * fs)).tan();
        let (c2, [b0, b1, b2], [a0, a1, a2]) = (c * c, num, den);
        let d0 = a0 + a1 * c + a2 * c2;
        Biquad {
            b: [
                (b0 + b1 * c + b2 * c2) / d0,
                (2.0 * b0 - 2.0 * b2 * c2) / d0,
                (b0 - b1 * c + b2 * c2) / d0,
            ],
            a: [
                (2.0 * a0 - 2.0 * a2 * c2) / d0,
                (a0 - a1 * c + a2 * c2) / d0,
            ],
            w: [0.0; 2],
        }
    }

    fn run(&mut self, x: f64) -> f64 {
        let y = self.b[0] * x + self.w[0];
        self.w[0] = self.b[1] * x - self.a[0] * y + self.w[1];
        self.w[1] = self.b[2] * x - self.a[1] * y;
        y
    }
}

impl Colour {
    /// The filter as second-order sections at rate `fs` (unit gain at 0 Hz).
    fn sections(&self, fs: f64) -> Result<Vec<Biquad>, SimError> {
        let two_pi = 2.0 * std::f64::consts::PI;
        let check = |what: &'static str, hz: f64| {
            if hz > 0.0 && hz < fs / 2.0 {
                Ok(two_pi * hz)
            } else {
                Err(SimError::InvalidSignal { what, value: hz })
            }
        };
        Ok(match *self {
            Colour::LowPass { corner_hz, order } => {
                let w = check("low-pass corner (Hz)", corner_hz)?;
                if !(1..=8).contains(&order) {
                    return Err(SimError::InvalidSignal {
                        what: "low-pass order",
                        value: order as f64,
                    });
                }
                let mut out = Vec::new();
                for k in 0..order / 2 {
                    // The Butterworth pair's damping: sin of its pole's angle.
                    let theta = std::f64::consts::PI * (2 * k + 1) as f64 / (2 * order) as f64;
                    let q = 2.0 * theta.sin();
                    out.push(Biquad::bilinear(
                        [w * w, 0.0, 0.0],
                        [w * w, q * w, 1.0],
                        fs,
                        w,
                    ));
                }
                if order % 2 == 1 {
                    out.push(Biquad::bilinear([w, 0.0, 0.0], [w, 1.0, 0.0], fs, w));
                }
                out
            }
            Colour::Resonance {
                frequency_hz,
                damping_ratio,
            } => {
                let w = check("resonance (Hz)", frequency_hz)?;
                vec![Biquad::bilinear(
                    [w * w, 0.0, 0.0],
                    [w * w, 2.0 * damping_ratio * w, 1.0],
                    fs,
                    w,
                )]
            }
            Colour::Red { corner_hz } => {
                let w = check("red corner (Hz)", corner_hz)?;
                vec![Biquad::bilinear([w, 0.0, 0.0], [w, 1.0, 0.0], fs, w)]
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_storey() -> ShearBuilding {
        ShearBuilding {
            masses: vec![1000.0, 1000.0],
            stiffnesses: vec![4e5, 4e5],
            damping_ratios: vec![0.02, 0.02],
            hysteresis: None,
            load: Load {
                floors: vec![0, 1],
                rms: 100.0,
                colours: vec![],
                modulation: None,
                harmonic: None,
            },
            sensors: vec![0, 1],
            reading: Reading::Displacement,
            noise: 0.0,
            drift: 0.0,
            fs: 50.0,
        }
    }

    #[test]
    fn two_storeys_have_the_textbook_frequencies() {
        // Equal masses m and storeys k: ω² = (3 ∓ √5)/2 · k/m.
        let b = two_storey();
        let modes = b.modes().unwrap();
        let km: f64 = 4e5 / 1000.0;
        for (j, sign) in [(0, -1.0), (1, 1.0)] {
            let w = ((3.0 + sign * 5f64.sqrt()) / 2.0 * km).sqrt();
            // Symmetric eigen-solver: relative 1e-12.
            assert!((modes[j].frequency_hz * 2.0 * std::f64::consts::PI / w - 1.0).abs() < 1e-12);
        }
        // First mode: both floors in phase, the top (1+√5)/2 times the first.
        let ratio = modes[0].shape[0] / modes[0].shape[1];
        assert!((ratio - 2.0 / (1.0 + 5f64.sqrt())).abs() < 1e-12);
    }

    #[test]
    fn the_response_variance_is_the_modal_sum() {
        // White load of variance σ² at the fine rate F on floor 0: a two-sided density
        // σ²/(2πF) per rad/s, so each modal coordinate has variance φ₀²σ²/(4Fζω³), and a
        // floor's displacement the sum over modes of φ_j² times it (the cross-term of two
        // modes 2.6 times apart at 2 % damping is under 1 % of it).
        let mut b = two_storey();
        b.load.floors = vec![0];
        let (omegas, phi) = b.eigen().unwrap();
        let y = b.generate(200_000, 3).unwrap();
        let fine = b.fine_rate().unwrap();
        let sigma2 = b.load.rms.powi(2);
        for j in 0..2 {
            let predicted: f64 = (0..2)
                .map(|r| {
                    let (w, z) = (omegas[r], b.damping_ratios[r]);
                    (phi[(j, r)] * phi[(0, r)]).powi(2) * sigma2 / (4.0 * fine * z * w.powi(3))
                })
                .sum();
            let n = y[j].len() as f64;
            let var = y[j].iter().map(|v| v * v).sum::<f64>() / n;
            // 4000 s of a 2 % mode at 2 Hz: its variance's estimate has a relative
            // standard deviation √(1/(2ζωT)) ≈ 3.5 %; 12 % is over three of them.
            assert!(
                (var / predicted - 1.0).abs() < 0.12,
                "{j}: {var} vs {predicted}"
            );
        }
    }

    #[test]
    fn the_frequency_responses_deviation_is_the_records() {
        // Two computations of one number: the record integrated in time, and the response
        // density integrated over frequency (coloured load, accelerations).
        let mut b = two_storey();
        b.reading = Reading::Acceleration;
        b.load.colours = vec![Colour::LowPass {
            corner_hz: 5.0,
            order: 4,
        }];
        let y = b.generate(200_000, 11).unwrap();
        let sd = b.response_deviation().unwrap();
        for (c, s) in y.iter().zip(&sd) {
            let n = c.len() as f64;
            let got = (c.iter().map(|v| v * v).sum::<f64>() / n).sqrt();
            // The variance's sampling error over 4000 s of 2 % modes is ~4 % (2 % on the
            // deviation); the analog prototype's gain differs from the bilinear filter's
            // by under 1 % below the corner.
            assert!((got / s - 1.0).abs() < 0.08, "{got} vs {s}");
        }
    }

    #[test]
    fn a_linear_buildings_response_to_given_loads_is_linear_and_checked() {
        let b = two_storey();
        let loads: Vec<Vec<f64>> = (0..2)
            .map(|f| {
                (0..8 * 500 + 1)
                    .map(|t| ((t * (f + 3)) % 17) as f64 - 8.0)
                    .collect()
            })
            .collect();
        let y = b.respond(&loads, 8, 100).unwrap();
        assert_eq!((y.len(), y[0].len()), (2, 400));
        let doubled: Vec<Vec<f64>> = loads
            .iter()
            .map(|c| c.iter().map(|v| 2.0 * v).collect())
            .collect();
        let y2 = b.respond(&doubled, 8, 100).unwrap();
        for (a, c) in y.iter().flatten().zip(y2.iter().flatten()) {
            // Linear state equations, the same steps: twice, to rounding.
            assert!((c - 2.0 * a).abs() <= 1e-9 * a.abs().max(1e-12), "{a} {c}");
        }
        assert!(b.respond(&loads[..1], 8, 0).is_err());
        let short: Vec<Vec<f64>> = loads.iter().map(|c| c[..100].to_vec()).collect();
        assert!(matches!(
            b.respond(&short, 8, 0),
            Err(SimError::InvalidSignal { value, .. }) if value == 100.0
        ));
    }

    #[test]
    fn a_butterworth_section_has_unit_gain_and_half_power_at_its_corner() {
        let fs = 1000.0;
        let corner = 50.0;
        let secs = Colour::LowPass {
            corner_hz: corner,
            order: 4,
        }
        .sections(fs)
        .unwrap();
        let gain = |hz: f64| -> f64 {
            use realfft::num_complex::Complex64;
            let z1 = Complex64::from_polar(1.0, -2.0 * std::f64::consts::PI * hz / fs);
            let z2 = z1 * z1;
            secs.iter()
                .map(|s| {
                    let num = s.b[0] + s.b[1] * z1 + s.b[2] * z2;
                    let den = 1.0 + s.a[0] * z1 + s.a[1] * z2;
                    (num / den).norm()
                })
                .product()
        };
        // Bilinear transform prewarped at the corner: exact there (1e-12).
        assert!((gain(1e-9) - 1.0).abs() < 1e-9);
        assert!((gain(corner) - 0.5f64.sqrt()).abs() < 1e-9);
        assert!(gain(4.0 * corner) < 0.01);
    }
}
