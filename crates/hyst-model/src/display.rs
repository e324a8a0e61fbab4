//! The oscillator as one line of text, in the schema's key names, each number to six
//! significant digits with its SI unit (`mass 2 kg, damping 10 N·s/m, stiffness 50000 N/m,
//! bouc_wen {alpha 50000 N/m, beta_gamma 800 1/N, …}`); extra terms that are off are not
//! written.

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

/// The unit of βγ and βδ, N^−ν: `1/N` for ν = 1.
fn per_force(nu: f64) -> String {
    if nu == 1.0 {
        "1/N".into()
    } else {
        format!("N^-{}", six_digits(nu))
    }
}

impl fmt::Display for Oscillator {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = six_digits;
        write!(
            f,
            "mass {} kg, damping {} N·s/m, stiffness {} N/m",
            s(self.mass),
            s(self.damping),
            s(self.stiffness)
        )?;
        match self.restoring {
            Restoring::None => {}
            Restoring::BoucWen(b) => {
                let u = per_force(b.nu);
                write!(
                    f,
                    ", bouc_wen {{alpha {} N/m, beta_gamma {} {u}, beta_delta {} {u}, nu {}}}",
                    s(b.alpha),
                    s(b.beta_gamma()),
                    s(b.beta_delta()),
                    s(b.nu)
                )?
            }
            Restoring::Zener(z) => write!(
                f,
                ", zener {{k_inf {} N/m, omega {} rad/s}}",
                s(z.k_inf),
                s(z.omega)
            )?,
        }
        let e = &self.extras;
        for (key, v, unit) in [
            ("cubic_stiffness", e.cubic_stiffness, "N/m³"),
            ("quadratic_stiffness", e.quadratic_stiffness, "N/m²"),
            ("quadratic_damping", e.quadratic_damping, "N·s²/m²"),
            ("offset", e.offset, "N"),
        ] {
            if v != 0.0 {
                write!(f, ", {key} {} {unit}", s(v))?;
            }
        }
        if let Some(c) = e.clearance {
            write!(
                f,
                ", clearance {{stiffness {} N/m, gap {} m}}",
                s(c.stiffness),
                s(c.gap)
            )?;
        }
        if let Some(c) = e.coulomb {
            write!(
                f,
                ", coulomb {{force {} N, smoothing_velocity {} m/s}}",
                s(c.force),
                s(c.smoothing_velocity)
            )?;
        }
        if let Some(sf) = e.surface {
            let terms: Vec<String> = ForceSurface::TERMS
                .iter()
                .zip(sf.coefficients)
                .filter(|(_, c)| *c != 0.0)
                .map(|(t, c)| format!("{t} {} N", s(c)))
                .collect();
            write!(
                f,
                ", surface {{x_scale {} m, v_scale {} m/s, {}}}",
                s(sf.x_scale),
                s(sf.v_scale),
                terms.join(", ")
            )?;
        }
        if let Some(m) = e.second_mass {
            write!(
                f,
                ", second_mass {{mass {} kg, stiffness {} N/m, damping {} N·s/m}}",
                s(m.mass),
                s(m.stiffness),
                s(m.damping)
            )?;
        }
        if let Some(c) = self.chain {
            write!(f, ", chain {{delay {} s, lag {} s}}", s(c.delay), s(c.lag))?;
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
            "mass 2 kg, damping 10 N·s/m, stiffness 50000 N/m, bouc_wen {alpha 50000 N/m, \
             beta_gamma 800 1/N, beta_delta -1100 1/N, nu 1}"
        );
    }
}
