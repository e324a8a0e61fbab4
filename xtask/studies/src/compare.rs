//! `cargo xtask compare-tools [--seeds N] [--first-seed S] [--timing] [--clusters] [--covssi-only] [--crb] [--cases NAMES]`:
//! covssi beside the two Python tools of `../shared/data/oma/README.md`, pyOMA2 and koma, with
//! the same settings and the same statistic, on the shared records, on fresh records of the
//! same systems over noise seeds, (`--timing`) the tools' identification step at N = 1e6 on
//! this machine, and (`--clusters`) covssi's mode values and spurious clusters over the same
//! seeds (with `--covssi-only`, without running the tools). `--crb` prints the Cramér–Rao
//! bound of the estimates on these systems' records instead, computed from their exact
//! spectral matrix, and on the records of covssi's unit tests of the joint likelihood.
//!
//! The tools run in a virtual environment made on first use under `target/compare-venv`
//! (`python3 -m venv`, then pip installs the pinned versions from PyPI); the comparison itself
//! is `xtask/studies/compare/oma_tools.py`, which drives covssi through `hyst ssi`. Not part of
//! `cargo test`: it needs Python and the network on first use, and takes minutes.

use std::path::PathBuf;
use std::process::Command;

use hyst_testkit::{run_ok, succeeded};

/// The versions whose numbers the OMA README quotes.
const TOOLS: [&str; 2] = ["pyOMA-2==1.4.3", "koma-python==1.3.6"];

pub fn run(args: &[String]) -> Result<(), String> {
    let root = hyst_testkit::workspace_root();
    let data = hyst_testkit::data_dir()
        .ok_or("no shared data folder: set HYST_DATA_DIR or provide ../shared/data")?
        .join("oma");
    if !data.join("data_3dof.csv").is_file() {
        return Err(format!("{}: data_3dof.csv is missing", data.display()));
    }
    // `cargo xtask` runs the release build of this binary: hyst is built beside it.
    let bin_dir: PathBuf = std::env::current_exe()
        .map_err(|e| format!("where is xtask: {e}"))?
        .parent()
        .ok_or("xtask has no folder")?
        .to_path_buf();
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    run_ok(
        Command::new(cargo)
            .args(["build", "--release", "--quiet", "--bin", "hyst"])
            .current_dir(&root),
        "cargo build --release --bin hyst",
    )?;
    let hyst = bin_dir.join("hyst");
    let venv = bin_dir
        .parent()
        .ok_or("the target folder has no parent")?
        .join("compare-venv");
    let python = venv.join("bin").join("python");
    if !python.is_file() {
        eprintln!(
            "making {} with {} (first use only)",
            venv.display(),
            TOOLS.join(", ")
        );
        run_ok(
            Command::new("python3").args(["-m", "venv"]).arg(&venv),
            "python3 -m venv",
        )?;
        run_ok(
            Command::new(&python)
                .args(["-m", "pip", "install", "--quiet"])
                .args(TOOLS),
            "pip install",
        )?;
    }
    run_with_progress(
        Command::new(&python)
            .arg(root.join("xtask/studies/compare/oma_tools.py"))
            .arg("--hyst")
            .arg(&hyst)
            .arg("--data")
            .arg(&data)
            .args(args)
            // One BLAS thread, as the README's timings.
            .env("OMP_NUM_THREADS", "1")
            .env("OPENBLAS_NUM_THREADS", "1")
            .env("MKL_NUM_THREADS", "1"),
        "oma_tools.py",
    )
}

/// Run `cmd` (its stdout as this program's), showing the `@progress DONE TOTAL WHAT` lines
/// of its stderr as a progress bar (hidden when stderr is not a terminal) and passing its
/// other lines on.
fn run_with_progress(cmd: &mut Command, what: &str) -> Result<(), String> {
    use std::io::BufRead;
    let mut child = cmd
        .stderr(std::process::Stdio::piped())
        .spawn()
        .map_err(|e| format!("{what}: could not start: {e}"))?;
    let bar = indicatif::ProgressBar::new(0);
    if let Ok(style) =
        indicatif::ProgressStyle::with_template("[{elapsed}] {bar:30} {pos}/{len} {msg}")
    {
        bar.set_style(style);
    }
    if let Some(err) = child.stderr.take() {
        for line in std::io::BufReader::new(err).lines() {
            let line = line.map_err(|e| format!("{what}: reading its stderr: {e}"))?;
            match progress_line(&line) {
                Some((done, total, step)) => {
                    bar.set_length(total);
                    bar.set_position(done);
                    bar.set_message(step.to_string());
                }
                None if bar.is_hidden() => eprintln!("{line}"),
                None => bar.println(line),
            }
        }
    }
    bar.finish_and_clear();
    let status = child
        .wait()
        .map_err(|e| format!("{what}: could not wait for it: {e}"))?;
    succeeded(status, what)
}

/// `@progress DONE TOTAL WHAT` read as (done, total, what).
fn progress_line(line: &str) -> Option<(u64, u64, &str)> {
    let rest = line.strip_prefix("@progress ")?;
    let mut parts = rest.splitn(3, ' ');
    let done = parts.next()?.parse().ok()?;
    let total = parts.next()?.parse().ok()?;
    Some((done, total, parts.next().unwrap_or("")))
}

#[cfg(test)]
mod tests {
    use super::progress_line;

    #[test]
    fn progress_lines_are_read_and_others_are_not() {
        assert_eq!(
            progress_line("@progress 3 120 3-DOF, seed 904: the three tools"),
            Some((3, 120, "3-DOF, seed 904: the three tools"))
        );
        assert_eq!(progress_line("@progress 3"), None);
        assert_eq!(progress_line("  3-DOF seed 904: pyOMA2 +0.1/+2.0"), None);
        assert_eq!(progress_line("@progress x 1 a"), None);
    }
}
