"""hyst: output-only modal analysis and hysteretic-damping identification, in Rust.

``hyst.ssi(y, fs)`` identifies the modes of a structure from its measured response alone
(operational modal analysis): covariance-driven stochastic subspace identification (SSI-COV)
with a stabilization diagram, then each mode refined by maximum likelihood on the whole record,
with standard errors. The same library runs the command ``hyst ssi``; ``result.to_dict()`` is
the JSON document ``hyst ssi --json`` writes.

``hyst.read(path)`` reads a record as the command line does: CSV, NumPy ``.npy``/``.npz``,
MATLAB ``.mat`` (level 5), Universal File datasets 58 (ASCII or 58b, with their sampling
rate); ``result.write_shapes_uff(path)`` writes the mode shapes as dataset 55.
"""

from dataclasses import dataclass as _dataclass
from typing import List as _List, Optional as _Optional, Tuple as _Tuple

import numpy as _np

from . import _hyst
from ._hyst import SsiResult

__all__ = ["read", "Record", "ssi", "SsiResult"]


@_dataclass(frozen=True)
class Record:
    """A record read by :func:`hyst.read`.

    Attributes
    ----------
    data : numpy.ndarray, shape (samples, channels)
        The channels, float64, Fortran-ordered (``hyst.ssi`` reads its columns in place).
    names : list of str
        The channels' names: a CSV's header, ``"0", "1", ...`` for arrays, the point
        (``"12+Z"``) for a Universal File.
    fs : float or None
        The sampling rate the file states (a Universal File's), else None.
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
        ``data`` (samples x channels), ``names``, ``fs`` (the file's rate, or None),
        ``points``, ``path``.

    Raises
    ------
    ValueError
        With the library's message, naming the file and what is wrong (a truncated file, a
        dataset that is not a time response, channels of different lengths or rates, a
        value that is not finite, ...).
    """
    import os

    data, names, fs, points = _hyst.read_record(
        os.fspath(path), format=format, variable=variable, delimiter=delimiter
    )
    return Record(data=data, names=list(names), fs=fs, points=points, path=os.fspath(path))


def ssi(
    y,
    fs,
    *,
    block_rows=None,
    lag_seconds=None,
    max_order=None,
    order_step=1,
    references=None,
    df=None,
    dzeta=None,
    dmac=None,
    dreal=None,
    refine=True,
    joint=True,
    channels=None,
    record="array",
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
        Block rows of the Toeplitz matrix of correlations (default 20): correlations up to
        lag ``2 * block_rows - 1`` are used. The lowest mode should have at least a period
        within that lag.
    lag_seconds : float, optional
        The same as a time: enough block rows that the largest lag covers this many
        seconds, ceil((lag_seconds * fs + 1) / 2). Not with ``block_rows``.
    max_order : int, optional
        Largest model order of the stabilization diagram (default: the Toeplitz matrix's
        numerical rank, at most 40).
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
    channels : list of str, optional
        Names of the channels (they head the shapes in ``str(result)`` and the JSON).
    record : str
        What the data is, for the report (the JSON's ``record``).

    Returns
    -------
    SsiResult
        ``frequency_hz``, ``damping_ratio``, ``frequency_se_hz``, ``damping_se``,
        ``shape`` (modes x channels, complex), ``shape_se``: the refined modes when the
        refinement ran and the record follows its model (``source == "refined"``), else
        SSI's (``source == "ssi"``, standard errors NaN). ``ssi_modes``, ``real_poles``,
        ``poles`` and ``pole_status`` (the stabilization diagram), ``misfit``,
        ``to_dict()``, ``to_json()``, ``stabilization_svg()``; ``print(result)`` prints the
        report of ``hyst ssi``.

    Raises
    ------
    ValueError
        With the library's message: a record too short or constant, an option out of
        range, a non-finite value.
    """
    a = _np.asarray(y, dtype=_np.float64)
    if a.ndim == 1:
        a = a.reshape(-1, 1)
    if a.ndim != 2:
        raise ValueError(f"y must be (samples, channels) or (samples,), got shape {a.shape}")
    return _hyst.ssi(
        a,
        float(fs),
        block_rows=block_rows,
        lag_seconds=lag_seconds,
        max_order=max_order,
        order_step=order_step,
        references=None if references is None else [int(r) for r in references],
        df=df,
        dzeta=dzeta,
        dmac=dmac,
        dreal=dreal,
        refine=bool(refine),
        joint=bool(joint),
        channels=None if channels is None else [str(c) for c in channels],
        record=str(record),
    )
