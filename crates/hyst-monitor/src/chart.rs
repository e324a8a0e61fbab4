//! A two-sided CUSUM chart of standardized residuals, and its in-control average run length
//! (see the crate's documentation).

use crate::MonitorError;

/// Which way the chart moved.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum Side {
    /// The values rose.
    Up,
    /// The values fell.
    Down,
}

/// An alarm: where, which way, and the statistic that passed the limit.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Alarm {
    /// 0-based index of the value that raised it.
    pub index: usize,
    /// Which way.
    pub side: Side,
    /// The CUSUM statistic there.
    pub statistic: f64,
}

/// A two-sided CUSUM of standardized values: reference value `k` (half the shift, in
/// standard deviations, it is tuned to detect fastest) and decision limit `h`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Cusum {
    /// Reference value k.
    pub k: f64,
    /// Decision limit h.
    pub h: f64,
}

impl Default for Cusum {
    /// k = 0.5, h = 12: tuned to a shift of one standard deviation, with an in-control
    /// average run length of about 5.2·10⁵ values (for hourly records, one false alarm per
    /// mode in some sixty years, if the residuals are independent and standard normal).
    fn default() -> Self {
        Cusum { k: 0.5, h: 12.0 }
    }
}

impl Cusum {
    /// A chart with these parameters, which must be positive and finite.
    pub fn new(k: f64, h: f64) -> Result<Cusum, MonitorError> {
        for (parameter, value) in [("k", k), ("h", h)] {
            if !(value.is_finite() && value > 0.0) {
                return Err(MonitorError::ChartParameter { parameter, value });
            }
        }
        Ok(Cusum { k, h })
    }

    /// The alarms over `z` (NaN values, records without the mode, are passed over); after
    /// an alarm the side that raised it starts again from zero.
    pub fn alarms(&self, z: &[f64]) -> Vec<Alarm> {
        self.runs(z).into_iter().map(|(a, _)| a).collect()
    }

    /// The alarms over `z` as [`Cusum::alarms`] finds them, each with the index where its
    /// side's run began (the first value after the side last stood at zero): the values
    /// that raised it.
    pub fn runs(&self, z: &[f64]) -> Vec<(Alarm, usize)> {
        let (mut up, mut down) = (0.0f64, 0.0f64);
        let (mut up_from, mut down_from) = (0usize, 0usize);
        let mut out = Vec::new();
        for (index, &v) in z.iter().enumerate() {
            if !v.is_finite() {
                continue;
            }
            if up == 0.0 {
                up_from = index;
            }
            if down == 0.0 {
                down_from = index;
            }
            up = (up + v - self.k).max(0.0);
            down = (down - v - self.k).max(0.0);
            for (s, from, side) in [
                (&mut up, up_from, Side::Up),
                (&mut down, down_from, Side::Down),
            ] {
                if *s > self.h {
                    out.push((
                        Alarm {
                            index,
                            side,
                            statistic: *s,
                        },
                        from,
                    ));
                    *s = 0.0;
                }
            }
        }
        out
    }

    /// The in-control average run length (values between false alarms) of the two-sided
    /// chart on independent standard normal values, by Siegmund's approximation of each
    /// side's, ARL = (e^{−2Δb} + 2Δb − 1) / (2Δ²) with Δ = −k and b = h + 1.166, combined
    /// as 1/ARL = 1/ARL⁺ + 1/ARL⁻.
    pub fn in_control_run_length(&self) -> f64 {
        let delta = -self.k;
        let b = self.h + 1.166;
        let one_side = ((-2.0 * delta * b).exp() + 2.0 * delta * b - 1.0) / (2.0 * delta * delta);
        one_side / 2.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    /// The approximation against a simulation of the chart on standard normal values:
    /// the false-alarm count over 4·10⁶ values for h = 4 (ARL ≈ 336 by the formula).
    #[test]
    fn the_run_length_formula_matches_a_simulation() {
        let chart = Cusum::new(0.5, 4.0).unwrap();
        let arl = chart.in_control_run_length();
        let mut rng = rand::rngs::StdRng::seed_from_u64(5);
        let normal = Normal::new(0.0, 1.0).unwrap();
        let z: Vec<f64> = (0..4_000_000).map(|_| normal.sample(&mut rng)).collect();
        let alarms = chart.alarms(&z).len() as f64;
        let simulated = z.len() as f64 / alarms;
        // ~12000 alarms: the count's own spread is ~1 %; Siegmund's approximation is
        // within a few per cent at these k, h.
        assert!((simulated / arl - 1.0).abs() < 0.05, "{simulated} vs {arl}");
        // The default's run length, as its documentation says.
        let d = Cusum::default().in_control_run_length();
        assert!((d / 5.2e5 - 1.0).abs() < 0.05, "{d}");
    }

    /// A shift of two standard deviations is caught within a few values; the side is
    /// right.
    #[test]
    fn a_shift_is_caught_on_its_side() {
        let chart = Cusum::default();
        let mut z = vec![0.0; 100];
        z.extend(vec![-2.0; 20]);
        let a = chart.alarms(&z);
        assert_eq!(a[0].side, Side::Down);
        // (2 − 0.5) per value: past 12 on the 9th.
        assert_eq!(a[0].index, 108);
        // The run that raised it began with the shift.
        assert_eq!(chart.runs(&z)[0].1, 100);
        assert!(Cusum::new(0.5, f64::NAN).is_err());
    }
}
