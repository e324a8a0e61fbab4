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


def _rate_of(path, rec, fs):
    """The rate of the record ``rec`` read from ``path``: ``fs`` when given (a file that
    states another is refused), else the file's own (None when it states none)."""
    import os

    if fs is None:
        return rec.fs
    if rec.fs is not None and abs(rec.fs - float(fs)) > 1e-5 * rec.fs:
        raise ValueError(f"{os.fspath(path)}: states {rec.fs} Hz, but fs={fs} was given")
    return float(fs)
