"""MATLAB files written by scipy.io.savemat, read by the hyst command line."""

import numpy as np
import pytest

from conftest import need
from test_formats import FS, csv_of, hyst_ssi
from test_ssi import read_record

scipy_io = need("scipy.io")


@pytest.mark.parametrize("compress", [False, True])
def test_a_mat_written_by_scipy_gives_the_modes_of_the_csv(data_dir, hyst_bin, tmp_path, compress):
    """The record saved by scipy.io.savemat (plain, and compressed as MATLAB's -v7 saves),
    beside a scalar `fs`: `hyst ssi` reads the matrix without being told, or by name, and
    gives the same document as on the CSV."""
    y, _ = read_record(data_dir / "oma" / "data_3dof.csv")
    mat = tmp_path / "rec.mat"
    scipy_io.savemat(mat, {"acc": y, "fs": FS}, do_compression=compress)
    csv = csv_of(y, ["0", "1", "2"], tmp_path / "rec.csv")
    want = hyst_ssi(hyst_bin, csv, tmp_path, "--fs", str(FS))
    assert hyst_ssi(hyst_bin, mat, tmp_path, "--fs", str(FS)) == want
    assert hyst_ssi(hyst_bin, mat, tmp_path, "--fs", str(FS), "--variable", "acc") == want


@pytest.mark.parametrize(
    "variables, flags, says",
    [
        ({"z": np.ones((50, 2)) * (1 + 1j)}, [], "variable z (50×2 double) is complex"),
        ({"a": np.ones((50, 2)), "b": np.ones((50, 2))}, [], "the file holds several arrays (a (50×2 double), b (50×2 double))"),
        ({"a": np.ones((50, 2))}, ["--variable", "c"], "no array `c`"),
        ({"a": np.ones((3, 500))}, [], "the array is 3 × 500"),
    ],
)
def test_a_bad_mat_is_refused_naming_the_file_and_the_problem(hyst_bin, tmp_path, variables, flags, says):
    path = tmp_path / "bad.mat"
    scipy_io.savemat(path, variables)
    p = hyst_ssi(hyst_bin, path, tmp_path, "--fs", "10", *flags, check=False)
    assert p.returncode != 0
    assert str(path) in p.stderr and says in p.stderr, p.stderr
