"""Run autobones on a Blender mesh: its files in, the subprocess, one-line errors out.

Beyond the papers (issue #37): the mesh goes to autobones in its own frame and units (the object's
local coordinates; no world transform, no modifiers) with its vertex order kept, so the rig's rows
are the mesh's vertices. The OBJ is written here from the mesh data rather than by Blender's
exporters, which may split vertices at seams or reorder them. autobones runs in a subprocess of the
Python the preferences name (``python -m autobones``) or of an ``autobones`` executable; its
one-line error (``autobones transfer: error: ...``, exit 2) becomes the operator's report.

Only the standard library, numpy and mesh data: runs inside Blender.
"""
import json
import os
import shutil
import subprocess
import threading

import numpy as np

LANDMARK_FORMAT = "autobones-landmarks/1"


class AddonError(Exception):
    """A problem the user can fix; the message is one line for Blender's report."""


def one_line(text):
    """``text`` squeezed onto one line (control characters as spaces), at most 400 characters."""
    line = " ".join(str(text).split())
    return line if len(line) <= 400 else line[:397] + "..."


def mesh_arrays(mesh):
    """(V (n, 3) float32 in the mesh's own frame and units, faces as a list of (k,) int arrays) of ``mesh``."""
    V = np.zeros(len(mesh.vertices) * 3, np.float32)
    mesh.vertices.foreach_get("co", V)
    loops = np.zeros(len(mesh.loops), np.int64)
    mesh.loops.foreach_get("vertex_index", loops)
    starts = np.zeros(len(mesh.polygons), np.int64)
    totals = np.zeros(len(mesh.polygons), np.int64)
    mesh.polygons.foreach_get("loop_start", starts)
    mesh.polygons.foreach_get("loop_total", totals)
    return V.reshape(-1, 3), [loops[s:s + t] for s, t in zip(starts.tolist(), totals.tolist())]


def write_obj(path, mesh):
    """Write ``mesh`` as an OBJ: ``v`` lines in vertex order (9 significant digits: float32 exactly),
    ``f`` lines as its polygons (1-based). Returns the vertex count."""
    V, faces = mesh_arrays(mesh)
    if not len(faces):
        raise AddonError(f"{mesh.name}: the mesh has no faces to rig")
    with open(path, "w", encoding="ascii") as fh:
        fh.write("# written by the autobones Blender add-on: the mesh's own frame and units\n")
        fh.writelines("v %.9g %.9g %.9g\n" % tuple(p) for p in V.tolist())
        fh.writelines("f " + " ".join(str(i + 1) for i in f.tolist()) + "\n" for f in faces)
    return len(V)


def write_landmarks(path, landmarks, mesh_name=""):
    """Write ``{name: (x, y, z)}`` (mesh frame and units) as the contract's JSON, names in contract order
    when given in it; returns ``path``."""
    data = {"format": LANDMARK_FORMAT, "mesh": mesh_name,
            "landmarks": {k: [float(c) for c in v] for k, v in landmarks.items()}}
    with open(path, "w", encoding="utf-8") as fh:
        json.dump(data, fh, indent=1)
    return path


def autobones_command(setting):
    """The command that runs autobones: ``[python, "-m", "autobones"]`` for a Python interpreter,
    ``[exe]`` for the autobones executable, ``autobones`` on PATH when ``setting`` is empty.

    Raises AddonError naming what was not found.
    """
    setting = (setting or "").strip()
    if not setting:
        exe = shutil.which("autobones")
        if exe is None:
            raise AddonError("autobones not found on PATH: install it (pip install autobones) or set its Python "
                             "in the add-on's preferences")
        return [exe]
    exe = os.path.abspath(os.path.expanduser(setting))
    if not os.path.isfile(exe) or not os.access(exe, os.X_OK):
        raise AddonError(f"autobones not found: {exe} is not an executable file (the add-on's preferences)")
    return [exe, "-m", "autobones"] if os.path.basename(exe).lower().startswith("python") else [exe]


def rig_arguments(settings, mesh_path, out_glb, landmarks_path=None):
    """autobones' arguments for the panel's options: ``place`` or ``transfer``, ``-v`` for progress."""
    if settings.method == "PLACE":
        args = ["place", mesh_path, "--density", settings.density]
    else:
        args = ["transfer", mesh_path]
        if settings.expressions:
            args.append("--expressions")
        if settings.arkit:
            args.append("--arkit")
    if landmarks_path:
        args += ["--landmarks", landmarks_path]
    return args + ["-o", out_glb, "-v"]


def failure(returncode, stderr):
    """The one-line report of an autobones run that exited ``returncode``: its own error line when it
    printed one (exit 2), else the exit status and its last line."""
    lines = [ln.strip() for ln in stderr.splitlines() if ln.strip()]
    errors = [ln for ln in lines if ": error: " in ln]
    if returncode == 2 and errors:
        return one_line(errors[-1])
    last = lines[-1] if lines else "no message"
    return one_line(f"autobones failed (exit {returncode}): {last}")


def run(cmd, timeout=None):
    """Run ``cmd`` to the end; its stdout. Raises AddonError (one line) when it cannot start or fails."""
    try:
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, stdin=subprocess.DEVNULL)
    except (OSError, subprocess.TimeoutExpired) as exc:
        raise AddonError(one_line(f"autobones did not run: {exc}")) from None
    if done.returncode != 0:
        raise AddonError(failure(done.returncode, done.stderr))
    return done.stdout


class Job:
    """autobones running in the background (the modal operator polls it): its latest stage line."""

    def __init__(self, cmd):
        try:
            self.proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                         stdin=subprocess.DEVNULL)
        except OSError as exc:
            raise AddonError(one_line(f"autobones did not run: {exc}")) from None
        self.lines, self.stdout = [], ""
        # a reader thread per pipe: a full pipe would stop autobones, and Blender's UI must not block
        self._threads = [threading.Thread(target=self._read_err, daemon=True),
                         threading.Thread(target=self._read_out, daemon=True)]
        for t in self._threads:
            t.start()

    def _read_err(self):
        for line in self.proc.stderr:
            self.lines.append(line.rstrip("\n"))

    def _read_out(self):
        self.stdout = self.proc.stdout.read()

    def status(self):
        """The latest progress line (``-v`` stages), one line."""
        line = self.lines[-1] if self.lines else "starting"
        return one_line(line[len("autobones: "):] if line.startswith("autobones: ") else line)

    def poll(self):
        """None while running; else the exit code (after the pipes are drained)."""
        code = self.proc.poll()
        if code is not None:
            for t in self._threads:
                t.join()
        return code

    def result(self):
        """stdout of a finished run; AddonError (one line) when it failed."""
        code = self.poll()
        if code != 0:
            raise AddonError(failure(code, "\n".join(self.lines)))
        return self.stdout

    def cancel(self):
        """Stop autobones (it writes its outputs under temporary names: nothing half-written remains)."""
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self.proc.kill()
