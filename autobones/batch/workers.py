"""Local batch workers that die with the batch process (issue #33).

``kill -9`` of a batch left its worker processes (and multiprocessing's resource tracker, which
waits for every holder of its pipe to go) running for 90 s and more: a worker only notices its
parent is gone when it next talks to it, so it finished its file and renamed the outputs after
the kill, and a rerun started meanwhile raced it on the same files.

So each worker, as it starts (:func:`init_worker`, the pool's initializer):

- on Linux asks the kernel for SIGKILL when its parent goes (``prctl(PR_SET_PDEATHSIG)``
  through ctypes: no extra dependency, and the signal comes even while the worker is deep in
  native code holding the GIL). The kernel sends it when the *thread* that spawned the worker
  exits: ``ProcessPoolExecutor`` (3.9+) spawns from ``submit``, called by the thread running
  :func:`~autobones.batch.engines.run_local`, which outlives the pool; for the CLI that is the
  main thread, so the signal comes at the process's own end;
- checks its parent once right after (a parent killed before the ``prctl`` is not signalled);
- elsewhere (macOS has no PDEATHSIG) polls ``os.getppid()`` from a daemon thread;
- and :func:`exit_if_orphaned`, called by the job just before it renames its outputs, makes
  sure an orphan never renames anything, whatever the platform.

The resource tracker then sees its pipe close and exits by itself.

Dask workers are not children of the batch: the cluster is the user's and outlives it, and a
task already running in a worker thread cannot be stopped. When the batch (the client) is
killed the scheduler releases its tasks, and the worker marks a running one ``cancelled``;
:func:`dask_task_cancelled` reads that just before the renames, so such a task ends without
writing (measured: without it, 2 more rigs were renamed 0.5 to 6.1 s after the kill; with it, none).
"""
from __future__ import annotations

import os
import sys
import threading
import time

PR_SET_PDEATHSIG = 1  # <linux/prctl.h>
POLL_SECONDS = 0.5

_parent = None  # the batch's pid in a local worker; None anywhere else (the batch itself, a Dask worker)


def init_worker(parent_pid):
    """The local pool's initializer: tie this worker's life to ``parent_pid`` (the batch)."""
    global _parent
    _parent = int(parent_pid)
    if sys.platform.startswith("linux"):
        try:
            import ctypes
            import signal

            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0)
        except (OSError, AttributeError):  # no libc symbol (an unusual libc): the poll below still works
            pass
    exit_if_orphaned()
    threading.Thread(target=_watch, name="autobones-parent-watch", daemon=True).start()


def _watch():
    while True:
        time.sleep(POLL_SECONDS)
        exit_if_orphaned()


def exit_if_orphaned():
    """End this process at once when it is a local batch worker whose batch is gone.

    ``os._exit``: no cleanup handlers, nothing more written; a ``.partial`` folder left behind
    marks the file to redo on the next run."""
    if _parent is not None and os.getppid() != _parent:
        os._exit(1)


def dask_task_cancelled():
    """True inside a Dask task that its client no longer wants (the batch was killed, or released it).

    False outside a Dask worker, and whenever the worker's state cannot be read (its internals
    change between versions: then the task writes as it always did, which is safe, only late)."""
    distributed = sys.modules.get("distributed")
    if distributed is None:  # never imported in this process: not a Dask worker
        return False
    try:
        worker = distributed.get_worker()
    except ValueError:  # "No worker found": the client side, or a local worker that imported distributed
        return False
    try:
        ts = worker.state.tasks.get(worker.get_current_task())
    except Exception:  # noqa: BLE001  (any change of Dask's internals: fall back to writing)
        return False
    return ts is None or ts.state in ("cancelled", "released", "forgotten")
