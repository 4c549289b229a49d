"""Write a saved rig as a UsdSkel stage (.usda, .usdc, .usd, .usdz) with usd-core.

Beyond the seeds (issue #17): film pipelines (Omniverse, Houdini, Maya, Apple) read USD. The
stage, its default prim ``/Rig`` a ``SkelRoot``:

- ``/Rig/Skeleton`` (``Skeleton``): one joint per glTF bone (marker nodes are not joints), joint
  paths from the bone names (``neck/head/jaw``; names that are not USD identifiers are made
  valid, the original names kept in ``jointNames``); ``bindTransforms`` = ``restTransforms``
  composed = the glb's rest pose: the glb's own joint frames (+Y from the joint's head to its
  tail, +X on the head's left-right axis), so turning a joint about its local axes turns the
  same way in USD as in the glb; the skinned points agree to float round-off when the weights
  are the same (``max_influences=4``; with every weight, the default, they differ by what the
  glb's four-influence cut leaves out).
- ``/Rig/Mesh`` (``Mesh``, triangles, ``subdivisionScheme = "none"``): the rig's vertices (float32
  of the exact input vertices, the input's own order), ``SkelBindingAPI`` with every influence
  the rig has (``primvars:skel:jointIndices`` / ``jointWeights``, elementSize = the largest number
  of non-zero weights on one vertex, not the glb's four, unless ``max_influences`` asks for the
  glb's), ``geomBindTransform`` identity (the mesh
  and the skeleton share the rig's frame), per-vertex ``primvars:autobones:*`` for the rig's depth
  labels and transferred fields.
- ``/Rig/Mesh/<name>`` (``BlendShape``): one per glb morph target (sparse ``offsets`` +
  ``pointIndices``); the names of ``skel:blendShapes`` are the prim names, each prim's
  ``customData["autobones:name"]`` keeps the original name.
- ``/Rig/Animations/<name>`` (``SkelAnimation``): one per glb animation, resampled at its key
  times; the first is the skeleton's ``skel:animationSource``.
- ``/Rig`` ``customData["autobones"]``: the frame, landmarks, muscles (origin, insertion, type,
  side, width), the muscle markers' joints, the source file, the version.

Frame and units: points stay in the rig's input frame and units (vertex for vertex the glb's).
``upAxis`` is ``Y`` or ``Z`` when the rig's detected up is ``+y`` or ``+z``; any other up (``-y``,
``±x``, ``-z``) gets ``upAxis = Y`` and a rotation on ``/Rig`` taking the detected up and front
axes to +Y and +Z. ``metersPerUnit``: the power of ten that makes the head size (the rig's frame
scale) nearest 0.3 m, a human head: metres, centimetres and millimetres scans all come out
right; pass ``meters_per_unit`` when the head is not human-sized or the unit is not metric.
"""
from __future__ import annotations

import math
import os

import numpy as np

from ..errors import AutobonesError
from ..arguments import finite_output
from ..io.atomic import check_destination, refuse_overwriting_inputs, replace_all, temp_beside
from . import USD_SUFFIXES
from .source import read_rig_source
from .usd_file import export_stage, pxr_modules, usd_errors, validate_stage

HUMAN_HEAD_M = 0.3   # a human head's size in metres (the frame's scale of the built-in head: 0.31)


def guess_meters_per_unit(head_size):
    """Metres per mesh unit: the power of ten taking ``head_size`` (mesh units) nearest
    :data:`HUMAN_HEAD_M` (0.31 -> 1, 31 -> 0.01, 310 -> 0.001)."""
    if not (head_size > 0 and math.isfinite(head_size)):
        return 1.0
    return 10.0 ** round(math.log10(HUMAN_HEAD_M / head_size))


def unique_identifiers(names, taken=()):
    """Valid USD prim names for ``names`` (list of str), distinct from each other and ``taken``."""
    _, _, Tf, *_ = pxr_modules()
    out, used = [], set(taken)
    for name in names:
        name = str(name)
        # a leading digit becomes "_9", not "_" (Tf would replace it): the digit is kept
        base = Tf.MakeValidIdentifier("_" + name if name[:1].isdigit() else name) if name else "_"
        ident, i = base, 1
        while ident in used:
            ident, i = f"{base}_{i}", i + 1
        used.add(ident)
        out.append(ident)
    return out


def joint_paths(names, parents):
    """UsdSkel joint paths (``neck/head/jaw``) from bone ``names`` and ``parents`` (-1: root):
    each element a valid identifier, siblings distinct."""
    paths = [None] * len(names)
    siblings = {}
    pending = list(range(len(names)))
    while pending:
        rest = []
        for k in pending:
            p = int(parents[k])
            if p >= 0 and paths[p] is None:
                rest.append(k)
                continue
            taken = siblings.setdefault(p, set())
            ident = unique_identifiers([names[k]], taken)[0]
            taken.add(ident)
            paths[k] = ident if p < 0 else f"{paths[p]}/{ident}"
        if len(rest) == len(pending):
            raise AutobonesError("the joints' parents form a cycle")
        pending = rest
    return paths


def all_influences(W):
    """Every non-zero weight of each vertex, largest first, as UsdSkel wants them.

    Parameters
    ----------
    W : (n, b) float
        Weights, rows summing to 1.

    Returns
    -------
    indices : (n, k) int32
        Joint indices; k = the largest count of non-zero weights on one vertex (at least 1);
        0 in unused slots.
    weights : (n, k) float32
        Their weights, rows renormalised to sum 1; 0 in unused slots.
    """
    W = np.asarray(W, dtype=np.float64)
    n, b = W.shape
    k = max(int((W > 0).sum(axis=1).max(initial=0)), 1)
    idx = np.argsort(-W, axis=1, kind="stable")[:, :k]
    w = np.take_along_axis(W, idx, axis=1)
    w = np.where(w > 0, w, 0.0)
    s = w.sum(axis=1, keepdims=True)
    w = np.where(s > 0, w / np.where(s > 0, s, 1.0), 0.0)
    idx = np.where(w > 0, idx, 0)
    return idx.astype(np.int32), w.astype(np.float32)


def _frame_orientation(frame):
    """(up axis token, 3x3 rotation or None): see the module doc."""
    up = frame.up
    if up == "+y":
        return "Y", None
    if up == "+z":
        return "Z", None
    axes = {"x": 0, "y": 1, "z": 2}

    def unit(a):
        v = np.zeros(3)
        v[axes[a[1]]] = 1.0 if a[0] == "+" else -1.0
        return v

    u, f = unit(up), unit(frame.front)
    if abs(u @ f) > 0.5:  # degenerate: keep the data as it is
        return "Y", None
    x = np.cross(u, f)
    R = np.stack([x, u, f])  # rows: new x, y, z in input coordinates -> R @ p is the upright point
    return "Y", R


def _to_vt(value):
    """JSON value -> a value USD's customData holds (dicts, strings, numbers, arrays); None dropped."""
    if isinstance(value, dict):
        return {str(k): _to_vt(v) for k, v in value.items() if v is not None}
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if isinstance(value, (list, tuple)):
        if len(value) == 3 and all(isinstance(r, (list, tuple)) and len(r) == 3 for r in value):
            from pxr import Gf

            return Gf.Matrix3d([[float(x) for x in r] for r in value])  # e.g. the frame's rotation
        items = [v for v in value if v is not None]
        if items and all(isinstance(v, (int, float, np.floating, np.integer)) and not isinstance(v, bool)
                         for v in items):
            from pxr import Vt

            return Vt.DoubleArray([float(v) for v in items])
        if all(isinstance(v, str) for v in items):
            from pxr import Vt

            return Vt.StringArray(items)
        return {str(i): _to_vt(v) for i, v in enumerate(items)}
    if isinstance(value, (np.floating, float)):
        return float(value)
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (np.integer, int)):
        return int(value)
    return str(value)


def _rig_record(src, meters_per_unit, guessed):
    rig = src.rig
    from ..version import __version__

    rec = {"format": "autobones-usd/1", "autobones_version": __version__, "source": os.path.basename(src.path),
           "frame": rig.frame.to_dict(), "units": {"meters_per_unit": meters_per_unit,
                                                   "guessed_from_head_size": guessed}}
    if rig.landmarks:
        rec["landmarks"] = {n: np.asarray(p, dtype=float).tolist() for n, p in rig.landmarks.items()}
    if rig.muscles:
        rec["muscles"] = {str(m.get("name", i)): m for i, m in enumerate(rig.muscles)}
    if src.markers:
        rec["muscle_markers"] = dict(src.markers)
    return _to_vt(rec)


def skin_weights(W, max_influences=None):
    """The weights a stage carries: ``W`` (n, b) as it is (None), or each vertex's
    ``max_influences`` largest renormalised exactly as the glb writes them
    (:func:`autobones.io.gltf.top_influences`), so a DCC deforms the mesh as glTF clients do."""
    if max_influences is None:
        return np.asarray(W, dtype=np.float64)
    from ..io.gltf import top_influences

    if int(max_influences) < 1:
        raise AutobonesError(f"max influences must be at least 1, not {max_influences!r}")
    J, w = top_influences(W, int(max_influences))
    out = np.zeros(np.shape(W))
    np.add.at(out, (np.repeat(np.arange(len(J)), J.shape[1]), J.ravel()), w.ravel().astype(np.float64))
    return out


def build_stage(src, meters_per_unit=None, max_influences=None):
    """The UsdSkel stage (in memory) of a :class:`autobones.export.source.RigSource`; see the module doc.
    ``max_influences``: None keeps every weight, k keeps the glb's k largest (:func:`skin_weights`)."""
    Gf, Sdf, Tf, Usd, UsdGeom, UsdSkel, Vt = pxr_modules()
    rig = src.rig
    guessed = meters_per_unit is None
    mpu = guess_meters_per_unit(float(rig.frame.size)) if guessed else float(meters_per_unit)
    if not (mpu > 0 and math.isfinite(mpu)):
        raise AutobonesError(f"meters per unit must be a positive number, not {meters_per_unit!r}")
    stage = Usd.Stage.CreateInMemory()
    up, R = _frame_orientation(rig.frame)
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y if up == "Y" else UsdGeom.Tokens.z)
    UsdGeom.SetStageMetersPerUnit(stage, mpu)
    root = UsdSkel.Root.Define(stage, "/Rig")
    stage.SetDefaultPrim(root.GetPrim())
    if R is not None:
        M = np.eye(4)
        M[:3, :3] = R.T  # row-vector convention: p_upright = p @ R.T
        root.AddTransformOp().Set(Gf.Matrix4d(M.tolist()))
    root.GetPrim().SetCustomDataByKey("autobones", _rig_record(src, mpu, guessed))

    # skeleton: USD matrices act on row vectors, the transpose of the column-vector ones
    skel = UsdSkel.Skeleton.Define(stage, "/Rig/Skeleton")
    paths = joint_paths(src.joint_names, src.parents)
    skel.CreateJointsAttr(Vt.TokenArray(paths))
    skel.CreateJointNamesAttr(Vt.TokenArray(src.joint_names))
    skel.CreateBindTransformsAttr(Vt.Matrix4dArray([Gf.Matrix4d(m.T.tolist()) for m in src.world]))
    skel.CreateRestTransformsAttr(Vt.Matrix4dArray([Gf.Matrix4d(m.T.tolist()) for m in src.local]))

    mesh = _define_mesh(stage, src, Gf, UsdGeom, Vt)
    binding = UsdSkel.BindingAPI.Apply(mesh.GetPrim())
    binding.CreateSkeletonRel().SetTargets([skel.GetPath()])
    idx, w = all_influences(skin_weights(rig.weights, max_influences))
    k = idx.shape[1]
    binding.CreateJointIndicesPrimvar(False, k).Set(Vt.IntArray.FromNumpy(np.ascontiguousarray(idx.ravel())))
    binding.CreateJointWeightsPrimvar(False, k).Set(Vt.FloatArray.FromNumpy(np.ascontiguousarray(w.ravel())))
    binding.CreateGeomBindTransformAttr(Gf.Matrix4d(1.0))
    _add_vertex_primvars(mesh, rig, Sdf, UsdGeom, Vt)

    shape_names = unique_identifiers([name for name, _ in src.morph_targets])
    if src.morph_targets:
        targets = []
        for ident, (name, delta) in zip(shape_names, src.morph_targets):
            bs = UsdSkel.BlendShape.Define(stage, mesh.GetPath().AppendChild(ident))
            moved = np.flatnonzero(np.any(delta != 0, axis=1)).astype(np.int32)
            bs.CreateOffsetsAttr(Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(delta[moved], dtype=np.float32)))
            bs.CreatePointIndicesAttr(Vt.IntArray.FromNumpy(moved))
            bs.GetPrim().SetCustomDataByKey("autobones:name", name)
            targets.append(bs.GetPath())
        binding.CreateBlendShapesAttr(Vt.TokenArray(shape_names))
        binding.CreateBlendShapeTargetsRel().SetTargets(targets)

    if src.animations:
        _define_animations(stage, skel, src.animations, paths, shape_names, UsdGeom, UsdSkel)
    return stage


def _define_mesh(stage, src, Gf, UsdGeom, Vt):
    """``/Rig/Mesh``: the rig's triangles and vertices (n, 3) as float32 (input frame and units), after
    refusing anything non-finite the stage would carry."""
    rig = src.rig
    mesh = UsdGeom.Mesh.Define(stage, "/Rig/Mesh")
    F = np.asarray(rig.faces, dtype=np.int32)
    # the last line of defence (issue #33): nothing non-finite reaches the stage, whatever the rig holds; a
    # value past float32's range is named by the check, not warned of by numpy
    with np.errstate(over="ignore"):
        V = np.asarray(rig.vertices, dtype=np.float32)
        finite_output(None, "the USD stage", ("points (float32)", V),
                      *((f"blend shape {n} (float32)", np.asarray(d, dtype=np.float32)) for n, d in src.morph_targets),
                      *((f"animation {a.name}", x) for a in src.animations
                        for x in (a.times, a.translations, a.rotations, a.scales)
                        if x is not None),
                      *((f"animation {a.name} weights (float32)", np.asarray(a.morph_weights, dtype=np.float32))
                        for a in src.animations if a.morph_weights is not None))
    mesh.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(V)))
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(np.full(len(F), 3, dtype=np.int32)))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(np.ascontiguousarray(F.ravel())))
    mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)  # triangles as they are, no Catmull-Clark
    mesh.CreateOrientationAttr(UsdGeom.Tokens.rightHanded)  # glTF's counter-clockwise front faces
    lo, hi = (V.min(axis=0), V.max(axis=0)) if len(V) else (np.zeros(3), np.zeros(3))
    mesh.CreateExtentAttr(Vt.Vec3fArray([Gf.Vec3f(*map(float, lo)), Gf.Vec3f(*map(float, hi))]))
    return mesh


def _define_animations(stage, skel, animations, paths, shape_names, UsdGeom, UsdSkel):
    """A ``SkelAnimation`` per animation under ``/Rig/Animations``, key times (s) in time codes of one
    frame rate (:func:`_frame_rate`); the first drives ``skel``. ``paths``: the joint paths."""
    UsdGeom.Scope.Define(stage, "/Rig/Animations")
    anims = unique_identifiers([a.name for a in animations])
    fps = _frame_rate(np.concatenate([a.times for a in animations]))
    stage.SetTimeCodesPerSecond(fps)
    stage.SetFramesPerSecond(fps)
    first = None
    for ident, a in zip(anims, animations):
        prim = write_animation(stage, f"/Rig/Animations/{ident}", paths, a.times * fps, a.translations,
                               a.rotations, a.scales,
                               None if a.morph_weights is None else shape_names, a.morph_weights)
        prim.GetPrim().SetCustomDataByKey("autobones:name", a.name)
        first = first or prim
    all_t = np.concatenate([a.times for a in animations]) * fps
    stage.SetStartTimeCode(float(all_t.min()))
    stage.SetEndTimeCode(float(all_t.max()))
    UsdSkel.BindingAPI.Apply(skel.GetPrim()).CreateAnimationSourceRel().SetTargets([first.GetPath()])


def write_animation(stage, path, joints, time_codes, translations, rotations, scales, shapes=None, shape_weights=None):
    """Define a ``SkelAnimation`` at ``path`` with every joint's local transform at each time code.

    Parameters
    ----------
    joints : list of str
        Joint paths (the skeleton's order).
    time_codes : (t,) float
    translations : (t, b, 3) float, rotations : (t, b, 4) float (x, y, z, w), scales : (t, b, 3) float
        Local (parent-relative) transforms, the rig's frame and units.
    shapes : list of str or None
        Blend shape names driven, with ``shape_weights`` (t, k) float.
    """
    Gf, Sdf, Tf, Usd, UsdGeom, UsdSkel, Vt = pxr_modules()
    anim = UsdSkel.Animation.Define(stage, path)
    anim.CreateJointsAttr(Vt.TokenArray(joints))
    ta, ra, sa = anim.CreateTranslationsAttr(), anim.CreateRotationsAttr(), anim.CreateScalesAttr()
    for i, t in enumerate(np.asarray(time_codes, dtype=np.float64)):
        tc = Usd.TimeCode(float(t))
        ta.Set(Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(translations[i], dtype=np.float32)), tc)
        ra.Set(Vt.QuatfArray([Gf.Quatf(float(q[3]), float(q[0]), float(q[1]), float(q[2])) for q in rotations[i]]), tc)
        sa.Set(Vt.Vec3hArray([Gf.Vec3h(*map(float, s)) for s in scales[i]]), tc)
    if shapes is not None and shape_weights is not None:
        anim.CreateBlendShapesAttr(Vt.TokenArray(shapes))
        wa = anim.CreateBlendShapeWeightsAttr()
        for i, t in enumerate(np.asarray(time_codes, dtype=np.float64)):
            wa.Set(Vt.FloatArray.FromNumpy(np.ascontiguousarray(shape_weights[i], dtype=np.float32)),
                   Usd.TimeCode(float(t)))
    return anim


def _frame_rate(times):
    """Time codes per second: the first common frame rate whose frames hold every key time, else 24."""
    for fps in (24.0, 25.0, 30.0, 48.0, 50.0, 60.0, 120.0):
        if np.all(np.abs(times * fps - np.round(times * fps)) < 1e-3):
            return fps
    return 24.0


def _add_vertex_primvars(mesh, rig, Sdf, UsdGeom, Vt):
    """Per-vertex ``primvars:autobones:label`` (0 face, 1 middle, 2 back) and each transferred field."""
    api = UsdGeom.PrimvarsAPI(mesh)
    n = len(rig.vertices)
    items = [("label", np.asarray(rig.labels))] + sorted((str(k), np.asarray(v)) for k, v in rig.fields.items())
    names = unique_identifiers([k for k, _ in items])
    for ident, (_, a) in zip(names, items):
        if a.shape[:1] != (n,) or a.ndim > 2:
            continue
        width = 1 if a.ndim == 1 else a.shape[1]
        if np.issubdtype(a.dtype, np.integer) or a.dtype == bool:
            pv = api.CreatePrimvar(f"autobones:{ident}", Sdf.ValueTypeNames.IntArray, UsdGeom.Tokens.vertex, width)
            pv.Set(Vt.IntArray.FromNumpy(np.ascontiguousarray(a.astype(np.int32).ravel())))
        else:
            pv = api.CreatePrimvar(f"autobones:{ident}", Sdf.ValueTypeNames.FloatArray, UsdGeom.Tokens.vertex, width)
            pv.Set(Vt.FloatArray.FromNumpy(np.ascontiguousarray(a.astype(np.float32).ravel())))


def write_usd(rig_path, out_path, meters_per_unit=None, max_influences=None):
    """Write the rig saved as ``rig_path`` to ``out_path`` as a UsdSkel stage (see the module doc).

    Parameters
    ----------
    rig_path : str or os.PathLike
        A glb written by autobones (``place``, ``transfer``, ``batch``), its ``.rig.json`` and
        ``.weights.npz`` beside it.
    out_path : str or os.PathLike
        ``.usda`` (text), ``.usdc`` or ``.usd`` (binary crate), ``.usdz`` (a package holding one
        ``.usdc``). Written under a temporary name and renamed when complete.
    meters_per_unit : float or None
        The stage's ``metersPerUnit``; None guesses it from the head size (:func:`guess_meters_per_unit`).
    max_influences : int or None
        None (the default) writes every weight of the rig; 4 writes the glb's four per vertex,
        so USD skins the mesh exactly as glTF clients skin the glb (:func:`skin_weights`).

    Returns
    -------
    dict
        ``path``; ``joints``, ``vertices``, ``influences`` (elementSize), ``blend_shapes``,
        ``animations`` (counts); ``meters_per_unit``, ``up_axis``; ``validation``: the
        findings of :func:`validate_stage` on the written file.

    Raises AutobonesError for a bad input (see :func:`read_rig_source`), an output that is the
    input, a suffix that is not USD's, or usd-core missing.
    """
    rig_path, out_path = os.fspath(rig_path), os.fspath(out_path)
    ext = os.path.splitext(out_path)[1].lower()
    if ext not in USD_SUFFIXES:
        raise AutobonesError(f"{out_path}: a USD file ends in .usd, .usda, .usdc or .usdz, not {ext or 'nothing'!r}")
    refuse_overwriting_inputs([out_path], [rig_path])
    check_destination(out_path, "the USD file")
    UsdGeom = pxr_modules()[4]
    src = read_rig_source(rig_path)
    stage = build_stage(src, meters_per_unit, max_influences)
    fd, tmp = temp_beside(out_path, suffix=ext)
    os.close(fd)
    try:
        with usd_errors(out_path):
            export_stage(stage, tmp, out_path, ext)
            findings = validate_stage(tmp)
        replace_all([(tmp, out_path)], "the USD file")
    finally:  # a partial file (a full disk) never stays
        if os.path.exists(tmp):
            os.remove(tmp)
    rig = src.rig
    idx, _ = all_influences(skin_weights(rig.weights, max_influences))
    return {"path": out_path, "joints": len(src.joint_names), "vertices": len(rig.vertices),
            "influences": int(idx.shape[1]), "blend_shapes": len(src.morph_targets),
            "animations": len(src.animations), "meters_per_unit": UsdGeom.GetStageMetersPerUnit(stage),
            "up_axis": str(UsdGeom.GetStageUpAxis(stage)), "validation": findings}
