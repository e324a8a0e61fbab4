//! A synthetic monitoring campaign (feature `synth`): a structure recorded many times a day
//! for weeks, its frequencies following the temperature, its excitation and so its
//! signal-to-noise ratio varying, and from a given day a stiffness loss lowering one mode.
//! Each record is made on demand by `covssi::synth` (the project's one generator), so a
//! campaign of any length takes the memory of one record.
//!
//! Record i is taken at t_i = i / per_day days. The temperature is
//! T(t) = T₀ + A_d sin(2π t) + A_s sin(2π t / P_s) (a daily cycle and a seasonal swing); mode
//! j's frequency is f_j (1 + a (T − T₀)) (1 + η_ij), with η_ij an environmental effect the
//! temperature does not explain (white, of standard deviation `unexplained`), times
//! (1 + `change`) for the changed mode from `change_day` on. The excitation level is
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
    /// Standard deviation of the log of the excitation level.
    pub level_spread: f64,
    /// The sensors' noise as a fraction of the response at level 1.
    pub noise: f64,
    /// The day the change starts, the mode it lowers (0-based) and the relative change.
    pub change: Option<(f64, usize, f64)>,
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
            level_spread: 0.5,
            noise: 0.05,
            change: Some((45.0, 1, -0.005)),
            seed: 700_000,
        }
    }
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

    /// Record `i`.
    pub fn record(&self, i: usize) -> CampaignRecord {
        let seed = self.seed + i as u64;
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x5eed);
        let normal = Normal::new(0.0, 1.0).expect("unit normal");
        let t = self.day(i);
        let (t0, daily, seasonal, period) = self.temperature;
        let two_pi = 2.0 * std::f64::consts::PI;
        let temp = t0 + daily * (two_pi * t).sin() + seasonal * (two_pi * t / period).sin();
        let frequencies: Vec<f64> = self
            .modes
            .iter()
            .enumerate()
            .map(|(j, &(f, _))| {
                let mut f = f
                    * (1.0 + self.temperature_coefficient * (temp - t0))
                    * (1.0 + self.unexplained * normal.sample(&mut rng));
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
        let measured = temp + self.temperature_noise * normal.sample(&mut rng);
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
        let modes: Vec<(f64, f64)> = frequencies
            .iter()
            .zip(&self.modes)
            .map(|(&f, &(_, z))| (f, z))
            .collect();
        let n = (self.seconds * self.fs).round() as usize;
        let channels = ModalRecord::new(self.fs, &modes)
            .with_gains(gains)
            .with_noise(self.noise / level)
            .generate(n, seed);
        CampaignRecord {
            time_s: t * 86400.0,
            temperature: measured,
            frequencies,
            channels,
        }
    }
}
