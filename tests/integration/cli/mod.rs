//! The `hyst` program end to end: its outputs and its errors on bad input, one module per
//! command as `src/cmd/` has them; here what every command shares (reading a record, the
//! outputs' guard, values refused up front) and the helpers.

use crate::common;

mod amplitude;
mod frf;
mod hostile;
mod ident;
mod levels;
mod options;
mod refine;
mod simulate;
mod ssi;
mod track;

use std::path::{Path, PathBuf};
use std::process::Command;

/// A parameter of a model in the schema reports write, by its short name: `m`, `c`, `k`, the
/// Bouc-Wen element's `alpha`, `beta_gamma`, `beta_delta`, `nu` and the Zener's `k_inf`,
/// `omega`.
fn param(model: &serde_json::Value, key: &str) -> Option<f64> {
    let v = match key {
        "m" => &model["mass"],
        "c" => &model["damping"],
        "k" => &model["stiffness"],
        "alpha" | "beta_gamma" | "beta_delta" | "nu" => &model["bouc_wen"][key],
        "k_inf" | "omega" => &model["zener"][key],
        other => &model[other],
    };
    v.as_f64()
}

fn hyst(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_hyst"))
        .args(args)
        .output()
        .expect("the hyst binary runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A path for the scratch file `name`: under cargo's per-target scratch folder, one folder
/// that every run reuses (a folder per process in the system's temp left 50 MB behind per run).
fn tmp(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("cli");
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn write(name: &str, text: &str) -> PathBuf {
    let p = tmp(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// A one-column record `y` of 20 000 samples of unit white noise.
fn write_white_noise(name: &str, seed: u64) -> PathBuf {
    let noise = hyst::sim::excitation::white_noise(20000, 1.0, seed).unwrap();
    let text: String = noise.iter().map(|v| format!("{v}\n")).collect();
    write(name, &format!("y\n{text}"))
}

/// A record `u,y` of `n` rows: two sines.
fn write_input_output(name: &str, n: usize) -> PathBuf {
    let rows: String = (0..n)
        .map(|k| format!("{},{}\n", (0.1 * k as f64).cos(), (0.3 * k as f64).sin()))
        .collect();
    write(name, &format!("u,y\n{rows}"))
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Run `hyst simulate` expecting failure; return stderr.
fn simulate_fails(args: &[&str]) -> String {
    let out = tmp("never.csv");
    let mut all = vec!["simulate"];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--out", s(&out)]);
    let (ok, _, err) = hyst(&all);
    assert!(!ok, "expected failure for {args:?}");
    assert!(err.starts_with("error:"), "stderr: {err}");
    err
}

/// Write `text` to the file `name` and run `hyst simulate` on it at 750 Hz, expecting
/// failure; return stderr.
fn simulate_fails_on(name: &str, text: &str) -> String {
    let p = write(name, text);
    simulate_fails(&["--input", s(&p), "--fs", "750"])
}

#[test]
fn missing_file() {
    let err = simulate_fails(&["--input", "/nonexistent/u.csv", "--fs", "750"]);
    assert!(err.contains("/nonexistent/u.csv"), "{err}");
}

#[test]
fn missing_column() {
    let err = simulate_fails_on("nocol.csv", "a,b\n1,2\n");
    assert!(
        err.contains("no column `u`") && err.contains("a,b"),
        "{err}"
    );
}

#[test]
fn non_numeric_cell_names_its_row() {
    let err = simulate_fails_on("text.csv", "u\n1\n2\nabc\n");
    assert!(err.contains("row 4") && err.contains("`abc`"), "{err}");
}

#[test]
fn nan_cell() {
    let err = simulate_fails_on("nan.csv", "u\n1\nNaN\n");
    assert!(err.contains("row 3") && err.contains("not finite"), "{err}");
}

#[test]
fn row_with_too_many_or_too_few_cells_names_its_row() {
    // An extra cell would otherwise be dropped silently, shifting nothing but hiding a
    // malformed file; a missing one would leave the columns of unequal length.
    let err = simulate_fails_on("long_row.csv", "u,y\n1,2\n3,4,5\n");
    assert!(
        err.contains("long_row.csv") && err.contains("row 3 has 3 cells, the header has 2"),
        "{err}"
    );
    let err = simulate_fails_on("short_row.csv", "u,y\n1,2\n3\n");
    assert!(err.contains("row 3 has 1 cells, the header has 2"), "{err}");
}

#[test]
fn a_column_named_twice_is_an_error() {
    // In the header, a column asked for by name would be ambiguous; in --columns, the same
    // channel twice makes the Toeplitz matrix rank-deficient and says nothing new.
    let err = simulate_fails_on("dup_header.csv", "u,u\n1,2\n");
    assert!(
        err.contains("dup_header.csv") && err.contains("names column `u` twice"),
        "{err}"
    );
    let err = ssi_fails_on_columns("a,b,a");
    assert!(err.contains("--columns names `a` twice"), "{err}");
}

#[test]
fn empty_record() {
    let err = simulate_fails_on("empty.csv", "u,y\n");
    assert!(err.contains("empty"), "{err}");
}

#[test]
fn non_positive_sampling_rate() {
    let p = write("ok.csv", "u\n1\n2\n");
    let err = simulate_fails(&["--input", s(&p), "--fs", "0"]);
    assert!(err.contains("--fs") && err.contains('0'), "{err}");
    let err = simulate_fails(&["--input", s(&p), "--fs=-3"]);
    assert!(err.contains("-3"), "{err}");
}

/// Values that can never work are refused with the program's own words before any work:
/// negative numbers reach its checks (not the parser's "unexpected argument"), a sweep that
/// would be NaN is not written, and a flatness band above Nyquist or an empty period are not
/// left to a note after the whole pipeline.
#[test]
fn impossible_values_are_refused_up_front() {
    let rec = write_input_output("uy600.csv", 600);
    let out = tmp("never.csv");
    let ident = |extra: &[&str]| {
        let mut args = vec!["ident", "--data", s(&rec), "--fs", "750"];
        args.extend_from_slice(extra);
        hyst(&args)
    };
    for (run, said) in [
        (ident(&["--mass", "-1"]), "mass must be > 0 kg, got -1"),
        (
            ident(&["--mass", "2", "--c", "-0.5"]),
            "--c must be a number >= 0 N s/m, got -0.5",
        ),
        (
            ident(&[
                "--mass",
                "2",
                "--excitation-band",
                "500:600",
                "--period",
                "600",
            ]),
            "--excitation-band 500:600 --period 600: excitation band 500..600 Hz reaches above the Nyquist frequency 375 Hz of 750 Hz",
        ),
        (
            ident(&["--mass", "2", "--excitation-band", "5:150", "--period", "0"]),
            "--excitation-band 5:150 --period 0: the excitation's period must be at least 2 samples, got 0",
        ),
        (
            hyst(&[
                "excite",
                "--excitation",
                "sweep",
                "--rms",
                "1",
                "--samples",
                "100",
                "--fs",
                "750",
                "--f-min",
                "nan",
                "--out",
                s(&out),
            ]),
            "invalid signal parameter `sweep start frequency`: NaN",
        ),
        (
            hyst(&[
                "simulate",
                "--excitation",
                "white",
                "--rms",
                "-3",
                "--samples",
                "100",
                "--out",
                s(&out),
            ]),
            "invalid signal parameter `rms`: -3",
        ),
    ] {
        let (ok, _, err) = run;
        assert!(!ok && err.contains(said), "expected `{said}`, got: {err}");
    }
}

/// An output file in a folder that does not exist is refused before any work (`hyst ssi`
/// used to run its refinement first), with the flag and the folder named.
#[test]
fn an_output_in_a_missing_folder_is_refused_before_any_work() {
    let rec = write_input_output("uy_out.csv", 600);
    let missing = tmp("no-such-folder").join("x.json");
    let m = s(&missing);
    for (args, flag) in [
        (
            vec!["ssi", "--input", s(&rec), "--fs", "10", "--json", m],
            "--json",
        ),
        (
            vec![
                "ssi",
                "--input",
                s(&rec),
                "--fs",
                "10",
                "--json",
                s(&tmp("fine.json")),
                "--svg",
                m,
            ],
            "--svg",
        ),
        (
            vec![
                "simulate",
                "--excitation",
                "white",
                "--rms",
                "1",
                "--samples",
                "100",
                "--out",
                m,
            ],
            "--out",
        ),
        (
            vec!["ident", "--data", s(&rec), "--fs", "750", "--json", m],
            "--json",
        ),
        (
            vec![
                "frf",
                "--input",
                s(&rec),
                "--fs",
                "750",
                "--force",
                "u",
                "--period",
                "100",
                "--band",
                "5:100",
                "--write-flat",
                m,
            ],
            "--write-flat",
        ),
    ] {
        let (ok, out, err) = hyst(&args);
        let said = format!("{flag} {m}: the folder ");
        assert!(
            !ok && err.contains(&said) && err.contains("does not exist"),
            "{args:?}: {err}"
        );
        // Nothing was computed: no line of results was printed.
        assert!(out.is_empty(), "{args:?}: {out}");
    }
}

/// Run `hyst ssi --input FILE --fs 10` with these further arguments, expecting failure;
/// return stderr.
fn ssi_fails(input: &Path, args: &[&str]) -> String {
    let json = tmp("failed.json");
    let mut all = vec!["ssi", "--input", s(input), "--fs", "10"];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--json", s(&json)]);
    let (ok, _, err) = hyst(&all);
    assert!(!ok, "expected failure for {args:?}");
    err
}

/// `hyst ssi` on a two-column record `a,b` with these `--columns`, expecting failure.
fn ssi_fails_on_columns(columns: &str) -> String {
    let p = write("cols.csv", "a,b\n1,2\n3,4\n");
    ssi_fails(&p, &["--columns", columns])
}

/// The bytes of every file under `dir`, by path: what a refused run must leave unchanged.
fn snapshot(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut v = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let bytes = std::fs::read(&p).unwrap();
                v.push((p, bytes));
            }
        }
    }
    v.sort();
    v
}

/// Issue 58's guard, for every command and every output flag: the output set to each of
/// the command's input files, and to the folder holding them, is refused before anything
/// is read or written, naming the output's flag, and every input is left byte for byte as
/// it was (`hyst track` included: its `--out` tables against its records, `--estimates`,
/// `--covariates` and `--reference`; a record named like a table it writes, with no store
/// beside it, is a record, and refused rather than left out and overwritten).
#[test]
fn no_output_of_any_command_lands_on_an_input() {
    let dir = tmp("guard");
    let _ = std::fs::remove_dir_all(&dir);
    let recs = dir.join("recs");
    std::fs::create_dir_all(&recs).unwrap();
    let rec = write("guard/rec.csv", "u,y\n1,2\n3,4\n");
    let other = write("guard/rec2.csv", "u,y\n1,2\n3,4\n");
    let cov = write("guard/cov.csv", "record,t_air\na.csv,1\n");
    let reference = write("guard/ref.json", "{}");
    let params = write("guard/params.json", "{}");
    write("guard/recs/a.csv", "y\n1\n2\n");
    let table = write("guard/recs/table.csv", "y\n1\n2\n");
    let estimates = write("guard/table.csv", "record,f1_hz\na,1.0\n");
    let track_out = dir.join("track_out");
    let (d, r, o) = (s(&dir), s(&rec), s(&other));
    // (arguments, output flags, the input files the outputs are set to)
    let cases: Vec<(Vec<&str>, Vec<&str>, Vec<&Path>)> = vec![
        (
            vec!["ssi", "--input", r, "--fs", "20"],
            vec!["--json", "--svg", "--shapes-uff", "--html"],
            vec![&rec],
        ),
        (
            vec!["amplitude", "--input", r, o, "--fs", "20"],
            vec!["--json", "--svg"],
            vec![&rec, &other],
        ),
        (
            vec![
                "frf", "--input", r, "--fs", "20", "--force", "u", "--period", "8", "--band", "1:5",
            ],
            vec!["--json", "--svg", "--write-flat"],
            vec![&rec],
        ),
        (
            vec!["ident", "--data", r, "--fs", "20", "--validate", o],
            vec!["--json"],
            vec![&rec, &other],
        ),
        (
            vec!["refine", "--data", r, "--fs", "20"],
            vec!["--json"],
            vec![&rec],
        ),
        (
            vec!["levels", "--data", r, o, "--fs", "20", "--mass", "1"],
            vec!["--json"],
            vec![&rec, &other],
        ),
        (
            vec![
                "simulate",
                "--input",
                r,
                "--fs",
                "20",
                "--params",
                s(&params),
            ],
            vec!["--out"],
            vec![&rec, &params],
        ),
        (
            vec![
                "track",
                "--inputs",
                s(&recs),
                "--covariates",
                s(&cov),
                "--reference",
                s(&reference),
                "--out",
                s(&track_out),
            ],
            vec!["--html"],
            vec![&cov, &reference, &table],
        ),
    ];
    let before = snapshot(&dir);
    for (args, outputs, inputs) in &cases {
        for flag in outputs {
            let targets: Vec<&Path> = inputs.iter().copied().chain([dir.as_path()]).collect();
            for target in targets {
                let mut v = args.clone();
                v.extend([*flag, s(target)]);
                let (ok, _, err) = hyst(&v);
                assert!(!ok && err.contains(flag), "{v:?}: {err}");
                assert!(snapshot(&dir) == before, "{v:?} changed an input");
            }
        }
    }
    // hyst track's --out: its tables on --estimates, on --covariates' folder, and on a
    // folder of records where one is named like a table it writes.
    let e = s(&estimates);
    for v in [
        vec!["track", "--estimates", e, "--out", d],
        vec!["track", "--inputs", s(&recs), "--out", s(&recs)],
        vec!["track", "--inputs", s(&recs), "--out", r],
    ] {
        let (ok, _, err) = hyst(&v);
        assert!(!ok && err.contains("--out"), "{v:?}: {err}");
        assert!(snapshot(&dir) == before, "{v:?} changed an input");
    }
}
