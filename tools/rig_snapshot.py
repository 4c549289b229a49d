#!/usr/bin/env python
"""Snapshot the CLI's outputs on the shared heads, and compare two snapshots: a refactor check.

A refactor must not change behaviour. This tool runs a fixed list of ``autobones`` CLI jobs
(place, transfer, pose, landmarks, batch, build-rig) on the shared heads with the OLD code and
with the NEW code, and compares every file written, by content, to 1e-10 of the head size.

Usage (from the repository root)::

    # 1. the old code (a git worktree of the reference commit, e.g. /work/baseline at 94329a9)
    python tools/rig_snapshot.py run /work/snapshots/old --expect-src /work/baseline \\
        --cli "env PYTHONPATH=/work/baseline python -c 'import sys; from cli.main import main; sys.exit(main())'"
    # 2. the new code (the installed console script, or python -m autobones once it exists)
    python tools/rig_snapshot.py run /work/snapshots/new --expect-src /work/main --cli autobones
    # 3. compare: a table, exit 0 when every file agrees within 1e-10 of its head size, 1 otherwise
    python tools/rig_snapshot.py compare /work/snapshots/old /work/snapshots/new

``run OUTDIR --cli PREFIX``
    PREFIX is split with shlex and the job's arguments appended (no shell). Every job runs in its
    own folder ``OUTDIR/<job>/`` (the current directory of the CLI, so default output names are
    exercised too); its stdout/stderr go to ``OUTDIR/_logs/<job>.out|.err``; the batch jobs' input
    folder is ``OUTDIR/_inputs/``. ``OUTDIR/jobs.json`` records each job's name, argv, exit code,
    expected exit code, wall seconds and the input mesh (for the head size). Jobs run one after
    the other; a failing job is recorded and the run goes on (a pose job whose transfer failed
    fails too). OUTDIR must be new or empty, or an earlier snapshot (it has ``jobs.json`` or ``provenance.json``):
    that is deleted first. Exit code 0 when every job exited as expected, 1 otherwise.

    Which code ran: before the jobs, ``PREFIX --version`` is run once with ``PYTHONVERBOSE=1``;
    the interpreter's import trace names the file each module was loaded from, so the check goes
    through exactly the same prefix (env, bootstrap, console script) as the jobs. The files of
    ``autobones`` and ``cli.main`` are written to ``OUTDIR/provenance.json`` and printed;
    ``--expect-src DIR`` stops the run when ``autobones`` was not imported from under DIR.

    Shadowing: this machine has an editable install of /work/main (a ``__editable__...finder``
    appended to ``sys.meta_path`` by a .pth file). ``PYTHONPATH=/work/baseline`` still wins,
    because ``PYTHONPATH`` entries are searched by the normal ``PathFinder``, which comes before the
    editable finder in ``sys.meta_path``; checked (provenance.json of the old snapshot names
    /work/baseline/autobones/__init__.py and /work/baseline/cli/main.py). Batch worker processes
    inherit the environment, so they import the same code. Beware the current folder: ``python -c``
    puts it FIRST on sys.path, before PYTHONPATH, so the old prefix run from /work/main imports
    /work/main's ``cli`` (found while writing this tool). Every job, and the check, therefore runs
    in a folder under OUTDIR, never in a source tree. Were it ever shadowed, a bootstrap that
    puts the tree first and drops the editable finders would do::

        --cli "python -c 'import sys; sys.path.insert(0, \\"/work/baseline\\"); \\
               sys.meta_path[:] = [f for f in sys.meta_path if \\"editable\\" not in repr(f)]; \\
               from cli.main import main; sys.exit(main())'"

    (plus PYTHONPATH for the batch's worker processes).

    Inputs: the heads under ``--data`` (default ``<repo>/../shared/data``), and the frozen
    reference files under ``--ref`` (default: this checkout): the goat and robot landmark files
    (``tests/landmarks/``) and the default head + landmarks for ``build-rig``
    (``generic_rig/default_head.obj``, ``.landmarks.json``). Both snapshots must use the same
    ``--data`` and ``--ref`` so the inputs are the same bytes.

    build-rig: ``generic_rig/build_default_rig.py`` calls ``build_rig(V, F, landmarks)`` on the
    default head and then sets two metadata strings (``rig.units``, ``rig.frame``) before
    ``rig.save``; the CLI job ``build-rig default_head.obj --landmarks default_head.landmarks.json
    -o rig/`` is the same computation without those two strings (so its rig.json is not
    byte-equal to ``generic_rig/default/rig.json``, but old and new CLI outputs are comparable).

``compare OLD_DIR NEW_DIR``
    Every file under either snapshot is compared with its namesake, by content; exit 0 when every
    file agrees within 1e-10 of its head size (``--tol``) and the job exit codes agree, 1 otherwise.
    What is compared, what is ignored as run-dependent and how the head size is found:
    ``tools/snapshot_compare.py``.

Modules: this file is the CLI (options, the job list, provenance, ``run``); ``snapshot_compare.py``
holds ``compare`` and ``snapshot_readers.py`` the hand-written glb/obj readers it uses. tools/ is
not a package, so they are imported from this file's folder.

Dependencies: numpy only (the GLB container is parsed by hand).
"""
from __future__ import annotations

import argparse
import json
import os
import re
import shlex
import shutil
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
DEFAULT_DATA = os.path.normpath(os.path.join(REPO, "..", "shared", "data"))
DEFAULT_REF = REPO  # this checkout; pass the same --ref to both runs

# tools/ is not a package: the compare half is a sibling file, found through this folder (as benchmarks/zoo.py does)
sys.path.insert(0, HERE)
from snapshot_compare import cmd_compare, files_under  # noqa: E402


# ---------------------------------------------------------------------------------------------
# jobs

def job_list(data, ref):
    """``[(name, args, head_mesh_or_None, expected_exit_code)]``; args relative to OUTDIR/<name>/."""
    ict = os.path.join(data, "ict")
    menpo = os.path.join(data, "menpo3d")
    misc = os.path.join(data, "misc")
    tl = os.path.join(ref, "tests", "landmarks")
    gr = os.path.join(ref, "generic_rig")
    ict0, ict1, ict2 = (os.path.join(ict, f"identity00{i}.obj") for i in range(3))
    james = os.path.join(menpo, "james.obj")
    lps = os.path.join(misc, "LeePerrySmith.obj")
    goat = os.path.join(misc, "goathead.obj")
    robot = os.path.join(misc, "robot_head_neutral.obj")
    fran = os.path.join(misc, "fran_cut.obj")
    lm = {"ict1": os.path.join(ict, "identity001.landmarks.json"),
          "ict2": os.path.join(ict, "identity002.landmarks.json"),
          "james": os.path.join(menpo, "james.landmarks.json"),
          "goat": os.path.join(tl, "goathead.landmarks.json"),
          "robot": os.path.join(tl, "robot_head_neutral.landmarks.json")}
    tr = {k: os.path.join("..", f"transfer_{k}", f"{k}.glb") for k in ("ict2", "ict1", "james", "goat", "robot")}
    jobs = [
        ("place_default", ["place"], None, 0),  # default output name default_head.rig.glb
        ("place_default_dense", ["place", "--density", "dense", "-o", "default_head_dense.glb"], None, 0),
        ("place_ict0", ["place", ict0, "-o", "ict0.glb"], ict0, 0),
        ("place_james", ["place", james, "-o", "james.glb"], james, 0),
        ("place_james_dense", ["place", james, "--density", "dense", "-o", "james_dense.glb"], james, 0),
        ("place_lps", ["place", lps, "-o", "lps.glb"], lps, 0),
        ("place_goat", ["place", goat, "-o", "goat.glb"], goat, 0),
        ("place_robot", ["place", robot, "-o", "robot.glb"], robot, 0),
        ("place_fran", ["place", fran, "-o", "fran.glb"], fran, 0),
        ("place_landmarks_ict2", ["place", ict2, "--landmarks", lm["ict2"], "-o", "ict2.glb"], ict2, 0),
        ("transfer_ict2", ["transfer", ict2, "--landmarks", lm["ict2"], "--expressions", "-o", "ict2.glb"], ict2, 0),
        ("transfer_ict1", ["transfer", ict1, "--landmarks", lm["ict1"], "--expressions", "-o", "ict1.glb"], ict1, 0),
        ("transfer_james", ["transfer", james, "--landmarks", lm["james"], "--expressions", "-o", "james.glb"],
         james, 0),
        ("transfer_goat", ["transfer", goat, "--landmarks", lm["goat"], "--expressions", "-o", "goat.glb"], goat, 0),
        ("transfer_robot", ["transfer", robot, "--landmarks", lm["robot"], "--expressions", "-o", "robot.glb"],
         robot, 0),
        ("transfer_ict0_auto", ["transfer", ict0, "-o", "ict0.glb"], ict0, 0),  # landmarks found by MediaPipe
        ("pose_ict2_fear", ["pose", tr["ict2"], "--expression", "fear", "-o", "fear.obj"], ict2, 0),
        ("pose_goat_happiness", ["pose", tr["goat"], "--expression", "happiness", "-o", "happiness.obj"], goat, 0),
        ("pose_james_au12L_gaze", ["pose", tr["james"], "--au", "12L=1", "--gaze", "20,0", "-o", "smirk.obj"],
         james, 0),
        ("pose_robot_jaw_au43", ["pose", tr["robot"], "--jaw", "10", "--au", "43=1", "-o", "jaw.obj"], robot, 0),
        ("pose_ict1_happiness_glb", ["pose", tr["ict1"], "--expression", "happiness", "-o", "happiness.glb"],
         ict1, 0),
        ("landmarks_lps", ["landmarks", lps, "-o", "lps.landmarks.json"], lps, 0),
        ("landmarks_james", ["landmarks", james, "-o", "james.landmarks.json"], james, 0),
        ("landmarks_ict0", ["landmarks", ict0, "-o", "ict0.landmarks.json"], ict0, 0),
        # no -o: the default name goathead.landmarks.json
        ("landmarks_goat_from", ["landmarks", goat, "--from", lm["goat"]], goat, 0),
        ("batch_place", ["batch", os.path.join("..", "_inputs", "batch_heads"), "-o", "out", "--jobs", "1"], None, 0),
        ("batch_transfer", ["batch", os.path.join("..", "_inputs", "batch_heads"), "-o", "out", "--transfer"], None, 0),
        ("build_rig_default", ["build-rig", os.path.join(gr, "default_head.obj"), "--landmarks",
                               os.path.join(gr, "default_head.landmarks.json"), "-o", "rig"],
         os.path.join(gr, "default_head.obj"), 0),
    ]
    batch_inputs = [(goat, "goathead.obj"), (lm["goat"], "goathead.landmarks.json"),
                    (robot, "robot_head_neutral.obj"), (lm["robot"], "robot_head_neutral.landmarks.json")]
    return jobs, batch_inputs


def provenance(prefix, env, cwd):
    """Run ``PREFIX --version`` with PYTHONVERBOSE=1 in ``cwd`` and read from the import trace where modules
    came from (``cwd`` matters: ``python -c`` puts the current folder first on sys.path)."""
    e = dict(env, PYTHONVERBOSE="1")
    p = subprocess.run(prefix + ["--version"], capture_output=True, text=True, env=e, timeout=300, cwd=cwd)
    found = {}
    pats = {"autobones": r"autobones[/\\]__init__\.py", "cli.main": r"cli[/\\]main\.py"}
    for line in p.stderr.splitlines():
        for mod, pat in pats.items():
            if mod in found:
                continue
            # "# /x/autobones/__pycache__/__init__.cpython-311.pyc matches /x/autobones/__init__.py"
            # or "# code object from /x/autobones/__init__.py" (no cache; quoted in some versions)
            m = (re.search(r"matches (\S*" + pat + r")\s*$", line)
                 or re.search(r"code object from '?(\S*?" + pat + r")'?\s*$", line))
            if m:
                found[mod] = os.path.realpath(m.group(1))
    return {"prefix": prefix, "version_output": p.stdout.strip(), "exit_code": p.returncode,
            "modules": found}


def cmd_run(args):
    prefix = shlex.split(args.cli)
    out = os.path.abspath(args.outdir)
    data, ref = os.path.abspath(args.data), os.path.abspath(args.ref)
    if os.path.exists(out) and os.listdir(out):
        if not any(os.path.exists(os.path.join(out, f)) for f in ("jobs.json", "provenance.json")):
            print(f"rig_snapshot: {out} is not empty and not a snapshot (no jobs.json); refusing to overwrite",
                  file=sys.stderr)
            return 2
        shutil.rmtree(out)
    os.makedirs(os.path.join(out, "_logs"), exist_ok=True)
    env = dict(os.environ)

    prov = provenance(prefix, env, cwd=os.path.join(out, "_logs"))
    with open(os.path.join(out, "provenance.json"), "w", encoding="utf-8") as fh:
        json.dump(prov, fh, indent=1)
    print(f"code: {prov['version_output'] or '(no --version output)'}; "
          + ", ".join(f"{k} from {v}" for k, v in prov["modules"].items()))
    if args.expect_src:
        src = os.path.realpath(args.expect_src)
        got = prov["modules"].get("autobones")
        if got is None or os.path.commonpath([src, got]) != src:
            print(f"rig_snapshot: autobones was imported from {got}, not from under {src}; stopping",
                  file=sys.stderr)
            return 2

    jobs, batch_inputs = job_list(data, ref)
    if args.only:
        keep = set(args.only.split(","))
        jobs = [j for j in jobs if j[0] in keep]
    bdir = os.path.join(out, "_inputs", "batch_heads")
    os.makedirs(bdir, exist_ok=True)
    for src, name in batch_inputs:
        shutil.copyfile(src, os.path.join(bdir, name))

    records, t_all = [], time.perf_counter()
    for name, jargs, head, expect in jobs:
        cwd = os.path.join(out, name)
        os.makedirs(cwd, exist_ok=True)
        argv = prefix + jargs
        t = time.perf_counter()
        with open(os.path.join(out, "_logs", name + ".out"), "w") as so, \
                open(os.path.join(out, "_logs", name + ".err"), "w") as se:
            try:
                rc = subprocess.run(argv, cwd=cwd, stdout=so, stderr=se, env=env, timeout=args.timeout).returncode
            except subprocess.TimeoutExpired:
                rc = "timeout"
        dt = time.perf_counter() - t
        rec = {"name": name, "argv": argv, "cwd": cwd, "exit_code": rc, "expected_exit_code": expect,
               "seconds": round(dt, 2), "head": head, "outputs": sorted(files_under(cwd, cwd))}
        records.append(rec)
        flag = "ok" if rc == expect else "UNEXPECTED"
        print(f"{name:28s} exit {rc!s:>7s} {dt:7.1f} s  {flag}  ({len(rec['outputs'])} files)", flush=True)
        _write_jobs(out, prov, records, time.perf_counter() - t_all, partial=True)
    total = time.perf_counter() - t_all
    _write_jobs(out, prov, records, total, partial=False)
    bad = [r["name"] for r in records if r["exit_code"] != r["expected_exit_code"]]
    print(f"{len(records)} jobs in {total:.1f} s; " + (f"unexpected exit codes: {', '.join(bad)}" if bad else
                                                       "every exit code as expected"))
    return 1 if bad else 0


def _write_jobs(out, prov, records, total, partial):
    doc = {"format": "rig-snapshot-jobs/1", "cli": prov["prefix"], "modules": prov["modules"],
           "complete": not partial, "total_seconds": round(total, 2), "jobs": records}
    with open(os.path.join(out, "jobs.json"), "w", encoding="utf-8") as fh:
        json.dump(doc, fh, indent=1)


def main(argv=None):
    ap = argparse.ArgumentParser(description="Snapshot the autobones CLI's outputs on the shared heads; compare two "
                                             "snapshots (see the module docstring).")
    sub = ap.add_subparsers(dest="mode", required=True)
    r = sub.add_parser("run", help="run the jobs, write every output under OUTDIR")
    r.add_argument("outdir", metavar="OUTDIR")
    r.add_argument("--cli", default="autobones", help='command prefix of the CLI (default "autobones")')
    r.add_argument("--expect-src", metavar="DIR", help="stop unless autobones is imported from under DIR")
    r.add_argument("--data", default=DEFAULT_DATA, help=f"shared heads folder (default {DEFAULT_DATA})")
    r.add_argument("--ref", default=DEFAULT_REF,
                   help=f"frozen reference tree for the goat/robot landmark files and the default head of build-rig "
                        f"(default {DEFAULT_REF})")
    r.add_argument("--only", metavar="NAMES", help="comma-separated job names to run (default: all)")
    r.add_argument("--timeout", type=float, default=1800, help="seconds per job (default 1800)")
    c = sub.add_parser("compare", help="compare two snapshots")
    c.add_argument("old", metavar="OLD_DIR")
    c.add_argument("new", metavar="NEW_DIR")
    c.add_argument("--tol", type=float, default=1e-10, help="allowed max difference / head size (default 1e-10)")
    c.add_argument("--max-details", type=int, default=8, help="problems listed per offending file (default 8)")
    c.add_argument("-v", "--verbose", action="store_true", help="also note files within tolerance but not identical")
    args = ap.parse_args(argv)
    return cmd_run(args) if args.mode == "run" else cmd_compare(args)


if __name__ == "__main__":
    sys.exit(main())
