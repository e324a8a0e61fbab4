//! `hyst amplitude`: its options named by their flags.

use super::*;

/// `hyst amplitude`'s options out of range are named by their flags, before any record is
/// read (the input here does not exist).
#[test]
fn amplitude_options_are_named_by_their_flags_before_reading() {
    for (flag, value, says) in [
        ("--levels", "0", "--levels 0 is out of range: at least 1"),
        (
            "--cycles",
            "0.1",
            "--cycles 0.1 is out of range: between 0.5 and 50",
        ),
        ("--groups", "1", "--groups 1 is out of range: at least 2"),
        ("--band", "2", "--band 2 is out of range"),
        ("--period", "0", "--period 0 is out of range"),
    ] {
        let (ok, _, err) = hyst(&[
            "amplitude",
            "--input",
            "/nonexistent/record.csv",
            "--fs",
            "20",
            flag,
            value,
        ]);
        assert!(!ok);
        assert!(err.contains(says), "{flag}: {err}");
    }
}

/// `hyst amplitude --floors`: each point's amplitude at every channel and across every
/// storey of a linear three-storey chain's displacements, in the structure's own shape
/// (the simulator's eigenvectors); floors counted from 1, a floor named twice refused.
#[test]
fn amplitude_with_floors_places_each_point_on_the_storeys() {
    let mut b = hyst_sim::building::ShearBuilding::three_storey_example(None);
    b.reading = hyst_sim::building::Reading::Displacement;
    b.load.rms = 2000.0;
    let y = b.generate(40_000, 8_400_901).unwrap();
    let mut text = String::from("x1,x2,x3\n");
    for ((a, b), c) in y[0].iter().zip(&y[1]).zip(&y[2]) {
        text.push_str(&format!("{a},{b},{c}\n"));
    }
    let record = write("amplitude_floors.csv", &text);
    let json = tmp("amplitude_floors.json");
    let (ok, out, err) = hyst(&[
        "amplitude",
        "--input",
        s(&record),
        "--fs",
        "200",
        "--floors",
        "1,2,3",
        "--json",
        s(&json),
    ]);
    assert!(ok, "{err}");
    assert!(
        out.contains("each storey's drift, from the ground up"),
        "{out}"
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let modes = v["curves"]["modes"].as_array().unwrap();
    let truth = b.modes().unwrap();
    // The first mode: all floors one way, the drifts the differences of its shape.
    let first = modes
        .iter()
        .find(|m| {
            (m["mode"]["frequency_hz"].as_f64().unwrap() / truth[0].frequency_hz - 1.0).abs() < 0.02
        })
        .expect("the first mode followed");
    let p = &first["points"][0];
    let a = p["amplitude"].as_f64().unwrap();
    let channels: Vec<f64> = p["channels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let drifts: Vec<f64> = p["drifts"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let norm = truth[0].shape.iter().map(|v| v * v).sum::<f64>().sqrt();
    for (c, t) in channels.iter().zip(&truth[0].shape) {
        // The unit shape times the amplitude; SSI's shape to 1.5 % (as in hyst-ident's test).
        assert!(
            (c / a - t.abs() / norm).abs() < 0.015,
            "{channels:?} {:?}",
            truth[0].shape
        );
    }
    assert!((drifts[0] - channels[0]).abs() < 1e-12 * a);
    assert!((drifts[2] - (channels[2] - channels[1]).abs()).abs() < 1e-12 * a);
    let with_floors = |floors: &str| {
        hyst(&[
            "amplitude",
            "--input",
            s(&record),
            "--fs",
            "200",
            "--floors",
            floors,
        ])
    };
    let (ok, _, err) = with_floors("1,1,2");
    assert!(
        !ok && err.contains("floors [1, 1, 2] (from 1) for 3 channels"),
        "{err}"
    );
    // Channels on floors 1, 2 and 4: storeys 3 and 4 have a floor without a channel, and
    // their drift is said as not measured, not printed as NaN (issue 77).
    let (ok, out, err) = with_floors("1,2,4");
    assert!(ok, "{err}");
    assert!(
        !out.contains("NaN") && out.contains("(storey 3, 4: a floor of it has no channel)"),
        "{out}"
    );
    let (ok, _, err) = with_floors("0,1,2");
    assert!(
        !ok && err.contains("--floors: floors count from 1"),
        "{err}"
    );
}
