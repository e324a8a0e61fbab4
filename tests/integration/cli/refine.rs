//! `hyst refine`: the residual loop through the command line, and its row ranges checked.

use super::*;

/// A Bouc-Wen element with ν = 2 (softening; the benchmark's oscillator otherwise), driven by
/// 50 N of white force: `hyst refine` from a linear start adds hysteresis (ν = 1), then frees
/// the exponent, and says which ν it fitted. Measured: held-out ε 4.457 → 1.087 → 0.255 %
/// (an RMS error of 7.55e-6 m against the 7.4e-6 m of added noise), ν = 2.001.
#[test]
fn refine_frees_the_exponent_of_a_sharper_element() {
    let params = write(
        "nu2_params.json",
        r#"{"mass": 2, "damping": 10, "stiffness": 5e4,
            "bouc_wen": {"alpha": 5e4, "beta_gamma": 24.242424242424242,
                         "beta_delta": -12.121212121212121, "nu": 2}}"#,
    );
    let rec = tmp("nu2_r50.csv");
    let (ok, _, err) = hyst(&[
        "simulate",
        "--params",
        s(&params),
        "--excitation",
        "white",
        "--rms",
        "50",
        "--samples",
        "8192",
        "--seed",
        "3",
        "--noise",
        "7.4e-6",
        "--out",
        s(&rec),
    ]);
    assert!(ok, "{err}");
    let json = tmp("nu2_refine.json");
    let figures = tmp("nu2_refine_figures");
    let (ok, out, err) = hyst(&[
        "refine",
        "--svg-dir",
        s(&figures),
        "--data",
        s(&rec),
        "--fs",
        "750",
        "--mass",
        "2",
        "--start",
        "linear",
        "--input-interpolation",
        "linear",
        "--estimate",
        "0:6144",
        "--test",
        "6144:8192",
        "--json",
        s(&json),
    ]);
    assert!(ok, "{err}");
    // The report says which start it used, each step's held-out test, the noise level and
    // whether anything is left; the JSON carries the same.
    assert!(out.contains("start: linear (asked for linear)"), "{out}");
    for f in [
        "residual_spectra.svg",
        "time_overlay.svg",
        "residual_force_cells.svg",
        "residual_force_surface.svg",
        "residual_force_stiffness.svg",
        "residual_force_damping.svg",
    ] {
        let svg = std::fs::read_to_string(figures.join(f)).unwrap_or_default();
        assert!(svg.starts_with("<svg"), "{f}");
    }
    assert!(out.contains("noise level: "), "{out}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["start"]["used"], "linear");
    let p = v["steps"][0]["gain"]["p_value"]
        .as_f64()
        .expect("the first step's p-value");
    assert!(p < 0.01, "{p}");
    assert!(v["steps"][0]["trace"]["signature"].is_string());
    // White force up to Nyquist (not periodic): the noise cannot be told, and the JSON says
    // why rather than guessing.
    assert!(v["noise"]["unknown"].is_string(), "{v}");
    assert!(v["unexplained"].is_null());
    let steps: Vec<&str> = out
        .lines()
        .filter_map(|l| l.strip_prefix("step: "))
        .map(|l| l.split_whitespace().next().unwrap_or(""))
        .collect();
    assert_eq!(
        steps,
        ["hysteresis", "hysteresis_exponent", "none"],
        "{out}"
    );
    // The exponent's candidate names its ν, and the final model's ν is within four of its
    // standard errors of the truth (measured: 2.00100 ± 0.00404).
    assert!(out.contains("(ν = 2.0"), "{out}");
    let nu: Vec<f64> = out
        .lines()
        .find(|l| l.contains("with standard errors"))
        .and_then(|l| l.split(", nu ").nth(1))
        .map(|r| {
            r.split_whitespace()
                .filter_map(|w| w.parse().ok())
                .take(2)
                .collect()
        })
        .unwrap_or_default();
    assert_eq!(nu.len(), 2, "no ν ± its standard error in {out}");
    assert!(
        (nu[0] - 2.0).abs() < 4.0 * nu[1],
        "ν = {} ± {}",
        nu[0],
        nu[1]
    );
}

#[test]
fn refine_needs_an_input_column() {
    let p = write(
        "y_no_u.csv",
        &format!(
            "y\n{}",
            (0..200)
                .map(|k| format!("{}\n", (0.3 * k as f64).sin()))
                .collect::<String>()
        ),
    );
    let (ok, _, err) = hyst(&["refine", "--data", s(&p), "--fs", "100"]);
    assert!(!ok);
    assert!(
        err.contains("no column `u`") && err.contains("refine needs the input"),
        "{err}"
    );
}

/// A test range shorter than the held-out test needs is refused before any work, naming
/// the rows and how many are needed.
#[test]
fn refine_refuses_a_test_range_too_short_for_its_test() {
    let p = write_input_output("uy_short_test.csv", 1000);
    let (ok, _, err) = hyst(&[
        "refine",
        "--data",
        s(&p),
        "--fs",
        "100",
        "--test",
        "800:1000",
    ]);
    assert!(!ok);
    assert!(
        err.contains("test rows 800:1000 are 200 rows; the held-out test needs at least 512"),
        "{err}"
    );
}

#[test]
fn refine_rejects_bad_row_ranges() {
    let p = write_input_output("uy.csv", 200);
    let (ok, _, err) = hyst(&[
        "refine",
        "--data",
        s(&p),
        "--fs",
        "100",
        "--estimate",
        "150:100",
    ]);
    assert!(!ok);
    assert!(
        err.contains("for '--estimate <ESTIMATE>': `150:100` is not A:B"),
        "{err}"
    );
    let (ok, _, err) = hyst(&["refine", "--data", s(&p), "--fs", "100", "--test", "0:500"]);
    assert!(!ok);
    assert!(
        err.contains("--test `0:500`") && err.contains("200"),
        "{err}"
    );
}
