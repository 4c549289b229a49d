"""Blender script for tests/test_blender_addon.py: install the add-on zip and drive its operators.

Run headless (the test sets BLENDER_USER_SCRIPTS to a temporary folder, so nothing is installed for
the user)::

    blender -b --factory-startup --python-exit-code 1 -P tests/blender_addon_check.py -- \
        ADDON.zip PYTHON HEAD.obj HEAD.landmarks.json OUT_DIR

PYTHON is the interpreter with autobones installed (the add-on's preference). Writes in OUT_DIR:

- ``report.json``: the one-line reports of the bad inputs (``errors``), the INFO line of each run,
  what the add-on made (parenting, modifier, text block);
- ``<run>.npz`` per run (``a_place``, ``a_transfer``: the head as given, metres, +Y up;
  ``b_place``, ``b_transfer``: the same head in millimetres, +Z up, moved and scaled in the scene,
  landmarks placed as empties with the add-on's operator; ``c_auto``: transfer with the landmarks found
  automatically): the armature's bones (names, parents,
  heads, tails, X and Y axes in the mesh's own frame), every vertex group's weights, the shape keys'
  offsets, the landmark empties, the mesh moved by turning ``head`` 20 degrees about its X axis, and
  the rest pose before and after ``autobones.reset_pose``. Each run keeps its autobones files in
  OUT_DIR/<run>/ (the panel's "Keep files in").

The script judges nothing; the test compares with the files autobones wrote.
"""
import json
import math
import os
import sys

import bpy
import numpy as np
from mathutils import Matrix

ADDON = "autobones_blender"


def read_obj(path):
    """(V (n, 3), triangles) of an OBJ's ``v`` and ``f`` lines, in file order."""
    V, F = [], []
    with open(path) as fh:
        for line in fh:
            parts = line.split()
            if parts and parts[0] == "v":
                V.append([float(c) for c in parts[1:4]])
            elif parts and parts[0] == "f":
                F.append([int(c.split("/")[0]) - 1 for c in parts[1:]])
    return np.array(V), F


def make_mesh(name, V, F, matrix):
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(V.tolist(), [], F)
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    obj.matrix_world = matrix
    return obj


def activate(obj):
    for o in bpy.context.view_layer.objects:
        o.select_set(False)
    bpy.context.view_layer.objects.active = obj
    if obj is not None:
        obj.select_set(True)


def rig(report, key, **options):
    """Set the panel's options, press Rig; the operator's outcome ("FINISHED" or its one-line error)."""
    s = bpy.context.scene.autobones
    for k, v in options.items():
        setattr(s, k, v)
    try:
        report.setdefault("results", {})[key] = sorted(bpy.ops.autobones.rig())
    except RuntimeError as exc:  # an ERROR report: bpy.ops raises it with the message
        report.setdefault("errors", {})[key] = str(exc)


def evaluated_local(obj):
    """(n, 3) the armature-deformed mesh in the mesh's own frame."""
    ev = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    co = np.zeros(len(ev.data.vertices) * 3)
    ev.data.vertices.foreach_get("co", co)
    return co.reshape(-1, 3)


def record(obj, out, report, run):
    """Save what the add-on made on ``obj`` (see the module doc) as OUT/<run>.npz."""
    from autobones_blender import landmark_empties, result
    from autobones_blender.vertex_groups import read_full_weights

    arm = result.rig_armature(obj)
    to_mesh = obj.matrix_world.inverted() @ arm.matrix_world
    bones = list(arm.data.bones)
    names = [b.name for b in bones]
    pt = lambda v: np.array(to_mesh @ v)
    heads = np.array([pt(b.head_local) for b in bones])
    tails = np.array([pt(b.tail_local) for b in bones])
    R = np.array(to_mesh.to_3x3())
    x_axes = np.array([R @ np.array(b.matrix_local.to_3x3().col[0]) for b in bones])
    y_axes = np.array([R @ np.array(b.matrix_local.to_3x3().col[1]) for b in bones])
    keys = obj.data.shape_keys
    base = np.zeros(len(obj.data.vertices) * 3)
    key_names, deltas = [], []
    if keys is not None:
        keys.reference_key.data.foreach_get("co", base)
        for kb in result.rig_shape_keys(obj):
            co = np.zeros_like(base)
            kb.data.foreach_get("co", co)
            key_names.append(kb.name)
            deltas.append((co - base).reshape(-1, 3))
    rest = evaluated_local(obj)
    pb = arm.pose.bones["head"]
    pb.rotation_euler = (math.radians(20.0), 0.0, 0.0)  # about the bone's X: across the head, a nod
    bpy.context.view_layer.update()
    turned = evaluated_local(obj)
    activate(obj)
    reset = sorted(bpy.ops.autobones.reset_pose())
    bpy.context.view_layer.update()
    lms = landmark_empties.collect(obj)
    co = np.zeros(len(obj.data.vertices) * 3)
    obj.data.vertices.foreach_get("co", co)
    np.savez(os.path.join(out, run + ".npz"), bone_names=np.array(names),
             parents=np.array([b.parent.name if b.parent else "" for b in bones]), heads=heads, tails=tails,
             x_axes=x_axes, y_axes=y_axes, weights=read_full_weights(obj, names),
             group_names=np.array([g.name for g in obj.vertex_groups]), shape_key_names=np.array(key_names),
             shape_key_deltas=np.array(deltas).reshape(len(deltas), len(co) // 3, 3), rest=rest, turned=turned,
             after_reset=evaluated_local(obj), mesh=co.reshape(-1, 3),
             landmark_names=np.array(list(lms)), landmarks=np.array(list(lms.values())).reshape(-1, 3),
             matrix_world=np.array(obj.matrix_world))
    text = bpy.data.texts.get(obj.get(result.SIDECAR_PROP, ""))
    mod = obj.modifiers.get(result.MODIFIER)
    report.setdefault("made", {})[run] = {
        "armature_parent": arm.parent.name if arm.parent else None, "mesh": obj.name,
        "armature_parent_type": arm.parent_type, "modifier_object": mod.object.name if mod else None,
        "modifier_index": list(obj.modifiers).index(mod) if mod else None,
        "sidecar_text": text.as_string() if text else None, "reset": reset,
        "armatures_in_scene": sum(o.type == "ARMATURE" for o in bpy.data.objects)}


def bad_inputs(report, head, out):
    """No active mesh, autobones not found (preference, PATH), autobones exiting 2."""
    prefs = bpy.context.preferences.addons[ADDON].preferences
    good = prefs.autobones_path
    activate(None)
    rig(report, "no_active_mesh", method="PLACE", landmarks="AUTO", output_dir="")
    activate(head)
    prefs.autobones_path = os.path.join(out, "no-such-python3")
    rig(report, "autobones_not_found")
    prefs.autobones_path, path = "", os.environ.get("PATH", "")
    os.environ["PATH"] = out  # no autobones on PATH
    rig(report, "autobones_not_on_path")
    os.environ["PATH"], prefs.autobones_path = path, good
    few = os.path.join(out, "three.landmarks.json")
    with open(few, "w") as fh:
        json.dump({"format": "autobones-landmarks/1", "landmarks": {"pronasale": [0, 0.08, 0.1], "menton": [0, 0, 0.07],
                                                                    "vertex": [0, 0.22, 0]}}, fh)
    rig(report, "autobones_exit_2", method="TRANSFER", landmarks="FILE", landmarks_file=few, arkit=False)


def main(zip_path, python, head_obj, landmarks_json, out):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.preferences.addon_install(filepath=zip_path, overwrite=True)
    bpy.ops.preferences.addon_enable(module=ADDON)
    bpy.context.preferences.addons[ADDON].preferences.autobones_path = python
    report = {"blender": bpy.app.version_string}
    V, F = read_obj(head_obj)
    with open(landmarks_json) as fh:
        given = json.load(fh)["landmarks"]

    a = make_mesh("head", V, F, Matrix.Identity(4))
    bad_inputs(report, a, out)
    activate(a)
    for run, opts in (("a_place", dict(method="PLACE", density="medium", landmarks="AUTO")),
                      ("a_transfer", dict(method="TRANSFER", landmarks="FILE", landmarks_file=landmarks_json,
                                          arkit=True))):
        os.makedirs(os.path.join(out, run))
        rig(report, run, output_dir=os.path.join(out, run), **opts)
        record(a, out, report, run)

    # the same head in millimetres, +Z up (file (x, y, z) -> (x, -z, y)), placed in metres in the scene
    to_b = Matrix(((1000, 0, 0), (0, 0, -1000), (0, 1000, 0))).to_4x4()
    b = make_mesh("head_mm", (V * 1000.0) @ np.array(to_b.to_3x3()).T / 1000.0,
                  F, Matrix.Translation((0.4, 0.1, 0.0)) @ Matrix.Scale(0.001, 4))
    activate(b)
    for name, p in given.items():  # the artist's clicks: world positions on the moved head
        world = b.matrix_world @ (to_b @ Matrix.Translation(p).translation)
        bpy.ops.autobones.add_landmark(name=name, location=world)
    report["written_landmarks"] = sorted(bpy.ops.autobones.write_landmarks(
        filepath=os.path.join(out, "b.landmarks.json")))
    for run, opts in (("b_place", dict(method="PLACE", density="medium", landmarks="AUTO")),
                      ("b_transfer", dict(method="TRANSFER", landmarks="EMPTIES", arkit=True))):
        os.makedirs(os.path.join(out, run))
        rig(report, run, output_dir=os.path.join(out, run), **opts)
        record(b, out, report, run)
    # a human face and no landmarks: transfer finds them (autobones[landmarks]) and they come back as empties
    c = make_mesh("head_auto", V, F, Matrix.Translation((-0.4, 0.0, 0.0)))
    activate(c)
    os.makedirs(os.path.join(out, "c_auto"))
    rig(report, "c_auto", method="TRANSFER", landmarks="AUTO", arkit=False, output_dir=os.path.join(out, "c_auto"))
    record(c, out, report, "c_auto")
    with open(os.path.join(out, "report.json"), "w") as fh:
        json.dump(report, fh, indent=1)


if __name__ == "__main__":
    main(*sys.argv[sys.argv.index("--") + 1:])
