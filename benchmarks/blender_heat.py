"""Blender script: time Blender's own bone-heat skinning on autobones' mesh and bones.

This is a Blender script, not a test and not a plain Python module: pytest never runs it,
and it only imports inside Blender (``bpy``). ``benchmarks/place.py`` runs it headless as a
subprocess to report autobones' weights stage against Blender's "Parent with Automatic
Weights" (``bpy.ops.object.parent_set(type='ARMATURE_AUTO')``) on the same mesh and bones::

    PATH=/usr/bin:$PATH blender -b --factory-startup --python-exit-code 1 \\
        -P benchmarks/blender_heat.py -- MESH.npz REPORT.json

(Debian's Blender embeds the system Python and finds its standard library from the first
``python3.11`` on PATH; from a pyenv/virtualenv shell the ``PATH=/usr/bin:$PATH`` prefix is
needed or ``import numpy`` fails. See ``tests/blender_check.py``.)

MESH.npz (``np.load(..., allow_pickle=False)``):

- ``V`` (n, 3) float64 vertices, ``F`` (m, 3) int64 triangles;
- ``heads``, ``tails`` (b, 3) float64 bone heads and tails, same frame and units as ``V``;
- ``parents`` (b,) int64, -1 for the root, parents before children;
- ``names`` (b,) fixed-width unicode (``np.array(names, dtype=str)``).

Nothing is rescaled: Blender works in the mesh's own units, as a user importing that mesh
would (bone heat depends on scale through Blender's fixed epsilons; call it with a scaled
copy to see that). The mesh object and armature object both sit at the origin with identity
transforms; each bone goes from its head to its tail (roll 0, not connected, deforming),
parented as given.

What is timed (``time.perf_counter``):

- ``seconds``: only the ``bpy.ops.object.parent_set(type='ARMATURE_AUTO')`` call, with the
  armature active and both objects selected in object mode. That call is Blender's whole
  "Automatic Weights": vertex groups for the deforming bones, the bone-heat solve
  (visibility ray casts, Laplacian factorisation, one solve per bone), writing the weights,
  the parenting and the Armature modifier. ``cpu_seconds`` is the process CPU time of the
  same call (all threads), to read ``seconds`` against on a loaded machine.
- ``build_seconds``: building the mesh datablock from the arrays (``vertices.add`` +
  ``foreach_set`` for positions, loops and polygons, ``update(calc_edges=True)``; on 1M
  vertices 1.7 s against 5.6 s for ``from_pydata`` in Blender 3.4.1), the mesh object, and
  the armature built in edit mode. Reading the .npz and counting weights afterwards are not
  in either figure.

REPORT.json (strict JSON, no NaN)::

    {"seconds": float, "cpu_seconds": float, "build_seconds": float, "n_vertices": int, "n_bones": int,
     "unweighted_vertices": int, "groups": int, "blender_version": str,
     "heat_failed": bool, "flat_cotangent_vertices": int, "reports": [str, ...]}

``unweighted_vertices`` counts mesh vertices with no vertex-group weight > 0 after the call;
``groups`` is the number of vertex groups the call created. When Blender's heat solver fails
it reports "Bone Heat Weighting: failed to find solution for one or more bones" as a warning
on the operator; bpy prints operator reports to Python's stdout, which this script also
captures: ``reports`` holds the lines it printed during the call and ``heat_failed`` whether
one of them is that message. The message still reaches the process's stdout, so the caller
can grep the subprocess output as well. ``flat_cotangent_vertices`` is a diagnostic for that
failure: vertices whose every triangle Blender gives a zero cotangent weight (twice its area
at most ``FLT_EPSILON``, an absolute threshold; see :func:`flat_cotangent_vertices`). In the
runs so far Blender failed exactly when this was > 0 (LeePerrySmith scaled by 0.01, the
535k-vertex demosthenes at its own scale); the failing call returns early and leaves every
vertex unweighted.

The script fails (non-zero exit with ``--python-exit-code 1``) only when it cannot produce a
report (bad input, the operator raising); judging the numbers is the caller's job.
"""
import contextlib
import io
import json
import sys
import time

import bpy
import numpy as np

HEAT_FAILURE = "failed to find solution"


class _Tee(io.TextIOBase):
    """A text stream writing to ``stream`` and keeping a copy."""

    def __init__(self, stream):
        self.stream, self.copy = stream, io.StringIO()

    def write(self, s):
        self.copy.write(s)
        return self.stream.write(s)

    def flush(self):
        self.stream.flush()


def load_input(path):
    """(V, F, heads, tails, parents, names) from MESH.npz, checked so Blender cannot crash on them."""
    with np.load(path, allow_pickle=False) as z:
        V = np.asarray(z["V"], dtype=np.float64)
        F = np.asarray(z["F"], dtype=np.int64)
        heads = np.asarray(z["heads"], dtype=np.float64)
        tails = np.asarray(z["tails"], dtype=np.float64)
        parents = np.asarray(z["parents"], dtype=np.int64)
        names = [str(s) for s in z["names"]]
    b = len(names)
    assert V.ndim == 2 and V.shape[1] == 3 and len(V) > 0, f"V: shape {V.shape}"
    assert F.ndim == 2 and F.shape[1] == 3 and len(F) > 0, f"F: shape {F.shape}"
    assert F.min() >= 0 and F.max() < len(V), "F: index out of range"
    assert np.isfinite(V).all() and np.isfinite(heads).all() and np.isfinite(tails).all(), "non-finite coordinates"
    assert heads.shape == (b, 3) and tails.shape == (b, 3) and parents.shape == (b,), "bone array shapes"
    assert all(-1 <= p < i for i, p in enumerate(parents)), "parents must come before children"
    assert len(set(names)) == b, "bone names must be unique"
    assert all(0 < len(n.encode()) < 64 for n in names), "Blender names are 1 to 63 bytes"
    # Blender deletes zero-length bones when leaving edit mode
    assert (np.linalg.norm(tails - heads, axis=1) > 0).all(), "zero-length bone"
    return V, F, heads, tails, parents, names


def build_mesh(V, F):
    """A triangle mesh datablock from arrays (the bulk ``foreach_set`` path)."""
    me = bpy.data.meshes.new("head")
    me.vertices.add(len(V))
    me.vertices.foreach_set("co", np.ascontiguousarray(V, dtype=np.float32).ravel())
    me.loops.add(3 * len(F))
    me.loops.foreach_set("vertex_index", np.ascontiguousarray(F, dtype=np.int32).ravel())
    me.polygons.add(len(F))
    me.polygons.foreach_set("loop_start", np.arange(0, 3 * len(F), 3, dtype=np.int32))
    me.polygons.foreach_set("loop_total", np.full(len(F), 3, dtype=np.int32))
    me.update(calc_edges=True)
    return me


def build_armature(heads, tails, parents, names):
    """An armature object with one deforming bone per head/tail, built in edit mode."""
    arm_data = bpy.data.armatures.new("rig")
    arm = bpy.data.objects.new("rig", arm_data)
    bpy.context.scene.collection.objects.link(arm)
    bpy.context.view_layer.objects.active = arm
    bpy.ops.object.mode_set(mode="EDIT")
    bones = []
    for name, h, t, p in zip(names, heads, tails, parents):
        eb = arm_data.edit_bones.new(name)
        eb.head = h.tolist()
        eb.tail = t.tolist()
        eb.roll = 0.0
        eb.use_deform = True
        eb.use_connect = False
        if p >= 0:
            eb.parent = bones[p]
        bones.append(eb)
    bpy.ops.object.mode_set(mode="OBJECT")
    got = [b.name for b in arm_data.bones]
    assert got == names, f"Blender renamed or dropped bones: {sorted(set(names) - set(got))}"
    return arm


def flat_cotangent_vertices(V, F):
    """Vertices all of whose triangles have ``|cross| <= FLT_EPSILON`` in float32.

    Blender's ``cotangent_tri_weight_v3`` returns 0 for such a triangle (an absolute
    threshold, so it depends on the mesh's units and density): a vertex with only such
    triangles gets an empty Laplacian row, and if it sees no bone the heat system is
    singular. A diagnostic for ``heat_failed``, computed outside both timings.
    """
    P = np.asarray(V, dtype=np.float32)
    cross = np.cross(P[F[:, 1]] - P[F[:, 0]], P[F[:, 2]] - P[F[:, 0]])
    ok = np.sqrt(np.einsum("ij,ij->i", cross, cross)) > np.finfo(np.float32).eps
    has_weight = np.zeros(len(V), dtype=bool)
    has_weight[F[ok].ravel()] = True
    return int((~has_weight).sum())


def unweighted_count(obj):
    """Vertices of ``obj`` with no vertex-group weight > 0."""
    return sum(1 for v in obj.data.vertices if not any(g.weight > 0.0 for g in v.groups))


def main(argv):
    mesh_path, report_path = argv
    V, F, heads, tails, parents, names = load_input(mesh_path)
    bpy.ops.wm.read_factory_settings(use_empty=True)

    t0 = time.perf_counter()
    me = build_mesh(V, F)
    obj = bpy.data.objects.new("head", me)
    bpy.context.scene.collection.objects.link(obj)
    arm = build_armature(heads, tails, parents, names)
    build_seconds = time.perf_counter() - t0
    assert len(me.vertices) == len(V) and len(me.polygons) == len(F)

    for o in bpy.context.view_layer.objects:
        o.select_set(False)
    obj.select_set(True)
    arm.select_set(True)
    bpy.context.view_layer.objects.active = arm
    assert len(obj.vertex_groups) == 0

    tee = _Tee(sys.stdout)
    with contextlib.redirect_stdout(tee):
        t0, c0 = time.perf_counter(), time.process_time()
        result = bpy.ops.object.parent_set(type="ARMATURE_AUTO")
        seconds, cpu_seconds = time.perf_counter() - t0, time.process_time() - c0
    sys.stdout.flush()
    reports = [line for line in tee.copy.getvalue().splitlines() if line.strip()]
    assert result == {"FINISHED"}, f"parent_set returned {result}"
    assert obj.parent == arm, "the mesh was not parented to the armature"

    report = {
        "seconds": float(seconds),
        "cpu_seconds": float(cpu_seconds),
        "build_seconds": float(build_seconds),
        "n_vertices": len(me.vertices),
        "n_bones": len(arm.data.bones),
        "unweighted_vertices": int(unweighted_count(obj)),
        "groups": len(obj.vertex_groups),
        "blender_version": bpy.app.version_string,
        "heat_failed": any(HEAT_FAILURE in line for line in reports),
        "flat_cotangent_vertices": flat_cotangent_vertices(V, F),
        "reports": reports,
    }
    with open(report_path, "w") as fh:
        json.dump(report, fh, indent=1, allow_nan=False)
    print(f"blender_heat: {json.dumps({k: v for k, v in report.items() if k != 'reports'})}")


if __name__ == "__main__":
    main(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])
