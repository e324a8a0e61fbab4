//! Where the loop starts: the output-only pipeline's model of the class asked for
//! ([`ModelClass`]), falling back to simpler classes, then [`refine`](super::refine).

use hyst_model::Oscillator;

use super::candidates::{self, equation_error_start};
use super::progress::{ProgressFn, no_progress, tell};
use super::{Effect, Record, Refinement, StartReport, check_rows, check_test_rows, refine_with};
use crate::IdentError;

/// Which model the loop starts from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "kebab-case"))]
pub enum ModelClass {
    /// The linear oscillator from the dominant pole pair.
    #[default]
    Linear,
    /// The Zener oscillator.
    Zener,
    /// The Bouc-Wen oscillator.
    BoucWen,
}

impl ModelClass {
    /// The class of a model.
    pub fn of(o: &Oscillator) -> ModelClass {
        match o.restoring {
            hyst_model::Restoring::None => ModelClass::Linear,
            hyst_model::Restoring::Zener(_) => ModelClass::Zener,
            hyst_model::Restoring::BoucWen(_) => ModelClass::BoucWen,
        }
    }

    /// The name used in reports.
    pub fn name(&self) -> &'static str {
        match self {
            ModelClass::Linear => "linear",
            ModelClass::Zener => "zener",
            ModelClass::BoucWen => "bouc-wen",
        }
    }

    /// This start and the simpler ones it falls back to, in order.
    fn chain(self) -> &'static [ModelClass] {
        match self {
            ModelClass::BoucWen => &[ModelClass::BoucWen, ModelClass::Zener, ModelClass::Linear],
            ModelClass::Zener => &[ModelClass::Zener, ModelClass::Linear],
            ModelClass::Linear => &[ModelClass::Linear],
        }
    }
}

/// The whole loop on a record: the output-only pipeline on the estimation rows gives the
/// starting model (mass 1 and fitted when `mass` is `None`), then [`refine`](super::refine). A start the
/// pipeline does not give, or whose fit diverges, falls back to the next simpler one
/// (Bouc-Wen → Zener → linear), and the report says so ([`Refinement::start`]); when the
/// pipeline gives nothing at all, the linear start comes from the equation-error regression.
pub fn refine_record(
    rec: &Record<'_>,
    mass: Option<f64>,
    start: ModelClass,
    estimate: (usize, usize),
    tests: &[(usize, usize)],
) -> Result<Refinement, IdentError> {
    refine_record_with(rec, mass, start, estimate, tests, &no_progress)
}

/// [`refine_record`], saying what it does as it goes.
pub fn refine_record_with(
    rec: &Record<'_>,
    mass: Option<f64>,
    start: ModelClass,
    estimate: (usize, usize),
    tests: &[(usize, usize)],
    progress: ProgressFn<'_>,
) -> Result<Refinement, IdentError> {
    if rec.u.len() != rec.y.len() {
        return Err(IdentError::LengthMismatch {
            input: rec.u.len(),
            output: rec.y.len(),
        });
    }
    check_rows(estimate, rec.y.len())?;
    for &range in tests {
        check_rows(range, rec.y.len())?;
    }
    check_test_rows(tests, estimate)?;
    let opts = crate::IdentOptions {
        mass: mass.unwrap_or(1.0),
        ..crate::IdentOptions::default()
    };
    tell(progress, 0, "output-only identification of the start");
    let models = match crate::identify(&rec.y[estimate.0..estimate.1], rec.fs, &opts) {
        Ok(id) => Some(id.models),
        Err(e) => {
            let mut notes = vec![format!(
                "the output-only pipeline failed ({e}): starting from the equation-error regression"
            )];
            let plain = Oscillator::linear(opts.mass, 0.0, 0.0);
            let m = equation_error_start(&plain, None, rec, estimate, mass.is_none()).ok_or(
                IdentError::StartDiverges {
                    start: estimate.0,
                    end: estimate.1,
                },
            )?;
            let mut r = refine_with(&m, rec, estimate, tests, mass.is_none(), progress)?;
            notes.append(&mut r.start.notes);
            r.start = StartReport {
                requested: start,
                used: ModelClass::Linear,
                notes,
            };
            return Ok(r);
        }
    };
    let models = models.expect("handled above");
    // Without a Bouc-Wen model from the pipeline, the element is started afresh on the
    // equation-error linear model (as the hysteresis candidate starts one on a model without
    // an element), before the simpler classes: on random-force records whose dominant pole
    // pair the pipeline misread, its Zener start sat at twice the true stiffness.
    let fresh = (start == ModelClass::BoucWen && models.bouc_wen.is_none())
        .then(|| fresh_bouc_wen(rec, estimate, opts.mass, mass.is_none()))
        .flatten();
    let class_model = |class: ModelClass| match class {
        ModelClass::Linear => Some(models.linear),
        ModelClass::Zener => models.zener,
        ModelClass::BoucWen => models.bouc_wen.or(fresh),
    };
    let (mut r, used, mut notes) = first_usable(start, estimate, class_model, |m| {
        refine_with(m, rec, estimate, tests, mass.is_none(), progress)
    })?;
    if used == ModelClass::BoucWen && models.bouc_wen.is_none() {
        notes.push(
            "the output-only pipeline gave no bouc-wen model: the element is started afresh on \
             the equation-error linear model"
                .into(),
        );
    }
    r.start = StartReport {
        requested: start,
        used,
        notes,
    };
    Ok(r)
}

/// A Bouc-Wen start made without the output-only pipeline: the equation-error linear model
/// on the estimation rows with an element added as [`Effect::Hysteresis`] adds one.
pub(super) fn fresh_bouc_wen(
    rec: &Record<'_>,
    estimate: (usize, usize),
    mass: f64,
    fit_mass: bool,
) -> Option<Oscillator> {
    let plain = Oscillator::linear(mass, 0.0, 0.0);
    let lin = equation_error_start(&plain, None, rec, estimate, fit_mass)?;
    if lin.stiffness <= 0.0 {
        return None;
    }
    let y = &rec.y[estimate.0..estimate.1];
    let sx = (y.iter().map(|v| v * v).sum::<f64>() / y.len() as f64).sqrt();
    let sv = sx * (lin.stiffness / lin.mass).sqrt();
    candidates::with_effect(&lin, Effect::Hysteresis, sx.max(1e-300), sv)
}

/// Run `run` from the model of `start`'s class (`model_of`), falling back along
/// [`ModelClass::chain`] past a class with no model or whose fit diverges; returns the result,
/// the class used and a note for each class passed over. Any other error stops the chain.
pub(super) fn first_usable<T>(
    start: ModelClass,
    estimate: (usize, usize),
    model_of: impl Fn(ModelClass) -> Option<Oscillator>,
    mut run: impl FnMut(&Oscillator) -> Result<T, IdentError>,
) -> Result<(T, ModelClass, Vec<String>), IdentError> {
    let mut notes = Vec::new();
    let mut last = None;
    for &class in start.chain() {
        let Some(m) = model_of(class) else {
            notes.push(format!(
                "the output-only pipeline gave no {} model: falling back",
                class.name()
            ));
            continue;
        };
        match run(&m) {
            Ok(r) => return Ok((r, class, notes)),
            Err(e @ IdentError::StartDiverges { .. }) => {
                notes.push(format!(
                    "the {} start diverges on the estimation rows: falling back",
                    class.name()
                ));
                last = Some(e);
            }
            Err(e) => return Err(e),
        }
    }
    Err(last.unwrap_or(IdentError::StartDiverges {
        start: estimate.0,
        end: estimate.1,
    }))
}
