"""hyst.ssi against the command line on the shared OMA records, its errors, its memory."""

import json
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import hyst


def read_record(path):
    """The record's response columns (all but a time column) and their names, as the
    command line takes them by default."""
    names = path.read_text().splitlines()[0].split(",")
    cols = [i for i, n in enumerate(names) if n.strip().lower() not in ("t", "time")]
    y = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return y[:, cols], [names[i] for i in cols]


def cli_flags(keywords):
    """The command line's flags for Python keywords, by the rule the parity test checks:
    `--` and the name in kebab case, a False switch as `--no-name`, a list comma-separated,
    a pair as two values."""
    args = []
    for k, v in keywords.items():
        flag = "--" + k.replace("_", "-")
        if v is False:
            args.append("--no-" + k.replace("_", "-"))
        elif isinstance(v, tuple):
            args += [flag] + [str(x) for x in v]
        elif isinstance(v, list):
            args += [flag, ",".join(str(x) for x in v)]
        else:
            args += [flag, str(v)]
    return args


@pytest.mark.parametrize(
    "name, fs, flags",
    [
        ("data_3dof.csv", 20.0, {}),
        ("data_3dof.csv", 20.0, {"block_rows": 60, "max_order": 40, "dmac": 0.03}),
        ("data_3dof.csv", 20.0, {"lag_periods": (10, 1.0), "decimate": 2, "joint": False,
                                 "references": [0, 2], "dzeta": 0.06, "order_step": 2}),
        ("data_sdof.csv", 20.0, {}),
    ],
)
def test_the_same_document_as_the_command_line(data_dir, hyst_bin, tmp_path, name, fs, flags):
    """On the shared OMA records hyst.ssi gives the very document `hyst ssi --json` writes:
    every mode, standard error, shape and pole, to the last bit (the same library on the
    same numbers; numpy and the command line parse the CSV's decimals alike)."""
    path = data_dir / "oma" / name
    if not path.is_file():
        pytest.fail(f"{path} is missing from the shared data")
    y, names = read_record(path)
    args = [str(hyst_bin), "ssi", "--input", str(path), "--fs", str(fs)] + cli_flags(flags)
    out = tmp_path / "cli.json"
    subprocess.run(args + ["--json", str(out)], check=True, capture_output=True)
    want = json.loads(out.read_text())
    r = hyst.ssi(y, fs, channels=names, record=str(path), **flags)
    assert r.to_dict() == want
    # The arrays are the document's answer (covssi::decision), number for number.
    assert r.source == want["decision"]["source"]
    modes = want["modes"]
    assert len(modes) == len(r.frequency_hz) > 0
    for i, m in enumerate(modes):
        assert r.frequency_hz[i] == m["frequency_hz"]
        assert r.damping_ratio[i] == m["damping_ratio"]
        if m["frequency_se_hz"] is None:
            assert np.isnan(r.frequency_se_hz[i])
        else:
            assert r.frequency_se_hz[i] == m["frequency_se_hz"]
            assert r.damping_se[i] == m["damping_se"]
    assert r.poles.shape[0] == len(r.pole_status) == sum(
        len(o["poles"]) for o in want["diagram"]["orders"]
    )


def test_a_fortran_array_gives_the_same_result_as_a_c_array(data_dir):
    y, _ = read_record(data_dir / "oma" / "data_3dof.csv")
    a = hyst.ssi(np.ascontiguousarray(y), 20.0, refine=False)
    b = hyst.ssi(np.asfortranarray(y), 20.0, refine=False)
    assert a.to_json() == b.to_json()


def test_errors_are_value_errors_with_the_librarys_message(hyst_bin, tmp_path):
    """A record too short for SSI: the message is the library's, the one the command line
    prints after the file's name."""
    y = np.sin(np.arange(30.0))[:, None]
    with pytest.raises(ValueError) as e:
        hyst.ssi(y, 10.0)
    csv = tmp_path / "short.csv"
    np.savetxt(csv, y, delimiter=",", header="y", comments="")
    p = subprocess.run(
        [str(hyst_bin), "ssi", "--input", str(csv), "--fs", "10", "--json", str(tmp_path / "o.json")],
        capture_output=True,
        text=True,
    )
    assert p.returncode != 0
    assert str(e.value) in p.stderr, (str(e.value), p.stderr)


@pytest.mark.parametrize(
    "y, kwargs, says",
    [
        (np.full((4096, 1), np.nan), {}, "finite"),
        (np.ones((4096, 2)), {"block_rows": 10, "lag_seconds": 1.0}, "not both"),
        (np.random.default_rng(1).standard_normal((4096, 2)), {"block_rows": 1}, "block"),
        # PyO3 raised OverflowError for a negative count; the documented error is ValueError.
        (np.random.default_rng(1).standard_normal((4096, 2)), {"block_rows": -1}, "block_rows must be at least 2"),
        (np.random.default_rng(1).standard_normal((4096, 2)), {"decimate": 0}, "decimate must be at least 1"),
        # Complex values lost their imaginary part with only numpy's warning.
        (np.ones((4096, 2)) * (1 + 1j), {}, "complex"),
        (np.random.default_rng(1).standard_normal((4096, 2)), {"references": [5]}, "5"),
        (np.zeros((2, 3, 4)), {}, "shape"),
        (np.ones((4096, 2)), {"channels": ["a"]}, "channel"),
    ],
)
def test_bad_input_is_a_value_error_naming_it(y, kwargs, says):
    with pytest.raises(ValueError, match=says):
        hyst.ssi(y, 10.0, **kwargs)


def test_track_refuses_what_the_command_line_refuses():
    """No records, a rate of 0 and complex records ran (or lost their imaginary part)."""
    y = np.random.default_rng(2).standard_normal((2000, 2))
    with pytest.raises(ValueError, match="no records"):
        hyst.track([], 10.0)
    with pytest.raises(ValueError, match="fs must be a positive finite rate"):
        hyst.track([y, y], 0.0)
    with pytest.raises(ValueError, match="record 1 is complex"):
        hyst.track([y, y * 1j], 10.0)


PEAK = """
import resource, sys, numpy as np, hyst
n, l = 1_000_000, 10
rng = np.random.default_rng(1)
y = rng.standard_normal((l, n)).T if sys.argv[1] == "F" else rng.standard_normal((n, l))
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
hyst.ssi(y, 100.0, refine=False)
print((resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before) * 1024 / y.nbytes)
"""


def peak_rise(order):
    """The rise of the peak resident memory over a 10^6 x 10 array's size while hyst.ssi
    runs SSI on it, in a process of its own."""
    p = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(PEAK), order],
        check=True,
        capture_output=True,
        text=True,
    )
    return float(p.stdout)


def test_a_long_record_crosses_without_a_copy_per_channel():
    """A 10^6 x 10 Fortran-ordered array is read in place (measured: the peak rose by 0.08
    of the array's size, SSI's own work); a C-ordered one is copied once (1.08), not once
    per channel and again."""
    fortran, c = peak_rise("F"), peak_rise("C")
    print(f"peak rise over the array's size: Fortran order {fortran:.2f}, C order {c:.2f}")
    assert fortran < 0.5
    assert c < 1.5


def test_the_type_stubs_name_what_the_package_has():
    """Every name the stubs (`hyst/__init__.pyi`) give exists, and every public attribute
    of SsiResult and field of Record is in them."""
    import re
    from pathlib import Path

    stubs = (Path(hyst.__file__).parent / "__init__.pyi").read_text()
    stubbed = set(re.findall(r"def (\w+)\(", stubs))
    functions = {"ssi", "read", "read_shapes", "excite", "simulate", "identify", "refine", "levels",
                 "track", "track_estimates", "amplitude", "follow"}
    assert functions <= stubbed and all(hasattr(hyst, f) for f in functions)
    assert "class Record" in stubs and set(hyst.Record.__dataclass_fields__) == set(
        re.findall(r"^    (\w+): ", stubs.split("class Record")[1].split("def ")[0], re.M)
    )
    methods = stubbed - functions
    classes = (hyst.SsiResult, hyst.Report, hyst.Follow)
    assert all(any(hasattr(c, m) for c in classes) for m in methods), (
        {m for m in methods if not any(hasattr(c, m) for c in classes)})
    for c in classes:
        public = {n for n in dir(c) if not n.startswith("_")}
        assert public <= methods, (c.__name__, public - methods)


def test_a_long_ssi_shows_its_steps_on_a_terminal_only():
    """On a terminal, hyst.ssi tells its steps on one stderr line (each model order, then the
    refinement's steps, asked for) and wipes it; in a pipe (a notebook, a log) it writes nothing."""
    import os
    import pty
    import sys

    code = (
        "import hyst; "
        "u = hyst.excite(750.0, excitation='white', rms=30.0, samples=2**14, seed=5); "
        "hyst.ssi(hyst.simulate('benchmark', u, 750.0, input_interpolation='linear'), 750.0, "
        "refine=True)"
    )
    leader, follower = pty.openpty()
    subprocess.run([sys.executable, "-c", code], stderr=follower, stdout=subprocess.DEVNULL,
                   check=True)
    os.close(follower)
    shown = b""
    while True:
        try:
            chunk = os.read(leader, 1 << 16)
        except OSError:  # Linux: the terminal's other side closed, all read
            break
        if not chunk:
            break
        shown += chunk
    os.close(leader)
    text = shown.decode()
    assert "SSI: poles of 1 of" in text and "refining: " in text, text
    assert text.endswith("\r\x1b[2K"), repr(text[-40:])
    piped = subprocess.run([sys.executable, "-c", code], capture_output=True, check=True)
    assert piped.stderr == b""
