//! The model the refinement fits: the record's spectra and θ's layout (each mode's pole,
//! each real pole, each channel's numerator), and what a fit and an evaluation give. Its
//! jobs, one file each: the likelihood ([`likelihood`]), the information's blocks
//! ([`information`]), starting values ([`starts`]), the scoring iteration and a mode's
//! evidence ([`scoring`]), and fitting from starts ([`fitting`]).

use crate::error::SsiError;
use crate::linalg::{C64, Dense};
use crate::refine::results::MisfitCounts;
use crate::refine::spectra::Spectra;
use std::sync::Arc;

mod fitting;
mod information;
mod likelihood;
pub(super) mod scoring;
mod starts;

/// The record's spectra and the model's shape: how many real poles it has.
pub(super) struct Model {
    /// The record as the likelihood sees it.
    pub(super) sp: Arc<Spectra>,
    pub(super) fs: f64,
    /// Real poles of the model besides its modes: θ holds their ln ρ (λ = −ρ) after the
    /// modes' parameters, and each numerator's degree is 2m + `reals`.
    pub(super) reals: usize,
}

/// A fitted model.
pub(super) struct Fit {
    pub(super) theta: Vec<f64>,
    pub(super) lambdas: Vec<C64>,
    /// The real poles λ = −ρ, after the modes in θ.
    pub(super) reals: Vec<f64>,
    pub(super) l: f64,
    pub(super) fisher: Dense,
    pub(super) iterations: usize,
}

/// What [`Model::eval`] computes besides L.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum What {
    /// L alone.
    Value,
    /// The score U = −∇L and the Fisher information F.
    Fisher,
    /// U and F of the numerators alone (the poles held): the poles' entries of U and their
    /// rows and columns of F are zero.
    FisherNumerators,
    /// U, and the covariance J of the score in place of F.
    Sandwich,
    /// The ratios I/S of every channel and frequency.
    #[cfg(test)]
    Ratios,
    /// The misfit of those ratios, counted without keeping them.
    Misfit,
}

/// L and what was asked for besides (empty otherwise).
pub(super) struct Eval {
    pub(super) l: f64,
    pub(super) u: Vec<f64>,
    pub(super) f: Dense,
    pub(super) ratios: Vec<f64>,
    /// The misfit's counts of the ratios (with [`What::Misfit`]).
    pub(super) misfit: Option<MisfitCounts>,
}

impl Eval {
    /// Nothing summed yet, with room for the score and Fisher information of `np` parameters
    /// (0 when they are not asked for).
    pub(super) fn zero(np: usize) -> Self {
        Eval {
            l: 0.0,
            u: vec![0.0; np],
            f: Dense::zeros(np, np),
            ratios: Vec::new(),
            misfit: None,
        }
    }

    /// The sums over two sets of frequencies, as one.
    pub(super) fn merge(mut self, other: Self) -> Self {
        self.l += other.l;
        self.u.iter_mut().zip(&other.u).for_each(|(x, y)| *x += y);
        self.f
            .data
            .iter_mut()
            .zip(&other.f.data)
            .for_each(|(x, y)| *x += y);
        self.ratios.extend(other.ratios);
        match (&mut self.misfit, other.misfit) {
            (Some(a), Some(b)) => a.merge(&b),
            (None, b) => self.misfit = b,
            _ => {}
        }
        self
    }
}

/// Bins per parallel chunk of an evaluation.
pub(super) const CHUNK: usize = 128;

impl Model {
    /// The model of the record `sp` sampled at `fs` Hz, without real poles.
    pub(super) fn new(sp: Spectra, fs: f64) -> Self {
        Model {
            sp: Arc::new(sp),
            fs,
            reals: 0,
        }
    }

    /// The exact Whittle likelihood's model of the channels `y` less `means` (every
    /// frequency its own bin).
    #[cfg(test)]
    pub(super) fn unbinned(y: &[&[f64]], means: &[f64], fs: f64) -> Self {
        Self::new(Spectra::unbinned(y, means), fs)
    }

    /// This record's model with `r` real poles.
    pub(super) fn with_reals(&self, r: usize) -> Self {
        Model {
            sp: Arc::clone(&self.sp),
            fs: self.fs,
            reals: r,
        }
    }

    /// Channels.
    pub(super) fn l(&self) -> usize {
        self.sp.l
    }

    /// Number of pole parameters of a model of `m` modes: 2m, and one per real pole.
    pub(super) fn poles(&self, m: usize) -> usize {
        2 * m + self.reals
    }

    /// Frequencies of the likelihood, K.
    pub(super) fn k(&self) -> usize {
        self.sp.k()
    }
}

/// Global index of local parameter `t` of a channel block starting at `off`: the first `p`
/// are the shared pole parameters.
pub(in crate::refine) fn global(t: usize, p: usize, off: usize) -> usize {
    if t < p { t } else { off + t - p }
}

/// The better (lower L) of two fits of one model from different starts, `a` on a tie; if one
/// failed, the other; if both, `a`'s error.
pub(in crate::refine) fn better(
    a: Result<Fit, SsiError>,
    b: Result<Fit, SsiError>,
) -> Result<Fit, SsiError> {
    match (a, b) {
        (Ok(a), Ok(b)) => Ok(if a.l <= b.l { a } else { b }),
        (Ok(a), Err(_)) | (Err(_), Ok(a)) => Ok(a),
        (Err(e), Err(_)) => Err(e),
    }
}
