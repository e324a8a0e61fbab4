//! The oscillator as one line of text, in the schema's key names
//! (`mass 2, damping 10, stiffness 50000, bouc_wen {alpha 50000, beta_gamma 800, …}`), each
//! number to six significant digits; extra terms that are off are not written.

use std::fmt;

use crate::{ForceSurface, Oscillator, Restoring};

/// `v` to six significant digits, trailing zeros dropped: fixed-point for magnitudes in
/// [1e-3, 1e6), else in exponent form.
pub fn six_digits(v: f64) -> String {
    let a = v.abs();
    let trim = |t: String| -> String {
        match t.split_once('e') {
            Some((m, e)) if m.contains('.') => {
                format!("{}e{e}", m.trim_end_matches('0').trim_end_matches('.'))
            }
            None if t.contains('.') => t.trim_end_matches('0').trim_end_matches('.').to_string(),
            _ => t,
        }
    };
    if a == 0.0 || !a.is_finite() {
        format!("{v}")
    } else if (1e-3..1e6).contains(&a) {
        let decimals = (5 - a.log10().floor() as i32).max(0) as usize;
        trim(format!("{v:.decimals$}"))
    } else {
        trim(format!("{v:.5e}"))
    }
}

impl fmt::Display for Oscillator {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = six_digits;
        write!(
            f,
            "mass {}, damping {}, stiffness {}",
            s(self.mass),
            s(self.damping),
            s(self.stiffness)
        )?;
        match self.restoring {
            Restoring::None => {}
            Restoring::BoucWen(b) => write!(
                f,
                ", bouc_wen {{alpha {}, beta_gamma {}, beta_delta {}, nu {}}}",
                s(b.alpha),
                s(b.beta_gamma()),
                s(b.beta_delta()),
                s(b.nu)
            )?,
            Restoring::Zener(z) => {
                write!(f, ", zener {{k_inf {}, omega {}}}", s(z.k_inf), s(z.omega))?
            }
        }
        let e = &self.extras;
        for (key, v) in [
            ("cubic_stiffness", e.cubic_stiffness),
            ("quadratic_stiffness", e.quadratic_stiffness),
            ("quadratic_damping", e.quadratic_damping),
            ("offset", e.offset),
        ] {
            if v != 0.0 {
                write!(f, ", {key} {}", s(v))?;
            }
        }
        if let Some(c) = e.clearance {
            write!(
                f,
                ", clearance {{stiffness {}, gap {}}}",
                s(c.stiffness),
                s(c.gap)
            )?;
        }
        if let Some(c) = e.coulomb {
            write!(
                f,
                ", coulomb {{force {}, smoothing_velocity {}}}",
                s(c.force),
                s(c.smoothing_velocity)
            )?;
        }
        if let Some(sf) = e.surface {
            let terms: Vec<String> = ForceSurface::TERMS
                .iter()
                .zip(sf.coefficients)
                .filter(|(_, c)| *c != 0.0)
                .map(|(t, c)| format!("{t} {}", s(c)))
                .collect();
            write!(
                f,
                ", surface {{x_scale {}, v_scale {}, {}}}",
                s(sf.x_scale),
                s(sf.v_scale),
                terms.join(", ")
            )?;
        }
        if let Some(m) = e.second_mass {
            write!(
                f,
                ", second_mass {{mass {}, stiffness {}, damping {}}}",
                s(m.mass),
                s(m.stiffness),
                s(m.damping)
            )?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn six_digits_in_either_form() {
        assert_eq!(six_digits(50006.23), "50006.2");
        assert_eq!(six_digits(0.0123456789), "0.0123457");
        assert_eq!(six_digits(-1099.7), "-1099.7");
        assert_eq!(six_digits(3.2e9), "3.2e9");
        assert_eq!(six_digits(-2.5e-7), "-2.5e-7");
        assert_eq!(six_digits(0.0), "0");
    }

    #[test]
    fn the_benchmark_reads_in_schema_keys() {
        let text = Oscillator::benchmark().to_string();
        assert_eq!(
            text,
            "mass 2, damping 10, stiffness 50000, bouc_wen {alpha 50000, beta_gamma 800, \
             beta_delta -1100, nu 1}"
        );
    }
}
