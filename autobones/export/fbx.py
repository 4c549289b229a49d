"""Write a saved rig as FBX through Blender run headless, and check an FBX against its rig.

Beyond the seeds (issue #17): game and animation tools (Maya, MotionBuilder, Unity, Unreal) read
FBX, and no FBX writer is on PyPI, so Blender (>= 3.4, on PATH) writes it: its glTF importer reads
the glb, the rig's full weight matrix replaces the glb's four influences, and its FBX exporter
writes the armature (one bone per glb joint, no leaf bones), the mesh with one vertex group per
bone, the morph targets as shape keys, the muscle markers as empties parented to their bones, and
any animation. The Blender side is :mod:`autobones.export.blender_fbx`, a script inside the package.

The FBX is Y up (Blender's FBX default axes), in Blender's units: coordinates are the glb's
(the rig's input frame and units) with FBX's unit scale, so a re-import gives them back.
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import tempfile

import numpy as np

from ..errors import AutobonesError
from ..io.atomic import check_destination, refuse_overwriting_inputs, replace_all, temp_beside
from ..rig import sidecar_paths
from .source import read_rig_source

INSTALL = "FBX export needs Blender (Debian: apt-get install blender)"
SCRIPT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "blender_fbx.py")
TIMEOUT_S = 600


def find_blender():
    """Path of the ``blender`` executable on PATH; AutobonesError saying how to install it when absent."""
    exe = shutil.which("blender")
    if exe is None:
        raise AutobonesError(INSTALL)
    return exe


def run_blender(args, what):
    """Run :mod:`.blender_fbx` in headless Blender with ``args`` (list of str); AutobonesError with the
    end of Blender's log when it fails."""
    exe = find_blender()
    cmd = [exe, "-b", "--factory-startup", "--python-exit-code", "1", "-P", SCRIPT, "--", *map(str, args)]
    # Debian's Blender embeds the system Python and finds its standard library through the first
    # python3.X on PATH: a virtualenv or pyenv interpreter first on PATH would hide the system numpy
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONHOME", "PYTHONPATH")}
    env["PATH"] = os.path.dirname(os.path.realpath(exe)) + os.pathsep + env.get("PATH", "")
    try:
        out = subprocess.run(cmd, capture_output=True, text=True, timeout=TIMEOUT_S, env=env)
    except (OSError, subprocess.TimeoutExpired) as exc:
        raise AutobonesError(f"{what}: Blender did not run ({type(exc).__name__}: {exc})") from None
    if out.returncode != 0:
        log = " | ".join(line for line in (out.stdout + out.stderr).splitlines()[-6:] if line.strip())
        hint = "; Blender's Python needs numpy (apt-get install python3-numpy)" if "numpy" in log else ""
        raise AutobonesError(f"{what}: Blender failed (exit {out.returncode}): {log}{hint}")
    return out


def write_fbx(rig_path, out_path, max_influences=None):
    """Write the rig saved as ``rig_path`` to ``out_path`` (.fbx) with Blender; see the module doc.

    Parameters
    ----------
    rig_path : str or os.PathLike
        A glb written by autobones, its ``.rig.json`` and ``.weights.npz`` beside it.
    out_path : str or os.PathLike
        The ``.fbx`` to write (under a temporary name, renamed when complete).
    max_influences : int or None
        None (the default) writes every weight of the rig; 4 the glb's four per vertex, so the
        FBX deforms exactly as the glb does (:func:`autobones.export.usd.skin_weights`).

    Returns
    -------
    dict
        ``path``, ``bones``, ``vertices``, ``influences`` (largest count of weights on a vertex),
        ``shape_keys``, ``markers``, ``animations`` (counts), ``blender`` (version),
        ``weights_matched_by`` (``"index"`` when Blender kept the file's vertex order).

    Raises AutobonesError for a bad input, an output that is the input, or no Blender.
    """
    rig_path, out_path = os.fspath(rig_path), os.fspath(out_path)
    if os.path.splitext(out_path)[1].lower() != ".fbx":
        raise AutobonesError(f"{out_path}: an FBX file ends in .fbx")
    refuse_overwriting_inputs([out_path], [rig_path, *sidecar_paths(rig_path)])
    check_destination(out_path, "the FBX file")
    find_blender()
    src = read_rig_source(rig_path)  # refuses a foreign glb or missing sidecars before Blender starts
    npz = sidecar_paths(rig_path)[1]
    fd, tmp = temp_beside(out_path, suffix=".fbx")
    os.close(fd)
    try:
        with tempfile.TemporaryDirectory(prefix="autobones-fbx-") as work:
            report_path = os.path.join(work, "report.json")
            if max_influences is not None:  # the glb's cut, made here so Blender gets exactly those weights
                npz = _cut_weights(npz, src.rig.weights, max_influences, os.path.join(work, "weights.npz"))
            run_blender(["export", os.path.abspath(rig_path), os.path.abspath(npz), tmp, report_path], out_path)
            with open(report_path, encoding="utf-8") as fh:
                rep = json.load(fh)
        if not os.path.getsize(tmp):
            raise AutobonesError(f"{out_path}: Blender wrote an empty file")
        replace_all([(tmp, out_path)], "the FBX file")
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)
    return {"path": out_path, "bones": len(rep["bones"]), "vertices": rep["mesh_vertices"],
            "influences": rep["influences_max"], "shape_keys": len(rep["shape_keys"]), "markers": len(rep["markers"]),
            "animations": len(rep["animations"]), "blender": rep["blender"],
            "weights_matched_by": rep["weights_matched_by"], "rig_bones": len(src.joint_names)}


def _cut_weights(npz, W, max_influences, out):
    """A copy of the weights sidecar ``npz`` at ``out`` whose ``weights`` keep each vertex's
    ``max_influences`` largest, renormalised as the glb writes them; returns ``out``."""
    from .usd import skin_weights

    with np.load(npz) as z:
        arrays = {k: z[k] for k in z.files}
    arrays["weights"] = skin_weights(W, max_influences).astype(np.float32)
    np.savez(out, **arrays)
    return out


def inspect_file(path):
    """What Blender sees in ``path`` (.fbx or .glb) imported into an empty scene: a dict of arrays
    (glTF frame, file units): ``bone_names``, ``bone_parents`` ('' for roots), ``bone_heads`` (b, 3),
    ``positions`` (n, 3) rest vertices, ``weights`` (n, b) vertex groups in bone order,
    ``shape_key_names``, ``shape_key_deltas`` (k, n, 3), ``markers`` (empties' names)."""
    with tempfile.TemporaryDirectory(prefix="autobones-inspect-") as work:
        out = os.path.join(work, "inspect.npz")
        run_blender(["inspect", os.path.abspath(os.fspath(path)), out], os.fspath(path))
        with np.load(out) as z:
            return {k: z[k] for k in z.files}


def posed_vertices(path, turns):
    """Blender's own skinning of ``path`` (.fbx or .glb) with one bone turned at a time.

    Parameters
    ----------
    path : str or os.PathLike
        The file, imported into an empty scene as :func:`inspect_file` does.
    turns : sequence of (bone name, (3,) axis, degrees)
        The axis in the bone's own rest frame (local +Y along the bone, as in the glb's joints).

    Returns
    -------
    (len(turns), n, 3) float
        The armature-deformed vertices for each turn (only that bone turned), in the glTF file
        frame (Y up) and the file's units, in Blender's vertex order (the file's, for an FBX
        this package wrote).
    """
    turns = [[str(b), [float(a) for a in axis], float(deg)] for b, axis, deg in turns]
    with tempfile.TemporaryDirectory(prefix="autobones-pose-") as work:
        spec, out = os.path.join(work, "turns.json"), os.path.join(work, "posed.npz")
        with open(spec, "w", encoding="utf-8") as fh:
            json.dump(turns, fh)
        run_blender(["pose", os.path.abspath(os.fspath(path)), spec, out], os.fspath(path))
        with np.load(out) as z:
            return z["positions"]


def check_fbx(fbx_path, rig_path):
    """Re-import ``fbx_path`` into Blender and compare it with the rig saved as ``rig_path``.

    Returns
    -------
    dict
        ``bones_match`` (names and parents), ``bone_head_error`` (largest head distance / head size),
        ``vertex_error`` (largest rest-position distance / head size, vertices matched by index),
        ``weight_error`` (largest |FBX vertex-group weight - rig weight|, all influences),
        ``shape_keys_match`` (names, in order), ``shape_key_error`` (largest delta distance / head
        size), ``markers_match``, and the counts.
    """
    src = read_rig_source(rig_path)
    rig = src.rig
    got = inspect_file(fbx_path)
    size = float(rig.frame.size)
    names = [str(s) for s in got["bone_names"]]
    parents = dict(zip(names, (str(p) for p in got["bone_parents"])))
    want_parents = {n: (src.joint_names[p] if p >= 0 else "") for n, p in zip(src.joint_names, src.parents)}
    out = {"bones": len(names), "vertices": len(got["positions"]), "shape_keys": len(got["shape_key_names"]),
           "bones_match": sorted(names) == sorted(src.joint_names) and parents == want_parents}
    if out["bones_match"]:
        order = [names.index(n) for n in src.joint_names]
        heads = got["bone_heads"][order]
        out["bone_head_error"] = float(np.linalg.norm(heads - rig.skeleton.heads, axis=1).max()) / size
    same_n = len(got["positions"]) == len(rig.vertices)
    out["vertex_count_match"] = same_n
    if same_n:
        out["vertex_error"] = float(np.linalg.norm(got["positions"] - rig.vertices, axis=1).max()) / size
        if out["bones_match"]:
            W = got["weights"][:, [names.index(n) for n in src.joint_names]]
            out["weight_error"] = float(np.abs(W - rig.weights).max())
    want_keys = [n for n, _ in src.morph_targets]
    got_keys = [str(s) for s in got["shape_key_names"]]
    out["shape_keys_match"] = got_keys == want_keys
    if out["shape_keys_match"] and same_n and want_keys:
        D = got["shape_key_deltas"]
        out["shape_key_error"] = max(float(np.linalg.norm(D[i] - d, axis=1).max())
                                     for i, (_, d) in enumerate(src.morph_targets)) / size
    out["markers_match"] = sorted(str(m) for m in got["markers"]) == sorted(src.markers)
    return out
