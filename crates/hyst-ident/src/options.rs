//! The pipeline's settings.

use crate::flatness;
use covssi::StabilityCriteria;
use hyst_linearize::Amplitude;

/// Where the viscous damping c of the Zener and Bouc-Wen models comes from.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum DampingGuess {
    /// From the record, with no guess, when it follows the stationary model (a random
    /// excitation) and SSI's pair and real pole were refined: the Zener oscillator fitted to
    /// the record's spectrum ([`zener_spectrum`](crate::zener_spectrum), step 3b), which assumes a force white over
    /// the band. Otherwise, or when that fit does not hold (see [`fit_zener_spectrum`](crate::fit_zener_spectrum)), as
    /// [`DampingGuess::LowDampingCluster`] (a note says why).
    #[default]
    ZenerSpectrum,
    /// The paper's choice: a cluster of lightly damped poles near the dominant frequency,
    /// $c = -2m\operatorname{Re}\lambda$; if there is none, c = 0.
    LowDampingCluster,
    /// A given value (N s/m).
    Value(f64),
}

/// How the Zener element maps to Bouc-Wen parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum Linearization {
    /// Eqs. (37)–(38) as printed.
    Paper,
    /// α from eq. (37), (βγ, βδ) by exact inversion of the numerical describing function.
    #[default]
    Harmonic,
}

/// Options of the pipeline.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
pub struct IdentOptions {
    /// Mass m (kg), assumed known.
    pub mass: f64,
    /// Target samples per period of the dominant mode after decimation (default 10).
    pub samples_per_period: f64,
    /// The block rows of the Toeplitz matrix span this many periods of the dominant mode
    /// (default 10, as the paper's Section 4).
    pub periods: f64,
    /// Largest model order (default 20).
    pub max_order: usize,
    /// Stabilization thresholds (default: the paper's 0.05, 0.05, real 1.5).
    pub criteria: StabilityCriteria,
    /// Source of c.
    pub damping_guess: DampingGuess,
    /// Mapping to Bouc-Wen.
    pub linearization: Linearization,
    /// Amplitude A for the mapping (default σₓ).
    pub amplitude: Amplitude,
    /// The excitation's design, when known: then the Bouc-Wen model is fitted by flatness of
    /// its implied input ([`flatness`]), starting from the mapped one (default: unknown).
    pub excitation: Option<flatness::ExcitationBand>,
    /// [`identify_and_validate`](crate::identify_and_validate) also profiles what one record leaves free: the Bouc-Wen
    /// models that reproduce the record's statistics along the ratio βδ/βγ
    /// ([`levels::beta_delta_profile`](crate::levels::beta_delta_profile); about a minute). Default false.
    pub profile: bool,
}

impl Default for IdentOptions {
    fn default() -> Self {
        IdentOptions {
            mass: 2.0,
            samples_per_period: 10.0,
            periods: 10.0,
            max_order: 20,
            criteria: StabilityCriteria {
                frequency: 0.05,
                damping: 0.05,
                mac: 0.02,
                real: 1.5,
            },
            damping_guess: DampingGuess::default(),
            linearization: Linearization::default(),
            amplitude: Amplitude::SigmaX,
            excitation: None,
            profile: false,
        }
    }
}
