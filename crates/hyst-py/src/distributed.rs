//! `hyst.track(..., client=...)`: the campaign's steps as pieces a cluster runs apart — the
//! analysis read from a record, one record identified (on a worker, from the file it read),
//! and the tracking of the gathered records — each the step `hyst.track` and `hyst track`
//! run, so that the report is theirs. Records travel between them as `RecordModes` JSON.

use numpy::PyReadonlyArray2;
use pyo3::prelude::*;

use hyst::monitor::RecordModes;

use crate::ident::{Report, value_error};

/// The columns of a (samples × channels) array.
fn columns(record: &PyReadonlyArray2<'_, f64>) -> Vec<Vec<f64>> {
    record
        .as_array()
        .columns()
        .into_iter()
        .map(|c| c.to_vec())
        .collect()
}

/// The analysis `settings` ask for with what they leave to the record read from `record`
/// (as JSON), or `None` when this record cannot give it; without a record, the analysis as
/// the settings give it.
#[pyfunction]
#[pyo3(signature = (record, fs, settings))]
pub(crate) fn resolve_analysis(
    record: Option<PyReadonlyArray2<'_, f64>>,
    fs: f64,
    settings: &str,
) -> PyResult<Option<String>> {
    let analysis = crate::analysis_options(settings)?;
    let resolved = match record {
        None => Some(analysis),
        Some(r) => {
            let data = columns(&r);
            let views: Vec<&[f64]> = data.iter().map(|c| c.as_slice()).collect();
            analysis.resolved_for(&views, fs).ok()
        }
    };
    resolved
        .map(|a| serde_json::to_string(&a).map_err(value_error))
        .transpose()
}

/// The campaign's analysis (JSON): the analysis `settings` ask for with what they leave to
/// the record read by [`hyst::monitor::campaign_analysis`]'s rule (the first of the first
/// records that gives it), `resolve(i)` giving record i's as [`resolve_analysis`] does (on a
/// worker), JSON or `None`. An exception `resolve` raises is raised here.
#[pyfunction]
#[pyo3(signature = (settings, records, resolve))]
pub(crate) fn campaign_analysis(
    settings: &str,
    records: usize,
    resolve: Bound<'_, PyAny>,
) -> PyResult<String> {
    let analysis = crate::analysis_options(settings)?;
    let failed: std::cell::RefCell<Option<PyErr>> = std::cell::RefCell::new(None);
    let read = |i: usize| -> Option<covssi::AnalysisOptions> {
        if failed.borrow().is_some() {
            return None;
        }
        let given = resolve
            .call1((i,))
            .and_then(|v| v.extract::<Option<String>>())
            .and_then(|json| {
                json.map(|j| serde_json::from_str(&j).map_err(value_error))
                    .transpose()
            });
        given.unwrap_or_else(|e| {
            *failed.borrow_mut() = Some(e);
            None
        })
    };
    let (fixed, _) = hyst::monitor::campaign_analysis(&analysis, records, &read);
    if let Some(e) = failed.into_inner() {
        return Err(e);
    }
    serde_json::to_string(&fixed).map_err(value_error)
}

/// One record identified with the analysis `analysis` (JSON, from [`resolve_analysis`]),
/// as a `RecordModes` JSON document; a record that could not be read (`record` None) is
/// kept with the reason `why`, as `hyst track` keeps it.
#[pyfunction]
#[pyo3(signature = (record, fs, time, covariates, name, analysis, why=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn identify_record(
    py: Python<'_>,
    record: Option<PyReadonlyArray2<'_, f64>>,
    fs: f64,
    time: f64,
    covariates: Vec<f64>,
    name: String,
    analysis: &str,
    why: Option<String>,
) -> PyResult<String> {
    let analysis: covssi::AnalysisOptions =
        serde_json::from_str(analysis).map_err(|e| value_error(format!("analysis: {e}")))?;
    let outcome = match record {
        Some(r) => {
            let data = columns(&r);
            py.detach(|| {
                let views: Vec<&[f64]> = data.iter().map(|c| c.as_slice()).collect();
                hyst::monitor::identify_record(&views, fs, &analysis).map_err(|e| e.to_string())
            })
        }
        None => Err(why.unwrap_or_else(|| "not read".into())),
    };
    let r = RecordModes {
        name,
        time,
        covariates,
        outcome,
    };
    serde_json::to_string(&r).map_err(value_error)
}

/// A campaign's record files as `hyst track --inputs … --covariates …` takes them: the files
/// of `inputs` (files, or folders whose files are taken in name order) put in time order by
/// the covariates file when it times every one ([`hyst::campaign::order_records`]), each as
/// (path, name, time, covariates, why it has no record: a gap the covariates file times);
/// and the covariates' names.
#[pyfunction]
#[pyo3(signature = (inputs, covariates=None))]
#[allow(clippy::type_complexity)]
pub(crate) fn campaign_records(
    inputs: Vec<std::path::PathBuf>,
    covariates: Option<std::path::PathBuf>,
) -> PyResult<(
    Vec<(String, String, f64, Vec<f64>, Option<String>)>,
    Vec<String>,
)> {
    let files = hyst::io::list_records(&inputs).map_err(value_error)?;
    let covariates = match covariates {
        Some(p) => hyst::io::read_covariates(&p).map_err(value_error)?,
        None => Default::default(),
    };
    let ordered = hyst::campaign::order_records(files, &covariates);
    let rows = ordered
        .files
        .iter()
        .enumerate()
        .map(|(i, f)| {
            let name = f.file_name().map_or_else(
                || f.display().to_string(),
                |n| n.to_string_lossy().into_owned(),
            );
            let (time, x) = hyst::campaign::covariates_of(&covariates, &name, i as f64);
            let gap = ordered
                .gaps
                .contains(&name)
                .then(|| hyst::campaign::GAP_REASON.to_string());
            (f.display().to_string(), name, time, x, gap)
        })
        .collect();
    Ok((rows, covariates.1))
}

/// Track records identified apart (each a `RecordModes` JSON document, in time order), as
/// `hyst.track` tracks the records it identifies.
#[pyfunction]
#[pyo3(signature = (records, *, covariate_names, tracking, reference))]
pub(crate) fn track_identified(
    py: Python<'_>,
    records: Vec<String>,
    covariate_names: Vec<String>,
    tracking: &str,
    reference: Option<&str>,
) -> PyResult<Report> {
    let records = records
        .iter()
        .enumerate()
        .map(|(i, r)| {
            serde_json::from_str::<RecordModes>(r)
                .map_err(|e| value_error(format!("record {i}: {e}")))
        })
        .collect::<PyResult<Vec<_>>>()?;
    crate::monitor::Campaign::new(covariate_names, tracking, reference)?.track(py, &records)
}
