"""The oscillator's commands on arrays: :func:`excite`, :func:`simulate`, :func:`identify`,
:func:`refine` and :func:`levels` (``hyst simulate``, ``ident``, ``refine``, ``levels``)."""

import numpy as _np

from . import _hyst
from ._checks import _count, _real, _vector


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
    """The response of an oscillator to a force record, as ``hyst simulate`` writes it; or of
    a fitted structure (``hyst simulate --structure``).

    Parameters
    ----------
    model : dict or "benchmark"
        The oscillator in the JSON schema ``--params`` reads (``{"mass", "damping",
        "stiffness", "bouc_wen": {...}, ...}``; a report's model, e.g.
        ``report.to_dict()["bouc_wen"]``), or ``"benchmark"`` for the Bouc-Wen benchmark's;
        or a storey fit, ``hyst.levels(..., masses=...).to_dict()``, driven from rest with
        the force linear between samples (the oscillator's options do not apply).
    u : array_like, shape (samples,), or (samples, loaded floors) for a storey fit
        The force (N) at ``fs`` Hz; for a storey fit one column per loaded floor, in the
        fit's ``load_floors`` order.
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
        The displacement (m); for a storey fit (samples, channels), its channels' quantity.
    """
    if isinstance(model, dict) and "building" in model:
        return _simulate_structure(model, u, fs, periodic, input_interpolation, oversample,
                                   integrator, decimation, noise)
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


def _simulate_structure(fit, u, fs, periodic, input_interpolation, oversample, integrator,
                        decimation, noise):
    import json

    if (periodic or input_interpolation != "band-limited" or oversample != 20
            or integrator != "rk4" or decimation != "sample" or noise != 0.0):
        raise ValueError(
            "a storey fit is driven from rest at its own step with the force linear between "
            "samples: periodic, input_interpolation, oversample, integrator, decimation and "
            "noise are the oscillator's")
    rate = fit["building"]["fs"]
    if abs(float(fs) - rate) > 1e-9 * rate:
        raise ValueError(f"fs {fs} Hz: the structure was fitted at {rate} Hz")
    forces = _np.ascontiguousarray(_real(u, "u"))
    if forces.ndim == 1:
        forces = forces[:, None]
    if forces.ndim != 2:
        raise ValueError(f"u for a storey fit is (samples, loaded floors), got shape {forces.shape}")
    # The report's own keys (its record's name, its run time) are not the fit's.
    fit = {k: v for k, v in fit.items() if k not in ("record", "seconds")}
    out = _hyst.simulate_structure(json.dumps(fit), forces.T.tolist())
    return _np.asarray(out).T


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


def levels(records, fs, mass=None, *, by_simulation=False, data_periodic=False,
           fit_exponent=False, validate=None, masses=None, floors=None,
           quantity="acceleration", load_floors=None, predict=None):
    """One Bouc-Wen model from records of one structure at several force levels, each under
    a random force (``hyst levels``); with ``masses``, a shear structure of several floors:
    the storey holding a hysteretic element located (or none) and fitted by simulation.

    Parameters
    ----------
    records : list of array_like, or dict of name -> array_like
        The records, one per level: displacements (samples,) of one oscillator; with
        ``masses``, arrays (samples, channels) of the structure's sensors.
    fs : float
        Sampling rate (Hz).
    mass : float
        The oscillator's mass (kg); not with ``masses``.
    by_simulation : bool
        Then fit the model by simulation (indirect inference; slower), ``data_periodic``
        when the records are periodic.
    fit_exponent : bool
        Fit the Bouc-Wen exponent too (three or more records).
    validate : list, optional
        As for :func:`identify`.
    masses : list of float, optional
        A shear structure's floor masses (kg), the lowest first.
    floors : list of int, optional
        With ``masses``: each channel's floor, 1 = the lowest (default 1, 2, ...).
    quantity : str
        With ``masses``: what the channels read, "acceleration", "velocity" or
        "displacement".
    load_floors : list of int, optional
        With ``masses``: the floors the force acts on, 1 = the lowest (default every floor).
    predict : list of float, optional
        With ``masses``: levels not recorded to predict, each a force this many times the
        loudest record's RMS: each storey's RMS drift and each mode's band, with standard
        errors (the report's ``predictions``).

    Returns
    -------
    Report
        As ``hyst levels`` prints and writes.
    """
    if masses is not None:
        if mass is not None or by_simulation or data_periodic or fit_exponent or validate:
            raise ValueError(
                "masses fits a structure by simulation: mass, by_simulation, data_periodic, "
                "fit_exponent and validate are the one-oscillator route's")
        items = records.items() if isinstance(records, dict) else (
            (f"level {i}", r) for i, r in enumerate(records))
        named = []
        for n, r in items:
            a = _np.ascontiguousarray(_real(r, "each record"))
            if a.ndim != 2:
                raise ValueError(
                    f"with masses each record is (samples, channels), got shape {a.shape}")
            named.append((str(n), a.T.tolist()))
        return _hyst.storeys(
            named, float(fs), [float(m) for m in masses],
            floors=None if floors is None else [_count(f, "floors", 1) for f in floors],
            quantity=str(quantity),
            load_floors=None if load_floors is None else [
                _count(f, "load_floors", 1) for f in load_floors],
            predict=[float(f) for f in (predict or ())],
        )
    if floors is not None or quantity != "acceleration" or load_floors is not None or predict:
        raise ValueError(
            "floors, quantity, load_floors and predict describe a structure of several "
            "floors: give its masses instead of mass")
    if mass is None:
        raise ValueError("levels needs mass (one oscillator) or masses (a structure)")
    items = records.items() if isinstance(records, dict) else (
        (f"level {i}", r) for i, r in enumerate(records))
    named = [(str(n), _vector(r, "each record").tolist()) for n, r in items]
    return _hyst.levels(
        named, float(fs), float(mass), by_simulation=bool(by_simulation),
        data_periodic=bool(data_periodic), fit_exponent=bool(fit_exponent),
        validate=_validations(validate),
    )
