"""pyOMA2's SSI-cov identification of one CSV record, for `cargo xtask bench command`.

Reads the record (not timed), then runs pyOMA2's cov_R SSI with the settings `hyst ssi` uses by
default (20 block rows, orders up to 40) and prints the median wall time of three runs in
seconds. Usage: ssi_timing.py RECORD.csv [FS]
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
    from pyoma2.algorithms import SSI

    times = []
    for _ in range(3):
        t0 = time.perf_counter()
        alg = SSI(name="t", method="cov_R", br=20, ordmax=40,
                  hc={"xi_max": 0.2, "mpc_lim": None, "mpd_lim": None, "CoV_max": None})
        alg._set_data(y, fs)
        alg.run()
        times.append(time.perf_counter() - t0)
    print(f"{float(np.median(times)):.4f}")


if __name__ == "__main__":
    main()
