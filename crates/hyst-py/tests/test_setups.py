"""`hyst.ssi(setups=...)` against `hyst ssi --setups`: the same merged report, on two roving
setups made here with scipy (each mode a resonator driven by white noise, an independent
generator), whose merged frequencies and shapes are the resonators'."""

import json
import subprocess

import numpy as np
import pytest

import hyst
from conftest import need

signal = need("scipy.signal")

FS = 20.0
MODES = [(1.5, 0.02), (4.0, 0.02)]


def shape(node):
    return np.array([np.sin(0.3 * node), np.sin(0.9 * node)])


def record(nodes, seed, n=8000):
    """Displacements at `nodes` of the modes MODES, each mode a discrete resonator (the
    exact pole pair at FS) driven by its own white noise."""
    rng = np.random.default_rng(seed)
    q = []
    for f, z in MODES:
        w = 2 * np.pi * f
        r, th = np.exp(-z * w / FS), w * np.sqrt(1 - z * z) / FS
        q.append(signal.lfilter([1.0], [1.0, -2 * r * np.cos(th), r * r], rng.standard_normal(n + 2000))[2000:])
    q = np.array(q)
    y = np.array([shape(k) @ q for k in nodes]).T
    return y + 0.02 * y.std(axis=0) * rng.standard_normal(y.shape)


@pytest.fixture(scope="module")
def setups(tmp_path_factory):
    d = tmp_path_factory.mktemp("setups")
    rows = ["setup,file,column,node,direction,quantity,reference"]
    for name, roving, seed in (("one", 3, 4701), ("two", 4, 4702)):
        y = record([6, 5, roving], seed)
        np.savetxt(d / f"{name}.csv", y, delimiter=",", header="a,b,r", comments="")
        rows += [f"{name},{name}.csv,a,6,x,displacement,yes",
                 f"{name},{name}.csv,b,5,x,displacement,yes",
                 f"{name},{name}.csv,r,{roving},x,displacement,no"]
    path = d / "setups.csv"
    path.write_text("\n".join(rows) + "\n")
    return path


def test_setups_give_the_commands_report_and_the_resonators_modes(hyst_bin, setups, tmp_path):
    out = tmp_path / "merged.json"
    # The command's file with the setups' diagrams (left out by default) is Python's report.
    subprocess.run([str(hyst_bin), "ssi", "--setups", str(setups), "--fs", str(FS), "--json", str(out),
                    "--json-diagrams"], check=True, capture_output=True)
    report = hyst.ssi(setups=setups, fs=FS)
    assert report.to_dict() == json.loads(out.read_text())
    assert "2 setups, each identified alone" in str(report)
    merged = report.to_dict()["merged"]
    assert len(merged["modes"]) == 2
    nodes = [d["node"] for d in merged["dofs"]]
    for j, (m, (f, _)) in enumerate(zip(merged["modes"], MODES)):
        assert abs(m["frequency_hz"] - f) < 0.01 * f
        v = np.array([complex(*e) for e in m["shape"]])
        truth = np.array([shape(int(k))[j] for k in nodes])
        mac = abs(np.vdot(v, truth)) ** 2 / (np.vdot(v, v).real * (truth @ truth))
        # 2 % noise on 400 s records of modes 60–160 decay times long: MAC above 0.99.
        assert mac > 0.99, (j, mac, v)
    # The merged table's MPC and MPD, against numpy's: MPC from the eigenvalues of the
    # real and imaginary parts' 2x2 covariance, MPD by Reynders et al.'s formula through the
    # SVD of [Re, Im] (the shape's entries some setup saw).
    lines = str(report).splitlines()
    head = lines.index(next(l for l in lines if "MPC    MPD" in l))
    for m, line in zip(merged["modes"], lines[head + 1:]):
        v = np.array([complex(*e) for e in m["shape"] if e is not None])
        x = np.c_[v.real, v.imag]
        s2 = np.linalg.eigvalsh(x.T @ x)
        mpc = ((s2[1] - s2[0]) / (s2[1] + s2[0])) ** 2
        vt = np.linalg.svd(x)[2]
        v12, v22 = vt[1, 0], vt[1, 1]
        cos = np.abs(v.real * v22 - v.imag * v12) / (np.hypot(v12, v22) * np.abs(v))
        mpd = np.degrees(np.sum(np.abs(v) * np.arccos(np.clip(cos, 0, 1))) / np.sum(np.abs(v)))
        cells = line.split()
        assert float(cells[-2]) == pytest.approx(mpc, abs=5e-4), line
        assert float(cells[-1]) == pytest.approx(mpd, abs=0.05 + 1e-6), line


def test_merged_shapes_go_to_a_universal_file_that_pyuff_reads_with_the_nodes(hyst_bin, setups, tmp_path):
    """`hyst ssi --setups --shapes-uff --geometry`: pyuff reads a dataset 15 with the
    geometry's nodes and positions, then one dataset 55 per merged mode whose eigenvalue is
    the mode's and whose nodes move as the merged report's JSON says, to the six significant
    digits of the format's E13.5 fields."""
    pyuff = need("pyuff")
    grid = tmp_path / "grid.txt"
    positions = {3: (0.0, 0.0, 3.0), 4: (0.0, 0.0, 4.0), 5: (0.0, 0.0, 5.0), 6: (0.0, 0.0, 6.0)}
    grid.write_text("node x y z\n" + "".join(f"{n} {x} {y} {z}\n" for n, (x, y, z) in positions.items()))
    out, uff = tmp_path / "merged.json", tmp_path / "merged.uff"
    run = subprocess.run([str(hyst_bin), "ssi", "--setups", str(setups), "--fs", str(FS), "--json", str(out),
                          "--shapes-uff", str(uff), "--geometry", str(grid)], check=True, capture_output=True, text=True)
    assert "2 merged mode shapes written" in run.stdout
    merged = json.loads(out.read_text())["merged"]
    sets = pyuff.UFF(str(uff)).read_sets()
    assert [s["type"] for s in sets] == [15] + [55] * len(merged["modes"])
    assert list(sets[0]["node_nums"]) == list(positions)
    assert np.allclose(np.c_[sets[0]["x"], sets[0]["y"], sets[0]["z"]], list(positions.values()))
    for k, (s, m) in enumerate(zip(sets[1:], merged["modes"])):
        assert s["analysis_type"] == 3 and s["mode_n"] == k + 1
        f = abs(s["eig"]) / (2 * np.pi)
        assert abs(f - m["frequency_hz"]) <= 1e-5 * f
        assert list(s["node_nums"]) == [int(n["node"]) for n in m["nodes"]]
        for axis, r in enumerate(("r1", "r2", "r3")):
            want = np.array([complex(*n["motion"][axis]) if n["motion"][axis] else 0 for n in m["nodes"]])
            # E13.5 keeps six significant digits of each part.
            assert np.allclose(s[r], want, rtol=1e-5, atol=1e-5 * np.abs(want).max())
    # hyst reads its own file back as pyuff does: the same nodes, eigenvalues and motions.
    back = hyst.read_shapes(uff)
    assert back.nodes == {n: tuple(x) for n, x in zip(sets[0]["node_nums"], np.c_[sets[0]["x"], sets[0]["y"], sets[0]["z"]])}
    for s, m in zip(sets[1:], back.modes):
        assert m.number == s["mode_n"] and m.nodes == list(s["node_nums"])
        assert m.frequency_hz == pytest.approx(abs(s["eig"]) / (2 * np.pi), rel=1e-12)
        assert m.damping_ratio == pytest.approx(-s["eig"].real / abs(s["eig"]), rel=1e-12)
        assert np.array_equal(m.motion, np.c_[s["r1"], s["r2"], s["r3"]])


def test_shapes_pyuff_writes_are_read_by_hyst(tmp_path):
    """A Universal File written by pyuff, as another program's export: a dataset 2411 of the
    nodes, a real normal mode (analysis type 2) with 6 values per node and a complex mode
    (type 3) with 3; hyst.read_shapes gives the nodes, each mode's frequency and damping and
    each node's translation as pyuff wrote them (to the file's E13.5 digits)."""
    pyuff = need("pyuff")
    from pyuff.datasets import dataset_55, dataset_2411
    path = tmp_path / "other.uff"
    nodes = np.array([3, 7, 11])
    xyz = np.array([[1.0, 2.5, -3.0], [0.0, 0.0, 12.5], [4.0, -1.0, 0.5]])
    normal = np.array([[1.0, -0.5, 0.25], [0.0, 0.0, 0.125], [0.3, 0.2, -0.1]])
    lam = 2 * np.pi * 5.5 * (-0.04 + 1j * np.sqrt(1 - 0.04 ** 2))
    complex_shape = np.array([[1 + 0.1j, 0, -0.2j], [0.5, 0.25 - 0.25j, 0], [0, 0, 1e-3 + 2e-3j]])
    uff = pyuff.UFF(str(path))
    uff.write_sets(dataset_2411.prepare_2411(node_nums=nodes, def_cs=np.ones(3, dtype=int), disp_cs=np.ones(3, dtype=int),
                                             color=np.ones(3, dtype=int), x=xyz[:, 0], y=xyz[:, 1], z=xyz[:, 2],
                                             return_full_dict=True), mode="overwrite")
    uff.write_sets(dataset_55.prepare_55(
        model_type=1, analysis_type=2, data_ch=3, spec_data_type=8, data_type=2, n_data_per_node=6,
        r1=normal[:, 0], r2=normal[:, 1], r3=normal[:, 2], r4=np.full(3, 9.0), r5=np.full(3, 9.0),
        r6=np.full(3, 9.0), load_case=1, mode_n=4, freq=3.25, modal_m=1.0, modal_damp_vis=0.015,
        modal_damp_his=0.0, node_nums=nodes, return_full_dict=True), mode="add")
    uff.write_sets(dataset_55.prepare_55(
        model_type=1, analysis_type=3, data_ch=2, spec_data_type=8, data_type=5, n_data_per_node=3,
        r1=complex_shape[:, 0], r2=complex_shape[:, 1], r3=complex_shape[:, 2], load_case=1, mode_n=5,
        eig=lam, modal_a=0j, modal_b=0j, node_nums=nodes), mode="add")
    shapes = hyst.read_shapes(path)
    assert list(shapes.nodes) == [3, 7, 11]
    assert np.allclose(list(shapes.nodes.values()), xyz, rtol=1e-15)
    first, second = shapes.modes
    assert (first.number, first.nodes, second.number) == (4, [3, 7, 11], 5)
    assert first.frequency_hz == pytest.approx(3.25, rel=1e-5)
    assert first.damping_ratio == pytest.approx(0.015, rel=1e-5)
    # E13.5 keeps six significant digits of each part.
    assert np.allclose(first.motion, normal, rtol=1e-5, atol=1e-6)
    assert second.frequency_hz == pytest.approx(5.5, rel=1e-5)
    assert second.damping_ratio == pytest.approx(0.04, rel=1e-5)
    assert np.allclose(second.motion, complex_shape, rtol=1e-5, atol=1e-6)
    # Nodes alone are no shapes: refused, naming what the file holds.
    other = tmp_path / "nodes_only.uff"
    pyuff.UFF(str(other)).write_sets(dataset_2411.prepare_2411(
        node_nums=nodes, def_cs=np.ones(3, dtype=int), disp_cs=np.ones(3, dtype=int), color=np.ones(3, dtype=int),
        x=xyz[:, 0], y=xyz[:, 1], z=xyz[:, 2], return_full_dict=True), mode="overwrite")
    with pytest.raises(ValueError, match="no dataset 55"):
        hyst.read_shapes(other)


def test_setups_refuse_a_record_beside_them(setups):
    with pytest.raises(ValueError, match="give y or setups, not both"):
        hyst.ssi(np.zeros((10, 2)), 20.0, setups=setups)
    with pytest.raises(ValueError, match="references is the setup file's"):
        hyst.ssi(setups=setups, references=[0])
    with pytest.raises(ValueError, match="no reference is common"):
        bad = setups.parent / "bad.csv"
        bad.write_text(setups.read_text().replace("b,5,x,displacement,yes", "b,5,x,displacement,no")
                       .replace("two,two.csv,a,6,x,displacement,yes", "two,two.csv,a,6,x,displacement,no"))
        hyst.ssi(setups=bad, fs=FS)


def test_records_outside_the_setup_folder_need_leave(setups, tmp_path):
    """A setup file naming its records by absolute paths (elsewhere than its folder) is
    refused with the flag that allows it; allowed, it merges as the file beside them does."""
    text = setups.read_text()
    for name in ("one.csv", "two.csv"):
        text = text.replace(f",{name},", f",{setups.parent / name},")
    elsewhere = tmp_path / "setups.csv"
    elsewhere.write_text(text)
    with pytest.raises(ValueError, match="not inside the setup file's folder"):
        hyst.ssi(setups=elsewhere, fs=FS)
    with pytest.raises(ValueError, match="rigid_floors go with setups"):
        hyst.ssi(np.zeros((10, 2)), FS, records_anywhere=True)
    anywhere = hyst.ssi(setups=elsewhere, fs=FS, records_anywhere=True).to_dict()["merged"]
    beside = hyst.ssi(setups=setups, fs=FS).to_dict()["merged"]
    assert anywhere == beside


def test_the_pages_are_the_commands(hyst_bin, setups, tmp_path):
    page = tmp_path / "merged.html"
    subprocess.run([str(hyst_bin), "ssi", "--setups", str(setups), "--fs", str(FS), "--html", str(page)],
                   check=True, capture_output=True)
    assert hyst.ssi(setups=setups, fs=FS).html() == page.read_text()
    # One record's page: the same as the command's, its FDD from the same samples.
    one = setups.parent / "one.csv"
    page = tmp_path / "one.html"
    subprocess.run([str(hyst_bin), "ssi", "--input", str(one), "--fs", str(FS), "--html", str(page)],
                   check=True, capture_output=True)
    y = np.loadtxt(one, delimiter=",", skiprows=1)
    result = hyst.ssi(y, FS, channels=["a", "b", "r"], fdd=True)
    assert result.html(title=f"hyst ssi: {one}") == page.read_text()
    # Without fdd=True the FDD is not computed: the page says so, and has no EFDD.
    bare = hyst.ssi(y, FS, channels=["a", "b", "r"]).html(title=f"hyst ssi: {one}")
    assert "No EFDD: the record's FDD was not computed" in bare
    assert "No EFDD" not in page.read_text()
    assert '"efdd":null' in bare and '"efdd":[' in page.read_text()
    with pytest.raises(ValueError, match="fdd is one record's"):
        hyst.ssi(setups=setups, fs=FS, fdd=True)
    with pytest.raises(ValueError, match="has no page"):
        hyst.amplitude(y[:, 0], FS).html()


def test_setups_of_universal_files_take_node_and_direction_from_the_file(tmp_path):
    """Two setups written by pyuff as datasets 58 (each channel at its node, along +Z): the
    setup file names only the columns (`6+Z`), the file gives each channel's node and
    direction, and the merge is the one the same setups give as CSV with them written out."""
    pyuff = need("pyuff")
    from test_uff import set58, write_uff

    rows = ["setup,file,column,node,direction,quantity,reference"]
    csv_rows = list(rows)
    for name, roving, seed in (("one", 3, 4711), ("two", 4, 4712)):
        y = record([6, 5, roving], seed)
        write_uff(tmp_path / f"{name}.uff", [set58(y[:, c], n, dx=1 / FS) for c, n in enumerate([6, 5, roving])])
        back = np.column_stack([s["data"] for s in pyuff.UFF(str(tmp_path / f"{name}.uff")).read_sets()])
        np.savetxt(tmp_path / f"{name}.csv", back, delimiter=",", header="a,b,r", comments="")
        for col, node, ref in (("6+Z", 6, "yes"), ("5+Z", 5, "yes"), (f"{roving}+Z", roving, "no")):
            rows.append(f"{name},{name}.uff,{col},,,displacement,{ref}")
            csv_rows.append(f"{name},{name}.csv,{'abr'[[6, 5, roving].index(node)]},{node},z,displacement,{ref}")
    (tmp_path / "uff_setups.csv").write_text("\n".join(rows) + "\n")
    (tmp_path / "csv_setups.csv").write_text("\n".join(csv_rows) + "\n")
    from_uff = hyst.ssi(setups=tmp_path / "uff_setups.csv").to_dict()["merged"]
    from_csv = hyst.ssi(setups=tmp_path / "csv_setups.csv", fs=FS).to_dict()["merged"]
    assert [(d["node"], d["direction"]) for d in from_uff["dofs"]] == [
        ("6", [0.0, 0.0, 1.0]), ("5", [0.0, 0.0, 1.0]), ("3", [0.0, 0.0, 1.0]), ("4", [0.0, 0.0, 1.0])]
    assert from_uff["modes"] == from_csv["modes"]
