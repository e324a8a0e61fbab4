//! `cargo xtask test`: every test of the project, the README's test command.
//!
//! One optimized build of the workspace with its tests (`cargo build --workspace
//! --all-targets --release`, which also builds `hyst-py`'s extension module), then `cargo test
//! --workspace --release` from it; then the Python package: a virtual environment under
//! `target/py-venv` (made on first use, with numpy, pytest, pyuff, scipy, pyarrow and
//! distributed from PyPI), the package laid out under `target/py-package` as maturin lays it
//! out (the Python sources and the module just built), and pytest run on
//! `crates/hyst-py/tests` (which also runs the code of `docs/python.md`) with the `hyst`
//! command the build made. Before them, Debian's Chromium is installed when it is missing and
//! the machine lets root install packages: the HTML reports' tests open the pages in it.
//! Fails on the first failure.
//!
//! Not `pip install ./crates/hyst-py`: maturin's build resolves `hyst-py`'s dependencies
//! alone, with other features than the tests' graph, and so compiled faer, nalgebra and every
//! library a second time (124 s of a clean run); `tests/test_package.py` holds the layout to
//! `pyproject.toml`.

use std::path::{Path, PathBuf};
use std::process::Command;

use hyst_testkit::run_ok as run;

/// What the Python tests need besides the package (pyuff and scipy write the Universal and
/// MATLAB files the readers are checked against; pyarrow reads `hyst track`'s Parquet table;
/// distributed runs `hyst.track` on a local Dask cluster).
const PYTHON_NEEDS: [&str; 6] = [
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
    if hyst_testkit::chromium::find().is_some() {
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
    let root = hyst_testkit::workspace_root();
    let python = python_environment(&root)?;
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    // One optimized build of everything — the tests, the hyst binary the Python tests compare
    // with, and the Python extension module (`hyst-py`'s cdylib, which `cargo test` alone
    // would not build) — so that every dependency compiles once, with the features the
    // workspace's tests unify; then the tests run from it at full speed. The module is built
    // as maturin builds it: for this interpreter, not linked to libpython.
    let cargo_for_python = |args: &[&str]| {
        let mut cmd = Command::new(&cargo);
        cmd.args(args)
            .env("PYO3_PYTHON", &python)
            .env("PYO3_BUILD_EXTENSION_MODULE", "1")
            .current_dir(&root);
        cmd
    };
    run(
        &mut cargo_for_python(&["build", "--workspace", "--all-targets", "--release"]),
        "cargo build --workspace --all-targets --release",
    )?;
    run(
        &mut cargo_for_python(&["test", "--workspace", "--release"]),
        "cargo test --workspace --release",
    )?;
    // The build's target folder (CARGO_TARGET_DIR when set): the binaries are there.
    let release = std::env::var_os("CARGO_TARGET_DIR")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| root.join("target"))
        .join("release");
    let package = assemble_package(&root, &python, &release)?;
    run(
        Command::new(&python)
            .args(["-m", "pytest", "-q"])
            .arg(root.join("crates").join("hyst-py").join("tests"))
            .env("PYTHONPATH", &package)
            .env("HYST_BIN", release.join("hyst"))
            .current_dir(&root),
        "pytest crates/hyst-py/tests",
    )
}

/// The virtual environment under `target/py-venv` (made on first use) with what the Python
/// tests need: its interpreter.
fn python_environment(root: &Path) -> Result<PathBuf, String> {
    let venv = root.join("target").join("py-venv");
    let python = venv.join("bin").join("python");
    if !python.is_file() {
        run(
            Command::new("python3").args(["-m", "venv"]).arg(&venv),
            "python3 -m venv target/py-venv",
        )?;
    }
    run(
        pip(&python).args(PYTHON_NEEDS),
        "pip install numpy pytest pyuff scipy pyarrow distributed",
    )?;
    Ok(python)
}

/// The package as maturin lays it out (`pyproject.toml`: `python-source = "python"`,
/// `module-name = "hyst._hyst"`): the Python sources of `crates/hyst-py/python/hyst` and the
/// extension module beside them under the interpreter's suffix, in `target/py-package/hyst`,
/// made anew. Returns the folder to put on `PYTHONPATH`. (`test_the_package_is_laid_out_as_
/// maturin_builds_it` checks the layout against `pyproject.toml`.)
fn assemble_package(root: &Path, python: &Path, release: &Path) -> Result<PathBuf, String> {
    let out = root.join("target").join("py-package");
    let dest = out.join("hyst");
    let fail = |what: &Path, e: std::io::Error| format!("{}: {e}", what.display());
    if dest.exists() {
        std::fs::remove_dir_all(&dest).map_err(|e| fail(&dest, e))?;
    }
    std::fs::create_dir_all(&dest).map_err(|e| fail(&dest, e))?;
    let source = root
        .join("crates")
        .join("hyst-py")
        .join("python")
        .join("hyst");
    for entry in std::fs::read_dir(&source).map_err(|e| fail(&source, e))? {
        let from = entry.map_err(|e| fail(&source, e))?.path();
        if from.is_file() {
            let to = dest.join(from.file_name().unwrap_or_default());
            std::fs::copy(&from, &to).map_err(|e| fail(&from, e))?;
        }
    }
    let suffix = Command::new(python)
        .args([
            "-c",
            "import sysconfig; print(sysconfig.get_config_var('EXT_SUFFIX'))",
        ])
        .output()
        .map_err(|e| format!("{}: {e}", python.display()))?;
    let suffix = String::from_utf8_lossy(&suffix.stdout).trim().to_string();
    if !suffix.ends_with(".so") {
        return Err(format!("the interpreter's extension suffix is `{suffix}`"));
    }
    let module = release.join("lib_hyst.so");
    std::fs::copy(&module, dest.join(format!("_hyst{suffix}"))).map_err(|e| fail(&module, e))?;
    Ok(out)
}
