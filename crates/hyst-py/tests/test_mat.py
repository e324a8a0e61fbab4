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


def sensors(y, fs):
    """The record as a data owner saves it: one sensor per channel, each with its samples
    (a 1-D array, which scipy saves as a row), name, units, position and rate."""
    return {
        f"s{k + 1}": {"data": y[:, k], "name": f"P{k + 1}", "units": "m/s^2", "position": [k, 0.0, 1.5], "fs": fs}
        for k in range(y.shape[1])
    }


@pytest.mark.parametrize("layout", ["struct of structs", "struct array", "struct of vectors"])
def test_a_struct_of_sensors_written_by_scipy_gives_the_modes_of_the_csv(data_dir, hyst_bin, tmp_path, layout):
    """A record saved as MATLAB structs (scipy.io.savemat of dicts, or of a structured
    array): `hyst ssi` finds the channels, names them by the sensors, takes the rate the
    file states, and gives the same document as on the CSV of those named columns."""
    y, _ = read_record(data_dir / "oma" / "data_3dof.csv")
    names = [f"P{k + 1}" for k in range(y.shape[1])]
    if layout == "struct of structs":
        record = sensors(y, FS)
    elif layout == "struct array":
        record = np.zeros((1, y.shape[1]), dtype=[("name", "O"), ("data", "O"), ("fs", "O")])
        for k in range(y.shape[1]):
            record[0, k] = (names[k], y[:, k], FS)
    else:
        record = {n: y[:, k] for k, n in enumerate(names)}
        record["fs"] = FS
    mat = tmp_path / "sensors.mat"
    scipy_io.savemat(mat, {"recording": record, "site": "lab"}, do_compression=True)
    want = hyst_ssi(hyst_bin, csv_of(y, names, tmp_path / "rec.csv"), tmp_path, "--fs", str(FS))
    assert hyst_ssi(hyst_bin, mat, tmp_path) == want
    assert hyst_ssi(hyst_bin, mat, tmp_path, "--variable", "recording", "--fs", str(FS)) == want
    p = hyst_ssi(hyst_bin, mat, tmp_path, "--fs", str(2 * FS), check=False)
    assert p.returncode != 0 and str(mat) in p.stderr, p.stderr


def test_a_mat_of_structs_beside_an_array_is_refused_listing_both(hyst_bin, tmp_path):
    """A struct of sensors beside a numeric array: either could be the record, so the file
    is refused, listing both with their shapes and fields."""
    y = np.random.default_rng(7).standard_normal((200, 2))
    path = tmp_path / "both.mat"
    scipy_io.savemat(path, {"recording": sensors(y, 10.0), "other": y})
    p = hyst_ssi(hyst_bin, path, tmp_path, "--fs", "10", check=False)
    assert p.returncode != 0
    assert "recording (1×1 struct; fields s1, s2)" in p.stderr and "other (200×2 double)" in p.stderr, p.stderr
    # One sensor asked for by its path is the CSV of its one column.
    one = hyst_ssi(hyst_bin, path, tmp_path, "--variable", "recording.s2", "--fs", "10")
    assert one == hyst_ssi(hyst_bin, csv_of(y[:, 1:], ["P2"], tmp_path / "p2.csv"), tmp_path, "--fs", "10")
