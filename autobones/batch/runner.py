""":func:`run_batch`: plan the folder, run the jobs on an engine, write the report."""
from __future__ import annotations

import os
import shutil
import time

from ..errors import AutobonesError
from ..io.atomic import probe_folder
from .engines import need_dask, run_dask, run_local
from .jobs import one_line, options_hash, refuse_inside_input, rig_one
from .lock import batch_lock
from .planning import check_folders, clean_stale_temps, plan
from .report import REPORT_FORMAT, REPORT_NAME, STATUSES, public_record, write_report


def run_batch(input_dir, output_dir, options, jobs=1, scheduler=None, force=False,
              on_start=None, on_result=None):
    """Rig every mesh under ``input_dir`` into ``output_dir``; write ``batch_report.json``.

    Parameters
    ----------
    input_dir, output_dir : str or os.PathLike
        Folders; the output is created and may not overlap the input.
    options : dict
        From :func:`make_options`.
    jobs : int
        Worker processes of the local engine (ignored with ``scheduler``).
    scheduler : str or None
        Address of a Dask distributed scheduler (``tcp://host:8786``).
    force : bool
        Overwrite outputs that exist but are out of date or made with other options.
    on_start : callable(n_to_run, n_skipped, n_refused), optional
    on_result : callable(record), optional
        Called once per file, as it finishes (skipped and refused files first).

    Returns
    -------
    dict
        The report (also written, atomically, to ``output_dir/batch_report.json``).

    AutobonesError (nothing written) for overlapping folders, an output that resolves inside the
    input (a symbolic link in the output tree), or another batch holding the output folder's lock.
    """
    if int(jobs) < 1:
        raise AutobonesError(f"--jobs {jobs}: give at least 1 worker process")
    if scheduler:  # before the output folder is made: a refused batch leaves nothing behind
        need_dask()
    t0 = time.perf_counter()
    inp, out = check_folders(input_dir, output_dir)
    probe_folder(out)  # up front: a folder that cannot be written fails the command, not every file
    with batch_lock(out):  # one batch at a time in a folder, planned under the lock: what it sees stays true
        items = plan(inp, out, options, force=force)  # refuses links into the input before anything is written
        clean_stale_temps(out)
        return _run(items, inp, out, options, jobs, scheduler, force, on_start, on_result, t0)


def _run(items, inp, out, options, jobs, scheduler, force, on_start, on_result, t0):
    h = options_hash(options)
    to_run = [it for it in items if it.action == "run"]
    if on_start:
        on_start(len(to_run), sum(it.action == "skip" for it in items), sum(it.action == "fail" for it in items))
    for it in items:
        if it.action != "run":
            it.record = _not_run_record(it, h)
            if on_result:
                on_result(public_record(it.record, inp, out, options))

    def done(i, record):
        record = dict(record)
        if to_run[i].reason:
            record["reason"] = to_run[i].reason
        if record.get("status") == "ok" and to_run[i].stale:
            _remove_stale(to_run[i].stale, inp, record)
        to_run[i].record = record
        if on_result:
            on_result(public_record(record, inp, out, options))

    argsets = [(it.input, it.output, options, inp) for it in to_run]
    if scheduler:
        run_dask(scheduler, rig_one, argsets, done, paths=(inp, out))
    else:
        run_local(int(jobs), rig_one, argsets, done)
    report = {
        "format": REPORT_FORMAT,
        "autobones_version": _version(),
        "input": inp, "output": out,
        "engine": "dask" if scheduler else "local",
        "scheduler": scheduler, "jobs": None if scheduler else int(jobs),
        "options": options, "options_hash": h, "force": bool(force),
        "finished": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "seconds": round(time.perf_counter() - t0, 3),
        "counts": {s: sum(it.record.get("status") == s for it in items) for s in STATUSES},
        "files": [public_record(it.record, inp, out, options) for it in items],
    }
    write_report(os.path.join(out, REPORT_NAME), report)
    return report


def _remove_stale(paths, inp, record):
    """Remove what an older batch wrote under the old name (``NAME.glb``, ``.NAME.glb.partial``), now that
    ``NAME.rig.glb`` is written; one that cannot be removed is a warning in the record, not a failure."""
    for path in paths:
        try:
            refuse_inside_input((path,), inp)  # a link made since the plan must not lead us into the input
            if os.path.isdir(path) and not os.path.islink(path):
                shutil.rmtree(path)
            elif os.path.lexists(path):
                os.unlink(path)
        except (OSError, AutobonesError) as exc:
            text = f"{os.path.basename(path)}: the old batch output could not be removed ({one_line(exc)})"
            record.setdefault("warnings", []).append({"kind": "old output kept", "text": text})


def _not_run_record(it, h):
    """The record of a planned item that is not run: skipped (up to date) or failed (refused)."""
    status = "skipped" if it.action == "skip" else "failed"
    return {"input": it.input, "output": it.output, "status": status,
            "error": it.reason if status == "failed" else None,
            "error_type": "Refused" if status == "failed" else None,
            "reason": it.reason if status == "skipped" else None,
            "seconds": 0.0, "timings": {}, "options_hash": h}


def _version():
    from ..version import __version__

    return __version__
