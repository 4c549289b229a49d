"""Split a head by depth into facial mask, middle and back; place the head and neck bones.

The bone-placement method of ``place``, its §3.1: average-linkage agglomerative clustering of the head along its
depth (canonical Z) into 3 groups; the middle group clustered again, along its
height, into an upper and a lower part. The method runs the head bone vertically
through the upper part's mean and the neck bone through the lower part's mean;
that mean lands wherever the mesh's proportions put it (the brow of a long-necked
bust), so here the groups only anchor the bones inside the volume and the joints
are placed where the anatomy is (:mod:`.joints`, after Chancey, Ottaviano, Myers
& Nightingale 2007): the head bone runs vertically up from the occiput-C1 pivot,
the neck bone from the neck's base to it; the two are connected.

Average linkage needs all pairwise distances (O(s^2) memory), about 70 GB for
a 134k-vertex scan. We cluster an area-uniform surface sample of fixed size
(``sample_count`` points; 4000 take 64 MB) and give each vertex the label of
the sample point nearest in depth (or height), which is exact wherever the
groups are depth intervals. The full merge tree is kept (``linkage_``), so a
user can cut it at another group count, as 003 describes.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import numpy as np
from scipy.cluster.hierarchy import fcluster

from ..geometry.head_share import face_only, neck_base_height
from ..geometry.sample import sample_surface
from ..geometry.sections import section_points
from ..geometry.topology import used_vertices
from .joints import MASK_CHIN, Joints, find_joints, head_length, height_profile

JOINT_SAMPLES = 16000
CRANIUM = 0.5         # of a first length below the top: the slabs the cranium's length is read in
TIP_FLOOR = 0.95      # head lengths below the top: the nose tip is sought above (_nose_tip)
JAW_FRONT = 0.1       # head sizes: a long head's chin step starts at most this far behind the nose tip
THROAT = 0.18         # head sizes: a step starting further behind the nose tip is a throat's (human chins 0.07-0.16)
NECK_THROAT = 0.12    # head sizes: ... where a neck goes on below the profile (animal throats from 0.13; _chin_height)
END_REACH = 5         # 1% bins: the profile's lowest stretch read for a chin the mesh ends at (_chin_height)
STEP = 0.04           # head sizes: the profile's least drop over 3% of the height that is a step (_chin_height)
SLOPE_STEP = 0.035    # ... that is a long head's jaw, starting within JAW_FRONT of the nose tip
NOSE_LEVEL = 0.0      # head sizes: a step starting no further behind the nose tip is none of the chin's
PROFILE_STRIP = 0.03  # head sizes: half-width of the midline strip the front profile is read in
PROFILE_PLANES = 9    # sections across that strip, the profile's points
PROFILE_SPACING = 0.0025   # head sizes: their points' spacing, a quarter of the profile's 1% bins

FACE, MIDDLE, BACK = 0, 1, 2
LABEL_NAMES = ("face", "middle", "back")


@dataclass
class HeadSegmentation:
    """Result of :func:`segment_head`; coordinates canonical (head sizes, +Y up, +Z front).

    Attributes
    ----------
    labels : (n,) int8
        Per vertex: FACE (0), MIDDLE (1) or BACK (2), by depth.
    neck : (n,) bool
        Vertices below the chin (where the face's front profile steps back to the
        neck), or below the head/neck split height when no chin step is found;
        these are left out of the facial mask.
    facial_mask : (n,) bool
        ``labels == FACE`` and not ``neck``.
    linkage : (s - 1, 4) float
        scipy merge tree of the depth clustering of the sample.
    sample_depth : (s,) float
        Depth of each sample point (the tree's leaves).
    neck_height : float
        Height splitting the middle group into head (above) and neck (below).
    head_bone, neck_bone : (2, 3) float
        Head and tail of each bone; ``neck_bone[1] == head_bone[0]``, the head pivot.
    chin_height : float or None
        The menton's height from the midline profile's step under the chin (None: none found).
    joints : Joints or None
        Where the pivot and the neck base are and which cues placed them (:mod:`.joints`).
    """

    labels: np.ndarray
    neck: np.ndarray
    facial_mask: np.ndarray
    linkage: np.ndarray
    sample_depth: np.ndarray
    neck_height: float
    head_bone: np.ndarray
    neck_bone: np.ndarray
    chin_height: Optional[float] = None
    joints: Optional[Joints] = None

    def groups(self, n_groups):
        """Cut the depth merge tree at another group count; (s,) labels of the sample
        ordered front (0) to back (n_groups - 1)."""
        return _ordered_cut(self.linkage, self.sample_depth, n_groups)


def segment_head(V, F, sample_count=4000, seed=0, volume=None, pivot=None):
    """Depth groups and head/neck bones of a head in the canonical frame.

    Parameters
    ----------
    V : (n, 3) float
        Canonical vertices (head sizes, +Y up, +Z front, symmetric about x=0).
    F : (m, 3) int
        Triangles.
    sample_count : int
        Points clustered; memory is 4 * sample_count**2 bytes.
    volume : (Vc, Fc), optional
        A coarser copy of the same surface (canonical frame) for the inside tests that keep the
        bones in the volume: winding numbers cost a tree over every triangle.
    pivot : (float, float), optional
        A face mask's head pivot (height, depth; canonical) from its landmarks (:func:`.joints.find_joints`).

    Returns
    -------
    HeadSegmentation
    """
    S, _, _ = sample_surface(V, F, sample_count, seed=seed)
    depth = S[:, 2]
    Z = average_linkage_1d(depth)
    s_labels = _ordered_cut(Z, depth, 3)
    labels = _carry(depth, s_labels, V[:, 2]).astype(np.int8)

    mid = S[s_labels == MIDDLE]
    Zm = average_linkage_1d(mid[:, 1])
    # order the two height groups so 0 is the upper part
    up_low = _ordered_cut(Zm, mid[:, 1], 2)
    upper, lower = mid[up_low == 0], mid[up_low == 1]
    neck_height = 0.5 * (upper[:, 1].min() + lower[:, 1].max())

    head_mean, neck_mean = upper.mean(axis=0), lower.mean(axis=0)
    head_mean[0] = neck_mean[0] = 0.0  # on the symmetry plane
    face_s = S[s_labels == FACE]
    top = S[:, 1].max()
    prof = height_profile(S, S[:, 1].min(), top)
    # the cranium's length (glabella-opisthocranion), measured above the nose: a head pitched up
    # brings nose and chin forward into the top half head size (ICT at 10 degrees: +7%)
    length = head_length(prof, top, reach=CRANIUM * head_length(prof, top))
    cut, chin = -np.inf, None
    Vm = V[used_vertices(F, len(V))]
    # the midline profile from the surface's own sections across the midline strip, points a quarter bin
    # apart: a random sample and the vertices near the midline fill a 1% bin by chance and by the
    # tessellation, and a bin with no skin point takes an inner part (ICT's mouth) or the back of the head
    # (the koala's, 0.37 head sizes behind its front) as its front, a step that is not there. Read from
    # them, the same surface split 1-to-4 put the cow's chin 0.45 head sizes lower, five sample seeds the
    # goat's 0.04 or 0.25 under its nose tip (benchmarks/density.py). The strip's own vertices join them:
    # a cropped chin's point is the lowest vertex, which the sections pass between
    across = np.linspace(-1.0, 1.0, PROFILE_PLANES) * (1.0 - 1e-3) * PROFILE_STRIP
    profile = np.vstack([section_points(V, F, 0, across, PROFILE_SPACING), Vm[np.abs(Vm[:, 0]) < PROFILE_STRIP]])
    mask = face_only(V, F)
    # a face mask's chin lies at least MASK_CHIN of its height below its top (a step higher up is its
    # nose or lips): its depth is no cranium's length to expect the chin from (James' scan, which runs
    # down the neck, took the lips for its chin, and the joints then scaled the pivot by the whole scan)
    lowest = MASK_CHIN * float(np.ptp(Vm[:, 1])) if mask else None
    tip = _nose_tip(profile, length, top)
    found = _chin_height(profile, tip, length, top, below_top=lowest)
    for h, is_chin in ((found, True), (neck_height, False)):
        # a cut that leaves less than a third of the facial group is no chin (cartoons, animals), nor
        # one above the nose tip: the depth groups' split of a head with no neck (Blender's Suzanne,
        # whose muzzle is its most anterior point) ran through its eyes and left the muzzle as neck;
        # nor, on a face mask, one higher than its chin may be (the split ran through fran_cut's upper
        # lip when its chin step, at the mask's lower edge, was missed: its mouth and chin were neck)
        if h is not None and (face_s[:, 1] >= h).mean() >= 1 / 3 and (tip is None or h < tip[1]) and (
                is_chin or lowest is None or top - h >= lowest):
            cut, chin = h, (h if is_chin else None)
            break
    joints, head_bone, neck_bone = _joints(V, F, Vm, chin, seed, volume, head_mean, neck_mean, mask, pivot)
    neck = V[:, 1] < cut
    return HeadSegmentation(
        labels=labels, neck=neck, facial_mask=(labels == FACE) & ~neck,
        linkage=Z, sample_depth=depth, neck_height=float(neck_height),
        head_bone=head_bone, neck_bone=neck_bone, chin_height=chin, joints=joints)


def _joints(V, F, Vm, chin, seed, volume, head_mean, neck_mean, mask, pivot=None):
    """The head pivot and the neck base (:func:`.joints.find_joints`) as bones kept inside the volume.

    The head bone runs vertically from the pivot to 0.8 of the way to the top of the head, the neck
    bone from the neck base to the pivot. ``Vm``: the used vertices; ``head_mean`` and ``neck_mean``
    (the depth groups' upper and lower middle means) anchor the pull back inside; ``mask``: the mesh
    is a face mask (:func:`autobones.geometry.head_share.face_only`); ``pivot`` its pivot from its landmarks."""
    # a larger sample than the clustering's: the profile's 2% slabs and 12% midline strip need some
    # tens of points each, and sampling is linear in the mesh
    P, _, _ = sample_surface(V, F, JOINT_SAMPLES, seed=seed)
    found = find_joints(P, float(Vm[:, 1].min()), float(Vm[:, 1].max()), chin=chin, face_mask=mask,
                        base=neck_base_height(Vm[:, 1]), pivot=pivot if mask else None)
    joint, neck_root = found.head.copy(), found.neck.copy()
    top = Vm[:, 1].max()
    head_tail = np.array([0.0, joint[1] + 0.8 * (top - joint[1]), joint[2]])
    # keep the bones inside the volume (horns, a long muzzle, a thin neck or shoulders can put the
    # geometric ends outside): pull each end toward its part's mean until it is inside
    # (a face mask has no inside: its pivot lies behind it, in the head it does not have)
    if "face_only" not in found.cues["head"]:
        Vi, Fi = (V, F) if volume is None else volume
        joint, head_tail, neck_root = _inside(Vi, Fi, np.array([joint, head_tail, neck_root]),
                                              np.array([head_mean, head_mean, neck_mean]))
        # a cavity (mouth, nasal or eye pocket) can still cut the line: slide the bones in depth
        shift = _inside_shift(Vi, Fi, [(joint, head_tail), (neck_root, joint)])
        joint, head_tail, neck_root = joint + shift, head_tail + shift, neck_root + shift
    found.head, found.neck = joint, neck_root
    return found, np.array([joint, head_tail]), np.array([neck_root, joint])


def average_linkage_1d(x):
    """Average-linkage merge tree of scalars, in scipy's ``linkage`` format, in O(s log s).

    On a line every average-linkage merge joins two neighbouring intervals (the mean distance
    between intervals A < B < C is the sum of A-B's and B-C's), and the mean distance between
    intervals is the difference of their means; so a heap of neighbour gaps replaces scipy's
    O(s^2) pairwise matrix (0.3 s per 4000 points, most of ``segment``). The same tree as
    ``scipy.cluster.hierarchy.linkage(x[:, None], "average")`` up to rounding.

    Parameters
    ----------
    x : (s,) float

    Returns
    -------
    Z : (s - 1, 4) float
        Rows ``[cluster a, cluster b, distance, size]``, clusters ``0..s-1`` the points and
        ``s + i`` the merge of row ``i``, distances non-decreasing.
    """
    import heapq

    x = np.asarray(x, dtype=np.float64)
    s = len(x)
    order = np.argsort(x, kind="stable")
    # intervals as a doubly linked list over sorted positions, keyed by their first position
    total, count = x[order].tolist(), [1] * s
    ident = order.tolist()
    nxt, prv = list(range(1, s + 1)), list(range(-1, s - 1))
    alive, version = [True] * s, [0] * s
    heap = [(total[i + 1] - total[i], i, i + 1, 0, 0) for i in range(s - 1)]
    heapq.heapify(heap)
    Z = np.empty((max(s - 1, 0), 4))
    row = 0
    while heap:
        d, a, b, va, vb = heapq.heappop(heap)
        if not (alive[a] and alive[b]) or nxt[a] != b or version[a] != va or version[b] != vb:
            continue  # a gap to an interval that has grown since
        ia, ib = ident[a], ident[b]
        Z[row] = (min(ia, ib), max(ia, ib), d, count[a] + count[b])
        total[a] += total[b]
        count[a] += count[b]
        ident[a] = s + row
        version[a] += 1
        row += 1
        alive[b] = False
        nxt[a] = nxt[b]
        if nxt[a] < s:
            prv[nxt[a]] = a
        mean = total[a] / count[a]
        # the merged interval's gaps to both neighbours (its older gaps are now stale)
        if prv[a] >= 0:
            p = prv[a]
            heapq.heappush(heap, (max(mean - total[p] / count[p], 0.0), p, a, version[p], version[a]))
        if nxt[a] < s:
            q = nxt[a]
            heapq.heappush(heap, (max(total[q] / count[q] - mean, 0.0), a, q, version[a], version[q]))
    return Z


def _winding(V, F, Q):
    import igl

    return igl.fast_winding_number(np.ascontiguousarray(V), np.ascontiguousarray(F), np.ascontiguousarray(Q))


def _inside(V, F, points, anchors, steps=20):
    """Each of ``points`` (k, 3) moved toward its anchor until its generalized winding number
    exceeds 1/2 (unchanged if already inside, or if its anchor is not inside either: open
    masks). One winding-number evaluation for all of them."""
    t = np.linspace(1.0, 0.0, steps + 1)
    Q = anchors[:, None, :] + t[None, :, None] * (points - anchors)[:, None, :]
    inside = (_winding(V, F, Q.reshape(-1, 3)) > 0.5).reshape(len(points), -1)
    out = points.copy()
    has = inside.any(axis=1)
    out[has] = Q[has, np.argmax(inside[has], axis=1)]
    return out


def _inside_shift(V, F, segments, samples=21, limit=0.1, step=0.005):
    """Smallest depth offset (0, -step, +step, -2 step, ...) that puts every sample of the
    segments inside the volume; zero if none within ``limit`` does (open masks)."""
    t = np.linspace(0.0, 1.0, samples)[:, None]
    P = np.vstack([a + t * (b - a) for a, b in segments])
    offsets = np.array([0.0] + [s * k * step for k in range(1, int(limit / step) + 1) for s in (-1, 1)])
    shifted = P[None, :, :] + offsets[:, None, None] * np.array([0.0, 0.0, 1.0])
    ok = (_winding(V, F, shifted.reshape(-1, 3)) > 0.5).reshape(len(offsets), -1).all(axis=1)
    return np.array([0.0, 0.0, offsets[np.argmax(ok)] if ok.any() else 0.0])


def _ordered_cut(Z, value, n_groups):
    """Cut a merge tree into ``n_groups`` labelled by descending mean ``value``."""
    raw = fcluster(Z, n_groups, criterion="maxclust")
    ids = np.unique(raw)
    means = np.array([value[raw == i].mean() for i in ids])
    rank = np.empty(len(ids), dtype=np.int64)
    rank[np.argsort(-means, kind="stable")] = np.arange(len(ids))
    return rank[np.searchsorted(ids, raw)]


def _carry(sample_value, sample_label, value):
    """Label of the sample nearest in ``value`` (1-D), for each of ``value``."""
    order = np.argsort(sample_value, kind="stable")
    sv, sl = sample_value[order], sample_label[order]
    i = np.clip(np.searchsorted(sv, value), 1, len(sv) - 1)
    left_closer = (value - sv[i - 1]) <= (sv[i] - value)
    return np.where(left_closer, sl[i - 1], sl[i])


def _nose_tip(points, length, top, strip=0.03):
    """The midline profile's most anterior point (3,) above ``TIP_FLOOR`` head lengths below the top
    (a bust's chest can stand further forward than the nose: vertex-pronasale is about 0.65 head
    lengths, the chest below 1.3), or None with fewer than 20 points in the midline ``strip``.
    ``points``, ``length`` and ``top`` as :func:`_chin_height`'s."""
    mid = points[np.abs(points[:, 0]) < strip]
    if len(mid) < 20:
        return None
    head = mid[mid[:, 1] > top - TIP_FLOOR * length]
    return head[np.argmax(head[:, 2])] if len(head) else None


def _chin_height(points, tip, length, top, below_top=None, strip=0.03, bin_size=0.01):
    """Height of the menton, or None if no chin step is found.

    Below the nose tip, the midline front profile of the head steps back
    sharply at the nose base and under the chin (and, on a bust, at its base).
    Of those steps, the chin is the one nearest the height anthropometry expects
    (vertex to menton is about 1.2 times the head's length, glabella-opisthocranion;
    anthropometry.md). The head's length, not its depth at the middle group's level nor
    that group's split: both moved with a few degrees of pitch (ICT's head pitched 0-10
    degrees found its chin at the lower lip at 4 of 8 angles). Where the profile ends within a
    chin's depth of the nose tip (:data:`THROAT`), the mesh ends at the chin: its lowest point is a
    step too. On a face mask (``below_top`` given) the lowest step is the chin.

    ``points``: (k, 3) canonical surface points of the whole head; ``tip`` their nose tip
    (:func:`_nose_tip`, None: no chin); ``length`` the head's length (:func:`.joints.head_length`),
    ``top`` its highest point; ``below_top``: when given,
    only steps at least this far below ``top`` count (a face mask's).
    """
    if tip is None:
        return None
    mid = points[np.abs(points[:, 0]) < strip]
    tip_y = tip[1]
    below = mid[mid[:, 1] < tip_y]
    if len(below) < 10:
        return None
    edges = np.arange(tip_y, below[:, 1].min() - bin_size, -bin_size)
    k = np.clip(np.searchsorted(-edges, -below[:, 1]) - 1, 0, len(edges) - 1)
    front = np.full(len(edges), np.nan)
    np.fmax.at(front, k, below[:, 2])
    valid = ~np.isnan(front)
    if valid.sum() < 4:
        return None
    front = np.interp(np.arange(len(front)), np.flatnonzero(valid), front[valid])
    ends, back = _profile_steps(front, edges, STEP)
    end_back = front[0] - front[-END_REACH:].max()
    ends_at_chin = end_back <= THROAT
    if ends_at_chin:
        # the profile ends with a chin's front, not a throat's: a head cropped under its chin has no
        # step there, and the nearest one was its lips or nose base (ICT cut at the menton: 0.22-0.27
        # head sizes high; James' mask 0.23-0.28; fran_cut found none)
        ends, back = np.r_[ends, below[:, 1].min()], np.r_[back, end_back]
    expected = top - 1.2 * length
    # a head long, not tall (a snout): its length is no cranium's and the chin it expects lies below the
    # mesh. Its lower jaw ends under the face: the highest step that starts within JAW_FRONT of the nose
    # tip (the zoo's animals' jaws 0.02-0.06 behind it, their throats 0.13-0.44; human chins 0.07-0.16),
    # a slope's too (the cow's and the goat's jaws drop 0.037 and 0.038 head sizes over 3%)
    jaw = np.empty(0)
    if expected < points[:, 1].min():
        slope_ends, slope_back = _profile_steps(front, edges, SLOPE_STEP)
        jaw = slope_ends[slope_back <= JAW_FRONT]
        if ends_at_chin and end_back <= JAW_FRONT:
            jaw = np.r_[jaw, below[:, 1].min()]   # a snout cropped at its chin
    if below_top is not None:
        jaw = jaw[top - jaw >= below_top]     # a face mask's, as its steps below
    if len(ends) == 0:
        return float(jaw.max()) if len(jaw) else None
    if below_top is not None:
        keep = top - ends >= below_top
        ends, back = ends[keep], back[keep]
        if len(ends) == 0:
            return None
    # a face mask's depth is no cranium's length to expect its chin from: its chin is its lowest step (a
    # mask's neck, where it has one, ends with no step; James' mask cropped under the chin took its lower lip)
    pick = int(np.argmin(np.abs(ends - expected))) if below_top is None else int(np.argmin(ends))
    # a throat's step starts further back than any chin's; where a neck goes on below the profile an
    # animal's throat steps start from 0.13 (the ogre's, the goat's), where the mesh ends at a chin a
    # cropped human chin's step starts up to 0.16 behind the nose tip: on a snout the step nearest the
    # expected height is then a throat's or the neck cut's (the cow's chin was taken 0.24 head sizes under
    # its menton), and the jaw's is the chin
    if len(jaw) and back[pick] > (THROAT if ends_at_chin else NECK_THROAT):
        return float(jaw.max())
    return float(ends[pick])


def _profile_steps(front, edges, least):
    """(ends (k,), back (k,)): the steps of a midline front profile ``front`` (b,) (front-most depth of
    each height bin from the nose tip down, bins starting at ``edges`` (b,)): where its drop over 3 bins
    is a local maximum of at least ``least`` head sizes, the height of the step's underside and how far
    behind the nose tip (``front[0]``) the step starts.

    A step that starts level with the nose tip or ahead of it (``NOSE_LEVEL``) is a chest standing as far
    forward (the springer's, 0.50 under its chin, was taken for it), never a chin (a beak's chin starts
    0.01 behind its tip); nor one ending at the profile's last bin, the mesh's own lower edge curling
    under (fsaverage's drops 0.036 there; a mesh that ends at its chin is read by ``ends_at_chin``)."""
    drop = np.r_[front[:-3] - front[3:], np.zeros(3)]
    back = front[0] - front
    peak = (drop >= least) & (drop >= np.r_[0, drop[:-1]]) & (drop >= np.r_[drop[1:], 0]) & (back > NOSE_LEVEL)
    peak[max(len(edges) - 4, 0):] = False
    return edges[np.minimum(np.flatnonzero(peak) + 3, len(edges) - 1)], back[peak]
