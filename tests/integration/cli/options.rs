//! Every numeric option of every command at its extremes (issue 58): each run ends, by
//! itself, with an answer or a clear error, and within stated bounds of memory and time.
//!
//! The options are read from the program's own help, so that an option added later is
//! tested too; each command runs on a small record it accepts, the one option replaced.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The most memory a run may hold at once, whatever its options: eight times the largest
/// peak of these runs on these records (6000 to 16000 samples), 32 MB; a count the record
/// cannot hold goes far past it.
const PEAK_BOUND_KB: i64 = 256 * 1024;

/// The longest a run may take: the base runs take under a second in a release build and a
/// few in a test build; an option that makes a command loop for ever is stopped here.
const TIME_BOUND: Duration = Duration::from_secs(90);

/// The values every numeric option is given: zero, negative, the largest double, the largest
/// 64-bit count, and not a number; and as ranges (`--band LOW:HIGH`, `--estimate A:B`), the
/// widest (any other option refuses them as it parses).
const EXTREMES: [&str; 8] = [
    "0",
    "-1",
    "1e308",
    "18446744073709551615",
    "NaN",
    "0:1e308",
    "0:18446744073709551615",
    "1e-300:1e308",
];

/// How a run ended.
struct Ended {
    /// Exit code, or `None` when a signal ended it.
    code: Option<i32>,
    /// The signal that ended it, if one did.
    signal: Option<i32>,
    /// Peak resident memory (kB).
    peak_kb: i64,
    /// Wall time.
    took: Duration,
    /// Stopped at [`TIME_BOUND`].
    stopped: bool,
    stderr: String,
}

/// `hyst args` in `dir`, its output discarded, its stderr kept; stopped at [`TIME_BOUND`].
/// The peak memory is the kernel's count for the child (wait4's rusage).
#[allow(
    clippy::zombie_processes,
    reason = "the child is reaped by wait4, which also gives its peak memory"
)]
fn run(args: &[String], dir: &Path) -> Ended {
    let err_path = dir.join("stderr.txt");
    let err_file = std::fs::File::create(&err_path).unwrap();
    let start = Instant::now();
    let mut child = Command::new(env!("CARGO_BIN_EXE_hyst"))
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::from(err_file))
        .spawn()
        .expect("the hyst binary runs");
    let pid = child.id() as libc::pid_t;
    let mut status = 0;
    // SAFETY: rusage is plain data, zero a valid value; wait4 fills it for our own child.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let mut stopped = false;
    loop {
        // SAFETY: `pid` is our child, not yet reaped; status and usage are valid pointers.
        let r = unsafe { libc::wait4(pid, &mut status, libc::WNOHANG, &mut usage) };
        if r == pid {
            break;
        }
        assert_eq!(r, 0, "wait4 failed");
        if start.elapsed() > TIME_BOUND && !stopped {
            stopped = true;
            child.kill().unwrap();
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    let took = start.elapsed();
    Ended {
        code: libc::WIFEXITED(status).then(|| libc::WEXITSTATUS(status)),
        signal: libc::WIFSIGNALED(status).then(|| libc::WTERMSIG(status)),
        peak_kb: usage.ru_maxrss,
        took,
        stopped,
        stderr: std::fs::read_to_string(&err_path).unwrap_or_default(),
    }
}

/// The commands, from `hyst --help`.
fn commands() -> Vec<String> {
    let (_, help, _) = super::hyst(&["--help"]);
    help.lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| !l.trim().is_empty())
        // A command's line starts two spaces in; its description's next lines further.
        .filter(|l| l.starts_with("  ") && !l.starts_with("   "))
        .filter_map(|l| l.split_whitespace().next().map(str::to_string))
        .filter(|c| c != "help")
        .collect()
}

/// A command's options that take values, from `hyst help <command>`, each with how many
/// values it takes (`--lag-periods <COUNT> <HZ>`: two).
fn valued_options(command: &str) -> Vec<(String, usize)> {
    let (_, help, _) = super::hyst(&["help", command]);
    help.lines()
        .filter_map(|l| {
            let line = l.trim();
            let line = match line.split_once(", ") {
                Some((short, rest)) if short.len() == 2 && short.starts_with('-') => rest,
                _ => line,
            };
            let mut tokens = line.split_whitespace();
            let flag = tokens.next()?;
            if !flag.starts_with("--") {
                return None;
            }
            let values = tokens.take_while(|t| t.starts_with('<')).count();
            (values > 0).then(|| (flag.to_string(), values))
        })
        .collect()
}

/// Whether `option` of `command` takes numbers: given a word, the parser refuses its value
/// (not as one of a list of names). The run ends at parsing: a valued flag follows without
/// its value.
fn is_numeric(command: &str, option: &str, values: usize) -> bool {
    let mut args = vec![command, option];
    args.extend(std::iter::repeat_n("abc", values));
    args.push("--format");
    let (_, _, err) = super::hyst(&args);
    err.contains("invalid value 'abc'") && !err.contains("possible values")
}

/// `base` with `option` given `value` (each of its `values` slots), replacing the base's own.
fn with_option(base: &[String], option: &str, values: usize, value: &str) -> Vec<String> {
    let mut args = base.to_vec();
    if let Some(i) = args.iter().position(|a| a == option) {
        // The option and its values, up to the next flag.
        let end = args[i + 1..]
            .iter()
            .position(|a| a.starts_with("--"))
            .map_or(args.len(), |k| i + 1 + k);
        args.drain(i..end);
    }
    args.push(option.to_string());
    args.extend(std::iter::repeat_n(value.to_string(), values));
    args
}

/// The records the commands run on, written by `hyst simulate` (the default oscillator)
/// under `dir`: white-noise responses, at two force levels, and a periodic multisine
/// response of two periods.
fn records(dir: &Path) {
    let at = |name: &str| dir.join(name).display().to_string();
    let white = |samples: &str, seed: &str, rms: &str, out: &str| {
        let args = [
            "--samples",
            samples,
            "--seed",
            seed,
            "--rms",
            rms,
            "--out",
            &at(out),
        ];
        let (ok, _, err) =
            super::hyst(&[&["simulate", "--excitation", "white"], &args[..]].concat());
        assert!(ok, "{err}");
    };
    white("6000", "1", "50", "w.csv");
    white("16000", "3", "20", "l1.csv");
    white("16000", "4", "60", "l2.csv");
    std::fs::create_dir_all(dir.join("recs")).unwrap();
    for seed in ["1", "2", "3", "4"] {
        white("3000", seed, "50", &format!("recs/r{seed}.csv"));
    }
    let m = at("m.csv");
    let (ok, _, err) = super::hyst(&[
        "simulate",
        "--excitation",
        "multisine",
        "--periodic",
        "--samples",
        "4096",
        "--out",
        &m,
    ]);
    assert!(ok, "{err}");
    // Two periods: `hyst frf` needs more than one.
    let m = std::fs::read_to_string(&m).unwrap();
    let (head, rows) = m.split_once('\n').unwrap();
    std::fs::write(dir.join("m2.csv"), format!("{head}\n{rows}{rows}")).unwrap();
}

/// Each command's run on the records in `data`: one it completes, which the options then
/// vary (`@name` is the record `name`).
fn base(command: &str, data: &Path) -> Option<Vec<String>> {
    let line = match command {
        "simulate" => "--excitation white --out s.csv --samples 3000",
        "excite" => "--out e.csv --samples 3000",
        "ssi" => "--input @w.csv --columns y --fs 750",
        "ident" => "--data @w.csv --fs 750 --mass 2",
        "refine" => "--data @w.csv --fs 750",
        "levels" => "--data @l1.csv @l2.csv --fs 750 --mass 2",
        "amplitude" => "--input @w.csv --columns y --fs 750",
        "frf" => "--input @m2.csv --fs 750 --force u --period 4096 --band 5:60",
        "track" => "--inputs @recs --columns y --fs 750 --out tr",
        _ => return None,
    };
    let args = line.split_whitespace().map(|w| match w.strip_prefix('@') {
        Some(name) => data.join(name).display().to_string(),
        None => w.to_string(),
    });
    Some(std::iter::once(command.to_string()).chain(args).collect())
}

#[test]
fn every_numeric_option_at_its_extremes_ends_cleanly_within_bounds() {
    let root = Path::new(env!("CARGO_TARGET_TMPDIR")).join("cli-options");
    let _ = std::fs::remove_dir_all(&root);
    let data = root.join("data");
    std::fs::create_dir_all(&data).unwrap();
    records(&data);
    // Every command has a base run, which completes: the options are varied on a run that
    // works, not one that fails before it reads them.
    let mut jobs: Vec<Vec<String>> = Vec::new();
    let mut numeric = 0;
    for command in commands() {
        let base = base(&command, &data)
            .unwrap_or_else(|| panic!("no base run for `hyst {command}`: add one to this test"));
        let dir = root.join(format!("base-{command}"));
        std::fs::create_dir_all(&dir).unwrap();
        let ended = run(&base, &dir);
        assert_eq!(ended.code, Some(0), "{base:?}: {}", ended.stderr);
        for (option, values) in valued_options(&command) {
            if !is_numeric(&command, &option, values) {
                continue;
            }
            numeric += 1;
            for value in EXTREMES {
                jobs.push(with_option(&base, &option, values, value));
            }
        }
    }
    // The help lists some 60 numeric options over the commands: far fewer means the help
    // was not read.
    assert!(numeric >= 40, "only {numeric} numeric options found");
    let next = std::sync::atomic::AtomicUsize::new(0);
    let failures = std::sync::Mutex::new(Vec::new());
    std::thread::scope(|scope| {
        for _ in 0..2 {
            scope.spawn(|| {
                loop {
                    let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    let Some(args) = jobs.get(i) else { break };
                    let dir = root.join(format!("run-{i}"));
                    std::fs::create_dir_all(&dir).unwrap();
                    let e = run(args, &dir);
                    let first = e
                        .stderr
                        .lines()
                        .find(|l| !l.trim().is_empty())
                        .unwrap_or("");
                    let problem = if e.stopped {
                        Some(format!("stopped after {:?}", e.took))
                    } else if let Some(sig) = e.signal {
                        Some(format!("killed by signal {sig}: {}", e.stderr.trim()))
                    } else if e.stderr.contains("panicked") {
                        Some(format!("panicked: {}", e.stderr.trim()))
                    } else if !matches!(e.code, Some(0..=2)) {
                        Some(format!("exit code {:?}", e.code))
                    } else if e.code != Some(0) && !first.starts_with("error:") {
                        Some(format!("failed without an error line: {}", e.stderr.trim()))
                    } else if e.peak_kb > PEAK_BOUND_KB {
                        Some(format!("peak memory {} MB", e.peak_kb / 1024))
                    } else {
                        None
                    };
                    if let Some(p) = problem {
                        failures
                            .lock()
                            .unwrap()
                            .push(format!("hyst {}: {p}", args.join(" ")));
                    }
                    let _ = std::fs::remove_dir_all(&dir);
                }
            });
        }
    });
    let failures = failures.into_inner().unwrap();
    assert!(
        failures.is_empty(),
        "{} of {} runs:\n{}",
        failures.len(),
        jobs.len(),
        failures.join("\n")
    );
}
