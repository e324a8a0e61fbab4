//! Which training records a mode's baseline is fitted on. A training value far from the
//! rest is set apart, by record, with the rule that set it apart; it is never silently used
//! (one typed cell of 100 Hz among 1 Hz values made a baseline of 5.95 Hz with an SD of 22 Hz,
//! and a later 2 % drop raised no alarm).
//!
//! Two robust rules, each from what it must hold for rather than from any record:
//! - **Gross**: a frequency a factor of [`GROSS_FACTOR`] or more from the mode's training
//!   median. An environment changes a structure's frequencies by tens of per cent at most
//!   (frost stiffening a bridge's supports raises them by 10–20 %); a factor of two is four
//!   times the stiffness: a typo (a unit, a decimal point) or another mode.
//! - **Far from the fit**: a residual of the baseline fitted on the rest more than
//!   [`ROBUST_SDS`] robust standard deviations (1.4826 · the median absolute deviation) from the
//!   residuals' median. A normal residual passes that limit about once in 10¹⁵, so only a value
//!   no model of the others explains is set apart; the baseline is then fitted again.

use std::fmt;

/// A training frequency this factor or more from the training median is gross.
pub const GROSS_FACTOR: f64 = 2.0;

/// A training residual this many robust standard deviations from the residuals' median is
/// set apart.
pub const ROBUST_SDS: f64 = 8.0;

/// A training record's value set apart from a mode's baseline.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct TrainingOutlier {
    /// The reference mode (from 0).
    pub mode: usize,
    /// The record (from 0).
    pub record: usize,
    /// Its frequency (Hz).
    pub frequency_hz: f64,
    /// The rule that set it apart.
    pub rule: OutlierRule,
}

/// Why a training value was set apart ([module doc](self)).
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub enum OutlierRule {
    /// A factor of [`GROSS_FACTOR`] or more from the training median.
    Gross {
        /// The training median (Hz).
        median_hz: f64,
    },
    /// Its residual from the baseline of the rest, in robust standard deviations.
    FarFromFit {
        /// The residual over 1.4826 · MAD.
        robust_z: f64,
    },
}

impl fmt::Display for OutlierRule {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            OutlierRule::Gross { median_hz } => write!(
                f,
                "a factor {GROSS_FACTOR} or more from the training median {median_hz:.4} Hz"
            ),
            OutlierRule::FarFromFit { robust_z } => write!(
                f,
                "{robust_z:.1} robust SDs from the baseline of the rest (limit {ROBUST_SDS})"
            ),
        }
    }
}

/// The median of the finite values of `v` (NaN when none).
pub(crate) fn median(v: &[f64]) -> f64 {
    let mut s: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if s.is_empty() {
        return f64::NAN;
    }
    s.sort_by(f64::total_cmp);
    let n = s.len();
    if n % 2 == 1 {
        s[n / 2]
    } else {
        0.5 * (s[n / 2 - 1] + s[n / 2])
    }
}

/// Whether `f` is gross against the training median `median_hz` (a value that is not finite
/// and positive is).
pub(crate) fn is_gross(f: f64, median_hz: f64) -> bool {
    !(f.is_finite() && f > 0.0) || f >= GROSS_FACTOR * median_hz || GROSS_FACTOR * f <= median_hz
}

/// Each residual's robust z when it is beyond [`ROBUST_SDS`], else `None`; all `None` when
/// the residuals' MAD is zero (too few distinct values to judge).
pub(crate) fn far_from_fit(residuals: &[f64]) -> Vec<Option<f64>> {
    let centre = median(residuals);
    let deviations: Vec<f64> = residuals.iter().map(|r| (r - centre).abs()).collect();
    let scale = 1.4826 * median(&deviations);
    residuals
        .iter()
        .map(|r| {
            let z = (r - centre) / scale;
            (scale > 0.0 && z.abs() > ROBUST_SDS).then_some(z)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rules on values whose answer is known: a 100× typo and 1e308 are gross, a 20 %
    /// frost rise is not; among residuals of unit spread, one of 50 is far and 4 is not;
    /// a constant set judges nothing.
    #[test]
    fn the_rules_set_apart_only_what_no_environment_makes() {
        let m = 1.0;
        assert!(is_gross(100.0, m) && is_gross(1e308, m) && is_gross(0.1, m));
        assert!(is_gross(f64::NAN, m) && is_gross(-1.0, m));
        assert!(!is_gross(1.2, m) && !is_gross(0.8, m));
        // Residuals of unit spread (a deterministic spread of quantiles), one far and one not.
        let mut r: Vec<f64> = (1..200)
            .map(|i| {
                let p = i as f64 / 200.0;
                // A rough normal quantile (logistic): spread of order 1.
                (p / (1.0 - p)).ln() / 1.7
            })
            .collect();
        r.push(50.0);
        r.push(4.0);
        let far = far_from_fit(&r);
        assert!(far[199].is_some_and(|z| z > ROBUST_SDS), "{:?}", far[199]);
        assert!(far[200].is_none());
        assert_eq!(far.iter().filter(|z| z.is_some()).count(), 1);
        assert!(far_from_fit(&[1.0; 10]).iter().all(Option::is_none));
        assert_eq!(median(&[3.0, 1.0, 2.0, f64::NAN]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), 2.5);
    }
}
