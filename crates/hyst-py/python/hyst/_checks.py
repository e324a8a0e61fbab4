"""Checks of the arguments every function shares: counts, real arrays, rates."""

import numpy as _np


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


def _check_rate(fs):
    """Refuse a sampling rate that is not a positive finite number."""
    if not (float(fs) > 0.0 and _np.isfinite(float(fs))):
        raise ValueError(f"fs must be a positive finite rate (Hz), got {fs}")
