//! A model's amplitude curves set against the measured ones: a check of a fitted model that
//! needs no truth. The model's records (e.g. [`crate::storeys::model_records`]) are analysed
//! exactly as the measured ones, the same modes followed; each measured point is then set
//! against the model's curve of the same record and mode read at the point's amplitude
//! (linear between the model's points, never beyond them):
//! $z = (x - \hat x(A))/\sqrt{\mathrm{se}^2 + \widehat{\mathrm{se}}(A)^2}$ for the frequency and
//! for the damping ratio. About 95 % of the $z$ fall within ±2 when the model is right.

use std::fmt;

use super::{AmplitudeCampaign, AmplitudePoint};

/// One mode's comparison over every record.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct ModeAgreement {
    /// The mode as the first measured record has it (Hz).
    pub frequency_hz: f64,
    /// Each compared point's frequency z.
    pub frequency_z: Vec<f64>,
    /// Each compared point's damping-ratio z.
    pub damping_z: Vec<f64>,
    /// Measured points outside the model's amplitudes (not compared).
    pub beyond: usize,
}

/// The model's curves against the measured ones.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct CurveAgreement {
    /// Mode by mode.
    pub modes: Vec<ModeAgreement>,
}

impl CurveAgreement {
    /// The z's within ±2, and all of them.
    pub fn within_two(&self) -> (usize, usize) {
        let all = self
            .modes
            .iter()
            .flat_map(|m| m.frequency_z.iter().chain(&m.damping_z));
        let (mut inside, mut total) = (0, 0);
        for z in all {
            total += 1;
            if z.abs() <= 2.0 {
                inside += 1;
            }
        }
        (inside, total)
    }
}

/// The measured records' curves, the model's records' curves (the same records' count and
/// modes, in order), and how they agree.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct CurvesBesideModel {
    /// The measured records.
    pub measured: AmplitudeCampaign,
    /// The model's records, analysed alike.
    pub model: AmplitudeCampaign,
    /// The comparison.
    pub agreement: CurveAgreement,
}

impl CurvesBesideModel {
    /// `measured` and `model` (record i of one against record i of the other, mode j against
    /// mode j) and their agreement.
    pub fn new(measured: AmplitudeCampaign, model: AmplitudeCampaign) -> CurvesBesideModel {
        let agreement = curve_agreement(&measured, &model);
        CurvesBesideModel {
            measured,
            model,
            agreement,
        }
    }
}

/// `curve` (points by increasing amplitude) read at amplitude `a`: (frequency, its se,
/// damping ratio, its se), linear between the two points around it; `None` outside.
fn read_at(curve: &[AmplitudePoint], a: f64) -> Option<[f64; 4]> {
    let lo = curve.first()?.amplitude;
    let hi = curve.last()?.amplitude;
    if !(a >= lo && a <= hi) {
        return None;
    }
    let k = curve
        .windows(2)
        .position(|w| a <= w[1].amplitude)
        .unwrap_or(0);
    let (p, q) = match curve.get(k + 1) {
        Some(q) => (&curve[k], q),
        None => (&curve[k], &curve[k]),
    };
    let t = if q.amplitude > p.amplitude {
        (a - p.amplitude) / (q.amplitude - p.amplitude)
    } else {
        0.0
    };
    let mix = |x: f64, y: f64| x + t * (y - x);
    Some([
        mix(p.frequency_hz, q.frequency_hz),
        mix(p.frequency_se_hz, q.frequency_se_hz),
        mix(p.damping_ratio, q.damping_ratio),
        mix(p.damping_se, q.damping_se),
    ])
}

/// Each measured point against the model's curve of its record and mode.
pub fn curve_agreement(measured: &AmplitudeCampaign, model: &AmplitudeCampaign) -> CurveAgreement {
    let modes = measured
        .records
        .first()
        .map_or(0, |r| r.1.curves.modes.len());
    let modes = (0..modes)
        .map(|j| {
            let mut out = ModeAgreement {
                frequency_hz: measured.records[0].1.curves.modes[j].mode.frequency_hz,
                frequency_z: vec![],
                damping_z: vec![],
                beyond: 0,
            };
            for (m, s) in measured.records.iter().zip(&model.records) {
                let (Some(mc), Some(sc)) = (m.1.curves.modes.get(j), s.1.curves.modes.get(j))
                else {
                    continue;
                };
                let mut curve = sc.points.clone();
                curve.sort_by(|a, b| a.amplitude.total_cmp(&b.amplitude));
                for p in &mc.points {
                    match read_at(&curve, p.amplitude) {
                        Some([f, fse, z, zse]) => {
                            out.frequency_z
                                .push((p.frequency_hz - f) / p.frequency_se_hz.hypot(fse));
                            out.damping_z
                                .push((p.damping_ratio - z) / p.damping_se.hypot(zse));
                        }
                        None => out.beyond += 1,
                    }
                }
            }
            out
        })
        .collect();
    CurveAgreement { modes }
}

fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|z| z * z).sum::<f64>() / v.len().max(1) as f64).sqrt()
}

impl fmt::Display for CurveAgreement {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (inside, total) = self.within_two();
        writeln!(
            f,
            "The model's curves against the measured (each measured point against the model's curve at its amplitude): {inside} of {total} within two standard errors (about 95 % when the model is right)"
        )?;
        for m in &self.modes {
            writeln!(
                f,
                "  mode {:.4} Hz: {} points compared, z RMS frequency {:.2}, damping {:.2}{}",
                m.frequency_hz,
                m.frequency_z.len(),
                rms(&m.frequency_z),
                rms(&m.damping_z),
                if m.beyond > 0 {
                    format!("; {} beyond the model's amplitudes", m.beyond)
                } else {
                    String::new()
                }
            )?;
        }
        Ok(())
    }
}

impl fmt::Display for CurvesBesideModel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "Measured:")?;
        self.measured.fmt(f)?;
        writeln!(f, "The fitted model's records, analysed alike:")?;
        self.model.fmt(f)?;
        self.agreement.fmt(f)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(amplitude: f64, f: f64, z: f64) -> AmplitudePoint {
        AmplitudePoint {
            amplitude,
            triggers: 100,
            frequency_hz: f,
            frequency_se_hz: 0.1,
            damping_ratio: z,
            damping_se: 0.01,
            channels: vec![],
            drifts: vec![],
        }
    }

    #[test]
    fn a_curve_is_read_between_its_points_and_not_beyond() {
        let c = [point(1.0, 10.0, 0.02), point(3.0, 9.0, 0.04)];
        let [f, fse, z, _] = read_at(&c, 2.0).unwrap();
        assert!((f - 9.5).abs() < 1e-12 && (z - 0.03).abs() < 1e-12 && (fse - 0.1).abs() < 1e-12);
        assert_eq!(read_at(&c, 1.0).unwrap()[0], 10.0);
        assert_eq!(read_at(&c, 3.0).unwrap()[0], 9.0);
        assert!(read_at(&c, 0.5).is_none() && read_at(&c, 3.5).is_none());
        assert!(read_at(&[], 1.0).is_none());
    }
}
