//! Python bindings of hyst: the extension module `hyst._hyst`, which the Python package
//! `hyst` (`python/hyst/`) wraps.
//!
//! One job: hand numpy arrays to the library and its results back as numpy arrays, with no
//! decision of its own. `ssi` runs [`covssi::analyze`] (SSI-COV, then the maximum-likelihood
//! refinement) on the columns of a `(samples, channels)` float64 array, with the GIL released;
//! a Fortran-ordered array's columns are read in place, a C-ordered one's are copied once.
//! Errors are the library's, raised as `ValueError` with its message. `SsiResult.to_dict()`
//! is the same JSON document `hyst ssi --json` writes (the library's types serialized, then
//! parsed by Python's `json`).

use std::borrow::Cow;

mod amplitude;
mod distributed;
mod ident;
mod monitor;

use covssi::ModalAnalysis;
use hyst::settings::SsiSettings;
use numpy::ndarray::{Array1, Array2, ShapeBuilder};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// What `hyst.ssi` found: SSI's stabilization diagram, modes and real poles, and the
/// maximum-likelihood refinement of them.
#[pyclass(module = "hyst", name = "SsiResult", frozen)]
struct SsiResult {
    analysis: ModalAnalysis,
    record: String,
}

impl SsiResult {
    /// The refinement when its modes are the ones reported (it ran, found modes, and the
    /// record follows its model); `None` when SSI's are.
    fn refined(&self) -> Option<&covssi::Refinement> {
        self.analysis.reported_refinement()
    }

    /// One value per reported mode ([`covssi::ModeDecision::modes`]).
    fn per_mode<'py>(
        &self,
        py: Python<'py>,
        value: impl Fn(&covssi::ReportedMode) -> f64,
    ) -> Bound<'py, PyArray1<f64>> {
        let v: Vec<f64> = self.analysis.decision.modes.iter().map(value).collect();
        Array1::from(v).into_pyarray(py)
    }

    /// The reported modes' shapes or their errors (modes × channels); `missing` where a
    /// mode has none.
    fn per_entry<T: Copy + numpy::Element>(
        &self,
        entries: impl Fn(&covssi::ReportedMode) -> Option<Vec<T>>,
        missing: T,
    ) -> Array2<T> {
        let l = self.analysis.ssi.diagram.channels;
        let rows: Vec<Vec<T>> = self
            .analysis
            .decision
            .modes
            .iter()
            .map(|m| entries(m).unwrap_or_else(|| vec![missing; l]))
            .collect();
        Array2::from_shape_fn((rows.len(), l), |(i, c)| rows[i][c])
    }
}

#[pymethods]
impl SsiResult {
    /// "refined" when the modes reported are the maximum-likelihood refinement's (it holds:
    /// every SSI mode kept has its agreeing refined counterpart), "ssi" when they are SSI's
    /// (see `decision` in `to_dict()` for why, and what was set apart).
    #[getter]
    fn source(&self) -> &'static str {
        match self.analysis.decision.source {
            covssi::ModeSource::Refined => "refined",
            _ => "ssi",
        }
    }

    /// Natural frequency of each reported mode (Hz), increasing.
    #[getter]
    fn frequency_hz<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.per_mode(py, |m| m.frequency_hz)
    }

    /// Damping ratio of each reported mode.
    #[getter]
    fn damping_ratio<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.per_mode(py, |m| m.damping_ratio)
    }

    /// Standard error of each frequency (Hz): the refinement's, or the jackknife's for
    /// SSI's modes; NaN where none was made (`ssi_errors=0`).
    #[getter]
    fn frequency_se_hz<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.per_mode(py, |m| m.frequency_se_hz.unwrap_or(f64::NAN))
    }

    /// Standard error of each damping ratio, as `frequency_se_hz`'s.
    #[getter]
    fn damping_se<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.per_mode(py, |m| m.damping_se.unwrap_or(f64::NAN))
    }

    /// Each reported mode's shape (modes × channels, complex, its largest entry 1).
    #[getter]
    fn shape<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<covssi::Complex64>> {
        let nan = covssi::Complex64::new(f64::NAN, f64::NAN);
        self.per_entry(|m| m.shape.clone(), nan).into_pyarray(py)
    }

    /// Standard error of each shape entry (modes × channels); NaN where none was made.
    #[getter]
    fn shape_se<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        self.per_entry(|m| m.shape_se.clone(), f64::NAN)
            .into_pyarray(py)
    }

    /// SSI's modes: frequency (Hz) and damping ratio, columns of a (modes × 2) array.
    #[getter]
    fn ssi_modes<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let m = &self.analysis.ssi.modes;
        Array2::from_shape_fn((m.len(), 2), |(i, j)| {
            [m[i].frequency_hz, m[i].damping_ratio][j]
        })
        .into_pyarray(py)
    }

    /// The real poles λ (rad/s, negative): the refined ones kept when the modes reported are
    /// refined, else SSI's clusters'.
    #[getter]
    fn real_poles<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let v: Vec<f64> = match self.refined() {
            Some(r) => r.real_poles.iter().map(|p| p.lambda).collect(),
            None => self
                .analysis
                .ssi
                .real_poles
                .iter()
                .map(|p| p.lambda)
                .collect(),
        };
        Array1::from(v).into_pyarray(py)
    }

    /// The stabilization diagram's poles, one row per pole: model order, frequency (Hz),
    /// damping ratio (a (poles × 3) array); their labels are [`Self::pole_status`].
    #[getter]
    fn poles<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let rows: Vec<[f64; 3]> = self
            .analysis
            .ssi
            .diagram
            .orders
            .iter()
            .flat_map(|o| {
                o.poles
                    .iter()
                    .map(move |p| [o.order as f64, p.frequency_hz, p.damping_ratio])
            })
            .collect();
        Array2::from_shape_fn((rows.len(), 3), |(i, j)| rows[i][j]).into_pyarray(py)
    }

    /// Each pole's label, in the order of [`Self::poles`]: `stable_f`, `stable_fd`,
    /// `stable_fdm`, `stable_real` or `rejected_<criterion>`.
    #[getter]
    fn pole_status(&self) -> Vec<&'static str> {
        self.analysis
            .ssi
            .diagram
            .orders
            .iter()
            .flat_map(|o| o.poles.iter().map(|p| p.status.name()))
            .collect()
    }

    /// The refinement's misfit (Kolmogorov–Smirnov distance; above 0.05 the record does not
    /// follow the model and SSI's modes are reported), or None when it did not run.
    #[getter]
    fn misfit(&self) -> Option<f64> {
        self.analysis.refined.as_ref().map(|r| r.misfit)
    }

    /// Why the refinement asked for gave no result, or None.
    #[getter]
    fn not_refined(&self) -> Option<String> {
        self.analysis.not_refined.clone()
    }

    /// The result as the JSON document `hyst ssi --json` writes.
    fn to_json(&self) -> PyResult<String> {
        let report = hyst::report::FileReport::new(self.record.clone(), &self.analysis);
        serde_json::to_string(&report).map_err(|e| PyValueError::new_err(e.to_string()))
    }

    /// The result as the dictionary of `hyst ssi --json`'s document (the same keys and
    /// values).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let json = self.to_json()?;
        py.import("json")?.call_method1("loads", (json,))
    }

    /// The report a browser opens (`hyst ssi --html`): one self-contained page with the
    /// stabilization diagram over the FDD singular values, the modes with their errors and
    /// EFDD's, each mode shape animated, and the MAC matrix.
    #[pyo3(signature = (title = None))]
    fn html(&self, title: Option<&str>) -> String {
        let title = title.map_or_else(|| format!("hyst.ssi: {}", self.record), str::to_string);
        hyst::html::ssi_page(&title, &self.analysis)
    }

    /// Write the reported modes' shapes as Universal File dataset 55 at `path`: one dataset
    /// per mode (its complex eigenvalue, and per node the X, Y, Z entries). `points` places
    /// each channel, as (node, direction) pairs in the Universal File's numbering (±1 ±2 ±3
    /// for ±X ±Y ±Z; `hyst.read` gives a Universal File's); without them channel c is node
    /// c + 1 along Z. A mode the refinement gave no shape is left out.
    #[pyo3(signature = (path, points = None, description = None))]
    fn write_shapes_uff(
        &self,
        path: std::path::PathBuf,
        points: Option<Vec<(i64, i32)>>,
        description: Option<&str>,
    ) -> PyResult<()> {
        let modes = self.analysis.reported_modes();
        let shapes: Vec<hyst::io::ShapeMode<'_>> = modes
            .iter()
            .filter_map(|m| {
                Some(hyst::io::ShapeMode {
                    frequency_hz: m.frequency_hz,
                    damping_ratio: m.damping_ratio,
                    shape: m.shape.as_deref()?,
                })
            })
            .collect();
        let points: Option<Vec<hyst::io::MeasurementPoint>> = points.map(|p| {
            p.into_iter()
                .map(|(node, direction)| hyst::io::MeasurementPoint { node, direction })
                .collect()
        });
        hyst::io::write_shapes_uff(
            &path,
            &shapes,
            points.as_deref(),
            description.unwrap_or(&self.record),
        )
        .map_err(|e| PyValueError::new_err(e.to_string()))
    }

    /// The report `hyst ssi` prints.
    fn __str__(&self) -> String {
        self.analysis.to_string()
    }

    fn __repr__(&self) -> String {
        let modes = self.analysis.decision.modes.len();
        format!(
            "<SsiResult: {modes} mode(s), {}, {} channel(s) at {} Hz>",
            self.source(),
            self.analysis.ssi.diagram.channels,
            self.analysis.fs_hz
        )
    }
}

/// The columns of `y` (samples × channels) as slices: in place when each is contiguous
/// (a Fortran-ordered array), else copied.
pub(crate) fn columns<'a>(y: &'a numpy::ndarray::ArrayView2<'a, f64>) -> Vec<Cow<'a, [f64]>> {
    y.columns()
        .into_iter()
        .map(|c| match c.to_slice() {
            Some(s) => Cow::Borrowed(s),
            None => Cow::Owned(c.to_vec()),
        })
        .collect()
}

/// SSI-COV and the maximum-likelihood refinement of the channels `y` (float64, samples ×
/// channels) sampled at `fs` Hz, with `settings` a JSON object of [`SsiSettings`] (what
/// the Python wrapper `hyst.ssi` makes of its keywords).
#[pyfunction]
#[pyo3(signature = (y, fs, *, settings, channels = None, record = "array", fdd = false))]
fn ssi(
    py: Python<'_>,
    y: PyReadonlyArray2<'_, f64>,
    fs: f64,
    settings: &str,
    channels: Option<Vec<String>>,
    record: &str,
    fdd: bool,
) -> PyResult<SsiResult> {
    let view = y.as_array();
    let l = view.ncols();
    if let Some(names) = &channels
        && names.len() != l
    {
        return Err(PyValueError::new_err(format!(
            "channels names {} channel(s), the array has {l}",
            names.len()
        )));
    }
    let opts = analysis_options(settings)?.with_fdd(fdd.then(covssi::fdd::FddOptions::default));
    let cols = columns(&view);
    let views: Vec<&[f64]> = cols.iter().map(|c| c.as_ref()).collect();
    let mut analysis = py
        .detach(|| {
            let a = covssi::analyze_with_progress(&views, fs, &opts, &terminal_progress);
            clear_terminal_progress();
            a
        })
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    if let Some(names) = channels {
        analysis.channels = names;
    }
    Ok(SsiResult {
        analysis,
        record: record.to_string(),
    })
}

/// Several setups of one test, described by the setup file (or pyOMA folder) `path`, each
/// identified with `settings` at `fs` Hz (or each record's or setup's stated rate) and merged:
/// `hyst ssi --setups`; see the Python wrapper `hyst.ssi`.
#[pyfunction]
#[pyo3(signature = (path, fs, *, settings, geometry = None, lines = None, records_anywhere = false, rigid_floors = false))]
#[allow(clippy::too_many_arguments)]
fn ssi_setups(
    py: Python<'_>,
    path: std::path::PathBuf,
    fs: Option<f64>,
    settings: &str,
    geometry: Option<std::path::PathBuf>,
    lines: Option<std::path::PathBuf>,
    records_anywhere: bool,
    rigid_floors: bool,
) -> PyResult<ident::Report> {
    let opts = SsiSettings::from_json(settings)
        .and_then(|s| s.analysis())
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    let (report, page) = py
        .detach(|| {
            let paths = if records_anywhere {
                hyst::io::RecordPaths::Anywhere
            } else {
                hyst::io::RecordPaths::InsideFolder
            };
            let setups = hyst::io::read_setups_with(&path, paths)?;
            let mut report = hyst::setups::analyze_setups(
                &setups,
                fs,
                &hyst::io::ReadOptions::default(),
                &opts,
                &covssi::multisetup::MergeOptions::default(),
            )?;
            let g = hyst::io::setups_geometry(&path, geometry.as_deref(), lines.as_deref())?;
            if rigid_floors {
                let Some((positions, _)) = &g else {
                    return Ok(Err(
                        "rigid_floors needs the nodes' positions: a pyOMA folder's grid.txt, or geometry=",
                    ));
                };
                report.floor_factors =
                    hyst::rigid_floors::floor_factors(&report.merged, positions);
            }
            // The command's title: the same page as `hyst ssi --setups --html`.
            let title = format!("hyst ssi --setups {}", path.display());
            let g = g.as_ref().map(|(g, p)| (g, p.as_path()));
            let page = hyst::html::setups_page(&title, &report, g)?;
            Ok::<_, hyst::setups::SetupsError>(Ok((report, page)))
        })
        .map_err(|e| PyValueError::new_err(e.to_string()))?
        .map_err(PyValueError::new_err)?;
    ident::Report::of(&path.display().to_string(), report).map(|r| r.with_html(page))
}

/// What `read_record` gives: the data (samples × channels), the column names, the sampling
/// rate the file states or its time column gives, and each channel's (node, direction) if the file gives them.
type RecordParts<'py> = (
    Bound<'py, PyArray2<f64>>,
    Vec<String>,
    Option<f64>,
    Option<Vec<(i64, i32)>>,
);

/// The record at `path`, read as `hyst ssi --input` reads it; see the Python wrapper
/// `hyst.read`.
#[pyfunction]
#[pyo3(signature = (path, format = None, variable = None, delimiter = None))]
fn read_record<'py>(
    py: Python<'py>,
    path: std::path::PathBuf,
    format: Option<&str>,
    variable: Option<String>,
    delimiter: Option<&str>,
) -> PyResult<RecordParts<'py>> {
    use hyst::io::{Delimiter, Format, ReadOptions};
    let named = |e: hyst::io::IoError| PyValueError::new_err(e.to_string());
    let format: Format = format.map_or(Ok(Format::Auto), str::parse).map_err(named)?;
    let delimiter: Delimiter = delimiter
        .map_or(Ok(Delimiter::Auto), str::parse)
        .map_err(named)?;
    let opts = ReadOptions::default()
        .with_format(format)
        .with_delimiter(delimiter)
        .with_variable(variable);
    let table = py
        .detach(|| hyst::io::read_record(&path, &opts))
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    let (n, l) = (table.len(), table.columns.len());
    // Column-major, one column after another: the array is Fortran-ordered, which
    // `hyst.ssi` then reads in place.
    let flat: Vec<f64> = table.columns.concat();
    let data = Array2::from_shape_vec((n, l).f(), flat)
        .map_err(|e| PyValueError::new_err(e.to_string()))?
        .into_pyarray(py);
    // The file's rate: stated (a Universal File), else its time column's step.
    let fs = table.rate(None).ok();
    let points = table
        .points
        .map(|p| p.iter().map(|q| (q.node, q.direction)).collect());
    Ok((data, table.names, fs, points))
}

/// What `read_shapes_uff` gives: the nodes (number, x, y, z) and each mode (number,
/// frequency, damping ratio, node numbers, each node's x, y, z motion as a complex array).
type ShapesParts<'py> = (
    Vec<(i64, [f64; 3])>,
    Vec<(
        i64,
        f64,
        f64,
        Vec<i64>,
        Bound<'py, PyArray2<hyst::covssi::Complex64>>,
    )>,
);

/// The mode shapes and nodes of a Universal File (datasets 55, and 15 or 2411); see the
/// Python wrapper `hyst.read_shapes`.
#[pyfunction]
fn read_shapes_uff<'py>(py: Python<'py>, path: std::path::PathBuf) -> PyResult<ShapesParts<'py>> {
    let shapes = py
        .detach(|| hyst::io::read_shapes_uff(&path))
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    let modes = shapes
        .modes
        .into_iter()
        .map(|m| {
            let nodes = m.motions.iter().map(|(n, _)| *n).collect();
            let flat: Vec<hyst::covssi::Complex64> = m
                .motions
                .iter()
                .flat_map(|(_, v)| v.iter().copied())
                .collect();
            let motion = Array2::from_shape_vec((m.motions.len(), 3), flat)
                .map_err(|e| PyValueError::new_err(e.to_string()))?
                .into_pyarray(py);
            Ok((m.number, m.frequency_hz, m.damping_ratio, nodes, motion))
        })
        .collect::<PyResult<_>>()?;
    Ok((shapes.nodes, modes))
}

/// The extension module: `hyst._hyst`.
#[pymodule]
fn _hyst(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(ssi, m)?)?;
    m.add_function(wrap_pyfunction!(ssi_setups, m)?)?;
    m.add_function(wrap_pyfunction!(read_record, m)?)?;
    m.add_function(wrap_pyfunction!(read_shapes_uff, m)?)?;
    m.add_function(wrap_pyfunction!(ident::simulate, m)?)?;
    m.add_function(wrap_pyfunction!(ident::simulate_structure, m)?)?;
    m.add_function(wrap_pyfunction!(ident::excite, m)?)?;
    m.add_function(wrap_pyfunction!(ident::identify, m)?)?;
    m.add_function(wrap_pyfunction!(ident::refine, m)?)?;
    m.add_function(wrap_pyfunction!(ident::levels, m)?)?;
    m.add_function(wrap_pyfunction!(ident::storeys, m)?)?;
    m.add_function(wrap_pyfunction!(monitor::track, m)?)?;
    m.add_function(wrap_pyfunction!(monitor::track_estimates, m)?)?;
    m.add_function(wrap_pyfunction!(amplitude::amplitude, m)?)?;
    m.add_function(wrap_pyfunction!(distributed::resolve_analysis, m)?)?;
    m.add_function(wrap_pyfunction!(distributed::campaign_analysis, m)?)?;
    m.add_function(wrap_pyfunction!(distributed::identify_record, m)?)?;
    m.add_function(wrap_pyfunction!(distributed::track_identified, m)?)?;
    m.add_function(wrap_pyfunction!(distributed::campaign_records, m)?)?;
    m.add_class::<ident::Report>()?;
    m.add_class::<SsiResult>()?;
    Ok(())
}

/// The analysis a JSON object of [`SsiSettings`] asks for; what is wrong as a `ValueError`.
pub(crate) fn analysis_options(settings: &str) -> PyResult<covssi::AnalysisOptions> {
    SsiSettings::from_json(settings)
        .and_then(|s| s.analysis())
        .map_err(|e| PyValueError::new_err(e.to_string()))
}

/// A long run's steps on one line of stderr when it is a terminal (as `hyst ssi`'s bar;
/// nothing in a notebook or a log); [`clear_terminal_progress`] wipes it at the end.
pub(crate) fn terminal_progress(p: covssi::Progress<'_>) {
    // A line wider than the terminal would wrap: the message is cut to 70 characters.
    let what: String = p.what.chars().take(70).collect();
    to_terminal(&format!("{}/{} {what}", p.done, p.total));
}

/// Wipe the line [`terminal_progress`] wrote.
pub(crate) fn clear_terminal_progress() {
    to_terminal("");
}

/// `text` in place of stderr's current line, when stderr is a terminal.
pub(crate) fn to_terminal(text: &str) {
    use std::io::{IsTerminal, Write};
    let mut err = std::io::stderr();
    if err.is_terminal() {
        let _ = write!(err, "\r\x1b[2K{text}");
        let _ = err.flush();
    }
}
