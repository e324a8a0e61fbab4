"""NumPy files (np.save, np.savez) read by the hyst command line, and the helpers the other
formats' tests share."""

import json
import subprocess

import numpy as np
import pytest

from test_ssi import read_record


FS = 20.0


def hyst_ssi(hyst_bin, path, tmp_path, *flags, check=True):
    """`hyst ssi` on `path` with `flags`; its JSON document (without the record's name), or
    the failed run."""
    out = tmp_path / (path.name + ".json")
    p = subprocess.run(
        [str(hyst_bin), "ssi", "--input", str(path), "--json", str(out), *flags],
        capture_output=True,
        text=True,
    )
    if not check:
        return p
    assert p.returncode == 0, p.stderr
    doc = json.loads(out.read_text())
    doc.pop("record")
    return doc


def csv_of(y, names, path):
    """`y` as a CSV with every digit, its columns named `names`."""
    np.savetxt(path, y, delimiter=",", fmt="%.17g", header=",".join(names), comments="")
    return path


@pytest.mark.parametrize("order", ["C", "F"])
def test_an_npy_written_by_numpy_gives_the_modes_of_the_csv(data_dir, hyst_bin, tmp_path, order):
    """The 3-DOF record saved by numpy (np.save, C or Fortran order) and as CSV with every
    digit: `hyst ssi` gives the same document from both, to the last bit."""
    y, _ = read_record(data_dir / "oma" / "data_3dof.csv")
    npy = tmp_path / "rec.npy"
    np.save(npy, np.asfortranarray(y) if order == "F" else np.ascontiguousarray(y))
    csv = csv_of(y, ["0", "1", "2"], tmp_path / "rec.csv")
    assert hyst_ssi(hyst_bin, npy, tmp_path, "--fs", str(FS)) == hyst_ssi(hyst_bin, csv, tmp_path, "--fs", str(FS))


@pytest.mark.parametrize("dtype", ["int16", "int32", "uint16"])
def test_an_integer_npy_is_read_as_its_numbers(data_dir, hyst_bin, tmp_path, dtype):
    """The 3-DOF record as an acquisition's counts (scaled and rounded to integers, as numpy
    stores them): the same document as the same counts written as CSV."""
    y, _ = read_record(data_dir / "oma" / "data_3dof.csv")
    counts = np.round(y / np.abs(y).max() * 3000.0) + (5000 if dtype.startswith("u") else 0)
    npy = tmp_path / "counts.npy"
    np.save(npy, counts.astype(dtype))
    csv = csv_of(counts, ["0", "1", "2"], tmp_path / "counts.csv")
    assert hyst_ssi(hyst_bin, npy, tmp_path, "--fs", str(FS)) == hyst_ssi(hyst_bin, csv, tmp_path, "--fs", str(FS))


@pytest.mark.parametrize(
    "array, says",
    [
        (np.ones(6, dtype=np.complex128), "dtype '<c16' is not a float or integer array"),
        (np.zeros((2, 2, 2)), "shape [2, 2, 2]"),
        (np.array([1.0, np.nan, 2.0]), "row 2, column `0`: value NaN is not finite"),
        (np.ones((3, 500)), "the array is 3 × 500"),
    ],
)
def test_a_bad_npy_is_refused_naming_the_file(hyst_bin, tmp_path, array, says):
    path = tmp_path / "bad.npy"
    np.save(path, array)
    p = hyst_ssi(hyst_bin, path, tmp_path, "--fs", "10", check=False)
    assert p.returncode != 0
    assert str(path) in p.stderr and says in p.stderr, p.stderr


@pytest.mark.parametrize("save", ["savez", "savez_compressed"])
def test_an_npz_written_by_numpy_gives_the_modes_of_the_csv(data_dir, hyst_bin, tmp_path, save):
    y, _ = read_record(data_dir / "oma" / "data_3dof.csv")
    npz = tmp_path / "rec.npz"
    getattr(np, save)(npz, y=y, fs=np.float64(FS))
    csv = csv_of(y, ["0", "1", "2"], tmp_path / "rec.csv")
    assert hyst_ssi(hyst_bin, npz, tmp_path, "--fs", str(FS)) == hyst_ssi(hyst_bin, csv, tmp_path, "--fs", str(FS))


def test_a_headerless_dat_with_a_time_column_reads_as_its_csv(data_dir, hyst_bin, tmp_path):
    """The 3-DOF record with its time column written by numpy's savetxt without a header
    (space-separated, 19 significant digits): read with columns "0".."3" and the rate of its time
    column, and `hyst ssi` without --fs decides the same modes as on the CSV with a header
    and --fs."""
    import hyst

    y, _ = read_record(data_dir / "oma" / "data_3dof.csv")
    t = np.arange(len(y)) / FS
    dat = tmp_path / "rec.dat"
    np.savetxt(dat, np.column_stack([t, y]))
    rec = hyst.read(dat)
    assert rec.names == ["0", "1", "2", "3"]
    assert rec.fs == pytest.approx(FS, rel=1e-12)
    csv = csv_of(np.column_stack([t, y]), ["t", "a", "b", "c"], tmp_path / "rec.csv")
    from_dat = hyst_ssi(hyst_bin, dat, tmp_path)
    from_csv = hyst_ssi(hyst_bin, csv, tmp_path, "--fs", str(FS))
    # The rate from 17-digit times is 20 Hz to rounding, and the answer the same to it.
    assert from_dat["fs_hz"] == pytest.approx(FS, rel=1e-12)
    modes = lambda d: [(m["frequency_hz"], m["damping_ratio"]) for m in d["modes"]]
    assert len(modes(from_dat)) == len(modes(from_csv)) >= 3
    for a, b in zip(modes(from_dat), modes(from_csv)):
        assert a == pytest.approx(b, rel=1e-6)
    # A rate ten times too large is refused, naming the time column.
    p = hyst_ssi(hyst_bin, dat, tmp_path, "--fs", str(10 * FS), check=False)
    assert p.returncode != 0 and "disagrees with the time column `0`" in p.stderr


def test_a_nan_in_a_column_not_analysed_is_read_and_refused_where_analysed(data_dir, tmp_path):
    """``hyst.read`` keeps a cell that is not finite (a column no one analyses may hold one);
    ``hyst.ssi`` of the channels without it answers, and of a channel with it is refused."""
    import hyst

    y, _ = read_record(data_dir / "oma" / "data_3dof.csv")
    note = np.ones(len(y))
    note[5] = np.nan
    path = csv_of(np.column_stack([y, note]), ["a", "b", "c", "note"], tmp_path / "rec.csv")
    rec = hyst.read(path)
    assert rec.names == ["a", "b", "c", "note"]
    assert np.isnan(rec.data[5, 3]) and np.isfinite(rec.data[:, :3]).all()
    assert len(hyst.ssi(rec.data[:, :3], FS).frequency_hz) >= 3
    with pytest.raises(ValueError, match="not finite"):
        hyst.ssi(rec.data, FS)
