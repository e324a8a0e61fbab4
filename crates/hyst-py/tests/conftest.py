"""Where the tests find the shared data and the `hyst` command: `HYST_DATA_DIR` (else
`../shared/data` beside the repository) and `HYST_BIN` (else the repository's release, then
debug, build). Missing, a test that needs them fails when `CI` is set and is skipped with a
message otherwise."""

import importlib
import os
import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]


def _missing(what):
    if os.environ.get("CI"):
        pytest.fail(f"{what} is missing, and CI needs it")
    pytest.skip(f"{what} is missing: skipped (set it up to run this test)")


@pytest.fixture(scope="session")
def data_dir():
    d = Path(os.environ.get("HYST_DATA_DIR") or ROOT.parent / "shared" / "data")
    if not (d / "oma" / "data_3dof.csv").is_file():
        _missing(f"the shared data ({d}/oma/data_3dof.csv; set HYST_DATA_DIR)")
    return d


@pytest.fixture(scope="session")
def hyst_bin():
    given = os.environ.get("HYST_BIN")
    candidates = [Path(given)] if given else [
        ROOT / "target" / "release" / "hyst",
        ROOT / "target" / "debug" / "hyst",
    ]
    for c in candidates:
        if c.is_file():
            return c
    found = shutil.which("hyst")
    if found:
        return Path(found)
    _missing("the hyst command (cargo build --release --bin hyst, or set HYST_BIN)")


def need(module):
    """The module `module` (another program the tests compare with): missing, the tests that
    import it fail when `CI` is set and are skipped with a message otherwise."""
    try:
        return importlib.import_module(module)
    except ImportError:
        if os.environ.get("CI"):
            raise
        pytest.skip(f"{module} is not installed: skipped (pip install it to run these tests)", allow_module_level=True)
