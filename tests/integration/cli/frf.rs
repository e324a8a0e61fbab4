//! `hyst frf`: the F-16's torsion mode from its frequency response.

use super::*;

/// `hyst frf` on the measured F-16 (lowest level, wing torsion band): the mode the data's
/// README gives (about 7.32 Hz, 0.3–0.5 %), and `hyst ssi` on its force-flattened outputs
/// finds it where the fit does (tests/f16_levels.rs has the study over all levels).
#[test]
fn frf_fits_the_f16_torsion_mode_and_writes_flattened_outputs() {
    let Some(data) = common::data_file("f16/msine_level1.csv") else {
        return;
    };
    let (json, svg, flat) = (tmp("frf.json"), tmp("frf.svg"), tmp("frf_flat.csv"));
    let base = [
        "frf",
        "--input",
        s(&data),
        "--fs",
        "400",
        "--force",
        "force",
        "--skip",
        "8192",
    ];
    let mut args = base.to_vec();
    args.extend_from_slice(&[
        "--period",
        "8192",
        "--band",
        "6.8:7.8",
        "--json",
        s(&json),
        "--svg",
        s(&svg),
        "--write-flat",
        s(&flat),
    ]);
    let (ok, out, err) = hyst(&args);
    assert!(ok, "{err}");
    assert!(out.contains("8 whole periods"), "{out}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let modes = v["fit"]["modes"].as_array().unwrap();
    assert_eq!(modes.len(), 1, "{v}");
    let f = modes[0]["frequency_hz"].as_f64().unwrap();
    let z = modes[0]["damping_ratio"].as_f64().unwrap();
    assert!(
        (f - 7.32).abs() <= 0.01 && (0.003..=0.005).contains(&z),
        "{f} {z}"
    );
    assert!(modes[0]["frequency_se_hz"].as_f64().unwrap() > 0.0);
    // The shape over the three channels, largest entry 1 (acc2, the wing next to the
    // interface; measured 0.497, 1, 0.969), printed with its MPC.
    let shape = modes[0]["shape"].as_array().unwrap();
    assert_eq!(shape.len(), 3, "{v}");
    assert_eq!(shape[1], serde_json::json!([1.0, 0.0]), "{v}");
    let se = modes[0]["shape_se"].as_array().unwrap();
    assert_eq!(se[1], 0.0, "{v}");
    assert!(
        se[0].as_f64().unwrap() > 0.0 && se[2].as_f64().unwrap() > 0.0,
        "{v}"
    );
    assert!(modes[0]["mpc"].as_f64().is_some_and(|m| m > 0.99), "{v}");
    assert!(out.contains("shape at 7.3") && out.contains("MPC"), "{out}");
    // The band's share of the uncertainty, from the fits over 6.9–7.7 and 6.7–7.9 Hz.
    let spread = &v["band_spread"][0];
    assert!(
        (0.0..0.01).contains(&spread["frequency_hz"].as_f64().unwrap()),
        "{v}"
    );
    assert!(spread["damping"].as_f64().unwrap() >= 0.0);
    assert!(out.contains("(band "), "{out}");
    assert!(std::fs::read_to_string(&svg).unwrap().contains("<svg"));
    // The flattened outputs: 8 periods of the three channels, and SSI finds the mode there
    // within 0.3 % of the fit (7.317 against 7.320 Hz; on the measured outputs 7.352).
    let t = hyst::io::read_csv(&flat).unwrap();
    assert_eq!(t.len(), 8 * 8192);
    assert_eq!(t.names, ["acc1", "acc2", "acc3"]);
    let sj = tmp("frf_flat_ssi.json");
    let (ok, _, err) = hyst(&[
        "ssi",
        "--input",
        s(&flat),
        "--fs",
        "400",
        "--decimate",
        "8",
        "--block-rows",
        "40",
        "--max-order",
        "60",
        "--no-refine",
        "--json",
        s(&sj),
    ]);
    assert!(ok, "{err}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&sj).unwrap()).unwrap();
    let near: Vec<f64> = v["ssi_modes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["frequency_hz"].as_f64().unwrap())
        .filter(|g| (g - f).abs() < 0.3)
        .collect();
    assert!(
        near.iter().any(|g| (g - f).abs() < 0.003 * f),
        "{near:?} vs {f}"
    );
    // Bad input is named.
    for (extra, needle) in [
        (
            &["--period", "8192", "--band", "6.8-7.8"][..],
            "for '--band <BAND>': `6.8-7.8` is not LO:HI with 0 <= LO < HI (Hz)",
        ),
        (
            &["--period", "8192", "--band", "6.8:300"][..],
            "is not an interval within 0..200 Hz",
        ),
        (
            &[
                "--period",
                "8192",
                "--band",
                "6.8:7.8",
                "--columns",
                "acc1,force",
            ][..],
            "includes the force column",
        ),
        (
            &["--period", "8192", "--band", "6.8:7.8", "--modes", "0"][..],
            "needs at least one mode",
        ),
        (
            &["--period", "8192", "--band", "0.001:0.01"][..],
            "holds 0 excited lines",
        ),
        (
            &["--period", "8000", "--band", "6.8:7.8"][..],
            "does not repeat every 8000 samples",
        ),
    ] {
        let mut args = base.to_vec();
        args.extend_from_slice(extra);
        let (ok, _, err) = hyst(&args);
        assert!(!ok && err.contains(needle), "{extra:?}: {err}");
    }
}
