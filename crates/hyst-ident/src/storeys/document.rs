//! A storey fit read back (`hyst levels --masses --json`, perhaps edited) checked once,
//! before anything is simulated from it: its structure physical ([`ShearBuilding::validate`]),
//! and every part that repeats another agreeing with it — the element's storey, the loaded
//! floors, the parameters' names and values against the structure's and the force
//! densities, the covariance's size — and its reading within what a fit of that structure
//! could have chosen (the integration step and warm-up bounded, so an edited number cannot
//! ask for terabytes).

use super::error::StoreyError;
use super::model::Layout;
use super::setup::{WARM_UP_LEAST_DAMPING, stepping};
use super::types::StoreyFit;
use crate::IdentError;
use hyst_sim::building::Reading as Quantity;

/// Relative disagreement allowed between a parameter and the structure's copy of it: the
/// document writes both from one double, and JSON's shortest round-trip representation reads
/// it back exactly, so anything beyond rounding is an edit.
const SAME: f64 = 1e-9;

/// How far the reading may go beyond the steps a fit of the structure takes
/// ([`super::setup::stepping`], its warm-up at the least damping it allows): ten times either.
const READING_MARGIN: f64 = 10.0;

/// The failure of a fit whose parts disagree.
pub(super) fn inconsistent(what: String) -> IdentError {
    StoreyError::InconsistentFit { what }.into()
}

impl StoreyFit {
    /// Checks the fit before it is simulated or read from: every field of its structure, and
    /// every part that repeats another (see the module's doc). Each failure names the field.
    /// [`super::simulate_structure`], [`super::predict_level`], [`super::model_records`] and
    /// [`super::level_statistics`] call it first.
    pub fn validate(&self) -> Result<(), IdentError> {
        let b = &self.building;
        b.validate()?;
        let floors = b.masses.len();
        let element = b.hysteresis.as_ref().map(|h| h.storey);
        if element != self.storey {
            return Err(inconsistent(format!(
                "`storey` is {:?} and `building.hysteresis` puts the element in storey {:?}",
                self.storey, element
            )));
        }
        if self.load_floors != b.load.floors {
            return Err(inconsistent(format!(
                "`load_floors` {:?} and `building.load.floors` {:?} differ",
                self.load_floors, b.load.floors
            )));
        }
        if self.load_floors.is_empty() {
            return Err(inconsistent(
                "`load_floors` is empty: no floor is loaded".into(),
            ));
        }
        if self.force_densities.is_empty() {
            return Err(inconsistent("`force_densities` is empty: no level".into()));
        }
        if let Some((l, q)) = self
            .force_densities
            .iter()
            .enumerate()
            .find(|(_, q)| !(q.is_finite() && **q > 0.0))
        {
            return Err(inconsistent(format!(
                "`force_densities[{l}]` = {q}: a force density (N²/Hz) must be positive"
            )));
        }
        if self.agreement.verdict == super::types::FitVerdict::Far {
            return Err(inconsistent(
                "`agreement.verdict` is `far`: the fit did not reach its records, so it is not a model of them".into(),
            ));
        }
        self.validate_parameters(floors)?;
        self.validate_reading(floors)
    }

    /// The parameters: the layout's names, each value the structure's (or the level's
    /// density), the covariance one row and column per parameter.
    fn validate_parameters(&self, floors: usize) -> Result<(), IdentError> {
        let b = &self.building;
        let layout = Layout {
            floors,
            levels: self.force_densities.len(),
            storey: self.storey,
            folded: b.reading == Quantity::Acceleration,
        };
        let names = layout.names();
        let given: Vec<&str> = self.parameters.iter().map(|p| p.name.as_str()).collect();
        if given != names {
            return Err(inconsistent(format!(
                "its parameters are {given:?}; its structure and levels make {names:?}"
            )));
        }
        let mut copies: Vec<(String, f64)> = Vec::new();
        for (s, &k) in b.stiffnesses.iter().enumerate() {
            copies.push((format!("building.stiffnesses[{s}]"), k));
        }
        for (j, &z) in b.damping_ratios.iter().enumerate() {
            copies.push((format!("building.damping_ratios[{j}]"), z));
        }
        for (l, &q) in self.force_densities.iter().enumerate() {
            copies.push((format!("force_densities[{l}]"), q));
        }
        let mut values = self.parameters.iter();
        for ((field, copy), p) in copies.iter().zip(values.by_ref()) {
            if (p.value - copy).abs() > SAME * copy.abs() {
                return Err(inconsistent(format!(
                    "parameter `{}` = {} but `{field}` = {copy}",
                    p.name, p.value
                )));
            }
        }
        if layout.folded {
            let p = values.next();
            if let Some(p) = p.filter(|p| !(p.value.is_finite() && p.value >= 0.0)) {
                return Err(inconsistent(format!(
                    "parameter `b` = {}: the folded band is at least 0",
                    p.value
                )));
            }
        }
        if let Some(h) = &b.hysteresis {
            let element = [
                ("building.hysteresis.linear_share", h.linear_share),
                ("building.hysteresis.beta", h.beta),
                ("building.hysteresis.gamma", h.gamma),
            ];
            for ((field, copy), p) in element.iter().zip(values) {
                if (p.value - copy).abs() > SAME * copy.abs() {
                    return Err(inconsistent(format!(
                        "parameter `{}` = {} but `{field}` = {copy}",
                        p.name, p.value
                    )));
                }
            }
        }
        let np = names.len();
        if self.covariance.len() != np || self.covariance.iter().any(|r| r.len() != np) {
            return Err(inconsistent(format!(
                "its covariance is not {np} × {np} (one row per parameter)"
            )));
        }
        Ok(())
    }

    /// The reading: one band per mode, edges increasing; a Welch segment of at least 4; the
    /// integration step and the warm-up within [`READING_MARGIN`] of what a fit of this
    /// structure chooses.
    fn validate_reading(&self, floors: usize) -> Result<(), IdentError> {
        let b = &self.building;
        let r = &self.reading;
        if r.bands_hz.len() != floors + 1 || r.segment < 4 || r.steps_per_sample == 0 {
            return Err(inconsistent(format!(
                "its reading has {} band edges (want {}), a segment of {} and {} steps per sample",
                r.bands_hz.len(),
                floors + 1,
                r.segment,
                r.steps_per_sample
            )));
        }
        let increasing = r.bands_hz.windows(2).all(|w| w[0] < w[1]);
        if !increasing || r.bands_hz.iter().any(|f| !(f.is_finite() && *f >= 0.0)) {
            return Err(inconsistent(format!(
                "`reading.bands_hz` {:?}: band edges are increasing frequencies (Hz)",
                r.bands_hz
            )));
        }
        let modes = b.modes()?;
        let (f1, f_max) = (modes[0].frequency_hz, modes[floors - 1].frequency_hz);
        let (rule_steps, rule_warm) = stepping(f1, f_max, WARM_UP_LEAST_DAMPING, b.fs);
        let most_steps = READING_MARGIN * rule_steps as f64;
        if r.steps_per_sample as f64 > most_steps {
            return Err(inconsistent(format!(
                "`reading.steps_per_sample` = {}: a fit of this structure takes {rule_steps}; more than {most_steps} only costs time",
                r.steps_per_sample
            )));
        }
        let most_warm = READING_MARGIN * rule_warm as f64;
        if r.warm_up as f64 > most_warm {
            return Err(inconsistent(format!(
                "`reading.warm_up` = {} samples: 20 time constants of the lowest mode ({f1:.4} Hz) at a damping ratio of {WARM_UP_LEAST_DAMPING} are {rule_warm}; more than {most_warm} only costs time and memory",
                r.warm_up
            )));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::super::predict::tests_support::linear_fit;
    use super::*;
    use hyst_sim::building::StoreyHysteresis;

    fn fit() -> StoreyFit {
        linear_fit([1000.0, 800.0], [4e6, 3e6], [0.05, 0.05], 50.0)
    }

    /// The fit with `edit` applied: its failure's message.
    fn refused(edit: impl FnOnce(&mut StoreyFit)) -> String {
        let mut f = fit();
        edit(&mut f);
        match f.validate() {
            Err(e) => e.to_string(),
            Ok(()) => panic!("not refused"),
        }
    }

    #[test]
    fn a_fit_as_written_holds_together() {
        fit().validate().unwrap();
    }

    #[test]
    fn each_edit_that_breaks_the_fit_is_named() {
        // The panic of issue 77: an element in storey 9 of 2.
        let element = |storey| StoreyHysteresis {
            storey,
            linear_share: 0.6,
            beta: 750.0,
            gamma: 500.0,
            nu: 1.0,
        };
        let msg = refused(|f| {
            f.storey = Some(9);
            f.building.hysteresis = Some(element(9));
        });
        assert!(msg.contains("hysteresis.storey"), "{msg}");
        let msg = refused(|f| f.storey = Some(1));
        assert!(msg.contains("`storey` is Some(1)"), "{msg}");
        // The abort of issue 77: a warm-up of 10¹² samples.
        let msg = refused(|f| f.reading.warm_up = 1_000_000_000_000);
        assert!(msg.contains("reading.warm_up"), "{msg}");
        let msg = refused(|f| f.reading.steps_per_sample = 1 << 20);
        assert!(msg.contains("reading.steps_per_sample"), "{msg}");
        // A structure ten times softer than its parameters say.
        let msg = refused(|f| f.building.stiffnesses[1] /= 10.0);
        assert!(msg.contains("building.stiffnesses[1]"), "{msg}");
        let msg = refused(|f| f.force_densities[0] = -50.0);
        assert!(msg.contains("force_densities[0]"), "{msg}");
        let msg = refused(|f| f.load_floors = vec![1]);
        assert!(msg.contains("load_floors"), "{msg}");
        let msg = refused(|f| f.building.damping_ratios[0] = -0.05);
        assert!(msg.contains("damping_ratios[0]"), "{msg}");
        let msg = refused(|f| f.reading.bands_hz = vec![2.0, 40.0, 12.0]);
        assert!(msg.contains("reading.bands_hz"), "{msg}");
        // A fit that did not reach its records is not a model of them (issue 77).
        let msg = refused(|f| f.agreement.verdict = super::super::FitVerdict::Far);
        assert!(msg.contains("agreement.verdict"), "{msg}");
    }

    #[test]
    fn every_use_of_an_edited_fit_is_refused_before_it_simulates() {
        let mut f = fit();
        f.reading.warm_up = 1_000_000_000_000;
        let forces = vec![vec![0.0; 100]; 2];
        assert!(super::super::simulate_structure(&f, &forces).is_err());
        assert!(super::super::model_records(&f, &[1000], 1).is_err());
        let opts = super::super::PredictionOptions::default();
        assert!(super::super::predict_level(&f, 50.0, 1000, &opts).is_err());
    }
}
