//! The frequency-response job as one report ([`frf_report`]): the fit over a band, each
//! mode's move with the band, and what the misfit says, printed ([`std::fmt::Display`]) and
//! serialized (feature `serde`).

use std::fmt;

use super::{BandSpread, FrfFit, IdentError, PeriodicRecord, band_spread, modes_from_frf};

/// What [`frf_report`] finds.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct FrfReport {
    /// The outputs' names, in order (they head the shapes in the text).
    pub channels: Vec<String>,
    /// The band fitted (Hz).
    pub band_hz: (f64, f64),
    /// The fit.
    pub fit: FrfFit,
    /// Each mode's largest move when the band is narrowed or widened ([`band_spread`]).
    pub band_spread: Vec<BandSpread>,
}

/// [`modes_from_frf`] of `rec` over `band` with `modes` modes, and [`band_spread`] of its
/// modes; `channels` names the outputs.
pub fn frf_report(
    rec: &PeriodicRecord<'_>,
    channels: &[String],
    band: (f64, f64),
    modes: usize,
) -> Result<FrfReport, IdentError> {
    let fit = modes_from_frf(rec, band, modes)?;
    let band_spread = band_spread(rec, band, modes, &fit);
    Ok(FrfReport {
        channels: channels.to_vec(),
        band_hz: band,
        fit,
        band_spread,
    })
}

impl fmt::Display for FrfReport {
    /// What `hyst frf` prints: the periods and lines used, each mode with its standard
    /// errors and its move with the band, the shapes with several outputs, and the misfit.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let fit = &self.fit;
        writeln!(
            f,
            "{} whole periods, {} excited lines in {}–{} Hz, {} channel(s)",
            fit.periods,
            fit.frequency_hz.len(),
            self.band_hz.0,
            self.band_hz.1,
            self.channels.len()
        )?;
        if fit.modes.is_empty() {
            writeln!(
                f,
                "no stable oscillating pole inside the band: try another band or more modes"
            )?;
        }
        for (m, d) in fit.modes.iter().zip(&self.band_spread) {
            writeln!(
                f,
                "mode {:9.4} ± {:.4} Hz (band {:.4} Hz)  damping ratio {:.5} ± {:.5} (band {:.5}) = {:.3} %",
                m.frequency_hz,
                m.frequency_se_hz,
                d.frequency_hz,
                m.damping_ratio,
                m.damping_se,
                d.damping,
                100.0 * m.damping_ratio
            )?;
        }
        if self.channels.len() > 1 {
            for m in &fit.modes {
                writeln!(
                    f,
                    "shape at {:.4} Hz ({}): {}  MPC {:.4}",
                    m.frequency_hz,
                    self.channels.join(", "),
                    covssi::shape_text(&m.shape, "  "),
                    m.mpc
                )?;
            }
        }
        if !fit.modes.is_empty() {
            writeln!(
                f,
                "± one standard error (the noise); band: the largest move of the mode when the \
                 band is narrowed or widened by a tenth of its width at each end"
            )?;
        }
        // With one period there is no noise estimate and the misfit has unit weights.
        if fit.periods < 2 {
            return writeln!(
                f,
                "one period only: no noise estimate, so no standard errors"
            );
        }
        writeln!(
            f,
            "misfit {:.3}: the weighted residual's mean square per equation, 1 when the fit is at the noise",
            fit.misfit
        )?;
        if fit.misfit > 3.0 {
            writeln!(
                f,
                "note: the response departs from the fitted model by more than its noise (a \
                 nonlinear structure's periodic distortions, or modes near the band left out); \
                 the ± describe the noise alone, and the band's share is given beside them: \
                 compare fits with more modes too"
            )?;
        }
        Ok(())
    }
}
