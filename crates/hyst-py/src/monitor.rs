//! `hyst.track` from Python: records given as arrays, identified and tracked by
//! `hyst_monitor`, the report returned as `hyst track` prints and writes it.

use numpy::PyReadonlyArray2;
use pyo3::prelude::*;

use hyst::monitor::{Loaded, RecordModes};
use hyst::settings::TrackSettings;

use crate::ident::{Report, value_error};

/// Track another system's modal estimates (`hyst track --estimates`); see the Python
/// wrapper `hyst.track_estimates`.
#[pyfunction]
#[pyo3(signature = (estimates, *, covariates, tracking))]
pub(crate) fn track_estimates(
    py: Python<'_>,
    estimates: std::path::PathBuf,
    covariates: Option<std::path::PathBuf>,
    tracking: &str,
) -> PyResult<Report> {
    let tracking = tracking_settings(tracking)?;
    let table = hyst::io::read_estimates(&estimates).map_err(value_error)?;
    let covariates = match covariates {
        Some(p) => hyst::io::read_covariates(&p).map_err(value_error)?,
        None => Default::default(),
    };
    let records = table.records(&covariates);
    let opts = tracking.options(records.len());
    let mut report = py
        .detach(|| hyst::monitor::track_estimates(&records, &table.modes, &opts))
        .map_err(value_error)?;
    report.name_covariates(covariates.1);
    let page = hyst::html::track_page(&report);
    Report::of(&estimates.display().to_string(), report).map(|r| r.with_html(page))
}

/// Track the modes of `records` (each samples × channels); see the Python wrapper
/// `hyst.track`.
#[pyfunction]
#[pyo3(signature = (records, fs, *, times, covariates, covariate_names, settings, tracking, reference, names=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn track(
    py: Python<'_>,
    records: Vec<PyReadonlyArray2<'_, f64>>,
    fs: f64,
    times: Vec<f64>,
    covariates: Vec<Vec<f64>>,
    covariate_names: Vec<String>,
    settings: &str,
    tracking: &str,
    reference: Option<&str>,
    names: Option<Vec<String>>,
) -> PyResult<Report> {
    let n = records.len();
    if times.len() != n || covariates.len() != n {
        return Err(value_error(format!(
            "{n} records but {} times and {} rows of covariates",
            times.len(),
            covariates.len()
        )));
    }
    // The columns copied out of the arrays while the GIL is held; then the work without it,
    // each record's copy handed over when it is loaded (once) and freed when it is done.
    let data: Vec<std::sync::Mutex<Vec<Vec<f64>>>> = records
        .iter()
        .map(|r| {
            std::sync::Mutex::new(
                r.as_array()
                    .columns()
                    .into_iter()
                    .map(|c| c.to_vec())
                    .collect(),
            )
        })
        .collect();
    let names: Vec<String> = names.unwrap_or_else(|| (0..n).map(|i| i.to_string()).collect());
    if names.len() != n {
        return Err(value_error(format!(
            "{n} records but {} names",
            names.len()
        )));
    }
    let analysis = crate::analysis_options(settings)?;
    let load = |i: usize| -> Result<Loaded, String> {
        Ok(Loaded {
            channels: std::mem::take(&mut *data[i].lock().map_err(|e| e.to_string())?),
            fs,
            time: times[i],
            covariates: covariates[i].clone(),
        })
    };
    // As `hyst track`: what the options leave to the record read once, from the first
    // record that gives it, and kept for every record.
    let resolve = |i: usize| {
        let held = data[i].lock().ok()?;
        let views: Vec<&[f64]> = held.iter().map(|c| c.as_slice()).collect();
        analysis.resolved_for(&views, fs).ok()
    };
    let (analysis, _) = hyst::monitor::campaign_analysis(&analysis, n, &resolve);
    // A bad reference said before the records are identified.
    let campaign = Campaign::new(covariate_names, tracking, reference)?;
    // Each record identified moves the terminal's progress line (as `hyst track`'s bar).
    let done = std::sync::atomic::AtomicUsize::new(0);
    let finished = |_: &hyst::monitor::RecordModes| {
        let k = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        crate::to_terminal(&format!("{k}/{n} records identified"));
    };
    let identified = py.detach(|| {
        let identified = hyst::monitor::identify_records(&names, &load, &analysis, &[], &finished);
        crate::to_terminal("");
        identified
    });
    campaign.track(py, &identified)
}

/// How identified records are tracked: what `hyst.track` is given besides the records.
pub(crate) struct Campaign {
    covariate_names: Vec<String>,
    tracking: TrackSettings,
    reference: Option<Vec<hyst::monitor::ModeEstimate>>,
}

impl Campaign {
    /// The campaign's tracking, `reference` a `hyst ssi --json` document (read here: a bad
    /// one is said before any record is identified).
    /// `tracking` is a JSON object of [`TrackSettings`].
    pub(crate) fn new(
        covariate_names: Vec<String>,
        tracking: &str,
        reference: Option<&str>,
    ) -> PyResult<Campaign> {
        let tracking = tracking_settings(tracking)?;
        let reference = reference
            .map(hyst::report::reference_modes)
            .transpose()
            .map_err(|e| value_error(format!("reference: {e}")))?;
        Ok(Campaign {
            covariate_names,
            tracking,
            reference,
        })
    }

    /// Track `records` (identified, in time order): the report `hyst.track` returns.
    pub(crate) fn track(self, py: Python<'_>, records: &[RecordModes]) -> PyResult<Report> {
        let opts = self.tracking.options(records.len());
        let reference = self.reference.as_deref();
        let mut report = py
            .detach(|| hyst::monitor::track(records, reference, &opts))
            .map_err(value_error)?;
        report.name_covariates(self.covariate_names);
        let page = hyst::html::track_page(&report);
        let lines = report.alarm_lines();
        Report::of("records", report).map(|r| r.with_html(page).with_alarm_lines(lines))
    }
}

/// The tracking a JSON object of [`TrackSettings`] asks for; what is wrong as a `ValueError`.
fn tracking_settings(text: &str) -> PyResult<TrackSettings> {
    TrackSettings::from_json(text).map_err(|e| value_error(format!("tracking: {e}")))
}
