"""hyst: output-only modal analysis and hysteretic-damping identification, in Rust.

``hyst.ssi(y, fs)`` identifies the modes of a structure from its measured response alone
(operational modal analysis): covariance-driven stochastic subspace identification (SSI-COV)
with a stabilization diagram, then each mode refined by maximum likelihood on the whole record,
with standard errors. The same library runs the command ``hyst ssi``; ``result.to_dict()`` is
the JSON document ``hyst ssi --json`` writes.

``hyst.read(path)`` reads a record as the command line does: CSV, NumPy ``.npy``/``.npz``,
MATLAB ``.mat`` (level 5), Universal File datasets 58 (ASCII or 58b, with their sampling
rate); ``result.write_shapes_uff(path)`` writes the mode shapes as dataset 55.

``hyst.simulate``, ``hyst.identify``, ``hyst.refine`` and ``hyst.levels`` are the commands of
the same names (``hyst simulate``, ``ident``, ``refine``, ``levels``) on arrays: models are
dicts in the JSON schema ``--params`` reads, reports are :class:`Report` objects whose
``to_dict()`` is the command's ``--json`` document.
"""

import os as _os
from dataclasses import dataclass as _dataclass
from typing import List as _List, Optional as _Optional, Tuple as _Tuple

import numpy as _np

from . import _hyst
from ._hyst import Report, SsiResult

__all__ = [
    "amplitude", "excite", "identify", "levels", "read", "Record", "refine", "Report",
    "simulate", "ssi", "SsiResult", "track", "track_estimates",
]


@_dataclass(frozen=True)
class Record:
    """A record read by :func:`hyst.read`.

    Attributes
    ----------
    data : numpy.ndarray, shape (samples, channels)
        The channels, float64, Fortran-ordered (``hyst.ssi`` reads its columns in place).
    names : list of str
        The channels' names: a CSV's header, ``"0", "1", ...`` for arrays and headerless
        text, the point (``"12+Z"``) for a Universal File.
    fs : float or None
        The sampling rate the file states (a Universal File's), else its time column's
        mean step (a column named ``t``, ``time``, ``Time (s)``, ... or increasing by a
        constant step), else None.
    points : list of (int, int) or None
        Each channel's (node, direction) where the file gives them (a Universal File),
        for ``SsiResult.write_shapes_uff``.
    path : str
        The file.
    """

    data: _np.ndarray
    names: _List[str]
    fs: _Optional[float]
    points: _Optional[_List[_Tuple[int, int]]]
    path: str


def read(path, *, format=None, variable=None, delimiter=None):
    """Read a record file as ``hyst ssi --input`` does.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    format : {"csv", "npy", "npz", "mat", "uff"}, optional
        Its format; by default from its extension (``.npy``, ``.npz``, ``.mat``,
        ``.uff``/``.unv``/``.uf``, anything else CSV).
    variable : str, optional
        The variable of a ``.mat`` file or the array of a ``.npz`` archive; needed when the
        file holds more than one array of more than one element.
    delimiter : {",", ";", "\\t"}, optional
        The cell separator of a CSV (default: detected from the header line).

    Returns
    -------
    Record
        ``data`` (samples x channels), ``names`` (a headerless file's ``"0"``, ``"1"``,
        ...), ``fs`` (the rate the file states, else its time column's step, else None),
        ``points``, ``path``. A cell that is not finite is read as NaN or inf (a column
        no one analyses may hold one); ``hyst.ssi`` refuses a channel that holds one.

    Raises
    ------
    ValueError
        With the library's message, naming the file and what is wrong (a truncated file, a
        dataset that is not a time response, channels of different lengths or rates, ...).
    """
    import os

    data, names, fs, points = _hyst.read_record(
        os.fspath(path), format=format, variable=variable, delimiter=delimiter
    )
    return Record(data=data, names=list(names), fs=fs, points=points, path=os.fspath(path))


def ssi(
    y=None,
    fs=None,
    *,
    block_rows=None,
    lag_seconds=None,
    lag_periods=None,
    decimate=None,
    max_order=None,
    order_step=1,
    references=None,
    df=None,
    dzeta=None,
    dmac=None,
    dreal=None,
    refine=True,
    joint=True,
    ssi_errors=None,
    max_damping=None,
    channels=None,
    record="array",
    fdd=False,
    setups=None,
    geometry=None,
    lines=None,
    records_anywhere=False,
):
    """Modes of a structure from its response alone: SSI-COV, then maximum likelihood.

    Parameters
    ----------
    y : array_like, shape (samples, channels) or (samples,)
        The measured response, one column per sensor. Converted to float64; a
        Fortran-ordered float64 array (``np.asfortranarray``) is read in place, any other
        is copied once.
    fs : float
        Sampling rate (Hz).
    block_rows : int, optional
        Block rows of the Toeplitz matrix of correlations: correlations up to lag
        ``2 * block_rows - 1`` are used. Default: read from the record, enough for ten
        periods of its lowest spectral peak within a size budget (the report says how).
    lag_seconds : float, optional
        The same as a time: enough block rows that the largest lag covers this many
        seconds, ceil((lag_seconds * fs + 1) / 2). Not with ``block_rows``.
    lag_periods : (float, float), optional
        The same as (count, Hz): the largest lag covers ``count`` periods of a mode at
        ``Hz``, e.g. ``(10, 1.5)`` (the paper's choice: ten periods of the dominant mode).
        Not with ``block_rows`` or ``lag_seconds``.
    decimate : int, optional
        Decimate by this factor first (an ideal low-pass below the new Nyquist, then every
        ``decimate``-th sample). Default: read from the record's spectrum (the report says
        how); 1 keeps the rate.
    max_order : int, optional
        Largest model order of the stabilization diagram (default: the Toeplitz matrix's
        numerical rank, at most 40, or four per spectral peak when the record shows more
        than ten and the block rows are read from it).
    order_step : int
        Orders run ``order_step, 2 * order_step, ...`` (default 1: odd orders too, where a
        real pole can appear).
    references : list of int, optional
        Reference channels (default: all).
    df, dzeta, dmac, dreal : float, optional
        Stabilization thresholds: relative frequency change (default 0.01), relative damping
        change (0.05), 1 - MAC (0.02), relative change of a real pole (1.5).
    refine : bool
        Refine SSI's modes by maximum likelihood (default True): the modes the record
        supports, each with standard errors, and every channel's shape.
    joint : bool
        Fit the channels jointly, cross-spectra included (default True); False fits each
        channel's spectrum alone.
    ssi_errors : int, optional
        Standard errors for SSI's modes: the jackknife over at most this many blocks of the
        record (default 10; 0: none). They are the errors reported where SSI's modes are the
        answer, and the decision of what is a mode reads them (a mode must be found again in
        the record's parts, its frequency determined).
    max_damping : float, optional
        The largest damping ratio of a mode (default 0.2): a candidate damped more is set
        apart with its reason, not reported.
    channels : list of str, optional
        Names of the channels (they head the shapes in ``str(result)`` and the JSON).
    record : str
        What the data is, for the report (the JSON's ``record``).
    fdd : bool
        Also compute the record's frequency-domain decomposition (on the record analysed,
        after the decimation), which ``html()`` draws behind the stabilization diagram with
        EFDD's opinion on each mode (default False: not computed; ``hyst ssi`` computes it
        when ``--html`` asks for the page).
    setups : str or os.PathLike, optional
        Instead of ``y``: a setup file (``hyst ssi --setups``: CSV of setup, file, column,
        node, direction, quantity, reference, gain), or a folder of setups in pyOMA's layout.
        Each setup is identified alone, then the modes are merged on the references shared
        by every setup, velocities and accelerations reconciled, each node's x, y, z solved
        from its directions, and every setup's standard errors carried into the merged
        frequencies, damping ratios and shapes. ``fs`` is then optional (each record's or
        setup's stated rate), and ``references`` and ``channels`` are the file's. Returns a
        ``Report``: ``str(report)`` as the command prints it, ``report.to_dict()`` its JSON
        (``setups``, ``merged``), ``report.html()`` the page ``--html`` writes.
    geometry, lines : str or os.PathLike, optional
        With ``setups``: the structure's nodes (a header line, then ``name x y z`` per line)
        and the lines between them (two node names per line), to draw the merged shapes on;
        a pyOMA setup folder's own ``grid.txt`` and ``lines.txt`` are read without them.
    records_anywhere : bool
        With ``setups``: let the setup file name records outside its own folder (absolute
        paths, ``..``); by default each is named by its path from that folder.

    Returns
    -------
    SsiResult
        ``frequency_hz``, ``damping_ratio``, ``frequency_se_hz``, ``damping_se``,
        ``shape`` (modes x channels, complex), ``shape_se``: the modes the analysis decides
        are structural — the refined ones where the refinement agrees with SSI on every
        mode (``source == "refined"``), else SSI's with the jackknife's errors
        (``source == "ssi"``; NaN with ``ssi_errors=0``); ``to_dict()["decision"]`` says why,
        and lists each candidate set apart with its reasons. ``ssi_modes``, ``real_poles``,
        ``poles`` and ``pole_status`` (the stabilization diagram), ``misfit``,
        ``to_dict()``, ``to_json()``, ``html()`` (the page ``hyst ssi
        --html`` writes); ``print(result)`` prints the report of ``hyst ssi``.

    Raises
    ------
    ValueError
        With the library's message: a record too short or constant, an option out of
        range, a non-finite value.
    """
    if setups is not None:
        if y is not None:
            raise ValueError("give y or setups, not both")
        for name, value in (("references", references), ("channels", channels)):
            if value is not None:
                raise ValueError(f"{name} is the setup file's with setups: leave it out")
        if fdd:
            raise ValueError("fdd is one record's: the page of merged setups draws none")
        settings = _settings(
            block_rows=block_rows, lag_seconds=lag_seconds, lag_periods=lag_periods,
            decimate=decimate, max_order=max_order, order_step=order_step, references=None,
            df=df, dzeta=dzeta, dmac=dmac, dreal=dreal, refine=refine, joint=joint,
            ssi_errors=ssi_errors, max_damping=max_damping,
        )
        if fs is not None:
            _check_rate(fs)
        return _hyst.ssi_setups(
            _os.fspath(setups),
            None if fs is None else float(fs),
            settings=settings,
            geometry=None if geometry is None else _os.fspath(geometry),
            lines=None if lines is None else _os.fspath(lines),
            records_anywhere=bool(records_anywhere),
        )
    if geometry is not None or lines is not None or records_anywhere:
        raise ValueError("geometry, lines and records_anywhere go with setups")
    if y is None or fs is None:
        raise ValueError("give y and fs (or setups)")
    a = _real(y, "y")
    if a.ndim == 1:
        a = a.reshape(-1, 1)
    if a.ndim != 2:
        raise ValueError(f"y must be (samples, channels) or (samples,), got shape {a.shape}")
    settings = _settings(
        block_rows=block_rows, lag_seconds=lag_seconds, lag_periods=lag_periods,
        decimate=decimate, max_order=max_order, order_step=order_step, references=references,
        df=df, dzeta=dzeta, dmac=dmac, dreal=dreal, refine=refine, joint=joint,
        ssi_errors=ssi_errors, max_damping=max_damping,
    )
    return _hyst.ssi(
        a,
        float(fs),
        settings=settings,
        channels=None if channels is None else [str(c) for c in channels],
        record=str(record),
        fdd=bool(fdd),
    )


def amplitude(y, fs, *, modes=None, measured="displacement", amplitude_of=None, levels=8,
              cycles=3.0, groups=20, min_triggers=50, band=None, method="envelope",
              period=None, block_rows=None, lag_seconds=None, lag_periods=None, decimate=None,
              max_order=None, order_step=1, references=None, df=None, dzeta=None, dmac=None,
              dreal=None, refine=True, joint=True, ssi_errors=None, max_damping=None,
              record="array"):
    """Each mode's natural frequency and damping ratio against its amplitude (``hyst
    amplitude``): the modes as :func:`ssi` finds them, each mode's response filtered out
    (a modal filter, then a band-pass), random decrement conditioned on its envelope in
    ``levels`` amplitude bands, each band's decay fitted, standard errors by the jackknife
    over ``groups`` stretches of the record, and a test of whether the mode is linear (see
    docs/amplitude.md).

    Parameters
    ----------
    y : array_like, shape (samples, channels) or (samples,); or a list of them
        The measured response; or several records of one structure (force levels, a
        campaign), each analysed alike with the same modes followed, and each mode's change
        pooled over all their points (``hyst amplitude --input A B ...``).
    fs : float
        Sampling rate (Hz).
    modes : list of float, optional
        Frequencies (Hz) of the modes to follow: the identified mode nearest each (within
        5 %); default every mode :func:`ssi` reports.
    measured : {"displacement", "velocity", "acceleration"}
        What the channels measure.
    amplitude_of : {"displacement", "velocity", "acceleration"}, optional
        The quantity amplitudes are reported in (converted at each point's frequency);
        default as measured.
    levels, cycles, groups, min_triggers : optional
        Amplitude bands; cycles of each band's decay fitted; stretches of the jackknife;
        fewest triggers a point needs.
    band : float, optional
        Band-pass half-width as a share of each mode's frequency (default 0.3, or half the
        relative distance to the nearest other mode).
    method : {"envelope", "extrema"}
        Random decrement conditioned on the analytic signal's envelope (default), or the
        classical one at the response's extrema.
    period : int, optional
        Samples per period of a periodic excitation: the periods are averaged into one,
        read as circular.
    block_rows, lag_seconds, lag_periods, decimate, max_order, order_step, references,
    df, dzeta, dmac, dreal, refine, joint, ssi_errors, max_damping
        The modal analysis, as for :func:`ssi`.
    record : str
        What the data is, for the report (several records are named ``record[i]``).

    Returns
    -------
    Report
        ``str(report)`` as ``hyst amplitude`` prints it; ``report.to_dict()`` its JSON (with
        several records: ``records``, a list of [name, analysis], and ``pooled``):
        ``curves.modes[j].points`` (``amplitude``, ``frequency_hz``, ``frequency_se_hz``,
        ``damping_ratio``, ``damping_se``, ``triggers``), ``linearity``, ``notes``.
    """
    import json

    many = isinstance(y, (list, tuple))
    arrays = []
    for i, r in enumerate(y if many else [y]):
        a = _real(r, f"y[{i}]" if many else "y")
        if a.ndim == 1:
            a = a.reshape(-1, 1)
        if a.ndim != 2:
            raise ValueError(f"y must be (samples, channels) or (samples,), got shape {a.shape}")
        arrays.append(a)
    if not arrays:
        raise ValueError("no records: give an array, or a list of them")
    quantities = ("displacement", "velocity", "acceleration")
    for name, v in (("measured", measured), ("amplitude_of", amplitude_of)):
        if v is not None and v not in quantities:
            raise ValueError(f'{name} "{v}" is not one of {", ".join(quantities)}')
    if method not in ("envelope", "extrema"):
        raise ValueError(f'method "{method}" is not one of envelope, extrema')
    options = {
        "levels": _count(levels, "levels", 1),
        "cycles": float(cycles),
        "groups": _count(groups, "groups", 2),
        "min_triggers": _count(min_triggers, "min_triggers", 1),
        "band": None if band is None else float(band),
        "measured": measured,
        "report_as": amplitude_of,
        "method": method,
        "period": _count(period, "period", 1),
    }
    settings = _settings(
        block_rows=block_rows, lag_seconds=lag_seconds, lag_periods=lag_periods,
        decimate=decimate, max_order=max_order, order_step=order_step, references=references,
        df=df, dzeta=dzeta, dmac=dmac, dreal=dreal, refine=refine, joint=joint,
        ssi_errors=ssi_errors, max_damping=max_damping,
    )
    names = [f"{record}[{i}]" for i in range(len(arrays))] if many else [str(record)]
    return _hyst.amplitude(
        arrays, float(fs), settings=settings, options=json.dumps(options),
        modes=[] if modes is None else [float(f) for f in modes], records=names,
    )


def _settings(*, block_rows, lag_seconds, lag_periods, decimate, max_order, order_step,
              references, df, dzeta, dmac, dreal, refine, joint, ssi_errors=None,
              max_damping=None):
    """The analysis settings :func:`ssi` and :func:`track` share, checked and written as
    the JSON object the library reads (``hyst::settings::SsiSettings``, whose fields are the
    command line's flags too); a keyword left None keeps the library's default."""
    import json

    def real(v, name):
        if v is None:
            return None
        if isinstance(v, bool):
            raise ValueError(f"{name} must be a number, got {v!r}")
        return float(v)

    if lag_periods is not None:
        lp = list(lag_periods)
        if len(lp) != 2:
            raise ValueError(f"lag_periods must be (count, Hz), got {lag_periods!r}")
        lag_periods = [real(lp[0], "lag_periods count"), real(lp[1], "lag_periods Hz")]
    values = {
        "block_rows": _count(block_rows, "block_rows", 2),
        "lag_seconds": real(lag_seconds, "lag_seconds"),
        "lag_periods": lag_periods,
        "decimate": _count(decimate, "decimate", 1),
        "max_order": _count(max_order, "max_order", 1),
        "order_step": _count(order_step, "order_step", 1),
        "references": None if references is None
        else [_count(r, "references", 0) for r in references],
        "df": real(df, "df"),
        "dzeta": real(dzeta, "dzeta"),
        "dmac": real(dmac, "dmac"),
        "dreal": real(dreal, "dreal"),
        "refine": bool(refine),
        "joint": bool(joint),
        "ssi_errors": _count(ssi_errors, "ssi_errors", 0),
        "max_damping": real(max_damping, "max_damping"),
    }
    # NaN and infinities are not JSON: the library's own checks name them.
    for k, v in values.items():
        if isinstance(v, float) and not _np.isfinite(v):
            raise ValueError(f"{k} must be finite, got {v!r}")
    return json.dumps({k: v for k, v in values.items() if v is not None})


def _tracking(*, training, whiten, environment_model, level_covariate=False):
    """The tracking settings :func:`track` and :func:`track_estimates` share, written as the
    JSON object the library reads (``hyst::settings::TrackSettings``, whose fields are
    ``hyst track``'s flags too)."""
    import json

    return json.dumps({
        "training": _count(training, "training", 0),
        "whiten": bool(whiten),
        "environment_model": bool(environment_model),
        "level_covariate": bool(level_covariate),
    })


def _count(v, name, least):
    """An optional whole-number option as an int of at least ``least``, else ValueError."""
    if v is None:
        return None
    if isinstance(v, bool) or int(v) != v:
        raise ValueError(f"{name} must be a whole number, got {v!r}")
    if int(v) < least:
        raise ValueError(f"{name} must be at least {least}, got {v!r}")
    return int(v)


def _real(x, what):
    """``x`` as a float64 array; complex values are refused (converting them drops the
    imaginary part with only a warning)."""
    if _np.iscomplexobj(x):
        raise ValueError(
            f"{what} is complex: give real values (np.real(...) or np.abs(...), as the data mean)"
        )
    return _np.asarray(x, dtype=_np.float64)


def _vector(x, what):
    a = _np.ascontiguousarray(_real(x, what))
    if a.ndim != 1:
        raise ValueError(f"{what} must be one-dimensional (samples,), got shape {a.shape}")
    return a


def _model_json(model):
    import json

    if isinstance(model, str):
        if model != "benchmark":
            raise ValueError(f'model {model!r}: give a dict in the --params schema or "benchmark"')
        return json.dumps(model)
    return json.dumps(model)


def _validations(validate):
    """(name, u, y, periodic or None) tuples from dicts {"u", "y", "name"?, "periodic"?} or
    (u, y) pairs."""
    out = []
    for i, v in enumerate(validate or ()):
        if isinstance(v, dict):
            unknown = set(v) - {"u", "y", "name", "periodic"}
            if unknown:
                raise ValueError(f"validate[{i}]: unknown keys {sorted(unknown)}")
            u, y, name, periodic = v["u"], v["y"], v.get("name", f"validation {i}"), v.get("periodic")
        else:
            u, y = v
            name, periodic = f"validation {i}", None
        out.append((str(name), _vector(u, "u").tolist(), _vector(y, "y").tolist(),
                    None if periodic is None else bool(periodic)))
    return out


def excite(fs=750.0, *, excitation="multisine", rms=50.0, samples=8192, seed=1, f_min=5.0,
           f_max=150.0):
    """A generated force record, as ``hyst excite`` writes it (same samples for the same
    arguments: the generator is seeded and portable).

    Parameters
    ----------
    fs : float
        Sampling rate (Hz).
    excitation : {"multisine", "white", "sweep"}
        A random-phase multisine flat on [f_min, f_max] and periodic with ``samples``
        samples, Gaussian white noise, or a linear sine sweep from f_min to f_max over the
        record (amplitude sqrt(2) * rms).
    rms : float
        RMS of the force (N).
    samples : int
        Samples (a multisine: one period).
    seed : int
        Seed of the random generator.
    f_min, f_max : float
        The excited band (Hz; multisine and sweep).

    Returns
    -------
    numpy.ndarray, shape (samples,)
        The force (N).
    """
    import json

    design = {"rms": float(rms), "samples": _count(samples, "samples", 1),
              "seed": _count(seed, "seed", 0), "f_min": float(f_min), "f_max": float(f_max)}
    return _hyst.excite(float(fs), kind=str(excitation), design=json.dumps(design))


def simulate(model, u, fs, *, periodic=False, input_interpolation="band-limited",
             oversample=20, integrator="rk4", decimation="sample", noise=0.0, noise_seed=2):
    """The response of an oscillator to a force record, as ``hyst simulate`` writes it.

    Parameters
    ----------
    model : dict or "benchmark"
        The oscillator in the JSON schema ``--params`` reads (``{"mass", "damping",
        "stiffness", "bouc_wen": {...}, ...}``; a report's model, e.g.
        ``report.to_dict()["bouc_wen"]``), or ``"benchmark"`` for the Bouc-Wen benchmark's.
    u : array_like, shape (samples,)
        The force (N) at ``fs`` Hz.
    fs : float
        Sampling rate (Hz).
    periodic : bool
        ``u`` is one period of a periodic signal: simulated to steady state, the result one
        steady-state period (the force interpolated exactly between samples).
    input_interpolation : {"band-limited", "linear"}
        How a non-periodic force is known between samples: a measured force (windowed-sinc,
        the default) or straight lines.
    oversample : int
        Integration sub-steps per sample (default 20).
    integrator : {"rk4", "newmark"}
    decimation : {"sample", "fir"}
        Back to ``fs`` by keeping every ``oversample``-th state, or MATLAB-style FIR
        decimation in stages.
    noise : float
        Standard deviation of white measurement noise added (m), seeded by ``noise_seed``.

    Returns
    -------
    numpy.ndarray, shape (samples,)
        The displacement (m).
    """
    if input_interpolation not in ("band-limited", "linear"):
        raise ValueError(
            f'input_interpolation {input_interpolation!r} is not one of "band-limited", "linear"'
        )
    return _hyst.simulate(
        _model_json(model), _vector(u, "u"), float(fs),
        input="periodic" if periodic else str(input_interpolation),
        oversample=int(oversample), integrator=str(integrator), decimation=str(decimation),
        noise=float(noise), noise_seed=int(noise_seed),
    )


def identify(y, fs, mass, *, damping="spectrum", c=None, excitation_band=None, period=None,
             linearization=None, validate=None, profile=False, record="array"):
    """The paper's output-only identification (``hyst ident``) of a record's output.

    Linear, Zener and Bouc-Wen models from the response alone: SSI-COV's poles, the real
    pole included, mapped to stiffness, Zener and Bouc-Wen parameters with the mass known.

    Parameters
    ----------
    y : array_like, shape (samples,)
        The measured displacement.
    fs : float
        Sampling rate (Hz).
    mass : float
        The mass (kg), assumed known.
    damping : {"spectrum", "cluster"}
        Where the viscous damping c of the Zener and Bouc-Wen models comes from (the Zener
        fit to the record's spectrum, or the paper's cluster of lightly damped poles).
    c : float, optional
        A known viscous damping (N s/m), in place of ``damping``.
    excitation_band : (float, float), optional
        The band (Hz) on which the excitation's spectrum was flat (with ``period``, the
        samples per period of the multisine): then the Bouc-Wen model is also fitted by
        flatness of its implied input.
    linearization : {"paper", "harmonic"}, optional
        The mapping from poles to Bouc-Wen (default: whichever validates better).
    validate : list, optional
        Records to validate each model on: dicts ``{"u", "y", "name"?, "periodic"?}`` or
        ``(u, y)`` pairs.
    profile : bool
        Also show what one record leaves free (``hyst ident --profile``): at each ratio
        βδ/βγ the Bouc-Wen model that best reproduces the record's statistics, its χ² and
        its validation errors (about a minute).
    record : str
        What the data is, for the report.

    Returns
    -------
    Report
        ``str(report)`` as ``hyst ident`` prints; ``report.to_dict()`` its ``--json``
        document, with the models (``"linear"``, ``"zener"``, ``"bouc_wen"``) in the schema
        ``simulate`` takes.
    """
    return _hyst.identify(
        _vector(y, "y").tolist(), float(fs), float(mass), damping=str(damping),
        c=None if c is None else float(c),
        excitation_band=None if excitation_band is None else tuple(map(float, excitation_band)),
        period=None if period is None else int(period),
        linearization=linearization, validate=_validations(validate), profile=bool(profile),
        record=str(record),
    )


def refine(u, y, fs, *, mass=None, start="linear", input_interpolation="band-limited",
           estimate=None, test=None, record="array"):
    """Close the loop with input and output (``hyst refine``): refine a model by output
    error, trace the residual to the effect the model lacks, add it, and report the held-out
    error before and after.

    Parameters
    ----------
    u, y : array_like, shape (samples,)
        The force and the displacement.
    fs : float
        Sampling rate (Hz).
    mass : float, optional
        The mass (kg); without it the mass is estimated too.
    start : {"linear", "zener", "bouc-wen"}
        The starting model class.
    input_interpolation : {"band-limited", "linear"}
        How the force is known between samples when models are simulated.
    estimate : (int, int), optional
        Estimation rows [a, b) (default the first 75 %).
    test : list of (int, int), optional
        Test rows (default the last 25 %).

    Returns
    -------
    Report
        As ``hyst refine`` prints and writes; ``report.to_dict()["model"]`` is the final
        model, in the schema ``simulate`` takes.
    """
    return _hyst.refine(
        _vector(u, "u").tolist(), _vector(y, "y").tolist(), float(fs),
        mass=None if mass is None else float(mass), start=str(start),
        input_interpolation=str(input_interpolation),
        estimate=None if estimate is None else (int(estimate[0]), int(estimate[1])),
        test=[(int(a), int(b)) for a, b in (test or ())], record=str(record),
    )


def levels(records, fs, mass, *, by_simulation=False, data_periodic=False, fit_exponent=False,
           validate=None):
    """One Bouc-Wen model from records of one structure at several force levels, each under
    a random force (``hyst levels``).

    Parameters
    ----------
    records : list of array_like, or dict of name -> array_like
        The displacement records, one per level.
    fs : float
        Sampling rate (Hz).
    mass : float
        The mass (kg).
    by_simulation : bool
        Then fit the model by simulation (indirect inference; slower), ``data_periodic``
        when the records are periodic.
    fit_exponent : bool
        Fit the Bouc-Wen exponent too (three or more records).
    validate : list, optional
        As for :func:`identify`.

    Returns
    -------
    Report
        As ``hyst levels`` prints and writes.
    """
    items = records.items() if isinstance(records, dict) else (
        (f"level {i}", r) for i, r in enumerate(records))
    named = [(str(n), _vector(r, "each record").tolist()) for n, r in items]
    return _hyst.levels(
        named, float(fs), float(mass), by_simulation=bool(by_simulation),
        data_periodic=bool(data_periodic), fit_exponent=bool(fit_exponent),
        validate=_validations(validate),
    )


def track(records, fs, *, times=None, covariates=None, training=None, whiten=True,
          environment_model=True, reference=None, block_rows=None, lag_seconds=None, lag_periods=None, decimate=None,
          max_order=None, order_step=1, references=None, df=None, dzeta=None, dmac=None,
          dreal=None, refine=True, joint=True, ssi_errors=None, max_damping=None, client=None,
          level_covariate=False):
    """Track the modes of many records of one structure (``hyst track``).

    Each record is identified as :func:`ssi` does (in parallel), its modes matched to a
    reference (the record with the most modes among the first 24) by frequency and MAC, each
    mode's frequency regressed on the covariates over the training records, and a CUSUM of
    the later records' standardized residuals raises alarms on changes the covariates and
    the estimation noise do not explain (see docs/monitoring.md).

    Parameters
    ----------
    records : list of array_like (samples, channels), or of file paths
        The records, in time order; a path is read as :func:`read` reads it, and the record
        is named by its file's name (an array by its place), as ``hyst track`` names it.
    fs : float or None
        Sampling rate (Hz); None when the files state it (Universal Files).
    times : list of float, optional
        Each record's time (s); default its index.
    covariates : array_like, shape (records, covariates), or dict of name -> sequence, optional
        E.g. the temperature at each record; NaN where missing (the record is then tracked
        but not charted). A dict (or a pandas DataFrame) names them in the report's text.
    training : int, optional
        The first this many records train the baselines (default 336, at most half).
    block_rows, lag_seconds, lag_periods, decimate, max_order, order_step, references,
    df, dzeta, dmac, dreal, joint, ssi_errors, max_damping
        The analysis of each record, as for :func:`ssi` (and ``hyst track``'s flags of the
        same names); what is left to the record (the lag, the decimation) is read from the
        first record and kept for every record, as ``hyst track`` does.
    refine : bool
        The maximum-likelihood refinement (default True; without it there are no standard
        errors and no chart).
    whiten : bool
        Where the training records show a slow effect the covariates leave unexplained,
        chart its model's filter's innovations (default True: the effect is then not taken
        for a change), or the residuals as they are always (``hyst track --no-whiten``).
    environment_model : bool
        Choose each mode's environmental model on the training records (default True: each
        covariate through a first-order lag of whole hours, its slope changing below a
        breakpoint; by BIC), or regress on the covariates as they are
        (``hyst track --no-environment-model``).
    reference : path, or the result of :func:`ssi`, optional
        The reference modes (``hyst track --reference``): a ``hyst ssi --json`` document, or
        an :func:`ssi` result; default the record with the most modes among the first 24.

    level_covariate : bool
        Add each record's excitation level as a covariate after the given ones
        (``log_rms``: ln of its RMS response, in the record's units; ``hyst track
        --level-covariate``), for frequencies that drift with amplitude.
    client : dask.distributed.Client, or "local", optional
        Identify the records on a Dask cluster: each worker reads its records' files
        itself (only the paths travel; ``records`` must be paths the workers can read) and
        identifies them; the tracking runs here on the gathered modes. ``"local"`` starts a
        ``LocalCluster`` of 2 worker processes for the call. A file a worker cannot read is
        skipped with the reason, as ``hyst track`` skips it. The report is the one this
        function gives without a client (see docs/monitoring.md).

    Returns
    -------
    Report
        ``str(report)`` as ``hyst track`` prints; ``report.to_dict()`` its ``report.json``:
        ``reference``, ``rows`` (record x mode), ``skipped``, ``baselines``, ``alarms``,
        ``split``, ``residual_models``, ``tracked``, ``in_control_run_length``.
    """
    import os

    if client is not None:
        return _track_on_dask(
            client, records, fs, times=times, covariates=covariates, reference=reference,
            tracking=_tracking(training=training, whiten=whiten,
                               environment_model=environment_model,
                               level_covariate=level_covariate),
            settings=_settings(
                block_rows=block_rows, lag_seconds=lag_seconds, lag_periods=lag_periods,
                decimate=decimate, max_order=max_order, order_step=order_step,
                references=references, df=df, dzeta=dzeta, dmac=dmac, dreal=dreal,
                refine=refine, joint=joint, ssi_errors=ssi_errors, max_damping=max_damping,
            ),
        )
    arrays = []
    names = []
    for i, r in enumerate(records):
        if isinstance(r, (str, os.PathLike)):
            # A file, read as hyst.read reads it; a Universal File brings its own rate.
            rec = read(r)
            fs = _rate_of(r, rec, fs)
            names.append(os.path.basename(os.fspath(r)))
            r = rec.data
        else:
            names.append(str(i))
        a = _real(r, f"record {i}")
        if a.ndim == 1:
            a = a.reshape(-1, 1)
        if a.ndim != 2:
            raise ValueError(f"record {i} must be (samples, channels), got shape {a.shape}")
        arrays.append(a)
    n = len(arrays)
    if n == 0:
        raise ValueError("no records: give at least one array or file")
    t = _times(times, n)
    x, cov_names = _covariates(covariates, n)
    ref = _reference(reference)
    if fs is None:
        raise ValueError("fs is needed: the records do not state their sampling rate")
    _check_rate(fs)
    return _hyst.track(
        arrays, float(fs), times=t, covariates=x, covariate_names=cov_names, names=names,
        reference=ref,
        tracking=_tracking(training=training, whiten=whiten,
                           environment_model=environment_model,
                           level_covariate=level_covariate),
        settings=_settings(
            block_rows=block_rows, lag_seconds=lag_seconds, lag_periods=lag_periods,
            decimate=decimate, max_order=max_order, order_step=order_step,
            references=references, df=df, dzeta=dzeta, dmac=dmac, dreal=dreal, refine=refine,
            joint=joint, ssi_errors=ssi_errors, max_damping=max_damping,
        ),
    )


def _times(times, n):
    """Each record's time (s): given, or its place."""
    return [float(i) for i in range(n)] if times is None else [float(v) for v in times]


def _covariates(covariates, n):
    """The covariates as rows of floats, one per record, and their names (a dict or a
    DataFrame names them)."""
    if covariates is None:
        return [[] for _ in range(n)], []
    names = []
    if hasattr(covariates, "keys"):
        names = [str(k) for k in covariates.keys()]
        covariates = _np.column_stack([_np.asarray(covariates[k], dtype=_np.float64)
                                       for k in covariates.keys()])
    c = _np.asarray(covariates, dtype=_np.float64)
    if c.ndim == 1:
        c = c.reshape(-1, 1)
    return c.tolist(), names


def _reference(reference):
    """The reference modes as a `hyst ssi --json` document's text, or None."""
    import os

    if reference is None:
        return None
    if isinstance(reference, (str, os.PathLike)):
        with open(reference, encoding="utf-8") as f:
            return f.read()
    if hasattr(reference, "to_json"):
        return reference.to_json()
    raise ValueError("reference must be a path to a `hyst ssi --json` document or an "
                     f"ssi() result, got {type(reference).__name__}")


def _check_rate(fs):
    """Refuse a sampling rate that is not a positive finite number."""
    if not (float(fs) > 0.0 and _np.isfinite(float(fs))):
        raise ValueError(f"fs must be a positive finite rate (Hz), got {fs}")


def _rate_of(path, rec, fs):
    """The rate of the record ``rec`` read from ``path``: ``fs`` when given (a file that
    states another is refused), else the file's own (None when it states none)."""
    import os

    if fs is None:
        return rec.fs
    if rec.fs is not None and abs(rec.fs - float(fs)) > 1e-5 * rec.fs:
        raise ValueError(f"{os.fspath(path)}: states {rec.fs} Hz, but fs={fs} was given")
    return float(fs)


def _read_on_worker(path, fs):
    """A record's data and rate as a Dask worker reads it (the file's rate when ``fs`` is
    None)."""
    rec = read(path)
    rate = _rate_of(path, rec, fs)
    if rate is None:
        raise ValueError(f"{path}: the file states no sampling rate and fs was not given")
    a = _real(rec.data, str(path))
    return (a.reshape(-1, 1) if a.ndim == 1 else a), rate


def _resolve_on_worker(path, fs, settings):
    """The campaign's analysis read from one record on a worker, or None."""
    try:
        a, rate = _read_on_worker(path, fs)
    except (OSError, ValueError):
        return None
    return _hyst.resolve_analysis(a, rate, settings)


def _identify_on_worker(path, fs, time, covariates, name, analysis):
    """One record read and identified on a worker: its modes as JSON (why not, if the file
    cannot be read)."""
    try:
        a, rate = _read_on_worker(path, fs)
    except (OSError, ValueError) as e:
        return _hyst.identify_record(None, 0.0, time, covariates, name, analysis, why=str(e))
    return _hyst.identify_record(a, rate, time, covariates, name, analysis)


def _track_on_dask(client, records, fs, *, times, covariates, reference, tracking, settings):
    """:func:`track` with the identification on a Dask cluster (``client``)."""
    import os

    paths = []
    for i, r in enumerate(records):
        if not isinstance(r, (str, os.PathLike)):
            raise ValueError(f"record {i}: with client=, give file paths (the workers read "
                             f"the files), not {type(r).__name__}")
        paths.append(os.path.abspath(os.fspath(r)))
    n = len(paths)
    if n == 0:
        raise ValueError("no records: give at least one file")
    if fs is not None:
        _check_rate(fs)
    t = _times(times, n)
    x, cov_names = _covariates(covariates, n)
    if len(t) != n or len(x) != n:
        raise ValueError(f"{n} records but {len(t)} times and {len(x)} rows of covariates")
    ref = _reference(reference)
    _hyst.resolve_analysis(None, 1.0, settings)  # bad settings said before any work
    cluster = None
    if isinstance(client, str):
        if client != "local":
            raise ValueError(f"client must be a dask.distributed.Client or \"local\", got {client!r}")
        from dask.distributed import Client, LocalCluster

        cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True)
        client = Client(cluster)
    try:
        # As hyst track: what the settings leave to the record read from the first of the
        # first 24 records that gives it, and kept for every record.
        analysis = None
        for p in paths[:24]:
            analysis = client.submit(_resolve_on_worker, p, fs, settings, pure=False).result()
            if analysis is not None:
                break
        if analysis is None:
            analysis = _hyst.resolve_analysis(None, 1.0, settings)
        names = [os.path.basename(p) for p in paths]
        futures = client.map(_identify_on_worker, paths, [fs] * n, t, x, names,
                             [analysis] * n, pure=False)
        identified = client.gather(futures)
    finally:
        if cluster is not None:
            client.close()
            cluster.close()
    return _hyst.track_identified(
        identified, covariate_names=cov_names, tracking=tracking, reference=ref,
    )


def track_estimates(estimates, *, covariates=None, training=None, whiten=True,
                    environment_model=True):
    """Track modal estimates made by another system (``hyst track --estimates``).

    Parameters
    ----------
    estimates : path
        A delimited table, one row per record in time order: ``record``, an optional
        ``time`` (s) and per tracked mode ``<mode>_hz``, optionally ``<mode>_hz_se`` (Hz)
        and ``<mode>_damping``; an empty cell is a mode the record did not have.
    covariates : path, optional
        The covariates file ``hyst track --covariates`` reads (``record``, optional
        ``time``, one column per covariate).
    training : int, optional
        The first this many records train the baselines (default 336, at most half).
    whiten, environment_model : bool
        As for :func:`track`.

    Returns
    -------
    Report
        The report ``hyst track --estimates`` writes as ``report.json`` (``to_json()``,
        ``str()`` its text). Without standard errors, each mode's estimation noise read
        from its training rows is in ``noise_from_training``.
    """
    import os

    return _hyst.track_estimates(
        os.fspath(estimates),
        covariates=None if covariates is None else os.fspath(covariates),
        tracking=_tracking(training=training, whiten=whiten,
                           environment_model=environment_model),
    )
