"""A face-capture recording as a glTF animation of a rig with ARKit morph targets.

Goes beyond the seeds (issue #15). The rig's glb (``autobones transfer HEAD --arkit``) is
copied with one animation added: a ``weights`` channel on the head mesh (one key per capture
frame, one weight per morph target: the ARKit ones from the capture, any other target 0)
and, when the capture has them, ``rotation`` channels on the ``head``, ``eye_l`` and
``eye_r`` joints. Angles (radians, as Live Link Face writes them) are right-handed turns about
the head's canonical axes (the rig's frame): yaw about up (+Y; positive turns the face toward
the subject's left), pitch about the subject's left (+X; positive tips the face down), roll
about the front (+Z), composed yaw * pitch * roll. Eye angles are relative to the head. The
signs follow that convention; they are not checked against a device recording.
"""
from __future__ import annotations


import numpy as np
from scipy.spatial.transform import Rotation

from ..errors import AutobonesError
from ..io.files import read_json
from ..io.gltf import add_animation, pack_glb, read_glb
from ..orient import Frame
from .names import ARKIT_NAMES

BONE_ANGLES = {"head": ("HeadYaw", "HeadPitch", "HeadRoll"),
               "eye_l": ("LeftEyeYaw", "LeftEyePitch", "LeftEyeRoll"),
               "eye_r": ("RightEyeYaw", "RightEyePitch", "RightEyeRoll")}


def _world_rotations(nodes):
    """(3, 3) rest world rotation of every node and each node's parent index (-1 for roots)."""
    parent = [-1] * len(nodes)
    for i, n in enumerate(nodes):
        for c in n.get("children", []):
            parent[c] = i
    world = [None] * len(nodes)

    def get(i):
        if world[i] is None:
            local = Rotation.from_quat(nodes[i].get("rotation", [0, 0, 0, 1])).as_matrix()
            world[i] = local if parent[i] < 0 else get(parent[i]) @ local
        return world[i]

    for i in range(len(nodes)):
        get(i)
    return world, parent


def canonical_turns(yaw, pitch, roll):
    """(f, 3, 3) rotations in the canonical head frame (+X subject's left, +Y up, +Z front), radians in."""
    return Rotation.from_euler("YXZ", np.c_[yaw, pitch, roll]).as_matrix()


def capture_glb(rig_path, capture, bones=True):
    """The rig's glb with the capture as an animation, as bytes.

    Parameters
    ----------
    rig_path : str
        A glb written by ``autobones transfer --arkit`` (its ``.rig.json`` beside it gives the frame).
    capture : Capture
        From :func:`autobones.arkit.capture.read_capture`.
    bones : bool
        Also animate the head and eye joints from the capture's angles (when it has them).
    """
    from ..rig import sidecar_paths

    try:
        doc, body = read_glb(rig_path)
    except (OSError, ValueError) as exc:
        raise AutobonesError(f"{rig_path}: cannot read it as a glb ({exc})") from None
    except RecursionError:  # read_glb's json.loads on a JSON chunk nested 100k deep
        raise AutobonesError(f"{rig_path}: cannot read it as a glb (its JSON chunk is nested too deeply: a "
                             "damaged file)") from None
    meshes = doc.get("meshes") or [{}]
    names = list((meshes[0].get("extras") or {}).get("targetNames", []))
    missing = [n for n in ARKIT_NAMES if n not in names]
    if missing:
        raise AutobonesError(f"{rig_path}: the rig has no ARKit morph targets ({missing[0]} missing); make it with "
                             "autobones transfer HEAD --arkit -o RIG.glb")
    nodes = doc.get("nodes", [])
    mesh_node = next(i for i, n in enumerate(nodes) if "mesh" in n)
    f = len(capture.times)
    W = np.zeros((f, len(names)))
    for name, w in capture.weights.items():
        W[:, names.index(name)] = w
    channels = [(mesh_node, "weights", W)]
    if bones and capture.angles:
        json_path = sidecar_paths(rig_path)[0]
        try:
            # the head's axes (a transferred rig's anatomical ones, Frame.axes), else its frame's
            Rf = Frame.from_dict(read_json(json_path, "sidecar")["frame"]).turn_axes
        except AutobonesError:  # read_json's own message, naming the file
            raise
        except (OSError, ValueError, KeyError, TypeError) as exc:
            raise AutobonesError(f"{json_path}: the rig's sidecar is needed for the head and eye turns "
                                 f"({type(exc).__name__}: {exc}); or animate without them (--no-bones)") from None
        world, parent = _world_rotations(nodes)
        by_name = {n.get("name"): i for i, n in enumerate(nodes)}
        for bone, cols in BONE_ANGLES.items():
            if bone not in by_name or not all(c in capture.angles for c in cols):
                continue
            i = by_name[bone]
            P = world[parent[i]] if parent[i] >= 0 else np.eye(3)
            local = Rotation.from_quat(nodes[i].get("rotation", [0, 0, 0, 1])).as_matrix()
            turn = Rf.T @ canonical_turns(*(capture.angles[c] for c in cols)) @ Rf  # input frame
            q = Rotation.from_matrix(np.transpose(P) @ turn @ P @ local).as_quat()
            for k in range(1, len(q)):  # neighbouring keys in one hemisphere: LINEAR keys do not spin the long way
                if q[k] @ q[k - 1] < 0:
                    q[k] = -q[k]
            channels.append((i, "rotation", q))
    doc, body = add_animation(doc, body, f"capture:{capture.source}", capture.times, channels)
    asset = dict(doc.get("asset", {}))
    extras = dict(asset.get("extras") or {})
    extras["autobones"] = {**(extras.get("autobones") or {}), "capture": capture.source}
    extras["autobones"].pop("sidecar", None)  # an animated copy, not a rig load_rig reads
    asset["extras"] = extras
    doc["asset"] = asset
    return pack_glb(doc, body)


def save_animated_rig(rig_path, capture, out_path, bones=True):
    """Write ``out_path`` (a .glb: the rig with the capture's animation, :func:`capture_glb`) and
    the rig's two sidecars beside it under its name, all three or none, so the animated file is a
    whole rig that ``load_rig``, ``export`` and ``view`` read like any other.

    Returns the three paths written (glb, rig.json, weights.npz).
    """
    import os

    from ..io.atomic import replace_all, temp_beside
    from ..rig import sidecar_paths

    data = capture_glb(rig_path, capture, bones=bones)
    sources = sidecar_paths(rig_path)
    targets = (os.fspath(out_path), *sidecar_paths(out_path))
    staged = []
    try:
        for target, payload in zip(targets, (data, *sources)):
            fd, tmp = temp_beside(target, suffix=os.path.splitext(target)[1])
            staged.append((tmp, target))
            with os.fdopen(fd, "wb") as fh:
                if isinstance(payload, (bytes, bytearray)):
                    fh.write(payload)
                else:
                    with open(payload, "rb") as src:
                        fh.write(src.read())
    except OSError as exc:
        for tmp, _ in staged:
            try:
                os.unlink(tmp)
            except OSError:
                pass
        raise AutobonesError(f"{out_path}: cannot write the animated rig ({exc.strerror or exc}); nothing was written") \
            from None
    return replace_all(staged, "the animated rig")
