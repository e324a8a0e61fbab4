"""Monitoring: :func:`track` (``hyst track``; on a Dask cluster with ``client=``),
:func:`follow` (``hyst track --follow``) and :func:`track_estimates` (``hyst track
--estimates``)."""

import numpy as _np

from . import _hyst
from ._checks import _check_rate, _count, _real
from ._modal import _settings
from ._read import _rate_of, read


def track(records, fs, *, times=None, covariates=None, training=None, whiten=True,
          environment_model=True, reference=None, block_rows=None, lag_seconds=None, lag_periods=None, decimate=None,
          max_order=None, order_step=1, references=None, df=None, dzeta=None, dmac=None,
          dreal=None, refine=False, joint=True, ssi_errors=None, max_damping=None, client=None,
          level_covariate=False, calibrate=True, joint_chart=True):
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
        The maximum-likelihood refinement of each record's modes (default False: SSI's
        modes with the jackknife's errors, which the charts read as they read the refined
        ones').
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
    calibrate : bool
        Calibrate each chart's limit on the training records' own charted values (default
        True: their block bootstrap, never below the nominal limit; the report's
        ``calibrations`` say the false-alarm rate measured on them), or keep the nominal
        limit (``hyst track --no-calibrate``).
    joint_chart : bool
        Judge the modes together beside each alone (default True: the factors their
        residuals share set apart, what is left charted as one statistic; the report's
        ``joint``), or not (``hyst track --no-joint-chart``).
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
                               level_covariate=level_covariate, calibrate=calibrate,
                               joint_chart=joint_chart),
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
                           level_covariate=level_covariate, calibrate=calibrate,
                           joint_chart=joint_chart),
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


def _tracking(*, training, whiten, environment_model, level_covariate=False, calibrate=True,
              joint_chart=True):
    """The tracking settings :func:`track` and :func:`track_estimates` share, written as the
    JSON object the library reads (``hyst::settings::TrackSettings``, whose fields are
    ``hyst track``'s flags too)."""
    import json

    return json.dumps({
        "training": _count(training, "training", 0),
        "whiten": bool(whiten),
        "environment_model": bool(environment_model),
        "level_covariate": bool(level_covariate),
        "calibrate": bool(calibrate),
        "joint_chart": bool(joint_chart),
    })


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
        # As hyst track: what the settings leave to the record read by the library's rule
        # (the first of the first records that gives it), each asked of a worker in turn,
        # and kept for every record.
        analysis = _hyst.campaign_analysis(
            settings, n,
            lambda i: client.submit(_resolve_on_worker, paths[i], fs, settings,
                                    pure=False).result())
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


def follow(inputs, fs=None, *, covariates=None, training=None, poll=10.0, passes=None,
           whiten=True, environment_model=True, reference=None, block_rows=None,
           lag_seconds=None, lag_periods=None, decimate=None, max_order=None, order_step=1,
           references=None, df=None, dzeta=None, dmac=None, dreal=None, refine=False,
           joint=True, ssi_errors=None, max_damping=None, level_covariate=False,
           calibrate=True, joint_chart=True):
    """Records as they arrive (``hyst track --follow``): an iterator of the lines the
    command prints.

    Each pass tracks the campaign over every record file taken so far, as ``hyst track
    --inputs <the files> --covariates <covariates>`` would (the files put in time order by
    the covariates file, each identified once and kept, the analysis read from the first
    record); the iterator then gives the lines of what is new: the first pass's whole
    report, later each new record (``name: k mode(s) tracked`` or ``name: skipped: why``)
    and each new alarm, once. A file is taken once its size and modification time have held
    for one ``poll``; the covariates file is read again at each pass, and a pass also
    follows its change. The training is fixed (``training``, else 336 records), so that a
    record's chart does not depend on the records after it. Stop iterating at any time; a
    new ``follow`` over the same folders gives the same report (each record is identified
    again: the identified records are kept in memory, where ``hyst track --follow`` keeps
    them in its store).

    Parameters
    ----------
    inputs : path or list of paths
        Folders whose files are the records (in name order), or files.
    fs : float or None
        Sampling rate (Hz); None when the files state it.
    covariates : path, optional
        The covariates file ``hyst track --covariates`` takes (a ``record`` column, an
        optional ``time`` and one column per covariate), read again at each pass.
    training : int, optional
        The first this many records train (default 336, whatever has arrived).
    poll : float
        Seconds between looks at the folders (default 10).
    passes : int, optional
        Stop after this many passes (default: never).
    whiten, environment_model, reference, block_rows, ... joint_chart
        As for :func:`track`.

    Returns
    -------
    Follow
        An iterator of lines (str); its ``report`` is the last pass's report (None before
        the first), ``taken`` the files taken, ``waiting`` the lines not yet given.
    """
    import os

    if isinstance(inputs, (str, os.PathLike)):
        inputs = [inputs]
    if fs is not None:
        _check_rate(fs)
    poll = _real(poll, "poll")
    if not (poll.ndim == 0 and 0.0 < float(poll) <= 86400.0):
        raise ValueError(f"poll {poll}: give the seconds between looks, more than 0 and at "
                         "most a day")
    settings = _settings(
        block_rows=block_rows, lag_seconds=lag_seconds, lag_periods=lag_periods,
        decimate=decimate, max_order=max_order, order_step=order_step,
        references=references, df=df, dzeta=dzeta, dmac=dmac, dreal=dreal, refine=refine,
        joint=joint, ssi_errors=ssi_errors, max_damping=max_damping,
    )
    _hyst.resolve_analysis(None, 1.0, settings)  # bad settings said before any work
    tracking = _tracking(training=336 if training is None else training, whiten=whiten,
                         environment_model=environment_model,
                         level_covariate=level_covariate, calibrate=calibrate,
                         joint_chart=joint_chart)
    return Follow([os.fspath(p) for p in inputs], fs, covariates, float(poll),
                  _count(passes, "passes", 1), settings, tracking, _reference(reference))


class Follow:
    """The iterator :func:`follow` returns."""

    def __init__(self, inputs, fs, covariates, poll, passes, settings, tracking, reference):
        self._inputs, self._fs, self._covariates = inputs, fs, covariates
        self._poll, self._passes = poll, passes
        self._settings, self._tracking, self._reference = settings, tracking, reference
        self.report = None
        self.taken = []
        self._pending = {}
        self._identified = {}
        self._resolved = {}
        self._lines = []
        self._said, self._alarms_said = set(), set()
        self._done = 0
        self._covariates_stamp = self._stamp(covariates) if covariates is not None else None

    @property
    def waiting(self):
        """Lines of the last pass not yet given."""
        return len(self._lines)

    def __iter__(self):
        return self

    def __next__(self):
        import time

        while not self._lines:
            if self._passes is not None and self._done >= self._passes:
                raise StopIteration
            if self._done == 0:
                self.taken = self._listed()
            else:
                while not self._settled():
                    time.sleep(self._poll)
            self._pass()
        return self._lines.pop(0)

    @staticmethod
    def _stamp(path):
        import os

        try:
            st = os.stat(path)
        except OSError:
            return None
        return (st.st_size, st.st_mtime_ns)

    def _listed(self):
        """The record files in the folders now, in name order."""
        rows, _ = _hyst.campaign_records(self._inputs, None)
        return [r[0] for r in rows]

    def _settled(self):
        """Take the files whose size and time held since the last look; whether anything
        (a file, the covariates file) is new."""
        new = []
        for path in self._listed():
            if path in self.taken:
                continue
            now = self._stamp(path)
            if now is not None and self._pending.get(path) == now:
                del self._pending[path]
                new.append(path)
            elif now is not None:
                self._pending[path] = now
        covs = self._stamp(self._covariates) if self._covariates is not None else None
        changed = covs != self._covariates_stamp
        self._covariates_stamp = covs
        self.taken.extend(new)
        return bool(new) or changed

    def _analysis(self, rows):
        """The campaign's analysis, read from its first records as ``hyst track`` reads it."""

        def resolve(i):
            path, _, _, _, gap = rows[i]
            if gap is not None:
                return None
            key = (path, self._stamp(path))
            if key not in self._resolved:
                try:
                    a, rate = _read_on_worker(path, self._fs)
                    self._resolved[key] = _hyst.resolve_analysis(a, rate, self._settings)
                except (OSError, ValueError):
                    self._resolved[key] = None
            return self._resolved[key]

        return _hyst.campaign_analysis(self._settings, len(rows), resolve)

    def _pass(self):
        """Track every record taken so far; the lines of what is new."""
        import json

        self._done += 1
        if not self.taken:
            self._lines.append(f"no record yet in {', '.join(self._inputs)}; waiting")
            return
        rows, names = _hyst.campaign_records(self.taken, self._covariates)
        analysis = self._analysis(rows)
        identified = []
        for path, name, time, covs, gap in rows:
            key = (path, self._stamp(path), analysis)
            if gap is not None:
                doc = _hyst.identify_record(None, 0.0, time, covs, name, analysis, why=gap)
            else:
                if key not in self._identified:
                    self._identified[key] = _identify_on_worker(path, self._fs, time, covs,
                                                                name, analysis)
                # Its time and covariates are this pass's (the file may have changed).
                record = json.loads(self._identified[key])
                record["time"], record["covariates"] = time, covs
                doc = json.dumps(record)
            identified.append(doc)
        try:
            report = _hyst.track_identified(identified, covariate_names=names,
                                            tracking=self._tracking,
                                            reference=self._reference)
        except ValueError as e:
            self._lines.append(f"{len(rows)} record(s) so far: {e}; waiting for more")
            return
        first = self.report is None
        self.report = report
        doc = report.to_dict()
        if first:
            text = str(report)
            self._lines.extend(text.rstrip("\n").split("\n"))
            # What each record gave, said once: a gap said as skipped is said again when
            # its file lands.
            self._said.update((r["name"], "tracked") for r in doc["rows"])
            self._said.update((name, why) for name, why in doc["skipped"])
            for line in report.alarm_lines():
                if line not in text:
                    self._lines.append(line)
                self._alarms_said.add(line)
            return
        modes = {}
        for r in doc["rows"]:
            modes[r["name"]] = modes.get(r["name"], 0) + 1
        for name, k in modes.items():
            if (name, "tracked") not in self._said:
                self._said.add((name, "tracked"))
                self._lines.append(f"{name}: {k} mode(s) tracked")
        for name, why in doc["skipped"]:
            if (name, why) not in self._said:
                self._said.add((name, why))
                self._lines.append(f"{name}: skipped: {why}")
        for line in report.alarm_lines():
            if line not in self._alarms_said:
                self._alarms_said.add(line)
                self._lines.append(line)


def track_estimates(estimates, *, covariates=None, training=None, whiten=True,
                    environment_model=True, calibrate=True, joint_chart=True):
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
    whiten, environment_model, calibrate, joint_chart : bool
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
                           environment_model=environment_model, calibrate=calibrate,
                           joint_chart=joint_chart),
    )
