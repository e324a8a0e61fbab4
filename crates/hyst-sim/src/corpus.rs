//! A corpus of realistic output-only building records with known modes, drawn from a seed:
//! what a modal analysis meets in the field, made by [`crate::building`] (physical
//! coordinates, Runge–Kutta in time: independent of any modal model).
//!
//! Each case draws, from its seed alone:
//! - 3 to 8 storeys, floor masses 2–5·10⁵ kg, storey stiffness tapering up the height and
//!   scaled so the first mode lies between 0.4 and 4 Hz (log-uniform); each mode's damping
//!   ratio 0.5–5 % (log-uniform);
//! - 3 sensors up to one per floor (always the roof), reading acceleration (most),
//!   velocity or displacement, with white noise of 2–10 % of each channel's deviation;
//!   a quarter of them with a slow drift;
//! - the load on every floor or on a few: white noise coloured by one of a Butterworth
//!   low-pass (order 2–6, its corner between the top mode in band and the record's
//!   Nyquist), a red roll-off (first-order, corner near the first mode), or a broad
//!   resonance (damping 30–60 %, inside the band) with a low-pass above; a third
//!   modulated in amplitude (depth 0.3–0.6, period 1–5 min); a third with a machine (a
//!   sinusoid at least 5 % from every mode);
//! - one in five with a Bouc-Wen element in a storey, yielding at about two standard
//!   deviations of its drift (its modes soften by a few per cent: [`CorpusCase::hysteretic`]).
//!
//! The rate is 100 Hz, or 200–500 Hz when the top mode needs it (2.5 times it at least,
//! so nothing aliases), and the record holds `periods` periods of the first mode (at least
//! 5 minutes).

use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

use crate::SimError;
use crate::building::{Colour, Load, Reading, ShearBuilding, StoreyHysteresis, TrueMode};

/// One record of the corpus and its truth.
#[derive(Debug, Clone, PartialEq)]
pub struct CorpusCase {
    /// A one-line description (storeys, load, sensors, noise).
    pub description: String,
    /// The structure, its loads and sensors.
    pub building: ShearBuilding,
    /// Samples of the record.
    pub samples: usize,
    /// The seed the record's noise is drawn from.
    pub seed: u64,
    /// The linear structure's modes at the sensors.
    pub truth: Vec<TrueMode>,
    /// The modes an analysis must find: within the load's band (below its low-pass corner
    /// and 80 % of Nyquist), their response at some sensor at least the sensor noise there.
    pub in_band: Vec<usize>,
    /// Each true mode's peak over the sensor noise: the largest, over the sensors, of the
    /// response's density at the mode over the noise's density (1: level with the noise;
    /// a mode of `in_band` has at least 1).
    pub visibility: Vec<f64>,
    /// Whether a storey holds a Bouc-Wen element (the truth is then the small-amplitude
    /// structure's, and the modes read somewhat softer).
    pub hysteretic: bool,
    /// The machine's frequency (Hz), when there is one.
    pub harmonic_hz: Option<f64>,
}

impl CorpusCase {
    /// The record (one vector per sensor).
    pub fn generate(&self) -> Result<Vec<Vec<f64>>, SimError> {
        self.building.generate(self.samples, self.seed)
    }
}

fn log_uniform(rng: &mut Xoshiro256PlusPlus, lo: f64, hi: f64) -> f64 {
    (lo.ln() + rng.random::<f64>() * (hi.ln() - lo.ln())).exp()
}

/// The corpus's case `seed`, its record `periods` periods of the first mode long.
pub fn realistic(seed: u64, periods: f64) -> Result<CorpusCase, SimError> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x5EED_C0DE);
    let n = rng.random_range(3..=8usize);
    let masses: Vec<f64> = (0..n).map(|_| 2e5 + 3e5 * rng.random::<f64>()).collect();
    let taper: Vec<f64> = (0..n)
        .map(|i| (1.0 - 0.5 * i as f64 / n as f64) * (0.8 + 0.4 * rng.random::<f64>()))
        .collect();
    let f1 = log_uniform(&mut rng, 0.4, 4.0);
    let damping_ratios: Vec<f64> = (0..n).map(|_| log_uniform(&mut rng, 0.005, 0.05)).collect();
    let mut building = ShearBuilding {
        masses,
        stiffnesses: taper.clone(),
        damping_ratios,
        hysteresis: None,
        load: Load {
            floors: (0..n).collect(),
            rms: 1.0,
            colours: vec![],
            modulation: None,
            harmonic: None,
        },
        sensors: vec![],
        reading: Reading::Acceleration,
        noise: 0.0,
        drift: 0.0,
        fs: 100.0,
    };
    // Scale the stiffness so the first mode is f1.
    let unit = building.modes()?[0].frequency_hz;
    let scale = (f1 / unit).powi(2);
    building.stiffnesses = taper.iter().map(|k| k * scale).collect();
    let all = building.modes()?;
    let top = all.last().map_or(f1, |m| m.frequency_hz);
    building.fs = [100.0, 200.0, 250.0, 500.0]
        .into_iter()
        .find(|&fs| fs >= 2.5 * top)
        .unwrap_or(5.0 * top);
    let nyquist = building.fs / 2.0;
    draw_sensors(&mut rng, &mut building);
    // The band the load covers: the corner of its low-pass.
    let in_band_top = all
        .iter()
        .map(|m| m.frequency_hz)
        .filter(|&f| f < 0.8 * nyquist)
        .fold(f1, f64::max);
    let corner =
        in_band_top * 1.1 + rng.random::<f64>() * (0.8 * nyquist - in_band_top * 1.1).max(0.0);
    let corner = corner.min(0.85 * nyquist);
    let order = rng.random_range(2..=6usize);
    let colour = rng.random_range(0..3);
    let (colours, what) = draw_colours(&mut rng, colour, (f1, in_band_top, corner, order));
    building.load.colours = colours;
    if rng.random::<f64>() < 1.0 / 3.0 {
        building.load.modulation = Some((
            0.3 + 0.3 * rng.random::<f64>(),
            60.0 + 240.0 * rng.random::<f64>(),
        ));
    }
    let harmonic_hz = draw_machine(&mut rng, &mut building, (f1, in_band_top, &all))?;
    let hysteretic = rng.random::<f64>() < 0.2;
    let samples = (periods / f1 * building.fs).max(300.0 * building.fs) as usize;
    if hysteretic {
        add_hysteresis(&mut rng, &mut building, samples, seed)?;
    }
    let (in_band, visibility) = must_find(&building, &all, corner)?;
    let description = format!(
        "{n} storeys, f1 {f1:.2} Hz, {} sensors ({:?}), noise {:.0} %{}, load on {} floor(s): {what}{}{}{}",
        building.sensors.len(),
        building.reading,
        100.0 * building.noise,
        if building.drift > 0.0 { ", drift" } else { "" },
        building.load.floors.len(),
        if building.load.modulation.is_some() {
            ", modulated"
        } else {
            ""
        },
        harmonic_hz.map_or(String::new(), |f| format!(", machine {f:.2} Hz")),
        if hysteretic { ", Bouc-Wen storey" } else { "" },
    );
    Ok(CorpusCase {
        description,
        building,
        samples,
        seed,
        truth: all,
        in_band,
        visibility,
        hysteretic,
        harmonic_hz,
    })
}

/// The sensors (the roof and some others), what they read, their noise and drift, and
/// the floors loaded.
fn draw_sensors(rng: &mut Xoshiro256PlusPlus, building: &mut ShearBuilding) {
    let n = building.masses.len();
    let count = rng.random_range(3.min(n)..=n);
    let mut sensors = vec![n - 1];
    while sensors.len() < count {
        let s = rng.random_range(0..n);
        if !sensors.contains(&s) {
            sensors.push(s);
        }
    }
    sensors.sort_unstable();
    building.sensors = sensors;
    building.reading = match rng.random_range(0..6) {
        0 => Reading::Displacement,
        1 => Reading::Velocity,
        _ => Reading::Acceleration,
    };
    building.noise = 0.02 + 0.08 * rng.random::<f64>();
    if rng.random::<f64>() < 0.25 {
        building.drift = 0.5 + 1.5 * rng.random::<f64>();
    }
    if rng.random::<f64>() < 0.3 {
        let k = rng.random_range(1..=n.min(3));
        building.load.floors = (0..k).map(|_| rng.random_range(0..n)).collect();
        building.load.floors.sort_unstable();
        building.load.floors.dedup();
    }
}

/// The load's filters of kind `colour` (0 low-pass, 1 red, 2 resonance) and their words.
fn draw_colours(
    rng: &mut Xoshiro256PlusPlus,
    colour: u32,
    (f1, in_band_top, corner, order): (f64, f64, f64, usize),
) -> (Vec<Colour>, String) {
    match colour {
        0 => (
            vec![Colour::LowPass {
                corner_hz: corner,
                order,
            }],
            format!("low-pass {corner:.1} Hz order {order}"),
        ),
        1 => {
            let red = f1 * (0.5 + 2.0 * rng.random::<f64>());
            (
                vec![
                    Colour::Red { corner_hz: red },
                    Colour::LowPass {
                        corner_hz: corner,
                        order,
                    },
                ],
                format!("red {red:.2} Hz, low-pass {corner:.1} Hz"),
            )
        }
        _ => {
            let peak = f1 + rng.random::<f64>() * (in_band_top - f1).max(0.0);
            let z = 0.3 + 0.3 * rng.random::<f64>();
            (
                vec![
                    Colour::Resonance {
                        frequency_hz: peak,
                        damping_ratio: z,
                    },
                    Colour::LowPass {
                        corner_hz: corner,
                        order,
                    },
                ],
                format!("resonance {peak:.2} Hz ζ {z:.2}, low-pass {corner:.1} Hz"),
            )
        }
    }
}

/// A machine between the modes (a third of the cases), at least 5 % from each: its
/// frequency.
fn draw_machine(
    rng: &mut Xoshiro256PlusPlus,
    building: &mut ShearBuilding,
    (f1, in_band_top, all): (f64, f64, &[TrueMode]),
) -> Result<Option<f64>, SimError> {
    let n = building.masses.len();
    let nyquist = building.fs / 2.0;
    let mut harmonic_hz = None;
    if rng.random::<f64>() < 1.0 / 3.0 {
        // A machine between the modes, at least 5 % from each.
        for _ in 0..50 {
            let f = f1 * 0.6 + rng.random::<f64>() * (in_band_top * 1.2 - f1 * 0.6);
            if f < 0.8 * nyquist
                && all
                    .iter()
                    .all(|m| (m.frequency_hz - f).abs() > 0.05 * m.frequency_hz)
            {
                harmonic_hz = Some(f);
                break;
            }
        }
        if let Some(f) = harmonic_hz {
            // Its force comparable to the random load's within the band.
            let fine = building.fine_rate()?;
            let band_rms = (2.0 * in_band_top / fine).sqrt();
            let floor = rng.random_range(0..n);
            building.load.harmonic = Some((floor, f, (0.5 + 2.5 * rng.random::<f64>()) * band_rms));
        }
    }
    Ok(harmonic_hz)
}

/// A Bouc-Wen element in a random storey, yielding at about twice its drift's deviation
/// (from a linear run of `samples` at most 20 000 samples).
fn add_hysteresis(
    rng: &mut Xoshiro256PlusPlus,
    building: &mut ShearBuilding,
    samples: usize,
    seed: u64,
) -> Result<(), SimError> {
    let n = building.masses.len();
    // Yielding at about twice the storey drift's deviation, from a linear run.
    let storey = rng.random_range(0..n);
    let mut probe = building.clone();
    probe.sensors = (0..n).collect();
    probe.reading = Reading::Displacement;
    probe.noise = 0.0;
    probe.drift = 0.0;
    let y = probe.generate(samples.min(20_000), seed)?;
    let d: Vec<f64> = (0..y[0].len())
        .map(|t| y[storey][t] - if storey > 0 { y[storey - 1][t] } else { 0.0 })
        .collect();
    let sd = (d.iter().map(|v| v * v).sum::<f64>() / d.len() as f64).sqrt();
    let zy = 2.0 * sd;
    // ν = 2: the element's force saturates near z_y when β + γ = 1/z_y².
    building.hysteresis = Some(StoreyHysteresis {
        storey,
        linear_share: 0.5,
        beta: 0.5 / (zy * zy),
        gamma: 0.5 / (zy * zy),
        nu: 2.0,
    });
    Ok(())
}

/// The modes an analysis must find, and each true mode's visibility (its peak over the
/// sensor noise).
fn must_find(
    building: &ShearBuilding,
    all: &[TrueMode],
    corner: f64,
) -> Result<(Vec<usize>, Vec<f64>), SimError> {
    // The modes an analysis must find: in the load's band (below its low-pass corner and
    // 80 % of Nyquist), and standing out of the sensor noise at some sensor (the response's
    // density at the mode at least the noise's; white noise of deviation σ at rate fs has
    // the two-sided density σ²/(2π fs) per rad/s).
    let sd = building.response_deviation()?;
    let nyquist = building.fs / 2.0;
    let mut in_band = Vec::new();
    let mut visibility = Vec::with_capacity(all.len());
    for (j, m) in all.iter().enumerate() {
        let density = building.response_density(m.frequency_hz)?;
        let ratio = density
            .iter()
            .zip(&sd)
            .map(|(d, s)| {
                let noise =
                    (building.noise * s).powi(2) / (2.0 * std::f64::consts::PI * building.fs);
                d / noise
            })
            .fold(0.0, f64::max);
        visibility.push(ratio);
        if m.frequency_hz > corner || m.frequency_hz >= 0.8 * nyquist {
            continue;
        }
        if ratio >= 1.0 {
            in_band.push(j);
        }
    }
    Ok((in_band, visibility))
}

/// How an analysis's reported modes of one case compare with its truth.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Score {
    /// In-band true modes.
    pub in_band: usize,
    /// In-band true modes some reported mode matches.
    pub found: usize,
    /// Modes reported.
    pub reported: usize,
    /// Reported modes that match no true mode (Hz).
    pub spurious: Vec<f64>,
    /// In-band true modes no reported mode matches (Hz).
    pub missed: Vec<f64>,
    /// Each in-band true mode's visibility ([`CorpusCase::visibility`]) and whether it was
    /// found.
    pub visibility_found: Vec<(f64, bool)>,
    /// (estimate − truth)/standard error of each matched frequency with an error (linear
    /// structures only).
    pub z_frequency: Vec<f64>,
    /// The same for damping ratios.
    pub z_damping: Vec<f64>,
    /// Each in-band true mode found, by its index in [`CorpusCase::truth`], with the index
    /// of the reported mode paired with it.
    pub matched: Vec<(usize, usize)>,
}

/// A reported mode as the score reads it: frequency (Hz) and its standard error, damping
/// ratio and its standard error.
pub type Estimate = (f64, Option<f64>, f64, Option<f64>);

impl CorpusCase {
    /// Relative frequency distance within which an estimate is a true mode's: 3 %, or 8 %
    /// with a Bouc-Wen storey (its modes soften with amplitude).
    pub fn tolerance(&self) -> f64 {
        if self.hysteretic { 0.08 } else { 0.03 }
    }

    /// The reported modes against the truth: true and reported modes within
    /// [`CorpusCase::tolerance`] of each other are paired one to one, nearest first; an
    /// in-band true mode paired is found, a reported mode paired with no true mode (in band
    /// or not) is not structural.
    pub fn score(&self, reported: &[Estimate]) -> Score {
        let tol = self.tolerance();
        let near = |a: f64, b: f64| (a - b).abs() <= tol * b;
        let mut s = Score {
            in_band: self.in_band.len(),
            reported: reported.len(),
            ..Score::default()
        };
        // Pairs (true mode, reported mode) within the tolerance, nearest first, each used
        // once: one estimate does not find two close modes.
        let mut pairs: Vec<(f64, usize, usize)> = Vec::new();
        for (j, t) in self.truth.iter().enumerate() {
            for (r, e) in reported.iter().enumerate() {
                if near(e.0, t.frequency_hz) {
                    pairs.push(((e.0 - t.frequency_hz).abs() / t.frequency_hz, j, r));
                }
            }
        }
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut truth_of: Vec<Option<usize>> = vec![None; reported.len()];
        let mut matched: Vec<Option<usize>> = vec![None; self.truth.len()];
        for (_, j, r) in pairs {
            if matched[j].is_none() && truth_of[r].is_none() {
                matched[j] = Some(r);
                truth_of[r] = Some(j);
            }
        }
        for &j in &self.in_band {
            let t = &self.truth[j];
            s.visibility_found.push((
                self.visibility.get(j).copied().unwrap_or(f64::NAN),
                matched[j].is_some(),
            ));
            match matched[j] {
                Some(r) => {
                    let (f, sf, z, sz) = reported[r];
                    s.found += 1;
                    s.matched.push((j, r));
                    if !self.hysteretic {
                        if let Some(sf) = sf.filter(|v| *v > 0.0) {
                            s.z_frequency.push((f - t.frequency_hz) / sf);
                        }
                        if let Some(sz) = sz.filter(|v| *v > 0.0) {
                            s.z_damping.push((z - t.damping_ratio) / sz);
                        }
                    }
                }
                None => s.missed.push(t.frequency_hz),
            }
        }
        // A reported mode no true mode took is not structural (a second estimate of one
        // mode is not one either).
        s.spurious = reported
            .iter()
            .zip(&truth_of)
            .filter(|(_, t)| t.is_none())
            .map(|(r, _)| r.0)
            .collect();
        s
    }
}

/// Scores of many cases together.
#[derive(Debug, Clone, PartialEq)]
pub struct Summary {
    /// Cases.
    pub cases: usize,
    /// Share of in-band true modes found.
    pub found: f64,
    /// Share of reported modes that are spurious.
    pub spurious: f64,
    /// Modes reported.
    pub reported: usize,
    /// RMS of the frequency z-scores, and how many.
    pub z_frequency_rms: (f64, usize),
    /// RMS of the damping z-scores, and how many.
    pub z_damping_rms: (f64, usize),
    /// Mean of the damping z-scores (a bias shows here).
    pub z_damping_mean: f64,
}

impl Summary {
    /// The summary of `scores`.
    pub fn of(scores: &[Score]) -> Summary {
        let sum = |f: &dyn Fn(&Score) -> usize| scores.iter().map(f).sum::<usize>();
        let in_band = sum(&|s| s.in_band);
        let reported = sum(&|s| s.reported);
        let rms = |v: Vec<f64>| -> (f64, usize) {
            let n = v.len();
            (
                (v.iter().map(|z| z * z).sum::<f64>() / n.max(1) as f64).sqrt(),
                n,
            )
        };
        let zd: Vec<f64> = scores.iter().flat_map(|s| s.z_damping.clone()).collect();
        Summary {
            cases: scores.len(),
            found: sum(&|s| s.found) as f64 / in_band.max(1) as f64,
            spurious: sum(&|s| s.spurious.len()) as f64 / reported.max(1) as f64,
            reported,
            z_frequency_rms: rms(scores.iter().flat_map(|s| s.z_frequency.clone()).collect()),
            z_damping_mean: zd.iter().sum::<f64>() / zd.len().max(1) as f64,
            z_damping_rms: rms(zd),
        }
    }
}

impl std::fmt::Display for Summary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} records: true modes found {:.1} %, reported modes not structural {:.1} % (of {}), frequency z RMS {:.2} ({}), damping z RMS {:.2} ({}, mean {:+.2})",
            self.cases,
            100.0 * self.found,
            100.0 * self.spurious,
            self.reported,
            self.z_frequency_rms.0,
            self.z_frequency_rms.1,
            self.z_damping_rms.0,
            self.z_damping_rms.1,
            self.z_damping_mean
        )
    }
}
