"""The package under test is the one in this source tree, laid out as maturin builds it.

`cargo xtask test` does not run `pip install` (maturin's build would compile the libraries a
second time with other features): it builds the extension module with the workspace's tests
and places it beside the Python sources as `pyproject.toml` tells maturin to. These tests hold
that layout to `pyproject.toml`, and the imported package to the sources here, however it
was installed."""

import filecmp
import importlib.machinery
import sys
from pathlib import Path

import pytest

import hyst
from conftest import ROOT

PACKAGE = ROOT / "crates" / "hyst-py"


def test_the_package_is_laid_out_as_maturin_builds_it():
    if sys.version_info < (3, 11):
        pytest.skip("tomllib needs Python 3.11")
    import tomllib

    config = tomllib.loads((PACKAGE / "pyproject.toml").read_text())["tool"]["maturin"]
    # maturin puts the module `hyst._hyst` inside the package found in `python-source`.
    assert config["module-name"] == "hyst._hyst"
    assert config["python-source"] == "python"
    here = Path(hyst.__file__).parent
    module = Path(hyst._hyst.__file__)
    assert module.parent == here
    assert module.name.startswith("_hyst.")
    assert any(module.name.endswith(s) for s in importlib.machinery.EXTENSION_SUFFIXES)


def test_the_imported_python_sources_are_this_trees():
    here = Path(hyst.__file__).parent
    sources = PACKAGE / "python" / "hyst"
    names = sorted(p.name for p in sources.iterdir() if p.is_file())
    assert "__init__.py" in names and "py.typed" in names
    _, mismatch, missing = filecmp.cmpfiles(sources, here, names, shallow=False)
    assert mismatch == [] and missing == [], f"stale package: {mismatch + missing} differ from {sources}"
