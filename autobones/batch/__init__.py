"""``batch``: rig every mesh of a folder tree, resumably, on local processes or a Dask cluster.

One head is rigged by :func:`autobones.place` (the bone-placement method of ``place``) or
:func:`autobones.transfer` (Orvalho, Zacur & Susin 2008); this package rigs folders of them.
The work for one file is :func:`rig_one`, a pure function of (input path, output path,
options): it runs :func:`autobones.place` or :func:`autobones.transfer`, writes the
glb and its two sidecars atomically, and returns a plain dict record. It never raises
for a bad file, so any engine can run it: :func:`run_batch` sends it to a
``concurrent.futures.ProcessPoolExecutor`` (``jobs``) or to a Dask distributed
cluster (``scheduler``), and writes ``batch_report.json``.

Layout: ``INPUT/a/b.obj`` -> ``OUTPUT/a/b.rig.glb``, ``OUTPUT/a/b.rig.json``,
``OUTPUT/a/b.weights.npz`` (the names ``place`` and ``transfer`` give). The output folder may not
overlap the input folder, and no output may resolve (through a symbolic link) inside it. One batch
at a time writes into an output folder (:mod:`.lock`), and local workers die with the batch
(:mod:`.workers`).

Resuming: a file is skipped when its three outputs exist, are newer than the mesh
(and its landmark file), and the sidecar records the same options hash
(``batch.options_hash`` in ``.rig.json``). One is written as: ``rig.save`` into a
hidden folder ``.NAME.rig.glb.partial`` beside the target, then glb, npz and last the
sidecar are renamed into place and the folder removed. A ``.partial`` folder left
behind marks a file whose write was interrupted (kill -9): it is rigged again.
Outputs that exist but are out of date or were written with other options are
overwritten only with ``force=True``. Batches before the ``.rig.glb`` name wrote ``NAME.glb``
beside the same sidecars: such a folder is rigged again once, and each old glb removed
when its new one is written.

Modules: :mod:`.jobs` (options, naming, the per-file job), :mod:`.planning` (walking the
folders, what to run or skip), :mod:`.engines` (local processes, Dask), :mod:`.report`
(the report and the summary table), :mod:`.runner` (:func:`run_batch`), :mod:`.lock` (the output
folder's lock), :mod:`.workers` (tying workers to the batch).
"""
from .engines import run_dask, run_local
from .jobs import (LANDMARK_SUFFIXES, OUTPUT_SUFFIX, PARTIAL_SUFFIX, landmarks_for, make_options, options_hash,
                   output_for, output_paths, rig_one)
from .planning import Item, check_folders, find_meshes, plan
from .report import REPORT_FORMAT, REPORT_NAME, STATUSES, summary_table, write_report
from .runner import run_batch

__all__ = ["LANDMARK_SUFFIXES", "OUTPUT_SUFFIX", "PARTIAL_SUFFIX", "REPORT_FORMAT", "REPORT_NAME", "STATUSES",
           "Item", "check_folders", "find_meshes", "landmarks_for", "make_options", "options_hash", "output_for",
           "output_paths", "plan", "rig_one", "run_batch", "run_dask", "run_local", "summary_table", "write_report"]
