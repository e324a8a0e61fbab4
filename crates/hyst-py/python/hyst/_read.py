"""Reading a record as the command line reads it: :func:`read` and its :class:`Record`."""

from dataclasses import dataclass as _dataclass
from typing import List as _List, Optional as _Optional, Tuple as _Tuple

import numpy as _np

from . import _hyst


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


@_dataclass(frozen=True)
class ModeShape:
    """One mode of a Universal File read by :func:`hyst.read_shapes` (a dataset 55).

    Attributes
    ----------
    number : int
        The mode's number in the file.
    frequency_hz : float
        Natural frequency (from a complex mode's eigenvalue λ: |λ|/2π).
    damping_ratio : float
        Damping ratio (a complex mode's −Re λ/|λ|, a normal mode's viscous one).
    nodes : list of int
        The nodes, in the file's order.
    motion : numpy.ndarray, shape (nodes, 3), complex
        Each node's x, y, z translation (a real mode's with zero imaginary parts).
    """

    number: int
    frequency_hz: float
    damping_ratio: float
    nodes: _List[int]
    motion: _np.ndarray


@_dataclass(frozen=True)
class Shapes:
    """What :func:`hyst.read_shapes` reads: ``nodes`` maps each node of datasets 15 or 2411
    to its (x, y, z); ``modes`` lists each dataset 55's :class:`ModeShape`."""

    nodes: dict
    modes: _List[ModeShape]


def read_shapes(path):
    """Read mode shapes from a Universal File, as ``hyst ssi --shapes-uff`` (and
    ``--setups``) write them or another program does: each dataset 55 (normal or complex
    modes, each node's translation) and the nodes' positions of datasets 15 and 2411.

    Raises
    ------
    ValueError
        Naming the file, the dataset and what is wrong (no dataset 55, a field that does
        not read, a data type or analysis type that is not a mode shape, ...).
    """
    import os

    nodes, modes = _hyst.read_shapes_uff(os.fspath(path))
    return Shapes(
        nodes={n: tuple(x) for n, x in nodes},
        modes=[ModeShape(number=k, frequency_hz=f, damping_ratio=z, nodes=list(n), motion=m)
               for k, f, z, n, m in modes],
    )


def _rate_of(path, rec, fs):
    """The rate of the record ``rec`` read from ``path``: ``fs`` when given (a file that
    states another is refused), else the file's own (None when it states none)."""
    import os

    if fs is None:
        return rec.fs
    if rec.fs is not None and abs(rec.fs - float(fs)) > 1e-5 * rec.fs:
        raise ValueError(f"{os.fspath(path)}: states {rec.fs} Hz, but fs={fs} was given")
    return float(fs)
