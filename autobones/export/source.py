"""Read what an exporter needs from a saved rig: the Rig, and the glb's joints, morph targets, animations.

Beyond the seeds (issue #17). The glb written by :func:`autobones.io.gltf.glb_bytes` holds one
node per bone (index = bone index, listed in ``skins[0].joints``), then marker nodes (muscle
origins and insertions, parented to bones; not joints), then the mesh node; morph targets as
POSITION deltas named in ``meshes[0].extras.targetNames``; and, when some tool added them,
``animations`` on the joint nodes and the mesh's morph weights. The full weight matrix (every
influence, not the glb's four) and the exact vertices come from the sidecars (:func:`load_rig`).
All coordinates are in the rig's input frame and units.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from ..errors import AutobonesError, counted
from ..io.gltf import FLOAT, read_accessor, read_glb
from ..io.rig_files import load_rig

SUPPORTED_PATHS = ("translation", "rotation", "scale", "weights")


@dataclass
class Animation:
    """One glTF animation resampled at the union of its key times.

    name : str
    times : (t,) float
        Seconds, increasing.
    translations : (t, b, 3) float, rotations : (t, b, 4) float (x, y, z, w), scales : (t, b, 3) float
        Every joint's local transform at each time (the rest value where a joint is not animated).
    morph_weights : (t, k) float or None
        The morph targets' weights, None when the animation does not drive them.
    """

    name: str
    times: np.ndarray
    translations: np.ndarray
    rotations: np.ndarray
    scales: np.ndarray
    morph_weights: object = None


@dataclass
class RigSource:
    """A saved rig as the exporters read it.

    rig : autobones.rig.Rig
        From :func:`autobones.io.rig_files.load_rig`: vertices (n, 3) float64, faces (m, 3),
        weights (n, b) float64 (all influences), skeleton, frame, muscles, landmarks...
    joint_names : list of str
        The glTF bone names, in skin joint order (= the rig's bone order).
    parents : (b,) int
        Parent joint of each joint, -1 for roots.
    local : (b, 4, 4) float
        Each joint's rest transform relative to its parent (column-vector convention, x' = M x).
    world : (b, 4, 4) float
        Each joint's rest (= bind) transform in the rig's frame.
    morph_targets : list of (str, (n, 3) float32)
        Name and POSITION delta of each morph target.
    animations : list of Animation
    markers : dict str -> str
        Marker node name (``muscle/<name>/origin``...) -> the joint it is parented to.
    """

    path: str
    rig: object
    joint_names: list
    parents: np.ndarray
    local: np.ndarray
    world: np.ndarray
    morph_targets: list = field(default_factory=list)
    animations: list = field(default_factory=list)
    markers: dict = field(default_factory=dict)


def trs_matrix(t=None, q=None, s=None):
    """4x4 matrix ``T @ R @ S`` (column vectors) from glTF translation (3,), rotation (x, y, z, w), scale (3,)."""
    from scipy.spatial.transform import Rotation

    M = np.eye(4)
    if q is not None:
        M[:3, :3] = Rotation.from_quat(np.asarray(q, dtype=np.float64)).as_matrix()
    if s is not None:
        M[:3, :3] = M[:3, :3] * np.asarray(s, dtype=np.float64)[None, :]
    if t is not None:
        M[:3, 3] = np.asarray(t, dtype=np.float64)
    return M


def read_rig_source(path):
    """The :class:`RigSource` of ``path`` (a glb written by autobones, its sidecars beside it).

    Raises AutobonesError (one line: which file, what is wrong) for a missing or foreign glb,
    missing or mismatched sidecars, or a glb whose joints are not the sidecar's bones.
    """
    path = os.fspath(path)
    rig = load_rig(path)  # checks the glb is autobones', the sidecars exist and belong together
    doc, body = read_glb(path)
    nodes = doc.get("nodes") or []
    try:
        joints = [int(j) for j in doc["skins"][0]["joints"]]
        names = [str(nodes[j].get("name", "")) for j in joints]
    except (KeyError, IndexError, TypeError, ValueError) as exc:
        raise AutobonesError(f"{path}: the glb has no readable skin ({type(exc).__name__}: {exc})") from None
    if names != list(rig.skeleton.names):
        raise AutobonesError(f"{path}: the glb's joints ({', '.join(names[:4])}...) are not the sidecar's bones "
                             f"({', '.join(rig.skeleton.names[:4])}...); save the rig again")
    parent_node = {c: i for i, nd in enumerate(nodes) for c in nd.get("children", [])}
    slot = {node: k for k, node in enumerate(joints)}
    b = len(joints)
    parents = np.full(b, -1, dtype=np.int64)
    local = np.zeros((b, 4, 4))
    for k, node in enumerate(joints):
        nd = nodes[node]
        p = parent_node.get(node)
        if p is not None and p not in slot:
            raise AutobonesError(f"{path}: joint {names[k]!r} hangs under a node that is not a joint")
        parents[k] = -1 if p is None else slot[p]
        local[k] = np.asarray(nd["matrix"], dtype=np.float64).reshape(4, 4).T if "matrix" in nd else \
            trs_matrix(nd.get("translation"), nd.get("rotation"), nd.get("scale"))
    world = np.zeros_like(local)
    for k in _parents_first(parents):
        world[k] = local[k] if parents[k] < 0 else world[parents[k]] @ local[k]
    markers = {str(nodes[c].get("name", "")): names[k] for k, node in enumerate(joints)
               for c in nodes[node].get("children", []) if c not in slot}
    try:
        mesh = doc["meshes"][0]
        targets = mesh["primitives"][0].get("targets") or []
        tnames = list((mesh.get("extras") or {}).get("targetNames") or [])
        tnames += [f"target_{i}" for i in range(len(tnames), len(targets))]
        morphs = [(str(tnames[i]), read_accessor(doc, body, t["POSITION"]).astype(np.float32))
                  for i, t in enumerate(targets)]
    except (KeyError, IndexError, TypeError, ValueError) as exc:
        raise AutobonesError(f"{path}: its morph targets cannot be read ({type(exc).__name__}: {exc})") from None
    n = len(rig.vertices)
    for name, d in morphs:
        if d.shape != (n, 3):
            raise AutobonesError(f"{path}: morph target {name!r} has {counted(len(d), 'delta')} for {counted(n, 'vertex', 'vertices')}")
    src = RigSource(path=path, rig=rig, joint_names=names, parents=parents, local=local, world=world,
                    morph_targets=morphs, markers=markers)
    src.animations = [_read_animation(path, doc, body, a, i, slot, local, len(morphs))
                      for i, a in enumerate(doc.get("animations") or [])]
    return src


def _parents_first(parents):
    order, done = [], set()
    while len(order) < len(parents):
        before = len(order)
        for k, p in enumerate(parents):
            if k not in done and (p < 0 or p in done):
                order.append(k)
                done.add(k)
        if len(order) == before:
            raise AutobonesError("the joints' parents form a cycle")
    return order


def _read_animation(path, doc, body, anim, index, slot, local, n_targets):
    """An :class:`Animation` from glTF ``anim``; channels on marker nodes are ignored (markers are
    not exported as joints)."""
    name = str(anim.get("name") or f"animation_{index}")
    mesh_nodes = {i for i, nd in enumerate(doc.get("nodes") or []) if "mesh" in nd}
    chans = []
    try:
        for ch in anim["channels"]:
            tgt, smp = ch["target"], anim["samplers"][ch["sampler"]]
            node, what = tgt.get("node"), tgt["path"]
            if what not in SUPPORTED_PATHS:
                raise ValueError(f"channel path {what!r} is not supported")
            if what == "weights" and node not in mesh_nodes or what != "weights" and node not in slot:
                continue
            for key in ("input", "output"):
                if doc["accessors"][smp[key]]["componentType"] != FLOAT:
                    raise ValueError("only float key times and values are supported")
            times = np.asarray(read_accessor(doc, body, smp["input"]), dtype=np.float64).reshape(-1)
            values = np.asarray(read_accessor(doc, body, smp["output"]), dtype=np.float64)
            chans.append((node, what, times, values.reshape(len(values), -1), smp.get("interpolation", "LINEAR")))
    except (KeyError, IndexError, TypeError, ValueError) as exc:
        raise AutobonesError(f"{path}: animation {name!r} cannot be read ({type(exc).__name__}: {exc})") from None
    T = np.unique(np.concatenate([c[2] for c in chans])) if chans else np.zeros(1)
    rest_t = local[:, :3, 3]
    from scipy.spatial.transform import Rotation

    rest_s = np.linalg.norm(local[:, :3, :3], axis=1)
    rest_q = Rotation.from_matrix(local[:, :3, :3] / rest_s[:, None, :]).as_quat()
    tr = np.repeat(rest_t[None], len(T), axis=0)
    rot = np.repeat(rest_q[None], len(T), axis=0)
    sc = np.repeat(rest_s[None], len(T), axis=0)
    mw = None
    for node, what, times, values, interp in chans:
        if what == "weights":
            values = values.reshape(-1, n_targets * (3 if interp == "CUBICSPLINE" else 1))
            mw = sample_channel(times, values, interp, T, n_targets)
            continue
        width = 4 if what == "rotation" else 3
        v = sample_channel(times, values.reshape(-1, width), interp, T, width, rotation=what == "rotation")
        {"translation": tr, "rotation": rot, "scale": sc}[what][:, slot[node]] = v
    return Animation(name=name, times=T, translations=tr, rotations=rot, scales=sc, morph_weights=mw)


def sample_channel(times, values, interp, T, width, rotation=False):
    """Values (len(T), width) of a glTF sampler at times ``T`` (seconds).

    ``values`` holds one row per key (``STEP``, ``LINEAR``) or three (in-tangent, value,
    out-tangent: ``CUBICSPLINE``); times outside the keys clamp to the first or last key.
    Rotations (x, y, z, w) interpolate by slerp (LINEAR) and are normalised after a cubic.
    """
    times = np.asarray(times, dtype=np.float64)
    cubic = interp == "CUBICSPLINE"
    V = values.reshape(len(times), 3, width)[:, 1] if cubic else values.reshape(len(times), width)
    out = np.zeros((len(T), width))
    for i, t in enumerate(T):
        k = int(np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(times) - 1))
        if t <= times[0] or k == len(times) - 1 or interp == "STEP":
            out[i] = V[0] if t <= times[0] else V[k]
            continue
        dt = times[k + 1] - times[k]
        u = (t - times[k]) / dt
        if cubic:
            C = values.reshape(len(times), 3, width)
            out[i] = ((2 * u ** 3 - 3 * u ** 2 + 1) * V[k] + (u ** 3 - 2 * u ** 2 + u) * dt * C[k, 2]
                      + (-2 * u ** 3 + 3 * u ** 2) * V[k + 1] + (u ** 3 - u ** 2) * dt * C[k + 1, 0])
        elif rotation:
            a, b = V[k], V[k + 1] * (1.0 if V[k] @ V[k + 1] >= 0 else -1.0)
            om = np.arccos(np.clip(a @ b / (np.linalg.norm(a) * np.linalg.norm(b)), -1.0, 1.0))
            out[i] = a if om < 1e-12 else (np.sin((1 - u) * om) * a + np.sin(u * om) * b) / np.sin(om)
        else:
            out[i] = (1 - u) * V[k] + u * V[k + 1]
    if rotation:
        out /= np.linalg.norm(out, axis=1, keepdims=True)
    return out
