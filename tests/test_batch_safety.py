"""``autobones batch`` against its own surroundings (issue #33): an output folder linked into the input,
``kill -9`` of the batch process alone, and two batches started at once into one folder.

The heads are four small robot heads (1.3k vertices each, ~1 s a rig at ``--density sparse``): the
kill and race tests need a batch that runs for several seconds, not a large one.
"""
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from autobones.batch import REPORT_NAME
from autobones.errors import AutobonesError
from bad_inputs import snapshot
from shared_data import ROOT, data

CLI = [sys.executable, "-m", "cli.main"]
HEADS = ["misc/robot_head_neutral.obj", "misc/robot_head_Angry.obj", "misc/robot_head_Sad.obj",
         "misc/robot_head_Surprised.obj"]
ARGS = ["--density", "sparse"]


def _env():
    return dict(os.environ, PYTHONPATH=str(ROOT))


def run(args, **kw):
    return subprocess.run(CLI + args, cwd=ROOT, env=_env(), capture_output=True, text=True, timeout=600, **kw)


def outputs(folder):
    """{relative path: bytes} of every file under ``folder`` but the report (hidden ones included)."""
    folder = Path(folder)
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file() and p.name != REPORT_NAME}


def _rigs_written(folder):
    """Whether a sidecar is in ``folder`` yet, looked at while the batch writes: a ``.partial`` folder it
    renames or removes during the walk is a "not yet" (the walk raised FileNotFoundError, a flake)."""
    try:
        return bool(list(Path(folder).rglob("*.rig.json")))
    except FileNotFoundError:
        return False


def make_heads(root, names=HEADS):
    for rel in names:
        dst = Path(root) / "sub" / Path(rel).name
        dst.parent.mkdir(parents=True, exist_ok=True)
        dst.write_bytes(data(rel).read_bytes())
    return Path(root)


@pytest.fixture(scope="module")
def heads_and_clean(tmp_path_factory):
    """The four heads and an uninterrupted run of them: the reference bytes."""
    base = tmp_path_factory.mktemp("safety")
    heads = make_heads(base / "heads")
    r = run(["batch", str(heads), "-o", str(base / "clean"), *ARGS, "--jobs", "2"])
    assert r.returncode == 0, r.stderr
    return heads, base / "clean"


# --------------------------------------------------------------------------------------------------
# processes, from /proc

def _stat(pid):
    """(state, ppid, pgrp, session, start time) of ``pid`` from /proc, or None when it is gone."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    f = text[text.rindex(")") + 2:].split()
    return f[0], int(f[1]), int(f[2]), int(f[3]), int(f[19])


def _all_pids():
    return [int(p) for p in os.listdir("/proc") if p.isdigit()]


def descendants(pid):
    """{pid: start time} of the live processes whose parent chain reaches ``pid``."""
    parent = {}
    for p in _all_pids():
        s = _stat(p)
        if s is not None:
            parent[p] = (s[1], s[4])
    found = {}
    for p in parent:
        q = p
        while q in parent and q > 1:
            q = parent[q][0]
            if q == pid:
                found[p] = parent[p][1]
                break
    return found


def left_of(batch_pid, known):
    """Live (not zombie) processes of the batch: in its session or process group (the test started it
    in a session of its own), or one of ``known`` (its descendants before the kill) still running."""
    left = []
    for p in _all_pids():
        s = _stat(p)
        if s is None or s[0] == "Z" or p == batch_pid:
            continue
        if s[2] == batch_pid or s[3] == batch_pid or known.get(p) == s[4]:
            left.append(p)
    return left


# --------------------------------------------------------------------------------------------------
# 1. an output linked into the input

@pytest.mark.parametrize("link", ["subfolder", "file_onto_input", "file_into_input", "report"])
@pytest.mark.parametrize("force", [False, True])
def test_an_output_linked_into_the_input_is_refused_and_the_input_untouched(tmp_path, link, force):
    heads = make_heads(tmp_path / "in", HEADS[:1])
    name = Path(HEADS[0]).name
    (heads / "sub" / "scan.glb").write_bytes(data(HEADS[0]).read_bytes())  # a glb-named input... an OBJ
    out = tmp_path / "out"
    (out / "sub").mkdir(parents=True)
    if link == "subfolder":  # the case: OUT/sub -> INPUT/sub
        (out / "sub").rmdir()
        (out / "sub").symlink_to(heads / "sub", target_is_directory=True)
    elif link == "file_onto_input":  # the rig's final name is a link to an input file
        (out / "sub" / Path(name).with_suffix(".rig.glb")).symlink_to(heads / "sub" / name)
    elif link == "file_into_input":  # a sidecar's final name is a link to a new name in the input folder
        (out / "sub" / Path(name).with_suffix(".rig.json")).symlink_to(heads / "sub" / "new.rig.json")
    else:
        (out / REPORT_NAME).symlink_to(heads / "sub" / REPORT_NAME)
    before_in, before_out = snapshot(heads), snapshot(out)
    r = run(["batch", str(heads), "-o", str(out), *ARGS] + (["--force"] if force else []))
    assert r.returncode == 2, (r.returncode, r.stderr)
    lines = r.stderr.splitlines()
    assert len(lines) == 1 and "inside the input folder" in lines[0] and "Traceback" not in r.stderr, r.stderr
    assert snapshot(heads) == before_in  # byte-identical, nothing added
    assert snapshot(out) == before_out


@pytest.mark.slow  # over 20 s (measured); `-m "not slow"` leaves it out
def test_a_link_to_a_folder_outside_the_input_is_followed(tmp_path, heads_and_clean):
    heads, clean = heads_and_clean
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    out = tmp_path / "out"
    out.mkdir()
    (out / "sub").symlink_to(elsewhere, target_is_directory=True)
    r = run(["batch", str(heads), "-o", str(out), *ARGS])
    assert r.returncode == 0, r.stderr
    assert outputs(elsewhere) == {k[len("sub/"):]: v for k, v in outputs(clean).items()}


def test_a_job_resolves_its_outputs_again_before_writing(tmp_path):
    """A link made after the plan (here: before rig_one is called directly) is refused by the job itself."""
    from autobones.batch import make_options, rig_one

    heads = make_heads(tmp_path / "in", HEADS[:1])
    out = tmp_path / "out"
    out.mkdir()
    (out / "sub").symlink_to(heads / "sub", target_is_directory=True)
    name = Path(HEADS[0]).name
    before = snapshot(heads)
    rec = rig_one(str(heads / "sub" / name), str(out / "sub" / Path(name).with_suffix(".rig.glb")),
                  make_options(density="sparse"), str(heads))
    assert rec["status"] == "failed" and "inside the input folder" in rec["error"], rec
    assert snapshot(heads) == before


def test_an_atomic_write_replaces_a_link_at_its_name_never_its_target(tmp_path):
    from autobones.io.atomic import replace_all, temp_beside, write_bytes_atomic

    precious = tmp_path / "input.obj"
    precious.write_bytes(b"v 0 0 0\n")
    link = tmp_path / "out.glb"
    link.symlink_to(precious)
    write_bytes_atomic(link, b"new")
    assert precious.read_bytes() == b"v 0 0 0\n" and not link.is_symlink() and link.read_bytes() == b"new"
    # a group whose second rename fails puts the first target back as it was: the link, not a copy
    link.unlink()
    link.symlink_to(precious)
    fd, tmp = temp_beside(link)
    os.write(fd, b"rig")
    os.close(fd)
    with pytest.raises(AutobonesError):
        replace_all([(tmp, link), (str(tmp_path / "missing-temp"), tmp_path / "b.json")])
    assert link.is_symlink() and os.readlink(link) == str(precious) and precious.read_bytes() == b"v 0 0 0\n"


# --------------------------------------------------------------------------------------------------
# 2. kill -9 of the batch process alone

@pytest.mark.slow  # over 20 s (measured); `-m "not slow"` leaves it out
def test_kill_9_of_the_batch_leaves_no_process_and_a_rerun_is_byte_identical(tmp_path, heads_and_clean):
    heads, clean = heads_and_clean
    out = tmp_path / "rigs"
    proc = subprocess.Popen(CLI + ["batch", str(heads), "-o", str(out), *ARGS, "--jobs", "2"], cwd=ROOT,
                            env=_env(), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    try:
        # the workers are busy once a first rig is complete: the other worker is inside one
        deadline = time.monotonic() + 300
        while not _rigs_written(out) and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.02)
        known = descendants(proc.pid)
        os.kill(proc.pid, signal.SIGKILL)  # the batch process only, as `kill -9 PID` does
        proc.wait()
        assert proc.returncode == -signal.SIGKILL, "the batch finished before it could be killed"
        assert len(known) >= 2, known  # its workers (and multiprocessing's resource tracker) were running
        deadline = time.monotonic() + 5
        while left_of(proc.pid, known) and time.monotonic() < deadline:
            time.sleep(0.05)
        left = left_of(proc.pid, known)
    finally:
        for p in left_of(proc.pid, {}):  # never leave them to other tests
            os.kill(p, signal.SIGKILL)
    assert left == [], f"processes of the killed batch still running after 5 s: {left}"
    assert not (out / REPORT_NAME).exists()
    r = run(["batch", str(heads), "-o", str(out), *ARGS, "--jobs", "2"])
    assert r.returncode == 0, r.stderr
    got, ref = outputs(out), outputs(clean)
    assert sorted(got) == sorted(ref)  # same files: no temporaries, no lock file left
    assert [k for k in ref if got[k] != ref[k]] == []


PARENT = """
import os, sys, time
from concurrent.futures import ProcessPoolExecutor
import multiprocessing

def init(parent):
    from autobones.batch.workers import init_worker
    platform, sys.platform = sys.platform, "darwin"  # as on macOS: no PR_SET_PDEATHSIG, the poll alone
    try:
        init_worker(parent)
    finally:
        sys.platform = platform

def work(path):
    with open(path + ".tmp", "w") as fh:
        fh.write(str(os.getpid()))
    os.replace(path + ".tmp", path)
    time.sleep(120)

if __name__ == "__main__":
    pool = ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn"), initializer=init,
                               initargs=(os.getpid(),))
    pool.submit(work, sys.argv[1])
    time.sleep(300)
"""


def test_without_pdeathsig_a_worker_still_ends_with_its_parent(tmp_path):
    script, pidfile = tmp_path / "parent.py", tmp_path / "worker.pid"
    script.write_text(PARENT)
    proc = subprocess.Popen([sys.executable, str(script), str(pidfile)], cwd=ROOT, env=_env(),
                            start_new_session=True)
    try:
        deadline = time.monotonic() + 120
        while not pidfile.exists() and time.monotonic() < deadline and proc.poll() is None:
            time.sleep(0.05)
        worker = int(pidfile.read_text())
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
        deadline = time.monotonic() + 5
        while _stat(worker) not in (None,) and _stat(worker)[0] != "Z" and time.monotonic() < deadline:
            time.sleep(0.05)
        state = _stat(worker)
    finally:
        for p in left_of(proc.pid, {}):
            os.kill(p, signal.SIGKILL)
    assert state is None or state[0] == "Z", f"the worker {worker} still runs 5 s after its parent was killed"


def _wait_then_answer(flag, started, answer):
    """A Dask task: says it started, waits for ``flag``, then writes what dask_task_cancelled() says."""
    from autobones.batch.workers import dask_task_cancelled

    Path(started).touch()
    deadline = time.monotonic() + 60
    while not os.path.exists(flag) and time.monotonic() < deadline:
        time.sleep(0.02)
    Path(answer).write_text(str(dask_task_cancelled()))


def test_a_dask_task_knows_when_its_batch_is_gone(tmp_path):
    import distributed

    from autobones.batch.workers import dask_task_cancelled

    assert dask_task_cancelled() is False  # the client side
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        worker = next(iter(cluster.workers.values()))
        futs = {}
        for name in ("kept", "cancelled"):
            args = [str(tmp_path / f"{name}.{k}") for k in ("flag", "started", "answer")]
            futs[name] = (client.submit(_wait_then_answer, *args, pure=False), args)
        deadline = time.monotonic() + 60
        while not all(Path(a[1]).exists() for _, a in futs.values()) and time.monotonic() < deadline:
            time.sleep(0.02)
        fut, args = futs["cancelled"]
        key = fut.key
        client.cancel(fut)  # what the scheduler does with the tasks of a client that is gone
        deadline = time.monotonic() + 10
        while getattr(worker.state.tasks.get(key), "state", None) not in (None, "cancelled") \
                and time.monotonic() < deadline:
            time.sleep(0.02)
        for _, a in futs.values():
            Path(a[0]).touch()
        deadline = time.monotonic() + 30
        while not all(Path(a[2]).exists() for _, a in futs.values()) and time.monotonic() < deadline:
            time.sleep(0.02)
        futs["kept"][0].result(timeout=30)
    assert Path(futs["kept"][1][2]).read_text() == "False"
    assert Path(futs["cancelled"][1][2]).read_text() == "True"


# --------------------------------------------------------------------------------------------------
# 3. two batches into one folder at once

@pytest.mark.slow  # over 20 s (measured); `-m "not slow"` leaves it out
def test_two_batches_at_once_one_refuses_naming_the_other_and_a_rerun_completes(tmp_path, heads_and_clean):
    heads, clean = heads_and_clean
    out = tmp_path / "rigs"
    cmd = CLI + ["batch", str(heads), "-o", str(out), *ARGS, "--jobs", "1"]
    procs = [subprocess.Popen(cmd, cwd=ROOT, env=_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
             for _ in range(2)]
    res = [p.communicate(timeout=600) for p in procs]
    codes = sorted(p.returncode for p in procs)
    assert codes == [0, 2], (codes, res)
    winner, loser = (0, 1) if procs[0].returncode == 0 else (1, 0)
    lines = res[loser][1].splitlines()
    assert len(lines) == 1 and "another autobones batch" in lines[0], lines
    assert f"pid {procs[winner].pid}" in lines[0], (lines, procs[winner].pid)
    rep = json.loads((out / REPORT_NAME).read_text())
    assert rep["counts"] == {"ok": 4, "failed": 0, "skipped": 0}, rep["counts"]
    got, ref = outputs(out), outputs(clean)
    assert sorted(got) == sorted(ref) and [k for k in ref if got[k] != ref[k]] == []
    r = run(["batch", str(heads), "-o", str(out), *ARGS])
    assert r.returncode == 0, r.stderr
    rep = json.loads((out / REPORT_NAME).read_text())
    assert rep["counts"] == {"ok": 0, "failed": 0, "skipped": 4}, rep["counts"]


def test_the_lock_refuses_a_second_holder_and_not_a_dead_one(tmp_path):
    from autobones.batch.lock import LOCK_NAME, batch_lock

    with batch_lock(tmp_path):  # a second open file description conflicts even in one process
        assert (tmp_path / LOCK_NAME).read_text().strip() == str(os.getpid())
        with pytest.raises(AutobonesError, match=f"pid {os.getpid()}"):
            with batch_lock(tmp_path):
                pass
    assert not (tmp_path / LOCK_NAME).exists()
    (tmp_path / LOCK_NAME).write_text("999999999\n")  # left by a run killed with -9: flock died with it
    with batch_lock(tmp_path):
        pass
    assert not (tmp_path / LOCK_NAME).exists()
