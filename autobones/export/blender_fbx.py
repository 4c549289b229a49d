"""Blender script (run by Blender, not imported by autobones): glb -> FBX, and what a file holds.

Run headless by :mod:`autobones.export.fbx` (Blender 3.4's bundled glTF importer and FBX
exporter/importer)::

    blender -b --factory-startup --python-exit-code 1 -P blender_fbx.py -- \
        export RIG.glb WEIGHTS.npz OUT.fbx REPORT.json
    blender -b --factory-startup --python-exit-code 1 -P blender_fbx.py -- inspect FILE(.glb|.fbx) OUT.npz
    blender -b --factory-startup --python-exit-code 1 -P blender_fbx.py -- pose FILE(.glb|.fbx) TURNS.json OUT.npz

``export`` imports the glb (bones keep the glb's joint axes: ``bone_heuristic="BLENDER"``),
replaces the glb's four influences per vertex by every weight of ``WEIGHTS.npz`` (the rig's full
weight matrix; vertices matched by index when Blender kept the file's order, else by position),
and writes the armature, the mesh with one vertex group per bone, its shape keys and any
animation as FBX (Y up, no leaf bones). REPORT.json says what was written.

``inspect`` imports a file into an empty scene and saves, in the glTF file frame (+Y up, Blender's
Z-up world converted back) and file units: bone names, parents and heads; the mesh's rest
positions; its full vertex-group weights (n, b) in bone order; shape key names and deltas.

``pose`` imports a file and, for each turn of TURNS.json (``[bone name, [x, y, z], degrees]``:
the axis in the bone's own rest frame, Blender's pose-bone space, whose +Y runs along the bone),
turns that one bone, evaluates the armature-deformed mesh and saves its vertices (k, n, 3) in
the glTF file frame and units (``positions``), every other bone at rest.
"""
import importlib.util
import json
import os
import sys

import bpy
import numpy as np

# every weight as vertex groups: the code the Blender add-on uses too (autobones/blender_addon/vertex_groups.py),
# loaded by path because Blender runs this file as a script, outside the package
_spec = importlib.util.spec_from_file_location(
    "autobones_vertex_groups", os.path.join(os.path.dirname(os.path.abspath(__file__)), os.pardir, "blender_addon",
                                            "vertex_groups.py"))
vertex_groups = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(vertex_groups)

# Blender 3.4's glTF importer still uses ``np.bool`` (removed in numpy 1.24, which Debian 12 ships
# with Blender 3.4): restore the alias so the importer runs with its default options.
if "bool" not in vars(np):
    np.bool = bool

S = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])  # Blender world (Z up) -> glTF (Y up)


def import_file(path):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    if path.lower().endswith((".glb", ".gltf")):
        result = bpy.ops.import_scene.gltf(filepath=path, bone_heuristic="BLENDER")
    else:
        result = bpy.ops.import_scene.fbx(filepath=path)
    arms = [o for o in bpy.context.scene.objects if o.type == "ARMATURE"]
    meshes = [o for o in bpy.context.scene.objects if o.type == "MESH"]
    if "FINISHED" not in result or len(arms) != 1 or len(meshes) != 1:
        raise SystemExit(f"{path}: expected one armature and one mesh, Blender made "
                         f"{[(o.name, o.type) for o in bpy.context.scene.objects]} ({sorted(result)})")
    return arms[0], meshes[0]


def rest_positions(obj):
    """(n, 3) rest positions of the mesh's own vertices (no modifier), glTF frame."""
    co = np.zeros(len(obj.data.vertices) * 3)
    obj.data.vertices.foreach_get("co", co)
    M = np.array(obj.matrix_world)
    P = co.reshape(-1, 3) @ M[:3, :3].T + M[:3, 3]
    return P @ S.T


def full_weights(obj, names):
    """(n, len(names)) vertex-group weights, 0 where a vertex is not in a group."""
    return vertex_groups.read_full_weights(obj, names)


def export(glb, npz, out, report_path):
    arm, obj = import_file(glb)
    with np.load(npz) as z:
        W = z["weights"].astype(np.float64)
        names = [str(s) for s in z["bone_names"]]
        V = z["vertices"].astype(np.float64) if "vertices" in z.files else None
    P = rest_positions(obj)
    report = {"blender": bpy.app.version_string, "bones": [b.name for b in arm.data.bones],
              "mesh_vertices": len(P), "rig_vertices": len(W)}
    scale = float(np.linalg.norm(P.max(0) - P.min(0))) if len(P) else 1.0
    if V is not None and len(P) == len(V) and np.abs(P - V).max(initial=0.0) <= 1e-6 * scale:
        rows, how = np.arange(len(P)), "index"
    else:
        from mathutils.kdtree import KDTree

        ref = V if V is not None else P
        tree = KDTree(len(ref))
        for i, p in enumerate(ref):
            tree.insert(p.tolist(), i)
        tree.balance()
        rows, how = np.array([tree.find(p.tolist())[1] for p in P]), "nearest position"
    report["weights_matched_by"] = how
    vertex_groups.write_full_weights(obj, names, W, rows)
    report["influences_max"] = int((W[rows] > 0).sum(axis=1).max(initial=0))
    keys = obj.data.shape_keys
    report["shape_keys"] = [k.name for k in keys.key_blocks if k != keys.reference_key] if keys else []
    report["markers"] = sorted(o.name for o in bpy.context.scene.objects if o.type == "EMPTY")
    report["animations"] = [a.name for a in bpy.data.actions]
    bpy.ops.export_scene.fbx(filepath=out, use_selection=False, object_types={"ARMATURE", "MESH", "EMPTY"},
                             add_leaf_bones=False, use_armature_deform_only=False, use_mesh_modifiers=False,
                             mesh_smooth_type="OFF", primary_bone_axis="Y", secondary_bone_axis="X",
                             axis_forward="-Z", axis_up="Y", bake_anim=bool(bpy.data.actions),
                             bake_anim_use_all_actions=bool(bpy.data.actions), path_mode="AUTO")
    with open(report_path, "w") as fh:
        json.dump(report, fh, indent=1)


def inspect(path, out):
    arm, obj = import_file(path)
    bones = list(arm.data.bones)
    names = [b.name for b in bones]
    M = np.array(arm.matrix_world)
    heads = np.array([M[:3, :3] @ np.array(b.head_local) + M[:3, 3] for b in bones]) @ S.T
    parents = [(b.parent.name if b.parent else "") for b in bones]
    keys = obj.data.shape_keys
    key_names, deltas = [], []
    if keys:
        base = np.zeros(len(obj.data.vertices) * 3)
        keys.reference_key.data.foreach_get("co", base)
        L = np.array(obj.matrix_world)[:3, :3]
        for k in keys.key_blocks:
            if k == keys.reference_key:
                continue
            co = np.zeros_like(base)
            k.data.foreach_get("co", co)
            key_names.append(k.name)
            deltas.append(((co - base).reshape(-1, 3) @ L.T) @ S.T)
    np.savez(out, bone_names=np.array(names), bone_parents=np.array(parents), bone_heads=heads,
             positions=rest_positions(obj), weights=full_weights(obj, names), shape_key_names=np.array(key_names),
             shape_key_deltas=np.array(deltas).reshape(len(deltas), len(obj.data.vertices), 3),
             markers=np.array(sorted(o.name for o in bpy.context.scene.objects if o.type == "EMPTY")),
             blender=np.array(bpy.app.version_string))


def pose(path, turns_path, out):
    import mathutils

    arm, obj = import_file(path)
    with open(turns_path) as fh:
        turns = json.load(fh)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    n = len(obj.data.vertices)
    P = np.zeros((len(turns), n, 3))
    for k, (bone, axis, degrees) in enumerate(turns):
        pb = arm.pose.bones[bone]
        pb.rotation_mode = "QUATERNION"  # the turn about the bone's rest axes, no Euler order involved
        pb.rotation_quaternion = mathutils.Quaternion(mathutils.Vector(axis).normalized(), np.radians(degrees))
        bpy.context.view_layer.update()
        ev = obj.evaluated_get(depsgraph)
        co = np.zeros(len(ev.data.vertices) * 3)
        ev.data.vertices.foreach_get("co", co)
        if len(co) != 3 * n:
            raise SystemExit(f"{path}: the evaluated mesh has {len(co) // 3} vertices, the mesh {n}")
        M = np.array(ev.matrix_world)
        P[k] = (co.reshape(-1, 3) @ M[:3, :3].T + M[:3, 3]) @ S.T
        pb.rotation_quaternion = mathutils.Quaternion()
    bpy.context.view_layer.update()
    np.savez(out, positions=P, blender=np.array(bpy.app.version_string))


if __name__ == "__main__":
    args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    if len(args) == 5 and args[0] == "export":
        export(*args[1:])
    elif len(args) == 3 and args[0] == "inspect":
        inspect(*args[1:])
    elif len(args) == 4 and args[0] == "pose":
        pose(*args[1:])
    else:
        raise SystemExit("usage: blender -b -P blender_fbx.py -- export RIG.glb WEIGHTS.npz OUT.fbx REPORT.json | "
                         "inspect FILE OUT.npz | pose FILE TURNS.json OUT.npz")
