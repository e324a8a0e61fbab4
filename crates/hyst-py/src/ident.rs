//! The input-output and hysteresis commands from Python: `simulate`, `identify`, `refine`,
//! `levels`, each one library call on numpy arrays, its report returned as a [`Report`] (the
//! text the command prints, and the JSON document it writes). Models cross as the JSON
//! schema of `--params` (`hyst_model::schema`): a Python dict, dumped by Python's `json` and
//! read by serde, unknown keys an error.

use std::fmt::Display;

use numpy::{IntoPyArray, PyArray1, PyReadonlyArray1};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use serde::Serialize;

use hyst::ident::residual::{self, InputInterpolation, ModelClass};
use hyst::ident::{self, DampingGuess, IdentOptions, Linearization, ValidationRecord};
use hyst::model::Oscillator;
use hyst::sim::{self, Decimation, InputKind, Integrator, SimOptions};

/// A command's report: `str(report)` is the text the command prints, `to_dict()` the JSON
/// document its `--json` writes.
#[pyclass(module = "hyst", name = "Report", frozen)]
pub(crate) struct Report {
    text: String,
    json: String,
    /// The report's page, for reports that have one (merged setups).
    html: Option<String>,
    /// Its alarms' lines, for a campaign's report.
    alarm_lines: Vec<String>,
}

impl Report {
    /// The report of `report` on the record `record`, as the command line makes it.
    pub(crate) fn of<T: Serialize + Display>(record: &str, report: T) -> PyResult<Report> {
        let report = hyst::report::FileReport::new(record, report);
        Ok(Report {
            text: report.to_string(),
            json: serde_json::to_string(&report).map_err(value_error)?,
            html: None,
            alarm_lines: Vec::new(),
        })
    }

    /// This report with its alarms' lines.
    pub(crate) fn with_alarm_lines(mut self, lines: Vec<String>) -> Report {
        self.alarm_lines = lines;
        self
    }

    /// This report with its page.
    pub(crate) fn with_html(mut self, page: String) -> Report {
        self.html = Some(page);
        self
    }
}

#[pymethods]
impl Report {
    /// A campaign's alarms, one line each in record order, as `hyst track --follow` prints
    /// them (empty for other reports).
    fn alarm_lines(&self) -> Vec<String> {
        self.alarm_lines.clone()
    }

    /// The report as the JSON document the command's `--json` writes.
    fn to_json(&self) -> String {
        self.json.clone()
    }

    /// The report as a dictionary (the JSON document's keys and values); its models are in
    /// the schema `simulate` takes.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        py.import("json")?
            .call_method1("loads", (self.json.as_str(),))
    }

    /// The report a browser opens (as the command's `--html` writes it); a ValueError for a
    /// report without one.
    fn html(&self) -> PyResult<String> {
        self.html.clone().ok_or_else(|| {
            value_error("this report has no page (only hyst.ssi(setups=...) makes one)")
        })
    }

    /// The text the command prints.
    fn __str__(&self) -> String {
        self.text.clone()
    }

    fn __repr__(&self) -> String {
        let first = self.text.lines().next().unwrap_or("");
        format!("<Report: {first}>")
    }
}

pub(crate) fn value_error(e: impl Display) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// An oscillator from the JSON text of a model in the `--params` schema, or the string
/// `"benchmark"` (the Bouc-Wen benchmark's system, `hyst simulate --system benchmark`).
fn oscillator(model_json: &str) -> PyResult<Oscillator> {
    if model_json == "\"benchmark\"" {
        return Ok(Oscillator::benchmark());
    }
    serde_json::from_str(model_json).map_err(|e| value_error(format!("model: {e}")))
}

/// A validation record as Python passes it: name, input, output, periodic (None: told from
/// the input).
type Validation = (String, Vec<f64>, Vec<f64>, Option<bool>);

/// Validation records from (name, u, y, periodic or None) tuples.
fn validations(records: Vec<Validation>) -> Vec<ValidationRecord> {
    records
        .into_iter()
        .map(|(name, u, y, periodic)| {
            let mut r = ValidationRecord::new(name, u, y);
            if let Some(p) = periodic {
                r.periodic = p;
            }
            r
        })
        .collect()
}

/// A generated excitation at `fs` Hz, `design` a JSON object of
/// `hyst_sim::excitation::ExcitationDesign`; see the Python wrapper `hyst.excite`.
#[pyfunction]
#[pyo3(signature = (fs, *, kind, design))]
pub(crate) fn excite<'py>(
    py: Python<'py>,
    fs: f64,
    kind: &str,
    design: &str,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    use hyst::sim::excitation::{ExcitationDesign, ExcitationKind};
    let mut d: ExcitationDesign =
        serde_json::from_str(design).map_err(|e| value_error(format!("excite: {e}")))?;
    d.kind = ExcitationKind::from_name(kind).ok_or_else(|| {
        value_error(format!(
            "excitation {kind:?} is not one of {:?}",
            ExcitationKind::NAMES
        ))
    })?;
    if !(fs.is_finite() && fs > 0.0) {
        return Err(value_error(format!(
            "fs must be a positive finite rate (Hz), got {fs}"
        )));
    }
    let u = py.detach(|| d.generate(fs)).map_err(value_error)?;
    Ok(u.into_pyarray(py))
}

/// A storey fit's channels (channels × samples) under `forces` (one per loaded floor, each
/// `samples` long); see the Python wrapper `hyst.simulate` with a storey fit as its model.
#[pyfunction]
pub(crate) fn simulate_structure(
    py: Python<'_>,
    fit_json: &str,
    forces: Vec<Vec<f64>>,
) -> PyResult<Vec<Vec<f64>>> {
    let fit: hyst::ident::storeys::StoreyFit = serde_json::from_str(fit_json)
        .map_err(|e| value_error(format!("model: not a storey fit: {e}")))?;
    py.detach(|| hyst::ident::storeys::simulate_structure(&fit, &forces))
        .map_err(value_error)
}

/// The response of a model to the force `u`; see the Python wrapper `hyst.simulate`.
#[pyfunction]
#[pyo3(signature = (model_json, u, fs, *, input, oversample, integrator, decimation, noise, noise_seed))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn simulate<'py>(
    py: Python<'py>,
    model_json: &str,
    u: PyReadonlyArray1<'py, f64>,
    fs: f64,
    input: &str,
    oversample: usize,
    integrator: &str,
    decimation: &str,
    noise: f64,
    noise_seed: u64,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let model = oscillator(model_json)?;
    let kind = match input {
        "periodic" => InputKind::Periodic,
        "band-limited" => InputKind::BandLimited,
        "linear" => InputKind::Linear,
        other => {
            return Err(value_error(format!(
                "input {other:?} is not one of \"periodic\", \"band-limited\", \"linear\""
            )));
        }
    };
    let opts = SimOptions {
        oversample,
        integrator: match integrator {
            "rk4" => Integrator::Rk4,
            "newmark" => Integrator::Trapezoidal,
            other => {
                return Err(value_error(format!(
                    "integrator {other:?} is not one of \"rk4\", \"newmark\""
                )));
            }
        },
        decimation: match decimation {
            "sample" => Decimation::Subsample,
            "fir" => Decimation::fir_stages(oversample),
            other => {
                return Err(value_error(format!(
                    "decimation {other:?} is not one of \"sample\", \"fir\""
                )));
            }
        },
        ..SimOptions::default()
    };
    let u = u.as_slice().map_err(value_error)?.to_vec();
    let y = py
        .detach(|| {
            let mut y = sim::response(&model, &u, fs, kind, &opts)?;
            if noise != 0.0 {
                sim::excitation::add_noise(&mut y, noise, noise_seed)?;
            }
            Ok::<_, sim::SimError>(y)
        })
        .map_err(value_error)?;
    Ok(y.into_pyarray(py))
}

/// The paper's output-only pipeline on the output `y`; see the Python wrapper `hyst.identify`.
#[pyfunction]
#[pyo3(signature = (y, fs, mass, *, damping, c, excitation_band, period, linearization, validate, profile, record))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn identify(
    py: Python<'_>,
    y: Vec<f64>,
    fs: f64,
    mass: f64,
    damping: &str,
    c: Option<f64>,
    excitation_band: Option<(f64, f64)>,
    period: Option<usize>,
    linearization: Option<&str>,
    validate: Vec<Validation>,
    profile: bool,
    record: &str,
) -> PyResult<Report> {
    let damping_guess = match (c, damping) {
        (Some(c), _) => DampingGuess::Value(c),
        (None, "spectrum") => DampingGuess::ZenerSpectrum,
        (None, "cluster") => DampingGuess::LowDampingCluster,
        (None, other) => {
            return Err(value_error(format!(
                "damping {other:?} is not one of \"spectrum\", \"cluster\""
            )));
        }
    };
    let excitation = match (excitation_band, period) {
        (Some((low_hz, high_hz)), Some(period)) => Some(ident::flatness::ExcitationBand {
            low_hz,
            high_hz,
            period,
        }),
        (None, None) => None,
        _ => return Err(value_error("excitation_band and period go together")),
    };
    let mapping = match linearization {
        None => None,
        Some("paper") => Some(Linearization::Paper),
        Some("harmonic") => Some(Linearization::Harmonic),
        Some(other) => {
            return Err(value_error(format!(
                "linearization {other:?} is not one of \"paper\", \"harmonic\""
            )));
        }
    };
    let opts = IdentOptions {
        mass,
        excitation,
        damping_guess,
        profile,
        ..IdentOptions::default()
    };
    let records = validations(validate);
    let report = py
        .detach(|| ident::identify_and_validate(&y, fs, &opts, mapping, &records))
        .map_err(value_error)?;
    Report::of(record, report)
}

/// The residual loop with input and output; see the Python wrapper `hyst.refine`.
#[pyfunction]
#[pyo3(signature = (u, y, fs, *, mass, start, input_interpolation, estimate, test, record))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn refine(
    py: Python<'_>,
    u: Vec<f64>,
    y: Vec<f64>,
    fs: f64,
    mass: Option<f64>,
    start: &str,
    input_interpolation: &str,
    estimate: Option<(usize, usize)>,
    test: Vec<(usize, usize)>,
    record: &str,
) -> PyResult<Report> {
    let start = match start {
        "linear" => ModelClass::Linear,
        "zener" => ModelClass::Zener,
        "bouc-wen" => ModelClass::BoucWen,
        other => {
            return Err(value_error(format!(
                "start {other:?} is not one of \"linear\", \"zener\", \"bouc-wen\""
            )));
        }
    };
    let interpolation = match input_interpolation {
        "band-limited" => InputInterpolation::BandLimited,
        "linear" => InputInterpolation::Linear,
        other => {
            return Err(value_error(format!(
                "input_interpolation {other:?} is not one of \"band-limited\", \"linear\""
            )));
        }
    };
    let (default_estimate, default_tests) = residual::default_rows(y.len());
    let estimate = estimate.unwrap_or(default_estimate);
    let tests = if test.is_empty() { default_tests } else { test };
    let rec = residual::Record {
        u: &u,
        y: &y,
        fs,
        interpolation,
    };
    let report = py
        .detach(|| {
            let r = residual::refine_report(
                &rec,
                mass,
                start,
                estimate,
                &tests,
                &crate::terminal_progress,
            );
            crate::clear_terminal_progress();
            r
        })
        .map_err(value_error)?;
    Report::of(record, report)
}

/// The storey fit of a shear structure from records at several levels; see the Python
/// wrapper `hyst.levels(..., masses=...)`. `records` are (name, channels × samples);
/// `floors` and `load_floors` count from 1, as the command's flags.
#[pyfunction]
#[pyo3(signature = (records, fs, masses, *, floors, quantity, load_floors, predict))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn storeys(
    py: Python<'_>,
    records: Vec<(String, Vec<Vec<f64>>)>,
    fs: f64,
    masses: Vec<f64>,
    floors: Option<Vec<usize>>,
    quantity: &str,
    load_floors: Option<Vec<usize>>,
    predict: Vec<f64>,
) -> PyResult<Report> {
    use hyst::ident::storeys::{Quantity, StoreyOptions, StoreyStructure, fit_storeys};
    let zero_based = |name: &str, v: Vec<usize>| -> PyResult<Vec<usize>> {
        v.into_iter()
            .map(|f| {
                f.checked_sub(1)
                    .ok_or_else(|| value_error(format!("{name}: floors count from 1, got 0")))
            })
            .collect()
    };
    let quantity = match quantity {
        "acceleration" => Quantity::Acceleration,
        "velocity" => Quantity::Velocity,
        "displacement" => Quantity::Displacement,
        other => {
            return Err(value_error(format!(
                "quantity must be \"acceleration\", \"velocity\" or \"displacement\", got {other:?}"
            )));
        }
    };
    let channels = records.first().map_or(0, |(_, r)| r.len());
    let sensors = match floors {
        Some(f) => zero_based("floors", f)?,
        None => (0..channels).collect(),
    };
    let mut opts = StoreyOptions::default();
    if let Some(l) = load_floors {
        opts.load_floors = Some(zero_based("load_floors", l)?);
    }
    opts.predict = predict;
    let structure = StoreyStructure::new(masses, sensors, quantity, fs);
    let data: Vec<Vec<Vec<f64>>> = records.iter().map(|(_, r)| r.clone()).collect();
    let fit = py
        .detach(|| {
            let r = fit_storeys(&data, &structure, &opts, &|p| {
                crate::terminal_progress(hyst::ident::Progress {
                    done: p.iteration,
                    total: p.iteration.max(1),
                    what: p.stage,
                })
            });
            crate::clear_terminal_progress();
            r
        })
        .map_err(value_error)?;
    let record = records
        .iter()
        .map(|(n, _)| n.as_str())
        .collect::<Vec<_>>()
        .join(", ");
    Report::of(&record, fit)
}

/// One Bouc-Wen model from records at several levels; see the Python wrapper `hyst.levels`.
#[pyfunction]
#[pyo3(signature = (records, fs, mass, *, by_simulation, data_periodic, fit_exponent, validate))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn levels(
    py: Python<'_>,
    records: Vec<(String, Vec<f64>)>,
    fs: f64,
    mass: f64,
    by_simulation: bool,
    data_periodic: bool,
    fit_exponent: bool,
    validate: Vec<Validation>,
) -> PyResult<Report> {
    use hyst::ident::levels::{self, LevelsOptions, SimulationOptions};
    let simulation = by_simulation.then(|| SimulationOptions {
        periodic: data_periodic,
        ..SimulationOptions::default()
    });
    let opts = LevelsOptions::with_mass(mass)
        .fit_exponent(fit_exponent)
        .by_simulation(simulation);
    let views: Vec<(String, &[f64])> = records.iter().map(|(n, y)| (n.clone(), &y[..])).collect();
    let checks = validations(validate);
    let report = py
        .detach(|| {
            let r = levels::levels_report(&views, fs, &opts, &checks, &crate::terminal_progress);
            crate::clear_terminal_progress();
            r
        })
        .map_err(value_error)?;
    let record = records
        .iter()
        .map(|(n, _)| n.as_str())
        .collect::<Vec<_>>()
        .join(", ");
    Report::of(&record, report)
}
