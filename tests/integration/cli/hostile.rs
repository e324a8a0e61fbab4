//! Issue 77's second hostile pass: each case it found said by name, not simulated, compared
//! or charted as if it made sense. The storey cases reuse the fit the storey test writes.

use super::{hyst, s, tmp, write};
use std::path::Path;

/// `hyst simulate --structure` and `hyst amplitude --model` on the fit `json` (three loaded
/// floors, accelerations a1..a3 at 200 Hz), with `record` holding forces f1..f3 and the
/// response, and `data` the fit's three levels.
pub(super) fn storey_surfaces_refuse_by_name(json: &Path, record: &Path, data: &[&str]) {
    let out = tmp("hostile_simulated.csv");
    // The structure `fit` driven by `input`'s forces f1..f3 at 200 Hz.
    let driven = |fit: &Path, input: &Path| {
        hyst(&[
            "simulate",
            "--structure",
            s(fit),
            "--input",
            s(input),
            "--fs",
            "200",
            "--forces",
            "f1,f2,f3",
            "--out",
            s(&out),
        ])
    };
    let simulate = |more: &[&str]| {
        let mut args = vec!["simulate", "--structure", s(json), "--input", s(record)];
        args.extend(more);
        args.extend(["--out", s(&out)]);
        hyst(&args)
    };
    let forces = ["--fs", "200", "--forces", "f1,f2,f3"];
    let with = |more: &[&str]| {
        let mut args = forces.to_vec();
        args.extend(more);
        simulate(&args)
    };
    // Each was accepted and simulated as if it meant something.
    let cases: [(&[&str], &str); 8] = [
        (
            &["--fs", "nan", "--forces", "f1,f2,f3"],
            "--fs NaN: a sampling rate",
        ),
        (
            &["--fs", "200", "--forces", "f1,f1,f1"],
            "--forces: `f1` is named twice",
        ),
        (&["--samples", "10"], "--samples is the oscillator's"),
        (&["--oversample", "0"], "--oversample is the oscillator's"),
        (
            &["--compare-skip", "10"],
            "--compare-skip leaves samples out",
        ),
        (
            &["--channels", "a1,a2,a3"],
            "--channels names --measured's columns",
        ),
        (
            &["--measured", s(record), "--channels", "a1,a1,a1"],
            "--channels: `a1` is named twice",
        ),
        (
            &["--measured", s(record), "--channels", "f1,f2,f3"],
            "`f1` is one of the --forces",
        ),
    ];
    for (more, said) in cases {
        let (ok, _, err) = if more.contains(&"--forces") {
            simulate(more)
        } else {
            with(more)
        };
        assert!(!ok && err.contains(said), "{more:?}: {err}");
    }
    let (ok, _, err) = with(&["--measured", s(record), "--compare-skip", "12000"]);
    assert!(
        !ok && err.contains("--compare-skip 12000: the records compared have 12000 samples"),
        "{err}"
    );
    // Forces a million times the record's diverge: said as the forces', with their size.
    let text = std::fs::read_to_string(record).unwrap();
    let mut lines = text.lines();
    let mut loud = format!("{}\n", lines.next().unwrap());
    for line in lines {
        let cells: Vec<String> = line
            .split(',')
            .enumerate()
            .map(|(k, c)| match k < 3 {
                true => (c.parse::<f64>().unwrap() * 1e6).to_string(),
                false => c.to_string(),
            })
            .collect();
        loud.push_str(&(cells.join(",") + "\n"));
    }
    let loud = write("hostile_loud.csv", &loud);
    let (ok, _, err) = driven(json, &loud);
    assert!(
        !ok && err.contains("under its --forces (RMS") && err.contains("check their units"),
        "{err}"
    );
    // A field of the document is the document's fault, named with its flag and file (not
    // the record read next, nor "the structure was fitted at -1 Hz").
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap();
    v["building"]["fs"] = (-1.0).into();
    let edited = write("hostile_fs.json", &v.to_string());
    let (ok, _, err) = driven(&edited, record);
    assert!(
        !ok && err.contains(&format!("--structure {}", s(&edited))) && err.contains("`fs` = -1"),
        "{err}"
    );
    let mut args = vec!["amplitude", "--fs", "200", "--model", s(&edited), "--input"];
    args.extend(data);
    let (ok, _, err) = hyst(&args);
    assert!(
        !ok && err.contains(&format!("--model {}", s(&edited))) && !err.contains("beside"),
        "{err}"
    );
    // A gain 300 decades from 1 overflowed into NaN distances.
    let mut args = vec!["amplitude", "--fs", "200", "--model", s(json), "--gains"];
    args.extend(["1e-300,1,1", "--input"]);
    args.extend(data);
    let (ok, _, err) = hyst(&args);
    assert!(!ok && err.contains("more than 12 decades from 1"), "{err}");
    // The one-oscillator route's periodic flags are not the structure's.
    let mut args = vec!["levels", "--fs", "200", "--masses", "1000,1000,800"];
    args.extend(["--data-periodic", "--data"]);
    args.extend(data);
    let (ok, _, err) = hyst(&args);
    assert!(!ok && err.contains("--data-periodic"), "{err}");
    // One record given as two levels was fitted as two that agree exactly.
    let (ok, _, err) = hyst(&[
        "levels",
        "--fs",
        "200",
        "--masses",
        "1000,1000,800",
        "--data",
        data[0],
        data[0],
    ]);
    assert!(!ok && err.contains("given as level 1 and level 2"), "{err}");
}

/// Records' surfaces: a time column in milliseconds, an unnamed header cell, a --fs that
/// the time column only nearly agrees with, a geometry nothing draws, a campaign trained
/// on every record.
#[test]
fn records_say_what_they_hold() {
    let mut ms = String::from("time_ms,a,b\n");
    let mut unnamed = String::from(",a,b\n");
    for i in 0..4000 {
        let t = i as f64 * 0.05;
        let (a, b) = ((7.0 * t).sin(), (17.0 * t).cos() + 0.3 * (7.0 * t).sin());
        ms.push_str(&format!("{},{a},{b}\n", 50 * i));
        unnamed.push_str(&format!("{i},{a},{b}\n"));
    }
    let ms = write("hostile_ms.csv", &ms);
    let (ok, out, err) = hyst(&["ssi", "--input", s(&ms), "--max-order", "8"]);
    // 50 ms steps: 20 Hz, not 0.02.
    assert!(
        ok && out.contains("at 20 Hz (from the time column `time_ms`)"),
        "{out}{err}"
    );
    let (ok, out, err) = hyst(&["ssi", "--input", s(&ms), "--fs", "20.1", "--max-order", "8"]);
    assert!(
        ok && out.contains("at 20.1 Hz (as --fs gives; the time column `time_ms` reads 20 Hz)"),
        "{out}{err}"
    );
    let unnamed = write("hostile_unnamed.csv", &unnamed);
    let (ok, _, err) = hyst(&["ssi", "--input", s(&unnamed), "--fs", "20"]);
    assert!(
        !ok && err.contains("the header leaves column 1 unnamed"),
        "{err}"
    );
    // --names names it, and then the file reads.
    let (ok, _, err) = hyst(&[
        "ssi",
        "--input",
        s(&unnamed),
        "--fs",
        "20",
        "--names",
        "k,a,b",
        "--columns",
        "a,b",
        "--max-order",
        "8",
    ]);
    assert!(ok, "{err}");
}

/// A campaign trained on every record was reported as "no alarm", though nothing was
/// charted.
#[test]
fn a_campaign_with_nothing_after_its_training_says_so() {
    let mut text = String::from("record,time,m1_hz,m1_hz_se\n");
    for i in 0..8 {
        let f = 2.0 + 0.001 * ((i * 7 % 5) as f64 - 2.0);
        text.push_str(&format!("r{i},{},{f},0.001\n", 3600 * i));
    }
    let est = write("hostile_estimates.csv", &text);
    let run = |training: &str| {
        let o = tmp(&format!("hostile_track_{training}"));
        let _ = std::fs::remove_dir_all(&o);
        hyst(&[
            "track",
            "--estimates",
            s(&est),
            "--training",
            training,
            "--out",
            s(&o),
        ])
    };
    for training in ["8", "100"] {
        let (ok, out, err) = run(training);
        assert!(ok, "{err}");
        assert!(
            out.contains("nothing monitored: every record trained") && !out.contains("no alarm"),
            "{out}"
        );
    }
    let (ok, out, err) = run("4");
    assert!(ok && !out.contains("nothing monitored"), "{out}{err}");
}

/// Two setups cut from the measured 3-DOF record: a --geometry nothing draws was not read
/// (its faults unsaid), and a merge that found nothing printed an empty table.
#[test]
fn setups_read_the_geometry_given_and_say_an_empty_merge() {
    let Some(path) = super::common::data_file("oma/data_3dof.csv") else {
        return;
    };
    let text = std::fs::read_to_string(path).unwrap();
    let rows: Vec<Vec<&str>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    let cut = |name: &str, from: usize, other: usize| {
        let mut t = format!("t,y1,y{other}\n");
        for r in &rows[from..from + 6000] {
            t.push_str(&format!("{},{},{}\n", r[0], r[1], r[other]));
        }
        write(name, &t)
    };
    cut("hostile_s1.csv", 0, 2);
    cut("hostile_s2.csv", 6000, 3);
    let setups = write(
        "hostile_setups.csv",
        "setup,file,column,node,direction,quantity,reference\n\
         one,hostile_s1.csv,y1,1,x,displacement,yes\none,hostile_s1.csv,y2,2,x,displacement,no\n\
         two,hostile_s2.csv,y1,1,x,displacement,yes\ntwo,hostile_s2.csv,y3,3,x,displacement,no\n",
    );
    let grid = write(
        "hostile_grid.txt",
        "name x y z\n1 0 0 0\n2 nan 0 0\n3 0 0 1\n",
    );
    let (ok, _, err) = hyst(&[
        "ssi",
        "--setups",
        s(&setups),
        "--max-order",
        "20",
        "--geometry",
        s(&grid),
    ]);
    assert!(!ok && err.contains("`nan` is not a coordinate"), "{err}");
    // Decimated by 64 (Nyquist 0.16 Hz, every mode above it): said, not an empty table.
    let (ok, out, err) = hyst(&[
        "ssi",
        "--setups",
        s(&setups),
        "--max-order",
        "20",
        "--decimate",
        "64",
    ]);
    assert!(ok, "{err}");
    assert!(
        out.contains("no mode found in any setup") && out.contains("  no mode found\n"),
        "{out}"
    );
}
