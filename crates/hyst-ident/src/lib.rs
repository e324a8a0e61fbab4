//! The output-only identification pipeline of the paper (Sections 3–4): from a measured
//! displacement record alone to linear, Zener and Bouc-Wen models of a single-degree-of-freedom
//! oscillator of known mass.
//!
//! Each step is a function of its own; [`identify`] runs them all:
//!
//! 1. [`prepare`]: remove the mean, find the dominant frequency from the spectrum, decimate to
//!    about [`IdentOptions::samples_per_period`] samples per period of it, report skewness and
//!    kurtosis (a stationary Gaussian-like response has 0 and 3).
//! 2. [`run_ssi`]: [`covssi`] with block rows spanning [`IdentOptions::periods`] periods of the
//!    dominant mode and the paper's thresholds (Δω = Δζ = 0.05, real-pole criterion 1.5).
//! 3. [`select_poles`]: the oscillating pair (the stable cluster nearest the dominant
//!    frequency, most members first, kept only when the record's likelihood supports it:
//!    its evidence in [`covssi::refine()`] at least the BIC penalty of a mode), the real
//!    pole (the largest stable real cluster, else the median of all stable real poles), and
//!    the viscous damping guess c ([`DampingGuess`]). When the record follows the stationary
//!    model (a random excitation), the pair and the real pole are then refined together by
//!    maximum likelihood ([`covssi::refine_with_real_poles`]) and used in place of SSI's.
//!
//!    Step 3b, [`fit_zener_spectrum`], when they were: the Zener oscillator fitted to the
//!    record's spectrum by maximum likelihood ([`zener_spectrum`]). The spectrum's zero at
//!    $-\Omega$ is the fourth relation the poles lack, so c comes from the record, with a
//!    standard error, instead of the guess (white force assumed; [`DampingGuess`]).
//! 4. [`build_models`]: linear $k = m|\lambda|^2$, $c = -2m\operatorname{Re}\lambda$; Zener
//!    $(k, k_\infty, \Omega)$ by coefficient matching of eq. (32); Bouc-Wen with α from eq. (37)
//!    and (βγ, βδ) from eq. (38) ([`Linearization::Paper`]) or from the exact inversion of the
//!    describing function at $A$ ([`Linearization::Harmonic`]).
//!
//!    Step 4b, [`fit_flatness`], when the excitation's band is known
//!    ([`IdentOptions::excitation`]): the Bouc-Wen parameters that make the implied input flat
//!    over the band ([`flatness`]); this replaces the mapped Bouc-Wen model.
//! 5. [`validate`]: simulate a model with a measured input and report
//!    $\varepsilon = \text{RMS}(\hat y - y)/(\max y - \min y)$ (eq. 39) and the RMS.
//!
//! The whole job on one record, with validation records to choose the Bouc-Wen candidate
//! by, is [`identify_and_validate`]: one [`IdentReport`] that prints as text and serializes.
//!
//! With the input too, [`frf`] fits the modes of a periodic record's frequency response: the
//! input-output second opinion on what output-only SSI reports.
//!
//! Across records: [`levels::bouc_wen_from_levels`] takes the step-3b fits of records at two
//! or more force levels and gives one Bouc-Wen model for all, through the statistical
//! linearization of [`hyst_linearize::statistical`] ([`levels::bouc_wen_and_exponent_from_levels`]
//! its exponent ν too, from three or more). For a shear structure of several floors,
//! [`storeys::fit_storeys`] locates the storey holding a Bouc-Wen element (or none) from
//! records at several levels and fits the structure by simulation;
//! [`storeys::predict_level`] predicts a level not recorded.

#![warn(missing_docs)]

mod error;
mod fft;
#[cfg(feature = "serde")]
mod nullable;
mod numerics;
mod options;
pub mod periodic;
// The paper's pipeline, one step per module (prepare, poles, models, validation, the
// spectral and flatness fits), and the whole job on one record (`report`).
mod pipeline;
// The jobs built on it, one folder each; with the input too, `frf` fits the modes of a
// periodic record's frequency response.
pub mod amplitude;
pub mod frf;
pub mod levels;
pub mod residual;
pub mod storeys;

pub use covssi::{Complex64, Progress};
pub use error::IdentError;
pub use numerics::welch_psd;
pub(crate) use numerics::{LmSchedule, lm_step, lm_step_with, normal_equations, solve};
pub use options::{DampingGuess, IdentOptions, Linearization};
pub use pipeline::{
    BoucWenCandidate, BoucWenRoute, IdentReport, Identification, Models, Prepared, ProfileRow,
    Score, SelectedPoles, Validation, ValidationRecord, ValidationRow, best_by_validation,
    build_models, epsilon, fit_flatness, fit_zener_spectrum, flatness, floor, identify,
    identify_and_validate, prepare, run_ssi, select_poles, simulate_model, validate, validate_all,
    zener_spectrum,
};

#[cfg(test)]
mod tests {
    use super::*;

    /// Welch's PSD by FFT against the defining sums, and its level: a white sequence of
    /// variance 1 at 100 Hz has a one-sided density of 2/100 per Hz.
    #[test]
    fn welch_psd_is_the_windowed_dft() {
        let y = hyst_sim::excitation::white_noise(3000, 1.0, 5).unwrap();
        let (f, s) = welch_psd(&y, 100.0, 256);
        assert_eq!(f.len(), 129);
        let win: Vec<f64> = (0..256)
            .map(|i| 0.5 - 0.5 * (2.0 * std::f64::consts::PI * i as f64 / 256.0).cos())
            .collect();
        let u: f64 = win.iter().map(|w| w * w).sum();
        for b in [0usize, 1, 37, 128] {
            let w = 2.0 * std::f64::consts::PI * b as f64 / 256.0;
            let (mut total, mut count, mut start) = (0.0, 0, 0);
            while start + 256 <= y.len() {
                let (mut re, mut im) = (0.0, 0.0);
                for k in 0..256 {
                    re += y[start + k] * win[k] * (w * k as f64).cos();
                    im -= y[start + k] * win[k] * (w * k as f64).sin();
                }
                total += re * re + im * im;
                count += 1;
                start += 128;
            }
            let direct = 2.0 * total / (100.0 * u * count as f64);
            // The FFT against the sums: rounding, 1e-13 of the value or so.
            approx::assert_relative_eq!(s[b], direct, max_relative = 1e-10);
        }
        // 22 half-overlapping segments × 127 bins (about 1500 independent exponential values
        // after the overlap): the mean's standard error is about 3 %, and 10 % is three of them.
        let mean = s[1..128].iter().sum::<f64>() / 127.0;
        approx::assert_relative_eq!(mean, 0.02, max_relative = 0.1);
    }
}
