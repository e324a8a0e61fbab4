"""`hyst.simulate`, `identify`, `refine` and `levels` against the command line's `simulate`,
`ident`, `refine` and `levels` on the same records: the same numbers, to the last bit, and the
same JSON documents (the run time and the record's name aside)."""

import json
import os
import subprocess

import numpy as np
import pytest

import hyst

FS = 750.0


def run(hyst_bin, *args):
    p = subprocess.run([str(hyst_bin), *map(str, args)], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    return p


def document(path):
    return comparable(json.loads(path.read_text()))


def comparable(doc):
    """A report's document without what differs between two runs of the same computation:
    the run time, and the record's name."""
    if isinstance(doc, dict):
        return {k: comparable(v) for k, v in doc.items() if k not in ("seconds", "record")}
    if isinstance(doc, list):
        return [comparable(v) for v in doc]
    return doc


def columns(path):
    names = path.read_text().splitlines()[0].split(",")
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return {n: data[:, i] for i, n in enumerate(names)}


@pytest.fixture(scope="module")
def white(hyst_bin, tmp_path_factory):
    """A 30 N white force of 2^14 samples (made by `hyst excite`) and the benchmark's
    response to it, both from the command line."""
    d = tmp_path_factory.mktemp("white")
    run(hyst_bin, "excite", "--excitation", "white", "--rms", 30, "--samples", 16384,
        "--seed", 7, "--fs", FS, "--out", d / "u.csv")
    run(hyst_bin, "simulate", "--input", d / "u.csv", "--fs", FS, "--out", d / "uy.csv")
    return d, columns(d / "uy.csv")


@pytest.mark.parametrize(
    "flags, kwargs",
    [
        ([], {}),
        (["--input-interpolation", "linear"], {"input_interpolation": "linear"}),
        (["--periodic", "--integrator", "newmark", "--decimation", "fir"],
         {"periodic": True, "integrator": "newmark", "decimation": "fir"}),
        (["--noise", "1e-6", "--noise-seed", "9"], {"noise": 1e-6, "noise_seed": 9}),
    ],
)
def test_simulate_gives_the_commands_samples(hyst_bin, white, flags, kwargs):
    d, uy = white
    u = uy["u"][:4096]
    np.savetxt(d / "u4k.csv", u, fmt="%.17g", header="u", comments="")
    out = d / "sim.csv"
    run(hyst_bin, "simulate", "--input", d / "u4k.csv", "--fs", FS, "--out", out, *flags)
    # The command writes the shortest digits that read back to the same double.
    assert np.array_equal(hyst.simulate("benchmark", u, FS, **kwargs), columns(out)["y"])


@pytest.mark.parametrize(
    "flags, kwargs",
    [
        ([], {}),
        (["--excitation", "white", "--rms", "3", "--samples", "1000", "--seed", "7"],
         {"excitation": "white", "rms": 3, "samples": 1000, "seed": 7}),
        (["--excitation", "sweep", "--f-min", "2", "--f-max", "40", "--fs", "200",
          "--samples", "2000"],
         {"excitation": "sweep", "f_min": 2, "f_max": 40, "fs": 200, "samples": 2000}),
    ],
)
def test_excite_gives_the_commands_samples(hyst_bin, tmp_path, flags, kwargs):
    out = tmp_path / "u.csv"
    run(hyst_bin, "excite", "--out", out, *flags)
    assert np.array_equal(hyst.excite(**kwargs), columns(out)["u"])


def test_the_printed_summary_is_the_files(hyst_bin, tmp_path):
    """What `hyst excite` and `hyst simulate` print (samples, duration, RMS, peak, with units)
    is what numpy computes from the files they wrote."""
    import re

    u = tmp_path / "u.csv"
    p = run(hyst_bin, "excite", "--excitation", "white", "--rms", 3, "--samples", 3000,
            "--fs", 300, "--out", u)
    x = columns(u)["u"]
    m = re.search(r"(\d+) samples at 300 Hz \(([\d.]+) s\); u: force \(N\), RMS ([\d.]+) N",
                  p.stdout)
    assert m, p.stdout
    assert int(m[1]) == x.size == 3000 and float(m[2]) == 10.0
    assert float(m[3]) == pytest.approx(np.sqrt(np.mean(x**2)), abs=1e-4)  # 4 decimals printed
    y = tmp_path / "y.csv"
    p = run(hyst_bin, "simulate", "--input", u, "--fs", 300, "--out", y)
    r = columns(y)["y"]
    m = re.search(r"y: displacement \(m\), RMS (\S+) m, peak (\S+) m", p.stdout)
    assert m, p.stdout
    # Five significant digits printed.
    assert float(m[1]) == pytest.approx(np.sqrt(np.mean(r**2)), rel=1e-4)
    assert float(m[2]) == pytest.approx(np.abs(r).max(), rel=1e-4)


def test_excite_refuses_an_unknown_kind():
    with pytest.raises(ValueError, match='excitation "pink" is not one of'):
        hyst.excite(excitation="pink")


def test_a_model_dict_simulates_as_the_params_file(hyst_bin, white, tmp_path):
    d, uy = white
    # Not the benchmark's numbers: a model of the schema `hyst_model::schema` documents.
    model = {"mass": 2.0, "damping": 8.0, "stiffness": 6e4,
             "bouc_wen": {"alpha": 4e4, "beta_gamma": 900.0, "beta_delta": -1200.0, "nu": 1.0}}
    y = hyst.simulate(model, uy["u"][:2048], FS)
    params = tmp_path / "m.json"
    params.write_text(json.dumps(model))
    np.savetxt(tmp_path / "u.csv", uy["u"][:2048], fmt="%.17g", header="u", comments="")
    run(hyst_bin, "simulate", "--input", tmp_path / "u.csv", "--fs", FS, "--params", params,
        "--out", tmp_path / "y.csv")
    assert np.array_equal(y, columns(tmp_path / "y.csv")["y"])


def test_identify_gives_the_commands_document(hyst_bin, white):
    d, uy = white
    run(hyst_bin, "ident", "--data", d / "uy.csv", "--fs", FS, "--mass", 2, "--json", d / "id.json")
    report = hyst.identify(uy["y"], FS, 2.0)
    assert comparable(report.to_dict()) == document(d / "id.json")
    assert str(report).startswith("record: array")
    # The identified model simulates as it is.
    y = hyst.simulate(report.to_dict()["bouc_wen"], uy["u"][:1024], FS)
    assert np.all(np.isfinite(y))


def test_refine_gives_the_commands_document(hyst_bin, white):
    d, uy = white
    # The first 6144 samples: the loop's cost grows with the record.
    u, y = uy["u"][:6144], uy["y"][:6144]
    np.savetxt(d / "short.csv", np.column_stack([u, y]), delimiter=",", fmt="%.17g",
               header="u,y", comments="")
    run(hyst_bin, "refine", "--data", d / "short.csv", "--fs", FS, "--mass", 2, "--start",
        "zener", "--json", d / "refine.json")
    report = hyst.refine(u, y, FS, mass=2.0, start="zener")
    assert comparable(report.to_dict()) == document(d / "refine.json")


def test_levels_give_the_commands_document(hyst_bin, tmp_path):
    paths, records = [], {}
    for rms, seed in [(10, 21), (50, 22), (90, 23)]:
        u = tmp_path / f"u{rms}.csv"
        run(hyst_bin, "excite", "--excitation", "white", "--rms", rms, "--samples", 32768,
            "--seed", seed, "--fs", FS, "--out", u)
        p = tmp_path / f"y{rms}.csv"
        run(hyst_bin, "simulate", "--input", u, "--fs", FS, "--out", p)
        paths.append(p)
        records[str(p)] = columns(p)["y"]
    run(hyst_bin, "levels", "--data", *paths, "--fs", FS, "--mass", 2, "--json", tmp_path / "l.json")
    report = hyst.levels(records, FS, 2.0)
    assert comparable(report.to_dict()) == document(tmp_path / "l.json")


@pytest.mark.parametrize(
    "call, says",
    [
        (lambda: hyst.simulate({"mass": 2.0, "stiffnes": 1.0}, np.ones(8), FS), "unknown field `stiffnes`"),
        (lambda: hyst.simulate("benchmark", np.ones(8), FS, integrator="euler"), 'integrator "euler" is not one of'),
        (lambda: hyst.simulate("benchmark", np.ones(8), -1.0), "sampling rate must be > 0"),
        (lambda: hyst.identify(np.zeros(4096), FS, 2.0), "constant"),
        (
            lambda: hyst.identify(np.random.default_rng(5).standard_normal(4096), 750.0, 2.0,
                                  excitation_band=(5.0, 400.0), period=1024),
            "excitation band 5..400 Hz reaches above the Nyquist frequency 375 Hz of 750 Hz",
        ),
        (lambda: hyst.refine(np.ones(10), np.ones(10), FS, start="cubic"), 'start "cubic" is not one of'),
        (lambda: hyst.levels([np.ones(100)], FS, 2.0, validate=[{"u": [1.0], "x": [2.0]}]), "unknown keys ['x']"),
    ],
)
def test_bad_input_raises_value_error_with_the_librarys_message(call, says):
    with pytest.raises(ValueError) as e:
        call()
    assert says in str(e.value), str(e.value)


@pytest.mark.parametrize(
    "settings", [{}, {"lag_periods": (8, 1.0), "decimate": 2, "joint": False, "dmac": 0.03}]
)
def test_track_gives_the_commands_report(data_dir, hyst_bin, tmp_path, settings):
    """`hyst.track` on ten 300 s windows of the 3-DOF record, as arrays, and `hyst track`
    on the same windows of the file: the same report (the record's name aside), with the
    defaults and with SSI settings given as keywords and as flags."""
    from test_ssi import cli_flags, read_record

    y, _ = read_record(data_dir / "oma" / "data_3dof.csv")
    out = tmp_path / "track"
    page = tmp_path / "track.html"
    run(hyst_bin, "track", "--input", data_dir / "oma" / "data_3dof.csv", "--fs", 20,
        "--window", 300, "--columns", "y1,y2,y3", "--out", out, "--html", page, *cli_flags(settings))
    windows = [y[i * 6000:(i + 1) * 6000] for i in range(10)]
    report = hyst.track(windows, 20.0, times=[300.0 * i for i in range(10)], **settings)
    assert comparable(report.to_dict()) == document(out / "report.json")
    # The page a browser opens: the command's, from the same report.
    assert report.html() == page.read_text()
    assert [round(m["frequency_hz"], 1) for m in report.to_dict()["reference"]] == [1.0, 2.8, 4.1]
    if settings:
        return
    # The same windows as files (.npy), read by hyst.track itself.
    paths = []
    for i, w in enumerate(windows):
        paths.append(tmp_path / f"w{i}.npy")
        np.save(paths[-1], w)
    from_files = hyst.track(paths, 20.0, times=[300.0 * i for i in range(10)])
    named = comparable(from_files.to_dict())
    assert [r["name"] for r in named["rows"][::3]] == [f"w{i}.npy" for i in range(10)]
    for r in named["rows"]:
        r["name"] = r["name"][1:-4]
    assert named == comparable(report.to_dict())


def test_track_on_a_local_dask_cluster_gives_the_commands_report(data_dir, hyst_bin, tmp_path):
    """`hyst.track(paths, client=...)` on a LocalCluster of 2 worker processes, each reading
    its records' files, and `hyst track --inputs` on the same 16 files: the same report;
    records per minute of both printed (`pytest -s`). An unreadable file is skipped with
    the reason, as the command skips it."""
    import time

    from dask.distributed import Client, LocalCluster

    from test_ssi import read_record

    y, _ = read_record(data_dir / "oma" / "data_3dof.csv")
    folder = tmp_path / "records"
    folder.mkdir()
    paths = []
    for i in range(16):
        paths.append(folder / f"w{i:02d}.npy")
        np.save(paths[-1], y[i * 4000:(i + 1) * 4000])
    # A file no reader takes: both skip it with the reason.
    paths.insert(5, folder / "w04b.npy")
    paths[5].write_bytes(b"not an array")
    out = tmp_path / "track"
    t0 = time.perf_counter()
    run(hyst_bin, "track", "--inputs", folder, "--fs", 20, "--out", out)
    command = time.perf_counter() - t0
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True) as cluster, \
            Client(cluster) as client:
        t0 = time.perf_counter()
        report = hyst.track(paths, 20.0, client=client)
        dask = time.perf_counter() - t0
    doc = comparable(report.to_dict())
    assert doc == document(out / "report.json")
    assert any("w04b.npy" in str(s) for s in doc["skipped"]), doc["skipped"]
    print(f"\n17 records: hyst track {60 * 17 / command:.0f} records/min ({command:.1f} s); "
          f"hyst.track on a LocalCluster of 2 processes {60 * 17 / dask:.0f} records/min "
          f"({dask:.1f} s)")
    with pytest.raises(ValueError, match="give file paths"):
        hyst.track([y[:4000]], 20.0, client=client)


def test_follow_gives_the_commands_report_as_records_land(data_dir, hyst_bin, tmp_path):
    """`hyst.follow` on a folder where twelve windows of the 3-DOF record land one after
    another (four there at the start, each later one written elsewhere and moved in), with a
    covariates file timing them: once all have landed its report is `hyst track --inputs
    <folder> --covariates` 's over the same files; the first pass says the files not landed
    as gaps and each is said once when it lands; no alarm line twice. A new follow over the
    whole folder (a stop and a start) gives the same report in one pass."""
    import threading
    import time

    from test_ssi import read_record

    y, _ = read_record(data_dir / "oma" / "data_3dof.csv")
    staging, folder = tmp_path / "staging", tmp_path / "records"
    staging.mkdir()
    folder.mkdir()
    cov = tmp_path / "covariates.csv"
    cov.write_text("record,time,temperature\n" + "".join(
        f"w{i:02d}.npy,{200.0 * i},{10.0 + 3.0 * np.sin(i)}\n" for i in range(12)))

    def land(i):
        np.save(staging / f"w{i:02d}.npy", y[i * 4000:(i + 1) * 4000])
        os.replace(staging / f"w{i:02d}.npy", folder / f"w{i:02d}.npy")

    for i in range(4):
        land(i)
    followed = hyst.follow(folder, 20.0, covariates=cov, training=6, poll=0.2)

    def later():
        for i in range(4, 12):
            time.sleep(0.5)
            land(i)

    lander = threading.Thread(target=later)
    lander.start()
    lines, deadline = [], time.monotonic() + 600
    for line in followed:
        lines.append(line)
        if len(followed.taken) == 12 and followed.waiting == 0:
            break
        assert time.monotonic() < deadline, lines
    lander.join()
    # The first pass's report: the files the covariates file times but that have not landed
    # are gaps, said as skipped; each is said again, once, when it lands.
    for i in range(4, 12):
        assert any(f"skipped w{i:02d}.npy: no such file" in l for l in lines), i
        assert lines.count(f"w{i:02d}.npy: 3 mode(s) tracked") == 1, (i, lines)
    out = tmp_path / "track"
    run(hyst_bin, "track", "--inputs", folder, "--fs", 20, "--covariates", cov, "--training",
        6, "--out", out)
    doc = comparable(followed.report.to_dict())
    assert doc == document(out / "report.json")
    alarms = [l.strip() for l in lines if l.strip().startswith("ALARM")]
    assert len(alarms) == len(set(alarms)), alarms
    for a in followed.report.alarm_lines():
        assert any(a in l for l in lines), a
    again = hyst.follow(folder, 20.0, covariates=cov, training=6, poll=0.2, passes=1)
    text = "\n".join(again)
    assert comparable(again.report.to_dict()) == doc
    assert text.strip() == str(again.report).strip()
    with pytest.raises(ValueError, match="poll"):
        hyst.follow(folder, 20.0, poll=0.0)


def test_track_with_the_level_covariate_gives_the_commands_report(data_dir, hyst_bin, tmp_path):
    """`hyst track --level-covariate` and `hyst.track(level_covariate=True)` on the same ten
    windows: the same report, its covariate named log_rms; each record's level is the root
    of its channels' mean variance, as numpy computes it."""
    from test_ssi import read_record

    y, _ = read_record(data_dir / "oma" / "data_3dof.csv")
    out = tmp_path / "track"
    run(hyst_bin, "track", "--input", data_dir / "oma" / "data_3dof.csv", "--fs", 20,
        "--window", 300, "--columns", "y1,y2,y3", "--level-covariate", "--out", out)
    windows = [y[i * 6000:(i + 1) * 6000] for i in range(10)]
    report = hyst.track(windows, 20.0, times=[300.0 * i for i in range(10)],
                        level_covariate=True)
    doc = comparable(report.to_dict())
    assert doc == document(out / "report.json")
    assert doc["covariate_names"] == ["log_rms"]
    for row in doc["rows"]:
        w = windows[int(row["name"])]
        assert abs(row["covariates"][0] - np.log(np.sqrt(np.mean(np.var(w, axis=0))))) < 1e-9


def test_track_takes_the_commands_reference_and_named_covariates(data_dir, hyst_bin, tmp_path):
    """`hyst track --reference ref.json --covariates cov.csv` and `hyst.track(reference=...,
    covariates={name: values})` on the same windows: the same report, the reference given as
    the file or as `hyst.ssi`'s result; the covariate named in both texts."""
    from test_ssi import read_record

    rec = data_dir / "oma" / "data_3dof.csv"
    y, _ = read_record(rec)
    windows = [y[i * 6000:(i + 1) * 6000] for i in range(10)]
    np.savetxt(tmp_path / "first.csv", windows[0], delimiter=",", header="y1,y2,y3",
               comments="", fmt="%.17g")
    run(hyst_bin, "ssi", "--input", tmp_path / "first.csv", "--fs", 20,
        "--json", tmp_path / "ref.json")
    temperature = 10.0 + np.arange(10) % 3
    rows = ["record,time,temperature"] + [f"{i},{300.0 * i},{t}" for i, t in enumerate(temperature)]
    (tmp_path / "cov.csv").write_text("\n".join(rows) + "\n")
    out = tmp_path / "track"
    p = run(hyst_bin, "track", "--input", rec, "--fs", 20, "--window", 300, "--columns",
            "y1,y2,y3", "--reference", tmp_path / "ref.json", "--covariates", tmp_path / "cov.csv",
            "--training", 5, "--out", out)
    times = [300.0 * i for i in range(10)]
    kwargs = dict(times=times, covariates={"temperature": temperature}, training=5)
    from_file = hyst.track(windows, 20.0, reference=tmp_path / "ref.json", **kwargs)
    assert comparable(from_file.to_dict()) == document(out / "report.json")
    from_ssi = hyst.track(windows, 20.0, reference=hyst.ssi(windows[0], 20.0), **kwargs)
    assert comparable(from_ssi.to_dict()) == comparable(from_file.to_dict())
    assert "Hz per unit of temperature" in p.stdout, p.stdout
    assert_exports_agree(out)
    assert str(from_file).splitlines()[1:] == p.stdout.splitlines()[-len(str(from_file).splitlines()) + 1:]
    with pytest.raises(ValueError, match="reference: not JSON"):
        (tmp_path / "bad.json").write_text("{")
        hyst.track(windows[:2], 20.0, reference=tmp_path / "bad.json")


def assert_exports_agree(out):
    """`hyst track`'s three copies of its tidy table, each read by another program: the
    Parquet file by pyarrow and the store's `tracked` table by Python's sqlite3 hold the
    cells of `table.csv` (read by the csv module): the same numbers, an empty cell null,
    NaN a number (null in SQLite, which has no NaN)."""
    import csv
    import math
    import sqlite3

    import pyarrow.parquet as pq

    with open(out / "table.csv", newline="") as f:
        rows = list(csv.reader(f))
    header, rows = rows[0], rows[1:]
    parquet = pq.read_table(out / "table.parquet").to_pydict()
    assert list(parquet) == header
    db = sqlite3.connect(out / "store.sqlite")
    sql = db.execute("SELECT * FROM tracked").fetchall()
    assert [d[0] for d in db.execute("SELECT * FROM tracked").description] == header
    assert len(sql) == len(rows) == len(parquet["record"]) > 0
    for i, row in enumerate(rows):
        for j, (name, cell) in enumerate(zip(header, row)):
            p, s = parquet[name][i], sql[i][j]
            if cell == "":
                assert p is None and s is None, (name, i)
            elif name in ("record", "mode", "alarm"):
                assert p == s == cell, (name, i)
            elif name in ("misfit_flag", "extrapolated"):
                assert p == bool(s) == (cell == "true"), (name, i)
            elif math.isnan(float(cell)):
                assert math.isnan(p) and s is None, (name, i)
            else:
                assert p == s == float(cell), (name, i, p, s, cell)
    # The store's records: one row per record, each a whole JSON record.
    names = [r[0] for r in db.execute("SELECT name FROM records ORDER BY rowid")]
    assert sorted(names, key=int) == sorted({r[0] for r in rows} | set(names), key=int)
    for (text,) in db.execute("SELECT record FROM records"):
        assert "outcome" in json.loads(text)


def test_track_estimates_gives_the_commands_report(hyst_bin, tmp_path):
    """`hyst.track_estimates` and `hyst track --estimates` on the same table and covariates:
    the same report; the mode given without standard errors has its noise read from the
    training rows (numpy's median of consecutive differences, computed here, is the
    report's); a 1 % drop of mode b's later estimates is alarmed on b, down."""
    rng = np.random.default_rng(46)
    n, training = 80, 40
    temperature = 8.0 + 5.0 * np.sin(np.arange(n) / 6.0)
    a = 2.0 * (1.0 - 1e-3 * temperature) * (1.0 + 5e-4 * rng.standard_normal(n))
    b = 5.0 * (1.0 - 1e-3 * temperature) * (1.0 + 5e-4 * rng.standard_normal(n))
    b[60:] *= 0.99
    rows = ["record,time,a_hz,a_hz_se,b_hz,b_damping"]
    for i in range(n):
        b_cell = "" if i == 17 else repr(float(b[i]))
        damping = "" if i == 17 else "0.012"
        rows.append(f"r{i},{3600.0 * i},{float(a[i])!r},{1e-3},{b_cell},{damping}")
    (tmp_path / "est.csv").write_text("\n".join(rows) + "\n")
    cov = ["record,temperature"] + [f"r{i},{float(t)!r}" for i, t in enumerate(temperature)]
    (tmp_path / "cov.csv").write_text("\n".join(cov) + "\n")
    out = tmp_path / "track"
    run(hyst_bin, "track", "--estimates", tmp_path / "est.csv", "--covariates",
        tmp_path / "cov.csv", "--training", training, "--out", out)
    report = hyst.track_estimates(tmp_path / "est.csv", covariates=tmp_path / "cov.csv",
                                  training=training)
    doc = report.to_dict()
    assert comparable(doc) == document(out / "report.json")
    b_train = np.delete(b[:training], 17)
    expected = 1.4826 * np.median(np.abs(np.diff(b_train))) / np.sqrt(2.0)
    assert doc["noise_from_training"][0] is None
    assert abs(doc["noise_from_training"][1] - expected) <= 1e-12 * expected
    assert "no standard errors given" in str(report)
    alarms = doc["alarms"]
    assert alarms and all(x["mode"] == 1 and x["side"] == "down" for x in alarms), alarms
    assert all(x["record"] >= 60 for x in alarms), alarms


def test_modes_judged_together_as_numpy_reads_their_correlations(hyst_bin, tmp_path):
    """Three modes' estimates sharing a slow effect (no covariates, one standard error per
    mode): each mode's standardized residual is then its frequency less a constant over a
    constant, so the joint chart's eigenvalues are those of numpy's correlation matrix of
    the training frequencies, and its shared factors those above (1 + sqrt(p/m))^2; a 1 %
    drop of mode c is alarmed with c its first driver. With ``calibrate=False,
    joint_chart=False`` the report is ``hyst track --no-calibrate --no-joint-chart``'s."""
    rng = np.random.default_rng(8_500_901)
    n, training = 120, 60
    g = np.zeros(n)
    for i in range(1, n):
        g[i] = 0.95 * g[i - 1] + np.sqrt(1 - 0.95 ** 2) * rng.standard_normal()
    base = {"a": 1.0, "b": 2.5, "c": 4.0}
    f = {k: v * (1.0 + 3e-3 * g + 1e-3 * rng.standard_normal(n)) for k, v in base.items()}
    f["c"][90:] *= 0.99
    rows = ["record,time," + ",".join(f"{k}_hz,{k}_hz_se" for k in base)]
    for i in range(n):
        cells = ",".join(f"{float(f[k][i])!r},{1e-3 * base[k]!r}" for k in base)
        rows.append(f"r{i},{3600.0 * i},{cells}")
    (tmp_path / "est.csv").write_text("\n".join(rows) + "\n")
    doc = hyst.track_estimates(tmp_path / "est.csv", training=training).to_dict()
    joint = doc["joint"]
    train = np.column_stack([f[k][:training] for k in base])
    expected = np.sort(np.linalg.eigvalsh(np.corrcoef(train.T)))[::-1]
    assert np.allclose(joint["eigenvalues"], expected, rtol=1e-9, atol=1e-12), (
        joint["eigenvalues"], expected)
    edge = (1 + np.sqrt(3 / training)) ** 2
    assert joint["common_factors"] == int(np.sum(expected[:2] > edge)) == 1
    first = [a for a in joint["alarms"] if a["record"] >= 90]
    assert first and first[0]["drivers"][0][0] == 2, joint["alarms"]
    assert all(a["record"] >= 90 for a in joint["alarms"]), joint["alarms"]
    assert len(doc["calibrations"]) == 3
    out = tmp_path / "plain"
    run(hyst_bin, "track", "--estimates", tmp_path / "est.csv", "--training", training,
        "--no-calibrate", "--no-joint-chart", "--out", out)
    plain = hyst.track_estimates(tmp_path / "est.csv", training=training, calibrate=False,
                                 joint_chart=False).to_dict()
    assert plain["joint"] is None and all(c is None for c in plain["calibrations"])
    assert comparable(plain) == document(out / "report.json")


def shear_chain_accelerations(sigma, seconds, seed, fs=200.0):
    """A linear three-storey chain (masses 1000, 1000, 800 kg; storeys 1.2, 1.0, 0.8 MN/m;
    Rayleigh damping of 2 % at modes 1 and 3) under a white force on each floor held over
    each sample (standard deviation `sigma` N), its exact zero-order-hold discretization
    (scipy's matrix exponential): the floors' accelerations, an independent generator."""
    from scipy.linalg import expm

    m = np.array([1000.0, 1000.0, 800.0])
    k = np.array([1.2e6, 1.0e6, 0.8e6])
    kk = np.array([[k[0] + k[1], -k[1], 0.0], [-k[1], k[1] + k[2], -k[2]], [0.0, -k[2], k[2]]])
    w = np.sqrt(np.sort(np.linalg.eigvals(kk / m[:, None]).real))
    a1 = 2 * 0.02 / (w[0] + w[2])
    c = a1 * w[0] * w[2] * np.diag(m) + a1 * kk
    minv = np.diag(1.0 / m)
    a = np.block([[np.zeros((3, 3)), np.eye(3)], [-minv @ kk, -minv @ c]])
    b = np.vstack([np.zeros((3, 3)), minv])
    big = expm(np.block([[a, b], [np.zeros((3, 9))]]) / fs)
    ad, bd = big[:6, :6], big[:6, 6:]
    rng = np.random.default_rng(seed)
    n = int(seconds * fs)
    warm = int(60 * fs)
    f = sigma * rng.standard_normal((warm + n, 3))
    x = np.zeros(6)
    out = np.empty((n, 3))
    for i in range(warm + n):
        if i >= warm:
            out[i - warm] = (a @ x + b @ f[i])[3:]
        x = ad @ x + bd @ f[i]
    return out + 0.01 * out.std(axis=0) * rng.standard_normal(out.shape)


def test_levels_of_a_structure_give_the_commands_document(hyst_bin, tmp_path):
    """`hyst.levels(..., masses=)` and `hyst levels --masses` on the same three records of a
    linear chain: the same document; and no element is found in it (the chain has none)."""
    paths, records = [], {}
    for i, sigma in enumerate([100.0, 300.0, 900.0]):
        y = shear_chain_accelerations(sigma, 90.0, 8_300_601 + i)
        p = tmp_path / f"level{i}.csv"
        np.savetxt(p, y, delimiter=",", header="a1,a2,a3", comments="")
        paths.append(p)
        records[str(p)] = y
    out = run(hyst_bin, "levels", "--data", *paths, "--fs", 200, "--masses", "1000,1000,800",
              "--json", tmp_path / "s.json", "--predict", 2)
    report = hyst.levels(records, 200.0, masses=[1000.0, 1000.0, 800.0], predict=[2.0])
    assert comparable(report.to_dict()) == document(tmp_path / "s.json")
    assert report.to_dict()["storey"] is None, out.stdout
    assert "Hysteretic element: none" in out.stdout
    fitted_structure_simulates_as_scipy(hyst_bin, tmp_path, report.to_dict())


def fitted_structure_simulates_as_scipy(hyst_bin, tmp_path, fit):
    """A fitted linear chain (no element) driven by a force: `hyst.simulate(fit, ...)` and
    `hyst simulate --structure` give the same channels, and both are scipy's exact
    first-order-hold solution of the fitted structure (its modal damping built from its own
    modes), started at rest one sample before the force as the command says."""
    from scipy.linalg import eigh
    from scipy.signal import lsim

    rng = np.random.default_rng(8_400_701)
    forces = 200.0 * rng.standard_normal((4000, 3))
    y = hyst.simulate(fit, forces, 200.0)
    np.savetxt(tmp_path / "f.csv", forces, delimiter=",", header="f1,f2,f3", comments="")
    run(hyst_bin, "simulate", "--structure", tmp_path / "s.json", "--input", tmp_path / "f.csv",
        "--fs", 200, "--forces", "f1,f2,f3", "--out", tmp_path / "y.csv")
    cli = columns(tmp_path / "y.csv")
    assert list(cli) == ["f1", "f2", "f3", "a1", "a2", "a3"]
    got = np.column_stack([cli["a1"], cli["a2"], cli["a3"]])
    # The CSV holds each number to its shortest round-trip form: the same floats.
    np.testing.assert_allclose(got, y, rtol=0, atol=1e-12 * np.abs(y).max())

    b = fit["building"]
    m = np.array(b["masses"])
    k = np.array(b["stiffnesses"])
    kk = np.array([[k[0] + k[1], -k[1], 0.0], [-k[1], k[1] + k[2], -k[2]], [0.0, -k[2], k[2]]])
    w2, phi = eigh(kk, np.diag(m))  # mass-normalized shapes
    c = np.diag(m) @ phi @ np.diag(2 * np.array(b["damping_ratios"]) * np.sqrt(w2)) @ phi.T @ np.diag(m)
    minv = np.diag(1.0 / m)
    a = np.block([[np.zeros((3, 3)), np.eye(3)], [-minv @ kk, -minv @ c]])
    bb = np.vstack([np.zeros((3, 3)), minv])
    u = np.vstack([np.zeros((1, 3)), forces])
    t = np.arange(len(u)) / 200.0
    _, want, _ = lsim((a, bb, a[3:], minv), u, t, interp=True)
    # Runge-Kutta 4 at the fit's step (ω h ≈ 0.07 at the top mode) against the exact
    # solution: a phase error of order (ω h)⁴/120 per step (measured 4.7e-6 of the largest
    # value over 20 s; 1e-4 leaves room for another fit's modes).
    scale = np.abs(want).max()
    np.testing.assert_allclose(y, want[1:], rtol=0, atol=1e-4 * scale)


@pytest.mark.parametrize(
    "call, says",
    [
        (lambda: hyst.levels([np.ones((900, 3))] * 2, 200.0, 2.0, masses=[1.0, 1.0, 1.0]), "mass, by_simulation"),
        (lambda: hyst.levels([np.ones(900)] * 2, 200.0, masses=[1.0, 1.0, 1.0]), "(samples, channels)"),
        (lambda: hyst.levels([np.ones((900, 3))] * 2, 200.0, masses=[1.0] * 3, floors=[0, 1, 2]), "floors must be at least 1"),
        (lambda: hyst.levels([np.ones((900, 3))] * 2, 200.0, masses=[1.0] * 3, quantity="strain"), 'got "strain"'),
        (lambda: hyst.levels([np.ones(900)] * 2, 200.0), "needs mass"),
        (lambda: hyst.levels([np.ones(900)] * 2, 200.0, 2.0, predict=[2.0]), "give its masses"),
    ],
)
def test_a_structures_bad_input_is_named(call, says):
    with pytest.raises(ValueError) as e:
        call()
    assert says in str(e.value), str(e.value)
