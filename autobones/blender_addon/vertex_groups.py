"""Every skin weight of a rig as Blender vertex groups, and back (one group per bone).

Beyond the papers: a glb carries only the four largest influences per vertex, while autobones'
``.weights.npz`` holds the whole (n, b) matrix (a medium ``place`` rig reaches 12 bones on a
vertex). Both the add-on (:mod:`.result`) and the FBX export (:mod:`autobones.export.blender_fbx`,
which imports this file by path) put that matrix into vertex groups, so the code lives here once.

Only ``bpy`` objects are touched; arrays are numpy. Runs inside Blender.
"""
import numpy as np


def write_full_weights(obj, names, W, rows=None):
    """Replace the vertex groups ``names`` of mesh object ``obj`` by the weights ``W``.

    Parameters
    ----------
    obj : bpy.types.Object
        A mesh object.
    names : sequence of str
        One group per column of ``W`` (bone names); made when missing, emptied when present.
    W : (r, len(names)) float
        Weights; only non-zero entries are written (Blender stores float32).
    rows : (n,) int or None
        Row of ``W`` for each of the mesh's n vertices; None when row i is vertex i.
    """
    n = len(obj.data.vertices)
    W = np.asarray(W, dtype=np.float64)
    W = W if rows is None else W[np.asarray(rows)]
    if W.shape != (n, len(names)):
        raise ValueError(f"weights {W.shape} for a mesh of {n} vertices and {len(names)} groups")
    everyone = list(range(n))
    for j, name in enumerate(names):
        group = obj.vertex_groups.get(name) or obj.vertex_groups.new(name=name)
        group.remove(everyone)
        col = W[:, j]
        nonzero = np.flatnonzero(col > 0)
        # one add() per distinct value: whole regions share a weight of exactly 1 (the neck's base,
        # the skull), so this is far fewer calls than one per vertex, with the same result
        values, inverse, counts = np.unique(col[nonzero], return_inverse=True, return_counts=True)
        members = np.split(nonzero[np.argsort(inverse, kind="stable")], np.cumsum(counts)[:-1])
        for value, vertices in zip(values, members):
            group.add(vertices.tolist(), float(value), "REPLACE")


def read_full_weights(obj, names):
    """(n, len(names)) float64 weights of ``obj``'s vertex groups ``names``; 0 where a vertex is not in one."""
    col = {obj.vertex_groups[n].index: j for j, n in enumerate(names) if n in obj.vertex_groups}
    W = np.zeros((len(obj.data.vertices), len(names)))
    for v in obj.data.vertices:
        for g in v.groups:
            if g.group in col:
                W[v.index, col[g.group]] = g.weight
    return W
