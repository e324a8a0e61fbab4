"""pyOMA2's and koma's SSI-cov identification of one CSV record, for `cargo xtask bench command`.

Reads the record (not timed), then runs pyOMA2's cov_R SSI and koma's covssi with the settings
`cargo xtask bench command` gives `hyst ssi` (20 block rows, orders up to 40, no decimation;
its defaults read a longer lag from this record) and prints the median wall time of
three runs of each in seconds, one line per tool: `pyoma2 S` and `koma S`; then pandas' C
reader's median time to read the CSV (`pandas_read_csv S`), the peer of hyst's reader. With
NPY, the record is also saved there as a NumPy array (hyst's other input).
Usage: ssi_timing.py RECORD.csv [FS] [NPY]
"""
import sys
import time
import logging
import warnings

import numpy as np

logging.disable(logging.CRITICAL)
warnings.filterwarnings("ignore")


def main():
    path = sys.argv[1]
    fs = float(sys.argv[2]) if len(sys.argv) > 2 else 100.0
    y = np.loadtxt(path, delimiter=",", skiprows=1)
    if len(sys.argv) > 3:
        np.save(sys.argv[3], y)
    from koma import oma
    from pyoma2.algorithms import SSI

    def pyoma2():
        alg = SSI(name="t", method="cov_R", br=20, ordmax=40,
                  hc={"xi_max": 0.2, "mpc_lim": None, "mpd_lim": None, "CoV_max": None})
        alg._set_data(y, fs)
        alg.run()

    def koma():
        oma.covssi(y, fs, 20, np.arange(2, 42, 2), showinfo=False)

    for name, run in (("pyoma2", pyoma2), ("koma", koma)):
        times = []
        for _ in range(3):
            t0 = time.perf_counter()
            run()
            times.append(time.perf_counter() - t0)
        print(f"{name} {float(np.median(times)):.4f}")
    import pandas as pd
    times = []
    for _ in range(3):
        t0 = time.perf_counter()
        pd.read_csv(path, engine="c")
        times.append(time.perf_counter() - t0)
    print(f"pandas_read_csv {float(np.median(times)):.4f}")


if __name__ == "__main__":
    main()
