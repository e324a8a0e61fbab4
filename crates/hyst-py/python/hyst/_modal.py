"""Modal analysis: :func:`ssi` (``hyst ssi``) and :func:`amplitude` (``hyst amplitude``),
and the SSI settings they and :func:`track` share."""

import os as _os

import numpy as _np

from . import _hyst
from ._checks import _check_rate, _count, _real


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
    refine=False,
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
    rigid_floors=False,
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
        Refine SSI's modes by maximum likelihood (default False: SSI's modes with the
        jackknife's errors): the modes the record supports, each with standard errors, and
        every channel's shape. Its model is a white load: it gains most under a broadband
        random load (errors up to half SSI's) and rarely holds under coloured ones.
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
    rigid_floors : bool
        With ``setups``: take each floor (the geometry's nodes at one height, z up) holding a
        reference node as rigid in its plane, and say what factor the other channels on it
        read against the references (``hyst ssi --setups --rigid-floors``; the report's
        ``floor_factors``). Needs the nodes' positions.

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
            rigid_floors=bool(rigid_floors),
        )
    if geometry is not None or lines is not None or records_anywhere or rigid_floors:
        raise ValueError("geometry, lines, records_anywhere and rigid_floors go with setups")
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
              dreal=None, refine=False, joint=True, ssi_errors=None, max_damping=None,
              floors=None, record="array"):
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
    floors : list of int, optional
        Each channel's floor, 1 = the lowest above the ground, one channel per floor: each
        point then carries its amplitude across every storey (``drifts``) beside each
        channel's (``channels``).
    record : str
        What the data is, for the report (several records are named ``record[i]``).

    Returns
    -------
    Report
        ``str(report)`` as ``hyst amplitude`` prints it; ``report.to_dict()`` its JSON (with
        several records: ``records``, a list of [name, analysis], and ``pooled``):
        ``curves.modes[j].points`` (``amplitude``, ``frequency_hz``, ``frequency_se_hz``,
        ``damping_ratio``, ``damping_se``, ``triggers``, ``channels``, ``drifts``),
        ``linearity``, ``notes``.
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
        "floors": None if floors is None else [_count(f, "floors", 1) - 1 for f in floors],
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
