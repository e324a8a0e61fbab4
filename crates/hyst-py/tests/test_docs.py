"""The code of docs/python.md runs as written."""

import json
import re

from conftest import ROOT


def test_the_python_guide_runs(data_dir, tmp_path, monkeypatch, capsys):
    text = (ROOT / "docs" / "python.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert blocks, "docs/python.md has no python block"
    monkeypatch.setenv("HYST_DATA_DIR", str(data_dir))
    monkeypatch.chdir(tmp_path)
    # The blocks run one after another in one namespace, as a reader pastes them.
    namespace = {"__name__": "docs"}
    for code in blocks:
        exec(compile(code, "docs/python.md", "exec"), namespace)
    out = capsys.readouterr().out
    # The first run: hyst's mode and numpy's averaged-spectrum peak agree within a quarter
    # of the mode's half-power bandwidth 2ζf (a lightly damped mode's spectral peak lies a
    # small fraction of that bandwidth from its natural frequency; the peak is read to one
    # 0.18 Hz bin).
    f, z, peak = map(float, re.search(
        r"^mode (\S+) Hz, damping ratio (\S+); the averaged spectrum peaks at (\S+) Hz$",
        out, flags=re.M).groups())
    assert abs(f - peak) <= 0.25 * 2 * z * f, (f, z, peak)
    # The mode table: each refined mode within three of its standard errors of the truth
    # file's (an independent computation from the chain's matrices).
    truth = json.loads((data_dir / "oma" / "truth_3dof.json").read_text())
    rows = re.findall(
        r"^\s*(\d+\.\d{4})\s+(\d+\.\d{4})\s+(\d+\.\d{4})\s+(\d+\.\d{4})\s+(\d\.\d{3})$",
        out,
        flags=re.M,
    )
    assert len(rows) == 3, out
    for row, f0, z0 in zip(rows, truth["fn_hz"], truth["zeta"]):
        f, fse, z, zse, mpc = map(float, row)
        assert abs(f - f0) <= 3 * fse, (f, fse, f0)
        assert abs(z - z0) <= 3 * zse, (z, zse, z0)
        assert mpc > 0.99
    assert "3 refined modes" in out
    assert "3-DOF record" in (tmp_path / "report.html").read_text()
    assert "3 mode shapes written" in out
    # The three models' errors on the record they came from, as the guide quotes them.
    nrmse = dict(re.findall(r"^(linear|zener|bouc_wen)\s+NRMSE (\S+)$", out, flags=re.M))
    assert nrmse == {"linear": "0.224", "zener": "0.206", "bouc_wen": "0.363"}, out
