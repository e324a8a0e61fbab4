//! A storey fit read back (`hyst levels --masses --json`, perhaps edited) checked once,
//! before anything is simulated from it: its structure physical ([`ShearBuilding::validate`]),
//! and every part that repeats another agreeing with it — the element's storey, the loaded
//! floors, the parameters' names and values against the structure's and the force
//! densities, the covariance's size — and its reading within what a fit of that structure
//! could have chosen (the integration step and warm-up bounded, so an edited number cannot
//! ask for terabytes).

use super::error::StoreyError;
use super::model::Layout;
use super::setup::{MAX_NU, WARM_UP_LEAST_DAMPING, stepping};
use super::types::StoreyFit;
use crate::IdentError;
use hyst_sim::building::Reading as Quantity;

/// Relative disagreement allowed between a parameter and the structure's copy of it: the
/// document writes both from one double, and JSON's shortest round-trip representation reads
/// it back exactly, so anything beyond rounding is an edit.
const SAME: f64 = 1e-9;

/// Welch's segment a fit's reading may hold (samples): a fit chooses a few hundred to a few
/// thousand.
const MIN_SEGMENT: usize = 16;
const MAX_SEGMENT: usize = 1 << 24;

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
        if b.sensors.is_empty() {
            return Err(inconsistent(
                "`building.sensors` is empty: a fit's structure reads at least one channel".into(),
            ));
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
                "`force_densities[{l}]` = {q:?}: a force density (N²/Hz) must be positive"
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
                    "parameter `{}` = {:?} but `{field}` = {copy:?}",
                    p.name, p.value
                )));
            }
        }
        if layout.folded {
            let p = values.next();
            if let Some(p) = p.filter(|p| !(p.value.is_finite() && p.value >= 0.0)) {
                return Err(inconsistent(format!(
                    "parameter `b` = {:?}: the folded band is at least 0",
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
                        "parameter `{}` = {:?} but `{field}` = {copy:?}",
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
        self.validate_covariance()
    }

    /// The covariance: all NaN (a singular Jacobian), or symmetric (to rounding) with
    /// finite entries and no negative variance; predictions draw their band from it.
    fn validate_covariance(&self) -> Result<(), IdentError> {
        let c = &self.covariance;
        if c.iter().flatten().all(|v| v.is_nan()) {
            return Ok(());
        }
        for (i, row) in c.iter().enumerate() {
            if !(row[i] >= 0.0 && row[i].is_finite()) {
                return Err(inconsistent(format!(
                    "`covariance[{i}][{i}]` = {:?}: a variance is finite and at least 0",
                    row[i]
                )));
            }
            for (j, &v) in row.iter().enumerate() {
                let scale = (row[i] * c[j][j]).sqrt();
                if !v.is_finite() || (v - c[j][i]).abs() > SAME * scale.max(v.abs()) {
                    return Err(inconsistent(format!(
                        "`covariance[{i}][{j}]` = {v:?} and `covariance[{j}][{i}]` = {:?}: a covariance is finite and symmetric",
                        c[j][i]
                    )));
                }
            }
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
        let nyquist = b.fs / 2.0;
        if !increasing || r.bands_hz.iter().any(|f| !(*f > 0.0 && *f <= nyquist)) {
            return Err(inconsistent(format!(
                "`reading.bands_hz` {:?}: band edges are increasing frequencies (Hz) above 0 and at most Nyquist, {nyquist} Hz at `building.fs` {} Hz",
                r.bands_hz, b.fs
            )));
        }
        if !(MIN_SEGMENT..=MAX_SEGMENT).contains(&r.segment) {
            return Err(inconsistent(format!(
                "`reading.segment` = {}: Welch's segment is {MIN_SEGMENT} to {MAX_SEGMENT} samples",
                r.segment
            )));
        }
        for (field, share) in [("building.noise", b.noise), ("building.drift", b.drift)] {
            if share > 1.0 {
                return Err(inconsistent(format!(
                    "`{field}` = {share:?}: a share of each channel's deviation, at most 1 (a fit writes 0)"
                )));
            }
        }
        if let Some(h) = &b.hysteresis
            && h.nu > MAX_NU
        {
            return Err(inconsistent(format!(
                "`building.hysteresis.nu` = {:?}: the Bouc-Wen exponent is at most {MAX_NU} (the loop is a step already)",
                h.nu
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
        // A structure that reads nothing simulated as a file of no channel (issue 77).
        let msg = refused(|f| f.building.sensors.clear());
        assert!(msg.contains("building.sensors"), "{msg}");
        // A band past Nyquist, a covariance with a negative variance.
        let msg = refused(|f| f.reading.bands_hz[2] = 1e308);
        assert!(msg.contains("reading.bands_hz"), "{msg}");
        let msg = refused(|f| f.covariance[1][1] = -1.0);
        assert!(msg.contains("covariance[1][1]"), "{msg}");
        // A fit that did not reach its records is not a model of them (issue 77).
        let msg = refused(|f| f.agreement.verdict = super::super::FitVerdict::Far);
        assert!(msg.contains("agreement.verdict"), "{msg}");
    }

    /// Every place in a JSON value (each object's fields, each array's items), as paths.
    fn places(v: &serde_json::Value, at: Vec<String>, out: &mut Vec<Vec<String>>) {
        match v {
            serde_json::Value::Object(m) => {
                for (k, x) in m {
                    let mut p = at.clone();
                    p.push(k.clone());
                    out.push(p.clone());
                    places(x, p, out);
                }
            }
            serde_json::Value::Array(a) => {
                for (i, x) in a.iter().enumerate() {
                    let mut p = at.clone();
                    p.push(i.to_string());
                    out.push(p.clone());
                    places(x, p, out);
                }
            }
            _ => {}
        }
    }

    /// The value at `path` in `v`, and its parent's key.
    fn at<'a>(v: &'a mut serde_json::Value, path: &[String]) -> &'a mut serde_json::Value {
        path.iter().fold(v, |v, k| match v {
            serde_json::Value::Array(a) => &mut a[k.parse::<usize>().unwrap()],
            v => &mut v[k.as_str()],
        })
    }

    /// The fuzz of issue 77 over the structure's document: every field of a linear and of
    /// an element fit given each hostile value, removed, or joined by an unknown field; each
    /// document read (`deny_unknown_fields`), checked, and, where it passes, simulated under
    /// a force and as the model's own records. Every case ends in an answer or an error:
    /// none panics (an abort would end the test run).
    #[test]
    fn a_mutated_document_is_refused_or_simulated_never_a_panic() {
        use serde_json::json;
        let started = std::time::Instant::now();
        let element = super::super::predict::tests_support::two_floor_fit(
            [1000.0, 800.0],
            &[4e6, 3e6, 0.05, 0.05, 50.0, 0.6, 750.0, 500.0],
            Some(1),
        );
        element.validate().unwrap();
        let hostile = [
            json!(0),
            json!(-1),
            json!(1e308),
            json!(-1e308),
            json!(1e-300),
            json!(9),
            json!(u64::MAX),
            json!(null),
            json!("x"),
            json!([]),
            json!({}),
            json!(true),
            json!(0.5),
        ];
        let (mut cases, mut read, mut simulated) = (0, 0, 0);
        let mut panics = Vec::new();
        for doc in [fit(), element] {
            let base = serde_json::to_value(&doc).unwrap();
            let mut paths = Vec::new();
            places(&base, Vec::new(), &mut paths);
            let mut docs: Vec<(String, serde_json::Value)> = Vec::new();
            for p in &paths {
                for h in &hostile {
                    let mut v = base.clone();
                    *at(&mut v, p) = h.clone();
                    docs.push((format!("{} = {h}", p.join(".")), v));
                }
                let (last, parent) = p.split_last().unwrap();
                let mut v = base.clone();
                if let serde_json::Value::Object(m) = at(&mut v, parent) {
                    m.remove(last);
                    docs.push((format!("{} removed", p.join(".")), v.clone()));
                    if let serde_json::Value::Object(m) = at(&mut v, parent) {
                        m.insert("unknown".into(), json!(1));
                    }
                    docs.push((format!("{} removed, `unknown` added", p.join(".")), v));
                }
            }
            for (what, v) in docs {
                cases += 1;
                let run = std::panic::catch_unwind(|| {
                    let Ok(f) = serde_json::from_value::<StoreyFit>(v) else {
                        return (false, false);
                    };
                    if f.validate().is_err() {
                        return (true, false);
                    }
                    let forces = vec![vec![10.0; 300]; f.load_floors.len()];
                    let _ = super::super::simulate_structure(&f, &forces);
                    let _ = super::super::model_records(&f, &[2000], 1);
                    (true, true)
                });
                match run {
                    Ok((r, s)) => {
                        read += usize::from(r);
                        simulated += usize::from(s);
                    }
                    Err(_) => panics.push(what),
                }
            }
        }
        println!(
            "{cases} mutated documents: {read} read, {simulated} passed the check and were simulated, {} panicked, in {:.1} s",
            panics.len(),
            started.elapsed().as_secs_f64()
        );
        assert!(panics.is_empty(), "{panics:#?}");
        // The fuzz reached the simulation (values within range) and the check (most not).
        assert!(cases > 1000 && simulated > 10 && simulated < cases / 2);
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
