"""A transferred rig's neck base kept still and its head/neck blend centred on the head joint.

The carried skin weights are the generic rig's, wherever the dense correspondence took them: the
generic's own neck base is pure neck, but its head/neck blend starts 0.34 of its height below the
head joint (head weight 0.5 a quarter of the way up), and a head whose neck the correspondence
stretches or folds (a long animal neck, a bust, a cut slanted to the face) gets head weight on its
lowest vertices: a 15 degree head turn moved the zoo's neck bases by 5-100% of the peak motion
(benchmarks/README.md, zoo check 3). A rigger expects the base to stay put.

So the transferred rig gets the same head share as ``place``'s
(:mod:`autobones.geometry.head_share`): 0 on the neck base (the lowest vertices and heights and a planar
neck cut's neighbourhood), a blend centred on a boundary through the head joint that passes under the
chin (the menton and pogonion landmarks) and the jaw's angle (the gonions, or where the generic rig's
gonions landed: the share there was 0.0-0.45 on the zoo's heads before), 1 above it; the carried face
(the generic's face depth group without its neck region) and a band around it keep the whole share
wherever they hang, down to the
menton even inside the neck base (ICT's dense face puts 5% of its vertices above its chin). It is
computed in the landmarks' anatomical frame (:func:`anatomical_axes`, head sizes: free of the file's
rotation and unit), then smoothed over the mesh (:func:`autobones.geometry.head_share.smooth_share`)
so no band is an edge wide on a coarse mesh. Below the share the head's side is scaled down alike and
the neck takes the rest; above the blend nothing changes. The vertices left still (outside the face's
band) are returned for the jaw's repair (:mod:`.jaw`, run after this), which holds them; within the
face's band the jaw as the landmarks say wins (a chin near the mesh's bottom: the bunny). A head whose
joint lies in its neck base (a closed head, no neck under the pivot: the robot) is left as carried.
"""
from __future__ import annotations

import numpy as np

from ..cut_cues import bottom_cut, cut_cues, is_planar_cut, midline_cuts
from ..geometry.head_share import (STILL, apply_head_share, face_only, head_share, mask_distance, neck_base_height,
                                   smooth_share)
from ..geometry.smooth import smoothstep
from ..orient import anatomical_axes as _anatomical_axes  # the wrapper below keeps its fallback
from ..geometry.topology import used_vertices, without_large_parts

FACE_HOLD = 0.16   # head sizes: the face keeps the head's whole share this far out (place's 2 x 0.08)
CHIN = ("menton", "pogonion")
ANGLE = ("gonion_l", "gonion_r")


def still_neck_base(V, F, W, skeleton, frame, landmarks, facial_mask, cues=None, fitted=None):
    """``W`` (n, b) with the head's share set by position (module docstring), a new array, and the
    vertices left still (n,) bool (a head share of at most ``STILL``; None when nothing changed).

    Parameters
    ----------
    V, F : (n, 3) float, (m, 3) int
        The head, input frame.
    W : (n, b) float
        Carried weights, rows summing to one, columns in ``skeleton``'s bone order.
    skeleton : Skeleton
        The transferred skeleton (input frame): ``neck`` the root, ``head`` its child, every other
        bone the head's descendant; any other layout is returned unchanged.
    frame : autobones.orient.Frame
        The rig's frame (from its landmarks).
    landmarks : dict str -> (3,) float
        The head's landmarks, input frame (``menton`` / ``pogonion`` place the chin).
    facial_mask : (n,) bool
        The carried face.
    cues : dict, optional
        :func:`autobones.cut_cues.cut_cues` of ``(V, F)`` when already computed.
    fitted : dict str -> (3,) float, optional
        The generic rig's landmarks where its fitted skin put them (input frame): the gonions, where
        ``landmarks`` has none, place the jaw's angle.

    Returns
    -------
    W : (n, b) float
    still : (n,) bool or None
    """
    names, parents = list(skeleton.names), list(skeleton.parents)
    if "neck" not in names or "head" not in names:
        return W, None
    neck, head = names.index("neck"), names.index("head")
    if parents[head] != neck or not all(_descends(parents, i, head) for i in range(len(names)) if i != neck):
        return W, None   # bones beside the head (shoulders, say): which side of the split they take is unknown
    R = anatomical_axes(V, F, landmarks, frame.rotation)
    def canonical(P):   # head sizes in the anatomical frame: free of the file's rotation and unit
        return (np.asarray(P, dtype=np.float64).reshape(-1, 3) - frame.origin) @ R.T / frame.size

    C = canonical(V)
    joint = canonical(skeleton.heads[head])[0]
    if joint[1] <= neck_base_height(C[used_vertices(F, len(C)), 1]):
        # no neck under the pivot (a closed head: the robot's joint is 0.06 of its height above its
        # bottom, under its chin's level): nothing to keep still that is not the head's own
        return W, None
    chin = [canonical(landmarks[n])[0] for n in CHIN if n in landmarks]
    chin = (min(p[1] for p in chin), max(p[2] for p in chin)) if chin else None
    angle = [canonical(p)[0] for p in jaw_angle_points(landmarks, fitted)]
    angle = (min(p[1] for p in angle), float(np.mean([p[2] for p in angle]))) if angle else None
    # the cut of the head itself, not of a large part beside it (hair: its rim is no neck cut)
    cues = cut_cues(V, without_large_parts(V, F)) if cues is None else cues
    cues = midline_cuts(cues, frame.rotation[0], frame.origin @ frame.rotation[0])  # an eye hole is no cut
    cues = bottom_cut(cues, frame.rotation[1])  # open at both ends: the neck's cut, not a missing crown
    cut = (canonical(cues["loop_centre"])[0], cues["loop_normal"] @ R.T) if is_planar_cut(cues) else None
    hold = 1.0 - smoothstep(np.minimum(mask_distance(C, facial_mask, FACE_HOLD), FACE_HOLD) / FACE_HOLD)
    share = head_share(C, joint, faces=F, chin=chin, face_only=face_only(C, F), face=hold, cut=cut, keep_chin=True,
                       jaw_angle=angle)
    # the bands are head sizes: on a coarse mesh some are an edge wide, a step of the jaw weight
    share = smooth_share(share, C, F)
    # the jaw's repair (after this) holds the still vertices, but not in the face's band: where the chin
    # nears the base (the bunny, the falcon statue) the jaw as the landmarks say wins over a still base.
    # The band's smooth tail is no band: held only where hold was exactly 0, the SMPL woman's throat at
    # hold 3e-5 took jaw weight 0.11-0.13 from the chin's falloff and a head turn moved her neck base 7 %
    still = (share <= STILL) & (hold <= STILL)
    return apply_head_share(np.array(W, dtype=np.float64), share, neck=neck, head=head), still


def jaw_angle_points(landmarks, fitted=None):
    """The gonions the head's ``landmarks`` give, else those of ``fitted`` (both dict str -> (3,)), else []."""
    for points in (landmarks, fitted or {}):
        found = [np.asarray(points[n], dtype=np.float64) for n in ANGLE if n in points]
        if found:
            return found
    return []


def anatomical_axes(V, F, landmarks, rotation):
    """(3, 3) rows left, up, front of the landmarks' anatomical frame
    (:func:`autobones.orient.anatomical_axes`), else ``rotation`` (3, 3): where they lack the names, or
    their up points away from ``rotation``'s. ``transfer``'s frame leans with the face (its rotation's
    up is menton -> vertex: 16 degrees on the generic rig, 36-73 on the zoo's animals), where the
    "lowest" vertices were the back of the skull and a level boundary behind the pivot cut the nape."""
    R = _anatomical_axes(V, F, landmarks)
    return rotation if R is None or R[1] @ rotation[1] <= 0 else R


def _descends(parents, i, ancestor):
    """Whether bone ``i`` is ``ancestor`` or below it."""
    while i >= 0:
        if i == ancestor:
            return True
        i = parents[i]
    return False
