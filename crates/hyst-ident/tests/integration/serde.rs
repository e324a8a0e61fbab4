//! The JSON form of the pipeline's options and reports (feature `serde`): a report reads
//! back to the same JSON, its models are in the oscillator's one schema, and an unknown
//! option is refused.

use hyst_ident::{IdentOptions, IdentReport, ValidationRecord, identify_and_validate};
use hyst_model::Oscillator;
use hyst_sim::excitation::{Multisine, add_noise};
use hyst_sim::{Input, SimOptions, simulate, steady_state_period};

/// The benchmark under its 50 N multisine: four periods after one of warm-up, with the
/// benchmark's noise, and a fresh period to validate on.
fn records() -> (Vec<f64>, ValidationRecord) {
    let ms = Multisine::benchmark(50.0);
    let u = ms.generate(21).unwrap();
    let model = Oscillator::benchmark();
    let n = u.len();
    let opts = SimOptions::default();
    let mut y = simulate(&model, Input::Periodic(&u), 750.0, 5 * n, &opts)
        .unwrap()
        .split_off(n);
    add_noise(&mut y, 7.4e-6, 22).unwrap();
    let uv = ms.generate(23).unwrap();
    let yv = steady_state_period(&model, &uv, 750.0, &opts, 1e-10, 50)
        .unwrap()
        .y;
    (y, ValidationRecord::new("fresh period", uv, yv))
}

#[test]
fn an_ident_report_reads_back_as_written() {
    let (y, val) = records();
    let opts = IdentOptions {
        excitation: Some(hyst_ident::flatness::ExcitationBand::benchmark()),
        ..IdentOptions::default()
    };
    let report = identify_and_validate(&y, 750.0, &opts, None, &[val]).unwrap();
    let json = serde_json::to_value(&report).unwrap();
    let back: IdentReport = serde_json::from_value(json.clone()).unwrap();
    assert_eq!(serde_json::to_value(&back).unwrap(), json);
    // The kept model is the candidate that validates best, and it reads as an oscillator
    // in the schema `hyst simulate --params` takes.
    assert_eq!(json["bouc_wen_route"], "flatness");
    let model: Oscillator = serde_json::from_value(json["bouc_wen"].clone()).unwrap();
    assert_eq!(Some(model), report.bouc_wen);
    assert!(json["validation"][0]["bouc_wen"]["epsilon"].is_number());
}

/// A residual loop's report, rejected candidates (ΔBIC = ∞, written as null) and all, reads
/// back to the same JSON.
#[test]
fn a_refine_report_reads_back_as_written() {
    use hyst_ident::residual::{InputInterpolation, ModelClass, Record, refine_report};
    let mut model = Oscillator::linear(2.0, 10.0, 5e4);
    model.extras.cubic_stiffness = 3e9;
    let u = hyst_sim::excitation::white_noise(4096, 50.0, 31).unwrap();
    let mut y = simulate(
        &model,
        Input::Sampled(&u),
        750.0,
        u.len(),
        &SimOptions::default(),
    )
    .unwrap();
    add_noise(&mut y, 1e-6, 32).unwrap();
    let rec = Record {
        u: &u,
        y: &y,
        fs: 750.0,
        interpolation: InputInterpolation::Linear,
    };
    let report = refine_report(
        &rec,
        Some(2.0),
        ModelClass::Linear,
        (0, 3072),
        &[(3072, 4096)],
        &|_| {},
    )
    .unwrap();
    let json = serde_json::to_value(&report).unwrap();
    let rejected = json["steps"][0]["evidence"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|e| e["delta_bic"].is_null())
        .count();
    assert!(rejected > 0, "no rejected candidate to read back: {json}");
    let back: hyst_ident::residual::RefineReport = serde_json::from_value(json.clone()).unwrap();
    assert_eq!(serde_json::to_value(&back).unwrap(), json);
}

#[test]
fn an_unknown_option_is_refused() {
    let o: IdentOptions = serde_json::from_str(r#"{"mass": 3.5}"#).unwrap();
    assert_eq!(
        o,
        IdentOptions {
            mass: 3.5,
            ..IdentOptions::default()
        }
    );
    let e = serde_json::from_str::<IdentOptions>(r#"{"mas": 3.5}"#)
        .unwrap_err()
        .to_string();
    assert!(e.contains("unknown field `mas`"), "{e}");
}
