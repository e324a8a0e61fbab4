//! The levels workflow as one call: each record's Zener spectral fit, the one Bouc-Wen model
//! of all levels ([`fit_levels`]: the statistical linearization, then optionally by
//! simulation), every model validated, as one [`LevelsReport`] that prints
//! ([`std::fmt::Display`]) and serializes (feature `serde`). `hyst levels` and
//! `cargo xtask sweep-random` call [`fit_levels`].

use std::fmt;

use hyst_model::{BoucWen, Oscillator, Restoring, ZenerParams};

use super::{
    IdentError, LevelsBoucWen, LinearizeError, SimulatedBoucWen, SimulationOptions,
    ZenerSpectralFit, bouc_wen_and_exponent_from_levels, bouc_wen_by_simulation,
    bouc_wen_from_levels, statistical,
};
use crate::{IdentOptions, Progress, Score, ValidationRecord, validate};

/// Options of [`levels_report`] and [`fit_levels`].
#[derive(Debug, Clone, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
#[non_exhaustive]
pub struct LevelsOptions {
    /// The pipeline's options for each record (its mass the structure's).
    pub ident: IdentOptions,
    /// Fit the Bouc-Wen exponent ν too (three or more levels). Default false.
    pub fit_exponent: bool,
    /// Then fit the model by simulation, with these options ([`bouc_wen_by_simulation`];
    /// its `fit_exponent` is this one's). Default `None`.
    pub by_simulation: Option<SimulationOptions>,
}

impl LevelsOptions {
    /// Options for a structure of mass `mass` (kg), the pipeline's defaults otherwise.
    pub fn with_mass(mass: f64) -> Self {
        LevelsOptions {
            ident: IdentOptions {
                mass,
                ..IdentOptions::default()
            },
            ..LevelsOptions::default()
        }
    }

    /// These options with the exponent fitted (`true`) or held at 1.
    pub fn fit_exponent(mut self, fit: bool) -> Self {
        self.fit_exponent = fit;
        self
    }

    /// These options with the fit by simulation run with `opts` (`None`: not run).
    pub fn by_simulation(mut self, opts: Option<SimulationOptions>) -> Self {
        self.by_simulation = opts;
        self
    }
}

/// One level: its record's Zener spectral fit, and the model's own linearization there.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Level {
    /// The record's name.
    pub record: String,
    /// σₓ of the record (m).
    pub sigma_x: f64,
    /// Samples in the record.
    pub samples: usize,
    /// The record's Zener spectral fit (step 3b).
    pub fit: ZenerSpectralFit,
    /// The Zener element the levels' Bouc-Wen model linearizes to under this level's force
    /// density (`None` when the linearization fails there): beside `fit`, how well one
    /// element explains every level.
    pub model_zener: Option<ZenerParams>,
}

/// The Bouc-Wen models of all levels.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct LevelsModels {
    /// By the statistical linearization of every level ([`bouc_wen_from_levels`]).
    pub statistical: LevelsBoucWen,
    /// Whether the levels determine α, βγ and βδ (each standard error below its value);
    /// when not, the levels' responses are too close together.
    pub determined: bool,
    /// By simulation, when asked ([`bouc_wen_by_simulation`], started from `statistical`).
    pub by_simulation: Option<SimulatedBoucWen>,
}

/// One Bouc-Wen model from the Zener spectral fits `fits` of records of `lengths` samples:
/// by the statistical linearization, ν too when `opts.fit_exponent`, then by simulation when
/// `opts.by_simulation` asks; `progress` hears each iteration of the latter.
pub fn fit_levels(
    fits: &[&ZenerSpectralFit],
    lengths: &[usize],
    opts: &LevelsOptions,
    progress: &(dyn Fn(usize, f64) + Sync),
) -> Result<LevelsModels, IdentError> {
    let statistical = if opts.fit_exponent {
        bouc_wen_and_exponent_from_levels(fits)?
    } else {
        bouc_wen_from_levels(fits)?
    };
    let o = &statistical.oscillator;
    let bw = bouc_wen_of(o)?;
    let values = [bw.alpha, bw.beta_gamma(), bw.beta_delta()];
    let determined = values
        .iter()
        .zip(&statistical.se[2..])
        .all(|(v, s)| s.partial_cmp(&v.abs()) == Some(std::cmp::Ordering::Less));
    let by_simulation = match &opts.by_simulation {
        Some(s) => {
            let s = SimulationOptions {
                fit_exponent: opts.fit_exponent,
                ..s.clone()
            };
            Some(bouc_wen_by_simulation(fits, lengths, o, &s, progress)?)
        }
        None => None,
    };
    Ok(LevelsModels {
        statistical,
        determined,
        by_simulation,
    })
}

/// The Zener element the Bouc-Wen oscillator `o` linearizes to under the force density
/// `q` (`None` when `o` has no Bouc-Wen element or the linearization fails).
fn own_linearization(o: &Oscillator, q: f64) -> Option<ZenerParams> {
    let bw = bouc_wen_of(o).ok()?;
    statistical::equivalent_zener(o.mass, o.damping, o.stiffness, &bw, q)
        .ok()
        .map(|(z, _)| z)
}

fn bouc_wen_of(o: &Oscillator) -> Result<BoucWen, IdentError> {
    match o.restoring {
        Restoring::BoucWen(b) => Ok(b),
        _ => Err(LinearizeError::Invalid {
            name: "the levels' model (a Bouc-Wen element is needed)",
            value: f64::NAN,
        }
        .into()),
    }
}

/// The models' scores on one validation record.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct LevelsValidation {
    /// The record's name.
    pub record: String,
    /// Whether it was simulated to its steady state (else from rest).
    pub periodic: bool,
    /// The statistical model's score.
    pub statistical: Score,
    /// The model by simulation's, when it was fitted.
    pub by_simulation: Option<Score>,
}

/// What [`levels_report`] finds.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct LevelsReport {
    /// Each level, in the order given.
    pub levels: Vec<Level>,
    /// The models of all levels.
    pub models: LevelsModels,
    /// Their scores on each validation record.
    pub validation: Vec<LevelsValidation>,
    /// Whether ν was fitted.
    pub fit_exponent: bool,
}

/// The levels workflow: each of `records` (name, output) sampled at `fs` identified
/// ([`crate::identify`]) for its Zener spectral fit (an error when a record has none: each
/// must be the response to a broadband random force), then [`fit_levels`], then each model
/// validated on `validations`. `progress` hears each step as it starts: each record's
/// identification, each iteration of the fit by simulation (as many as it may take), each
/// validation.
pub fn levels_report(
    records: &[(String, &[f64])],
    fs: f64,
    opts: &LevelsOptions,
    validations: &[ValidationRecord],
    progress: &(dyn Fn(Progress<'_>) + Sync),
) -> Result<LevelsReport, IdentError> {
    let iterations = opts.by_simulation.as_ref().map_or(0, |s| s.max_iterations);
    let total = records.len() + iterations + validations.len();
    let tell = |done: usize, what: &str| progress(Progress { done, total, what });
    // (name, σₓ, samples, fit) of each record.
    let mut identified = Vec::with_capacity(records.len());
    for (i, (name, y)) in records.iter().enumerate() {
        tell(i, &format!("identifying {name}"));
        let id = crate::identify(y, fs, &opts.ident).map_err(|e| e.in_record(name))?;
        let fit = id.zener_spectrum.ok_or_else(|| IdentError::NoSpectralFit {
            record: name.clone(),
            notes: id.poles.notes.join("; "),
        })?;
        identified.push((name.clone(), id.prepared.sigma_x, y.len(), fit));
    }
    let fits: Vec<&ZenerSpectralFit> = identified.iter().map(|l| &l.3).collect();
    let lengths: Vec<usize> = identified.iter().map(|l| l.2).collect();
    if opts.by_simulation.is_some() {
        tell(records.len(), "fitting by simulation");
    }
    let iteration = |it: usize, cost: f64| {
        tell(
            records.len() + it,
            &format!("fitting by simulation: iteration {it}, weighted sum of squares {cost:.2}"),
        )
    };
    let models = fit_levels(&fits, &lengths, opts, &iteration)?;
    let own = &models.statistical.oscillator;
    let levels = identified
        .into_iter()
        .map(|(record, sigma_x, samples, fit)| Level {
            model_zener: own_linearization(own, fit.force_density),
            record,
            sigma_x,
            samples,
            fit,
        })
        .collect();
    let mut validation = Vec::with_capacity(validations.len());
    for (v, r) in validations.iter().enumerate() {
        tell(
            records.len() + iterations + v,
            &format!("validating on {}", r.name),
        );
        let score = |m: &Oscillator| Score::of(validate(m, &r.u, &r.y, fs, r.periodic));
        validation.push(LevelsValidation {
            record: r.name.clone(),
            periodic: r.periodic,
            statistical: score(&models.statistical.oscillator),
            by_simulation: models.by_simulation.as_ref().map(|s| score(&s.oscillator)),
        });
    }
    Ok(LevelsReport {
        levels,
        models,
        validation,
        fit_exponent: opts.fit_exponent,
    })
}

/// One line of a Bouc-Wen model: c, k, α, βγ, βδ with their standard errors `se`, βγ and
/// βδ in their unit (they multiply |z|^ν: 1/m only at ν = 1), then `tail` in parentheses;
/// and a line with ν ± `nu_se` when ν was fitted.
fn bouc_wen_lines(
    f: &mut fmt::Formatter<'_>,
    label: &str,
    o: &Oscillator,
    se: &[f64; 5],
    tail: &str,
    nu_se: Option<f64>,
) -> fmt::Result {
    let Ok(bw) = bouc_wen_of(o) else {
        return writeln!(f, "{label}: {o}");
    };
    let unit = if bw.nu == 1.0 {
        "1/m".to_string()
    } else {
        format!("1/(m·N^{:.3})", bw.nu - 1.0)
    };
    writeln!(
        f,
        "{label}: c {:.2} ± {:.2} N s/m, k {:.0} ± {:.0} N/m, α {:.0} ± {:.0} N/m, βγ {:.1} ± {:.1} {unit}, βδ {:.1} ± {:.1} {unit} ({tail})",
        o.damping,
        se[0],
        o.stiffness,
        se[1],
        bw.alpha,
        se[2],
        bw.beta_gamma(),
        se[3],
        bw.beta_delta(),
        se[4],
    )?;
    match nu_se {
        Some(nu_se) => writeln!(f, "  exponent ν {:.3} ± {nu_se:.3}", bw.nu),
        None => Ok(()),
    }
}

impl fmt::Display for LevelsReport {
    /// What `hyst levels` prints: each level's fit, the model of all levels (with a warning
    /// when the levels do not determine it), the model's own linearization beside each
    /// level's, the model by simulation, and the validations.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for l in &self.levels {
            let z = &l.fit;
            writeln!(
                f,
                "{}: c {:.2} ± {:.2} N s/m, k {:.0} ± {:.0} N/m, k∞ {:.0} ± {:.0} N/m, Ω {:.2} ± {:.2} rad/s, force density {:.4} N² s",
                l.record,
                z.c,
                z.se[0],
                z.k,
                z.se[1],
                z.k_inf,
                z.se[2],
                z.omega,
                z.se[3],
                z.force_density
            )?;
        }
        let m = &self.models.statistical;
        bouc_wen_lines(
            f,
            "Bouc-Wen of all levels",
            &m.oscillator,
            &m.se,
            &format!("χ² per degree of freedom {:.2}", m.chi2_per_dof),
            self.fit_exponent.then_some(m.nu_se),
        )?;
        if !self.models.determined {
            writeln!(
                f,
                "warning: the levels do not determine α, βγ and βδ (a standard error as large as \
                 its value): their response levels are too close together; record levels further apart"
            )?;
        }
        let show = |v: Option<f64>, d: usize| v.map_or("—".into(), |v| format!("{v:.d$}"));
        for l in &self.levels {
            writeln!(
                f,
                "  {}: k∞ {:.0} ± {:.0} N/m (model {}), Ω {:.2} ± {:.2} rad/s (model {})",
                l.record,
                l.fit.k_inf,
                l.fit.se[2],
                show(l.model_zener.map(|z| z.k_inf), 0),
                l.fit.omega,
                l.fit.se[3],
                show(l.model_zener.map(|z| z.omega), 2)
            )?;
        }
        if let Some(s) = &self.models.by_simulation {
            bouc_wen_lines(
                f,
                "Bouc-Wen by simulation",
                &s.oscillator,
                &s.se,
                &format!(
                    "whitened residual RMS {:.2}, {} iterations",
                    s.residual_rms, s.iterations
                ),
                self.fit_exponent.then_some(s.nu_se),
            )?;
        }
        let eps = |s: &Score| {
            s.epsilon()
                .map_or("—".to_string(), |e| format!("{:.3} %", 100.0 * e))
        };
        for v in &self.validation {
            writeln!(f, "validation on {}: ε = {}", v.record, eps(&v.statistical))?;
            if let Some(s) = &v.by_simulation {
                writeln!(
                    f,
                    "validation on {}, model by simulation: ε = {}",
                    v.record,
                    eps(s)
                )?;
            }
        }
        Ok(())
    }
}
