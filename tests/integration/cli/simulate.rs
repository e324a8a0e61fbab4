//! `hyst simulate` and `hyst excite`: the benchmark's records reproduced, inputs interpolated, models and options checked.

use super::*;

#[test]
fn reproduces_multisine_val_through_the_command_line() {
    let Some(path) = common::data_file("boucwen/multisine_val.csv") else {
        return;
    };
    let out = tmp("ms_val_sim.csv");
    let (ok, _, err) = hyst(&[
        "simulate",
        "--input",
        s(&path),
        "--fs",
        "750",
        "--periodic",
        "--integrator",
        "newmark",
        "--decimation",
        "fir",
        "--out",
        s(&out),
    ]);
    assert!(ok, "{err}");
    let sim = hyst::io::read_csv(&out).unwrap();
    let reference = hyst::io::read_csv(&path).unwrap();
    let e = common::rel_rms(sim.column("y").unwrap(), reference.column("y").unwrap());
    assert!(e <= 1e-9, "relative RMS error {e:e}");
    assert_eq!(sim.column("u").unwrap(), reference.column("u").unwrap());
}

/// A measured input file is interpolated band-limited by default, as validation and the
/// residual loop take it: on the benchmark's sweep record (a chirp at 0.05-0.14 of Nyquist)
/// the true model's output is then closer to the record than with linear interpolation
/// (3.9e-3 against 7.0e-3 relative RMS when written; the rest is the record's own
/// single-stage FIR decimation, 3.5e-3 by the data's README, and the integrator).
#[test]
fn an_input_file_is_interpolated_band_limited() {
    let Some(path) = common::data_file("boucwen/sinesweep_val.csv") else {
        return;
    };
    let reference = hyst::io::read_csv(&path).unwrap();
    let error = |name: &str, extra: &[&str]| {
        let out = tmp(name);
        let mut args = vec![
            "simulate",
            "--input",
            s(&path),
            "--fs",
            "750",
            "--out",
            s(&out),
        ];
        args.extend(extra);
        let (ok, _, err) = hyst(&args);
        assert!(ok, "{err}");
        let sim = hyst::io::read_csv(&out).unwrap();
        common::rel_rms(sim.column("y").unwrap(), reference.column("y").unwrap())
    };
    let band = error("sweep_band.csv", &[]);
    let linear = error("sweep_linear.csv", &["--input-interpolation", "linear"]);
    assert!(band < 5e-3 && band < 0.7 * linear, "{band:e} vs {linear:e}");
}

#[test]
fn generates_excitations_and_simulates_them() {
    let out = tmp("gen.csv");
    let (ok, _, err) = hyst(&[
        "simulate",
        "--excitation",
        "white",
        "--rms",
        "10",
        "--samples",
        "3000",
        "--seed",
        "4",
        "--out",
        s(&out),
    ]);
    assert!(ok, "{err}");
    let t = hyst::io::read_csv(&out).unwrap();
    assert_eq!(t.len(), 3000);
    let u = t.column("u").unwrap();
    let rms = (u.iter().map(|v| v * v).sum::<f64>() / u.len() as f64).sqrt();
    assert!((rms - 10.0).abs() < 1e-9);
    let y = t.column("y").unwrap();
    assert!(y.iter().any(|v| *v != 0.0));
    let ex = tmp("ex.csv");
    let (ok, _, err) = hyst(&[
        "excite",
        "--excitation",
        "sweep",
        "--samples",
        "100",
        "--out",
        s(&ex),
    ]);
    assert!(ok, "{err}");
    assert_eq!(hyst::io::read_csv(&ex).unwrap().len(), 100);
}

#[test]
fn zero_oversampling() {
    let p = write("ok2.csv", "u\n1\n2\n");
    let err = simulate_fails(&["--input", s(&p), "--fs", "750", "--oversample", "0"]);
    assert!(err.contains("oversample"), "{err}");
}

#[test]
fn invalid_parameters() {
    let u = write("ok3.csv", "u\n1\n2\n");
    let p = write("bad.json", r#"{"mass": 0, "damping": 1, "stiffness": 1}"#);
    let err = simulate_fails(&["--input", s(&u), "--fs", "750", "--params", s(&p)]);
    assert!(err.contains("mass") && err.contains("bad.json"), "{err}");
    let p = write("bad2.json", r#"{"mass": 1, "damping": 1}"#);
    let err = simulate_fails(&["--input", s(&u), "--fs", "750", "--params", s(&p)]);
    assert!(err.contains("stiffness"), "{err}");
    // An array was read by position, as mass, damping, stiffness, …
    let p = write("array.json", "[2, 10, 50000]");
    let err = simulate_fails(&["--input", s(&u), "--fs", "750", "--params", s(&p)]);
    assert!(
        err.contains("must be a JSON object") && err.contains("an array"),
        "{err}"
    );
}

/// A misspelled key is an error naming it and the keys allowed, not a model without it.
#[test]
fn a_misspelled_parameter_is_refused() {
    let u = write("ok4.csv", "u\n1\n2\n");
    let p = write(
        "typo.json",
        r#"{"mass": 1, "damping": 1, "stiffness": 1, "cubic_stifness": 5}"#,
    );
    let err = simulate_fails(&["--input", s(&u), "--fs", "750", "--params", s(&p)]);
    assert!(
        err.contains("typo.json")
            && err.contains("unknown field `cubic_stifness`")
            && err.contains("`cubic_stiffness`"),
        "{err}"
    );
    let err = simulate_fails(&[
        "--input",
        s(&u),
        "--fs",
        "750",
        "--params",
        &format!("{}#/model", p.display()),
    ]);
    assert!(err.contains("nothing at `#/model`"), "{err}");
}

/// `,` `;` and tab records, quoted numbers, a byte-order mark and CRLF simulate alike;
/// `--delimiter` names the separator when detection is not wanted.
#[test]
fn every_delimiter_simulates_alike() {
    let run = |name: &str, text: &str, more: &[&str]| {
        let input = write(name, text);
        let out = tmp(&format!("out_{name}"));
        let mut args = vec![
            "simulate",
            "--input",
            s(&input),
            "--fs",
            "750",
            "--out",
            s(&out),
        ];
        args.extend(more);
        let (ok, _, err) = hyst(&args);
        assert!(ok, "{name}: {err}");
        std::fs::read_to_string(out).unwrap()
    };
    let plain = run("d_plain.csv", "t,u\n0,1.5\n1,-2\n2,0.25\n", &[]);
    for (name, text, more) in [
        ("d_semi.csv", "t;u\n0;1,5\n1;-2\n2;0,25\n", &[][..]),
        ("d_tab.csv", "t\tu\n0\t1.5\n1\t-2\n2\t0.25\n", &[]),
        (
            "d_quoted.csv",
            "\u{feff}\"t\",\"u\"\r\n\"0\",\"1.5\"\r\n1,-2\r\n2,\"0.25\"\r\n",
            &[],
        ),
        (
            "d_given.csv",
            "t;u\n0;1.5\n1;-2\n2;0.25\n",
            &["--delimiter", "semicolon"],
        ),
    ] {
        assert_eq!(run(name, text, more), plain, "{name}");
    }
}

#[test]
fn diverging_simulation_names_the_sample() {
    let u = write("ones.csv", &format!("u\n{}", "1\n".repeat(2000)));
    let p = write(
        "unstable.json",
        r#"{"mass": 1, "damping": 0, "stiffness": -1e6}"#,
    );
    let err = simulate_fails(&["--input", s(&u), "--fs", "750", "--params", s(&p)]);
    assert!(err.contains("diverged at sample"), "{err}");
}
