//! `hyst track`'s campaign store under abuse: runs killed with SIGKILL at random moments and
//! resumed, and two runs on one store at once.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use rand::{RngExt, SeedableRng};

/// The arguments of a run over 16 windows of the 3-DOF OMA record into `out`.
fn args(record: &Path, out: &Path) -> Vec<String> {
    [
        "track",
        "--input",
        &record.display().to_string(),
        "--fs",
        "20",
        "--window",
        "200",
        "--columns",
        "y1,y2,y3",
        "--out",
        &out.display().to_string(),
    ]
    .map(String::from)
    .to_vec()
}

fn start(args: &[String]) -> std::process::Child {
    Command::new(env!("CARGO_BIN_EXE_hyst"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the hyst binary runs")
}

fn finish(child: std::process::Child) -> Output {
    child.wait_with_output().expect("the run ends")
}

/// A fresh scratch folder `name`.
fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("track_store")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// The store is whole: SQLite's integrity check passes and every row is a record.
fn check_store(store: &Path) -> usize {
    let conn = rusqlite::Connection::open(store).unwrap();
    let check: String = conn
        .query_row("PRAGMA integrity_check", [], |r| r.get(0))
        .unwrap();
    assert_eq!(check, "ok");
    let mut q = conn.prepare("SELECT record FROM records").unwrap();
    let rows: Vec<String> = q
        .query_map([], |r| r.get(0))
        .unwrap()
        .map(Result::unwrap)
        .collect();
    for row in &rows {
        let v: serde_json::Value = serde_json::from_str(row).expect("a whole record");
        assert!(v["name"].is_string(), "{row}");
    }
    rows.len()
}

/// Ten runs killed (SIGKILL) at moments drawn over what is left of an uninterrupted run's
/// length, each then resumed by the next: the store is whole after every kill (no half-written row, SQLite's
/// integrity check passes), it never loses a record it held, and the run that finishes gives
/// the uninterrupted run's report and table, byte for byte.
#[test]
fn runs_killed_at_random_moments_resume_to_the_same_report() {
    let Some(record) = common::data_file("oma/data_3dof.csv") else {
        return;
    };
    let whole = scratch("whole");
    let t0 = Instant::now();
    let clean = finish(start(&args(&record, &whole)));
    let length = t0.elapsed();
    assert!(
        clean.status.success(),
        "{}",
        String::from_utf8_lossy(&clean.stderr)
    );
    let out = scratch("killed");
    let store = out.join("store.sqlite");
    let mut rng = rand::rngs::StdRng::seed_from_u64(20261127);
    let mut held = 0;
    let mut kills = 0;
    for _ in 0..10 {
        if held == 16 {
            // Every record is stored: no run is left to cut short.
            break;
        }
        let mut child = start(&args(&record, &out));
        // Within the first half of what is left of the work (a resumed run skips the records
        // the store holds): a moment drawn over all of it let one run store 12 of the 16
        // records, and the rest finished before their moments.
        let left = 1.0 - held as f64 / 16.0;
        let at = length.mul_f64(left * rng.random_range(0.05..0.5));
        std::thread::sleep(at);
        if child.try_wait().unwrap().is_none() {
            child.kill().unwrap(); // SIGKILL on Unix
            kills += 1;
        }
        let _ = finish(child);
        if store.exists() {
            let now = check_store(&store);
            assert!(now >= held, "the store lost records: {held} then {now}");
            held = now;
            eprintln!("kill at {at:?}: the store holds {held} records");
        }
    }
    // Each kill leaves at least half of the work, so the runs are killed part-way through
    // at least five times (16 records halved four times leave one); a run that ends on its
    // own before its moment does not count as a kill.
    assert!(kills >= 5, "only {kills} runs were killed mid-run");
    let resumed = finish(start(&args(&record, &out)));
    assert!(
        resumed.status.success(),
        "{}",
        String::from_utf8_lossy(&resumed.stderr)
    );
    assert_eq!(check_store(&store), 16);
    assert_eq!(resumed.stdout, clean.stdout);
    for file in ["report.json", "table.csv", "table.parquet"] {
        assert_eq!(
            std::fs::read(out.join(file)).unwrap(),
            std::fs::read(whole.join(file)).unwrap(),
            "{file}"
        );
    }
}

/// Two runs on one store at once: one is refused with the reason (the store is held for the
/// whole run), the other ends with the report a lone run gives; the store is whole.
#[test]
fn a_second_run_at_once_is_refused_and_the_first_unharmed() {
    let Some(record) = common::data_file("oma/data_3dof.csv") else {
        return;
    };
    let alone = scratch("alone");
    let lone = finish(start(&args(&record, &alone)));
    assert!(lone.status.success());
    let out = scratch("together");
    let first = start(&args(&record, &out));
    // The second starts once the first holds the store.
    let t0 = Instant::now();
    while !out.join("store.sqlite").exists() && t0.elapsed() < Duration::from_secs(30) {
        std::thread::sleep(Duration::from_millis(5));
    }
    std::thread::sleep(Duration::from_millis(50));
    let second = finish(start(&args(&record, &out)));
    let first = finish(first);
    let err = String::from_utf8_lossy(&second.stderr);
    assert!(
        !second.status.success() && err.contains("another `hyst track` is writing"),
        "{err}"
    );
    assert!(
        first.status.success(),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    assert_eq!(first.stdout, lone.stdout);
    assert_eq!(check_store(&out.join("store.sqlite")), 16);
}
