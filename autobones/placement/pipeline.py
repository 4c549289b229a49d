"""``place``: landmark-free head, neck and facial bones with smooth skin weights.

The bone-placement method of ``place``: average-linkage grouping of the head by depth
(head and neck bones), k-means facial bones, bone-heat skin weights.

The pipeline, one module a stage: load (io.mesh) -> orient -> segment (head and
neck bones) -> facial (facial bones) -> weights -> Rig (save writes io.gltf).
All geometry runs in the canonical frame; results go back to the input frame.
"""
from __future__ import annotations

import logging
import time

import numpy as np

from .facial_bones import bone_count, bones_for_mask, check_seed, facial_bones
from ..io.mesh import resolve_mesh, wound_outward
from ..io.parts import stray_parts, worn_parts
from ..geometry.proxy import mesh_proxy
from ..geometry.head_share import face_only
from ..geometry.rigid_parts import closed_small_parts, rigid_weights
from ..geometry.topology import used_vertices
from ..geometry.winding import outward_faces
from ..orient import Frame, close_front, detect_frame
from ..rig import Rig
from ..timing import Stopwatch
from .segment import segment_head
from ..skeleton import Skeleton
from .locality import restrict_weights
from .skin_weights import PROXY_ABOVE, PROXY_VERTICES, WELD_TOL, bone_heat_weights

log = logging.getLogger("autobones")

NO_NECK = 0.01   # head sizes: a menton this close to the lowest vertex has no neck under it (_no_neck)
MIDLINE = 0.03   # head sizes either side of the symmetry plane: a face mask's midline (_no_neck)
FLAT_BASE = 0.5  # of the head's depth: a lowest level that wide is a flat base, not a chin (_no_neck)
ANGLE_SHARE = (0.42, 0.15)   # the jaw's angle between the menton and the head joint: height, depth (jaw_angle)


def place(mesh=None, density="medium", up=None, front=None, random_state=0, landmarks=None, rig=None):
    """Rig a head: head and neck bones, facial bones, smooth skin weights.

    Parameters
    ----------
    mesh : str, (V, F) or None
        A mesh file, arrays ``V`` (n, 3) float and ``F`` (m, 3) int in any
        frame and unit, or None for the built-in default head.
    density : {'sparse', 'medium', 'dense'} or int
        Facial bones: 8, 16, 32, or that many.
    up, front : str or None
        Force the input axis pointing up / out of the face (``'+z'``, ``'-x'``...).
    random_state : int
        Seed of the k-means restarts; the same seed gives the same rig.
    landmarks : str or dict, optional
        With landmarks, the labelled generic rig (``rig``, default the built-in
        one) is transferred first (see :func:`autobones.transfer`): its ``neck``,
        ``head``, ``jaw`` and eye bones and their weights replace the depth-based
        head and neck bones, the facial mask is the transferred face (not neck,
        ears or scalp), and each facial bone becomes a child of the jaw or the
        head, splitting that bone's weight with it by bone heat.

    Returns
    -------
    Rig
        In the input's own frame and units, vertices unchanged.

    Examples
    --------
    >>> import os, tempfile
    >>> import autobones
    >>> from autobones import samples
    >>> rig = autobones.place(samples.path("robot.obj"), density="sparse")
    >>> rig.skeleton.names[:3], len(rig.skeleton.names)
    (['neck', 'head', 'face_00'], 10)
    >>> rig.frame.up, rig.frame.front
    ('+y', '+z')
    >>> bool(abs(rig.weights.sum(axis=1) - 1).max() < 1e-6)
    True
    >>> [os.path.basename(p) for p in rig.save(os.path.join(tempfile.mkdtemp(), "robot.glb"))]
    ['robot.glb', 'robot.rig.json', 'robot.weights.npz']
    """
    watch = Stopwatch()
    lap, timings = watch.lap, watch.timings

    n_bones = bone_count(density)
    random_state = check_seed(random_state)
    if landmarks is not None:
        return _place_on_transfer(mesh, landmarks, rig, n_bones, density, up, front, random_state)
    V, F, source = resolve_mesh(mesh, strays=True)
    # small parts far off (weighted to the neck), then large parts set on the head, a hat (weighted as
    # the skin under them): rigged without them (io.parts)
    body = stray_parts(V, F) or worn_parts(V, F)
    if body is not None:
        return body.restore(place(body.as_mesh(source), density, up, front, random_state), source)
    F_given, (F, wound) = F, wound_outward(V, F, source)   # rigged outward, written as given
    lap("load")
    frame = detect_frame(V, F, up=up, front=front)
    close = close_front(frame)
    if close:
        log.warning("%s: %s", source or "mesh", close)
    C = frame.to_canonical(V)
    lap("orient")
    # one welded copy, decimated for a dense scan, serves the inside tests, the closest surface points
    # and the heat solve; made in the canonical frame (head sizes) so the input's unit and axes do
    # not change it
    proxy = mesh_proxy(C, F, WELD_TOL, above=PROXY_ABOVE, vertices=PROXY_VERTICES)
    coarse = proxy.coarse_surface
    lap("proxy")
    log.info("frame: up %s, front %s, head size %.4g", frame.up, frame.front, frame.size)
    pivot, note = _face_mask_pivot(C, F)
    lap("face_landmarks")
    seg = segment_head(C, F, volume=coarse, pivot=pivot)
    if _no_neck(C, F, seg, frame):
        seg.joints.cues["neck"].append("no_neck")
    lap("segment")
    asked, n_bones = n_bones, _fewer_bones(n_bones, density, seg.facial_mask, source)
    heads, tails, model = facial_bones(C, F, seg.facial_mask, n_bones, random_state=random_state, surface=coarse)
    lap("facial")
    skel_c = _depth_skeleton(seg, heads, tails, n_bones)
    W = _local_weights(C, F, skel_c, proxy, seg, frame)
    lap("weights")
    options = {"density": density if isinstance(density, str) else int(density), "facial_bones": n_bones,
               "up": up, "front": front, "random_state": random_state}
    if n_bones != asked:
        options["facial_bones_asked"] = asked
    joints = seg.joints.to_dict()
    if note:
        joints["head"]["face_landmarks"] = note   # why a face mask's pivot is the nose rule's
    if wound:
        options["faces_turned"] = wound
    return Rig(vertices=V, faces=F_given, skeleton=skel_c.transformed(frame.from_canonical), weights=W,
               labels=seg.labels, facial_mask=seg.facial_mask, frame=frame, options=options,
               timings=timings, segmentation=seg, source=source, facial_bone_partner=model.partner_.tolist(),
               neck_height_canonical=seg.neck_height, other={"joints": joints})


def _face_mask_pivot(C, F):
    """((height, depth), None): a face mask's head pivot (canonical, head sizes) from its automatic
    landmarks (:func:`autobones.rig_transfer.face_joints.face_joints`); (None, why not) when none is
    found; (None, None) for a mesh that is no face mask. Found on the canonical mesh ``C`` (n, 3), in
    the canonical frame: a turned or rescaled copy of a head then gives the detector the same pictures
    (on the input's own vertices the menpo template's pivot moved 0.04 head sizes between copies)."""
    if not face_only(C, F):
        return None, None
    from ..rig_transfer.face_joints import face_joints

    joints, note = face_joints(C, F, Frame(np.eye(3), np.zeros(3), 1.0))
    if joints is None:
        log.info("face mask: its pivot from its nose (automatic landmarks: %s)", note)
        return None, note
    return (float(joints["head"][1]), float(joints["head"][2])), None


def _depth_skeleton(seg, heads, tails, n_bones):
    """The canonical skeleton of a landmark-free rig: ``neck`` and ``head`` from the depth grouping
    ``seg`` (:func:`segment_head`), then ``n_bones`` facial bones ``face_00``... (heads and tails
    (n_bones, 3) float, canonical frame, head sizes) all children of ``head``."""
    names = ["neck", "head"] + [f"face_{i:02d}" for i in range(n_bones)]
    parents = [-1, 0] + [1] * n_bones
    return Skeleton(names, parents,
                    np.vstack([seg.neck_bone[0], seg.head_bone[0], heads]),
                    np.vstack([seg.neck_bone[1], seg.head_bone[1], tails]))


def _local_weights(C, F, skel_c, proxy, seg, frame):
    """Bone-heat skin weights (n, b) float of the canonical head ``C`` (n, 3) float, head sizes,
    with triangles ``F`` (m, 3) int, for ``skel_c``'s b bones (canonical), restricted to their
    regions by :func:`restrict_weights` (with ``seg``'s masks and joints and ``frame``'s cut), each small
    closed part's rows made one (:mod:`autobones.geometry.rigid_parts`)."""
    W = bone_heat_weights(C, F, skel_c.segments, proxy=proxy, prune=0)  # pruned once, after the restriction
    # keep them local, on the full mesh (after a proxy's carry-up): facial bones on the face and its
    # blend band, the neck base pure neck, no neck weight on the skull
    joints = seg.joints
    restrict_weights(C, W, seg.facial_mask, seg.head_bone[0], neck=0, head=1, faces=F,
                     chin=(joints.menton, joints.chin_front), face_only="face_only" in joints.cues["head"],
                     cut=frame.cut, no_neck="no_neck" in joints.cues["neck"],
                     chin_base=joints.menton_source == "chin",
                     jaw_angle=jaw_angle(seg.head_bone[0], joints.menton, joints.chin_front))
    # eyeballs, teeth: a small closed part moves whole (the heat gave an eyeball's front and back different bones)
    return rigid_weights(W, C, F, closed_small_parts(C, F))


def jaw_angle(joint, menton, chin_front):
    """The jaw's angle (height, depth), canonical head sizes, where human heads put it between the head
    joint ``joint`` (3,) and the chin (``menton`` height, ``chin_front`` depth): ``ANGLE_SHARE`` of the way
    up from the menton to the joint, and of the way forward from the joint to the chin's front; None
    when the chin is not below and in front of the joint.

    ``place`` has no landmark for the gonions. Their proportions on eight human heads (the SMPL man's
    and woman's hand-placed gonions, and where the generic rig's landed on ICT 000-002, James, the
    menpo3d template and Lee Perry-Smith, each against ``place``'s own joint and chin): 0.38-0.52 of
    the height (median 0.42) and 0.16-0.54 of the depth. The straight line from the joint to the chin
    passed 0.05-0.10 head sizes over them, so the angle stayed with the neck on a head turn (the SMPL
    woman's head share 0.14 there) and the jaw folded along its lower border. The depth taken is the
    range's back end: the boundary passes under it and from there along the border to the chin, so
    under the angles further forward too (`benchmarks/head_turn.py`, the boundary down to two
    half-bands under the estimate as under a landmark's: the woman's angle 0.56 at the median depth
    0.40, 0.76 at 0.15; ``head_share``'s ``angle_estimated`` keeps it above the neck base, 0.44).
    """
    dy, dz = float(joint[1]) - menton, chin_front - float(joint[2])
    if not (dy > 0 and dz > 0):
        return None
    return menton + ANGLE_SHARE[0] * dy, float(joint[2]) + ANGLE_SHARE[1] * dz


def _fewer_bones(n_bones, density, mask, source):
    """:func:`bones_for_mask` for the facial ``mask`` (n,) bool, with one warning naming the head
    (``source``: its file, or None) when it places fewer bones than the density asks."""
    k = int(np.count_nonzero(mask))
    n = bones_for_mask(n_bones, density, k)
    if n != n_bones:
        log.warning("%sthe facial mask has %d vertices, too few for the %d facial bones of density %r: placed %d "
                    "(sidecar options.facial_bones)", f"{source}: " if source else "", k, n_bones, density, n)
    return n


def _no_neck(C, F, seg, frame):
    """Whether the head has no neck to weigh, from ``C`` (n, 3) canonical (used by ``F``), its
    :class:`.segment.HeadSegmentation` ``seg`` and its ``frame``:

    - nothing was cut below its chin (a face mask whose chin step, at its edge, was missed), unless
      its lowest level is a flat base as deep as the head (:data:`FLAT_BASE`): a neck's cap that the
      chin may reach (the robot's: 0.83 of its depth), not a chin alone (Suzanne's: 0.08);
    - or its menton lies within ``NO_NECK`` head sizes of its lowest vertex, with no planar cut
      (``frame.cut``) nor a flat base; on a face mask, of its lowest midline vertex. Its lowest
      vertices are then its chin, which must turn with the head: held still as a neck's base,
      Blender's Suzanne's muzzle tip stayed behind on a head turn and the muzzle sheared. (The
      mentons of the shared heads with no cut and no face mask lie 0.038-0.46 head sizes above their
      lowest vertex, Suzanne's 0.000-0.001.)
    """
    used = C[used_vertices(F, len(C))]
    low = used[used[:, 1] <= used[:, 1].min() + NO_NECK]
    flat = np.ptp(low[:, 2]) > FLAT_BASE * np.ptp(used[:, 2])
    if not (seg.neck.any() or flat):
        return True
    menton = seg.joints.menton
    if "face_only" in seg.joints.cues["head"]:
        # a mask that ends at its chin: what lies lower, at its sides, is the jaw's edge, not a neck
        # (fran_cut's lower edge dips 0.025 head sizes along its jaw; the neck took it once its chin,
        # at that edge, was found)
        mid = used[np.abs(used[:, 0]) < MIDLINE]
        return len(mid) > 0 and menton - float(mid[:, 1].min()) <= NO_NECK
    if frame.cut is not None or flat:
        return False
    return menton - float(used[:, 1].min()) <= NO_NECK


def _place_on_transfer(mesh, landmarks, rig, n_bones, density, up, front, random_state):
    """``place`` with landmarks: facial bones on top of the transferred neck, head, jaw and eyes."""
    from ..rig_transfer.pipeline import transfer

    base = transfer(mesh, landmarks, rig=rig, up=up, front=front, aim_head=False)
    t = time.perf_counter()
    V, frame = base.vertices, base.frame
    F = outward_faces(V, base.faces)[0]   # transfer keeps the file's triangles; the heat solve needs them outward
    C = frame.to_canonical(V)
    region = base.fields.get("region")
    names = base.field_labels.get("region", [])
    mask = base.labels == 0
    if region is not None:
        mask &= ~np.isin(region, [names.index(n) for n in ("neck", "ears", "scalp") if n in names])
    asked, n_bones = n_bones, _fewer_bones(n_bones, density, mask, base.source)
    heads, tails, model = facial_bones(C, F, mask, n_bones, random_state=random_state)
    skel = base.skeleton
    jaw = skel.names.index("jaw") if "jaw" in skel.names else None
    head = skel.names.index("head")
    from scipy.spatial import cKDTree

    _, nearest = cKDTree(C).query(heads)
    on_jaw = np.zeros(n_bones, bool) if jaw is None else base.weights[nearest, jaw] > 0.5
    parents = np.where(on_jaw, jaw if jaw is not None else head, head)
    b0 = len(skel)
    skel_c = Skeleton(list(skel.names) + [f"face_{i:02d}" for i in range(n_bones)],
                      np.r_[skel.parents, parents],
                      np.vstack([frame.to_canonical(skel.heads), heads]),
                      np.vstack([frame.to_canonical(skel.tails), tails]))
    W = np.zeros((len(V), len(skel_c)))
    W[:, :b0] = base.weights
    for parent in {int(p) for p in parents}:
        kids = b0 + np.flatnonzero(parents == parent)
        H = bone_heat_weights(C, F, skel_c.segments[np.r_[parent, kids]])
        mass = base.weights[:, parent]
        W[:, parent] = mass * H[:, 0]
        W[:, kids] = mass[:, None] * H[:, 1:]
    W = rigid_weights(W, C, F, closed_small_parts(C, F))   # teeth split by the facial bones' heat: whole again
    base.timings["facial+weights"] = time.perf_counter() - t
    # the facial bones' heat ran against the generic's head bone as carried; exported, it twists about
    # the head's up, as a transferred rig's does
    base.skeleton = skel_c.transformed(frame.from_canonical).aimed("head", frame.turn_axes[1])
    base.weights = W
    base.facial_mask = mask
    base.options.update({"command": "place", "density": density if isinstance(density, str) else int(density),
                         "facial_bones": n_bones, "random_state": random_state})
    if n_bones != asked:
        base.options["facial_bones_asked"] = asked
    base.facial_bone_partner = model.partner_.tolist()
    return base
