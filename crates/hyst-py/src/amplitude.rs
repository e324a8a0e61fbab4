//! `hyst.amplitude` from Python: the channels as an array, the analysis as `hyst amplitude`
//! runs it, the report returned as the command prints and writes it.

use numpy::PyReadonlyArray2;
use pyo3::prelude::*;

use crate::ident::{Report, value_error};

/// Each mode's frequency and damping against its amplitude; see the Python wrapper
/// `hyst.amplitude`. `settings`: the SSI settings' JSON; `options`: the
/// `AmplitudeOptions`' JSON.
#[pyfunction]
#[pyo3(signature = (y, fs, *, settings, options, modes, record))]
pub(crate) fn amplitude(
    py: Python<'_>,
    y: PyReadonlyArray2<'_, f64>,
    fs: f64,
    settings: &str,
    options: &str,
    modes: Vec<f64>,
    record: &str,
) -> PyResult<Report> {
    let analysis = crate::analysis_options(settings)?;
    let opts: hyst::ident::amplitude::AmplitudeOptions =
        serde_json::from_str(options).map_err(value_error)?;
    let view = y.as_array();
    let cols = crate::columns(&view);
    let views: Vec<&[f64]> = cols.iter().map(|c| c.as_ref()).collect();
    let result = py
        .detach(|| hyst::ident::amplitude::amplitude_analysis(&views, fs, &analysis, &opts, &modes))
        .map_err(value_error)?;
    Report::of(record, result)
}
