//! `cargo xtask test`: every test of the project, the README's test command.
//!
//! First `cargo test --workspace --release`; then the Python package: a virtual environment under
//! `target/py-venv` (made on first use, with maturin, numpy, pytest, pyuff and scipy from
//! PyPI), the package built and installed into it from `crates/hyst-py` (`pip install`,
//! maturin's release build), the `hyst` command the Rust tests built for the tests that
//! compare with it,
//! and pytest run on `crates/hyst-py/tests` (which also runs the code of `docs/python.md`).
//! Before them, Debian's Chromium is installed when it is missing and the machine lets root
//! install packages: the HTML reports' tests open the pages in it. Fails on the first failure.

use std::path::Path;
use std::process::Command;

use crate::compare::run_ok as run;

/// What the Python tests need besides the package (pyuff and scipy write the Universal and
/// MATLAB files the readers are checked against; pyarrow reads `hyst track`'s Parquet table;
/// distributed runs `hyst.track` on a local Dask cluster).
const PYTHON_NEEDS: [&str; 7] = [
    "maturin>=1.7,<2",
    "numpy",
    "pytest",
    "pyuff",
    "scipy",
    "pyarrow",
    "distributed",
];

/// `python -m pip install --quiet`, the arguments to follow.
fn pip(python: &Path) -> Command {
    let mut cmd = Command::new(python);
    cmd.args([
        "-m",
        "pip",
        "install",
        "--quiet",
        "--disable-pip-version-check",
    ]);
    cmd
}

/// Debian's `chromium`, installed with apt-get when it is missing and this is root on a
/// machine with apt-get; otherwise left to the tests (which fail under CI without it).
fn ensure_chromium() -> Result<(), String> {
    if hyst::html::chromium::find().is_some() {
        return Ok(());
    }
    let root = Command::new("id")
        .arg("-u")
        .output()
        .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0");
    if !root || !Path::new("/usr/bin/apt-get").is_file() {
        eprintln!(
            "chromium is missing and cannot be installed here: the HTML report tests need it"
        );
        return Ok(());
    }
    run(
        Command::new("apt-get").args(["update", "-qq"]),
        "apt-get update",
    )?;
    run(
        Command::new("apt-get")
            .args(["install", "-y", "-qq", "chromium"])
            .env("DEBIAN_FRONTEND", "noninteractive"),
        "apt-get install chromium",
    )
}

/// Every test, in order: the workspace's, then the Python package's.
pub fn run_all() -> Result<(), String> {
    ensure_chromium()?;
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .ok_or("no workspace root")?
        .to_path_buf();
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    // Optimized, as this command itself is built (`cargo xtask` runs it in release): the
    // dependencies are compiled once for both, and the tests run at full speed. The hyst
    // binary the Python tests compare with is built with the tests (theirs use it).
    run(
        Command::new(&cargo)
            .args(["test", "--workspace", "--release"])
            .current_dir(&root),
        "cargo test --workspace --release",
    )?;
    // The build's target folder (CARGO_TARGET_DIR when set): the command's binary is there.
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| root.join("target"));
    let venv = root.join("target").join("py-venv");
    let bin = venv.join("bin");
    let python = bin.join("python");
    if !python.is_file() {
        run(
            Command::new("python3").args(["-m", "venv"]).arg(&venv),
            "python3 -m venv target/py-venv",
        )?;
    }
    run(
        pip(&python).args(PYTHON_NEEDS),
        "pip install maturin numpy pytest",
    )?;
    // maturin is found on PATH by pip's build step: the environment's own first.
    let path = std::env::join_paths(
        std::iter::once(bin.clone()).chain(
            std::env::var_os("PATH")
                .iter()
                .flat_map(std::env::split_paths),
        ),
    )
    .map_err(|e| format!("PATH: {e}"))?;
    run(
        pip(&python)
            .args(["--no-build-isolation", "--force-reinstall", "--no-deps"])
            .arg(root.join("crates").join("hyst-py"))
            .env("PATH", &path)
            .current_dir(&root),
        "pip install ./crates/hyst-py",
    )?;
    // Built by the tests above: their integration tests run it.
    let hyst = target.join("release").join("hyst");
    run(
        Command::new(&python)
            .args(["-m", "pytest", "-q"])
            .arg(root.join("crates").join("hyst-py").join("tests"))
            .env("HYST_BIN", &hyst)
            .current_dir(&root),
        "pytest crates/hyst-py/tests",
    )
}
