"""Engines of a batch: run the per-file job on local worker processes or on a Dask distributed cluster."""
from __future__ import annotations

import logging
import os
import shutil

from ..errors import AutobonesError
from .jobs import one_line, options_hash, partial_dir
from .workers import init_worker

log = logging.getLogger("autobones")


def run_local(jobs, fn, argsets, on_result):
    """Run ``fn(*args)`` for every args tuple on ``jobs`` worker processes; ``on_result(i, record)``.

    At most ``jobs`` files are in flight, so when a worker dies (a crash in native
    code, the out-of-memory killer) the files it may have held are known: they are
    run again one at a time, and the one that kills a worker alone is reported
    failed. The batch goes on. Workers die with this process (:mod:`.workers`): a batch killed
    with ``kill -9`` leaves none behind.
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
            pool = ProcessPoolExecutor(max_workers=jobs, mp_context=ctx, initializer=init_worker,
                                       initargs=(os.getpid(),))
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
    input_path, output_path, options = args[:3]
    shutil.rmtree(partial_dir(output_path), ignore_errors=True)
    return {"input": input_path, "output": output_path, "status": "failed",
            "error": f"{input_path}: the worker process died on this file (a crash in native code or out of memory)",
            "error_type": "WorkerDied", "seconds": None, "timings": {}, "options_hash": options_hash(options)}


def need_dask():
    """AutobonesError, with the install line, when Dask distributed is not installed."""
    try:
        import distributed  # noqa: F401
    except ImportError:
        raise AutobonesError("--scheduler needs Dask distributed: pip install 'autobones[dask]'") from None


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
        futures = client.map(fn, *zip(*argsets), pure=False)
        index = {f.key: i for i, f in enumerate(futures)}
        for fut in as_completed(futures):
            i = index[fut.key]
            try:
                on_result(i, fut.result())
            except Exception as exc:  # KilledWorker, a worker without autobones...
                rec = _died_record(argsets[i])
                rec.update(error=one_line(f"{argsets[i][0]}: the Dask task failed ({type(exc).__name__}: {exc})"),
                           error_type=type(exc).__name__)
                on_result(i, rec)
            fut.release()
    finally:
        client.close()
