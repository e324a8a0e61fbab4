//! `hyst track --follow`: records and rows of estimates taken as they land, the run killed
//! and started again, against batch runs over the same records.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

/// A fresh scratch folder `name`.
fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("track_follow")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// `hyst` started with `args`, its standard output into `log`.
fn start(args: &[&str], log: &Path) -> Child {
    Command::new(env!("CARGO_BIN_EXE_hyst"))
        .args(args)
        .stdout(Stdio::from(std::fs::File::create(log).unwrap()))
        .stderr(Stdio::null())
        .spawn()
        .expect("the hyst binary runs")
}

/// `hyst` run to its end with `args`; its standard output.
fn batch(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_hyst"))
        .args(args)
        .output()
        .expect("the hyst binary runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The records `out`'s table.csv lists.
fn tabled(out: &Path) -> usize {
    let Ok(text) = std::fs::read_to_string(out.join("table.csv")) else {
        return 0;
    };
    let mut names: Vec<&str> = text
        .lines()
        .skip(1)
        .filter_map(|l| l.split(',').next())
        .collect();
    names.dedup();
    names.len()
}

/// Wait (up to two minutes) until `out`'s table lists `records` records and its report is
/// written after it.
fn wait_for(out: &Path, records: usize, child: &mut Child) {
    let start = Instant::now();
    while tabled(out) != records {
        assert!(
            child.try_wait().unwrap().is_none(),
            "the --follow run ended by itself"
        );
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "{} of {records} records tabled after two minutes",
            tabled(out)
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    // The report is written after the table: let the pass finish writing.
    std::thread::sleep(Duration::from_millis(500));
}

/// What lands record k (from 1) in `inbox`: the k-th 300 s window of the 3-DOF record at
/// `path`, as `rec_k.csv`.
fn lander(path: &Path, inbox: &Path) -> impl Fn(usize) {
    let t = hyst::io::read_csv(path).unwrap();
    let col = |c: &str| t.column(c).unwrap().to_vec();
    let (y1, y2, y3) = (col("y1"), col("y2"), col("y3"));
    let inbox = inbox.to_path_buf();
    move |k: usize| {
        let r = (k - 1) * 6000..k * 6000;
        hyst::io::write_csv(
            &inbox.join(format!("rec_{k}.csv")),
            &["y1", "y2", "y3"],
            &[&y1[r.clone()], &y2[r.clone()], &y3[r]],
        )
        .unwrap();
    }
}

/// Kill `child` (SIGKILL) and reap it.
fn kill(mut child: Child) {
    child.kill().unwrap();
    child.wait().unwrap();
}

/// Two outputs folders hold the same table and report, byte for byte.
fn same_outputs(follow: &Path, batch: &Path) {
    for name in ["table.csv", "report.json"] {
        let a = std::fs::read_to_string(follow.join(name)).unwrap();
        let b = std::fs::read_to_string(batch.join(name)).unwrap();
        assert!(a == b, "{name} differs between --follow and the batch run");
    }
}

/// `hyst track --follow` on `inbox`, four records training, into `out`.
fn follow_args<'a>(inbox: &'a Path, out: &'a Path) -> Vec<&'a str> {
    let mut a = vec![
        "track",
        "--inputs",
        s(inbox),
        "--fs",
        "20",
        "--training",
        "4",
    ];
    a.extend(["--out", s(out), "--follow", "--poll", "0.2"]);
    a
}

/// The batch run over `inbox`'s records 1 to `k` (named, not the folder), into a fresh
/// scratch folder `name`.
fn batch_over_records(inbox: &Path, k: usize, name: &str) -> PathBuf {
    let dir = scratch(name);
    let files: Vec<String> = (1..=k)
        .map(|i| inbox.join(format!("rec_{i}.csv")).display().to_string())
        .collect();
    let mut a = vec!["track", "--inputs"];
    a.extend(files.iter().map(String::as_str));
    a.extend(["--fs", "20", "--training", "4", "--out", s(&dir)]);
    batch(&a);
    dir
}

/// Record files land one after another in a folder `hyst track --follow` watches: after
/// each arrival its table and report are a batch run's over the files so far, byte for
/// byte; killed (SIGKILL) and started again it takes up where it stopped and reaches the
/// batch run's over all of them.
#[test]
fn follow_takes_record_files_as_a_batch_run_would() {
    let Some(path) = common::data_file("oma/data_3dof.csv") else {
        return;
    };
    let inbox = scratch("inbox");
    let land = lander(&path, &inbox);
    let out = scratch("out");
    let log = scratch("logs").join("follow.txt");
    let args = follow_args(&inbox, &out);
    let batch_over = |k: usize, name: &str| batch_over_records(&inbox, k, name);
    (1..=5).for_each(&land);
    let mut child = start(&args, &log);
    wait_for(&out, 5, &mut child);
    same_outputs(&out, &batch_over(5, "batch5"));
    (6..=8).for_each(&land);
    wait_for(&out, 8, &mut child);
    kill(child);
    same_outputs(&out, &batch_over(8, "batch8"));
    let said = std::fs::read_to_string(&log).unwrap();
    for k in 6..=8 {
        assert!(said.contains(&format!("rec_{k}.csv: ")), "{said}");
    }
    // Started again: what the store holds is served, the new files taken.
    let mut child = start(&args, &scratch("logs2").join("follow.txt"));
    (9..=10).for_each(&land);
    wait_for(&out, 10, &mut child);
    kill(child);
    same_outputs(&out, &batch_over(10, "batch10"));
}

/// With a covariates file timing every record, the files not landed yet are gaps of the
/// first pass (said as skipped); each is said once more, with its modes, when it lands (it
/// was said as skipped alone before), and the table then is a batch run's.
#[test]
fn a_gap_is_said_again_when_its_file_lands() {
    let Some(path) = common::data_file("oma/data_3dof.csv") else {
        return;
    };
    let inbox = scratch("gap_inbox");
    let land = lander(&path, &inbox);
    let covariates = scratch("gap_covariates").join("covariates.csv");
    let rows: String = (1..=8)
        .map(|k| format!("rec_{k}.csv,{},{}\n", 300.0 * k as f64, 10.0 + k as f64))
        .collect();
    std::fs::write(&covariates, format!("record,time,temperature\n{rows}")).unwrap();
    let out = scratch("gap_out");
    let log = scratch("gap_logs").join("follow.txt");
    let args = [
        "track",
        "--inputs",
        s(&inbox),
        "--fs",
        "20",
        "--covariates",
        s(&covariates),
        "--training",
        "4",
        "--out",
        s(&out),
        "--follow",
        "--poll",
        "0.2",
    ];
    (1..=5).for_each(&land);
    let mut child = start(&args, &log);
    wait_for(&out, 5, &mut child);
    (6..=8).for_each(&land);
    wait_for(&out, 8, &mut child);
    kill(child);
    let batch_dir = scratch("gap_batch");
    batch(&[
        "track",
        "--inputs",
        s(&inbox),
        "--fs",
        "20",
        "--covariates",
        s(&covariates),
        "--training",
        "4",
        "--out",
        s(&batch_dir),
    ]);
    same_outputs(&out, &batch_dir);
    let said = std::fs::read_to_string(&log).unwrap();
    for k in 6..=8 {
        let name = format!("rec_{k}.csv");
        assert!(
            said.contains(&format!("skipped {name}: no such file")),
            "{said}"
        );
        let tracked = said
            .lines()
            .filter(|l| l.starts_with(&format!("{name}: ")) && l.ends_with("mode(s) tracked"))
            .count();
        assert_eq!(tracked, 1, "{said}");
    }
}

/// An estimates table that grows row by row under `hyst track --follow --estimates`: the
/// alarm of a 2 % drop of one mode is printed once, as it happens; after each growth the
/// table and report are a batch run's over the rows so far; killed and started again, the
/// same.
#[test]
fn follow_takes_rows_of_estimates_and_prints_alarms_as_they_come() {
    let dir = scratch("estimates");
    let mut rng = rand::rngs::StdRng::seed_from_u64(8_500_801);
    let normal = Normal::new(0.0, 1.0).unwrap();
    let rows: Vec<String> = (0..80)
        .map(|i| {
            let f1 = 1.0 * (1.0 + 1e-3 * normal.sample(&mut rng));
            let drop = if i >= 60 { 0.98 } else { 1.0 };
            let f2 = 3.0 * drop * (1.0 + 1e-3 * normal.sample(&mut rng));
            format!("r{i},{},{f1},0.001,{f2},0.003\n", 3600 * i)
        })
        .collect();
    let table = dir.join("estimates.csv");
    let header = "record,time,f1_hz,f1_hz_se,f2_hz,f2_hz_se\n";
    let write_rows = |n: usize, to: &Path| {
        std::fs::write(to, format!("{header}{}", rows[..n].concat())).unwrap();
    };
    let out = dir.join("out");
    let args = [
        "track",
        "--estimates",
        s(&table),
        "--training",
        "40",
        "--out",
        s(&out),
        "--follow",
        "--poll",
        "0.2",
    ];
    let batch_over = |n: usize| {
        let copy = dir.join(format!("first_{n}.csv"));
        write_rows(n, &copy);
        let o = dir.join(format!("batch_{n}"));
        let text = batch(&[
            "track",
            "--estimates",
            s(&copy),
            "--training",
            "40",
            "--out",
            s(&o),
        ]);
        (o, text)
    };
    write_rows(50, &table);
    let first_log = dir.join("follow1.txt");
    let mut child = start(&args, &first_log);
    wait_for(&out, 50, &mut child);
    same_outputs(&out, &batch_over(50).0);
    write_rows(65, &table);
    wait_for(&out, 65, &mut child);
    kill(child);
    let (b65, text65) = batch_over(65);
    same_outputs(&out, &b65);
    let said = std::fs::read_to_string(&first_log).unwrap();
    let alarms: Vec<&str> = text65
        .lines()
        .filter(|l| l.starts_with("ALARM: mode"))
        .collect();
    assert!(
        !alarms.is_empty() && alarms.iter().all(|l| l.contains("mode f2 fell")),
        "{text65}"
    );
    for a in &alarms {
        assert_eq!(said.matches(a).count(), 1, "{a} in {said}");
    }
    let second_log = dir.join("follow2.txt");
    let mut child = start(&args, &second_log);
    write_rows(80, &table);
    wait_for(&out, 80, &mut child);
    kill(child);
    let (b80, text80) = batch_over(80);
    same_outputs(&out, &b80);
    // Every alarm of the whole table printed by one of the two runs.
    let said = std::fs::read_to_string(&first_log).unwrap()
        + &std::fs::read_to_string(&second_log).unwrap();
    for a in text80.lines().filter(|l| l.starts_with("ALARM: mode")) {
        assert!(said.contains(a), "{a} not printed: {said}");
    }
}

/// A `--poll` that is not a positive number of seconds up to a day is refused, named,
/// before anything is followed (else `--follow` would spin, or sleep for ever).
#[test]
fn a_bad_poll_is_refused_naming_it() {
    let dir = scratch("bad_poll");
    let table = dir.join("estimates.csv");
    std::fs::write(&table, "record,a_hz\nr0,1.0\n").unwrap();
    for poll in ["0", "-1", "1e9", "NaN"] {
        let out = Command::new(env!("CARGO_BIN_EXE_hyst"))
            .args([
                "track",
                "--estimates",
                s(&table),
                "--out",
                s(&dir.join("out")),
                "--follow",
                "--poll",
                poll,
            ])
            .output()
            .expect("the hyst binary runs");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "--poll {poll}: {err}");
        assert!(
            err.contains("--poll") && !err.contains("panicked"),
            "--poll {poll}: {err}"
        );
    }
}

/// An `--html` page inside a followed folder would be taken for a record on the next look
/// (it stopped the follower on its second pass): refused at start, naming both.
#[test]
fn a_page_inside_the_followed_folder_is_refused_at_start() {
    let dir = scratch("page_inside");
    let inbox = dir.join("inbox");
    std::fs::create_dir_all(&inbox).unwrap();
    let page = inbox.join("page.html");
    let out = Command::new(env!("CARGO_BIN_EXE_hyst"))
        .args([
            "track",
            "--inputs",
            s(&inbox),
            "--out",
            s(&dir.join("out")),
            "--html",
            s(&page),
            "--follow",
        ])
        .output()
        .expect("the hyst binary runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{err}");
    assert!(
        err.contains(&format!(
            "--html {}: inside the records folder {}",
            s(&page),
            s(&inbox)
        )),
        "{err}"
    );
    assert!(!page.exists());
}

/// A note among the records takes no record's place (`--training 4` trains on four
/// records, as the batch run over the record files alone does), and a record landing after
/// a later name goes to its name's place: the follower's table and report are the batch
/// run's over the same record files, byte for byte (issue 77: the note took a training
/// slot, and a late file went to the table's end).
#[test]
fn a_note_takes_no_place_and_a_late_record_goes_to_its_name() {
    let Some(path) = common::data_file("oma/data_3dof.csv") else {
        return;
    };
    let inbox = scratch("inbox_late");
    let land = lander(&path, &inbox);
    std::fs::write(
        inbox.join("notes.txt"),
        "Hourly records of the bridge.\nSensor 3 re-glued on day 2.\n",
    )
    .unwrap();
    let out = scratch("out_late");
    let args = follow_args(&inbox, &out);
    [1, 2, 3, 4, 6].into_iter().for_each(&land);
    let mut child = start(&args, &scratch("logs_late").join("follow.txt"));
    wait_for(&out, 5, &mut child);
    land(5);
    wait_for(&out, 6, &mut child);
    kill(child);
    let dir = batch_over_records(&inbox, 6, "batch_late");
    same_outputs(&out, &dir);
    // The batch run over the folder leaves the note out the same way, and names it.
    let folder = scratch("batch_folder");
    let run = Command::new(env!("CARGO_BIN_EXE_hyst"))
        .args(["track", "--inputs", s(&inbox), "--fs", "20"])
        .args(["--training", "4", "--out", s(&folder)])
        .output()
        .unwrap();
    assert!(run.status.success());
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(
        err.contains("left out, not a record") && err.contains("notes.txt"),
        "{err}"
    );
    same_outputs(&folder, &dir);
}
