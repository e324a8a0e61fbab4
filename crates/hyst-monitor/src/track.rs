//! A campaign's records tracked: each record's modes matched to the reference, each mode's
//! baseline fitted over the training records, the later records charted, alarms raised.

use crate::MonitorError;
use crate::baseline::{Baseline, fit_baseline};
use crate::calibration::{self, Calibration, Sides};
use crate::chart::{Cusum, Side};
use crate::environment::{Environment, Series};
use crate::joint::{JointChart, joint_chart};
use crate::matching::{MatchOptions, ModeEstimate, match_modes};
use crate::records::{Identified, RecordModes};
use crate::training::{self, OutlierRule, TrainingOutlier};
use crate::whiten::ResidualModel;

/// How a campaign is tracked.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct TrackOptions {
    /// When a record's mode is the reference's.
    pub matching: MatchOptions,
    /// The first this many records train the baselines (default 336: two weeks of hourly
    /// records).
    pub training: usize,
    /// Without a reference given, it is the modes the first this many records agree on
    /// (default 24): the candidate record whose modes the others hold most often, each of
    /// its modes kept when at least half the others hold it.
    pub reference_pool: usize,
    /// The chart of the standardized residuals.
    pub chart: Cusum,
    /// Model a slow effect the covariates leave unexplained, when the training residuals
    /// hold one, and chart the filter's innovations (default), not the residuals themselves:
    /// see [`crate::whiten`].
    pub whiten: bool,
    /// Choose each mode's environmental model on the training records (each covariate
    /// through a first-order lag, a breakpoint; [`crate::environment`]; from 20 training
    /// records; default), rather than regress on the covariates as they are.
    pub environment: bool,
    /// Add each record's excitation level as a covariate, after the given ones: ln of its
    /// RMS response (the root of the channels' mean variance, in the record's units), named
    /// `log_rms` (default off). Real frequencies drift with amplitude (friction, cracks
    /// opening, the hysteresis hyst identifies); the environmental model then regresses on
    /// it as on the temperature.
    #[cfg_attr(feature = "serde", serde(default))]
    pub level_covariate: bool,
    /// Calibrate each chart's limit on the training records' own charted values
    /// ([`crate::calibration`]; default), rather than take the limit independent standard
    /// normal values would ask.
    #[cfg_attr(feature = "serde", serde(default = "yes"))]
    pub calibrate: bool,
    /// Judge the modes together ([`crate::joint`]; default): the joint chart beside the
    /// modes' own.
    #[cfg_attr(feature = "serde", serde(default = "yes"))]
    pub joint: bool,
}

#[cfg(feature = "serde")]
fn yes() -> bool {
    true
}

impl Default for TrackOptions {
    fn default() -> Self {
        TrackOptions {
            matching: MatchOptions::default(),
            training: 336,
            reference_pool: 24,
            chart: Cusum::default(),
            whiten: true,
            environment: true,
            level_covariate: false,
            calibrate: true,
            joint: true,
        }
    }
}

impl TrackOptions {
    /// The options for a campaign of `records` records: `training` records train the
    /// baselines (by default 336, at most half the campaign), whitened and with the
    /// environmental model as asked.
    pub fn for_campaign(
        records: usize,
        training: Option<usize>,
        whiten: bool,
        environment: bool,
    ) -> TrackOptions {
        let mut opts = TrackOptions::default();
        opts.training = training.unwrap_or(opts.training.min(records / 2));
        opts.whiten = whiten;
        opts.environment = environment;
        opts
    }
}

impl TrackReport {
    /// What users call mode `j` (an index from 0): its name, else its number counted from 1.
    pub fn mode_name(&self, j: usize) -> String {
        self.mode_names
            .get(j)
            .cloned()
            .unwrap_or_else(|| (j + 1).to_string())
    }

    /// Name the covariates the records were given (in their order); the excitation level,
    /// when [`track`] added it, keeps its name `log_rms` after them.
    pub fn name_covariates(&mut self, names: Vec<String>) {
        self.covariate_names = names;
        if self.level_covariate {
            self.covariate_names.push("log_rms".into());
        }
    }
}

/// One record × mode of the tidy table.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct TrackRow {
    /// The record's place in the campaign (0-based).
    pub record: usize,
    /// Its name.
    pub name: String,
    /// Its time (s).
    pub time: f64,
    /// The reference mode (0-based).
    pub mode: usize,
    /// The record's estimate of it.
    pub frequency_hz: f64,
    /// Standard error (Hz), if any.
    pub frequency_se_hz: Option<f64>,
    /// Damping ratio.
    pub damping_ratio: f64,
    /// Standard error, if any.
    pub damping_se: Option<f64>,
    /// MAC to the reference's shape (NaN without shapes).
    pub mac: f64,
    /// The record's misfit is above the limit: its modes are SSI's.
    pub misfit_flag: bool,
    /// The standardized residual against the baseline (records after training).
    pub z: Option<f64>,
    /// What the chart was given: the residual less what the slow effect's filter predicted
    /// from the records before, standardized (z itself when the residuals are independent).
    pub innovation: Option<f64>,
    /// An alarm this record raised on this mode.
    pub alarm: Option<Side>,
    /// The covariates.
    pub covariates: Vec<f64>,
    /// The environmental model's regressors lie outside their training range here: the
    /// prediction is extrapolated.
    #[cfg_attr(feature = "serde", serde(default))]
    pub extrapolated: bool,
}

/// A change found: a mode's chart passed its limit.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ModeAlarm {
    /// The reference mode.
    pub mode: usize,
    /// The record that raised it.
    pub record: usize,
    /// Its time (s).
    pub time: f64,
    /// Which way the frequency moved.
    pub side: Side,
}

/// What tracking a campaign found.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct TrackReport {
    /// The reference modes.
    pub reference: Vec<ModeEstimate>,
    /// Record × mode.
    pub rows: Vec<TrackRow>,
    /// Records that gave no modes, and why.
    pub skipped: Vec<(String, String)>,
    /// Poles taken for harmonics, not modes: (record, frequency).
    #[cfg_attr(feature = "serde", serde(default))]
    pub harmonics: Vec<(usize, f64)>,
    /// Modes a record had that the reference does not: (record, frequency).
    pub new_modes: Vec<(usize, f64)>,
    /// (record, reference mode) where the record held the mode twice, with one shape (see
    /// [`Assignment::split`](crate::Assignment::split)): not tracked there.
    pub split: Vec<(usize, usize)>,
    /// Each reference mode's baseline (`None` with too few training records).
    pub baselines: Vec<Option<Baseline>>,
    /// Why a mode has no baseline.
    pub baseline_errors: Vec<Option<String>>,
    /// Per mode, the estimation noise (Hz) read from its training rows when the estimates
    /// came without standard errors ([`crate::estimates`]); empty or `None` otherwise.
    #[cfg_attr(feature = "serde", serde(default))]
    pub noise_from_training: Vec<Option<f64>>,
    /// Each mode's environmental model (`None` without a baseline).
    #[cfg_attr(feature = "serde", serde(default))]
    pub environments: Vec<Option<Environment>>,
    /// Each mode's slow unexplained effect, whose filter's innovations were charted (`None`:
    /// its residuals were independent, were charted as they are, or it has no baseline).
    pub residual_models: Vec<Option<ResidualModel>>,
    /// Each reference mode's share of the identified records that had it.
    pub tracked: Vec<f64>,
    /// The alarms, in time order.
    pub alarms: Vec<ModeAlarm>,
    /// Each mode's chart limit as calibrated on its training values (`None`: not
    /// calibrated, too few values, or no baseline; the nominal limit charted).
    #[cfg_attr(feature = "serde", serde(default))]
    pub calibrations: Vec<Option<Calibration>>,
    /// The modes judged together ([`crate::joint`]), when asked and possible.
    #[cfg_attr(feature = "serde", serde(default))]
    pub joint: Option<JointChart>,
    /// Why the joint chart could not be drawn, when it could not.
    #[cfg_attr(feature = "serde", serde(default))]
    pub joint_error: Option<String>,
    /// Training values set apart from their mode's baseline ([`crate::training`]), by
    /// record.
    #[cfg_attr(feature = "serde", serde(default))]
    pub training_outliers: Vec<TrainingOutlier>,
    /// The chart's in-control average run length (records per false alarm, per mode).
    pub in_control_run_length: f64,
    /// The modes' names, in the reference's order: an estimates table's columns, else each
    /// mode's number counted from 1 ([`TrackReport::mode_name`]: what the text, the table,
    /// the page and the figures call it). Rows and alarms refer to modes by their index
    /// into this list and the reference, from 0.
    #[cfg_attr(feature = "serde", serde(default))]
    pub mode_names: Vec<String>,
    /// The covariates' names, in the order of each row's `covariates` (the caller's to
    /// set: [`track`] leaves it empty, and the text then numbers them).
    #[cfg_attr(feature = "serde", serde(default))]
    pub covariate_names: Vec<String>,
    /// The excitation level is the last covariate (`log_rms`, added by [`track`]).
    #[cfg_attr(feature = "serde", serde(default))]
    pub level_covariate: bool,
    /// The subspace damage test over the same records ([`crate::subspace`]), when the
    /// records carry their correlations.
    #[cfg_attr(feature = "serde", serde(default))]
    pub subspace: Option<crate::subspace::SubspaceChart>,
    /// Why the subspace test could not be run, when it could not.
    #[cfg_attr(feature = "serde", serde(default))]
    pub subspace_error: Option<String>,
    /// Records charted after the training period (none: every record trained, and "no
    /// alarm" would say nothing); unknown in a report written before it was kept.
    #[cfg_attr(feature = "serde", serde(default))]
    pub monitored: Option<usize>,
}

/// The reference the first records agree on: among the first `opts.reference_pool` records
/// that gave modes, each candidate's modes matched to every other's; a mode is confirmed
/// when at least half the others hold it; the candidate whose confirmed modes the others
/// hold most often (in all) gives them. A spurious pole of one record, or one mode held
/// twice (a mode moved by frost between two records' worth of frequency), is not confirmed,
/// and so never tracked as a mode of its own. With one record, its modes.
fn consensus_reference(records: &[RecordModes], opts: &TrackOptions) -> Vec<ModeEstimate> {
    let pool: Vec<&Identified> = records
        .iter()
        .take(opts.reference_pool.max(1))
        .filter_map(|r| r.outcome.as_ref().ok())
        .filter(|id| !id.modes.is_empty())
        .collect();
    if pool.len() < 2 {
        return pool.first().map(|id| id.modes.clone()).unwrap_or_default();
    }
    let others = (pool.len() - 1) as f64;
    let mut best: Option<(usize, Vec<ModeEstimate>)> = None;
    for (c, candidate) in pool.iter().enumerate() {
        let mut held = vec![0usize; candidate.modes.len()];
        for (o, other) in pool.iter().enumerate() {
            if o == c {
                continue;
            }
            let a = match_modes(&candidate.modes, &other.modes, &opts.matching);
            for (j, m) in a.matched.iter().enumerate() {
                held[j] += usize::from(m.is_some());
            }
        }
        let confirmed: Vec<usize> = (0..held.len())
            .filter(|&j| held[j] as f64 >= 0.5 * others)
            .collect();
        let score: usize = confirmed.iter().map(|&j| held[j]).sum();
        if best.as_ref().is_none_or(|(b, _)| score > *b) {
            let modes = confirmed
                .iter()
                .map(|&j| candidate.modes[j].clone())
                .collect();
            best = Some((score, modes));
        }
    }
    best.map(|(_, m)| m).unwrap_or_default()
}

/// The subspace test over the `usable` records that carry their correlations (on the
/// channels of the first that does), for a model of order `order`, the residual regressed
/// on the union of the modes' environmental models `environments` (each record's covariates
/// `covariates`, `None` where it has none); `None` when no record carries correlations
/// (estimates made elsewhere).
fn subspace_over(
    records: &[RecordModes],
    usable: &[bool],
    covariates: &[Option<Vec<f64>>],
    environments: &[Option<Environment>],
    order: usize,
    opts: &TrackOptions,
) -> Result<Option<crate::subspace::SubspaceChart>, MonitorError> {
    let correlations: Vec<Option<&crate::subspace::Correlations>> = records
        .iter()
        .zip(usable)
        .map(|(r, &ok)| {
            r.outcome
                .as_ref()
                .ok()
                .filter(|_| ok)
                .and_then(|id| id.correlations.as_ref())
        })
        .collect();
    let Some(channels) = correlations.iter().flatten().map(|c| c.channels).next() else {
        return Ok(None);
    };
    let environment = union_environment(environments);
    let at: Vec<(f64, Vec<f64>)> = records
        .iter()
        .zip(covariates)
        .filter_map(|(r, x)| Some((r.time, x.clone()?)))
        .collect();
    let series = Series::new(&at);
    let lags = correlations
        .iter()
        .flatten()
        .map(|c| c.lags())
        .next()
        .unwrap_or(0);
    let trained = correlations[..opts.training.min(correlations.len())]
        .iter()
        .flatten()
        .count();
    let blocks = crate::subspace::blocks_for(order, channels, trained, lags);
    let inputs: Vec<Option<crate::subspace::SubspaceRecord>> = correlations
        .iter()
        .zip(records.iter().zip(covariates))
        .map(|(c, (r, x))| {
            let c = c.filter(|c| c.channels == channels)?;
            let features = match &environment {
                Some(e) => e.features(&series, r.time, x.as_ref()?),
                None => Vec::new(),
            };
            if !features.iter().all(|v| v.is_finite()) {
                return None;
            }
            c.record(blocks, features)
        })
        .collect();
    let time: Vec<f64> = records.iter().map(|r| r.time).collect();
    let mut chart = crate::subspace::subspace_chart(
        &inputs,
        &time,
        opts.training,
        order,
        crate::subspace::ALPHA,
        &opts.chart,
        opts.calibrate,
    )?;
    chart.environment = environment;
    Ok(Some(chart))
}

/// What the campaign's records have in common, against which one is unlike the rest: the
/// median length, and the reference's channel count.
struct Unlike {
    median_samples: usize,
    channels: Option<usize>,
}

impl Unlike {
    fn of(records: &[RecordModes], reference: &[ModeEstimate]) -> Unlike {
        let mut lengths: Vec<usize> = records
            .iter()
            .filter_map(|r| r.outcome.as_ref().ok())
            .map(|id| id.samples)
            .filter(|&n| n > 0)
            .collect();
        lengths.sort_unstable();
        Unlike {
            median_samples: lengths.get(lengths.len() / 2).copied().unwrap_or(0),
            channels: reference
                .iter()
                .find_map(|m| m.shape.as_ref().map(|s| s.len())),
        }
    }

    /// Why the record is unlike the campaign's others, if it is: far shorter (under half
    /// the median length: its estimates' errors are more than √2 the others' and its
    /// lowest modes barely resolved), or its modes on another number of channels (the
    /// shapes cannot be compared with the reference's).
    fn why(&self, id: &Identified) -> Option<String> {
        if id.samples > 0 && 2 * id.samples < self.median_samples {
            return Some(format!(
                "its {} samples are {:.0} % of the campaign's median {}: far shorter than the rest; skipped",
                id.samples,
                100.0 * id.samples as f64 / self.median_samples as f64,
                self.median_samples
            ));
        }
        let expected = self.channels?;
        let got = id
            .modes
            .iter()
            .find_map(|m| m.shape.as_ref().map(|s| s.len()))?;
        (got != expected).then(|| {
            format!(
                "its modes are on {got} channels, the reference's on {expected}: another sensor layout; skipped"
            )
        })
    }
}

/// Track `records` (in time order) against `reference`, or against the reference the first
/// records give.
pub fn track(
    records: &[RecordModes],
    reference: Option<&[ModeEstimate]>,
    opts: &TrackOptions,
) -> Result<TrackReport, MonitorError> {
    let reference: Vec<ModeEstimate> = match reference {
        Some(r) => r.to_vec(),
        None => consensus_reference(records, opts),
    };
    let misfit_limit = covssi::MISFIT_LIMIT;
    let mut rows = Vec::new();
    let mut skipped = Vec::new();
    let mut new_modes = Vec::new();
    let mut split = Vec::new();
    let mut seen = vec![0usize; reference.len()];
    let mut identified = 0usize;
    let mut harmonics = Vec::new();
    let unlike = Unlike::of(records, &reference);
    let mut usable = vec![false; records.len()];
    let mut record_covariates: Vec<Option<Vec<f64>>> = vec![None; records.len()];
    for (i, r) in records.iter().enumerate() {
        let id = match &r.outcome {
            Ok(id) => id,
            Err(why) => {
                skipped.push((r.name.clone(), why.clone()));
                continue;
            }
        };
        if let Some(why) = unlike.why(id) {
            skipped.push((r.name.clone(), why));
            continue;
        }
        usable[i] = true;
        let mut covariates = r.covariates.clone();
        if opts.level_covariate {
            covariates.push(if id.rms > 0.0 { id.rms.ln() } else { f64::NAN });
        }
        record_covariates[i] = Some(covariates.clone());
        identified += 1;
        harmonics.extend(id.harmonics.iter().map(|h| (i, h.frequency_hz)));
        let a = match_modes(&reference, &id.modes, &opts.matching);
        for (mode, m) in a.matched.iter().enumerate() {
            let Some((j, mac)) = m else { continue };
            seen[mode] += 1;
            let e = &id.modes[*j];
            rows.push(TrackRow {
                record: i,
                name: r.name.clone(),
                time: r.time,
                mode,
                frequency_hz: e.frequency_hz,
                frequency_se_hz: e.frequency_se_hz,
                damping_ratio: e.damping_ratio,
                damping_se: e.damping_se,
                mac: *mac,
                misfit_flag: id.misfit.is_some_and(|f| f > misfit_limit),
                z: None,
                innovation: None,
                alarm: None,
                covariates: covariates.clone(),
                extrapolated: false,
            });
        }
        new_modes.extend(a.new.iter().map(|&j| (i, id.modes[j].frequency_hz)));
        split.extend(a.split.iter().map(|&mode| (i, mode)));
    }
    if identified == 0
        && let Some((first, why)) = skipped.first()
    {
        return Err(MonitorError::NoneIdentified {
            records: records.len(),
            first: first.clone(),
            why: why.clone(),
        });
    }
    let tracked = seen
        .iter()
        .map(|&s| s as f64 / identified.max(1) as f64)
        .collect();
    let mut report = chart_modes(reference, rows, records.len(), opts);
    match subspace_over(
        records,
        &usable,
        &record_covariates,
        &report.environments,
        2 * report.reference.len(),
        opts,
    ) {
        Ok(chart) => report.subspace = chart,
        Err(e) => report.subspace_error = Some(e.to_string()),
    }
    report.level_covariate = opts.level_covariate;
    report.skipped = skipped;
    report.harmonics = harmonics;
    report.new_modes = new_modes;
    report.split = split;
    report.tracked = tracked;
    Ok(report)
}

/// Each reference mode's baseline fitted and its later rows charted ([`chart_mode`]): the
/// report of a campaign of `records` records whose rows are `rows`, the skipped records,
/// new and split modes and the tracked shares left empty for the caller.
pub(crate) fn chart_modes(
    reference: Vec<ModeEstimate>,
    mut rows: Vec<TrackRow>,
    records: usize,
    opts: &TrackOptions,
) -> TrackReport {
    let reference_len = reference.len();
    let mut baselines = Vec::with_capacity(reference.len());
    let mut baseline_errors = Vec::with_capacity(reference.len());
    let mut residual_models = Vec::with_capacity(reference.len());
    let mut environments = Vec::with_capacity(reference.len());
    let mut alarms = Vec::new();
    let mut training_outliers = Vec::new();
    // Each record's time and covariates once, for lagged values.
    let mut time = vec![f64::NAN; records];
    let mut at = Vec::new();
    for r in &rows {
        if r.record < records && time[r.record].is_nan() {
            time[r.record] = r.time;
            at.push((r.time, r.covariates.clone()));
        }
    }
    let series = Series::new(&at);
    let mut calibrations = Vec::with_capacity(reference.len());
    let mut z = Vec::with_capacity(reference.len());
    for mode in 0..reference.len() {
        match chart_mode(&mut rows, mode, records, &series, opts) {
            Ok(c) => {
                baselines.push(Some(c.baseline));
                baseline_errors.push(None);
                environments.push(Some(c.environment));
                residual_models.push(c.residual_model);
                alarms.extend(c.alarms);
                training_outliers.extend(c.outliers);
                calibrations.push(c.calibration);
                z.push(c.z);
            }
            Err(e) => {
                baselines.push(None);
                baseline_errors.push(Some(e.to_string()));
                environments.push(None);
                residual_models.push(None);
                calibrations.push(None);
                z.push(vec![f64::NAN; records]);
            }
        }
    }
    let (joint, joint_error) = if opts.joint && reference.len() > 1 {
        // Every mode regressed on the same terms (the union of their environmental
        // models), so that a term one mode's model took for an effect the modes share (a
        // breakpoint fitted to an episode of it) is taken by every mode in its proportion,
        // and stays along the shared direction after training.
        if let Some(union) = union_environment(&environments) {
            for (mode, zj) in z.iter_mut().enumerate() {
                if baselines[mode].is_some() {
                    let apart: Vec<usize> = training_outliers
                        .iter()
                        .filter(|o| o.mode == mode)
                        .map(|o| o.record)
                        .collect();
                    if let Some(common) =
                        residuals_on(&rows, mode, records, &union, &series, &apart, opts)
                    {
                        *zj = common;
                    }
                }
            }
        }
        match joint_chart(&z, &time, opts.training, &opts.chart, opts.calibrate) {
            Ok(j) => (Some(j), None),
            Err(e) => (None, Some(e.to_string())),
        }
    } else {
        (None, None)
    };
    alarms.sort_by(|a, b| a.record.cmp(&b.record).then(a.mode.cmp(&b.mode)));
    rows.sort_by(|a, b| a.record.cmp(&b.record).then(a.mode.cmp(&b.mode)));
    TrackReport {
        reference,
        rows,
        skipped: Vec::new(),
        harmonics: Vec::new(),
        new_modes: Vec::new(),
        split: Vec::new(),
        baselines,
        baseline_errors,
        noise_from_training: Vec::new(),
        environments,
        residual_models,
        tracked: Vec::new(),
        alarms,
        calibrations,
        joint,
        joint_error,
        training_outliers,
        in_control_run_length: opts.chart.in_control_run_length(),
        mode_names: (1..=reference_len).map(|j| j.to_string()).collect(),
        covariate_names: Vec::new(),
        subspace: None,
        subspace_error: None,
        level_covariate: false,
        monitored: Some(records.saturating_sub(opts.training)),
    }
}

/// Whether row `r` is one of `mode`'s that a chart takes: of a record of the campaign, with
/// a standard error and every covariate.
fn chartable(r: &TrackRow, mode: usize, records: usize) -> bool {
    r.mode == mode
        && r.record < records
        && r.frequency_se_hz.is_some()
        && r.covariates.iter().all(|v| v.is_finite())
}

/// A baseline with the frequencies and regressors it was fitted on.
type FittedBaseline = (Baseline, Vec<f64>, Vec<Vec<f64>>);

/// The baseline of the frequencies of `rows` on `environment`'s regressors, with the
/// frequencies and regressors it was fitted on.
fn baseline_of(
    rows: &[&TrackRow],
    environment: &Environment,
    series: &Series,
) -> Result<FittedBaseline, MonitorError> {
    let f: Vec<f64> = rows.iter().map(|r| r.frequency_hz).collect();
    let se: Vec<f64> = rows
        .iter()
        .map(|r| r.frequency_se_hz.unwrap_or(0.0))
        .collect();
    let x: Vec<Vec<f64>> = rows
        .iter()
        .map(|r| environment.features(series, r.time, &r.covariates))
        .collect();
    fit_baseline(&f, &se, &x).map(|b| (b, f, x))
}

/// The union of the modes' environmental models' terms (`None` when none has a term): one
/// term per covariate and lag, with the breakpoint or curvature any mode's model gave it
/// (the first's, when two gave it different ones: one regressor per covariate and lag, so
/// that the union is never collinear).
fn union_environment(environments: &[Option<Environment>]) -> Option<Environment> {
    let mut terms: Vec<crate::environment::Term> = Vec::new();
    for t in environments.iter().flatten().flat_map(|e| &e.terms) {
        match terms
            .iter_mut()
            .find(|u| u.covariate == t.covariate && u.lag_s == t.lag_s)
        {
            Some(u) => {
                if u.breakpoint.is_none() && u.quadratic_about.is_none() {
                    u.breakpoint = t.breakpoint;
                    u.quadratic_about = t.quadratic_about;
                }
            }
            None => terms.push(*t),
        }
    }
    (!terms.is_empty()).then(|| Environment {
        terms,
        bic_gain: 0.0,
        ranges: Vec::new(),
    })
}

/// `mode`'s standardized residual at every record (NaN where it has none) from a baseline
/// on the regressors of `environment`, fitted on its training rows but those set `apart`;
/// `None` when that baseline cannot be fitted.
fn residuals_on(
    rows: &[TrackRow],
    mode: usize,
    records: usize,
    environment: &Environment,
    series: &Series,
    apart: &[usize],
    opts: &TrackOptions,
) -> Option<Vec<f64>> {
    let usable = |r: &&TrackRow| chartable(r, mode, records) && !apart.contains(&r.record);
    let train: Vec<&TrackRow> = rows
        .iter()
        .filter(usable)
        .filter(|r| r.record < opts.training)
        .collect();
    let (b, _, _) = baseline_of(&train, environment, series).ok()?;
    let mut z = vec![f64::NAN; records];
    for r in rows.iter().filter(usable) {
        let x = environment.features(series, r.time, &r.covariates);
        z[r.record] = b
            .residual(r.frequency_hz, r.frequency_se_hz.unwrap_or(0.0), &x)
            .2;
    }
    Some(z)
}

/// Fit `mode`'s baseline on its training rows, standardize its later rows (setting their
/// `z`), whiten them by the slow unexplained effect's model when `opts.whiten` and the
/// training residuals hold one (setting `innovation`) and chart them (setting `alarm`); the
/// baseline, the environmental model, the slow effect's model and the alarms. `records`
/// counts the campaign's records: one missing the mode is a gap. `series`: every record's
/// covariates, for lagged values.
fn chart_mode(
    rows: &mut [TrackRow],
    mode: usize,
    records: usize,
    series: &Series,
    opts: &TrackOptions,
) -> Result<ModeChart, MonitorError> {
    // The mode's row of each record, if it has one with what the chart needs (a standard
    // error and every covariate).
    let mut row_of: Vec<Option<usize>> = vec![None; records];
    for (k, r) in rows.iter().enumerate() {
        if chartable(r, mode, records) {
            row_of[r.record] = Some(k);
        }
    }
    let training = opts.training.min(records);
    let train: Vec<usize> = row_of[..training].iter().flatten().copied().collect();
    let (b, env, outliers) = fit_training(rows, train, mode, series, opts)?;
    let features = |row: &TrackRow| env.features(series, row.time, &row.covariates);
    // Each record's residual (Hz) and the variance the baseline knows of (Hz²), for the
    // slow effect's model, and its standardized residual z; NaN where it has none (not
    // charted: a record without its covariates is tracked all the same).
    let mut r = vec![f64::NAN; records];
    let mut n = vec![f64::NAN; records];
    let mut z = vec![f64::NAN; records];
    for (t, k) in row_of.iter().enumerate() {
        if let Some(k) = k
            && !outliers.iter().any(|o| o.record == t)
        {
            let row = &rows[*k];
            let se = row.frequency_se_hz.unwrap_or(0.0);
            let x = features(row);
            (r[t], n[t], z[t]) = b.residual(row.frequency_hz, se, &x);
            rows[*k].extrapolated = env.extrapolated(&x);
        }
    }
    let later = &z[training..];
    let model = if opts.whiten {
        ResidualModel::fit(&r[..training], &n[..training])
    } else {
        None
    };
    let innovations = match &model {
        Some(m) => m.innovations(
            (&r[..training], &n[..training]),
            &r[training..],
            &n[training..],
        ),
        None => later.to_vec(),
    };
    // What the chart would have been given over the training records, to calibrate its
    // limit on.
    let calibration = if opts.calibrate {
        let trained = match &model {
            Some(m) => m.innovations((&[], &[]), &r[..training], &n[..training]),
            None => z[..training].to_vec(),
        };
        calibration::calibrate(&trained, &opts.chart, Sides::Both)
    } else {
        None
    };
    let chart = calibration
        .as_ref()
        .map_or(opts.chart, |c| c.chart(&opts.chart));
    for (i, (&v, &a)) in later.iter().zip(&innovations).enumerate() {
        if let Some(k) = row_of[training + i] {
            rows[k].z = v.is_finite().then_some(v);
            rows[k].innovation = a.is_finite().then_some(a);
        }
    }
    let mut alarms = Vec::new();
    for a in chart.alarms(&innovations) {
        let Some(k) = row_of[training + a.index] else {
            continue;
        };
        rows[k].alarm = Some(a.side);
        alarms.push(ModeAlarm {
            mode,
            record: rows[k].record,
            time: rows[k].time,
            side: a.side,
        });
    }
    Ok(ModeChart {
        baseline: b,
        environment: env,
        residual_model: model,
        alarms,
        outliers,
        calibration,
        z,
    })
}

/// What [`chart_mode`] finds for one mode.
struct ModeChart {
    baseline: Baseline,
    environment: Environment,
    residual_model: Option<ResidualModel>,
    alarms: Vec<ModeAlarm>,
    outliers: Vec<TrainingOutlier>,
    calibration: Option<Calibration>,
    /// Every record's standardized residual (NaN where it has none), the training
    /// records' in-sample: the joint chart's input.
    z: Vec<f64>,
}

/// The baseline of `mode` and its environmental model, fitted on the training rows `train`
/// (indices into `rows`) less those [`crate::training`] sets apart, which it returns.
fn fit_training(
    rows: &[TrackRow],
    train: Vec<usize>,
    mode: usize,
    series: &Series,
    opts: &TrackOptions,
) -> Result<(Baseline, Environment, Vec<TrainingOutlier>), MonitorError> {
    let outlier = |k: usize, rule| TrainingOutlier {
        mode,
        record: rows[k].record,
        frequency_hz: rows[k].frequency_hz,
        rule,
    };
    let all: Vec<f64> = train.iter().map(|&k| rows[k].frequency_hz).collect();
    let median_hz = training::median(&all);
    let (gross, mut train): (Vec<usize>, Vec<usize>) = train
        .into_iter()
        .partition(|&k| training::is_gross(rows[k].frequency_hz, median_hz));
    let mut outliers: Vec<TrainingOutlier> = gross
        .into_iter()
        .map(|k| outlier(k, OutlierRule::Gross { median_hz }))
        .collect();
    let q = train.first().map_or(0, |&k| rows[k].covariates.len());
    let env = if opts.environment && train.len() >= 20 {
        let data: Vec<(f64, Vec<f64>, f64)> = train
            .iter()
            .map(|&k| {
                (
                    rows[k].time,
                    rows[k].covariates.clone(),
                    rows[k].frequency_hz,
                )
            })
            .collect();
        Environment::choose(series, &data)
    } else {
        Environment::linear(q)
    };
    let fit = |train: &[usize]| {
        let picked: Vec<&TrackRow> = train.iter().map(|&k| &rows[k]).collect();
        baseline_of(&picked, &env, series)
    };
    let (mut b, f, x) = fit(&train)?;
    let residuals: Vec<f64> = f.iter().zip(&x).map(|(f, x)| f - b.predict(x).0).collect();
    let far = training::far_from_fit(&residuals);
    if far.iter().any(Option::is_some) {
        let mut kept = Vec::with_capacity(train.len());
        for (&k, z) in train.iter().zip(&far) {
            match z {
                Some(robust_z) => outliers.push(outlier(
                    k,
                    OutlierRule::FarFromFit {
                        robust_z: *robust_z,
                    },
                )),
                None => kept.push(k),
            }
        }
        train = kept;
        b = fit(&train)?.0;
    }
    outliers.sort_by_key(|o| o.record);
    Ok((b, env, outliers))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Records whose covariates are missing (NaN) are tracked but neither train nor are
    /// charted; the others are.
    #[test]
    fn records_without_covariates_are_tracked_not_charted() {
        let records: Vec<RecordModes> = (0..40)
            .map(|i| {
                let t = (i % 7) as f64;
                let f = 2.0 + 0.01 * t + 1e-4 * ((i * 37 % 11) as f64 - 5.0);
                let missing = i == 5 || i == 30;
                RecordModes {
                    name: i.to_string(),
                    time: i as f64,
                    covariates: vec![if missing { f64::NAN } else { t }],
                    outcome: Ok(Identified {
                        modes: vec![ModeEstimate {
                            frequency_hz: f,
                            frequency_se_hz: Some(1e-4),
                            damping_ratio: 0.01,
                            damping_se: Some(1e-3),
                            shape: None,
                        }],
                        misfit: Some(0.01),
                        ..Default::default()
                    }),
                }
            })
            .collect();
        let opts = TrackOptions {
            training: 20,
            ..TrackOptions::default()
        };
        let report = track(&records, None, &opts).unwrap();
        assert_eq!(report.rows.len(), 40);
        assert_eq!(report.baselines[0].as_ref().map(|b| b.records), Some(19));
        let z = |i: usize| report.rows[i].z;
        assert!(z(30).is_none() && z(29).is_some() && z(31).is_some());
        assert!(report.alarms.is_empty(), "{:?}", report.alarms);
    }
}
