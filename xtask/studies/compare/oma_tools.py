"""covssi against pyOMA2 and koma on the OMA records, with the same settings and statistic.

Run by `cargo xtask compare-tools` (which makes a virtual environment with the pinned tools
under target/ and passes the paths); not part of `cargo test`: it needs Python packages.

What it does, for each tool (pyOMA2 1.4.3 `cov_R`, koma-python 1.3.6 `covssi`, and covssi
through the `hyst ssi` command):
  1. the records in ../shared/data/oma (the files the README's table was made from);
  2. `--seeds` fresh records of the same two systems (3-DOF chain, SDOF), made here by exact
     zero-order-hold discretisation, white force at every DOF, 5 % white measurement noise;
     and of the 3-DOF chain seen by ten sensors (`ten_sensors`; no shared record), where
     covssi fits the joint likelihood through four combinations of the channels, and of a
     5-DOF chain seen by ten sensors (`chain_5dof`, `sensors`), where with five modes it fits
     them band by band;
  3. `--timing`: the identification step at N = 1e6 (one BLAS thread) for the same four cases
     as `cargo xtask bench covssi`;
  4. `--clusters`: covssi alone over the same seeds: three ways to take a mode's value from its
     member poles, and the spurious clusters. Pass `--hyst` of another build (e.g. an older
     commit's) to compare clusterings;
  5. `--crb`: the Cramer-Rao bound of the frequencies and damping ratios on records of these
     systems (the smallest standard deviation any unbiased estimator can have), computed
     here from the exact spectral matrix, independently of covssi; and on the records of
     covssi's unit tests of the joint likelihood (3 and 10 channels, 10 with five modes),
     whose RMS errors those tests hold against it.
Settings as the README: max order 40, dF 1 %, dzeta 5 %, MAC 0.97; 20 block rows for three
channels, 60 for one. The statistic as the README: the median frequency and the median damping
of the poles each tool flags stable within +-5 % of the true frequency. Errors in % of the truth.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time
import logging
import warnings

import numpy as np
from scipy import linalg

warnings.filterwarnings("ignore")
logging.disable(logging.INFO)  # pyOMA2 logs every step
os.environ.setdefault("TQDM_DISABLE", "1")  # and draws progress bars

FS = 20.0
N = 65536
MAX_ORDER = 40
DF, DZ, DMAC = 0.01, 0.05, 0.03


# ---------------------------------------------------------------------------- systems
class Steps:
    """The run's steps, told to `cargo xtask compare-tools` as `@progress DONE TOTAL WHAT`
    lines on stderr, which it shows as a progress bar."""

    def __init__(self, total):
        self.done, self.total = 0, total

    def start(self, what):
        print(f"@progress {self.done} {self.total} {what}", file=sys.stderr, flush=True)
        self.done += 1


STEPS = Steps(0)


def chain_3dof():
    k = 200.0
    K = k * np.array([[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]])
    w2, phi = linalg.eigh(K)  # M = I: mass-normalised shapes
    w = np.sqrt(w2)
    zeta = np.array([0.01, 0.02, 0.05])
    C = phi @ np.diag(2.0 * zeta * w) @ phi.T
    return np.eye(3), C, K


def sdof():
    w = 2.0 * math.pi * 1.5
    return np.eye(1), np.array([[2.0 * 0.02 * w]]), np.array([[w * w]])


def chain_5dof():
    """A fixed-free 5-mass chain, m = 1, k = 200 each, modal damping 1 to 5 %: five modes
    between 0.6 and 4.4 Hz."""
    k = 200.0
    K = k * (2.0 * np.eye(5) - np.eye(5, k=1) - np.eye(5, k=-1))
    K[4, 4] = k
    w2, phi = linalg.eigh(K)
    w = np.sqrt(w2)
    zeta = np.array([0.01, 0.02, 0.03, 0.04, 0.05])
    C = phi @ np.diag(2.0 * zeta * w) @ phi.T
    return np.eye(5), C, K


def sensors(d, count=10):
    """`count` displacement sensors on a chain of d masses, evenly spaced from its fixed base
    (0) to the top mass (d), each reading the linear interpolation between its neighbouring
    masses."""
    W = np.zeros((count, d))
    for s in range(count):
        x = d * (s + 1) / count
        i = min(int(x), d - 1)  # between mass i (0: the base) and mass i + 1
        t = x - i
        if i > 0:
            W[s, i - 1] = 1 - t
        W[s, i] = t
    return W


def ten_sensors():
    """Ten sensors on the 3-DOF chain."""
    return sensors(3)


def truth(M, C, K):
    """Natural frequencies |lambda|/2pi and damping -Re(lambda)/|lambda| of the continuous model."""
    n = M.shape[0]
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-K, -C]])
    lam = linalg.eigvals(A)
    lam = sorted((l for l in lam if l.imag > 0), key=abs)
    return [(abs(l) / (2 * math.pi), -l.real / abs(l)) for l in lam]


def discrete(M, C, K, fs=FS):
    """Ad, Bd of the exact zero-order-hold discretisation of M q'' + C q' + K q = f, state
    (q, q')."""
    d = M.shape[0]
    Minv = linalg.inv(M)
    A = np.block([[np.zeros((d, d)), np.eye(d)], [-Minv @ K, -Minv @ C]])
    B = np.vstack([np.zeros((d, d)), Minv])
    big = linalg.expm(np.block([[A, B], [np.zeros((d, 2 * d + d))]]) / fs)
    return big[: 2 * d, : 2 * d], big[: 2 * d, 2 * d :]


def simulate(M, C, K, seed, n=N, fs=FS, noise=0.05):
    """Displacements of M q'' + C q' + K q = f, f white and held over each step (exact ZOH)."""
    d = M.shape[0]
    Ad, Bd = discrete(M, C, K, fs)
    rng = np.random.default_rng(seed)
    f = rng.standard_normal((n + 2000, d))
    x = np.zeros(2 * d)
    y = np.empty((n + 2000, d))
    for t in range(n + 2000):
        y[t] = x[:d]
        x = Ad @ x + Bd @ f[t]
    y = y[2000:]  # drop the start from rest
    y = y + noise * y.std(axis=0) * rng.standard_normal(y.shape)
    return y


def record(system, chans, seed):
    """A fresh record of a case: the displacements at `chans` (a list of DOFs), each with 5 %
    measurement noise; or, for a sensor matrix, the sensors' readings of the noise-free
    displacements with 5 % noise of their own."""
    M, C, K = system()
    if isinstance(chans, list):
        return simulate(M, C, K, seed=seed)[:, chans]
    y = simulate(M, C, K, seed=seed, noise=0.0) @ chans.T
    rng = np.random.default_rng([seed, 1])
    return y + 0.05 * y.std(axis=0) * rng.standard_normal(y.shape)


# ---------------------------------------------------------------------------- statistic
def median_errors(freqs, damps, f_true, z_true):
    sel = [(f, z) for f, z in zip(freqs, damps) if near(f, f_true)]
    if not sel:
        return (math.nan, math.nan)
    fm = float(np.median([s[0] for s in sel]))
    zm = float(np.median([s[1] for s in sel]))
    return (100.0 * (fm - f_true) / f_true, 100.0 * (zm - z_true) / z_true)


# ---------------------------------------------------------------------------- the tools
def run_pyoma2(y, br):
    from pyoma2.algorithms import SSI as SSIcov

    one = y.shape[1] == 1
    hc = {"xi_max": 0.2, "mpc_lim": 0.5, "mpd_lim": 0.5, "CoV_max": 0.2}
    if one:  # a one-element shape has MPC 1 (or NaN): the defaults reject every pole
        hc = {"xi_max": 0.2, "mpc_lim": None, "mpd_lim": None, "CoV_max": None}
    alg = SSIcov(
        name="cov_R",
        method="cov_R",
        br=br,
        ordmax=MAX_ORDER,
        sc={"err_fn": DF, "err_xi": DZ, "err_phi": DMAC},
        hc=hc,
    )
    alg._set_data(y, FS)
    res = alg.run()
    lab = np.asarray(res.Lab)
    fn = np.asarray(res.Fn_poles)
    xi = np.asarray(res.Xi_poles)
    keep = (lab == 1) & np.isfinite(fn)
    return fn[keep], xi[keep]


def run_koma(y, br):
    from koma import oma

    orders = np.arange(2, MAX_ORDER + 2, 2)
    lam, phi, ords = oma.covssi(y, FS, br, orders, showinfo=False)
    vr = {"freq": [0, np.inf], "damping": [0, np.inf], "mpc": [0, 1]}
    if y.shape[1] == 1:
        vr["mpc"] = [-1.0, 2.0]  # MPC is exactly 1 for one channel: the default range drops it
    # stability level 2 (stable against each of the two previous orders): the setting that
    # reproduces the README's koma column on the shared records
    ls, _, _, _ = oma.find_stable_poles(
        lam, phi, ords, 2, stabcrit={"freq": DF, "damping": DZ, "mac": DMAC}, valid_range=vr
    )
    ls = np.asarray(ls)
    return np.abs(ls) / (2 * math.pi), -ls.real / np.abs(ls)


def run_covssi(hyst, y, br, tmp, extra=()):
    names = [f"y{j + 1}" for j in range(y.shape[1])]
    csv = os.path.join(tmp, "rec.csv")
    np.savetxt(csv, y, delimiter=",", header=",".join(names), comments="", fmt="%.17g")
    out = os.path.join(tmp, "rec.json")
    subprocess.run(
        # The tools analyse the record at its own rate: so does covssi here (its default
        # decimation is read from the record).
        [hyst, "ssi", "--input", csv, "--fs", str(FS), "--decimate", "1", "--block-rows", str(br),
         "--max-order", str(MAX_ORDER), "--df", str(DF), "--dzeta", str(DZ),
         "--dmac", str(DMAC), "--json", out, *extra],
        check=True, stdout=subprocess.DEVNULL,
    )
    doc = json.load(open(out))
    top = "stable_fdm" if y.shape[1] > 1 else "stable_fd"
    poles = [p for o in doc["diagram"]["orders"] for p in o["poles"] if p["label"] == top]
    return (
        np.array([p["frequency_hz"] for p in poles]),
        np.array([p["damping_ratio"] for p in poles]),
        doc,
    )


def near(f, f_true):
    """Within +-5 % of the true frequency: the README's window."""
    return abs(f - f_true) <= 0.05 * f_true


def reported_mode(modes, f_true):
    """covssi's own report for a true mode: the mode (cluster) with most members within the
    window, or None."""
    candidates = [m for m in modes if near(m["frequency_hz"], f_true)]
    return max(candidates, key=lambda m: len(m["members"])) if candidates else None


def refined_mode(doc, f_true):
    """covssi's maximum-likelihood report for a true mode: the refined mode within the window
    with the most evidence (the nearer on a tie), or None."""
    refined = (doc.get("refined") or {}).get("modes", [])
    candidates = [m for m in refined if near(m["frequency_hz"], f_true)]
    if not candidates:
        return None
    return max(candidates, key=lambda m: (m["evidence"], -abs(m["frequency_hz"] - f_true)))


def percent_errors(m, f_true, z_true):
    """Errors of a reported mode (a dict with frequency_hz and damping_ratio, or None) in % of
    the truth."""
    if m is None:
        return (math.nan, math.nan)
    return (100.0 * (m["frequency_hz"] - f_true) / f_true,
            100.0 * (m["damping_ratio"] - z_true) / z_true)


def refined_errors(doc, f_true, z_true):
    return percent_errors(refined_mode(doc, f_true), f_true, z_true)


def refined_z_scores(doc, f_true, z_true):
    """(estimate - truth) / standard error, for frequency and damping: ~N(0, 1) if the
    standard errors are right."""
    m = refined_mode(doc, f_true)
    if m is None or m["frequency_se_hz"] is None or m["damping_se"] is None:
        return (math.nan, math.nan)
    return ((m["frequency_hz"] - f_true) / m["frequency_se_hz"],
            (m["damping_ratio"] - z_true) / m["damping_se"])


def mode_errors(modes, f_true, z_true):
    return percent_errors(reported_mode(modes, f_true), f_true, z_true)


CASES = [
    # name, system, channels, block rows, file, columns
    ("3 channels", chain_3dof, [0, 1, 2], 20, "data_3dof.csv", ["y1", "y2", "y3"]),
    ("channel y1", chain_3dof, [0], 60, "data_3dof.csv", ["y1"]),
    ("SDOF", sdof, [0], 60, "data_sdof.csv", ["y"]),
    ("10 sensors", chain_3dof, ten_sensors(), 20, None, None),
    ("10 sensors on 5-DOF", chain_5dof, sensors(5), 20, None, None),
]
TOOLS = ["pyOMA2", "koma", "covssi", "covssi mode", "covssi ML", "covssi ML per channel"]


def run_all(hyst, y, br, tr, tmp):
    out = {}
    f, z = run_pyoma2(y, br)
    out["pyOMA2"] = [median_errors(f, z, *t) for t in tr]
    f, z = run_koma(y, br)
    out["koma"] = [median_errors(f, z, *t) for t in tr]
    f, z, doc = run_covssi(hyst, y, br, tmp)
    out["covssi"] = [median_errors(f, z, *t) for t in tr]
    out["covssi mode"] = [mode_errors(doc["ssi_modes"], *t) for t in tr]
    out["covssi ML"] = [refined_errors(doc, *t) for t in tr]
    # The per-channel likelihood alone (for one channel it is the same likelihood).
    if y.shape[1] > 1:
        _, _, per = run_covssi(hyst, y, br, tmp, ["--no-joint"])
        out["covssi ML per channel"] = [refined_errors(per, *t) for t in tr]
    else:
        out["covssi ML per channel"] = out["covssi ML"]
    out["z"] = [refined_z_scores(doc, *t) for t in tr]
    return out


def read_csv_columns(path, cols):
    with open(path) as fh:
        header = fh.readline().strip().split(",")
    data = np.loadtxt(path, delimiter=",", skiprows=1)
    return data[:, [header.index(c) for c in cols]]


def check_truth(data_dir):
    """The systems made here are the README's: their poles match its truth files."""
    for system, fname in ((chain_3dof, "truth_3dof.json"), (sdof, "truth_sdof.json")):
        ref = json.load(open(os.path.join(data_dir, fname)))
        for (f, z), fr, zr in zip(truth(*system()), ref["fn_hz"], ref["zeta"]):
            if abs(f - fr) > 1e-9 * fr or abs(z - zr) > 1e-9 * zr:
                raise SystemExit(f"{fname}: system made here has {f} Hz / {z}, file {fr} / {zr}")


def files(hyst, data_dir, tmp):
    check_truth(data_dir)
    print("## The shared records (errors in %, frequency / damping)\n")
    print("| case | mode | " + " | ".join(TOOLS) + " |")
    print("|---|---|" + "---|" * len(TOOLS))
    for name, system, _, br, fname, cols in CASES:
        if fname is None:  # no shared record of this case
            continue
        y = read_csv_columns(os.path.join(data_dir, fname), cols)
        tr = truth(*system())
        res = run_all(hyst, y, br, tr, tmp)
        for j in range(len(tr)):
            cells = [f"{res[t][j][0]:+.3f} / {res[t][j][1]:+.2f}" for t in TOOLS]
            print(f"| {name} | {j + 1} | " + " | ".join(cells) + " |")
    print()


def seeds(hyst, count, first, tmp):
    print(f"## {count} fresh records per case (seeds {first}..{first + count - 1})\n")
    print("RMS error over seeds (bias = mean error), frequency % / damping %.\n")
    print("| case | mode | " + " | ".join(TOOLS) + " |")
    print("|---|---|" + "---|" * len(TOOLS))
    wins, ratios, zrows, every = {}, [], [], {}
    for name, system, chans, br, _, _ in CASES:
        M, C, K = system()
        tr = truth(M, C, K)
        errs = {t: [] for t in TOOLS + ["z"]}
        for s in range(first, first + count):
            STEPS.start(f"{name}, seed {s}: the three tools")
            y = record(system, chans, s)
            res = run_all(hyst, y, br, tr, tmp)
            for t in TOOLS + ["z"]:
                errs[t].append(res[t])
            print(f"  {name} seed {s}: " + "; ".join(
                f"{t} " + " ".join(f"{e[0]:+.3f}/{e[1]:+.2f}" for e in res[t]) for t in TOOLS
            ), file=sys.stderr)
        for j in range(len(tr)):
            cells = []
            for t in TOOLS:
                e = np.array([r[j] for r in errs[t]])
                rms = np.sqrt(np.nanmean(e**2, axis=0))
                bias = np.nanmean(e, axis=0)
                missing = int(np.isnan(e[:, 0]).sum())
                miss = f", {missing} missed" if missing else ""
                cells.append(
                    f"{rms[0]:.3f} ({bias[0]:+.3f}) / {rms[1]:.2f} ({bias[1]:+.2f}){miss}"
                )
            print(f"| {name} | {j + 1} | " + " | ".join(cells) + " |")
            # how often covssi's error (README statistic; maximum likelihood) is no larger
            # than both tools' errors
            for k, what in ((0, "f"), (1, "zeta")):
                p = np.array([abs(r[j][k]) for r in errs["pyOMA2"]])
                q = np.array([abs(r[j][k]) for r in errs["koma"]])
                for t in ("covssi", "covssi ML"):
                    c = np.array([abs(r[j][k]) for r in errs[t]])
                    wins[(name, j + 1, what, t)] = int(np.sum((c <= p) & (c <= q)))
            ratios.append((name, j + 1, rms_ratios(errs, j)))
            z = np.array([r[j] for r in errs["z"]])
            zrows.append((name, j + 1, np.sqrt(np.nanmean(z**2, axis=0)), int(np.sum(~np.isnan(z[:, 0])))))
        # records on which covssi ML is at most both tools' on every entry of the case (every
        # mode's frequency and damping): what a comparison on one record asks
        a = {t: np.abs(np.array(errs[t], dtype=float)) for t in ("pyOMA2", "koma", "covssi ML")}
        ml = a["covssi ML"]
        every[name] = (2 * len(tr),
                       int(np.sum(np.all((ml <= a["pyOMA2"]) & (ml <= a["koma"]), axis=(1, 2)))))
    print()
    print("Seeds on which covssi's error is at most both tools' (README statistic | maximum "
          "likelihood):\n")
    print("| case | mode | frequency | damping |")
    print("|---|---|---|---|")
    for name, _, _, _, _, _ in CASES:
        j = 1
        while (name, j, "f", "covssi") in wins:
            cells = [" / ".join(f"{wins[(name, j, w, t)]}" for t in ("covssi", "covssi ML"))
                     for w in ("f", "zeta")]
            print(f"| {name} | {j} | {cells[0]} of {count} | {cells[1]} of {count} |")
            j += 1
    print()
    print("Seeds on which covssi ML's error is at most both tools' on every entry of the case "
          "(each mode's frequency and damping), as a comparison on one record asks:\n")
    print("| case | entries | records |")
    print("|---|---|---|")
    for name, (entries, records) in every.items():
        print(f"| {name} | {entries} | {records} of {count} |")
    print()
    print("RMS error of covssi ML over each tool's, frequency / damping, with a 95 % interval "
          "from resampling the seeds (paired: the same records); below 1 = covssi ML closer:\n")
    print("| case | mode | over pyOMA2 | over koma | over covssi ML per channel |")
    print("|---|---|---|---|---|")
    for name, j, r in ratios:
        cells = [" / ".join(f"{m:.2f} [{lo:.2f}, {hi:.2f}]" for m, lo, hi in r[t])
                 for t in ("pyOMA2", "koma", "covssi ML per channel")]
        print(f"| {name} | {j} | {cells[0]} | {cells[1]} | {cells[2]} |")
    print()
    print("Calibration of covssi ML's standard errors: RMS of (estimate - truth) / standard "
          "error, frequency / damping (1 if they are right):\n")
    print("| case | mode | frequency | damping | records |")
    print("|---|---|---|---|---|")
    for name, j, zr, nrec in zrows:
        print(f"| {name} | {j} | {zr[0]:.2f} | {zr[1]:.2f} | {nrec} |")
    print()


def rms_ratios(errs, j, draws=2000):
    """RMS(covssi ML) / RMS(tool) for frequency and damping, with a 95 % paired bootstrap
    interval over the seeds."""
    rng = np.random.default_rng(0)
    ml = np.array([r[j] for r in errs["covssi ML"]])
    out = {}
    for t in ("pyOMA2", "koma", "covssi ML per channel"):
        e = np.array([r[j] for r in errs[t]])
        ok = ~np.isnan(ml[:, 0]) & ~np.isnan(e[:, 0])
        a, b = ml[ok], e[ok]
        cells = []
        for k in (0, 1):
            ratio = np.sqrt(np.mean(a[:, k] ** 2) / np.mean(b[:, k] ** 2))
            idx = rng.integers(0, len(a), size=(draws, len(a)))
            boot = np.sqrt(np.mean(a[idx, k] ** 2, axis=1) / np.mean(b[idx, k] ** 2, axis=1))
            cells.append((ratio, *np.percentile(boot, [2.5, 97.5])))
        out[t] = cells
    return out


UNPHYSICAL = ("rejected_nyquist", "rejected_unstable", "rejected_damping_limit")


def cluster_statistics(doc, tr, nchan):
    """covssi's modes from one document: errors of three mode values (mean of the members, what
    covssi reports; median of the members; mean of the members whose matched pole at the previous
    order was fully stable too, koma's stability level 2), and the clusters far from every true
    mode (spurious) with their member counts and first orders."""
    top = "stable_fdm" if nchan > 1 else "stable_fd"
    by_order = {o["order"]: o["poles"] for o in doc["diagram"]["orders"]}

    def previous_stable(order, p):
        for back in (1, 2):  # as covssi: a real pole may sit at every other order only
            q = [x for x in by_order.get(order - back, [])
                 if not x["real"] and x["label"] not in UNPHYSICAL]
            if q:
                return min(q, key=lambda x: abs(x["frequency_hz"] - p["frequency_hz"]))["label"] == top
        return False

    values = {"mean": [], "median": [], "level 2": []}
    for f_true, z_true in tr:
        m = reported_mode(doc["ssi_modes"], f_true)
        if m is None:
            for v in values.values():
                v.append((math.nan, math.nan))
            continue
        members = [(o, by_order[o][i]) for o, i in m["members"]]
        level2 = [p for o, p in members if previous_stable(o, p)]

        def err(ps, stat):
            if not ps:
                return (math.nan, math.nan)
            f = stat([p["frequency_hz"] for p in ps])
            z = stat([p["damping_ratio"] for p in ps])
            return (100.0 * (f - f_true) / f_true, 100.0 * (z - z_true) / z_true)

        values["mean"].append(err([p for _, p in members], np.mean))
        values["median"].append(err([p for _, p in members], np.median))
        values["level 2"].append(err(level2, np.mean))
    spurious, physical = [], []
    for m in doc["ssi_modes"]:
        physical_mode = any(near(m["frequency_hz"], f) for f, _ in tr)
        (physical if physical_mode else spurious).append((len(m["members"]), m["members"][0][0]))
    return values, spurious, physical


def fit_kind(r):
    """Which likelihood the refinement `r` reported: each channel's, the channels' jointly, or
    the joint likelihood of combinations of them (in bands)."""
    if not r.get("joint"):
        return "per channel"
    c, b = r.get("combinations"), r.get("bands", 1)
    if c is None:
        return "joint"
    return f"{c} combinations" + (f" in {b} bands" if b > 1 else "")


def refined_census(doc, tr):
    """(extra refined modes: far from every true mode or a second one near a true mode, true
    modes with no refined mode near, 1 if the misfit warning is raised, the fit's kind), or
    None without a refinement."""
    r = doc.get("refined")
    if r is None:
        return None
    ms = r["modes"]
    far = sum(1 for m in ms if not any(near(m["frequency_hz"], f) for f, _ in tr))
    dup = sum(max(0, sum(near(m["frequency_hz"], f) for m in ms) - 1) for f, _ in tr)
    missed = sum(1 for f, _ in tr if not any(near(m["frequency_hz"], f) for m in ms))
    return (far + dup, missed, int(r["misfit"] > r["misfit_limit"]), fit_kind(r))


def clusters(hyst, count, first, tmp):
    print(f"## covssi's modes over {count} fresh records (seeds {first}..{first + count - 1})\n")
    print("RMS error of three mode values, frequency % / damping %: the mean of a mode's "
          "members (what covssi reports), their median, and the mean of the members stable at "
          "level 2.\n")
    print("| case | mode | mean | median | level 2 |")
    print("|---|---|---|---|---|")
    spur_rows = []
    refined_counts = {name: [] for name, *_ in CASES}
    for name, system, chans, br, _, _ in CASES:
        M, C, K = system()
        tr = truth(M, C, K)
        acc = {k: [[] for _ in tr] for k in ("mean", "median", "level 2")}
        spur, phys = [], []
        for s in range(first, first + count):
            STEPS.start(f"{name}, seed {s}: covssi's clusters")
            y = record(system, chans, s)
            doc = run_covssi(hyst, y, br, tmp)[2]
            refined_counts[name].append(refined_census(doc, tr))
            values, sp, ph = cluster_statistics(doc, tr, y.shape[1])
            for k, v in values.items():
                for j, e in enumerate(v):
                    acc[k][j].append(e)
            spur += sp
            phys += ph
        for j in range(len(tr)):
            cells = []
            for k in ("mean", "median", "level 2"):
                r = np.sqrt(np.nanmean(np.array(acc[k][j]) ** 2, axis=0))
                cells.append(f"{r[0]:.3f} / {r[1]:.2f}")
            print(f"| {name} | {j + 1} | " + " | ".join(cells) + " |")
        pm = np.array([p[0] for p in phys])
        row = f"| {name} | {len(spur)} | "
        if spur:
            sm = np.array([p[0] for p in spur])
            sf = np.array([p[1] for p in spur])
            row += f"{sm.max()} | {int(np.min(sf))}–{int(np.max(sf))} (median {np.median(sf):g}) | "
        else:
            row += "– | – | "
        row += f"{np.percentile(pm, 5):.1f} |"
        spur_rows.append(row)
    print("\nClusters far (> 5 %) from every true mode, over all records:\n")
    print("| case | spurious clusters | their most members | their first orders | "
          "5 % quantile of the physical modes' members |")
    print("|---|---|---|---|---|")
    for r in spur_rows:
        print(r)
    print()
    print("The maximum-likelihood refinement's modes over the same records (absent from the "
          "table when the hyst given has no refinement):\n")
    print("| case | records | with an extra refined mode | true modes missed | misfit warnings "
          "| fitted by (records) |")
    print("|---|---|---|---|---|---|")
    for name, rows in refined_counts.items():
        rows = [r for r in rows if r is not None]
        if rows:
            kinds = {}
            for r in rows:
                kinds[r[3]] = kinds.get(r[3], 0) + 1
            fitted = ", ".join(f"{k} ({n})" for k, n in sorted(kinds.items()))
            print(f"| {name} | {len(rows)} | {sum(r[0] > 0 for r in rows)} | "
                  f"{sum(r[1] for r in rows)} | {sum(r[2] for r in rows)} | {fitted} |")
    print()


def timing(hyst_unused, repeats=7):
    """Identification step at N = 1e6 for the bench's four cases: median of `repeats` runs."""
    from koma import oma
    from pyoma2.algorithms import SSI as SSIcov

    rng = np.random.default_rng(7)
    n = 1_000_000
    M, C, K = chain_3dof()
    base = simulate(M, C, K, seed=7, n=n)
    # ten channels: mixtures of the three displacements plus noise (as the bench's record)
    mix = rng.standard_normal((3, 10))
    y10 = base @ mix + 0.05 * rng.standard_normal((n, 10))
    print("## Identification step at N = 1e6 on this machine (one BLAS thread), median of "
          f"{repeats} runs, ms\n")
    print("| case | pyOMA2 cov_R | koma |")
    print("|---|---|---|")
    for name, ch, br, order in [("1 channel", 1, 20, 40), ("3 channels", 3, 20, 40),
                                ("10 channels", 10, 20, 40), ("10 channels, 50 block rows", 10, 50, 100)]:
        y = y10[:, :ch].copy()
        # the rank bounds the order: pyOMA2 needs it below l·(br − 1), the rows of its shifted
        # observability matrix (the bench gives covssi up to l·br)
        order = min(order, ch * (br - 1))
        row = []
        for tool in ("pyoma2", "koma"):
            ts = []
            for _ in range(repeats if tool == "pyoma2" or ch < 10 else 3):
                t0 = time.perf_counter()
                if tool == "pyoma2":
                    alg = SSIcov(name="t", method="cov_R", br=br, ordmax=order,
                                 hc={"xi_max": 0.2, "mpc_lim": None, "mpd_lim": None, "CoV_max": None})
                    alg._set_data(y, FS)
                    alg.run()
                else:
                    oma.covssi(y, FS, br, np.arange(2, order + 2, 2), showinfo=False)
                ts.append(time.perf_counter() - t0)
            row.append(f"{1e3 * float(np.median(ts)):.0f}")
        print(f"| {name} | " + " | ".join(row) + " |")
    print()


# ---------------------------------------------------------------------------- Cramer-Rao bound
def physical(system, chans):
    """Ad, Bd and the output matrix of a physical system's displacements at `chans`."""
    M, C, K = system()
    Ad, Bd = discrete(M, C, K)
    d = M.shape[0]
    if isinstance(chans, list):
        return Ad, Bd, np.eye(2 * d)[:d][chans]
    return Ad, Bd, chans @ np.eye(2 * d)[:d]


def modal(modes, gains):
    """Ad, Bd and the output matrix of covssi's unit-test records (`refine::tests::record`):
    one 2-state block per mode (f Hz, zeta) with the exact discrete pole, x_{t+1} = M x_t + w,
    w white with unit covariance, channel c seeing sum_r gains[c][r] x_r[0]."""
    m = len(modes)
    Ad = np.zeros((2 * m, 2 * m))
    for r, (f, zeta) in enumerate(modes):
        w = 2 * math.pi * f
        mu = np.exp((-zeta * w + 1j * w * math.sqrt(1 - zeta * zeta)) / FS)
        Ad[2 * r : 2 * r + 2, 2 * r : 2 * r + 2] = [[mu.real, -mu.imag], [mu.imag, mu.real]]
    Cy = np.zeros((len(gains), 2 * m))
    for c, g in enumerate(gains):
        Cy[c, 0::2] = g
    return Ad, np.eye(2 * m), Cy


def chain_gains(l, m, weak):
    """`refine::joint::tests::chain_gains`: a fixed-free chain's shapes at l points, mode 2
    scaled to `weak`."""
    return [[(weak if r == 1 else 1.0) * math.sin((2 * r + 1) * math.pi / 2 * (c + 1) / (l + 0.5))
             for r in range(m)] for c in range(l)]


def covariance_model(Ad, Bd, Cy, noise=0.05):
    """The records' exact second-order model in covariance form: the output covariances
    R_j = sum_r (c_r g_r^T mu_r^(j-1) + conj) for j >= 1, and R_0 with the measurement noise.
    Returns the modes (f Hz, zeta, c_r, g_r) by frequency, and R_0."""
    Sx = linalg.solve_discrete_lyapunov(Ad, Bd @ Bd.T)
    G = Ad @ Sx @ Cy.T
    R0 = Cy @ Sx @ Cy.T
    R0 = R0 + np.diag(noise**2 * np.diag(R0))
    mu, V = linalg.eig(Ad)
    Vi = linalg.inv(V)
    modes = []
    for i in sorted((i for i in range(len(mu)) if mu[i].imag > 0), key=lambda i: abs(np.log(mu[i]))):
        lam = np.log(mu[i]) * FS
        modes.append((abs(lam) / (2 * math.pi), -lam.real / abs(lam), Cy @ V[:, i], Vi[i, :] @ G))
    return modes, R0


def spectral_matrix(p, l, m, om):
    """S(omega) = R_0 + P(z) + P(z)^H, P(z) = sum_r c_r g_r^T / (z - mu_r) + conj, z = e^(i omega),
    from the parameter vector p = per mode (f, zeta, Re c, Im c, Re g, Im g), then R_0's upper
    triangle."""
    z = np.exp(1j * om)
    S = np.zeros((len(om), l, l), complex)
    k = 0
    for _ in range(m):
        f, zeta = p[k], p[k + 1]
        w = 2 * math.pi * f
        mu = np.exp((-zeta * w + 1j * w * math.sqrt(1 - zeta * zeta)) / FS)
        c = p[k + 2 : k + 2 + l] + 1j * p[k + 2 + l : k + 2 + 2 * l]
        g = p[k + 2 + 2 * l : k + 2 + 3 * l] + 1j * p[k + 2 + 3 * l : k + 2 + 4 * l]
        k += 2 + 4 * l
        R = np.outer(c, g)
        P = R[None] / (z - mu)[:, None, None] + np.conj(R)[None] / (z - np.conj(mu))[:, None, None]
        S += P + np.conj(np.transpose(P, (0, 2, 1)))
    iu = np.triu_indices(l)
    R0 = np.zeros((l, l))
    R0[iu] = p[k:]
    R0 = R0 + np.triu(R0, 1).T
    return S + R0[None]


def cramer_rao(Ad, Bd, Cy, n=N, grid=8192):
    """Standard deviation bound (in % of the truth) of each mode's frequency and damping ratio
    from n samples: the inverse of the Whittle Fisher information
    F_ij = sum_k tr(S^-1 dS_i S^-1 dS_j) over the n/2 frequencies in (0, pi), the derivatives
    by central differences. Each residue c_r g_r^T is unchanged by (c_r alpha, g_r / alpha), so
    g_r is normalised to 1 at its largest component and that component is held: F is then
    regular, and it is inverted after scaling to a unit diagonal. (A pseudo-inverse of the
    redundant F, used before, needs a cut-off between the redundant directions and the weakly
    informed ones; with ten sensors on three modes no cut-off separates them.)"""
    modes, R0 = covariance_model(Ad, Bd, Cy)
    l, m = Cy.shape[0], len(modes)
    p, held = [], []
    for f, zeta, c, g in modes:
        ref = int(np.argmax(np.abs(g)))
        c, g = c * g[ref], g / g[ref]
        base = len(p)
        held += [base + 2 + 2 * l + ref, base + 2 + 3 * l + ref]
        p += [f, zeta, *c.real, *c.imag, *g.real, *g.imag]
    p = np.array(p + list(R0[np.triu_indices(l)]))
    free = [i for i in range(len(p)) if i not in held]
    om = (np.arange(grid) + 0.5) * math.pi / grid
    Si = np.linalg.inv(spectral_matrix(p, l, m, om))
    D = []
    for i in free:
        h = 1e-6 * max(abs(p[i]), 1e-3)
        a, b = p.copy(), p.copy()
        a[i] += h
        b[i] -= h
        D.append(Si @ ((spectral_matrix(a, l, m, om) - spectral_matrix(b, l, m, om)) / (2 * h)))
    F = np.array([[np.einsum("kab,kba->k", Di, Dj).real.mean() * n / 2 for Dj in D] for Di in D])
    d = 1 / np.sqrt(np.diag(F))
    cov = np.linalg.inv(F * d[:, None] * d[None, :]) * d[:, None] * d[None, :]
    out, k = [], 0
    for f, zeta, _, _ in modes:
        i, j = free.index(k), free.index(k + 1)
        out.append((100 * math.sqrt(cov[i, i]) / f, 100 * math.sqrt(cov[j, j]) / zeta))
        k += 2 + 4 * l
    return out


def crb_table():
    print(f"## Cramer-Rao bound at N = {N} (standard deviation, % of the truth, frequency / damping)\n")
    print("| case | mode | bound |")
    print("|---|---|---|")
    for name, system, chans, _, _, _ in CASES:
        for j, (bf, bz) in enumerate(cramer_rao(*physical(system, chans))):
            print(f"| {name} | {j + 1} | {bf:.3f} / {bz:.2f} |")
    print()
    # covssi's unit tests of the joint likelihood (records of 16384 samples; the tests print
    # the RMS errors to hold against these).
    two = [(1.5, 0.02), (3.0, 0.05)]
    three = [(1.5, 0.02), (3.0, 0.05), (5.0, 0.03)]
    five = three + [(6.5, 0.02), (8.0, 0.03)]
    tests = [
        ("3 channels, weak mode 2 (the_channels_together_see_a_weak_mode_better)", two,
         [[1.0, 0.15], [0.6, -0.15], [-0.4, 0.15]]),
        ("10 channels, weak mode 2 (many_channels_are_fitted_jointly_through_combinations)",
         three, chain_gains(10, 3, 0.15)),
        ("10 channels, 5 modes, weak mode 2 (more_modes_than_combinations_are_fitted_by_bands)",
         five, chain_gains(10, 5, 0.15)),
    ]
    print("## Cramer-Rao bound of covssi's unit-test records, N = 16384\n")
    print("| case | mode | bound |")
    print("|---|---|---|")
    for name, modes, gains in tests:
        for j, (bf, bz) in enumerate(cramer_rao(*modal(modes, gains), n=16384)):
            print(f"| {name} | {j + 1} | {bf:.3f} / {bz:.2f} |")
    print()


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hyst", required=True, help="path to the hyst binary (release)")
    ap.add_argument("--data", required=True, help="the shared oma/ folder")
    ap.add_argument("--seeds", type=int, default=60)
    ap.add_argument("--first-seed", type=int, default=201)
    ap.add_argument("--timing", action="store_true")
    ap.add_argument("--clusters", action="store_true",
                    help="also: covssi's mode values and spurious clusters over the same seeds")
    ap.add_argument("--covssi-only", action="store_true",
                    help="skip the tools (the shared records and the seed tables): with "
                         "--clusters, covssi alone")
    ap.add_argument("--crb", action="store_true",
                    help="print the Cramer-Rao bound of the estimates and stop")
    ap.add_argument("--cases", default=None,
                    help="comma-separated case names to run (default: all), e.g. '10 sensors'")
    a = ap.parse_args()
    if a.cases is not None:
        wanted = [c.strip() for c in a.cases.split(",")]
        unknown = [w for w in wanted if w not in [c[0] for c in CASES]]
        if unknown:
            raise SystemExit(f"unknown case(s) {unknown}; cases: {[c[0] for c in CASES]}")
        CASES[:] = [c for c in CASES if c[0] in wanted]
    if a.crb:
        crb_table()
        return
    import koma  # noqa: F401  (fail early if the tools are missing)
    import pyoma2  # noqa: F401

    from importlib.metadata import version

    print(f"pyOMA-2 {version('pyOMA-2')}, koma-python {version('koma-python')}, "
          f"numpy {np.__version__}\n")
    phases = (a.seeds > 0 and not a.covssi_only) + a.clusters
    STEPS.total = phases * a.seeds * len(CASES)
    with tempfile.TemporaryDirectory() as tmp:
        if not a.covssi_only:
            files(a.hyst, a.data, tmp)
            if a.seeds > 0:
                seeds(a.hyst, a.seeds, a.first_seed, tmp)
        if a.clusters:
            clusters(a.hyst, a.seeds, a.first_seed, tmp)
    if a.timing:
        timing(a.hyst)


if __name__ == "__main__":
    main()
