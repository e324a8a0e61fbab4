//! The whole output-only job on one record ([`identify_and_validate`]): the pipeline, each
//! mapping's Bouc-Wen model beside the flatness fit, every model validated on the records
//! given, the Bouc-Wen candidate kept that validates best, as one report that prints
//! ([`std::fmt::Display`]) and serializes (feature `serde`).

use std::fmt;

use crate::{
    IdentError, IdentOptions, Identification, Linearization, Validation, ValidationRecord,
    best_by_validation, build_models, identify, validate_all, zener_spectrum,
};
use hyst_model::Oscillator;

/// Where a Bouc-Wen candidate came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum BoucWenRoute {
    /// Fitted by flatness of the implied input ([`fit_flatness`](crate::fit_flatness)).
    Flatness,
    /// Mapped from the poles by eqs. (37)–(38) ([`Linearization::Paper`]).
    Paper,
    /// Mapped by the describing function's inversion ([`Linearization::Harmonic`]).
    Harmonic,
}

impl BoucWenRoute {
    /// The name used in reports.
    pub fn name(self) -> &'static str {
        match self {
            BoucWenRoute::Flatness => "flatness",
            BoucWenRoute::Paper => "paper",
            BoucWenRoute::Harmonic => "harmonic",
        }
    }

    fn of(l: Linearization) -> Self {
        match l {
            Linearization::Paper => BoucWenRoute::Paper,
            Linearization::Harmonic => BoucWenRoute::Harmonic,
        }
    }
}

/// A model's score on one validation record: ε and the RMS error, or why it could not be
/// simulated.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(untagged))]
pub enum Score {
    /// The model simulated and was compared.
    Scored(Validation),
    /// It did not simulate.
    Failed {
        /// Why.
        error: String,
    },
}

impl Score {
    /// A validation's outcome as a score.
    pub(crate) fn of(r: Result<Validation, IdentError>) -> Self {
        match r {
            Ok(v) => Score::Scored(v),
            Err(e) => Score::Failed {
                error: e.to_string(),
            },
        }
    }

    /// ε, when the model simulated.
    pub fn epsilon(&self) -> Option<f64> {
        match self {
            Score::Scored(v) => Some(v.epsilon),
            Score::Failed { .. } => None,
        }
    }
}

/// A Bouc-Wen candidate with its score on every validation record.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct BoucWenCandidate {
    /// Where it came from.
    pub route: BoucWenRoute,
    /// The model.
    pub model: Oscillator,
    /// Its score on each validation record, in order.
    pub validation: Vec<Score>,
}

/// Every model's score on one validation record.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ValidationRow {
    /// The record's name.
    pub record: String,
    /// Whether it was simulated to its steady state (else from rest).
    pub periodic: bool,
    /// The linear model's score.
    pub linear: Score,
    /// The Zener model's, when there is one.
    pub zener: Option<Score>,
    /// The kept Bouc-Wen candidate's, when there is one.
    pub bouc_wen: Option<Score>,
}

/// What [`identify_and_validate`] finds: the models (the Bouc-Wen one the candidate kept),
/// the candidates and validations, and the pipeline's own result.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct IdentReport {
    /// The linear model.
    pub linear: Oscillator,
    /// The Zener model, when there is one.
    pub zener: Option<Oscillator>,
    /// The Bouc-Wen candidate kept: the best on the first validation record, or without
    /// records the first (the flatness fit when the band is known, else the first mapping).
    /// None when even the best validates worse than the Zener model there (a note says so).
    pub bouc_wen: Option<Oscillator>,
    /// Where the kept candidate came from.
    pub bouc_wen_route: Option<BoucWenRoute>,
    /// Every Bouc-Wen candidate, in the order tried.
    pub candidates: Vec<BoucWenCandidate>,
    /// Every model's score on each validation record.
    pub validation: Vec<ValidationRow>,
    /// The options the pipeline ran with (its linearization the first mapping tried).
    pub options: IdentOptions,
    /// The pipeline's result (steps 1–4b).
    pub identification: Identification,
    /// Remarks of every step.
    pub notes: Vec<String>,
    /// Wall time of the identification (s), validation apart.
    pub seconds: f64,
    /// With [`IdentOptions::profile`]: what the record leaves free, each point's model
    /// validated on the records.
    pub profile: Vec<ProfileRow>,
}

/// A point of the one-record profile ([`crate::levels::beta_delta_profile`]) and its
/// model's score on each validation record.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ProfileRow {
    /// The point.
    pub point: crate::levels::ProfilePoint,
    /// Its model's scores, in the records' order (empty without a model).
    pub validation: Vec<Score>,
}

/// The mappings to Bouc-Wen tried: `chosen` alone when given, else the describing
/// function's, with the paper's beside it when there are records to tell them apart.
fn mappings(chosen: Option<Linearization>, records: usize) -> Vec<Linearization> {
    match chosen {
        Some(l) => vec![l],
        None if records == 0 => vec![Linearization::Harmonic],
        None => vec![Linearization::Harmonic, Linearization::Paper],
    }
}

/// The output-only job on `y` sampled at `fs`: [`identify`] with `opts` (its
/// `linearization` replaced by the first of the mappings tried: `mapping` when given, else
/// [`Linearization::Harmonic`] and, with validation records, [`Linearization::Paper`] too),
/// each mapping's Bouc-Wen model beside the flatness fit, every model validated on
/// `records`, and the Bouc-Wen candidate that validates best on the first record kept
/// ([`best_by_validation`]).
pub fn identify_and_validate(
    y: &[f64],
    fs: f64,
    opts: &IdentOptions,
    mapping: Option<Linearization>,
    records: &[ValidationRecord],
) -> Result<IdentReport, IdentError> {
    let t0 = std::time::Instant::now();
    let choices = mappings(mapping, records.len());
    let opts = IdentOptions {
        linearization: choices[0],
        ..opts.clone()
    };
    let id = identify(y, fs, &opts)?;
    // The other mappings share steps 1–3: only the models are built again.
    let mut mapped = vec![(choices[0], id.models.bouc_wen_mapped)];
    for lin in &choices[1..] {
        let o = IdentOptions {
            linearization: *lin,
            ..opts.clone()
        };
        mapped.push((
            *lin,
            build_models(&id.poles, &id.prepared, &o)?.bouc_wen_mapped,
        ));
    }
    let seconds = t0.elapsed().as_secs_f64();
    let mut candidates: Vec<(BoucWenRoute, Oscillator)> = Vec::new();
    if let Some(f) = &id.flatness {
        candidates.push((BoucWenRoute::Flatness, f.model));
    }
    candidates.extend(
        mapped
            .iter()
            .filter_map(|(l, m)| Some((BoucWenRoute::of(*l), (*m)?))),
    );
    let scores: Vec<Vec<Result<Validation, IdentError>>> = candidates
        .iter()
        .map(|(_, m)| validate_all(m, records, fs))
        .collect();
    let best = best_by_validation(&scores);
    let candidates: Vec<BoucWenCandidate> = candidates
        .into_iter()
        .zip(scores)
        .map(|((route, model), v)| BoucWenCandidate {
            route,
            model,
            validation: v.into_iter().map(Score::of).collect(),
        })
        .collect();
    let mut kept = best.and_then(|i| candidates.get(i));
    let linear = scores_of(&id.models.linear, records, fs);
    let zener = id.models.zener.as_ref().map(|m| scores_of(m, records, fs));
    let dropped = worse_than_zener(kept, zener.as_deref(), records);
    if dropped.is_some() {
        kept = None;
    }
    let validation = records
        .iter()
        .enumerate()
        .map(|(i, r)| ValidationRow {
            record: r.name.clone(),
            periodic: r.periodic,
            linear: linear[i].clone(),
            zener: zener.as_ref().map(|z| z[i].clone()),
            bouc_wen: kept.map(|c| c.validation[i].clone()),
        })
        .collect();
    let mut notes: Vec<String> = id
        .poles
        .notes
        .iter()
        .chain(&id.models.notes)
        .chain(&id.ssi.notes)
        .cloned()
        .collect();
    notes.extend(dropped);
    let profile = if opts.profile {
        match &id.zener_spectrum {
            Some(fit) => one_record_profile(fit, y, fs, records),
            None => {
                notes.push(
                    "no profile: it starts from the Zener spectral fit, which did not hold".into(),
                );
                Vec::new()
            }
        }
    } else {
        Vec::new()
    };
    if id.zener_spectrum.is_some() && opts.excitation.is_none() {
        notes.push(
            "one record under a random force fixes the Zener element at its amplitude (k, k∞, \
             Ω), not all of the Bouc-Wen element: its statistics bound the ratio βδ/βγ only \
             loosely, and models they cannot tell apart predict other force levels differently \
             (--profile shows them; docs/amplitude.md); records of the same structure at \
             several force levels fix it: hyst levels"
                .into(),
        );
    }
    Ok(IdentReport {
        linear: id.models.linear,
        zener: id.models.zener,
        bouc_wen: kept.map(|c| c.model),
        bouc_wen_route: kept.map(|c| c.route),
        candidates,
        validation,
        options: opts,
        identification: id,
        notes,
        seconds,
        profile,
    })
}

/// [`crate::levels::beta_delta_profile`] of the record `y` at its default ratios, each
/// point's model validated on `records`.
fn one_record_profile(
    fit: &zener_spectrum::ZenerSpectralFit,
    y: &[f64],
    fs: f64,
    records: &[ValidationRecord],
) -> Vec<ProfileRow> {
    let curve_opts = crate::amplitude::AmplitudeOptions::default();
    let record = crate::levels::OneRecord {
        fit,
        y,
        curve_opts: &curve_opts,
    };
    crate::levels::beta_delta_profile(
        &record,
        &crate::levels::PROFILE_RATIOS,
        &crate::levels::SimulationOptions::default(),
        &|_, _| {},
    )
    .into_iter()
    .map(|point| {
        let validation = match &point.fit {
            Ok(f) => scores_of(&f.oscillator, records, fs),
            Err(_) => Vec::new(),
        };
        ProfileRow { point, validation }
    })
    .collect()
}

/// `m`'s score on each of `records`.
fn scores_of(m: &Oscillator, records: &[ValidationRecord], fs: f64) -> Vec<Score> {
    validate_all(m, records, fs)
        .into_iter()
        .map(Score::of)
        .collect()
}

/// Why the kept Bouc-Wen candidate is dropped, when it validates worse than the Zener model
/// (`zener`: its scores) on the first record: from one record the element is not fixed
/// (docs/amplitude.md, "One record, one oscillator").
fn worse_than_zener(
    kept: Option<&BoucWenCandidate>,
    zener: Option<&[Score]>,
    records: &[ValidationRecord],
) -> Option<String> {
    let first_eps = |v: &[Score]| v.first().and_then(Score::epsilon);
    let (c, ez) = (kept?, zener.and_then(first_eps)?);
    let eb = first_eps(&c.validation).filter(|&eb| eb > ez)?;
    Some(format!(
        "no Bouc-Wen model is kept: the best ({}) validates worse than the Zener model on {} \
         (ε {:.3} % against {:.3} %); one record fixes the equivalent Zener element at its \
         amplitude, not the Bouc-Wen element that would extrapolate to another: records at \
         several force levels do (hyst levels)",
        c.route.name(),
        records
            .first()
            .map_or("the first record", |r| r.name.as_str()),
        100.0 * eb,
        100.0 * ez
    ))
}

fn eps_text(s: Option<&Score>) -> String {
    s.and_then(Score::epsilon)
        .map_or("-".to_string(), |e| format!("{:.3} %", 100.0 * e))
}

impl IdentReport {
    fn fmt_fits(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let id = &self.identification;
        if let Some(z) = &id.zener_spectrum {
            let held = z.unconstrained_c.map_or(String::new(), |[c, se]| {
                format!(" (held at 0: the most likely c is {c:.3} ± {se:.3})")
            });
            writeln!(
                f,
                "zener spectral fit (white force, {} frequencies up to {:.1} Hz, misfit {:.3}): \
                 c = {:.3} ± {:.3} N s/m{held}, k = {:.1} ± {:.1} N/m, k_inf = {:.1} ± {:.1} N/m, \
                 omega = {:.3} ± {:.3} rad/s; force density {:.4e} ± {:.1e} N^2 s, measurement noise std {:.3e} m",
                z.bins,
                z.max_frequency_hz,
                z.misfit,
                z.c,
                z.se[0],
                z.k,
                z.se[1],
                z.k_inf,
                z.se[2],
                z.omega,
                z.se[3],
                z.force_density,
                z.force_density_se,
                z.noise_std
            )?;
        }
        if let Some(fl) = &id.flatness {
            let band = self.options.excitation.map_or(String::new(), |b| {
                format!(
                    " of the {}-sample period ({}–{} Hz)",
                    b.period, b.low_hz, b.high_hz
                )
            });
            writeln!(
                f,
                "flatness fit: {} periods averaged (aperiodicity {}: last period against the first), \
                 DFT bins {}–{}{band}, spread of the implied input's |U| over the band {:.3} dB -> \
                 {:.3} dB in {} iterations, implied input RMS {:.3} N",
                fl.periods,
                fl.aperiodicity
                    .map_or("-".to_string(), |a| format!("{a:.3}")),
                fl.bins.0,
                fl.bins.1,
                fl.start_spread_db,
                fl.spread_db,
                fl.iterations,
                fl.input_rms
            )?;
        }
        Ok(())
    }

    fn fmt_validation(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let route = self.bouc_wen_route.map_or("none", BoucWenRoute::name);
        if !self.validation.is_empty() {
            writeln!(
                f,
                "validation error ε below: eq. (39) of the paper, the RMS of simulated − measured \
                 output over the measured output's range"
            )?;
        }
        for c in &self.candidates {
            let tag = if Some(c.route) == self.bouc_wen_route {
                " (kept)"
            } else {
                ""
            };
            writeln!(f, "bouc_wen model [{}]{tag}: {}", c.route.name(), c.model)?;
            for (r, s) in self.validation.iter().zip(&c.validation) {
                writeln!(
                    f,
                    "  validation error ε on {}: {}",
                    r.record,
                    eps_text(Some(s))
                )?;
            }
        }
        for r in &self.validation {
            writeln!(
                f,
                "validation error ε on {} ({}): linear {}, zener {}, bouc_wen [{route}] {}",
                r.record,
                if r.periodic {
                    "one steady-state period"
                } else {
                    "from rest"
                },
                eps_text(Some(&r.linear)),
                eps_text(r.zener.as_ref()),
                eps_text(r.bouc_wen.as_ref())
            )?;
        }
        Ok(())
    }

    fn fmt_profile(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.profile.is_empty() {
            return Ok(());
        }
        writeln!(
            f,
            "what one record leaves free: the Bouc-Wen models that best reproduce its statistics \
             (Zener fit, amplitude curve, kurtosis) at each ratio βδ/βγ held; χ² over the \
             statistics (a difference of a few is within the record's noise)"
        )?;
        let names: Vec<&str> = self.validation.iter().map(|r| r.record.as_str()).collect();
        for row in &self.profile {
            match &row.point.fit {
                Ok(p) => {
                    let eps: Vec<String> = names
                        .iter()
                        .zip(&row.validation)
                        .map(|(n, s)| format!("ε on {n} {}", eps_text(Some(s))))
                        .collect();
                    writeln!(
                        f,
                        "  βδ/βγ {:5.2}: χ² {:7.1} of {}  {}{}{}",
                        row.point.ratio,
                        p.chi2,
                        p.residuals,
                        p.oscillator,
                        if eps.is_empty() { "" } else { "  " },
                        eps.join(", ")
                    )?;
                }
                Err(e) => writeln!(f, "  βδ/βγ {:5.2}: no model ({e})", row.point.ratio)?,
            }
        }
        Ok(())
    }
}

impl fmt::Display for IdentReport {
    /// What `hyst ident` prints: the prepared record, the poles, each model, the spectral
    /// and flatness fits, every Bouc-Wen candidate with its validation, the validation
    /// table, the notes and the time taken.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let id = &self.identification;
        let p = &id.prepared;
        writeln!(
            f,
            "prepared: sampling rate {} Hz (decimated by {}), dominant frequency {:.2} Hz, displacement std σx {:.3e} m, skewness {:.3}, kurtosis {:.3} (3 for a Gaussian)",
            p.fs, p.decimation, p.dominant_hz, p.sigma_x, p.skewness, p.kurtosis
        )?;
        let real = id
            .poles
            .real
            .map_or("none".to_string(), |r| format!("λ = {r:.4} rad/s"));
        let pair = id.poles.pair;
        writeln!(
            f,
            "poles: oscillating pair λ = {:.4} ± {:.4}i rad/s ({:.4} Hz, damping ratio {:.4}), \
             real pole {real}; viscous damping c = {:.3} N·s/m ({})",
            pair.re,
            pair.im.abs(),
            pair.norm() / (2.0 * std::f64::consts::PI),
            -pair.re / pair.norm(),
            id.poles.c,
            id.poles.c_source
        )?;
        writeln!(f, "linear model: {}", self.linear)?;
        if let Some(z) = &self.zener {
            writeln!(f, "zener model: {z}")?;
        }
        self.fmt_fits(f)?;
        self.fmt_validation(f)?;
        self.fmt_profile(f)?;
        for n in &self.notes {
            writeln!(f, "note: {n}")?;
        }
        writeln!(f, "identification time: {:.3} s", self.seconds)
    }
}
