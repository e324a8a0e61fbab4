//! Whether an effect the held-out test would add is a finding at its fitted size: a term that
//! pays on the test rows can still be what the record's acquisition does (a decimation filter,
//! coloured noise) absorbed by the nearest shape the list has. A second mass of a few grams
//! on a 2 kg structure, or a second mode where the force puts no energy, is such a term.

use hyst_model::Oscillator;

use super::Effect;

/// A second mass below this share of the main mass is not a finding: the project's second
/// modes to find are 5–10 % of the main mass (`cargo xtask loop-battery`,
/// `crates/hyst-ident/tests/integration/refine_synthetic.rs`); the spurious ones that took up a decimation filter's or a
/// coloured noise's share were 0.1–0.3 % (issue 45).
pub const MIN_SECOND_MASS_SHARE: f64 = 0.01;

/// Why `effect`, as fitted in `model`, is not a finding (`band`: the input's,
/// [`super::surface::input_band`], Hz), or
/// `None` when it is.
pub(super) fn implausible(effect: Effect, model: &Oscillator, band: (f64, f64)) -> Option<String> {
    match effect {
        Effect::SecondMode => {
            let s = model.extras.second_mass?;
            let share = s.mass / model.mass;
            let f2 = (s.stiffness / s.mass).sqrt() / (2.0 * std::f64::consts::PI);
            if share < MIN_SECOND_MASS_SHARE {
                Some(format!(
                    "not a finding: its second mass is {:.3} kg, {:.2} % of the first (at least {} % is one)",
                    s.mass,
                    100.0 * share,
                    100.0 * MIN_SECOND_MASS_SHARE
                ))
            } else if !(band.0..=band.1).contains(&f2) {
                Some(format!(
                    "not a finding: its mode at {f2:.1} Hz lies outside the band the force excites ({:.1}–{:.1} Hz)",
                    band.0, band.1
                ))
            } else {
                None
            }
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use hyst_model::SecondMass;

    #[test]
    fn the_excited_band_is_the_inputs() {
        let u = hyst_sim::excitation::band_limited_noise(32768, 750.0, 5.0, 150.0, 1.0, 3).unwrap();
        let (lo, hi) = super::super::surface::input_band(&u, 750.0);
        // Welch bins of 750/512 = 1.46 Hz.
        assert!(
            (lo - 5.0).abs() < 3.0 && (hi - 150.0).abs() < 3.0,
            "{lo}–{hi}"
        );
    }

    #[test]
    fn a_tiny_or_unexcited_second_mass_is_no_finding() {
        let with = |mass: f64, f: f64| {
            let mut o = Oscillator::benchmark();
            let w = 2.0 * std::f64::consts::PI * f;
            o.extras.second_mass = Some(SecondMass {
                mass,
                stiffness: mass * w * w,
                damping: 0.0,
            });
            o
        };
        let band = (5.0, 150.0);
        let e = Effect::SecondMode;
        assert_eq!(implausible(e, &with(0.1, 60.0), band), None);
        let tiny = implausible(e, &with(0.005, 30.0), band).unwrap();
        assert!(tiny.contains("0.25 % of the first"), "{tiny}");
        let outside = implausible(e, &with(0.1, 300.0), band).unwrap();
        assert!(outside.contains("300.0 Hz lies outside"), "{outside}");
        assert_eq!(
            implausible(Effect::CubicStiffness, &with(0.001, 1.0), band),
            None
        );
    }
}
