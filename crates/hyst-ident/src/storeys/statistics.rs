//! What a record says of the structure, read the same way from a measured record and from a
//! simulated one (the auxiliary statistics of the indirect inference). Each channel's
//! spectrum by Welch's method (Hann, 50 % overlap, segments fine enough to resolve a 1 %
//! damped lowest mode), split into one band per mode (edges at the geometric means of
//! neighbouring modes); in each band
//!
//! - the centroid frequency and the relative spread (standard deviation over centroid) of
//!   the channels' summed spectrum: where the mode is and how wide (its damping);
//! - the log of the channels' summed power (the mode's energy), and each further channel's
//!   log power ratio to the first (the mode's shape at the sensors).
//!
//! These move smoothly with the parameters (a fixed-order SSI's poles jump between noisy
//! estimates), so the finite differences of the fit see the model, not the noise. Bands stop
//! just above the highest mode, so what lies above the modes (an acceleration's direct
//! feed-through of the force, whose level depends on how white the force is far above the
//! structure) is not read.

use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;
use rand_distr::{Distribution, StandardNormal};

use super::types::LevelStatistics;
use crate::IdentError;
use hyst_sim::building::{Reading as Quantity, ShearBuilding};

/// How the statistics are read: fixed once from the quietest level, the same for every
/// record measured or simulated.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Reading {
    /// The record's rate (Hz).
    pub(crate) fs: f64,
    /// Welch's segment (samples).
    pub(crate) segment: usize,
    /// Band edges (Hz): mode j's band is edges[j]..edges[j + 1].
    pub(crate) edges: Vec<f64>,
}

impl Reading {
    /// The reading for modes at `hz` (ascending) on records at `fs` Hz whose shortest is
    /// `shortest` samples: segments of a power of two giving lines at most 1 % of the lowest
    /// mode apart (its half-power band at 1 % damping holds two), and at most a third of the
    /// shortest record; bands from half the lowest mode to the highest times the ratio to
    /// its neighbour's square root (below 0.45 fs).
    pub(crate) fn new(fs: f64, hz: &[f64], shortest: usize) -> Reading {
        let n = hz.len();
        let want = (fs / (0.01 * hz[0])).ceil() as usize;
        let segment = want
            .next_power_of_two()
            .min(prev_power_of_two(shortest / 3).max(64));
        let mut edges = vec![0.5 * hz[0]];
        for j in 1..n {
            edges.push((hz[j - 1] * hz[j]).sqrt());
        }
        let above = if n > 1 {
            hz[n - 1] * (hz[n - 1] / hz[n - 2]).sqrt()
        } else {
            1.5 * hz[0]
        };
        edges.push(above.min(0.45 * fs));
        Reading { fs, segment, edges }
    }

    /// Modes read.
    pub(crate) fn modes(&self) -> usize {
        self.edges.len() - 1
    }

    /// The statistics of a record (channels of equal length): centroids (Hz), relative
    /// spreads, then band by band the log summed power and the other channels' log power
    /// ratios to the first.
    pub(crate) fn of(&self, y: &[Vec<f64>]) -> Vec<f64> {
        let spectra: Vec<(Vec<f64>, Vec<f64>)> = y
            .iter()
            .map(|c| crate::welch_psd(c, self.fs, self.segment))
            .collect();
        let f = &spectra[0].0;
        let m = self.modes();
        let mut centroid = Vec::with_capacity(m);
        let mut spread = Vec::with_capacity(m);
        let mut power = Vec::with_capacity(m * y.len());
        for j in 0..m {
            let (lo, hi) = (self.edges[j], self.edges[j + 1]);
            let lines: Vec<usize> = (0..f.len()).filter(|&i| f[i] >= lo && f[i] < hi).collect();
            let total = |i: usize| spectra.iter().map(|(_, p)| p[i]).sum::<f64>();
            let s0: f64 = lines.iter().map(|&i| total(i)).sum();
            let s1: f64 = lines.iter().map(|&i| f[i] * total(i)).sum();
            let c = s1 / s0;
            let s2: f64 = lines.iter().map(|&i| (f[i] - c).powi(2) * total(i)).sum();
            centroid.push(c);
            spread.push((s2 / s0).sqrt() / c);
            // The mode's energy (all channels) apart from its shape (each channel's share
            // against the first's): a chance swing of the mode's energy moves one number,
            // not one per channel.
            let band: Vec<f64> = spectra
                .iter()
                .map(|(_, p)| {
                    lines
                        .iter()
                        .map(|&i| p[i])
                        .sum::<f64>()
                        .max(f64::MIN_POSITIVE)
                })
                .collect();
            power.push(band.iter().sum::<f64>().ln());
            power.extend(band[1..].iter().map(|b| (b / band[0]).ln()));
        }
        centroid.extend(spread);
        centroid.extend(power);
        centroid
    }
}

/// A statistics vector as [`LevelStatistics`] (`floors` modes, `channels` channels), with
/// its standard errors `se` (empty when none).
pub(crate) fn level(s: &[f64], (n, channels): (usize, usize), se: Vec<f64>) -> LevelStatistics {
    LevelStatistics {
        centroid_hz: s[..n].to_vec(),
        spread: s[n..2 * n].to_vec(),
        band_rms: s[2 * n..]
            .chunks(channels)
            .map(|c| {
                // Back from (ln Σ P, ln P_c/P_1 …) to each channel's RMS √P_c.
                let ratios: Vec<f64> = std::iter::once(1.0)
                    .chain(c[1..].iter().map(|r| r.exp()))
                    .collect();
                let first = c[0].exp() / ratios.iter().sum::<f64>();
                ratios.iter().map(|r| (first * r).sqrt()).collect()
            })
            .collect(),
        se,
    }
}

/// [`level`] backwards: the statistics vector of a [`LevelStatistics`].
pub(crate) fn vector(l: &LevelStatistics) -> Vec<f64> {
    let mut out = l.centroid_hz.clone();
    out.extend(&l.spread);
    for band in &l.band_rms {
        let power: Vec<f64> = band.iter().map(|r| r * r).collect();
        out.push(power.iter().sum::<f64>().ln());
        out.extend(power[1..].iter().map(|p| (p / power[0]).ln()));
    }
    out
}

fn prev_power_of_two(n: usize) -> usize {
    if n < 2 {
        1
    } else {
        1 << (usize::BITS - 1 - n.leading_zeros())
    }
}

/// The model's records under common random numbers: each level's white force per loaded
/// floor drawn once (standard normals at `oversample` steps per sample), scaled by the
/// level's density at every evaluation, so that the statistics move smoothly with the
/// parameters.
///
/// The force is white below the record's Nyquist frequency and nothing above it (each
/// column low-passed there): what a record shows of a real force is its band below Nyquist,
/// while what lies above folds into an acceleration record as a white floor, since an
/// acceleration carries the force itself ($\ddot x_i = f_i/m_i + \dots$). How much folds
/// depends on how far above the structure the real force stays white, which no record
/// shows apart from the structure; so for accelerations the model adds an independent white
/// floor of two-sided density $q\,b/m_i^2$ to each channel, the folded band $b$ (in units
/// of the record's rate) a parameter of the fit. (The model's own direct term stays: it is
/// part of the acceleration's response, correlated with the rest.)
pub(crate) struct Simulator {
    /// Steps per output sample (fixed for the whole fit).
    pub(crate) oversample: usize,
    /// Samples dropped from the start (the response from rest settling).
    pub(crate) warm_up: usize,
    /// The floors loaded.
    pub(crate) load_floors: Vec<usize>,
    /// Floors.
    pub(crate) floors: usize,
    /// Channels.
    pub(crate) channels: usize,
    /// Per level: the standard normals of each loaded floor and of each channel's floor.
    normals: Vec<Draws>,
}

/// One record's random numbers.
struct Draws {
    force: Vec<Vec<f64>>,
    floor: Vec<Vec<f64>>,
}

impl Simulator {
    /// Forces for records of `lengths` samples, drawn from `seed` (level i from seed + i).
    pub(crate) fn new(
        (floors, channels): (usize, usize),
        load_floors: Vec<usize>,
        (oversample, warm_up): (usize, usize),
        lengths: &[usize],
        seed: u64,
    ) -> Simulator {
        let mut sim = Simulator {
            oversample,
            warm_up,
            load_floors,
            floors,
            channels,
            normals: vec![],
        };
        sim.normals = lengths
            .iter()
            .enumerate()
            .map(|(i, &n)| sim.draws(n, seed + i as u64))
            .collect();
        sim
    }

    fn draws(&self, samples: usize, seed: u64) -> Draws {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let mut column = |len: usize| -> Vec<f64> {
            (0..len).map(|_| StandardNormal.sample(&mut rng)).collect()
        };
        let fine = (self.warm_up + samples) * self.oversample + 1;
        // Drawn over a power of two (fast transforms), low-passed at the output's Nyquist
        // frequency, cut to length: a stretch of band-limited white noise of unit density
        // per fine sample below it.
        let padded = fine.next_power_of_two();
        let keep = padded / (2 * self.oversample);
        let mut band_limited = |len: usize| -> Vec<f64> {
            let mut spec = crate::fft::rfft(&column(len));
            for v in spec.iter_mut().skip(keep + 1) {
                *v = crate::fft::C::new(0.0, 0.0);
            }
            let mut x = crate::fft::irfft(&spec, len);
            x.truncate(fine);
            x
        };
        let force = (0..self.load_floors.len())
            .map(|_| band_limited(padded))
            .collect();
        Draws {
            force,
            floor: (0..self.channels).map(|_| column(samples)).collect(),
        }
    }

    /// Level `level`'s record from `building` with each loaded floor's force of two-sided
    /// density `q` (N²/Hz; its white noise at the fine rate F has variance q·F), and for
    /// accelerations the folded band `b`.
    pub(crate) fn record(
        &self,
        building: &ShearBuilding,
        level: usize,
        (q, b): (f64, f64),
    ) -> Result<Vec<Vec<f64>>, IdentError> {
        self.respond(building, &self.normals[level], (q, b))
    }

    /// A record of `samples` samples under forces drawn afresh from `seed` (a replicate).
    pub(crate) fn replicate(
        &self,
        building: &ShearBuilding,
        samples: usize,
        (q, b): (f64, f64),
        seed: u64,
    ) -> Result<Vec<Vec<f64>>, IdentError> {
        self.respond(building, &self.draws(samples, seed), (q, b))
    }

    fn respond(
        &self,
        building: &ShearBuilding,
        draws: &Draws,
        (q, b): (f64, f64),
    ) -> Result<Vec<Vec<f64>>, IdentError> {
        let fine = draws.force.first().map_or(0, Vec::len);
        let rms = (q * building.fs * self.oversample as f64).sqrt();
        let mut loads = vec![vec![0.0; fine]; self.floors];
        for (&floor, z) in self.load_floors.iter().zip(&draws.force) {
            for (l, v) in loads[floor].iter_mut().zip(z) {
                *l = rms * v;
            }
        }
        let mut out = building.respond(&loads, self.oversample, self.warm_up)?;
        if building.reading == Quantity::Acceleration {
            let level = (q * b * building.fs).max(0.0).sqrt();
            for ((o, &s), e) in out.iter_mut().zip(&building.sensors).zip(&draws.floor) {
                let m = building.masses[s];
                for (v, e) in o.iter_mut().zip(e) {
                    *v += level * e / m;
                }
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::storeys::model;

    /// Far above a floor's resonance its acceleration is the force over the mass: the model's
    /// record there is its force's band below Nyquist (density q) plus the folded floor
    /// (q·b), over m²: one-sided 2·q·(1 + b)/m².
    #[test]
    fn the_accelerations_floor_is_the_folded_band() {
        let (m, q, fs) = (10.0, 4.0, 200.0);
        let template = model::template(&[m], &[0], Quantity::Acceleration, fs, &[0]);
        // 2 Hz, 2 %: the band 60–90 Hz is 30–45 times above it.
        let k = m * (2.0 * std::f64::consts::PI * 2.0f64).powi(2);
        let b = ShearBuilding {
            stiffnesses: vec![k],
            damping_ratios: vec![0.02],
            ..template
        };
        let sim = Simulator::new((1, 1), vec![0], (8, 2000), &[], 5);
        for folded in [2.0, 0.5] {
            let y = sim.replicate(&b, 1 << 16, (q, folded), 11).unwrap();
            let (f, p) = crate::welch_psd(&y[0], fs, 1024);
            let band: Vec<f64> = f
                .iter()
                .zip(&p)
                .filter(|(f, _)| (60.0..90.0).contains(*f))
                .map(|(_, p)| *p)
                .collect();
            let mean = band.iter().sum::<f64>() / band.len() as f64;
            let want = 2.0 * q * (1.0 + folded) / (m * m);
            // 64 segments × 153 lines averaged: the mean's sampling error is under 1 %;
            // the structure's own response there is (2/60)⁴ of the force's, and the
            // spectrum's leakage from the resonance below 1 %: 5 % is the budget.
            assert!(
                (mean / want - 1.0).abs() < 0.05,
                "{folded}: {mean} vs {want}"
            );
        }
    }

    #[test]
    fn a_band_centroid_is_where_its_mode_is() {
        // Two sinusoids in two bands, with weak white noise: each band's centroid is its
        // sinusoid's frequency within a line, its spread under a few lines.
        let fs = 100.0;
        let r = Reading::new(fs, &[5.0, 12.0], 40_000);
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(3);
        let y: Vec<f64> = (0..40_000)
            .map(|i| {
                let t = i as f64 / fs;
                let e: f64 = StandardNormal.sample(&mut rng);
                (2.0 * std::f64::consts::PI * 5.0 * t).sin()
                    + 0.5 * (2.0 * std::f64::consts::PI * 12.0 * t).sin()
                    + 1e-3 * e
            })
            .collect();
        let s = r.of(&[y]);
        let line = fs / r.segment as f64;
        assert!((s[0] - 5.0).abs() < line, "{s:?}");
        assert!((s[1] - 12.0).abs() < line, "{s:?}");
        assert!(s[2] * 5.0 < 3.0 * line && s[3] * 12.0 < 3.0 * line, "{s:?}");
        // The powers' ratio is the amplitudes' squared: ln 4 apart (the Hann window's
        // leakage stays inside each band); one channel, so no shape ratios.
        assert_eq!(s.len(), 6);
        assert!((s[4] - s[5] - 4f64.ln()).abs() < 0.01, "{s:?}");
    }

    /// The fit's simulator (band-limited force, folded floor, common random numbers) and the
    /// project's record generator (its force white to its own step, no floor added) make
    /// the same statistics for one linear structure, the generator's folded band being its
    /// steps per sample less one: each statistic's mean over replicates agrees within
    /// four standard errors of the difference.
    #[test]
    fn the_fits_simulator_agrees_with_the_generator() {
        let fs = 200.0;
        let mut b = model::template(
            &[1000.0, 1000.0, 800.0],
            &[0, 1, 2],
            Quantity::Acceleration,
            fs,
            &[0, 1, 2],
        );
        b.stiffnesses = vec![1.2e6, 1e6, 8e5];
        b.damping_ratios = vec![0.02, 0.017, 0.02];
        let q = 11.25;
        b.load.rms = (q * b.fine_rate().unwrap()).sqrt();
        let o = (b.fine_rate().unwrap() / fs).round() as usize;
        let r = Reading::new(fs, &[2.455, 6.320, 8.979], 30_000);
        let sim = Simulator::new((3, 3), vec![0, 1, 2], (o, 6000), &[], 1);
        let reps = 12;
        let (mut a, mut g) = (vec![], vec![]);
        for i in 0..reps {
            a.push(
                r.of(&sim
                    .replicate(&b, 30_000, (q, o as f64 - 1.0), 100 + i)
                    .unwrap()),
            );
            g.push(r.of(&b.generate(30_000, 200 + i).unwrap()));
        }
        let moments = |x: &[Vec<f64>], k: usize| {
            let m = x.iter().map(|s| s[k]).sum::<f64>() / reps as f64;
            let v = x.iter().map(|s| (s[k] - m).powi(2)).sum::<f64>() / (reps - 1) as f64;
            (m, v)
        };
        for k in 0..a[0].len() {
            let ((ma, va), (mg, vg)) = (moments(&a, k), moments(&g, k));
            let se = ((va + vg) / reps as f64).sqrt();
            // Four standard errors: with 15 statistics, a chance failure is under 0.1 %;
            // the force's folding handled wrongly shifts the centroids by 5–10 of them.
            assert!(
                (ma - mg).abs() < 4.0 * se,
                "statistic {k}: {ma} vs {mg} ± {se}"
            );
        }
    }
}
