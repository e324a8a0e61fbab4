//! The storey fit as text: where the element is (with the runner-up), the parameters with
//! their standard errors, and each level's statistics measured beside the model's.

use std::fmt;

use super::{Quantity, StoreyFit};

/// A location as users count it: storeys from 1 (between the ground and the first floor).
fn place(storey: Option<usize>) -> String {
    storey.map_or("none".to_string(), |s| format!("storey {}", s + 1))
}

fn unit(name: &str) -> &'static str {
    match name.chars().next() {
        Some('k') => "N/m",
        Some('q') => "N²/Hz",
        _ if name == "beta" || name == "gamma" => "1/m^ν",
        _ => "",
    }
}

impl fmt::Display for StoreyFit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let b = &self.building;
        let quantity = match b.reading {
            Quantity::Displacement => "displacements",
            Quantity::Velocity => "velocities",
            Quantity::Acceleration => "accelerations",
        };
        writeln!(
            f,
            "Storey fit: {} floors, {} levels of {} at {} Hz",
            b.masses.len(),
            self.measured.len(),
            quantity,
            b.fs
        )?;
        let mut ranked = self.candidates.iter();
        if let Some(best) = ranked.next() {
            write!(
                f,
                "Hysteretic element: {} (held-out score {:.1})",
                place(best.storey),
                best.held_out
            )?;
            match ranked.next() {
                Some(r) => writeln!(f, "; runner-up {} ({:.1})", place(r.storey), r.held_out)?,
                None => writeln!(f)?,
            }
        }
        if let Some(e) = &self.element_evidence {
            let verdict = if e.improvement > e.threshold {
                "an element"
            } else {
                "no element: chance improves as much more than 1 % of the time"
            };
            writeln!(
                f,
                "Is there one? The best-placed element ({}) improves the fits by {:.1} against {:.1} at 1 % chance: {verdict}",
                place(Some(e.storey)),
                e.improvement,
                e.threshold
            )?;
        }
        writeln!(
            f,
            "Candidates (fitted on the first half of each record, scored on the second; lower is better):"
        )?;
        for c in &self.candidates {
            match &c.failed {
                Some(why) => writeln!(f, "  {:<10} fit failed: {why}", place(c.storey))?,
                None => writeln!(
                    f,
                    "  {:<10} held out {:>9.1}   fitted {:>9.1}",
                    place(c.storey),
                    c.held_out,
                    c.fitted
                )?,
            }
        }
        writeln!(f, "Parameters (± standard error):")?;
        for p in &self.parameters {
            writeln!(
                f,
                "  {:<6} {:>12.5e} ± {:<10.2e} {}",
                p.name,
                p.value,
                p.se,
                unit(&p.name)
            )?;
        }
        writeln!(
            f,
            "Each level, mode by mode: band centroid (Hz) and relative spread, measured ± se | model:"
        )?;
        for (l, (m, s)) in self.measured.iter().zip(&self.simulated).enumerate() {
            write!(f, "  level {}:", l + 1)?;
            let n = m.centroid_hz.len();
            for j in 0..n {
                write!(
                    f,
                    "  [{}] {:.3} ± {:.3} | {:.3}, {:.4} ± {:.4} | {:.4}",
                    j + 1,
                    m.centroid_hz[j],
                    m.se.get(j).copied().unwrap_or(f64::NAN),
                    s.centroid_hz[j],
                    m.spread[j],
                    m.se.get(n + j).copied().unwrap_or(f64::NAN),
                    s.spread[j]
                )?;
            }
            writeln!(f)?;
        }
        writeln!(
            f,
            "Whitened residual RMS {:.2} (about 1 when the model explains every level) after {} iterations",
            self.residual_rms, self.iterations
        )
    }
}
