//! The fitted structure driven by a measured force: its channels in time, and how far they
//! are from a measured record's (a check on a level the fit never saw, when its force was
//! measured).
//!
//! The structure starts at rest one sample before the record; each loaded floor's force
//! rises linearly from zero to its first sample and is linear between samples, at the fit's
//! integration step.

use hyst_sim::building::ShearBuilding;

use super::error::StoreyError;
use super::types::StoreyFit;
use crate::IdentError;

/// The fitted structure's channels (one vector per channel, as many samples as the forces)
/// under `forces`: one column per loaded floor ([`StoreyFit::load_floors`], in that order),
/// in N, at the fit's rate.
pub fn simulate_structure(
    fit: &StoreyFit,
    forces: &[Vec<f64>],
) -> Result<Vec<Vec<f64>>, IdentError> {
    fit.validate()?;
    let b: &ShearBuilding = &fit.building;
    let floors = b.masses.len();
    if forces.len() != fit.load_floors.len() {
        return Err(StoreyError::ForceColumns {
            given: forces.len(),
            loaded: fit.load_floors.len(),
        }
        .into());
    }
    let n = forces.first().map_or(0, Vec::len);
    for f in forces {
        if f.len() != n || n < 2 {
            return Err(StoreyError::TooShort {
                samples: f.len().min(n),
                needed: 2,
            }
            .into());
        }
        if let Some(v) = f.iter().find(|v| !v.is_finite()) {
            return Err(StoreyError::Unphysical {
                name: "a force sample (N)",
                value: *v,
            }
            .into());
        }
    }
    let steps = fit.reading.steps_per_sample.max(1);
    // A zero before the first sample (rest), then every sample: n intervals of `steps`.
    let fine = n * steps + 1;
    let mut loads = vec![vec![0.0; fine]; floors];
    for (&floor, f) in fit.load_floors.iter().zip(forces) {
        let column = &mut loads[floor];
        for (i, v) in column.iter_mut().enumerate() {
            let (k, r) = (i / steps, (i % steps) as f64 / steps as f64);
            let before = if k == 0 { 0.0 } else { f[k - 1] };
            let after = if k < n { f[k] } else { f[n - 1] };
            *v = before + r * (after - before);
        }
    }
    Ok(b.respond(&loads, steps, 0)?)
}

/// How far a simulated record is from a measured one, channel by channel.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct ChannelError {
    /// RMS of the difference (the record's unit).
    pub rms_error: f64,
    /// RMS of the measured channel about its mean.
    pub measured_sd: f64,
}

impl ChannelError {
    /// The error as a share of the measured channel's deviation.
    pub fn share(&self) -> f64 {
        self.rms_error / self.measured_sd
    }
}

/// Each channel's error of `simulated` against `measured` (one vector per channel, as
/// long), over the samples from `skip` on (the start's transient left out).
pub fn response_errors(
    simulated: &[Vec<f64>],
    measured: &[Vec<f64>],
    skip: usize,
) -> Result<Vec<ChannelError>, IdentError> {
    if simulated.len() != measured.len() {
        return Err(StoreyError::ChannelCount {
            level: 1,
            channels: measured.len(),
            sensors: simulated.len(),
        }
        .into());
    }
    simulated
        .iter()
        .zip(measured)
        .enumerate()
        .map(|(c, (s, m))| {
            if s.len() != m.len() || m.len() <= skip + 1 {
                return Err(StoreyError::BadLength {
                    level: 1,
                    channel: c + 1,
                    samples: m.len(),
                    first: s.len(),
                    needed: skip + 2,
                }
                .into());
            }
            let (s, m) = (&s[skip..], &m[skip..]);
            let len = m.len() as f64;
            let mean = m.iter().sum::<f64>() / len;
            let sd = (m.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / len).sqrt();
            let e = (s.iter().zip(m).map(|(a, b)| (a - b).powi(2)).sum::<f64>() / len).sqrt();
            Ok(ChannelError {
                rms_error: e,
                measured_sd: sd,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::storeys::{Quantity, StoreyReading};

    /// A two-floor chain under a step force settles at its static drifts.
    #[test]
    fn a_step_force_settles_at_the_static_drift() {
        let mut fit = crate::storeys::predict::tests_support::linear_fit(
            [1000.0, 800.0],
            [4e6, 3e6],
            [0.05, 0.05],
            50.0,
        );
        fit.building.reading = Quantity::Displacement;
        fit.reading = StoreyReading {
            steps_per_sample: 8,
            ..fit.reading
        };
        let n = 4000;
        let forces = vec![vec![0.0; n], vec![1000.0; n]];
        let y = simulate_structure(&fit, &forces).unwrap();
        // 1000 N on the top floor: both storeys carry it, x1 = F/k1, x2 = F/k1 + F/k2.
        let want = [1000.0 / 4e6, 1000.0 / 4e6 + 1000.0 / 3e6];
        for (c, w) in y.iter().zip(want) {
            // 40 s at ζ = 5 % of a 6 Hz mode: the transient is e^-75 of its start.
            assert!(
                (c[n - 1] / w - 1.0).abs() < 1e-6,
                "{} against {w}",
                c[n - 1]
            );
        }
        let errors = response_errors(&y, &y, 10).unwrap();
        assert!(
            errors
                .iter()
                .all(|e| e.rms_error == 0.0 && e.share() == 0.0)
        );
        assert!(matches!(
            simulate_structure(&fit, &forces[..1]),
            Err(IdentError::Storey(StoreyError::ForceColumns {
                given: 1,
                loaded: 2
            }))
        ));
        let mut bad = forces.clone();
        bad[1][7] = f64::NAN;
        assert!(simulate_structure(&fit, &bad).is_err());
    }
}
