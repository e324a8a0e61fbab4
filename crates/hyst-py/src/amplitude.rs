//! `hyst.amplitude` from Python: the channels as arrays, the analysis as `hyst amplitude`
//! runs it, the report returned as the command prints and writes it.

use numpy::PyReadonlyArray2;
use pyo3::prelude::*;

use crate::ident::{Report, value_error};

/// Each mode's frequency and damping against its amplitude, in each record of `ys` (one:
/// its analysis; several: the campaign, as `hyst amplitude --input A B ...`); see the
/// Python wrapper `hyst.amplitude`. `settings`: the SSI settings' JSON; `options`: the
/// `AmplitudeOptions`' JSON; `records`: the records' names.
#[pyfunction]
#[pyo3(signature = (ys, fs, *, settings, options, modes, records))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn amplitude(
    py: Python<'_>,
    ys: Vec<PyReadonlyArray2<'_, f64>>,
    fs: f64,
    settings: &str,
    options: &str,
    modes: Vec<f64>,
    records: Vec<String>,
) -> PyResult<Report> {
    let analysis = crate::analysis_options(settings)?;
    let opts: hyst::ident::amplitude::AmplitudeOptions =
        serde_json::from_str(options).map_err(value_error)?;
    if records.len() != ys.len() || ys.is_empty() {
        return Err(value_error(format!(
            "{} record(s) but {} name(s)",
            ys.len(),
            records.len()
        )));
    }
    let data: Vec<Vec<Vec<f64>>> = ys
        .iter()
        .map(|y| {
            y.as_array()
                .columns()
                .into_iter()
                .map(|c| c.to_vec())
                .collect()
        })
        .collect();
    let mut campaign = py
        .detach(|| {
            hyst::ident::amplitude::amplitude_campaign(data.len(), &modes, |i, follow| {
                let views: Vec<&[f64]> = data[i].iter().map(|c| c.as_slice()).collect();
                let a = hyst::ident::amplitude::amplitude_analysis(
                    &views, fs, &analysis, &opts, follow,
                )
                .map_err(|e| e.in_record(&records[i]))?;
                Ok::<_, hyst::ident::IdentError>((records[i].clone(), a))
            })
        })
        .map_err(value_error)?;
    if campaign.records.len() == 1 {
        let (record, analysis) = campaign.records.remove(0);
        return Report::of(&record, analysis);
    }
    Report::of("records", campaign)
}
