//! `hyst track`: campaigns of files, windows and estimates, resumed from the store, with gaps.

use super::*;

/// `hyst track` over windows of one record: every window's modes tracked; a second run
/// finds every record done and gives the same report (the store's rows unchanged); a run
/// cut short (four records kept) continues with the rest; an empty folder is an error.
#[test]
fn track_windows_resumes_and_refuses_no_records() {
    let Some(path) = common::data_file("oma/data_3dof.csv") else {
        return;
    };
    let out = tmp("track");
    let _ = std::fs::remove_dir_all(&out);
    let args = [
        "track",
        "--input",
        s(&path),
        "--fs",
        "20",
        "--window",
        "300",
        "--columns",
        "y1,y2,y3",
        "--out",
        s(&out),
        // The refinement, as the 3-DOF record's white load allows: it confirms the 4 Hz
        // mode the jackknife finds in too few replicates of one window (SSI's answer alone
        // loses it there, and keeps a fourth mode in another).
        "--refine",
    ];
    let (ok, first, err) = hyst(&args);
    assert!(ok, "{err}");
    assert!(
        first.contains("3 reference mode(s); 10 record(s) with modes, 0 skipped"),
        "{first}"
    );
    for m in 0..3 {
        assert!(
            first.contains(&format!("mode {}: ", m + 1)) && first.contains("tracked in 100.0 %"),
            "{first}"
        );
    }
    let store = out.join("store.sqlite");
    let rows = || stored_rows(&store);
    let stored = rows();
    assert_eq!(stored.len(), 10);
    let (ok, again, err) = hyst(&args);
    assert!(ok, "{err}");
    assert_eq!(again, first);
    assert_eq!(rows(), stored);
    // Cut short: the first four records kept; the rest identified again, the same report.
    rusqlite::Connection::open(&store)
        .unwrap()
        .execute("DELETE FROM records WHERE CAST(name AS INTEGER) >= 4", [])
        .unwrap();
    assert_eq!(rows().len(), 4);
    let (ok, resumed, err) = hyst(&args);
    assert!(ok, "{err}");
    assert_eq!(resumed, first);
    assert_eq!(rows().len(), 10);
    let table = std::fs::read_to_string(out.join("table.csv")).unwrap();
    assert_eq!(table.lines().count(), 1 + 30);
    let rows = std::fs::read_to_string(out.join("table.jsonl")).unwrap();
    assert_eq!(rows.lines().count(), 30);
    let row: serde_json::Value = serde_json::from_str(rows.lines().next().unwrap()).unwrap();
    assert_eq!(
        (row["record"].as_u64(), row["mode"].as_u64()),
        (Some(0), Some(0))
    );
    // A reference from `hyst ssi --json` on the whole record: its modes are the report's.
    let modes = tmp("track_reference.json");
    let (ok, _, err) = hyst(&[
        "ssi",
        "--input",
        s(&path),
        "--fs",
        "20",
        "--columns",
        "y1,y2,y3",
        "--lag-seconds",
        "3",
        "--json",
        s(&modes),
    ]);
    assert!(ok, "{err}");
    let figures = tmp("track_figures");
    // An earlier run's figures would stand in for missing ones.
    let _ = std::fs::remove_dir_all(&figures);
    let mut with_ref = args.to_vec();
    with_ref.extend(["--reference", s(&modes), "--svg-dir", s(&figures)]);
    let (ok, _, err) = hyst(&with_ref);
    assert!(ok, "{err}");
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&modes).unwrap()).unwrap();
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let f = |v: &serde_json::Value| v["frequency_hz"].as_f64().unwrap();
    // The reference is the document's answer (`modes`).
    let want: Vec<f64> = doc["modes"].as_array().unwrap().iter().map(f).collect();
    let got: Vec<f64> = report["reference"]
        .as_array()
        .unwrap()
        .iter()
        .map(f)
        .collect();
    assert_eq!(got, want);
    // Named as the text names the modes: from 1.
    for j in 1..=3 {
        for what in ["frequency", "damping"] {
            let svg = std::fs::read_to_string(figures.join(format!("mode{j}_{what}.svg"))).unwrap();
            assert!(
                svg.starts_with("<svg") && svg.contains("standard error"),
                "{j} {what}"
            );
        }
    }
    let (ok, _, err) = hyst(&[
        "track",
        "--input",
        s(&path),
        "--fs",
        "20",
        "--window",
        "300",
        "--out",
        s(&out),
        "--reference",
        s(&path),
    ]);
    assert!(
        !ok && err.contains("--reference") && err.contains("not JSON"),
        "{err}"
    );
    // Covariates by window number: they reach the table; one window without them.
    let cov = write(
        "track_cov.csv",
        &(0..9).fold("record,time,temperature\n".to_string(), |t, i| {
            t + &format!("{i},{},{}\n", 3600 * i, 10 + i)
        }),
    );
    let mut with_cov = args.to_vec();
    with_cov.extend(["--covariates", s(&cov)]);
    let (ok, _, err) = hyst(&with_cov);
    assert!(ok, "{err}");
    let table = std::fs::read_to_string(out.join("table.csv")).unwrap();
    assert!(
        table.lines().next().unwrap().ends_with(",temperature"),
        "{table}"
    );
    assert!(
        table.lines().nth(4).unwrap().starts_with("1,3600,"),
        "{table}"
    );
    assert!(table.lines().last().unwrap().ends_with(",NaN"), "{table}");
    let empty = tmp("track_empty");
    std::fs::create_dir_all(&empty).unwrap();
    let (ok, _, err) = hyst(&[
        "track",
        "--inputs",
        s(&empty),
        "--fs",
        "20",
        "--out",
        s(&out),
    ]);
    assert!(!ok && err.contains("no records"), "{err}");
}

/// `hyst track --estimates` on the modes `hyst track` itself identified (its table pivoted to
/// one row per record, a column per mode) charts the same standardized residuals and
/// innovations, record by record and mode by mode: another system's estimates get the same
/// normalization. Without standard errors the noise is read from the training rows and said;
/// a 1 % step in one mode's later estimates is alarmed on that mode alone; a bad table is an
/// error naming the column.
#[test]
fn track_estimates_charts_as_the_records_do() {
    let Some(path) = common::data_file("oma/data_3dof.csv") else {
        return;
    };
    let cov = write(
        "track_est_cov.csv",
        &(0..10).fold("record,time,temperature\n".to_string(), |t, i| {
            t + &format!("{i},{},{}\n", 3600 * i, 10.0 + (i * 7 % 5) as f64)
        }),
    );
    let out = tmp("track_est_records");
    let _ = std::fs::remove_dir_all(&out);
    let (ok, _, err) = hyst(&[
        "track",
        "--input",
        s(&path),
        "--fs",
        "20",
        "--window",
        "300",
        "--columns",
        "y1,y2,y3",
        "--covariates",
        s(&cov),
        "--training",
        "6",
        "--out",
        s(&out),
        // Every window's three modes, as the refinement finds them on this white load.
        "--refine",
    ]);
    assert!(ok, "{err}");
    let table = std::fs::read_to_string(out.join("table.csv")).unwrap();
    let rows: Vec<Vec<String>> = table
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    // Columns: record,time_s,mode,frequency_hz,frequency_se_hz,damping_ratio,damping_se,mac,
    // misfit_flag,z,innovation,alarm,extrapolated,temperature.
    let cell = |rec: usize, mode: usize, col: usize| -> String {
        rows.iter()
            .find(|r| r[0] == rec.to_string() && r[2] == (mode + 1).to_string())
            .map_or(String::new(), |r| r[col].clone())
    };
    let pivot = |with_se: bool, step: f64| {
        let mut text = String::from("record");
        // The modes named as hyst's table names its own (from 1), so the tables compare.
        for m in 1..=3 {
            text += &format!(",{m}_hz");
            if with_se {
                text += &format!(",{m}_hz_se");
            }
            text += &format!(",{m}_damping");
        }
        text.push('\n');
        for rec in 0..10 {
            text += &rec.to_string();
            for m in 0..3 {
                let f: f64 = cell(rec, m, 3).parse().unwrap();
                let f = if m == 1 && rec >= 6 {
                    f * (1.0 + step)
                } else {
                    f
                };
                text += &format!(",{f:e}");
                if with_se {
                    text += &format!(",{}", cell(rec, m, 4));
                }
                text += &format!(",{}", cell(rec, m, 5));
            }
            text.push('\n');
        }
        text
    };
    let run = |name: &str, text: &str| {
        let est = write(&format!("{name}.csv"), text);
        let o = tmp(name);
        let _ = std::fs::remove_dir_all(&o);
        let (ok, stdout, err) = hyst(&[
            "track",
            "--estimates",
            s(&est),
            "--covariates",
            s(&cov),
            "--training",
            "6",
            "--out",
            s(&o),
        ]);
        (
            ok,
            stdout,
            err,
            std::fs::read_to_string(o.join("table.csv")).unwrap_or_default(),
        )
    };
    let (ok, _, err, same) = run("track_est_same", &pivot(true, 0.0));
    assert!(ok, "{err}");
    let again: Vec<Vec<String>> = same
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    assert_eq!(again.len(), rows.len());
    let mut charted = 0;
    for (a, b) in rows.iter().zip(&again) {
        // Record, time, mode, frequency, its error, z, innovation, alarm, extrapolated,
        // temperature.
        for c in [0, 1, 2, 3, 4, 9, 10, 11, 12, 13] {
            assert_eq!(a[c], b[c], "column {c} of {a:?} against {b:?}");
        }
        charted += usize::from(!a[9].is_empty());
    }
    assert_eq!(charted, 12, "records 6–9, three modes each, charted");
    let (ok, stdout, err, _) = run("track_est_nose", &pivot(false, 0.0));
    assert!(ok, "{err}");
    assert!(
        stdout
            .contains("no standard errors given: the estimation noise read from the training rows"),
        "{stdout}"
    );
    let (ok, stdout, err, stepped) = run("track_est_step", &pivot(true, 0.01));
    assert!(ok, "{err}");
    let alarmed: Vec<&str> = stepped
        .lines()
        .skip(1)
        .filter(|l| !l.split(',').nth(11).unwrap_or("").is_empty())
        .map(|l| l.split(',').nth(2).unwrap_or(""))
        .collect();
    assert!(
        !alarmed.is_empty() && alarmed.iter().all(|m| *m == "2"),
        "alarms on modes {alarmed:?}\n{stdout}"
    );
    let (ok, _, err, _) = run("track_est_bad", "record,m0_hz,colour\n0,1.2,red\n");
    assert!(!ok && err.contains("unknown column `colour`"), "{err}");
}

/// `hyst track` on files never serves a stale or wrong result: a run resumed with another
/// `--fs` gives what a fresh run with it gives (it served the first run's 1.0 Hz where the
/// fresh run gives 2.0); records are taken in natural order (rec_2 before rec_10); a record
/// with the channels in another order is matched by name, one with other channels skipped
/// with the reason; the run's own outputs inside the input folder are not read as records; a
/// store another process holds refuses a second run.
#[test]
fn track_files_resume_only_what_is_unchanged() {
    let Some(path) = common::data_file("oma/data_3dof.csv") else {
        return;
    };
    let t = hyst::io::read_csv(&path).unwrap();
    let dir = tmp("track_files");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let col = |c: &str| t.column(c).unwrap().to_vec();
    let (y1, y2, y3) = (col("y1"), col("y2"), col("y3"));
    for k in 1..=10 {
        let r = (k - 1) * 6000..k * 6000;
        let (names, cols): (Vec<&str>, Vec<&[f64]>) = match k {
            // Another order of the same channels, and a record missing one.
            4 => (
                vec!["y2", "y1", "y3"],
                vec![&y2[r.clone()], &y1[r.clone()], &y3[r]],
            ),
            7 => (vec!["y1", "y2"], vec![&y1[r.clone()], &y2[r]]),
            _ => (
                vec!["y1", "y2", "y3"],
                vec![&y1[r.clone()], &y2[r.clone()], &y3[r]],
            ),
        };
        hyst::io::write_csv(&dir.join(format!("rec_{k}.csv")), &names, &cols).unwrap();
    }
    // --out the input folder itself: the run's own files (the store, the tables, the
    // report, the lock) are not records.
    let out = dir.clone();
    let files: Vec<PathBuf> = (1..=10).map(|k| dir.join(format!("rec_{k}.csv"))).collect();
    let run = |fs: &str, out: &Path, inputs: &[&str]| {
        let mut args = vec!["track", "--inputs"];
        args.extend_from_slice(inputs);
        args.extend(["--fs", fs, "--training", "4", "--out", s(out)]);
        let (ok, text, err) = hyst(&args);
        assert!(ok, "{err}");
        text
    };
    let folder = [s(&dir)];
    let first = run("20", &out, &folder);
    assert!(first.contains("10 records, in natural order"), "{first}");
    assert!(first.contains("1 skipped"), "{first}");
    let table = std::fs::read_to_string(out.join("table.csv")).unwrap();
    let order: Vec<&str> = table
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap())
        .collect();
    let mut seen: Vec<&str> = order.clone();
    seen.dedup();
    assert_eq!(
        seen,
        [
            "rec_1.csv",
            "rec_2.csv",
            "rec_3.csv",
            "rec_4.csv",
            "rec_5.csv",
            "rec_6.csv",
            "rec_8.csv",
            "rec_9.csv",
            "rec_10.csv"
        ],
        "{table}"
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let skipped = report.to_string();
    assert!(
        skipped.contains("differ from the first record's y1,y2,y3"),
        "{skipped}"
    );
    // The same run again (its outputs now in the input folder): the same report.
    assert_eq!(run("20", &out, &folder), first);
    // Another rate: every record identified again, as a fresh run does.
    let fresh = tmp("track_files_fresh");
    let _ = std::fs::remove_dir_all(&fresh);
    let at40 = run("40", &out, &folder);
    let listed: Vec<&str> = files.iter().map(|f| s(f)).collect();
    assert_eq!(at40, run("40", &fresh, &listed));
    assert_ne!(at40, first);
    // A store held by another process (here this test's) refuses a second run.
    let held = hyst::store::CampaignStore::open(&out).unwrap();
    let (ok, _, err) = hyst(&["track", "--inputs", s(&dir), "--fs", "20", "--out", s(&out)]);
    assert!(!ok && err.contains("another `hyst track`"), "{err}");
    drop(held);
}

/// The rows of a campaign store, `(name, key, record)`, in name order.
fn stored_rows(store: &Path) -> Vec<(String, String, String)> {
    let conn = rusqlite::Connection::open(store).unwrap();
    let mut q = conn
        .prepare("SELECT name, key, record FROM records ORDER BY name")
        .unwrap();
    q.query_map([], |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?)))
        .unwrap()
        .map(Result::unwrap)
        .collect()
}

/// A file missing from a campaign whose covariates give every record a time leaves a gap at
/// its time, said, never a shift: the later records keep their places (their record numbers
/// in the table), and the gap is skipped with the reason.
#[test]
fn track_a_missing_file_leaves_a_gap() {
    let Some(path) = common::data_file("oma/data_3dof.csv") else {
        return;
    };
    let t = hyst::io::read_csv(&path).unwrap();
    let dir = tmp("track_gap");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let mut cov = "record,time,temperature\n".to_string();
    for k in 0..6 {
        cov.push_str(&format!("rec_{k}.csv,{},{}\n", 3600 * k, 10 + k));
        if k == 3 {
            continue;
        }
        let r = k * 6000..(k + 1) * 6000;
        let cols: Vec<&[f64]> = ["y1", "y2", "y3"]
            .iter()
            .map(|c| &t.column(c).unwrap()[r.clone()])
            .collect();
        hyst::io::write_csv(
            &dir.join(format!("rec_{k}.csv")),
            &["y1", "y2", "y3"],
            &cols,
        )
        .unwrap();
    }
    let covariates = tmp("track_gap_cov.csv");
    std::fs::write(&covariates, cov).unwrap();
    let out = tmp("track_gap_out");
    let _ = std::fs::remove_dir_all(&out);
    let run = |extra: &[&str]| {
        let mut args = vec![
            "track",
            "--inputs",
            s(&dir),
            "--fs",
            "20",
            "--covariates",
            s(&covariates),
            "--out",
            s(&out),
        ];
        args.extend_from_slice(extra);
        hyst(&args)
    };
    let (ok, stdout, err) = run(&[]);
    assert!(ok, "{err}");
    assert!(
        stdout.contains("6 records, in the order of their time"),
        "{stdout}"
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let skipped = report["skipped"].to_string();
    assert!(
        skipped.contains("rec_3.csv") && skipped.contains("a gap in the campaign"),
        "{skipped}"
    );
    let table = std::fs::read_to_string(out.join("table.csv")).unwrap();
    let places: Vec<(String, String)> = table
        .lines()
        .skip(1)
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            (c[0].to_string(), c[1].to_string())
        })
        .collect();
    assert!(
        places.contains(&("rec_4.csv".into(), "14400".into())),
        "{table}"
    );
    assert!(!places.iter().any(|(r, _)| r == "rec_3.csv"), "{table}");
    // The excitation level as a covariate: a column after the file's, named in the text.
    let (ok, stdout, err) = run(&["--level-covariate"]);
    assert!(ok, "{err}");
    let table = std::fs::read_to_string(out.join("table.csv")).unwrap();
    assert!(
        table
            .lines()
            .next()
            .unwrap()
            .ends_with(",temperature,log_rms"),
        "{table}"
    );
    assert!(stdout.contains("log_rms"), "{stdout}");
}
