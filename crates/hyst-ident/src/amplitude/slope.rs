//! Tests of a mode's change with its amplitude: within one record (the slope's standard error
//! by the same jackknife as the points'), and pooled over several records (independent
//! records, each point with its standard error).

use statrs::distribution::{ContinuousCDF, StudentsT};

use super::{AmplitudePoint, LINEARITY_LEVEL, Linearity, SlopeTest, decay};

/// The weighted least-squares slope of `v` on `a` (weights `w`), times the range of `a`.
fn change(a: &[f64], v: &[f64], w: &[f64]) -> f64 {
    let sw: f64 = w.iter().sum();
    let ma = a.iter().zip(w).map(|(a, w)| a * w).sum::<f64>() / sw;
    let mv = v.iter().zip(w).map(|(v, w)| v * w).sum::<f64>() / sw;
    let sxy: f64 = a
        .iter()
        .zip(v)
        .zip(w)
        .map(|((a, v), w)| w * (a - ma) * (v - mv))
        .sum();
    let sxx: f64 = a.iter().zip(w).map(|(a, w)| w * (a - ma).powi(2)).sum();
    let range = a.iter().fold(f64::NEG_INFINITY, |m, &x| m.max(x))
        - a.iter().fold(f64::INFINITY, |m, &x| m.min(x));
    sxy / sxx * range
}

pub(super) type Row = (decay::Decay, Vec<decay::Decay>, usize);

pub(super) fn linearity(
    rows: &[Row],
    groups: usize,
    amp: &dyn Fn(&decay::Decay) -> f64,
    jack: &dyn Fn(&[f64]) -> f64,
) -> Linearity {
    let test = |get: &dyn Fn(&decay::Decay) -> f64| -> SlopeTest {
        let reps: Vec<Vec<f64>> = (0..groups)
            .map(|g| rows.iter().map(|r| get(&r.1[g])).collect())
            .collect();
        let se: Vec<f64> = (0..rows.len())
            .map(|k| jack(&reps.iter().map(|r| r[k]).collect::<Vec<_>>()))
            .collect();
        let w: Vec<f64> = se
            .iter()
            .map(|s| 1.0 / (s * s).max(f64::MIN_POSITIVE))
            .collect();
        let a: Vec<f64> = rows.iter().map(|r| amp(&r.0)).collect();
        let full = change(&a, &rows.iter().map(|r| get(&r.0)).collect::<Vec<_>>(), &w);
        let replicate: Vec<f64> = (0..groups)
            .map(|g| {
                let a: Vec<f64> = rows.iter().map(|r| amp(&r.1[g])).collect();
                change(&a, &reps[g], &w)
            })
            .collect();
        let change_se = jack(&replicate);
        let t = full / change_se;
        let p_value = StudentsT::new(0.0, 1.0, (groups - 1) as f64)
            .map(|d| 2.0 * (1.0 - d.cdf(t.abs())))
            .unwrap_or(f64::NAN);
        SlopeTest {
            change: full,
            change_se,
            p_value,
        }
    };
    let frequency = test(&|d| d.frequency_hz);
    let damping = test(&|d| d.damping_ratio);
    let half = 0.5 * LINEARITY_LEVEL;
    let significant = |p: f64| p < half;
    Linearity {
        frequency,
        damping,
        // A p-value that could not be computed (NaN) is no evidence of a change.
        linear: !significant(frequency.p_value) && !significant(damping.p_value),
    }
}

/// A mode's change over several records' points, each with its standard error: the
/// weighted least-squares slope of frequency and of damping on the amplitude (weights
/// 1/se²), its standard error from the weights, inflated by the fit's reduced χ² when the
/// points scatter more than their errors say (they do when the change is not a straight
/// line, or one record's points share an error), and Student's t with n − 2 degrees of
/// freedom. `None` with fewer than three points.
pub fn pooled_linearity(points: &[AmplitudePoint]) -> Option<Linearity> {
    if points.len() < 3 {
        return None;
    }
    let a: Vec<f64> = points.iter().map(|p| p.amplitude).collect();
    let test = |v: &[f64], se: &[f64]| -> SlopeTest {
        let w: Vec<f64> = se
            .iter()
            .map(|s| 1.0 / (s * s).max(f64::MIN_POSITIVE))
            .collect();
        let sw: f64 = w.iter().sum();
        let ma = a.iter().zip(&w).map(|(a, w)| a * w).sum::<f64>() / sw;
        let mv = v.iter().zip(&w).map(|(v, w)| v * w).sum::<f64>() / sw;
        let sxx: f64 = a.iter().zip(&w).map(|(a, w)| w * (a - ma).powi(2)).sum();
        let slope = a
            .iter()
            .zip(v)
            .zip(&w)
            .map(|((a, v), w)| w * (a - ma) * (v - mv))
            .sum::<f64>()
            / sxx;
        let dof = (points.len() - 2) as f64;
        let chi2: f64 = a
            .iter()
            .zip(v)
            .zip(&w)
            .map(|((a, v), w)| w * (v - mv - slope * (a - ma)).powi(2))
            .sum();
        let inflate = (chi2 / dof).max(1.0).sqrt();
        let range = a.iter().fold(f64::NEG_INFINITY, |m, &x| m.max(x))
            - a.iter().fold(f64::INFINITY, |m, &x| m.min(x));
        let change_se = inflate * range / sxx.sqrt();
        let change = slope * range;
        let p_value = StudentsT::new(0.0, 1.0, dof)
            .map(|d| 2.0 * (1.0 - d.cdf((change / change_se).abs())))
            .unwrap_or(f64::NAN);
        SlopeTest {
            change,
            change_se,
            p_value,
        }
    };
    let col = |f: &dyn Fn(&AmplitudePoint) -> f64| points.iter().map(f).collect::<Vec<f64>>();
    let frequency = test(&col(&|p| p.frequency_hz), &col(&|p| p.frequency_se_hz));
    let damping = test(&col(&|p| p.damping_ratio), &col(&|p| p.damping_se));
    let significant = |p: f64| p < 0.5 * LINEARITY_LEVEL;
    Some(Linearity {
        frequency,
        damping,
        linear: !significant(frequency.p_value) && !significant(damping.p_value),
    })
}
