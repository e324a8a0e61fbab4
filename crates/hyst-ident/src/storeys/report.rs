//! The storey fit as text: where the element is (with the runner-up), the parameters with
//! their standard errors, and each level's statistics measured beside the model's.

use std::fmt;

use super::predict::LevelPrediction;
use super::types::{FitVerdict, StoreyFit};
use hyst_sim::building::Reading as Quantity;

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
        location(f, self)?;
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
        if let Some(loudest) = self
            .force_densities
            .iter()
            .copied()
            .max_by(|a, b| a.total_cmp(b))
        {
            for p in &self.predictions {
                prediction(f, p, (p.force_density / loudest).sqrt())?;
            }
        }
        for n in &self.not_predicted {
            // A factor far from 1 in exponent form (1e300, not its 301 digits).
            let factor = if (1e-3..1e4).contains(&n.factor) {
                n.factor.to_string()
            } else {
                format!("{:e}", n.factor)
            };
            writeln!(
                f,
                "Not predicted at {factor} × the loudest level's force: {} (the fit above stands)",
                n.reason
            )?;
        }
        writeln!(
            f,
            "Whitened residual RMS {:.2} (chance exceeds {:.2} 0.1 % of the time when the model holds) after {} iterations{}",
            self.residual_rms,
            self.agreement.chance_rms,
            self.iterations,
            if self.agreement.converged {
                ""
            } else {
                ", the limit, still improving"
            }
        )?;
        verdict(f, self)
    }
}

/// Where the element is (unless the fit did not reach its records), whether there is
/// one, and every candidate's scores.
fn location(f: &mut fmt::Formatter<'_>, fit: &StoreyFit) -> fmt::Result {
    let far = fit.agreement.verdict == FitVerdict::Far;
    let mut ranked = fit.candidates.iter();
    if far {
        writeln!(
            f,
            "Hysteretic element: not located: the fit did not reach its records (see the end)"
        )?;
    } else if let Some(best) = ranked.next() {
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
    if let Some(e) = &fit.element_evidence {
        let verdict = if far {
            "not judged, the fit did not reach its records"
        } else if e.improvement > e.threshold {
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
    for c in &fit.candidates {
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
    Ok(())
}

/// The final fit's agreement with its records, in words.
fn verdict(f: &mut fmt::Formatter<'_>, fit: &StoreyFit) -> fmt::Result {
    let a = &fit.agreement;
    match a.verdict {
        FitVerdict::Explains | FitVerdict::NotJudged => Ok(()),
        FitVerdict::Misses => writeln!(
            f,
            "The model does not explain every level (residual {:.2} beyond chance's {:.2}): every mode is where the records put it, so the location stands on held-out evidence, but the parameters are the nearest of a model that lacks something{}",
            fit.residual_rms,
            a.chance_rms,
            if a.converged {
                ""
            } else {
                " (or a fit stopped before its end)"
            }
        ),
        FitVerdict::Far => {
            let bands: Vec<String> = a
                .far
                .iter()
                .take(3)
                .map(|b| {
                    format!(
                        "level {} mode {} at {:.3} Hz in the model against {:.3} ± {:.3} Hz measured",
                        b.level + 1,
                        b.mode + 1,
                        b.model_hz,
                        b.measured_hz,
                        b.width_hz
                    )
                })
                .collect();
            let more = a.far.len().saturating_sub(3);
            writeln!(
                f,
                "The fit did not reach its records: {}{}; nothing is located from it. Check what the fit takes as known (the masses, the sensors' floors, what they read, the loaded floors)",
                if bands.is_empty() {
                    "its residual is not finite".to_string()
                } else {
                    bands.join("; ")
                },
                if more > 0 {
                    format!(" (and {more} more)")
                } else {
                    String::new()
                }
            )
        }
    }
}

/// A level not recorded: each storey's drift, each mode's centroid and spread with the
/// parameters' standard error and a record's own spread.
fn prediction(f: &mut fmt::Formatter<'_>, p: &LevelPrediction, factor: f64) -> fmt::Result {
    writeln!(
        f,
        "Predicted at {factor:.3} × the loudest level's force (density {:.4e} N²/Hz), records of {} samples:",
        p.force_density, p.samples
    )?;
    let drifts: Vec<String> = p
        .drift_rms
        .iter()
        .enumerate()
        .map(|(s, d)| format!("storey {} {d:.3e}", s + 1))
        .collect();
    writeln!(f, "  RMS drift (m): {}", drifts.join(", "))?;
    let s = &p.statistics;
    let n = s.centroid_hz.len();
    for j in 0..n {
        writeln!(
            f,
            "  mode {}: centroid {:.3} Hz ± {:.3} (a record: ± {:.3}), spread {:.4} ± {:.4} (a record: ± {:.4})",
            j + 1,
            s.centroid_hz[j],
            p.parameters_se[j],
            s.se[j],
            s.spread[j],
            p.parameters_se[n + j],
            s.se[n + j]
        )?;
    }
    Ok(())
}
