//! Tests of a mode's change with its amplitude: within one record (the slope's standard error
//! by the same jackknife as the points'), and pooled over several records (independent
//! records, each point with its standard error).

use statrs::distribution::{ContinuousCDF, StudentsT};

use super::{AmplitudePoint, LINEARITY_LEVEL, Linearity, SlopeTest, decay};

/// The grouped jackknife's standard error from the estimates with each group left out:
/// $\sqrt{\tfrac{G-1}{G}\sum_g(\theta_{-g} - \bar\theta)^2}$.
pub(crate) fn jackknife_se(values: &[f64]) -> f64 {
    let g = values.len() as f64;
    let mean = values.iter().sum::<f64>() / g;
    ((g - 1.0) / g * values.iter().map(|v| (v - mean).powi(2)).sum::<f64>()).sqrt()
}

/// The weighted least-squares line of `v` on `a` (weights `w`).
struct Line {
    /// Weighted means of a and v.
    mean_a: f64,
    mean_v: f64,
    slope: f64,
    /// Σ w (a − ā)².
    sxx: f64,
    /// max a − min a.
    range: f64,
}

fn weighted_line(a: &[f64], v: &[f64], w: &[f64]) -> Line {
    let sw: f64 = w.iter().sum();
    let mean_a = a.iter().zip(w).map(|(a, w)| a * w).sum::<f64>() / sw;
    let mean_v = v.iter().zip(w).map(|(v, w)| v * w).sum::<f64>() / sw;
    let sxy: f64 = a
        .iter()
        .zip(v)
        .zip(w)
        .map(|((a, v), w)| w * (a - mean_a) * (v - mean_v))
        .sum();
    let sxx: f64 = a.iter().zip(w).map(|(a, w)| w * (a - mean_a).powi(2)).sum();
    let range = a.iter().fold(f64::NEG_INFINITY, |m, &x| m.max(x))
        - a.iter().fold(f64::INFINITY, |m, &x| m.min(x));
    Line {
        mean_a,
        mean_v,
        slope: sxy / sxx,
        sxx,
        range,
    }
}

/// Weights 1/se².
fn weights(se: &[f64]) -> Vec<f64> {
    se.iter()
        .map(|s| 1.0 / (s * s).max(f64::MIN_POSITIVE))
        .collect()
}

/// The change's test: two-sided p-value of Student's t with `dof` degrees of freedom.
fn slope_test(change: f64, change_se: f64, dof: f64) -> SlopeTest {
    let p_value = StudentsT::new(0.0, 1.0, dof)
        .map(|d| 2.0 * (1.0 - d.cdf((change / change_se).abs())))
        .unwrap_or(f64::NAN);
    SlopeTest {
        change,
        change_se,
        p_value,
    }
}

/// Linear when neither change is significant at half of [`LINEARITY_LEVEL`] (a p-value that
/// could not be computed, NaN, is no evidence of a change).
fn verdict(frequency: SlopeTest, damping: SlopeTest) -> Linearity {
    let significant = |p: f64| p < 0.5 * LINEARITY_LEVEL;
    Linearity {
        frequency,
        damping,
        linear: !significant(frequency.p_value) && !significant(damping.p_value),
    }
}

/// One record's test: its `points` (each with its jackknife error) and, per point, its
/// estimates with each of the `groups` groups left out (`replicates[k][g]`); `amp` gives a
/// replicate's amplitude as the points give theirs. The change's error is the jackknife's
/// over the same groups.
pub(super) fn linearity(
    points: &[AmplitudePoint],
    replicates: &[Vec<decay::Decay>],
    groups: usize,
    amp: &dyn Fn(&decay::Decay) -> f64,
) -> Linearity {
    let a: Vec<f64> = points.iter().map(|p| p.amplitude).collect();
    let test = |value: &dyn Fn(&AmplitudePoint) -> f64,
                se: &dyn Fn(&AmplitudePoint) -> f64,
                get: &dyn Fn(&decay::Decay) -> f64|
     -> SlopeTest {
        let w = weights(&points.iter().map(se).collect::<Vec<_>>());
        let v: Vec<f64> = points.iter().map(value).collect();
        let line = weighted_line(&a, &v, &w);
        let replicate: Vec<f64> = (0..groups)
            .map(|g| {
                let a: Vec<f64> = replicates.iter().map(|r| amp(&r[g])).collect();
                let v: Vec<f64> = replicates.iter().map(|r| get(&r[g])).collect();
                let l = weighted_line(&a, &v, &w);
                l.slope * l.range
            })
            .collect();
        slope_test(
            line.slope * line.range,
            jackknife_se(&replicate),
            (groups - 1) as f64,
        )
    };
    verdict(
        test(&|p| p.frequency_hz, &|p| p.frequency_se_hz, &|d| {
            d.frequency_hz
        }),
        test(&|p| p.damping_ratio, &|p| p.damping_se, &|d| {
            d.damping_ratio
        }),
    )
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
    let dof = (points.len() - 2) as f64;
    let test = |v: &[f64], se: &[f64]| -> SlopeTest {
        let w = weights(se);
        let l = weighted_line(&a, v, &w);
        let chi2: f64 = a
            .iter()
            .zip(v)
            .zip(&w)
            .map(|((a, v), w)| w * (v - l.mean_v - l.slope * (a - l.mean_a)).powi(2))
            .sum();
        let inflate = (chi2 / dof).max(1.0).sqrt();
        slope_test(l.slope * l.range, inflate * l.range / l.sxx.sqrt(), dof)
    };
    let col = |f: &dyn Fn(&AmplitudePoint) -> f64| points.iter().map(f).collect::<Vec<f64>>();
    Some(verdict(
        test(&col(&|p| p.frequency_hz), &col(&|p| p.frequency_se_hz)),
        test(&col(&|p| p.damping_ratio), &col(&|p| p.damping_se)),
    ))
}
