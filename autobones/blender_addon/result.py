"""An autobones result in the scene, on the user's own mesh object.

Beyond the papers (issue #37): what ``autobones place`` / ``transfer`` wrote (``x.glb``,
``x.rig.json``, ``x.weights.npz``) becomes, on the mesh that was rigged: an armature object parented
to it (one bone per joint, each bone's axes the glb joint's own: +Y from head to tail, +X across the
head, so rotating a bone about X nods it as ``autobones pose`` does), an Armature modifier, one
vertex group per bone holding every weight of the ``.weights.npz`` (the glb keeps only four), a
shape key per morph target under its name, the landmarks as named empties, and the sidecar as a
text block. Everything is in the mesh's own frame: the armature sits at the mesh's origin, so the rig
follows the object's transform. Rigging again replaces what the last run made and nothing else.
"""
import json
import os

import bpy
import numpy as np
from mathutils import Matrix

from . import glb, landmark_empties
from .runner import AddonError
from .vertex_groups import write_full_weights

RESULT_PROP = "autobones_result"  # JSON: what the last run made on this object (armature, groups, keys)
SIDECAR_PROP = "autobones_sidecar"  # name of the text block holding the sidecar
MODIFIER = "autobones"
POSE_BONES = ("jaw", "head", "neck", "eye_l", "eye_r")  # the bones the Pose panel turns


def sidecar_paths(glb_path):
    """``x.glb`` -> (``x.rig.json``, ``x.weights.npz``), as autobones names them."""
    base = glb_path[:-4] if glb_path.lower().endswith(".glb") else glb_path
    base = base[:-4] if base.endswith(".rig") else base
    return base + ".rig.json", base + ".weights.npz"


def read_result(glb_path):
    """(sidecar dict, weights (n, b) float32, weight bone names, glb dict) of a finished run."""
    json_path, npz_path = sidecar_paths(glb_path)
    try:
        with open(json_path, encoding="utf-8") as fh:
            sidecar = json.load(fh)
        with np.load(npz_path) as z:
            W, names = z["weights"], [str(s) for s in z["bone_names"]]
        rig = glb.read_rig_glb(glb_path)
    except (OSError, ValueError, KeyError, IndexError, TypeError) as exc:  # a truncated or foreign file
        raise AddonError(f"cannot read autobones' result {os.path.basename(glb_path)}: {exc}") from None
    return sidecar, W, names, rig


def clear_result(obj):
    """Remove what the last run made on ``obj`` (armature, modifier, its groups and shape keys);
    landmark empties stay (they may be the user's own input)."""
    made = _made(obj)
    arm = bpy.data.objects.get(made.get("armature", ""))
    if arm is not None and arm.type == "ARMATURE" and arm.parent == obj:
        data = arm.data
        bpy.data.objects.remove(arm)
        if data.users == 0:
            bpy.data.armatures.remove(data)
    mod = obj.modifiers.get(MODIFIER)
    if mod is not None and mod.type == "ARMATURE":
        obj.modifiers.remove(mod)
    for name in made.get("bones", []):
        group = obj.vertex_groups.get(name)
        if group is not None:
            obj.vertex_groups.remove(group)
    keys = obj.data.shape_keys
    if keys is not None:
        for name in made.get("shape_keys", []):
            kb = keys.key_blocks.get(name)
            if kb is not None:
                obj.shape_key_remove(kb)
        if made.get("made_basis") and len(keys.key_blocks) == 1:
            obj.shape_key_remove(keys.key_blocks[0])
    obj[RESULT_PROP] = "{}"


def build_armature(context, obj, rig, sidecar):
    """An armature object parented to ``obj`` with a bone per joint of ``rig`` (:func:`glb.read_rig_glb`),
    heads and tails from the sidecar's bones, axes from the glb's joint frames; returns it."""
    ends = {b["name"]: (np.array(b["head"], float), np.array(b["tail"], float)) for b in sidecar.get("bones", [])}
    if sorted(ends) != sorted(rig["joint_names"]):
        raise AddonError("autobones' result: the glb's joints and the sidecar's bones differ")
    data = bpy.data.armatures.new(f"{obj.name}_rig")
    arm = bpy.data.objects.new(f"{obj.name}_rig", data)
    for collection in obj.users_collection:
        collection.objects.link(arm)
    arm.parent = obj
    arm.matrix_parent_inverse.identity()  # armature space = the mesh's own frame
    data.display_type = "OCTAHEDRAL"
    arm.show_in_front = True
    view_layer = context.view_layer
    previous = view_layer.objects.active
    view_layer.objects.active = arm
    try:  # edit bones exist only in edit mode, which needs the armature visible in the view layer
        bpy.ops.object.mode_set(mode="EDIT")
    except RuntimeError as exc:
        view_layer.objects.active = previous
        bpy.data.objects.remove(arm)
        bpy.data.armatures.remove(data)
        raise AddonError(f"autobones: cannot make the armature beside {obj.name} (is its collection hidden?): "
                         f"{' '.join(str(exc).split())}") from None
    try:
        bones = []
        for name, frame in zip(rig["joint_names"], rig["world"]):
            head, tail = ends[name]
            eb = data.edit_bones.new(name)
            eb.head, eb.tail = (0.0, 0.0, 0.0), (0.0, max(float(np.linalg.norm(tail - head)), 1e-6), 0.0)
            # setting the matrix keeps the length and sets head, direction and roll: the joint's frame
            eb.matrix = Matrix(frame.tolist())
            eb.use_deform = True
            bones.append(eb)
        for eb, parent in zip(bones, rig["parents"]):
            if parent >= 0:
                eb.parent = bones[parent]
    finally:
        bpy.ops.object.mode_set(mode="OBJECT")
        view_layer.objects.active = previous
    for pb in arm.pose.bones:
        pb.rotation_mode = "XYZ"  # Euler sliders in the Pose panel; X nods (the joint's +X is across the head)
    return arm


def add_shape_keys(obj, names, deltas):
    """A shape key per morph target (``names``, (k, n, 3) deltas in mesh units), value 0; returns
    (the names Blender gave them, whether a Basis key was made)."""
    made_basis = obj.data.shape_keys is None
    if made_basis:
        obj.shape_key_add(name="Basis", from_mix=False)
    base = np.zeros(len(obj.data.vertices) * 3, np.float32)
    obj.data.shape_keys.reference_key.data.foreach_get("co", base)
    made = []
    for name, delta in zip(names, deltas):
        kb = obj.shape_key_add(name=name, from_mix=False)
        kb.data.foreach_set("co", base + delta.astype(np.float32).ravel())
        kb.value = 0.0
        kb.slider_min, kb.slider_max = 0.0, 1.0
        made.append(kb.name)
    return made, made_basis


def keep_sidecar(obj, sidecar_path):
    """The sidecar's text as a text block named after the object; its name in ``obj[SIDECAR_PROP]``."""
    name = f"{obj.name}.rig.json"
    text = bpy.data.texts.get(name) or bpy.data.texts.new(name)
    with open(sidecar_path, encoding="utf-8") as fh:
        text.from_string(fh.read())
    obj[SIDECAR_PROP] = text.name
    return text


def import_result(context, obj, glb_path):
    """Put the run written as ``glb_path`` onto the mesh object ``obj`` (see the module doc).

    Returns a dict: ``armature`` (object), ``bones``, ``vertex_groups``, ``shape_keys``, ``landmarks``
    (counts), ``influences`` (most weights on one vertex). Raises AddonError when the result does not
    fit the mesh (another vertex count).
    """
    sidecar, W, weight_names, rig = read_result(glb_path)
    n = len(obj.data.vertices)
    if W.shape[0] != n or rig["vertex_count"] != n:
        raise AddonError(f"autobones' result has {W.shape[0]} vertices, {obj.name} has {n}: was the mesh edited?")
    clear_result(obj)
    arm = build_armature(context, obj, rig, sidecar)
    write_full_weights(obj, weight_names, W)
    mod = obj.modifiers.new(MODIFIER, "ARMATURE")
    mod.object, mod.use_vertex_groups, mod.use_bone_envelopes = arm, True, False
    if len(obj.modifiers) > 1:  # skin before any other modifier (a subdivision after it, say)
        with context.temp_override(object=obj, active_object=obj):
            bpy.ops.object.modifier_move_to_index(modifier=mod.name, index=0)
    keys, made_basis = add_shape_keys(obj, rig["morph_names"], rig["morph_deltas"])
    landmarks = sidecar.get("landmarks") or {}
    landmark_empties.put_landmarks(obj, landmarks, snap=False)
    keep_sidecar(obj, sidecar_paths(glb_path)[0])
    obj[RESULT_PROP] = json.dumps({"armature": arm.name, "bones": weight_names, "shape_keys": keys,
                                   "made_basis": made_basis, "command": sidecar.get("options", {}).get("command")})
    return {"armature": arm, "bones": len(arm.data.bones), "vertex_groups": len(weight_names),
            "shape_keys": len(keys), "landmarks": len(landmarks), "influences": int((W > 0).sum(axis=1).max())}


def _made(obj):
    try:
        return json.loads(obj.get(RESULT_PROP, "{}"))
    except (ValueError, TypeError):
        return {}


def rig_armature(obj):
    """The armature the last run made on ``obj`` (``obj`` itself when it is that armature), or None."""
    if obj.type == "ARMATURE" and obj.parent is not None and _made(obj.parent).get("armature") == obj.name:
        return obj
    arm = bpy.data.objects.get(_made(obj).get("armature", ""))
    return arm if arm is not None and arm.type == "ARMATURE" and arm.parent == obj else None


def rig_mesh(obj):
    """The rigged mesh of ``obj`` (itself, or the parent of its rig's armature), or None."""
    if obj is None:
        return None
    if obj.type == "MESH" and rig_armature(obj) is not None:
        return obj
    return obj.parent if obj.type == "ARMATURE" and rig_armature(obj) is obj else None


def rig_shape_keys(obj):
    """The shape keys the last run made on the mesh ``obj``, in order."""
    keys = obj.data.shape_keys if obj.type == "MESH" else None
    names = _made(obj).get("shape_keys", [])
    return [keys.key_blocks[n] for n in names if keys is not None and n in keys.key_blocks]
