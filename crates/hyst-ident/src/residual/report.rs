//! The loop on one record as one report ([`refine_report`]): the rows it used, the
//! [`Refinement`] and the time taken, printed as text ([`std::fmt::Display`]) and
//! serialized (feature `serde`) with the refinement's fields at the top level.

use std::fmt;

use hyst_model::display::six_digits;

use super::noise::NoiseMethod;
use super::{
    Effect, Evidence, IdentError, ModelClass, ProgressFn, Record, Refinement, SE_BLOCK_ROWS, drift,
    refine_record_with,
};

/// What [`refine_report`] finds.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct RefineReport {
    /// The estimation rows (first, one past the last).
    pub estimate_rows: (usize, usize),
    /// The test rows, each (first, one past the last).
    pub test_rows: Vec<(usize, usize)>,
    /// Whether the mass was fitted (no mass given).
    pub mass_fitted: bool,
    /// The loop's result.
    #[cfg_attr(feature = "serde", serde(flatten))]
    pub refinement: Refinement,
    /// Wall time (s).
    pub seconds: f64,
}

/// The rows a record of `n` samples is split into when none are given: the first 75 %
/// estimates, the last 25 % tests.
pub fn default_rows(n: usize) -> ((usize, usize), Vec<(usize, usize)>) {
    ((0, 3 * n / 4), vec![(3 * n / 4, n)])
}

/// [`refine_record_with`] on `rec`, as a report with its rows and time.
pub fn refine_report(
    rec: &Record<'_>,
    mass: Option<f64>,
    start: ModelClass,
    estimate: (usize, usize),
    tests: &[(usize, usize)],
    progress: ProgressFn<'_>,
) -> Result<RefineReport, IdentError> {
    let t0 = std::time::Instant::now();
    let refinement = refine_record_with(rec, mass, start, estimate, tests, progress)?;
    Ok(RefineReport {
        estimate_rows: estimate,
        test_rows: tests.to_vec(),
        mass_fitted: mass.is_none(),
        refinement,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

fn pct(v: f64) -> String {
    format!("{:.3} %", 100.0 * v)
}

/// One candidate's line of a step: its ΔBIC, variance explained, held-out gain, ν for the
/// exponent's candidate, and why it was rejected.
fn evidence_line(e: &Evidence) -> String {
    let nu = match (e.effect, e.model.map(|m| m.restoring)) {
        (Effect::HysteresisExponent, Some(hyst_model::Restoring::BoucWen(b))) => {
            format!("  (ν = {:.3})", b.nu)
        }
        _ => String::new(),
    };
    let held = e.held_out.map_or(String::new(), |g| {
        format!(
            "  held out {:+.2} % (p {:.1e})",
            -100.0 * g.relative_gain(),
            g.p_value
        )
    });
    format!(
        "    {:<19} dBIC {:>12.1}  variance explained {:>7.3}{held}{nu}{}",
        e.effect.name(),
        e.delta_bic,
        e.variance_explained,
        e.rejected
            .as_ref()
            .map_or(String::new(), |w| format!("  ({w})"))
    )
}

impl RefineReport {
    fn fmt_steps(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for s in &self.refinement.steps {
            let name = s.effect.map_or("none", |e| e.name());
            writeln!(
                f,
                "step: {name}  (residual peak {:.2} Hz, share above 1.5x resonance {:.2})",
                s.spectrum.peak_hz, s.spectrum.above_resonance
            )?;
            if let Some(t) = &s.trace {
                writeln!(f, "    trace: {}", t.signature)?;
            }
            for e in &s.evidence {
                writeln!(f, "{}", evidence_line(e))?;
            }
            for ((rows, b), af) in self.test_rows.iter().zip(&s.before).zip(&s.after) {
                writeln!(
                    f,
                    "    test rows {}:{}  ε {} -> {}  RMS error {:.4e} -> {:.4e} (output units, m)",
                    rows.0,
                    rows.1,
                    pct(b.epsilon),
                    pct(af.epsilon),
                    b.rms,
                    af.rms
                )?;
            }
        }
        if let Some(why) = &self.refinement.stopped {
            writeln!(f, "step: none, not traced: {why}")?;
        }
        Ok(())
    }

    fn fmt_noise(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let r = &self.refinement;
        match &r.noise {
            Ok(nl) => {
                let how = match nl.method {
                    NoiseMethod::PeriodToPeriod { period, pairs } => format!(
                        "from the output one period ({period} samples) apart, {pairs} pairs"
                    ),
                    NoiseMethod::OutOfBand { share } => format!(
                        "from the residual's spectrum where the input has no power ({:.0} % of \
                         the band; white noise assumed)",
                        100.0 * share
                    ),
                    NoiseMethod::Residual { out_of_band } => format!(
                        "the residual itself: above the level out of band ({out_of_band:.4e}) but \
                         no function of (x, dx/dt), of time or of the input, so coloured noise"
                    ),
                };
                let eps: Vec<String> = r.noise_epsilon.iter().map(|e| pct(*e)).collect();
                writeln!(
                    f,
                    "noise level: std {:.4e} (output units, m; ε {} on the test rows), {how}",
                    nl.std,
                    eps.join(", ")
                )?;
            }
            Err(why) => writeln!(f, "noise level: unknown ({why})")?,
        }
        if r.nonstationary {
            writeln!(
                f,
                "nonstationary: the halves of the estimation rows differ:"
            )?;
            for h in drift::drifting(&r.halves) {
                writeln!(
                    f,
                    "    {} {} ± {:.2e} then {} ± {:.2e} (z = {:.1})",
                    h.name,
                    six_digits(h.first.0),
                    h.first.1,
                    six_digits(h.second.0),
                    h.second.1,
                    h.z
                )?;
            }
        }
        match &r.unexplained {
            Some(u) => writeln!(
                f,
                "unexplained: the held-out residual is {:.2} × the noise level; the missing force: {}",
                u.residual_to_noise, u.signature
            ),
            None if r.noise.is_ok() => writeln!(f, "the held-out residual is at the noise level"),
            None => Ok(()),
        }
    }
}

impl fmt::Display for RefineReport {
    /// What `hyst refine` prints: the start, the baseline, each step with its trace, the
    /// candidates' evidence and the held-out errors, the final model with its standard
    /// errors, the noise level, a drift, what is left unexplained, and the time.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let r = &self.refinement;
        writeln!(
            f,
            "start: {} (asked for {})",
            r.start.used.name(),
            r.start.requested.name()
        )?;
        for note in &r.start.notes {
            writeln!(f, "  {note}")?;
        }
        if self.mass_fitted {
            writeln!(
                f,
                "  no mass given: the mass is fitted ({:.6e} kg); the missing force is traced with it",
                r.model.mass
            )?;
        }
        writeln!(
            f,
            "baseline (output-only start, refined with the input): {}",
            r.baseline
        )?;
        self.fmt_steps(f)?;
        writeln!(f, "final model: {}", r.model)?;
        if let Some(c) = r.model.chain.filter(|c| !c.is_identity()) {
            writeln!(
                f,
                "  measurement chain: the recorded output lags the structure's by a delay of {} s \
                 and a sensor lag of {} s; this is the acquisition, not the structure",
                six_digits(c.delay),
                six_digits(c.lag)
            )?;
        }
        if !r.estimates.is_empty() {
            let list: Vec<String> = r
                .estimates
                .iter()
                .map(|e| format!("{} {} ± {:.2e}", e.name, six_digits(e.value), e.se))
                .collect();
            writeln!(
                f,
                "  with standard errors (output error, blocks of {SE_BLOCK_ROWS} rows, coloured residual allowed): {}",
                list.join(", ")
            )?;
        }
        self.fmt_noise(f)?;
        writeln!(f, "time: {:.1} s", self.seconds)
    }
}
