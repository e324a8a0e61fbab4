//! A synthetic monitoring campaign (feature `synth`): a structure recorded many times a day
//! for weeks, its frequencies following the temperature, its excitation and so its
//! signal-to-noise ratio varying, and from a given day a stiffness loss lowering one mode.
//! Each record is made on demand by `covssi::synth` (the project's one generator), so a
//! campaign of any length takes the memory of one record.
//!
//! Record i is taken at t_i = i / per_day days. The temperature is
//! T(t) = T₀ + A_d sin(2π t) + A_s sin(2π t / P_s) (a daily cycle and a seasonal swing); mode
//! j's frequency is f_j (1 + a (T − T₀)) (1 + η_ij), with η_ij an environmental effect the
//! temperature does not explain (of standard deviation `unexplained`; independent from record
//! to record, or with `unexplained_hours` a first-order autoregression), times
//! (1 + `change`) for the changed mode from `change_day` on; with `frost`, times
//! (1 + c_f min(0, T_s − T_f)) for the structure's temperature T_s below T_f; with
//! `amplitude_coefficient` b, times (1 + b ln level). A `harmonic` (a machine) adds a
//! sinusoid to every channel of a share of the records. The excitation level is
//! log-normal (its log's standard deviation `level_spread`); the sensors' noise has a fixed
//! size, so its fraction of the response is `noise` / level. The temperature is measured with
//! white error `temperature_noise`.

use covssi::synth::ModalRecord;
use rand::{SeedableRng, rngs::Xoshiro256PlusPlus};
use rand_distr::{Distribution, Normal};

/// A campaign's design (see the module's documentation).
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct Campaign {
    /// Days recorded.
    pub days: usize,
    /// Records per day.
    pub per_day: usize,
    /// Sampling rate (Hz).
    pub fs: f64,
    /// Length of each record (s).
    pub seconds: f64,
    /// Each mode's frequency at T₀ (Hz) and damping ratio.
    pub modes: Vec<(f64, f64)>,
    /// Sensors: channel c reads mode j as sin((j + 1) π (c + 1) / (channels + 1)).
    pub channels: usize,
    /// T₀, the daily and the seasonal amplitudes (°C), and the seasonal period (days).
    pub temperature: (f64, f64, f64, f64),
    /// a: relative frequency change per °C.
    pub temperature_coefficient: f64,
    /// Standard deviation of the temperature's measurement (°C).
    pub temperature_noise: f64,
    /// Standard deviation of the relative frequency change the temperature does not explain.
    pub unexplained: f64,
    /// The structure's thermal time constant τ (hours): the frequencies follow the air's
    /// temperature through a first-order lag, each cycle of period P damped by
    /// 1/√(1 + (2πτ/P)²) and delayed by atan(2πτ/P)/(2π/P), while the covariate is the air's
    /// temperature (0: no lag).
    pub thermal_lag_hours: f64,
    /// Its correlation time (hours): 0 makes it independent from record to record, τ > 0 a
    /// first-order autoregression over the records with φ = e^{−Δt/τ} (an unmeasured slow
    /// effect: moisture, the structure's temperature lagging the air's).
    pub unexplained_hours: f64,
    /// An unexplained effect the modes share (a support's stiffness wandering with moisture
    /// or frost beyond what the temperature says): its standard deviation (relative
    /// frequency change of the first mode; mode j of n feels it times 1 − j/(2(n − 1)), so
    /// the last mode half as much) and its correlation time (hours; a first-order
    /// autoregression over the records as `unexplained_hours`'s). Default none (0, 0).
    pub shared_unexplained: (f64, f64),
    /// Episodes of that shared effect (a support that sticks, or freezes, for days at a
    /// time): the campaign cut in blocks of the second value's hours, each block in an
    /// episode with the probability of the third value, drawn from the block's own seed;
    /// during one the frequencies change by the first value (relative, the first mode's;
    /// the others by the shared effect's loadings). Default none (0, 48, 0).
    pub shared_episodes: (f64, f64, f64),
    /// Standard deviation of the log of the excitation level.
    pub level_spread: f64,
    /// The sensors' noise as a fraction of the response at level 1.
    pub noise: f64,
    /// The day the change starts, the mode it lowers (0-based) and the relative change.
    pub change: Option<(f64, usize, f64)>,
    /// Frost: below the first temperature (°C, the structure's), each frequency changes by
    /// the second value (relative, per °C) times the degrees below it — negative makes it
    /// stiffer as it freezes, as a bridge's asphalt and soil do (default none: 0 per °C).
    pub frost: (f64, f64),
    /// Relative frequency change per unit of ln(level): amplitude dependence (negative:
    /// softer when shaken harder; default 0).
    pub amplitude_coefficient: f64,
    /// A machine: its frequency (Hz), its amplitude (of the response's RMS at level 1) and
    /// the share of records in which it runs (default none).
    pub harmonic: Option<(f64, f64, f64)>,
    /// The campaign's seed (record i uses seed + i).
    pub seed: u64,
}

impl Default for Campaign {
    /// Issue 33's campaign: a 4-mode structure recorded 24 times a day for 60 days, ten
    /// minutes at 25 Hz on 6 sensors; frequencies −0.15 %/°C over a daily ±4 °C and a
    /// seasonal ±6 °C swing (±1.5 % in all, a day's swing ±0.6 %); on day 45 mode 2 (index 1)
    /// lowered by 0.5 %.
    fn default() -> Self {
        Campaign {
            days: 60,
            per_day: 24,
            fs: 25.0,
            seconds: 600.0,
            modes: vec![(1.1, 0.012), (3.2, 0.015), (5.6, 0.018), (8.3, 0.02)],
            channels: 6,
            temperature: (10.0, 4.0, 6.0, 120.0),
            temperature_coefficient: -0.0015,
            temperature_noise: 0.2,
            unexplained: 2e-4,
            unexplained_hours: 0.0,
            shared_unexplained: (0.0, 0.0),
            shared_episodes: (0.0, 48.0, 0.0),
            thermal_lag_hours: 0.0,
            level_spread: 0.5,
            noise: 0.05,
            change: Some((45.0, 1, -0.005)),
            frost: (0.0, 0.0),
            amplitude_coefficient: 0.0,
            harmonic: None,
            seed: 700_000,
        }
    }
}

/// The structure and its environment when a record is taken.
#[derive(Debug, Clone, PartialEq)]
pub struct CampaignState {
    /// When (s from the campaign's start).
    pub time_s: f64,
    /// The temperature as measured (°C).
    pub temperature: f64,
    /// The modes' true frequencies (Hz).
    pub frequencies: Vec<f64>,
    /// The excitation's level (the sensors' noise is `noise / level` of the response).
    pub level: f64,
}

/// One record of a campaign, with what made it.
#[derive(Debug, Clone, PartialEq)]
pub struct CampaignRecord {
    /// When (s from the campaign's start).
    pub time_s: f64,
    /// The temperature as measured (°C).
    pub temperature: f64,
    /// The modes' true frequencies (Hz).
    pub frequencies: Vec<f64>,
    /// The channels.
    pub channels: Vec<Vec<f64>>,
}

impl Campaign {
    /// The number of records.
    pub fn len(&self) -> usize {
        self.days * self.per_day
    }

    /// Whether the campaign has no records.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The time of record `i` (days).
    pub fn day(&self, i: usize) -> f64 {
        i as f64 / self.per_day as f64
    }

    /// The unit-variance autoregressive effect of each mode at record `i` (`None` when the
    /// effect is independent).
    fn correlated_unexplained(&self, i: usize) -> Option<Vec<f64>> {
        self.autoregression(i, self.unexplained_hours, self.modes.len(), 0xc0_ffee)
    }

    /// `count` unit-variance first-order autoregressions over the records with correlation
    /// time `hours` at record `i`, √(1 − φ²) Σ_k φ^k w_{i−k}, the sum cut where φ^k < 10⁻⁴,
    /// each w_m a standard normal drawn from its own seed (the campaign's seed, `salt` and
    /// m), so that any record is made alone; `None` for a time of 0 (or NaN).
    fn autoregression(&self, i: usize, hours: f64, count: usize, salt: u64) -> Option<Vec<f64>> {
        if hours.is_nan() || hours <= 0.0 {
            return None;
        }
        let step_hours = 24.0 / self.per_day as f64;
        let phi = (-step_hours / hours).exp();
        let terms = ((1e-4f64).ln() / phi.ln()).ceil().max(1.0) as i64;
        let normal = Normal::new(0.0, 1.0).expect("unit normal");
        let mut eta = vec![0.0; count];
        let mut weight = (1.0 - phi * phi).sqrt();
        for k in 0..terms {
            let m = i as i64 - k;
            let seed = (self.seed ^ salt).wrapping_add(m as u64);
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
            for e in eta.iter_mut() {
                *e += weight * normal.sample(&mut rng);
            }
            weight *= phi;
        }
        Some(eta)
    }

    /// The shared unexplained effect's relative change of each mode at record `i` (zeros
    /// without one).
    fn shared_effect(&self, i: usize) -> Vec<f64> {
        let n = self.modes.len();
        let (size, hours) = self.shared_unexplained;
        let g = if size == 0.0 {
            0.0
        } else {
            // A correlation time of 0 makes it independent from record to record.
            self.autoregression(i, hours.max(1e-9), 1, 0x5a4e_d000)
                .map_or(0.0, |g| g[0])
        };
        let (jump, block_hours, share) = self.shared_episodes;
        let episode = if jump != 0.0 && block_hours > 0.0 && share > 0.0 {
            let hours = i as f64 * 24.0 / self.per_day as f64;
            let block = (hours / block_hours).floor() as u64;
            let mut rng =
                Xoshiro256PlusPlus::seed_from_u64((self.seed ^ 0xe915_0de0).wrapping_add(block));
            if rand::RngExt::random::<f64>(&mut rng) < share {
                jump
            } else {
                0.0
            }
        } else {
            0.0
        };
        (0..n)
            .map(|j| {
                let loading = if n > 1 {
                    1.0 - j as f64 / (2.0 * (n - 1) as f64)
                } else {
                    1.0
                };
                loading * (size * g + episode)
            })
            .collect()
    }

    /// The state of the structure and its environment at record `i`, without the record
    /// itself (cheap: for tests of the tracking on known frequencies).
    pub fn state(&self, i: usize) -> CampaignState {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64((self.seed + i as u64) ^ 0x5eed);
        let normal = Normal::new(0.0, 1.0).expect("unit normal");
        let t = self.day(i);
        let (t0, daily, seasonal, period) = self.temperature;
        let two_pi = 2.0 * std::f64::consts::PI;
        let temp = t0 + daily * (two_pi * t).sin() + seasonal * (two_pi * t / period).sin();
        // The structure's temperature: each cycle through the lag's gain and phase.
        let lagged = |amplitude: f64, period_days: f64| {
            let wt = two_pi * self.thermal_lag_hours / 24.0 / period_days;
            amplitude / (1.0 + wt * wt).sqrt() * (two_pi * t / period_days - wt.atan()).sin()
        };
        let structure = t0 + lagged(daily, 1.0) + lagged(seasonal, period);
        let correlated = self.correlated_unexplained(i);
        let shared = self.shared_effect(i);
        let frequencies: Vec<f64> = self
            .modes
            .iter()
            .enumerate()
            .map(|(j, &(f, _))| {
                // Drawn in any case, so that the other draws are those of an independent
                // effect's campaign.
                let independent = normal.sample(&mut rng);
                let eta = correlated.as_ref().map_or(independent, |c| c[j]);
                let (freezing, per_degree) = self.frost;
                let mut f = f
                    * (1.0 + self.temperature_coefficient * (structure - t0))
                    * (1.0 + per_degree * (structure - freezing).min(0.0))
                    * (1.0 + self.unexplained * eta)
                    * (1.0 + shared[j]);
                if let Some((day, mode, change)) = self.change
                    && t >= day
                    && mode == j
                {
                    f *= 1.0 + change;
                }
                f
            })
            .collect();
        let level = (self.level_spread * normal.sample(&mut rng)).exp();
        // Drawn after the frequencies, so that the draws are those of a campaign without it.
        let frequencies: Vec<f64> = frequencies
            .iter()
            .map(|f| f * (1.0 + self.amplitude_coefficient * level.ln()))
            .collect();
        let measured = temp + self.temperature_noise * normal.sample(&mut rng);
        CampaignState {
            time_s: t * 86400.0,
            temperature: measured,
            frequencies,
            level,
        }
    }

    /// Whether the machine runs during record `i` (a share `share` of the records, drawn
    /// from the record's own seed).
    pub fn machine_runs(&self, i: usize, share: f64) -> bool {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64((self.seed + i as u64) ^ 0x4a41);
        rand::RngExt::random::<f64>(&mut rng) < share
    }

    /// Record `i`.
    pub fn record(&self, i: usize) -> CampaignRecord {
        let state = self.state(i);
        let level = state.level;
        let l = self.channels;
        let gains: Vec<Vec<f64>> = (0..l)
            .map(|c| {
                (0..self.modes.len())
                    .flat_map(|j| {
                        let x = (c + 1) as f64 / (l + 1) as f64;
                        [
                            level * ((j + 1) as f64 * std::f64::consts::PI * x).sin(),
                            0.0,
                        ]
                    })
                    .collect()
            })
            .collect();
        let modes: Vec<(f64, f64)> = state
            .frequencies
            .iter()
            .zip(&self.modes)
            .map(|(&f, &(_, z))| (f, z))
            .collect();
        let n = (self.seconds * self.fs).round() as usize;
        let mut channels = ModalRecord::new(self.fs, &modes)
            .with_gains(gains)
            .with_noise(self.noise / level)
            .generate(n, self.seed + i as u64);
        if let Some((f, amplitude, share)) = self.harmonic
            && self.machine_runs(i, share)
        {
            let w = 2.0 * std::f64::consts::PI * f / self.fs;
            for (c, y) in channels.iter_mut().enumerate() {
                // The sinusoid's amplitude: `amplitude` times the channel's response RMS at
                // level 1 (its RMS in this record over the record's level).
                let rms = (y.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt() / level;
                for (t, v) in y.iter_mut().enumerate() {
                    *v += amplitude * rms * (w * t as f64 + 0.7 * c as f64).sin();
                }
            }
        }
        CampaignRecord {
            time_s: state.time_s,
            temperature: state.temperature,
            frequencies: state.frequencies,
            channels,
        }
    }
}
