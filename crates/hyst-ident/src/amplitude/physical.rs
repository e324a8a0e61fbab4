//! Each point's amplitude where the structure moves: at every channel, and across every
//! storey when the channels' floors are known.
//!
//! The modal filter (or projection) reads the mode's coordinate $q_j$ against its unit real
//! shape $\phi_j$ (`filter.rs`): the channels carry $y_i \approx \sum_j \phi_{ij} q_j$, so a
//! point of amplitude $A$ moves channel $i$ by $|\phi_{ij}|A$, and a storey between floors
//! $s-1$ and $s$ by $|\phi_{sj} - \phi_{s-1,j}|A$ (the ground fixed), in the point's quantity.

use super::{AmplitudeError, ModeCurve, ModeToFollow, filter};

/// The floors, when given, are one per channel and each once.
pub(super) fn check_floors(
    floors: Option<&[usize]>,
    channels: usize,
) -> Result<(), AmplitudeError> {
    let Some(f) = floors else {
        return Ok(());
    };
    let twice = f.iter().enumerate().any(|(i, a)| f[..i].contains(a));
    if f.len() != channels || twice {
        return Err(AmplitudeError::Floors {
            floors: f.to_vec(),
            channels,
        });
    }
    Ok(())
}

/// Each point of `curve` at every channel and across every storey, from `mode`'s shape (a
/// single channel is its own coordinate; a mode without a shape among several channels
/// gets none).
pub(super) fn place(
    curve: &mut ModeCurve,
    mode: &ModeToFollow,
    channels: usize,
    floors: Option<&[usize]>,
) {
    let shape = match &mode.shape {
        _ if channels == 1 => vec![1.0],
        Some(s) if s.len() == channels => filter::real_shape(s),
        _ => return,
    };
    // The shape's sign is arbitrary: the largest entry positive, so drifts keep their sense.
    let big = shape
        .iter()
        .copied()
        .fold(0.0f64, |m, v| if v.abs() > m.abs() { v } else { m });
    let shape: Vec<f64> = shape.iter().map(|v| v * big.signum()).collect();
    let storey_shape = floors.map(|f| storey_shape(&shape, f));
    for p in &mut curve.points {
        p.channels = shape.iter().map(|v| v.abs() * p.amplitude).collect();
        if let Some(d) = &storey_shape {
            p.drifts = d.iter().map(|v| v * p.amplitude).collect();
        }
    }
}

/// Each storey's share of the shape: |φ at its floor − φ at the floor below| (0 for the
/// ground), NaN where a floor is not measured.
fn storey_shape(shape: &[f64], floors: &[usize]) -> Vec<f64> {
    let top = floors.iter().copied().max().map_or(0, |t| t + 1);
    let at = |floor: usize| floors.iter().position(|&f| f == floor).map(|c| shape[c]);
    (0..top)
        .map(|s| {
            let below = if s == 0 { Some(0.0) } else { at(s - 1) };
            match (at(s), below) {
                (Some(a), Some(b)) => (a - b).abs(),
                _ => f64::NAN,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_storey_is_the_difference_of_its_floors() {
        let shape = [0.3, 0.7, 0.9];
        // Channels on floors 0, 2 (floor 1 not measured) and 3.
        let d = storey_shape(&shape, &[0, 2, 3]);
        assert_eq!(d.len(), 4);
        assert!((d[0] - 0.3).abs() < 1e-15);
        assert!(d[1].is_nan() && d[2].is_nan());
        assert!((d[3] - 0.2).abs() < 1e-15);
        assert!(check_floors(Some(&[0, 0, 1]), 3).is_err());
        assert!(check_floors(Some(&[0, 1]), 3).is_err());
        assert!(check_floors(Some(&[2, 0, 1]), 3).is_ok());
        // A floor beyond any structure is refused with the options, before any work.
        let opts = crate::amplitude::AmplitudeOptions {
            floors: Some(vec![0, usize::MAX]),
            ..Default::default()
        };
        let e = opts.check().unwrap_err().to_string();
        assert!(
            e.contains("floors = 18446744073709552000 is out of range"),
            "{e}"
        );
    }
}

#[cfg(test)]
mod structure_tests {
    use super::super::{AmplitudeOptions, Quantity, amplitude_analysis};

    /// A linear three-storey chain's displacements: every point's channel amplitudes stand
    /// in the ratios of the structure's own mode shapes (its eigenvectors, computed by the
    /// simulator and not read from the record), and each storey's drift is the difference of
    /// its floors' shape entries.
    #[test]
    fn the_channels_move_as_the_structures_shapes() {
        let mut b = hyst_sim::building::ShearBuilding::three_storey_example(None);
        b.reading = hyst_sim::building::Reading::Displacement;
        b.load.rms = 2000.0;
        let y = b.generate(60_000, 8_400_801).unwrap();
        let channels: Vec<&[f64]> = y.iter().map(Vec::as_slice).collect();
        let opts = AmplitudeOptions {
            measured: Quantity::Displacement,
            floors: Some(vec![0, 1, 2]),
            ..AmplitudeOptions::default()
        };
        let got = amplitude_analysis(
            &channels,
            b.fs,
            &covssi::AnalysisOptions::default(),
            &opts,
            &[],
        )
        .unwrap();
        let truth = b.modes().unwrap();
        let mut checked = 0;
        for curve in &got.curves.modes {
            let Some(t) = truth
                .iter()
                .find(|t| (t.frequency_hz / curve.mode.frequency_hz - 1.0).abs() < 0.02)
            else {
                continue;
            };
            let top = t.shape.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for p in &curve.points {
                let big = p.channels.iter().fold(0.0f64, |m, v| m.max(*v));
                for (c, s) in p.channels.iter().zip(&t.shape) {
                    // SSI's shapes from 300 s at 1 % noise: every entry within 0.4 % of the
                    // largest on this seed; 1.5 % leaves room for another record, and a
                    // channel of the wrong floor would be off by 20 % or more.
                    assert!(
                        (c / big - s.abs() / top).abs() < 0.015,
                        "mode {} Hz: channels {:?}, shape {:?}",
                        t.frequency_hz,
                        p.channels,
                        t.shape
                    );
                }
                for (s, d) in p.drifts.iter().enumerate() {
                    let below = if s == 0 { 0.0 } else { t.shape[s - 1] };
                    let want = (t.shape[s] - below).abs() / top;
                    // A difference of two entries: twice an entry's error.
                    assert!(
                        (d / big - want).abs() < 0.03,
                        "{:?} {:?}",
                        p.drifts,
                        t.shape
                    );
                }
                checked += 1;
            }
        }
        // Three modes, several points each.
        assert!(checked >= 12, "{checked} points checked");
    }
}
