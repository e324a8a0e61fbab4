//! Synthetic output-only records of linear systems with known modes (feature `synth`): the
//! one generator the tests, examples, documentation and benchmarks share.
//!
//! Each mode $j$ (natural frequency $f_j$, damping ratio $\zeta_j$) is a two-state oscillator
//! sampled exactly at $f_s$: its state $s_j$ advances by the rotation-and-decay of its discrete
//! pole $\mu_j = e^{\lambda_j/f_s}$, $\lambda_j = 2\pi f_j(-\zeta_j + i\sqrt{1-\zeta_j^2})$,
//!
//! $$ s_j(n+1) = \begin{pmatrix}\operatorname{Re}\mu_j & -\operatorname{Im}\mu_j\\
//! \operatorname{Im}\mu_j & \operatorname{Re}\mu_j\end{pmatrix} s_j(n) + w_j(n), $$
//!
//! driven by independent unit white noise $w_j$ in both states. Channel $c$ reads
//! $y_c(n) = \sum_j g_{c,2j}\,s_{j,0}(n) + g_{c,2j+1}\,s_{j,1}(n)$ plus white measurement
//! noise of a given fraction of its noise-free standard deviation. The output spectrum is
//! then exactly that of the refinement's model (a rational spectrum with the modes' poles),
//! so an estimator's error can be judged against the truth.
//!
//! ```
//! use covssi::synth::ModalRecord;
//! let system = ModalRecord::new(20.0, &[(1.5, 0.02), (4.0, 0.03)])
//!     .with_gains(vec![vec![1.0, 0.0, 0.5, 0.0], vec![0.3, 0.0, -1.0, 0.0]])
//!     .with_noise(0.05);
//! let y = system.generate(4096, 7);
//! assert_eq!((y.len(), y[0].len()), (2, 4096));
//! ```

use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use rand_distr::StandardNormal;

use crate::Complex64;

/// A linear system of known modes seen by some channels, and how a record of it is made.
#[derive(Debug, Clone, PartialEq)]
pub struct ModalRecord {
    /// Sampling rate (Hz).
    pub fs: f64,
    /// Each mode's natural frequency (Hz) and damping ratio.
    pub modes: Vec<(f64, f64)>,
    /// One row per channel: how it reads each mode's two states (2 · modes entries).
    /// Default: one channel reading the first state of every mode.
    pub gains: Vec<Vec<f64>>,
    /// Measurement noise of each channel, as a fraction of its noise-free standard
    /// deviation. Default 0.
    pub noise: f64,
    /// Samples run before the record starts, so that it is stationary. Default 2000.
    pub warm_up: usize,
}

impl ModalRecord {
    /// The modes `modes` (Hz, damping ratio) sampled at `fs` Hz, read by one channel, no
    /// measurement noise.
    pub fn new(fs: f64, modes: &[(f64, f64)]) -> Self {
        let mut first = vec![0.0; 2 * modes.len()];
        first.iter_mut().step_by(2).for_each(|g| *g = 1.0);
        ModalRecord {
            fs,
            modes: modes.to_vec(),
            gains: vec![first],
            noise: 0.0,
            warm_up: 2000,
        }
    }

    /// This system read through `gains` (one row of 2 · modes entries per channel).
    pub fn with_gains(mut self, gains: Vec<Vec<f64>>) -> Self {
        self.gains = gains;
        self
    }

    /// This system read with measurement noise of `fraction` of each channel's standard
    /// deviation.
    pub fn with_noise(mut self, fraction: f64) -> Self {
        self.noise = fraction;
        self
    }

    /// This system run `samples` samples before its record starts.
    pub fn with_warm_up(mut self, samples: usize) -> Self {
        self.warm_up = samples;
        self
    }

    /// The continuous poles λ (rad/s, Im λ > 0), one per mode.
    pub fn poles(&self) -> Vec<Complex64> {
        self.modes.iter().map(|&(f, z)| pole(f, z)).collect()
    }

    /// `n` samples of every channel (one vector per channel), seeded by `seed`
    /// (Xoshiro256++: a seed gives the same record everywhere).
    ///
    /// # Panics
    /// When a row of `gains` does not have 2 · modes entries: a test's mistake, not data.
    pub fn generate(&self, n: usize, seed: u64) -> Vec<Vec<f64>> {
        let m = self.modes.len();
        assert!(
            self.gains.iter().all(|g| g.len() == 2 * m),
            "each row of gains needs 2 entries per mode ({})",
            2 * m
        );
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let mu: Vec<Complex64> = self.poles().iter().map(|p| (p / self.fs).exp()).collect();
        let mut s = vec![[0.0f64; 2]; m];
        let mut out = vec![Vec::with_capacity(n); self.gains.len()];
        for t in 0..n + self.warm_up {
            for (state, mu) in s.iter_mut().zip(&mu) {
                let [p, q] = *state;
                let w0: f64 = rng.sample(StandardNormal);
                let w1: f64 = rng.sample(StandardNormal);
                *state = [mu.re * p - mu.im * q + w0, mu.im * p + mu.re * q + w1];
            }
            if t >= self.warm_up {
                for (channel, g) in out.iter_mut().zip(&self.gains) {
                    let y = s
                        .iter()
                        .enumerate()
                        .map(|(j, st)| g[2 * j] * st[0] + g[2 * j + 1] * st[1])
                        .sum();
                    channel.push(y);
                }
            }
        }
        if self.noise != 0.0 {
            for channel in &mut out {
                let len = channel.len().max(1) as f64;
                let mean = channel.iter().sum::<f64>() / len;
                let var = channel.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / len;
                let sd = self.noise * var.sqrt();
                for v in channel.iter_mut() {
                    *v += sd * rng.sample::<f64, _>(StandardNormal);
                }
            }
        }
        out
    }
}

/// A roving modal test with truth: a cantilever of `nodes` nodes, its first bending modes'
/// shapes approximated by sines, sin((2j+1)πk/2N) at node k (1-based, the tip last), read in
/// setups that share reference accelerometers while velocity sensors rove over the other
/// nodes, each setup at its own excitation level (1 + 0.5 × its index) and seed (the test's
/// seed plus its index). The records the multi-setup merge is judged on
/// (`tests/integration/multisetup.rs`) and compared with pyOMA2's (`cargo xtask compare-setups`).
#[derive(Debug, Clone, PartialEq)]
pub struct RovingTest {
    /// Nodes along the cantilever.
    pub nodes: usize,
    /// Each mode's natural frequency (Hz) and damping ratio, by increasing frequency.
    pub modes: Vec<(f64, f64)>,
    /// Sampling rate (Hz).
    pub fs: f64,
    /// Samples per setup.
    pub samples: usize,
    /// The reference nodes (accelerations), in every setup.
    pub references: Vec<usize>,
    /// Roving nodes (velocities) per setup.
    pub roving_per_setup: usize,
    /// Measurement noise, a fraction of each channel's standard deviation.
    pub noise: f64,
}

/// One channel of a [`RovingTest`]'s setup.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RovingChannel {
    /// Its node (1-based).
    pub node: usize,
    /// What it measures.
    pub quantity: crate::multisetup::Quantity,
    /// Whether it is a reference (in every setup).
    pub reference: bool,
}

impl RovingChannel {
    /// The channel as the merge describes it: its node by number, along x, gain 1.
    pub fn setup_channel(&self) -> crate::multisetup::SetupChannel {
        crate::multisetup::SetupChannel {
            node: self.node.to_string(),
            direction: [1.0, 0.0, 0.0],
            quantity: self.quantity,
            gain: 1.0,
            reference: self.reference,
        }
    }
}

impl RovingTest {
    /// The 12-node cantilever's three modes (1.3, 3.9, 6.6 Hz; 1.5–2.5 % damping) at 25 Hz,
    /// 320 s per setup, references at the tip and node 8, 5 % noise, `roving_per_setup` roving
    /// nodes per setup (2: five setups; 4: three).
    pub fn cantilever(roving_per_setup: usize) -> Self {
        RovingTest {
            nodes: 12,
            modes: vec![(1.3, 0.015), (3.9, 0.02), (6.6, 0.025)],
            fs: 25.0,
            samples: 8000,
            references: vec![12, 8],
            roving_per_setup,
            noise: 0.05,
        }
    }

    /// Mode `j`'s displacement at node `k` (1-based).
    pub fn truth(&self, j: usize, k: usize) -> f64 {
        ((2 * j + 1) as f64 * std::f64::consts::PI * k as f64 / (2 * self.nodes) as f64).sin()
    }

    /// The setups: each its roving nodes, then the references.
    pub fn layout(&self) -> Vec<Vec<RovingChannel>> {
        use crate::multisetup::Quantity;
        let roving: Vec<usize> = (1..=self.nodes)
            .filter(|k| !self.references.contains(k))
            .collect();
        roving
            .chunks(self.roving_per_setup.max(1))
            .map(|nodes| {
                let rove = nodes.iter().map(|&node| RovingChannel {
                    node,
                    quantity: Quantity::Velocity,
                    reference: false,
                });
                let refs = self.references.iter().map(|&node| RovingChannel {
                    node,
                    quantity: Quantity::Acceleration,
                    reference: true,
                });
                rove.chain(refs).collect()
            })
            .collect()
    }

    /// Setup `setup`'s record for the test's `seed`: each channel reads Re(φ λᵖ z) of every
    /// mode's complex state z, times the setup's level.
    pub fn record(&self, setup: usize, seed: u64) -> Vec<Vec<f64>> {
        let level = 1.0 + 0.5 * setup as f64;
        let gains = self.layout()[setup]
            .iter()
            .map(|c| {
                self.modes
                    .iter()
                    .enumerate()
                    .flat_map(|(j, &(f, z))| {
                        let g = level * self.truth(j, c.node) * pole(f, z).powi(c.quantity.power());
                        [g.re, -g.im]
                    })
                    .collect()
            })
            .collect();
        ModalRecord::new(self.fs, &self.modes)
            .with_gains(gains)
            .with_noise(self.noise)
            .generate(self.samples, seed + setup as u64)
    }
}

/// The continuous pole of a mode of `f` Hz and damping ratio `zeta` (Im λ > 0).
pub fn pole(f: f64, zeta: f64) -> Complex64 {
    2.0 * std::f64::consts::PI * f * Complex64::new(-zeta, (1.0 - zeta * zeta).sqrt())
}

/// Three accelerometer-like channels of two modes (2 and 6 Hz at 2 %) at 50 Hz, 5 % noise:
/// the unit tests' record of a decision that must keep both modes.
#[cfg(test)]
pub(crate) fn two_modes(n: usize, seed: u64) -> Vec<Vec<f64>> {
    ModalRecord::new(50.0, &[(2.0, 0.02), (6.0, 0.02)])
        .with_gains(vec![
            vec![1.0, 0.0, 1.0, 0.0],
            vec![0.8, 0.0, -0.5, 0.0],
            vec![0.4, 0.0, -1.0, 0.0],
        ])
        .with_noise(0.05)
        .generate(n, seed)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One mode read by one channel: the record's variance is the state's stationary
    /// variance 1/(1 − |μ|²), and its lag-one correlation Re μ of it; noise adds its share.
    #[test]
    fn one_mode_has_the_stationary_moments_of_its_pole() {
        let (fs, f, z) = (20.0, 2.0, 0.05);
        let n = 400_000;
        let y = ModalRecord::new(fs, &[(f, z)]).generate(n, 3);
        let mu = (pole(f, z) / fs).exp();
        let var = 1.0 / (1.0 - mu.norm_sqr());
        let v = y[0].iter().map(|a| a * a).sum::<f64>() / n as f64;
        let r1 = y[0].windows(2).map(|w| w[0] * w[1]).sum::<f64>() / (n - 1) as f64;
        // The sample variance of a process with correlation time ~1/(ζω) = 16 samples over
        // 4e5 samples: a relative standard error of about 1 %; 5 % is five of them.
        approx::assert_relative_eq!(v, var, max_relative = 0.05);
        approx::assert_relative_eq!(r1 / v, mu.re, max_relative = 0.05);
        let noisy = ModalRecord::new(fs, &[(f, z)])
            .with_noise(0.5)
            .generate(n, 3);
        let vn = noisy[0].iter().map(|a| a * a).sum::<f64>() / n as f64;
        approx::assert_relative_eq!(vn, 1.25 * v, max_relative = 0.02);
    }
}
