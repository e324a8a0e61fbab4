"""pyOMA2 on the files hyst's multi-setup merge and FDD/EFDD are compared on
(`cargo xtask compare-setups` runs this and prints both side by side).

Arguments: the shared data folder; the folder of synthetic roving setups xtask wrote
(`roving.json` lists each seed's setup files and references). Prints one JSON document:
- `efdd`: per OMA record, pyOMA2's FDD and EFDD at the true frequencies (nxseg 4096, Welch
  with 50 % overlap) and the time of each (run + mpe, median of 5);
- `poser`, `preger`: the steel frame's 15 setups merged by pyOMA2's PoSER and PreGER
  (channel 5 deleted, references 3 and 4, decimated by 4 to 64 Hz, SSI-cov with 100 block
  rows and order 60, modes picked at the data README's frequencies; PreGER's at order 60, where
  "find_min" finds none): Fn, Xi and Phi (rows:
  the references, then each setup's three laser channels), and the time;
- `roving`: per seed of the synthetic roving test, PoSER's Fn, Xi and Phi (rows: the
  references, then each setup's roving channels) from SSI-cov per setup (the block rows and
  order xtask gives, modes picked at the true frequencies), and the time.
"""

import json
import sys
import time
from pathlib import Path

import numpy as np

from pyoma2.algorithms import EFDD, FDD, SSI, SSI_MS
from pyoma2.setup import MultiSetup_PoSER, MultiSetup_PreGER, SingleSetup

README_HZ = [1.2287, 1.4359, 2.1000, 4.0172, 4.7706, 6.6822, 7.6156, 9.6652, 12.1668, 12.5982, 13.863]


def complex_list(a):
    return [[float(np.real(v)), float(np.imag(v))] for v in a]


def shapes(phi):
    """The modes' shapes, one list per mode, from pyOMA2's Phi (channels x modes; a 1-D
    array when it kept one mode)."""
    phi = np.asarray(phi)
    if phi.ndim == 1:
        phi = phi[:, None]
    return [complex_list(phi[:, j]) for j in range(phi.shape[1])]


def efdd_on(path, truth):
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)[:, 1:]
    f = json.loads(Path(truth).read_text())["fn_hz"]
    out = {}
    for name, cls in (("fdd", FDD), ("efdd", EFDD)):
        times = []
        try:
            for _ in range(5):
                setup = SingleSetup(data, fs=20.0)
                alg = cls(name=name, nxseg=4096, method_SD="per", pov=0.5)
                setup.add_algorithms(alg)
                t0 = time.perf_counter()
                setup.run_all()
                alg.mpe(sel_freq=f)
                times.append(time.perf_counter() - t0)
        except Exception as e:  # a tool's failure on a record is a result to report
            out[name] = {"error": f"{type(e).__name__}: {e}"}
            continue
        r = alg.result
        out[name] = {
            "fn": [float(v) for v in r.Fn],
            "xi": None if getattr(r, "Xi", None) is None else [float(v) for v in r.Xi],
            "seconds": float(np.median(times)),
        }
    return out


def steelframe(folder):
    datasets = []
    for k in range(1, 16):
        d = np.load(folder / f"measurement_{k}" / f"measurement_{k}.npy")
        datasets.append(np.delete(d, 5, axis=1))
    refs = [[3, 4]] * 15
    t0 = time.perf_counter()
    singles = []
    for d in datasets:
        s = SingleSetup(d, fs=256.0)
        s.decimate_data(q=4)
        alg = SSI(name="SSIcov", method="cov", br=100, ordmax=60)
        s.add_algorithms(alg)
        s.run_all()
        alg.mpe(sel_freq=README_HZ, order_in="find_min")
        singles.append(s)
    poser = MultiSetup_PoSER(ref_ind=refs, single_setups=singles, names=["SSIcov"])
    r = poser.merge_results()["SSIcov"]
    poser_out = {
        "fn": [float(v) for v in r.Fn], "fn_std": [float(v) for v in r.Fn_std],
        "xi": [float(v) for v in r.Xi],
        "phi": shapes(r.Phi),
        "seconds": time.perf_counter() - t0,
    }
    t0 = time.perf_counter()
    pre = MultiSetup_PreGER(fs=256.0, ref_ind=refs, datasets=datasets)
    pre.decimate_data(q=4)
    alg = SSI_MS(name="SSIcov", method="cov", br=100, ordmax=60)
    pre.add_algorithms(alg)
    pre.run_all()
    # "find_min" finds no stable order for these modes: the poles at the largest order.
    alg.mpe(sel_freq=README_HZ, order_in=60)
    r = alg.result
    preger_out = {
        "fn": [float(v) for v in r.Fn], "xi": [float(v) for v in r.Xi],
        "phi": shapes(r.Phi),
        "seconds": time.perf_counter() - t0,
    }
    return poser_out, preger_out


def roving(folder):
    manifest = json.loads((folder / "roving.json").read_text())
    out = []
    for test in manifest["seeds"]:
        t0 = time.perf_counter()
        singles = []
        for path in test["files"]:
            d = np.loadtxt(folder / path, delimiter=",", ndmin=2)
            s = SingleSetup(d, fs=manifest["fs"])
            alg = SSI(name="SSIcov", method="cov", br=manifest["block_rows"],
                      ordmax=manifest["max_order"])
            s.add_algorithms(alg)
            s.run_all()
            alg.mpe(sel_freq=manifest["truth_hz"], order_in="find_min")
            singles.append(s)
        poser = MultiSetup_PoSER(ref_ind=test["references"], single_setups=singles,
                                 names=["SSIcov"])
        r = poser.merge_results()["SSIcov"]
        out.append({
            "seed": test["seed"],
            "fn": [float(v) for v in r.Fn], "xi": [float(v) for v in r.Xi],
            "phi": shapes(r.Phi),
            "seconds": time.perf_counter() - t0,
        })
    return out


def main():
    data = Path(sys.argv[1])
    efdd = {name: efdd_on(data / "oma" / f"data_{name}.csv", data / "oma" / f"truth_{name}.json")
            for name in ("sdof", "3dof")}
    poser, preger = steelframe(data / "steelframe")
    rov = roving(Path(sys.argv[2]))
    print(json.dumps({"efdd": efdd, "poser": poser, "preger": preger, "roving": rov}))


if __name__ == "__main__":
    main()
