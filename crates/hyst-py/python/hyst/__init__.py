"""hyst: output-only modal analysis and hysteretic-damping identification, in Rust.

``hyst.ssi(y, fs)`` identifies the modes of a structure from its measured response alone
(operational modal analysis): covariance-driven stochastic subspace identification (SSI-COV)
with a stabilization diagram, then each mode refined by maximum likelihood on the whole record,
with standard errors. The same library runs the command ``hyst ssi``; ``result.to_dict()`` is
the JSON document ``hyst ssi --json`` writes.

``hyst.read(path)`` reads a record as the command line does: CSV, NumPy ``.npy``/``.npz``,
MATLAB ``.mat`` (level 5), Universal File datasets 58 (ASCII or 58b, with their sampling
rate); ``result.write_shapes_uff(path)`` writes the mode shapes as dataset 55, and
``hyst.read_shapes(path)`` reads such shapes back.

``hyst.simulate``, ``hyst.identify``, ``hyst.refine`` and ``hyst.levels`` are the commands of
the same names (``hyst simulate``, ``ident``, ``refine``, ``levels``) on arrays: models are
dicts in the JSON schema ``--params`` reads, reports are :class:`Report` objects whose
``to_dict()`` is the command's ``--json`` document.
"""

from ._hyst import Report, SsiResult
from ._modal import amplitude, ssi
from ._monitor import Follow, follow, track, track_estimates
from ._oscillator import excite, identify, levels, refine, simulate
from ._read import ModeShape, Record, Shapes, read, read_shapes

__all__ = [
    "amplitude", "excite", "identify", "levels", "read", "read_shapes", "Record", "refine",
    "Report", "ModeShape", "Shapes",
    "simulate", "ssi", "SsiResult", "track", "track_estimates", "follow", "Follow",
]
