//! Fitting θ by Levenberg–Marquardt: from SSI's poles, with a pole added or removed, with
//! some held.

use crate::error::SsiError;
use crate::linalg::C64;
use crate::refine::model::better;
use crate::refine::model::scoring::{Evidence, scoring};
use crate::refine::model::{Fit, Model, What};
use crate::refine::options::RefineOptions;

impl Model {
    /// Fit a model with the given starting poles (numerators from [`Self::start_numerator`]);
    /// `tol` is the convergence threshold on L. With `hold_poles` only the numerators move.
    pub(in crate::refine) fn fit(
        &self,
        start: &[C64],
        opts: &RefineOptions,
        tol: f64,
        hold_poles: bool,
    ) -> Result<Fit, SsiError> {
        self.fit_from(self.start(start)?, start.len(), opts, tol, hold_poles, None)
    }

    /// `prev` with the mode `new` added, refitted from two starts, fresh numerators and
    /// [`Self::nested_start`]; the better fit.
    pub(in crate::refine) fn fit_with(
        &self,
        prev: &Fit,
        new: C64,
        penalty: Option<f64>,
        opts: &RefineOptions,
    ) -> Result<Fit, SsiError> {
        let mut trial = prev.lambdas.clone();
        trial.push(new);
        let ev = Evidence::adding(prev.l, penalty);
        let (tol, m) = (opts.tolerance, trial.len());
        let fresh = self
            .start_with(&trial, &prev.reals)
            .and_then(|th| self.fit_from(th, m, opts, tol, false, ev));
        let nested = self.nested_start(prev, new).map_or(
            Err(SsiError::Refinement {
                reason: "the new pole is at or above the Nyquist frequency",
            }),
            |th| self.fit_from(th, m, opts, tol, false, ev),
        );
        better(fresh, nested)
    }

    /// `full` without one of its poles, as this model (as many real poles as `reals`) with
    /// the modes `pairs` and the real poles `reals`: the rise of L when the poles are held and
    /// the numerators refitted (the removed pole's evidence, to about 10⁻⁵ of itself), and
    /// the fit with everything let move from there. That fit stops once L is within `penalty`
    /// of `full`'s (the pole goes whatever further iterations would find) or once that is out
    /// of reach; with no penalty (no selection) at convergence. With `hold_modes` the modes
    /// stay held in that fit too (for a real pole removed: the other real poles may take its
    /// place, but a mode left free would turn into a pole pair damped near ζ = 1 that mimics
    /// it, at twice its parameters).
    pub(in crate::refine) fn without(
        &self,
        full: &Fit,
        pairs: &[C64],
        reals: &[f64],
        penalty: Option<f64>,
        hold_modes: bool,
        opts: &RefineOptions,
    ) -> Result<(f64, Fit), SsiError> {
        // These fits need L only to well within the penalty, and a model missing one of its
        // real modes descends slowly while its poles wander (hundreds of iterations, seconds
        // each fit) without coming near the penalty: 40 iterations decide, and a fit stops
        // sooner once its gains are small against the rise or the penalty is out of reach
        // ([`Evidence`]).
        let loose = 1e-3;
        let eopts = &RefineOptions {
            max_iterations: opts.max_iterations.min(40),
            ..opts.clone()
        };
        let report = Evidence {
            full: full.l,
            drop_below: f64::NEG_INFINITY,
            stop_below: true,
        };
        let m = pairs.len();
        let th = self.start_with(pairs, reals)?;
        let held = self.fit_from(th, m, eopts, loose, true, Some(report))?;
        let decide = Evidence {
            drop_below: penalty.map_or(f64::NEG_INFINITY, |p| full.l + p),
            ..report
        };
        let hold = if hold_modes { 2 * m } else { 0 };
        let free = self.fit_holding(held.theta, m, eopts, loose, hold, Some(decide))?;
        Ok((held.l - full.l, free))
    }

    /// [`scoring`] on this model's likelihood.
    pub(in crate::refine) fn fit_from(
        &self,
        th: Vec<f64>,
        m: usize,
        opts: &RefineOptions,
        tol: f64,
        hold_poles: bool,
        evidence: Option<Evidence>,
    ) -> Result<Fit, SsiError> {
        let held = if hold_poles { self.poles(m) } else { 0 };
        self.fit_holding(th, m, opts, tol, held, evidence)
    }

    /// [`scoring`] on this model's likelihood with θ's first `held` entries held: none, the
    /// modes' 2m, or all pole parameters.
    pub(in crate::refine) fn fit_holding(
        &self,
        th: Vec<f64>,
        m: usize,
        opts: &RefineOptions,
        tol: f64,
        held: usize,
        evidence: Option<Evidence>,
    ) -> Result<Fit, SsiError> {
        // Held poles need no derivatives by the poles.
        let fisher = if held == self.poles(m) && held > 0 {
            What::FisherNumerators
        } else {
            What::Fisher
        };
        let eval =
            |t: &[f64], derivs: bool| self.eval(t, m, if derivs { fisher } else { What::Value });
        scoring(eval, th, (m, self.reals), opts, tol, held, evidence)
    }
}
