"""``batch``: rig every mesh of a folder tree, resumably, on local processes or a Dask cluster.

Goes beyond the seeds (003 and 004 rig one head; issue #5 rigs folders of them). The
work for one file is :func:`rig_one`, a pure function of (input path, output path,
options): it runs :func:`autobones.place` or :func:`autobones.transfer`, writes the
glb and its two sidecars atomically, and returns a plain dict record. It never raises
for a bad file, so any engine can run it: :func:`run_batch` sends it to a
``concurrent.futures.ProcessPoolExecutor`` (``jobs``) or to a Dask distributed
cluster (``scheduler``), and writes ``batch_report.json``.

Layout: ``INPUT/a/b.obj`` -> ``OUTPUT/a/b.glb``, ``OUTPUT/a/b.rig.json``,
``OUTPUT/a/b.weights.npz``. The output folder may not overlap the input folder.

Resuming: a file is skipped when its three outputs exist, are newer than the mesh
(and its landmark file), and the sidecar records the same options hash
(``batch.options_hash`` in ``.rig.json``). One is written as: ``rig.save`` into a
hidden folder ``.NAME.glb.partial`` beside the target, then glb, npz and last the
sidecar are renamed into place and the folder removed. A ``.partial`` folder left
behind marks a file whose write was interrupted (kill -9): it is rigged again.
Outputs that exist but are out of date or were written with other options are
overwritten only with ``force=True``.
"""
from __future__ import annotations

import hashlib
import json
import logging
import os
import shutil
import socket
import time
import traceback
from dataclasses import dataclass, field

from .errors import AutobonesError
from .io.atomic import write_text_atomic
from .io.mesh import SUPPORTED

log = logging.getLogger("autobones")

REPORT_NAME = "batch_report.json"
REPORT_FORMAT = "autobones-batch-report/1"
PARTIAL_SUFFIX = ".partial"

#: Landmark files looked for beside ``NAME.ext`` in transfer mode, first found wins.
LANDMARK_SUFFIXES = (".landmarks.json", ".pp", ".pts", ".ljson")

STATUSES = ("ok", "failed", "skipped")


# ---------------------------------------------------------------------------------------------
# options and naming

def make_options(transfer=False, density="medium", rig=None, random_state=0, expressions=False):
    """The per-file options as a plain JSON-able dict (what :func:`rig_one` takes).

    ``density`` is ignored (None) for a transfer; ``rig`` is made absolute so the
    options mean the same thing on every worker. ``expressions`` (transfer only: True or
    ``"sides"``) adds AU morph targets to each glb (``Rig.save``); the key is present only
    when set, so other batches keep their options hash.
    """
    from .placement.facial_bones import DENSITIES, bone_count

    if transfer:
        return {"mode": "transfer", "density": None,
                "rig": None if rig is None else os.path.abspath(os.fspath(rig)), "random_state": None,
                **({"expressions": expressions} if expressions else {})}
    if expressions:
        raise AutobonesError("--expressions needs muscles, which place does not make; add --transfer")
    if rig is not None:
        raise AutobonesError("--rig is only used with --transfer")
    n = bone_count(density)  # refuse a bad density once, before any file is touched
    named = isinstance(density, str) and density.strip().lower() in DENSITIES
    d = density.strip().lower() if named else n
    return {"mode": "place", "density": d, "rig": None, "random_state": int(random_state)}


def options_hash(options):
    """sha256 (16 hex digits) of the options and the autobones version: what makes outputs comparable."""
    from . import __version__

    text = json.dumps({"options": options, "autobones_version": __version__}, sort_keys=True)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]


def output_paths(glb_path):
    """``x.glb`` -> (``x.glb``, ``x.rig.json``, ``x.weights.npz``), as :meth:`Rig.save` names them."""
    from .rig import sidecar_paths

    return (os.fspath(glb_path), *sidecar_paths(glb_path))


def landmarks_for(mesh_path):
    """The landmark file beside ``DIR/NAME.ext`` (``NAME.landmarks.json``, ``.pp``, ``.pts``,
    ``.ljson``; the first that exists), or None."""
    stem = os.path.splitext(os.fspath(mesh_path))[0]
    for suffix in LANDMARK_SUFFIXES:
        if os.path.isfile(stem + suffix):
            return stem + suffix
    return None


def _partial_dir(glb_path):
    folder, name = os.path.split(os.fspath(glb_path))
    return os.path.join(folder, f".{name}{PARTIAL_SUFFIX}")


# ---------------------------------------------------------------------------------------------
# the per-file job

def rig_one(input_path, output_path, options):
    """Rig one mesh and write its glb and sidecars atomically; never raises for a bad file.

    Parameters
    ----------
    input_path : str
        Mesh file (absolute, so workers elsewhere read the same file).
    output_path : str
        Target ``.glb``; the sidecars go beside it. Parent folders are created.
    options : dict
        From :func:`make_options`: ``mode`` ('place' or 'transfer'), ``density``,
        ``rig``, ``random_state``. In transfer mode the landmarks are the file
        :func:`landmarks_for` finds beside the mesh.

    Returns
    -------
    dict
        ``input``, ``output``, ``status`` ('ok' or 'failed'), ``error`` (one line,
        None when ok), ``error_type``, ``seconds``, ``timings`` (per stage),
        ``vertices``, ``bones``, ``options_hash``, ``landmarks``, ``host``, ``pid``;
        ``traceback`` for an unexpected exception (a bug, not a bad file).

    The result depends only on the arguments and the files' contents: BLAS runs on
    one thread in every engine so a rig is the same bit for bit wherever it is made.
    """
    t0 = time.perf_counter()
    h = options_hash(options)
    record = {"input": input_path, "output": output_path, "status": "failed", "error": None,
              "error_type": None, "seconds": 0.0, "timings": {}, "vertices": None, "bones": None,
              "options_hash": h, "landmarks": None, "host": socket.gethostname(), "pid": os.getpid()}
    partial = _partial_dir(output_path)
    try:
        with _one_blas_thread():
            rig = _make_rig(input_path, options, record)
        rig.extra = {**rig.extra, "batch": {"options": options, "options_hash": h}}
        _save_atomically(rig, output_path, partial, options.get("expressions", False))
        record.update(status="ok", timings={k: round(float(v), 4) for k, v in rig.timings.items()},
                      vertices=int(len(rig.vertices)), bones=int(len(rig.skeleton)))
    except AutobonesError as exc:
        record.update(error=_one_line(str(exc)), error_type="AutobonesError")
    except Exception as exc:  # a batch never dies on one file: record the bug and go on
        record.update(error=_one_line(f"{type(exc).__name__}: {exc}"), error_type=type(exc).__name__,
                      traceback=traceback.format_exc())
    finally:
        if os.path.isdir(partial):
            shutil.rmtree(partial, ignore_errors=True)
    record["seconds"] = round(time.perf_counter() - t0, 4)
    return record


def _make_rig(input_path, options, record):
    import autobones

    mode = options.get("mode")
    if mode == "place":
        return autobones.place(input_path, density=options["density"], random_state=options["random_state"])
    if mode == "transfer":
        # a mesh without a landmark file beside it gets automatic landmarks (human faces)
        lm = landmarks_for(input_path)
        record["landmarks"] = lm if lm is not None else "detected"
        return autobones.transfer(input_path, lm, rig=options.get("rig"))
    raise AutobonesError(f"unknown batch mode {mode!r}; use 'place' or 'transfer'")


class _one_blas_thread:
    def __enter__(self):
        try:
            from threadpoolctl import threadpool_limits
        except ImportError:  # without it, the engines' own settings apply
            self._limits = None
        else:
            self._limits = threadpool_limits(limits=1)
        return self

    def __exit__(self, *exc):
        if self._limits is not None:
            self._limits.restore_original_limits()
        return False


def _save_atomically(rig, output_path, partial, expressions=False):
    """Save into ``partial``, then rename glb, npz and last the sidecar (the commit mark) into place."""
    folder = os.path.dirname(os.path.abspath(output_path))
    try:
        os.makedirs(folder, exist_ok=True)
        if os.path.isdir(partial):
            shutil.rmtree(partial)
        os.mkdir(partial)
    except OSError as exc:
        raise AutobonesError(f"{output_path}: cannot create the output folder ({exc.strerror or exc})") from exc
    staged = rig.save(os.path.join(partial, os.path.basename(output_path)), expressions=expressions)
    glb, js, npz = output_paths(output_path)
    try:
        for src, dst in ((staged[0], glb), (staged[2], npz), (staged[1], js)):
            os.replace(src, dst)
        os.rmdir(partial)
    except OSError as exc:
        raise AutobonesError(f"{output_path}: cannot write ({exc.strerror or exc})") from exc


def _one_line(text, limit=500):
    text = " ".join(str(text).split())
    return text if len(text) <= limit else text[:limit - 3] + "..."


# ---------------------------------------------------------------------------------------------
# walking and planning

@dataclass
class Item:
    """One mesh of the batch: what to do with it and, when skipped or refused, why."""

    input: str           # absolute
    rel: str             # relative to the input folder, '/' separated
    output: str          # absolute .glb
    action: str = "run"  # run | skip | fail
    reason: str | None = None
    record: dict = field(default_factory=dict)


def check_folders(input_dir, output_dir):
    """Absolute (input, output) folders; refuse a missing input or overlapping folders."""
    inp = os.path.realpath(os.fspath(input_dir))
    out = os.path.realpath(os.fspath(output_dir))
    if not os.path.isdir(inp):
        raise AutobonesError(f"{input_dir}: no such folder")
    if os.path.exists(out) and not os.path.isdir(out):
        raise AutobonesError(f"{output_dir}: exists and is not a folder")
    if out == inp:
        raise AutobonesError(f"{output_dir}: the output folder is the input folder; outputs are never "
                             f"written inside the input, choose another folder")
    if out.startswith(inp + os.sep):
        raise AutobonesError(f"{output_dir}: the output folder is inside the input folder {input_dir}; "
                             f"outputs are never written inside the input, choose a folder outside it")
    if inp.startswith(out + os.sep):
        raise AutobonesError(f"{input_dir}: the input folder is inside the output folder {output_dir}; "
                             f"its outputs would land inside the input, choose separate folders")
    return inp, out


def find_meshes(input_dir, output_dir=None):
    """Mesh files under ``input_dir``, recursively, sorted by relative path.

    Only :data:`autobones.io.mesh.SUPPORTED` extensions; hidden files and folders
    (a leading dot) and ``output_dir`` (should it sit inside) are left out; symbolic
    links to folders are not followed.
    """
    inp = os.path.realpath(os.fspath(input_dir))
    skip = os.path.realpath(os.fspath(output_dir)) if output_dir is not None else None
    found = []
    for root, dirs, files in os.walk(inp):
        dirs[:] = sorted(d for d in dirs if not d.startswith(".")
                         and os.path.realpath(os.path.join(root, d)) != skip)
        for name in sorted(files):
            if name.startswith(".") or os.path.splitext(name)[1].lower() not in SUPPORTED:
                continue
            path = os.path.join(root, name)
            if os.path.isfile(path):
                found.append(path)
    return sorted(found, key=lambda p: os.path.relpath(p, inp).replace(os.sep, "/"))


def plan(input_dir, output_dir, options, force=False):
    """One :class:`Item` per mesh, with ``action`` run, skip (up to date) or fail (refused).

    Refused: two inputs that would write the same output (``a.obj`` and ``a.ply``),
    and, without ``force``, outputs that exist but are older than the input or were
    made with other options.
    """
    inp, out = check_folders(input_dir, output_dir)
    h = options_hash(options)
    items = []
    for path in find_meshes(inp, out):
        rel = os.path.relpath(path, inp)
        glb = os.path.join(out, os.path.splitext(rel)[0] + ".glb")
        items.append(Item(input=path, rel=rel.replace(os.sep, "/"), output=glb))
    owners = {}
    for it in items:
        for target in output_paths(it.output):
            owners.setdefault(target.lower(), []).append(it)
    for it in items:
        clash = sorted({o.rel for target in output_paths(it.output) for o in owners[target.lower()]} - {it.rel})
        if clash:
            it.action, it.reason = "fail", (f"{it.rel}: {', '.join(clash)} would write the same output "
                                            f"{os.path.relpath(it.output, out)}; rename one of them")
    for it in items:
        if it.action == "run":
            it.action, it.reason = _state(it, options, h, force)
    return items


def _state(it, options, h, force):
    targets = output_paths(it.output)
    present = [os.path.exists(t) for t in targets]
    if os.path.isdir(_partial_dir(it.output)):
        return "run", "interrupted"
    if not any(present):
        return "run", None
    why = None
    if not all(present):
        why = "some of its outputs exist (" + ", ".join(os.path.basename(t) for t, p in zip(targets, present) if p) + ")"
    else:
        recorded = _recorded_hash(targets[1])
        sources = [it.input]
        if options.get("mode") == "transfer":
            lm = landmarks_for(it.input)
            sources += [lm] if lm else []
        newest_in = max(os.stat(s).st_mtime_ns for s in sources)
        oldest_out = min(os.stat(t).st_mtime_ns for t in targets)
        if recorded is None:
            why = "its outputs exist but were not written by autobones batch"
        elif recorded != h:
            why = "its outputs were made with other options or another autobones version"
        elif oldest_out < newest_in:
            why = "its outputs are older than the input"
        else:
            return "skip", "up to date"
    if force:
        return "run", f"overwritten: {why}"
    return "fail", f"{it.rel}: {why}; pass --force to overwrite"


def _recorded_hash(sidecar):
    try:
        with open(sidecar, encoding="utf-8") as fh:
            return json.load(fh).get("batch", {}).get("options_hash")
    except (OSError, ValueError, AttributeError):
        return None


def _clean_stale_temps(out):
    """Remove what an interrupted run left behind: Rig.save's ``.autobones-*`` temporaries and
    a half-written report. ``.partial`` folders are kept: they mark files to redo."""
    for root, dirs, files in os.walk(out):
        dirs[:] = [d for d in dirs if not d.endswith(PARTIAL_SUFFIX)]
        for name in files:
            if name.startswith(".autobones-") or name.startswith(".batch_report-"):
                try:
                    os.unlink(os.path.join(root, name))
                except OSError:
                    pass


# ---------------------------------------------------------------------------------------------
# engines

def run_local(jobs, fn, argsets, on_result):
    """Run ``fn(*args)`` for every args tuple on ``jobs`` worker processes; ``on_result(i, record)``.

    At most ``jobs`` files are in flight, so when a worker dies (a crash in native
    code, the out-of-memory killer) the files it may have held are known: they are
    run again one at a time, and the one that kills a worker alone is reported
    failed. The batch goes on.
    """
    import multiprocessing
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
    from concurrent.futures.process import BrokenProcessPool

    ctx = multiprocessing.get_context("spawn")  # no inherited threads or BLAS state
    queue = list(range(len(argsets)))
    suspects = set()  # in flight when a worker died: rerun alone
    pool = None
    try:
        while queue:
            pool = ProcessPoolExecutor(max_workers=jobs, mp_context=ctx)
            running = {}
            broken = False
            while (queue or running) and not broken:
                while queue and len(running) < jobs:
                    nxt = queue[0]
                    if running and (nxt in suspects or suspects.intersection(running.values())):
                        break  # a suspect runs alone
                    queue.pop(0)
                    running[pool.submit(fn, *argsets[nxt])] = nxt
                done, _ = wait(running, return_when=FIRST_COMPLETED)
                for fut in done:
                    i = running.pop(fut)
                    try:
                        on_result(i, fut.result())
                    except BrokenProcessPool:
                        broken = True
                        if i in suspects:
                            on_result(i, _died_record(argsets[i]))
                        else:
                            suspects.add(i)
                            queue.insert(0, i)
            if broken:
                for fut, i in running.items():  # also lost with the pool
                    if i in suspects:
                        on_result(i, _died_record(argsets[i]))
                    else:
                        suspects.add(i)
                        queue.insert(0, i)
                log.warning("a worker process died; rerunning the files it may have held one at a time")
            pool.shutdown(wait=True, cancel_futures=True)
            pool = None
    finally:
        if pool is not None:
            pool.shutdown(wait=False, cancel_futures=True)


def _died_record(args):
    input_path, output_path, options = args
    shutil.rmtree(_partial_dir(output_path), ignore_errors=True)
    return {"input": input_path, "output": output_path, "status": "failed",
            "error": f"{input_path}: the worker process died on this file (a crash in native code or out of memory)",
            "error_type": "WorkerDied", "seconds": None, "timings": {}, "options_hash": options_hash(options)}


def run_dask(address, fn, argsets, on_result, paths=()):
    """Run ``fn(*args)`` on the Dask distributed scheduler at ``address``; ``on_result(i, record)``.

    Workers must see ``paths`` (input and output folders) at the same place: a
    shared file system. A task lost with its worker (after Dask's own retries) is
    a failed record, not a failed batch.
    """
    try:
        from distributed import Client, as_completed
    except ImportError:
        raise AutobonesError("--scheduler needs Dask distributed: pip install 'autobones[dask]'") from None
    try:
        client = Client(address)  # connect timeout: Dask config distributed.comm.timeouts.connect
    except (OSError, TimeoutError, ValueError) as exc:
        raise AutobonesError(f"cannot connect to the Dask scheduler at {address} ({type(exc).__name__}: {exc})") from None
    try:
        for path in paths:
            seen = client.run(os.path.isdir, path)
            blind = sorted(w for w, ok in seen.items() if not ok)
            if blind:
                raise AutobonesError(f"Dask worker{'s' if len(blind) > 1 else ''} {', '.join(blind)} cannot see "
                                     f"{path}; the input and output folders must be on a file system shared "
                                     f"by every worker, at the same path")
        if not argsets:
            return
        ins, outs, opts = zip(*argsets)
        futures = client.map(fn, ins, outs, opts, pure=False)
        index = {f.key: i for i, f in enumerate(futures)}
        for fut in as_completed(futures):
            i = index[fut.key]
            try:
                on_result(i, fut.result())
            except Exception as exc:  # KilledWorker, a worker without autobones...
                rec = _died_record(argsets[i])
                rec.update(error=_one_line(f"{argsets[i][0]}: the Dask task failed ({type(exc).__name__}: {exc})"),
                           error_type=type(exc).__name__)
                on_result(i, rec)
            fut.release()
    finally:
        client.close()


# ---------------------------------------------------------------------------------------------
# the batch

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
    """
    if int(jobs) < 1:
        raise AutobonesError(f"--jobs {jobs}: give at least 1 worker process")
    t0 = time.perf_counter()
    items = plan(input_dir, output_dir, options, force=force)
    inp, out = check_folders(input_dir, output_dir)
    os.makedirs(out, exist_ok=True)
    _clean_stale_temps(out)
    h = options_hash(options)
    to_run = [it for it in items if it.action == "run"]
    if on_start:
        on_start(len(to_run), sum(it.action == "skip" for it in items), sum(it.action == "fail" for it in items))
    for it in items:
        if it.action != "run":
            status = "skipped" if it.action == "skip" else "failed"
            it.record = {"input": it.input, "output": it.output, "status": status,
                         "error": it.reason if status == "failed" else None,
                         "error_type": "Refused" if status == "failed" else None,
                         "reason": it.reason if status == "skipped" else None,
                         "seconds": 0.0, "timings": {}, "options_hash": h}
            if on_result:
                on_result(_public(it.record, inp, out, options))

    def done(i, record):
        record = dict(record)
        if to_run[i].reason:
            record["reason"] = to_run[i].reason
        to_run[i].record = record
        if on_result:
            on_result(_public(record, inp, out, options))

    argsets = [(it.input, it.output, options) for it in to_run]
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
        "files": [_public(it.record, inp, out, options) for it in items],
    }
    write_report(os.path.join(out, REPORT_NAME), report)
    return report


def _version():
    from . import __version__

    return __version__


def _public(record, inp, out, options):
    """A record as the report shows it: paths relative to the folders, error naming the file."""
    rec = dict(record)
    rec.setdefault("options", options)
    rel_in = os.path.relpath(record["input"], inp).replace(os.sep, "/")
    rec["input"] = rel_in
    rec["output"] = os.path.relpath(record["output"], out).replace(os.sep, "/")
    if rec.get("landmarks") and rec["landmarks"] != "detected":
        rec["landmarks"] = os.path.relpath(rec["landmarks"], inp).replace(os.sep, "/")
    rec.pop("pid", None)
    err = rec.get("error")
    if err:
        err = err.replace(record["input"], rel_in).replace(inp + os.sep, "")
        base = os.path.basename(record["input"])
        if err.startswith(base + ":") and not err.startswith(rel_in):
            err = rel_in + err[len(base):]
        elif not err.startswith(rel_in):
            err = f"{rel_in}: {err}"
        rec["error"] = err
    return rec


def write_report(path, report):
    """Write the report as JSON through a temporary file renamed into place."""
    write_text_atomic(path, json.dumps(report, indent=1) + "\n", "the batch report")


def summary_table(report):
    """The end-of-batch table as text: one row per status with count and time, then the total."""
    rows = []
    for s in STATUSES:
        files = [f for f in report["files"] if f["status"] == s]
        secs = sum(f.get("seconds") or 0.0 for f in files)
        rows.append((s, str(len(files)), f"{secs:.1f} s"))
    rows.append(("total", str(len(report["files"])), f"{report['seconds']:.1f} s wall"))
    w = [max(len(r[k]) for r in rows + [("status", "files", "time")]) for k in range(3)]
    line = f"{'status':<{w[0]}}  {'files':>{w[1]}}  {'time':>{w[2]}}"
    out = [line, "-" * len(line)]
    for i, r in enumerate(rows):
        if i == len(rows) - 1:
            out.append("-" * len(line))
        out.append(f"{r[0]:<{w[0]}}  {r[1]:>{w[1]}}  {r[2]:>{w[2]}}")
    return "\n".join(out)
