//! Every field of a [`ShearBuilding`] checked once, each failure naming its field: the
//! counts agree with the floors, every floor and storey named exists, every value is
//! physical, and the element lies in Bouc-Wen's bounded range (β + γ > 0, γ ≤ β; Ismail et
//! al. 2009) with ν ≥ 1 (below 1, |z|^{ν−1} is infinite at z = 0, where every record
//! starts).

use super::{Colour, ShearBuilding};
use crate::SimError;

/// The failure for `field` holding `value`.
fn bad(field: impl Into<String>, value: f64, why: &'static str) -> SimError {
    SimError::InvalidBuilding {
        field: field.into(),
        value,
        why,
    }
}

/// Nothing when `ok` holds and `value` is finite, else the failure for `field`.
fn need(field: impl Into<String>, value: f64, ok: bool, why: &'static str) -> Result<(), SimError> {
    if ok && value.is_finite() {
        Ok(())
    } else {
        Err(bad(field, value, why))
    }
}

/// Each of `floors` (named `field[i]`) below `n`, none twice when `distinct`.
fn floors_exist(field: &str, floors: &[usize], n: usize, distinct: bool) -> Result<(), SimError> {
    for (i, &f) in floors.iter().enumerate() {
        if f >= n {
            return Err(bad(
                format!("{field}[{i}]"),
                f as f64,
                "a floor above the building's top (floors count from 0)",
            ));
        }
        if distinct && floors[..i].contains(&f) {
            return Err(bad(
                format!("{field}[{i}]"),
                f as f64,
                "a floor given twice (each loaded floor carries its own force)",
            ));
        }
    }
    Ok(())
}

impl ShearBuilding {
    /// Checks every field: one mass, stiffness and damping ratio per floor, each physical
    /// (masses and stiffnesses positive, 0 ≤ ζ < 1); the element's storey within the
    /// building, its linear share in [0, 1], β ≥ 0, β + γ > 0, γ ≤ β and ν ≥ 1; every
    /// sensor and loaded floor a floor of the building (no floor loaded twice); the load's
    /// RMS, colours, modulation and machine physical; noise and drift at least 0; a positive
    /// rate. Every simulation runs it first.
    pub fn validate(&self) -> Result<(), SimError> {
        let n = self.masses.len();
        if n == 0 {
            return Err(bad("masses", 0.0, "a building needs at least one floor"));
        }
        let counts = [
            ("stiffnesses", self.stiffnesses.len()),
            ("damping_ratios", self.damping_ratios.len()),
        ];
        for (field, len) in counts {
            if len != n {
                return Err(bad(field, len as f64, "one per floor (as many as masses)"));
            }
        }
        for (i, &m) in self.masses.iter().enumerate() {
            need(
                format!("masses[{i}]"),
                m,
                m > 0.0,
                "a mass (kg) must be positive",
            )?;
        }
        for (i, &k) in self.stiffnesses.iter().enumerate() {
            need(
                format!("stiffnesses[{i}]"),
                k,
                k > 0.0,
                "a storey stiffness (N/m) must be positive",
            )?;
        }
        for (i, &z) in self.damping_ratios.iter().enumerate() {
            need(
                format!("damping_ratios[{i}]"),
                z,
                (0.0..1.0).contains(&z),
                "a damping ratio lies in [0, 1)",
            )?;
        }
        if let Some(h) = &self.hysteresis {
            if h.storey >= n {
                return Err(bad(
                    "hysteresis.storey",
                    h.storey as f64,
                    "a storey the building has (0: between the ground and the first floor)",
                ));
            }
            need(
                "hysteresis.linear_share",
                h.linear_share,
                (0.0..=1.0).contains(&h.linear_share),
                "a share of the storey's stiffness, in [0, 1]",
            )?;
            need(
                "hysteresis.beta",
                h.beta,
                h.beta >= 0.0,
                "β must be at least 0",
            )?;
            need(
                "hysteresis.gamma",
                h.gamma,
                h.beta + h.gamma > 0.0 && h.gamma <= h.beta,
                "Bouc-Wen's bounded range needs β + γ > 0 and γ ≤ β",
            )?;
            need(
                "hysteresis.nu",
                h.nu,
                h.nu >= 1.0,
                "ν must be at least 1 (|z|^(ν−1) is infinite at z = 0 below it)",
            )?;
        }
        floors_exist("sensors", &self.sensors, n, false)?;
        self.validate_load(n)?;
        need(
            "noise",
            self.noise,
            self.noise >= 0.0,
            "a share of each channel's deviation, at least 0",
        )?;
        need(
            "drift",
            self.drift,
            self.drift >= 0.0,
            "a share of each channel's deviation, at least 0",
        )?;
        need("fs", self.fs, self.fs > 0.0, "a rate (Hz) must be positive")
    }

    /// The load's fields.
    fn validate_load(&self, n: usize) -> Result<(), SimError> {
        let load = &self.load;
        floors_exist("load.floors", &load.floors, n, true)?;
        need(
            "load.rms",
            load.rms,
            load.rms >= 0.0,
            "an RMS (N) is at least 0",
        )?;
        let nyquist = self.fs / 2.0;
        for (i, c) in load.colours.iter().enumerate() {
            let field = |name: &str| format!("load.colours[{i}].{name}");
            match *c {
                Colour::LowPass { corner_hz, order } => {
                    need(
                        field("corner_hz"),
                        corner_hz,
                        corner_hz > 0.0,
                        "a corner (Hz) must be positive",
                    )?;
                    if !(1..=8).contains(&order) {
                        return Err(bad(field("order"), order as f64, "an order from 1 to 8"));
                    }
                }
                Colour::Resonance {
                    frequency_hz,
                    damping_ratio,
                } => {
                    need(
                        field("frequency_hz"),
                        frequency_hz,
                        frequency_hz > 0.0,
                        "a frequency (Hz) must be positive",
                    )?;
                    need(
                        field("damping_ratio"),
                        damping_ratio,
                        damping_ratio > 0.0 && damping_ratio < 1.0,
                        "a resonance's damping ratio lies in (0, 1)",
                    )?;
                }
                Colour::Red { corner_hz } => need(
                    field("corner_hz"),
                    corner_hz,
                    corner_hz > 0.0,
                    "a corner (Hz) must be positive",
                )?,
            }
        }
        if let Some((depth, period)) = load.modulation {
            need(
                "load.modulation[0]",
                depth,
                (0.0..=1.0).contains(&depth),
                "a modulation's depth lies in [0, 1]",
            )?;
            need(
                "load.modulation[1]",
                period,
                period > 0.0,
                "a modulation's period (s) must be positive",
            )?;
        }
        if let Some((floor, hz, amplitude)) = load.harmonic {
            floors_exist("load.harmonic[0]", &[floor], n, false)?;
            need(
                "load.harmonic[1]",
                hz,
                hz > 0.0 && hz < nyquist,
                "a machine's frequency (Hz) lies between 0 and the Nyquist frequency",
            )?;
            need(
                "load.harmonic[2]",
                amplitude,
                true,
                "a machine's amplitude (N) must be finite",
            )?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The example with one field changed by `edit`: its failure's field name.
    fn refused(edit: impl FnOnce(&mut ShearBuilding)) -> String {
        let mut b = ShearBuilding::three_storey_example(Some(1));
        edit(&mut b);
        match b.validate() {
            Err(SimError::InvalidBuilding { field, .. }) => field,
            other => panic!("not refused: {other:?}"),
        }
    }

    #[test]
    fn the_example_is_valid() {
        ShearBuilding::three_storey_example(Some(1))
            .validate()
            .unwrap();
        ShearBuilding::three_storey_example(None)
            .validate()
            .unwrap();
    }

    #[test]
    fn each_unphysical_field_is_named() {
        assert_eq!(refused(|b| b.masses[2] = -1.0), "masses[2]");
        assert_eq!(
            refused(|b| {
                b.stiffnesses.pop();
            }),
            "stiffnesses"
        );
        assert_eq!(refused(|b| b.stiffnesses[0] = f64::NAN), "stiffnesses[0]");
        assert_eq!(
            refused(|b| b.damping_ratios[1] = -0.01),
            "damping_ratios[1]"
        );
        let h = |b: &mut ShearBuilding| b.hysteresis.as_mut().unwrap().clone();
        let set = |edit: fn(&mut super::super::StoreyHysteresis)| {
            move |b: &mut ShearBuilding| {
                let mut e = h(b);
                edit(&mut e);
                b.hysteresis = Some(e);
            }
        };
        assert_eq!(refused(set(|e| e.storey = 9)), "hysteresis.storey");
        assert_eq!(
            refused(set(|e| e.linear_share = 2.0)),
            "hysteresis.linear_share"
        );
        assert_eq!(refused(set(|e| e.beta = -1.0)), "hysteresis.beta");
        assert_eq!(
            refused(set(|e| e.gamma = 2.0 * e.beta + 1.0)),
            "hysteresis.gamma"
        );
        assert_eq!(refused(set(|e| e.nu = 0.0)), "hysteresis.nu");
        assert_eq!(refused(|b| b.sensors.push(3)), "sensors[3]");
        assert_eq!(refused(|b| b.load.floors = vec![2, 2]), "load.floors[1]");
        assert_eq!(refused(|b| b.load.rms = -1.0), "load.rms");
        assert_eq!(refused(|b| b.noise = -0.1), "noise");
        assert_eq!(refused(|b| b.fs = 0.0), "fs");
    }

    #[test]
    fn a_storey_beyond_the_top_is_refused_by_every_simulation() {
        let mut b = ShearBuilding::three_storey_example(Some(1));
        b.hysteresis.as_mut().unwrap().storey = 9;
        assert!(matches!(
            b.generate(100, 1),
            Err(SimError::InvalidBuilding { .. })
        ));
        let loads = vec![vec![0.0; 9]; 3];
        assert!(matches!(
            b.respond(&loads, 8, 0),
            Err(SimError::InvalidBuilding { .. })
        ));
    }
}
