"""Blender script: import a skinned .glb written by autobones and report how Blender sees it.

Run headless (Blender 3.4, its bundled glTF importer with default options)::

    blender -b --factory-startup --python-exit-code 1 -P tests/blender_check.py -- FILE.glb REPORT.json

Debian's Blender embeds the system Python and finds its standard library from the first
``python3.11`` on PATH; from a pyenv/virtualenv shell run it as ``PATH=/usr/bin:$PATH blender ...``
or the importer cannot find numpy (the pytest test does this itself).

Writes REPORT.json (all coordinates in the file's own glTF frame, converted back from
Blender's Z-up world; lengths in file units):

- ``armature``: an armature object was imported; ``bones``: its bone names;
  ``bone_heads``: each bone's head (the joint's rest position).
- ``vertex_groups``: per bone, whether a vertex group of that name exists and how many
  vertices have weight > 0 in it; ``vertex_count``, ``unweighted_vertices``.
- ``rest``: the evaluated mesh (depsgraph, armature modifier on) with no bone moved,
  compared with the file's POSITION accessor by nearest neighbour.
- ``poses``: for ``head``, ``neck`` and one facial bone, each rotated 30 degrees about
  its local X axis (separately): displacement of the evaluated mesh, displacement of
  vertices outside the rotated bone's chain (the bone and its descendants), the top of
  the head's displacement against a rigid rotation scaled by its chain weight, and how
  far the whole mesh is from linear blend skinning with Blender's own vertex groups.
- ``shape_keys`` (files with morph targets, else null): the shape key names Blender made
  and, per key set to 1 alone, the largest distance between the evaluated mesh's
  displacement and the file's morph target delta (``max_error``).

Blender's importer may drop vertices no triangle uses and split or merge vertices, so
Blender vertices are matched to file vertices by nearest position, never by index. The
script fails (non-zero exit with ``--python-exit-code 1``) only when it cannot produce a
report; judging the numbers is the caller's job.
"""
import json
import math
import sys

import bpy
import mathutils
import numpy as np
from mathutils.kdtree import KDTree

ROTATION_DEG = 30.0

# Blender 3.4's glTF importer (io_scene_gltf2 3.4.50, gltf2_blender_mesh.set_poly_smoothing)
# still uses ``np.bool``, which numpy 1.24 removed (Debian 12 ships numpy 1.24 with
# Blender 3.4.1): every import with default shading fails with AttributeError. Restore
# the alias so the importer runs with its default options.

def _addon_module(name):
    """The add-on's own ``name``.py, loaded by path (Blender runs this file as a script, outside the package):
    the glb reader and the vertex-group weights the add-on and the FBX export use."""
    import importlib.util
    import os

    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), os.pardir, "autobones", "blender_addon", name + ".py")
    spec = importlib.util.spec_from_file_location("autobones_addon_" + name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


glb_file, vertex_groups = _addon_module("glb"), _addon_module("vertex_groups")

if "bool" not in vars(np):  # (hasattr would itself warn on numpy 1.24)
    np.bool = bool


def accessor(doc, body, index):
    """An accessor's data as a numpy array (tightly packed views only, as autobones writes)."""
    acc = doc["accessors"][index]
    view = doc["bufferViews"][acc["bufferView"]]
    dtype = {5121: "<u1", 5123: "<u2", 5125: "<u4", 5126: "<f4"}[acc["componentType"]]
    width = {"SCALAR": 1, "VEC3": 3, "VEC4": 4, "MAT4": 16}[acc["type"]]
    start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
    a = np.frombuffer(body, dtype=dtype, count=width * acc["count"], offset=start)
    return a.reshape(acc["count"], width) if width > 1 else a


def to_file_frame(co):
    """Blender world (Z up) -> glTF (Y up): the importer maps glTF (x, y, z) to (x, -z, y)."""
    return (co[0], co[2], -co[1])


S = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])  # to_file_frame as a matrix


def evaluated_positions(obj):
    """(n, 3) world positions of the evaluated (deformed) mesh, file frame."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    ev = obj.evaluated_get(depsgraph)
    mesh = ev.to_mesh()
    M = ev.matrix_world
    P = np.array([to_file_frame(M @ v.co) for v in mesh.vertices], dtype=np.float64)
    ev.to_mesh_clear()
    return P


def shape_key_report(obj, doc, body, P_file, rest, tree_file):
    """The file's morph targets as Blender's shape keys: names, and for each key set to 1
    (alone), how far the evaluated mesh's displacement is from the file's POSITION delta.

    Each Blender vertex is compared with the file vertices at its rest position (within
    1e-6 of the bounding box diagonal; duplicates may carry different deltas, the closest
    counts). None when the file has no morph targets.
    """
    mesh = doc["meshes"][0]
    targets = mesh["primitives"][0].get("targets")
    if not targets:
        return None
    file_names = (mesh.get("extras") or {}).get("targetNames") or []
    keys = obj.data.shape_keys
    out = {"file_target_names": file_names, "file_weights": mesh.get("weights"),
           "reference": keys.reference_key.name if keys else None,
           "names": [k.name for k in keys.key_blocks if k != keys.reference_key] if keys else [],
           "values": {k.name: float(k.value) for k in keys.key_blocks} if keys else {},
           "keys": {}}
    if not keys:
        return out
    eps = 1e-6 * float(np.linalg.norm(P_file.max(0) - P_file.min(0)))
    match = [[j for _, j, _ in tree_file.find_range(p.tolist(), eps)] or [tree_file.find(p.tolist())[1]]
             for p in rest]
    for name in out["names"]:
        if name not in file_names:
            continue
        delta = accessor(doc, body, targets[file_names.index(name)]["POSITION"]).astype(np.float64)
        kb = keys.key_blocks[name]
        kb.value = 1.0
        bpy.context.view_layer.update()
        disp = evaluated_positions(obj) - rest
        kb.value = 0.0
        bpy.context.view_layer.update()
        err = np.array([np.linalg.norm(delta[js] - d, axis=1).min() for d, js in zip(disp, match)])
        out["keys"][name] = {"max_error": float(err.max()),
                             "max_file_delta": float(np.linalg.norm(delta, axis=1).max()),
                             "max_blender_displacement": float(np.linalg.norm(disp, axis=1).max()),
                             "vertices_moved": int((np.linalg.norm(disp, axis=1) > eps).sum())}
    out["rest_restored_max_error"] = float(np.linalg.norm(evaluated_positions(obj) - rest, axis=1).max())
    return out


def main(argv):
    glb, report_path = argv
    doc, body = glb_file.read_glb(glb)
    prim = doc["meshes"][0]["primitives"][0]
    P_file = accessor(doc, body, prim["attributes"]["POSITION"]).astype(np.float64)
    used = np.unique(accessor(doc, body, prim["indices"]))
    bpy.ops.wm.read_factory_settings(use_empty=True)
    # "BLENDER" keeps each joint's own axes (the writer points +Y from head to tail), so the
    # bones come in as placed; the default heuristic re-aims them at their children
    result = bpy.ops.import_scene.gltf(filepath=glb, bone_heuristic="BLENDER")
    report = {"blender": bpy.app.version_string, "import_result": sorted(result)}
    arms = [o for o in bpy.context.scene.objects if o.type == "ARMATURE"]
    meshes = [o for o in bpy.context.scene.objects if o.type == "MESH"]
    report["armature"] = len(arms) == 1
    report["mesh_objects"] = len(meshes)
    if len(arms) != 1 or len(meshes) != 1:
        report["objects"] = [(o.name, o.type) for o in bpy.context.scene.objects]
        with open(report_path, "w") as fh:
            json.dump(report, fh, indent=1)
        return
    arm, obj = arms[0], meshes[0]
    report["armature_modifier"] = any(m.type == "ARMATURE" and m.object == arm for m in obj.modifiers)
    names = [b.name for b in arm.data.bones]
    report["bones"] = names
    report["bone_heads"] = {b.name: to_file_frame(arm.matrix_world @ b.head_local) for b in arm.data.bones}
    report["bone_tails"] = {b.name: to_file_frame(arm.matrix_world @ b.tail_local) for b in arm.data.bones}
    report["bone_parents"] = {b.name: (b.parent.name if b.parent else None) for b in arm.data.bones}

    # vertex groups
    W = vertex_groups.read_full_weights(obj, names)
    report["vertex_groups"] = {n: {"exists": n in obj.vertex_groups, "vertices": int((W[:, j] > 0).sum())}
                               for j, n in enumerate(names)}
    report["extra_vertex_groups"] = [g.name for g in obj.vertex_groups if g.name not in names]
    report["vertex_count"] = len(obj.data.vertices)
    report["file_vertex_count"] = len(P_file)
    report["unweighted_vertices"] = int((W.sum(axis=1) <= 0).sum())
    report["weight_sum_range"] = [float(W.sum(axis=1).min()), float(W.sum(axis=1).max())]

    # rest pose against the file, by nearest neighbour both ways
    rest = evaluated_positions(obj)
    tree_file = KDTree(len(P_file))
    for i, p in enumerate(P_file):
        tree_file.insert(p.tolist(), i)
    tree_file.balance()
    d_b2f = np.array([tree_file.find(p.tolist())[2] for p in rest])
    tree_bl = KDTree(len(rest))
    for i, p in enumerate(rest):
        tree_bl.insert(p.tolist(), i)
    tree_bl.balance()
    d_f2b = np.array([tree_bl.find(P_file[i].tolist())[2] for i in used])
    report["rest"] = {"max_blender_to_file": float(d_b2f.max()), "max_file_to_blender": float(d_f2b.max()),
                      "file_vertices_used_by_faces": int(len(used)),
                      "bbox_diagonal": float(np.linalg.norm(P_file.max(0) - P_file.min(0)))}

    # poses
    children = {b.name: [c.name for c in b.children_recursive] for b in arm.data.bones}
    faces = [n for n in names if n.startswith("face_")]
    # the facial bone with the most weighted vertices: the clearest motion to look for
    face = max(faces, key=lambda n: report["vertex_groups"][n]["vertices"]) if faces else None
    neck_head = np.array(report["bone_heads"].get("neck", (0, 0, 0)))
    head_head = np.array(report["bone_heads"].get("head", (0, 1, 0)))
    up = head_head - neck_head
    up = up / (np.linalg.norm(up) or 1.0)
    top = int(np.argmax(rest @ up))  # the top of the head: farthest along neck -> head joint
    report["top_vertex"] = {"index": top, "position": rest[top].tolist()}
    report["poses"] = {}
    for name in [n for n in ("head", "neck", face, "jaw") if n in names]:
        pb = arm.pose.bones[name]
        pb.rotation_mode = "QUATERNION"
        pb.rotation_quaternion = mathutils.Quaternion((1.0, 0.0, 0.0), math.radians(ROTATION_DEG))
        bpy.context.view_layer.update()
        posed = evaluated_positions(obj)
        # rigid motion of the whole chain, in the file frame: world = A @ rest
        A_bl = arm.matrix_world @ pb.matrix @ pb.bone.matrix_local.inverted() @ arm.matrix_world.inverted()
        A = np.array(A_bl)
        R = S @ A[:3, :3] @ S.T
        t = S @ A[:3, 3]
        rigid = rest @ R.T + t
        chain = [name] + children[name]
        w_chain = W[:, [names.index(c) for c in chain]].sum(axis=1)
        lbs = w_chain[:, None] * rigid + (1.0 - w_chain[:, None]) * rest
        disp = np.linalg.norm(posed - rest, axis=1)
        outside = w_chain <= 0
        moved = disp > 1e-3 * report["rest"]["bbox_diagonal"]
        pivot = np.array(to_file_frame(arm.matrix_world @ pb.bone.head_local))
        k = int(np.argmax(disp))
        strong = disp >= 0.5 * disp.max()  # where the bone's motion is concentrated
        report["poses"][name] = {
            "chain": chain,
            "pivot": pivot.tolist(),
            "max_displacement": float(disp.max()),
            "argmax_position": posed[k].tolist(),
            "argmax_rest_position": rest[k].tolist(),
            "vertices_in_chain": int((~outside).sum()),
            "vertices_outside_chain": int(outside.sum()),
            "max_displacement_outside_chain": float(disp[outside].max()) if outside.any() else 0.0,
            "vertices_moved": int(moved.sum()),
            "moved_centroid": (rest[moved].mean(axis=0).tolist() if moved.any() else None),
            "moved_max_distance_to_pivot": (float(np.linalg.norm(rest[moved] - pivot, axis=1).max())
                                            if moved.any() else None),
            "strongly_moved": int(strong.sum()),
            "strongly_moved_centroid": rest[strong].mean(axis=0).tolist(),
            "strongly_moved_max_distance_to_pivot": float(np.linalg.norm(rest[strong] - pivot, axis=1).max()),
            "top_displacement": float(disp[top]),
            "top_chain_weight": float(w_chain[top]),
            "top_rigid_displacement": float(np.linalg.norm(rigid[top] - rest[top])),
            "max_error_vs_lbs": float(np.linalg.norm(posed - lbs, axis=1).max()),
        }
        if name == "jaw":  # per vertex, in the file's order, to see which parts the jaw carries
            report["poses"][name]["displacement"] = [float(d) for d in disp]
        pb.rotation_quaternion = mathutils.Quaternion()
        bpy.context.view_layer.update()
    after = evaluated_positions(obj)
    report["rest_restored_max_error"] = float(np.linalg.norm(after - rest, axis=1).max())
    report["shape_keys"] = shape_key_report(obj, doc, body, P_file, rest, tree_file)
    with open(report_path, "w") as fh:
        json.dump(report, fh, indent=1)


if __name__ == "__main__":
    args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    if len(args) != 2:
        raise SystemExit("usage: blender -b --factory-startup --python-exit-code 1 "
                         "-P tests/blender_check.py -- FILE.glb REPORT.json")
    main(args)
