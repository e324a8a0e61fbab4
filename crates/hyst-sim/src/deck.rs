//! A long bridge deck's ambient response at many sensors: the record SSI with many channels
//! is tested on, made without SSI's own state-space simulator.
//!
//! The deck is a beam of unit length with sensor stations at $x_s = (s + \tfrac12)/S$, each
//! carrying three accelerometers (longitudinal, lateral, vertical); the vertical ones sit on
//! alternate edges, so that they see torsion with alternating sign. It has [`DECK_MODES`]:
//! lateral, vertical, torsional and longitudinal modes from 0.20 to 2.40 Hz, three pairs of
//! them closer than 7 %, with shapes $\sin(n\pi x)$ (longitudinal $\cos(n\pi x)$, seen also
//! weakly by the vertical sensors). Each mode is driven by its own red load (white noise
//! through a first-order low-pass at [`LOAD_CORNER_HZ`], as wind and waves are coloured,
//! scaled so that the modes' accelerations fall from 1 to 0.4 with frequency), its
//! modal equation $\ddot q + 2\zeta\omega\dot q + \omega^2 q = f$ integrated by Newmark's
//! average acceleration at [`SUBSTEPS`] sub-steps per sample and read at every
//! [`SUBSTEPS`]-th; each channel gets white sensor noise of a share of its own deviation.

use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use rand_distr::StandardNormal;

use crate::SimError;

/// Sub-steps of the Newmark integration per output sample.
pub const SUBSTEPS: usize = 8;

/// Corner of the loads' first-order low-pass (Hz).
pub const LOAD_CORNER_HZ: f64 = 1.0;

/// A sensor's direction.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Direction {
    /// Along the deck.
    Longitudinal,
    /// Across the deck, horizontal.
    Lateral,
    /// Up.
    Vertical,
}

/// What a deck mode moves.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum ModeKind {
    /// Lateral bending.
    Lateral,
    /// Vertical bending.
    Vertical,
    /// Torsion (seen by the vertical sensors on the edges).
    Torsion,
    /// Longitudinal (with a weak vertical part).
    Longitudinal,
}

/// One mode of the deck.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct DeckMode {
    /// Natural frequency (Hz).
    pub frequency_hz: f64,
    /// Damping ratio.
    pub damping_ratio: f64,
    /// What it moves.
    pub kind: ModeKind,
    /// Half-waves along the deck.
    pub half_waves: u32,
}

const fn mode(frequency_hz: f64, damping_ratio: f64, kind: ModeKind, half_waves: u32) -> DeckMode {
    DeckMode {
        frequency_hz,
        damping_ratio,
        kind,
        half_waves,
    }
}

/// The deck's modes, by frequency.
pub const DECK_MODES: [DeckMode; 16] = [
    mode(0.200, 0.015, ModeKind::Lateral, 1),
    mode(0.290, 0.012, ModeKind::Vertical, 1),
    mode(0.386, 0.010, ModeKind::Lateral, 2),
    mode(0.397, 0.012, ModeKind::Vertical, 2),
    mode(0.480, 0.010, ModeKind::Torsion, 1),
    mode(0.509, 0.011, ModeKind::Vertical, 3),
    mode(0.580, 0.012, ModeKind::Lateral, 3),
    mode(0.614, 0.010, ModeKind::Longitudinal, 1),
    mode(0.830, 0.012, ModeKind::Vertical, 4),
    mode(1.085, 0.010, ModeKind::Torsion, 2),
    mode(1.361, 0.011, ModeKind::Vertical, 5),
    mode(1.520, 0.012, ModeKind::Lateral, 4),
    mode(1.740, 0.010, ModeKind::Longitudinal, 2),
    mode(2.008, 0.011, ModeKind::Vertical, 6),
    mode(2.200, 0.010, ModeKind::Torsion, 3),
    mode(2.400, 0.012, ModeKind::Lateral, 5),
];

/// A deck's sensor layout and record.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct BridgeDeck {
    /// Sensor stations along the deck (three channels each).
    pub stations: usize,
    /// Sampling rate (Hz).
    pub fs: f64,
    /// Record length (s).
    pub duration_s: f64,
    /// Each channel's sensor noise, as a share of its deviation.
    pub noise: f64,
}

impl Default for BridgeDeck {
    /// Eight stations (24 channels) at 10 Hz for 30 minutes, 5 % sensor noise.
    fn default() -> Self {
        BridgeDeck {
            stations: 8,
            fs: 10.0,
            duration_s: 1800.0,
            noise: 0.05,
        }
    }
}

impl BridgeDeck {
    /// This deck with `stations` stations at `fs` Hz.
    pub fn with(stations: usize, fs: f64) -> Self {
        BridgeDeck {
            stations,
            fs,
            ..Default::default()
        }
    }

    /// The channels' directions, station by station (longitudinal, lateral, vertical).
    pub fn directions(&self) -> Vec<Direction> {
        (0..self.stations)
            .flat_map(|_| {
                [
                    Direction::Longitudinal,
                    Direction::Lateral,
                    Direction::Vertical,
                ]
            })
            .collect()
    }

    /// Mode `m`'s shape at the channels (unscaled).
    pub fn shape(&self, m: &DeckMode) -> Vec<f64> {
        let n = f64::from(m.half_waves) * std::f64::consts::PI;
        (0..self.stations)
            .flat_map(|s| {
                let x = (s as f64 + 0.5) / self.stations as f64;
                let edge = if s % 2 == 0 { 1.0 } else { -1.0 };
                let (sin, cos) = ((n * x).sin(), (n * x).cos());
                match m.kind {
                    ModeKind::Lateral => [0.0, sin, 0.0],
                    ModeKind::Vertical => [0.0, 0.0, sin],
                    ModeKind::Torsion => [0.0, 0.1 * sin, edge * sin],
                    ModeKind::Longitudinal => [cos, 0.0, 0.2 * sin],
                }
            })
            .collect()
    }

    /// The accelerations at every channel (`3·stations` channels of `fs·duration_s` samples),
    /// from `seed`.
    pub fn accelerations(&self, seed: u64) -> Result<Vec<Vec<f64>>, SimError> {
        if !(self.fs > 0.0 && self.fs.is_finite()) {
            return Err(SimError::NonPositiveRate { fs: self.fs });
        }
        let samples = (self.fs * self.duration_s).round();
        if !(samples >= 1.0 && samples.is_finite()) || self.stations == 0 {
            return Err(SimError::InvalidSignal {
                what: if self.stations == 0 {
                    "stations"
                } else {
                    "samples"
                },
                value: if self.stations == 0 { 0.0 } else { samples },
            });
        }
        if !(self.noise >= 0.0 && self.noise.is_finite()) {
            return Err(SimError::InvalidSignal {
                what: "noise share",
                value: self.noise,
            });
        }
        let n = samples as usize;
        let channels = 3 * self.stations;
        let total = n.saturating_mul(channels);
        let mut y = Vec::new();
        y.try_reserve_exact(channels)
            .map_err(|_| SimError::TooLong { samples: total })?;
        for _ in 0..channels {
            let mut ch = Vec::new();
            ch.try_reserve_exact(n)
                .map_err(|_| SimError::TooLong { samples: total })?;
            ch.resize(n, 0.0);
            y.push(ch);
        }
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let h = 1.0 / (self.fs * SUBSTEPS as f64);
        let decay = (-2.0 * std::f64::consts::PI * LOAD_CORNER_HZ * h).exp();
        for (index, m) in DECK_MODES.iter().enumerate() {
            let shape = self.shape(m);
            let w = 2.0 * std::f64::consts::PI * m.frequency_hz;
            let (c, k) = (2.0 * m.damping_ratio * w, w * w);
            // Newmark, average acceleration (β = 1/4, γ = 1/2), unit mass.
            let lhs = 1.0 + c * h / 2.0 + k * h * h / 4.0;
            let (mut q, mut v, mut a, mut f) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
            // A unit white load gives an acceleration variance of about ω/(4ζ), the low-pass
            // divides it by 1 + (f/f_c)²: each mode's level makes it about `amplitude`²,
            // from 1 for the lowest mode down to 0.4 for the highest.
            let ratio = m.frequency_hz / LOAD_CORNER_HZ;
            let amplitude = 1.0 / (1.0 + 0.1 * index as f64);
            let level = amplitude * (4.0 * m.damping_ratio / w * (1.0 + ratio * ratio)).sqrt();
            for t in 0..n {
                for _ in 0..SUBSTEPS {
                    let e: f64 = rng.sample(StandardNormal);
                    f = decay * f + (1.0 - decay) * level * e / h.sqrt();
                    let q_pred = q + h * v + h * h / 4.0 * a;
                    let v_pred = v + h / 2.0 * a;
                    let a_new = (f - c * v_pred - k * q_pred) / lhs;
                    q = q_pred + h * h / 4.0 * a_new;
                    v = v_pred + h / 2.0 * a_new;
                    a = a_new;
                }
                for (ch, s) in y.iter_mut().zip(&shape) {
                    ch[t] += s * a;
                }
            }
        }
        for (c, ch) in y.iter_mut().enumerate() {
            let mean = ch.iter().sum::<f64>() / n as f64;
            let sd = (ch.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n as f64).sqrt();
            crate::excitation::add_noise(ch, self.noise * sd, seed ^ (0xD1CE_0000 + c as u64))?;
        }
        Ok(y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every mode is seen by some channel, and the close pairs are closer than 7 %.
    #[test]
    fn every_mode_is_seen_and_the_pairs_are_close() {
        let deck = BridgeDeck::default();
        for m in &DECK_MODES {
            let peak = deck.shape(m).iter().fold(0.0f64, |a, v| a.max(v.abs()));
            assert!(peak > 0.5, "{m:?}");
        }
        let close = DECK_MODES
            .windows(2)
            .filter(|w| w[1].frequency_hz / w[0].frequency_hz < 1.07)
            .count();
        assert_eq!(close, 3);
        assert!(
            DECK_MODES
                .windows(2)
                .all(|w| w[0].frequency_hz < w[1].frequency_hz)
        );
    }

    /// A record has the channels and samples asked, all finite; a bad rate, no station or
    /// a negative noise share is refused.
    #[test]
    fn a_record_has_the_shape_and_length_asked() {
        let deck = BridgeDeck {
            duration_s: 60.0,
            ..Default::default()
        };
        let y = deck.accelerations(1).unwrap();
        assert_eq!(y.len(), 24);
        assert!(
            y.iter()
                .all(|c| c.len() == 600 && c.iter().all(|v| v.is_finite()))
        );
        assert_eq!(deck.directions()[5], Direction::Vertical);
        assert!(BridgeDeck::with(2, -1.0).accelerations(1).is_err());
        assert!(BridgeDeck::with(0, 10.0).accelerations(1).is_err());
        let noisy = BridgeDeck {
            noise: -0.1,
            ..deck
        };
        assert!(noisy.accelerations(1).is_err());
    }
}
