"""Universal Files: datasets 58 written by pyuff (ASCII) and by the published 58b layout,
read by the hyst command line; its dataset 55 read back by pyuff."""

import numpy as np
import pytest

from conftest import need
from test_formats import FS, csv_of, hyst_ssi
from test_ssi import read_record

pyuff = need("pyuff")


def set58(values, node, *, dx=1 / FS, func_type=1, binary=0):
    return pyuff.prepare_58(
        binary=binary,
        func_type=func_type,
        rsp_node=node,
        rsp_dir=3,
        ref_node=0,
        ref_dir=0,
        data=np.asarray(values, dtype=float),
        x=np.arange(len(values)) * dx,
        id1=f"channel {node}",
        rsp_ent_name="pt",
        ref_ent_name="NONE",
        abscissa_spacing=1,
        abscissa_spec_data_type=17,
        ordinate_spec_data_type=12,
        orddenom_spec_data_type=0,
    )


def write_uff(path, sets):
    if path.exists():
        path.unlink()
    pyuff.UFF(str(path)).write_sets(sets, mode="add")
    return path


def test_a_uff58_written_by_pyuff_gives_the_modes_of_the_csv(data_dir, hyst_bin, tmp_path):
    """The 3-DOF record written by pyuff as three datasets 58 (ASCII, double precision):
    `hyst ssi` takes the rate from the file and gives the same document as on a CSV of the
    values pyuff reads back from it, to the last bit."""
    y, _ = read_record(data_dir / "oma" / "data_3dof.csv")
    uff = write_uff(tmp_path / "rec.uff", [set58(y[:, c], c + 1) for c in range(3)])
    back = pyuff.UFF(str(uff)).read_sets()
    as_read = np.column_stack([s["data"] for s in back])
    # pyuff writes 12 significant digits.
    assert np.allclose(as_read, y, rtol=1e-11, atol=0)
    csv = csv_of(as_read, ["1+Z", "2+Z", "3+Z"], tmp_path / "rec.csv")
    from_uff = hyst_ssi(hyst_bin, uff, tmp_path)
    assert from_uff == hyst_ssi(hyst_bin, csv, tmp_path, "--fs", str(FS))
    assert from_uff["fs_hz"] == FS and len(from_uff["modes"]) >= 3


def write_58b(path, columns, dx=1 / FS, little=True):
    """Datasets 58b laid out as the format's description gives them: the first line with
    `b`, the byte order (1 little, 2 big endian), IEEE floats (2), 11 ASCII lines and the byte
    count; the 11 header records; the values as raw doubles; `    -1` right after them."""
    out = bytearray()
    for c, v in enumerate(columns):
        data = np.asarray(v, dtype="<f8" if little else ">f8").tobytes()
        out += b"    -1\n"
        out += b"    58b%6d%6d%12d%12d%6d%6d%12d%12d\n" % (1 if little else 2, 2, 11, len(data), 0, 0, 0, 0)
        for line in [f"channel {c + 1}", "NONE", "NONE", "NONE", "NONE"]:
            out += b"%-80s\n" % line.encode()
        out += b"%5d%10d%5d%10d %10s%10d%4d %10s%10d%4d\n" % (1, 0, 0, 0, b"pt", c + 1, 3, b"NONE", 0, 0)
        out += b"%10d%10d%10d%13.5e%13.5e%13.5e\n" % (4, len(v), 1, 0.0, dx, 0.0)
        for t in (17, 12, 0, 0):
            out += b"%10d%5d%5d%5d %-20s %-20s\n" % (t, 0, 0, 0, b"NONE", b"NONE")
        out += data
        out += b"    -1\n"
    path.write_bytes(bytes(out))
    return path


@pytest.mark.parametrize("little", [True, False])
def test_a_binary_58b_that_pyuff_reads_gives_the_modes_of_the_csv(data_dir, hyst_bin, tmp_path, little):
    """A 58b file made by the published layout (pyuff's own 58b writer drops data sets), in
    either byte order: pyuff's reader gives back every value exactly, and `hyst ssi` gives
    the same document as on the CSV of the values."""
    y, _ = read_record(data_dir / "oma" / "data_3dof.csv")
    path = write_58b(tmp_path / "rec58b.uff", [y[:, c] for c in range(3)], little=little)
    back = pyuff.UFF(str(path)).read_sets()
    assert [s["binary"] for s in back] == [1, 1, 1]
    assert np.array_equal(np.column_stack([s["data"] for s in back]), y)
    csv = csv_of(y, ["1+Z", "2+Z", "3+Z"], tmp_path / "rec.csv")
    assert hyst_ssi(hyst_bin, path, tmp_path) == hyst_ssi(hyst_bin, csv, tmp_path, "--fs", str(FS))


def test_dataset_55_written_by_hyst_reads_back_in_pyuff_with_the_same_shapes(data_dir, hyst_bin, tmp_path):
    """`hyst ssi --shapes-uff` on the UFF record: pyuff reads one dataset 55 per reported
    mode, each channel at its node along +Z, equal to the JSON's shapes and frequencies to
    the six significant digits of the format's E13.5 fields."""
    import hyst

    y, _ = read_record(data_dir / "oma" / "data_3dof.csv")
    uff = write_58b(tmp_path / "rec.uff", [y[:, c] for c in range(3)])
    shapes = tmp_path / "shapes.uff"
    hyst_ssi(hyst_bin, uff, tmp_path, "--shapes-uff", str(shapes))
    r = hyst.ssi(y, FS)
    sets = pyuff.UFF(str(shapes)).read_sets()
    sets = sets if isinstance(sets, list) else [sets]
    assert len(sets) == len(r.frequency_hz) >= 3
    for k, s in enumerate(sets):
        assert s["type"] == 55 and s["analysis_type"] == 3 and s["mode_n"] == k + 1
        assert list(s["node_nums"]) == [1, 2, 3]
        # E13.5 keeps six significant digits: each entry within 5e-6 of its size.
        assert np.allclose(s["r3"], r.shape[k], rtol=5e-6, atol=0)
        assert np.all(s["r1"] == 0) and np.all(s["r2"] == 0)
        f = abs(s["eig"]) / (2 * np.pi)
        zeta = -s["eig"].real / abs(s["eig"])
        assert abs(f - r.frequency_hz[k]) <= 1e-5 * f
        assert abs(zeta - r.damping_ratio[k]) <= 1e-5 * zeta + 1e-9


def bad_uff(tmp_path, kind):
    """A Universal File written by pyuff with one thing wrong."""
    v = np.sin(np.arange(200) * 0.3)
    path = tmp_path / f"{kind}.uff"
    if kind == "frf":
        s = set58(v, 1, func_type=4)
        s["abscissa_spec_data_type"] = 18
        return write_uff(path, [s]), "function type 4 (frequency response function)"
    if kind == "lengths":
        return write_uff(path, [set58(v, 1), set58(v[:150], 2)]), "channels of different lengths"
    if kind == "rates":
        return write_uff(path, [set58(v, 1), set58(v, 2, dx=0.01)]), "channels at different rates"
    if kind == "nan":
        # pyuff writes a NaN as 0; the binary layout keeps it.
        w = v.copy()
        w[17] = np.nan
        return write_58b(path, [v, w]), "row 18, column `2+Z`: value NaN is not finite"
    if kind == "truncated":
        write_uff(path, [set58(v, 1), set58(v, 2)])
        text = path.read_text()
        path.write_text(text[: len(text) - 300])
        return path, "the file ends after"
    if kind == "geometry":
        s = pyuff.prepare_15(node_nums=[1, 2], def_cs=[0, 0], disp_cs=[0, 0], color=[1, 1],
                             x=[0.0, 1.0], y=[0.0, 0.0], z=[0.0, 0.0])
        return write_uff(path, [s]), "no dataset 58 (a function at a node) to read as a record; the file holds datasets 15"
    raise ValueError(kind)


@pytest.mark.parametrize("kind", ["frf", "lengths", "rates", "nan", "truncated", "geometry"])
def test_a_bad_uff_is_refused_naming_the_file_and_the_problem(hyst_bin, tmp_path, kind):
    path, says = bad_uff(tmp_path, kind)
    p = hyst_ssi(hyst_bin, path, tmp_path, check=False)
    assert p.returncode != 0
    assert str(path) in p.stderr and says in p.stderr, p.stderr


def test_a_rate_given_that_disagrees_with_the_files_is_refused(hyst_bin, tmp_path):
    v = np.sin(np.arange(400) * 0.3)
    path = write_uff(tmp_path / "r.uff", [set58(v, 1)])
    p = hyst_ssi(hyst_bin, path, tmp_path, "--fs", "100", check=False)
    assert p.returncode != 0
    assert "a sampling rate of 100 Hz was given, but the file states 20 Hz" in p.stderr, p.stderr


def test_hyst_read_gives_the_record_and_its_rate_and_the_shapes_go_back_out(data_dir, tmp_path):
    """From Python: `hyst.read` of the pyuff file gives the values pyuff reads, the file's
    rate and points; `hyst.ssi` on it equals `hyst.ssi` on the array; `write_shapes_uff`
    with the record's points writes what pyuff reads back as the shapes."""
    import hyst

    y, _ = read_record(data_dir / "oma" / "data_3dof.csv")
    uff = write_uff(tmp_path / "rec.uff", [set58(y[:, c], c + 1) for c in range(3)])
    rec = hyst.read(uff)
    back = np.column_stack([s["data"] for s in pyuff.UFF(str(uff)).read_sets()])
    assert np.array_equal(rec.data, back)
    assert rec.fs == FS and rec.names == ["1+Z", "2+Z", "3+Z"]
    assert rec.points == [(1, 3), (2, 3), (3, 3)]
    assert rec.data.flags["F_CONTIGUOUS"]
    r = hyst.ssi(rec.data, rec.fs, channels=rec.names)
    assert np.array_equal(r.frequency_hz, hyst.ssi(back, FS).frequency_hz)
    out = tmp_path / "modes.uff"
    r.write_shapes_uff(out, points=rec.points)
    sets = pyuff.UFF(str(out)).read_sets()
    sets = sets if isinstance(sets, list) else [sets]
    assert len(sets) == len(r.frequency_hz)
    for k, s in enumerate(sets):
        assert np.allclose(s["r3"], r.shape[k], rtol=5e-6, atol=0)
    with pytest.raises(ValueError, match="no dataset 58"):
        hyst.read(out)
    with pytest.raises(ValueError, match='format `xls` is not one of auto, csv, npy, npz, mat, uff'):
        hyst.read(uff, format="xls")
