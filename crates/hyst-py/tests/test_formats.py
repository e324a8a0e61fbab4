"""Files written by other programs, read by the hyst command line."""

import json
import subprocess

import numpy as np
import pytest

from test_ssi import read_record


def ssi_document(hyst_bin, path, tmp_path, fs=20.0):
    out = tmp_path / (path.name + ".json")
    subprocess.run(
        [str(hyst_bin), "ssi", "--input", str(path), "--fs", str(fs), "--json", str(out)],
        check=True,
        capture_output=True,
    )
    doc = json.loads(out.read_text())
    doc.pop("record")
    return doc


@pytest.mark.parametrize("order", ["C", "F"])
def test_an_npy_written_by_numpy_gives_the_modes_of_the_csv(data_dir, hyst_bin, tmp_path, order):
    """The 3-DOF record saved by numpy (np.save, C or Fortran order) and as CSV with every
    digit: `hyst ssi` gives the same document from both, to the last bit."""
    y, _ = read_record(data_dir / "oma" / "data_3dof.csv")
    npy = tmp_path / "rec.npy"
    np.save(npy, np.asfortranarray(y) if order == "F" else np.ascontiguousarray(y))
    csv = tmp_path / "rec.csv"
    np.savetxt(csv, y, delimiter=",", fmt="%.17g", header="0,1,2", comments="")
    assert ssi_document(hyst_bin, npy, tmp_path) == ssi_document(hyst_bin, csv, tmp_path)


@pytest.mark.parametrize(
    "array, says",
    [
        (np.arange(12, dtype=np.int64).reshape(6, 2), "dtype '<i8' is not a float64 or float32 array"),
        (np.zeros((2, 2, 2)), "shape [2, 2, 2]"),
        (np.array([1.0, np.nan, 2.0]), "row 2, column `0`: value NaN is not finite"),
    ],
)
def test_a_bad_npy_is_refused_naming_the_file(hyst_bin, tmp_path, array, says):
    path = tmp_path / "bad.npy"
    np.save(path, array)
    p = subprocess.run(
        [str(hyst_bin), "ssi", "--input", str(path), "--fs", "10", "--json", str(tmp_path / "o.json")],
        capture_output=True,
        text=True,
    )
    assert p.returncode != 0
    assert str(path) in p.stderr and says in p.stderr, p.stderr
