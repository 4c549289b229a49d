"""Find a head's up, front and left-right symmetry plane; map to and from the canonical frame.

Goes beyond the papers we implement: the bone-placement method of ``place`` assumes the head
already stands +Y up facing +Z.
Real heads arrive Z-up or Y-up, facing +-X or +-Z, in millimetres or metres.

Method
------
1. The symmetry plane: for each input axis as a starting normal, reflective
   ICP on an area-uniform sample (pair each point with the nearest point to its
   mirror image; the pair differences give the normal, their midpoints the
   offset). The plane that mirrors the sample onto itself best wins.
2. Up and front: the two remaining input axes, projected into the symmetry
   plane, give 8 signed (up, front) choices. When one direction clearly has a
   cut at its far end (a flat base or an open rim: neck cut, bust base), it is
   down -- unless the mesh is a face-only capture: an open shell (its
   area-weighted normals sum to a large part of its area) faces away from its
   opening, which is then its back, and only the fronts along that way stay. When two directions look
   clearly cut (a neck cut slanted down and back shows at the bottom and at the back), the bottom is one
   of them and only their choices stay. The remaining choices are scored by how well the head's top slice
   (1.2 head widths tall, so shoulders and bust bases don't count) overlays the
   same slice of a reference head (the built-in default head): a trimmed
   similarity ICP that may turn by at most 35 degrees, so a tilted head still
   matches but a head facing the other way cannot turn round.
3. With landmarks (``frame_from_landmarks``), the frame comes from them instead.

Every step is a function of the mesh's shape (sample faces and barycentric
coordinates do not depend on the frame), so a head rotated by any axis-aligned
rotation and scaled gives the same canonical head.

The canonical frame is the glTF/landmark-contract frame: +Y up, +Z out of the
face, +X toward the subject's own left ear, origin on the symmetry plane at the
sample's centroid, and coordinates divided by the head size (the largest
extent of the mesh in the canonical axes), so canonical heads measure about 1.
"""
from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy.spatial import cKDTree

from .errors import AutobonesError
from .geometry.sample import sample_surface
from .geometry.mirror_plane import best_plane, mirror_error, reflect, refine_plane, shape_starts
from .geometry.topology import used_vertices
from .cut_cues import base_score as _base_score, cut_cues as _cut_cues, open_shell_facing as _open_shell_facing
from .cut_cues import cut_up_front, is_planar_cut

AXES = {
    "+x": (1.0, 0.0, 0.0), "-x": (-1.0, 0.0, 0.0),
    "+y": (0.0, 1.0, 0.0), "-y": (0.0, -1.0, 0.0),
    "+z": (0.0, 0.0, 1.0), "-z": (0.0, 0.0, -1.0),
}

SAMPLE_COUNT = 3000
# vector area / area of an open surface (cut_cues.open_shell_facing): above OPEN_SHELL a clear cut
# opposite the way it faces is its back (a face-only capture), not a neck cut; above FACE_SHELL it is
# a face-only capture whatever its rim looks like
OPEN_SHELL = 0.22
FACE_SHELL = 0.4
# a symmetry normal within AUTHORED_DEG of an input axis: the file was authored with its axes on the
# head's (most are), and the up and front are looked for along the other two axes
AUTHORED_DEG = 10.0
AUTHORED = float(np.cos(np.radians(AUTHORED_DEG)))
# a plane from the sample's principal directions replaces the best from the input axes only when it
# mirrors the head this much better, so heads authored on their axes keep their frame bit for bit
SHAPE_PLANE_GAIN = 0.8
# the reference head's overlay score (trimmed distances in RMS radii) above which a head is not taken
# for a human face: human heads and busts of the shared and zoo sets score 0.08-0.12 in their true
# frame, the zoo's animals and cartoons 0.13-0.46
HUMAN_LIKE = 0.13
# the same for a head taken for a face-only capture (scored against the reference's front part): the
# shared heads' front halves and quarters score 0.08-0.25, the zoo's wide-necked beast 0.30
FACE_UNLIKE = 0.28
# a face-only capture whose opening is a planar cut stays one only when the reference's face overlays it
# better than this share of the whole reference head stood on that cut does
FACE_VS_NECK = 0.65


@dataclass(frozen=True)
class Frame:
    """A rigid map between a mesh's own frame and the canonical head frame.

    Attributes
    ----------
    rotation : (3, 3) float
        Rows are the canonical +X (subject's left), +Y (up) and +Z (front)
        directions expressed in the input frame; orthonormal, det +1.
    origin : (3,) float
        The canonical origin in input coordinates.
    size : float
        Head size in input units: canonical coordinates are input units / size.
    symmetry_error : float
        Mean distance, in head sizes, between the sample and its mirror image.
    cut : ((3,) float, (3,) float) or None
        A planar neck cut or bust base found by :func:`detect_frame`: its centre (canonical) and unit
        normal pointing out of the mesh (canonical); None when there is none (or not detected). Not
        written by :meth:`to_dict`: it is the detection's, kept so ``place`` need not look again.
    """

    rotation: np.ndarray
    origin: np.ndarray
    size: float
    symmetry_error: float = float("nan")
    cut: tuple = None

    def to_canonical(self, P):
        """(k, 3) input-frame points -> (k, 3) canonical points (head sizes)."""
        return (np.asarray(P, dtype=np.float64) - self.origin) @ self.rotation.T / self.size

    def from_canonical(self, Q):
        """(k, 3) canonical points -> (k, 3) input-frame points (input units)."""
        return np.asarray(Q, dtype=np.float64) * self.size @ self.rotation + self.origin

    @property
    def up(self):
        """The input axis nearest to canonical up, e.g. ``'+z'``."""
        return nearest_axis(self.rotation[1])

    @property
    def front(self):
        """The input axis nearest to the direction the face looks, e.g. ``'-x'``."""
        return nearest_axis(self.rotation[2])

    @classmethod
    def from_dict(cls, d):
        """The frame :meth:`to_dict` wrote (a sidecar's ``frame``); ``symmetry_error`` null or absent
        (undefined, e.g. a transferred rig's) reads as NaN. KeyError / TypeError / ValueError on a
        malformed dict."""
        if not isinstance(d, dict):
            raise TypeError(f"a frame is an object, not {type(d).__name__}")
        sym = d.get("symmetry_error")
        return cls(np.asarray(d["rotation"], dtype=np.float64), np.asarray(d["origin"], dtype=np.float64),
                   float(d["head_size"]), float("nan") if sym is None else float(sym))

    def to_dict(self):
        return {
            "up": self.up, "front": self.front,
            "rotation": self.rotation.tolist(), "origin": self.origin.tolist(),
            "head_size": float(self.size), "symmetry_error": float(self.symmetry_error),
        }


def nearest_axis(d):
    """The signed input axis closest to direction ``d`` (3,), e.g. ``'-x'``."""
    d = np.asarray(d, dtype=np.float64)
    i = int(np.argmax(np.abs(d)))
    return ("+" if d[i] > 0 else "-") + "xyz"[i]


def parse_axis(name, what="axis"):
    """``'+y'``, ``'y'``, ``'-Z'`` -> unit (3,) vector; AutobonesError otherwise."""
    key = str(name).strip().lower()
    key = key if key[:1] in "+-" else "+" + key
    if key not in AXES:
        raise AutobonesError(f"--{what} {name!r}: expected one of +x -x +y -y +z -z")
    return np.array(AXES[key])


def detect_frame(V, F, up=None, front=None, reference=None):
    """Find the canonical frame of a head mesh.

    Parameters
    ----------
    V : (n, 3) float
        Vertices in the mesh's own frame and units.
    F : (m, 3) int
        Triangles.
    up, front : str or None
        Force the up or front axis (``'+z'``, ``'-x'``...); the other is detected.
    reference : (k, 3) float or None
        Canonical sample of the reference head to score orientations against;
        default: the built-in default head.

    Returns
    -------
    Frame
    """
    P, _, _ = sample_surface(V, F, SAMPLE_COUNT, seed=0)
    center = P.mean(axis=0)
    rms = np.sqrt(((P - center) ** 2).sum(axis=1).mean())
    tree = cKDTree(P)
    up_v = None if up is None else parse_axis(up, "up")
    front_v = None if front is None else parse_axis(front, "front")

    if up_v is not None and front_v is not None:
        if abs(up_v @ front_v) > 0.5:
            raise AutobonesError(f"--up {up} and --front {front} must be different axes")
        normal, offset = np.cross(up_v, front_v), center @ np.cross(up_v, front_v)
        sym_err = mirror_error(P, tree, normal, offset) / rms
        candidates, cues = [(up_v, front_v)], None
    else:
        sym_err, normal, offset, cues = _symmetry_plane(V, F, P, tree, rms, up_v, front_v)
    # free: nothing forced; turned: nor authored on the input axes, so the candidates come from the shape
    free = up_v is None and front_v is None
    turned = free and np.abs(normal).max() < AUTHORED
    if cues is None:
        cues = _cut_cues(V, F)  # only the frame's cut needs them when up is forced
    planar = is_planar_cut(cues)
    if up_v is None or front_v is None:
        candidates = _shape_candidates(P, normal, cues) if turned else _candidates(normal, up_v, front_v)

    ref = default_reference() if reference is None else np.asarray(reference, dtype=np.float64)
    face_only = False
    every, full_ref = candidates, ref
    if len(candidates) > 1 and up_v is None:
        candidates, ref, face_only = _cut_candidates(P, normal, candidates, cues, ref)
    if len(candidates) > 1:
        scores = _overlay_scores(P, candidates, ref)
        if face_only and front_v is None and planar:
            # a head cut at a wide neck looks as open as a face cut behind the ears: a face-only
            # capture must overlay the reference's face far better than its whole head stood on
            # the cut (the shared heads' front halves and quarters: 0.25-0.42 of it; the zoo's
            # wide-necked armadillo and beast: 0.85-0.94)
            neck = [(u, f) for u, f in every if u @ -cues["loop_normal"] > 0.5]
            neck_scores = _overlay_scores(P, neck, full_ref) if neck else []
            if neck and min(scores) > FACE_VS_NECK * min(neck_scores):
                candidates, scores, ref, face_only = neck, neck_scores, full_ref, False
        up_d, front_d = candidates[int(np.argmin(scores))]
        if turned:
            # candidates 30 degrees apart round a turned head: settle the angle between them
            up_d, front_d = _refine_angle(P, normal, up_d, front_d, ref)
        if free and planar and min(scores) > (FACE_UNLIKE if face_only else HUMAN_LIKE):
            # no human face matches (an animal, a cartoon): the reference head cannot tell its
            # front from its back, the neck cut can
            up_d, front_d, _ = cut_up_front(P, normal, offset, cues)
    else:
        up_d, front_d = candidates[0]
    # an exact frame from the refined symmetry normal and the chosen up, in an order that does
    # not depend on which input axis was which (so rotated inputs give the same frame)
    left = normal * np.sign(normal @ np.cross(up_d, front_d))
    up_d = up_d - (up_d @ left) * left
    up_d /= np.linalg.norm(up_d)
    R = np.vstack([left, up_d, np.cross(left, up_d)])
    origin = center - ((center @ normal) - offset) * normal  # on the symmetry plane
    used = used_vertices(F, len(V))
    local = (V[used] - origin) @ R.T
    size = float((local.max(axis=0) - local.min(axis=0)).max())
    cut = ((cues["loop_centre"] - origin) @ R.T / size, cues["loop_normal"] @ R.T) if planar else None
    return Frame(rotation=R, origin=origin, size=size, symmetry_error=float(sym_err), cut=cut)


def _overlay_scores(P, candidates, ref):
    """:func:`_overlay_score` of each (up, front) candidate. Independent ICPs whose time is in the
    k-d tree queries, which release the GIL: threads give the same scores in about half the time
    on two cores."""
    with ThreadPoolExecutor(max_workers=min(len(candidates), os.cpu_count() or 1)) as pool:
        return list(pool.map(lambda c: _overlay_score(P, c[0], c[1], ref), candidates))


def _refine_angle(P, normal, up, front, ref, half=15.0, evaluations=8):
    """(up, front) turned about the symmetry ``normal`` by the angle within +-``half`` degrees
    that overlays the reference best (the overlay held at that turn: a golden-section search on a
    score that is smooth in the angle), for candidates spaced ``2 * half`` degrees apart."""
    def turned(t):
        c, s = np.cos(np.radians(t)), np.sin(np.radians(t))
        side = np.cross(normal, up) * np.sign(np.cross(normal, up) @ front)
        return c * up + s * side, c * front - s * up

    def score(t):
        u, f = turned(t)
        return _overlay_score(P, u, f, ref, max_turn=0.0)

    g = (np.sqrt(5.0) - 1.0) / 2.0
    a, b = -half, half
    x1, x2 = b - g * (b - a), a + g * (b - a)
    f1, f2 = score(x1), score(x2)
    for _ in range(evaluations - 2):
        if f1 <= f2:
            b, x2, f2 = x2, x1, f1
            x1 = b - g * (b - a)
            f1 = score(x1)
        else:
            a, x1, f1 = x1, x2, f2
            x2 = a + g * (b - a)
            f2 = score(x2)
    return turned(x1 if f1 <= f2 else x2)


def _cut_candidates(P, normal, candidates, cues, ref):
    """The (up, front) candidates a cut allows, the reference to score them against, and whether
    the head was taken for a face-only capture. A flat cut or an open rim (neck, bust base) marks
    the bottom when one is clear; a face-only capture faces away from its opening, which is its
    back, not its bottom: a shell open that wide, or one whose clear "cut" lies opposite the way it
    faces (then only the fronts along that way stay, scored against as deep a front part of the
    reference head)."""
    bases = {}
    facing, openness = _open_shell_facing(cues)
    mask = [(u, f) for u, f in candidates if f @ facing > 0.7]
    for u, _ in candidates:
        key = tuple(np.round(u, 6))
        if key not in bases:
            bases[key] = _base_score(cues, u)
    ranked = sorted(bases.values(), reverse=True)
    winner = max(bases, key=bases.get) if ranked[0] > 0.02 and ranked[0] > 2.0 * ranked[1] else None
    if mask and (openness > FACE_SHELL or (openness > OPEN_SHELL and winner is not None
                                           and np.array(winner) @ facing > 0.7)):
        depth = np.ptp(P @ facing) / max(np.ptp(P @ normal), 1e-300)
        z = ref[:, 2]
        front_part = ref[z >= z.max() - depth * np.ptp(ref[:, 0])]
        return mask, (front_part if len(front_part) >= 0.1 * len(ref) else ref), True
    if winner is not None:
        return [(u, f) for u, f in candidates if tuple(np.round(u, 6)) == winner], ref, False
    if len(ranked) > 2 and ranked[1] > 0.02 and ranked[1] > 1.5 * ranked[2]:
        # two directions look cut (a neck cut slanted down and back shows at the bottom and at the
        # back): the bottom is one of them, and only their candidates are scored
        pair = sorted(bases, key=bases.get, reverse=True)[:2]
        return [(u, f) for u, f in candidates if tuple(np.round(u, 6)) in pair], ref, False
    if is_planar_cut(cues):
        # a planar cut's far side is the bottom (a neck cut, a bust base) or the back (a face-only
        # capture), or between (a neck cut slanted down and back)
        d = cues["loop_normal"]
        kept = [(u, f) for u, f in candidates if max(-(d @ u), -(d @ f)) > 0.3 and d @ u < 0.3 and d @ f < 0.3]
        return kept or candidates, ref, False
    return candidates, ref, False


def _symmetry_plane(V, F, P, tree, rms, up_v, front_v):
    """The symmetry plane of the sample ``P`` (input frame) as (mirror error in RMS radii, unit
    normal, offset), and the cut cues (None when up is given), computed beside the plane's ICPs."""
    center = P.mean(axis=0)
    given = up_v if up_v is not None else front_v
    starts = [np.array(a) for a in np.eye(3) if given is None or abs(a @ given) < 0.5]
    # independent ICPs whose time is in k-d tree queries and numpy, which release the GIL: on
    # threads, beside the cut cues (needed when up is not given), in about half the time
    with ThreadPoolExecutor(max_workers=min(len(starts) + 1, os.cpu_count() or 1)) as pool:
        cues_job = pool.submit(_cut_cues, V, F) if up_v is None else None
        planes = list(pool.map(lambda n0: refine_plane(P, tree, n0, center @ n0, rms), starts))
        cues = None if cues_job is None else cues_job.result()
    best = best_plane(P, tree, planes, rms)
    if given is None:
        # a head turned in its file (not about an axis) traps the ICPs started on the input axes
        # on planes that mirror it badly (ICT turned at random: 0.11-0.13 of the RMS radius
        # against 0.03), and an asymmetric one can trap them as is (the penguin: 0.041 against
        # 0.029): the planes started from the sample's own principal directions win then
        shaped = best_plane(P, tree, [refine_plane(P, tree, n0, center @ n0, rms)
                                       for n0 in shape_starts(P, tree)], rms)
        best = shaped if shaped[0] < SHAPE_PLANE_GAIN * best[0] else best
    return best[0] / rms, best[1], best[2], cues


def _shape_candidates(P, normal, cues, steps=12):
    """Signed (up, front) pairs for a head turned in its file: ``steps`` directions round the
    symmetry plane, from the main cut's far side (a neck cut or a bust base: see
    :func:`autobones.cut_cues.cut_cues`) or, with none, the sample's longest in-plane axis; plus any input axis that
    lies in the plane (a head turned about its up axis keeps that axis as a candidate)."""
    ref = cues["loop_normal"] if cues is not None and cues["loop_normal"] is not None else None
    if ref is None or np.linalg.norm(ref - (ref @ normal) * normal) < 0.3:
        c = P - P.mean(axis=0)
        c = c - np.outer(c @ normal, normal)
        c = c / max(float(np.abs(c).max()), 1e-300)
        _, E = np.linalg.eigh(c.T @ c)
        ref = E[:, 2]
    a = ref - (ref @ normal) * normal
    a /= np.linalg.norm(a)
    b = np.cross(normal, a)
    ups = [np.cos(t) * a + np.sin(t) * b for t in np.radians(np.arange(steps) * 360.0 / steps)]
    for axis in np.eye(3):
        if abs(axis @ normal) < np.sin(np.radians(AUTHORED_DEG)):
            for sign in (1.0, -1.0):
                u = sign * (axis - (axis @ normal) * normal)
                ups.append(u / np.linalg.norm(u))
    return [(u, f) for u in ups for f in (np.cross(normal, u), np.cross(u, normal))]


def _candidates(normal, up_v, front_v):
    """Signed (up, front) pairs, orthonormal and orthogonal to the symmetry normal: up is an
    input axis projected into the symmetry plane, front completes the frame."""
    out = []
    for i in sorted(np.argsort(np.abs(normal))[:2]):
        for sign in (1.0, -1.0):
            u = sign * np.eye(3)[i]
            u = u - (u @ normal) * normal
            u /= np.linalg.norm(u)
            if up_v is not None and u @ up_v < 0.7:
                continue
            for f in (np.cross(normal, u), np.cross(u, normal)):
                if front_v is not None and f @ front_v < 0.7:
                    continue
                out.append((u, f))
    if not out:
        raise AutobonesError("the given --up/--front lies along the head's left-right axis; pick another axis")
    return out


def _top_part(Q):
    """The cranium and face of a +Y-up point set, centred and scaled to unit RMS radius,
    whether the mesh ends at the neck, the shoulders or a bust base: the top slice as tall as
    1.2 head widths, the head width measured on the cap above the widest part."""
    y = Q[:, 1]
    band = 0.3 * np.ptp(y)
    for _ in range(2):  # settle the width on the head, not on shoulders
        width = np.ptp(Q[y >= y.max() - band, 0])
        band = 0.6 * width
    top = Q[y >= y.max() - 1.2 * width]
    # a lone spike above the head leaves a slice of almost nothing: then the whole set is the head
    Q = top if width > 0 and len(top) >= 0.03 * len(Q) else Q
    Q = Q - Q.mean(axis=0)
    return Q / max(np.sqrt((Q ** 2).sum(axis=1).mean()), 1e-300)


def _overlay_score(P, up, front, ref, iterations=30, max_turn=35.0):
    """Trimmed two-way distance between the head oriented as (up, front) and the reference,
    after a similarity ICP that may turn the head by at most ``max_turn`` degrees (a tilted
    or turned head still matches; a head facing the other way cannot turn round)."""
    R = np.vstack([np.cross(up, front), up, front])
    Q = _top_part(P @ R.T)
    ref = _top_part(ref)
    ref_tree = cKDTree(ref)
    rot, s, t = np.eye(3), 1.0, np.zeros(3)
    last = None
    for _ in range(iterations):
        X = s * Q @ rot.T + t
        dist, j = ref_tree.query(X)
        keep = dist <= np.quantile(dist, 0.8)
        if last is not None and np.array_equal(j, last[0]) and np.array_equal(keep, last[1]):
            break  # the same matches give the same similarity: a fixed point, every later step equal
        last = (j, keep)
        A, B = Q[keep], ref[j[keep]]
        # Umeyama: the similarity B ~ s rot A + t in least squares
        Am, Bm = A.mean(axis=0), B.mean(axis=0)
        U, S, Wt = np.linalg.svd((B - Bm).T @ (A - Am))
        D = np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Wt))])
        new_rot = U @ D @ Wt
        if np.degrees(np.arccos(np.clip((np.trace(new_rot) - 1) / 2, -1, 1))) <= max_turn:
            rot = new_rot
        s = float(np.clip((S * np.diag(D)).sum() / ((A - Am) ** 2).sum(), 0.5, 2.0))
        t = Bm - s * Am @ rot.T
    X = s * Q @ rot.T + t
    d1, _ = ref_tree.query(X)
    d2, _ = cKDTree(X).query(ref)
    trim = lambda d: float(np.sort(d)[: int(0.8 * len(d))].mean())
    return trim(d1) + trim(d2)


@lru_cache(maxsize=1)
def default_reference():
    """Canonical sample of the built-in default head (cached; read-only)."""
    from .generic_rig import default_head_path
    from .io.mesh import load_mesh

    V, F = load_mesh(default_head_path())
    P, _, _ = sample_surface(V, F, SAMPLE_COUNT, seed=1)
    P = P - P.mean(axis=0)
    P /= np.sqrt((P ** 2).sum(axis=1).mean())
    P.setflags(write=False)
    return P


TOP = ("vertex", "glabella", "nasion")
BOTTOM = ("menton", "pogonion", "labiale_inferius", "stomion", "subnasale")
FRONT = ("pronasale", "nasion", "stomion", "subnasale", "glabella")


def frame_from_landmarks(V, F, landmarks):
    """The canonical frame from landmarks, when they tell it: up from a top midline landmark
    to a bottom one, front from the mesh's centroid to the nose (or another front midline
    landmark), left completing the frame; the symmetry plane through the midline landmarks
    and the midpoints of the bilateral pairs.

    Left is derived without the bilateral names, so a set with left and right swapped is
    caught by :func:`autobones.io.landmarks.validate_landmarks`. Returns None when the
    landmarks lack a top, a bottom or a front point (use :func:`detect_frame` then).

    Parameters
    ----------
    V : (n, 3) float
        Vertices, input frame.
    F : (m, 3) int
        Triangles.
    landmarks : dict of str -> (3,)
        Contract landmarks in the input frame.

    Returns
    -------
    Frame or None
    """
    pick = lambda names: next((np.asarray(landmarks[n], float) for n in names if n in landmarks), None)
    top, bottom, nose = pick(TOP), pick(BOTTOM), pick(FRONT)
    if top is None or bottom is None or nose is None:
        return None
    used = used_vertices(F, len(V))
    centroid = V[used].mean(axis=0)
    up = top - bottom
    front = nose - centroid
    if np.linalg.norm(up) == 0 or np.linalg.norm(front) == 0:
        return None
    up /= np.linalg.norm(up)
    front -= (front @ up) * up
    if np.linalg.norm(front) < 1e-6 * np.ptp(V[used], axis=0).max():
        return None
    front /= np.linalg.norm(front)
    left = np.cross(up, front)
    R = np.vstack([left, up, front])
    # the symmetry plane passes through midline points and pair midpoints
    mids = [np.asarray(p, float) for n, p in landmarks.items() if not n.endswith(("_l", "_r"))]
    mids += [(np.asarray(landmarks[n], float) + np.asarray(landmarks[n[:-2] + "_r"], float)) / 2
             for n in landmarks if n.endswith("_l") and n[:-2] + "_r" in landmarks]
    x0 = float(np.median(np.array(mids) @ left))
    origin = centroid - (centroid @ left - x0) * left
    local = (V[used] - origin) @ R.T
    return Frame(rotation=R, origin=origin, size=float(np.ptp(local, axis=0).max()))
