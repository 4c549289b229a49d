"""Checks of landmark values against the contract and the mesh they belong to.

:func:`validate_landmarks` checks names and values, then, given the mesh, the set's spread on the head
and the distance to its surface (with a hint when the units differ) and, given the head's canonical frame
(+X the subject's left), that no ``_l`` / ``_r`` pair is exchanged. Every problem is one
:class:`~autobones.errors.AutobonesError` naming the source. :func:`shorten` and
:func:`quoted` keep the values quoted in messages on one line (the file readers use them too).
"""
from __future__ import annotations

import difflib
from collections.abc import Mapping

import numpy as np

from ..errors import AutobonesError, counted
from ..geometry.topology import used_vertices
from .landmark_names import BILATERAL, NAME_INDEX, NAMES

# Global scales tried when landmarks miss the surface, and what each one means.
_UNIT_HINTS = (
    (0.001, "millimetres for a mesh in metres"),
    (1000.0, "metres for a mesh in millimetres"),
    (0.1, "millimetres for a mesh in centimetres"),
    (10.0, "centimetres for a mesh in millimetres"),
    (0.01, "centimetres for a mesh in metres"),
    (100.0, "metres for a mesh in centimetres"),
)
# the RMS distance of a landmark set from its centroid, in the mesh's largest extent, that a units hint
# may give: the 20 landmark files of the shared data measure 0.14 (ICT, the beast) to 0.40 (the penguin);
# a face's landmarks on a whole body would be near 0.03
MIN_SPREAD, MAX_SPREAD = 0.02, 3.0
# head sizes: within this of the surface once scaled, landmarks are on it and a units hint names the scale
HINT_OFF = 0.005


def validate_landmarks(landmarks, V=None, F=None, frame=None, min_count=10, source="landmarks",
                       max_off_surface=0.05):
    """Check a landmark dict against the contract and, optionally, the mesh it belongs to.

    Parameters
    ----------
    landmarks : mapping str -> (3,) float
        Contract names -> positions in the mesh's own frame and units.
    V : (n, 3) float or None
        Mesh vertices, same frame and units as the landmarks.
    F : (m, 3) int or None
        Mesh triangles; given together with ``V``.
    frame : autobones.orient.Frame or None
        The head's canonical frame (``autobones.orient.detect_frame(V, F)``);
        enables the left/right check.
    min_count : int
        Fewest landmarks accepted (the transfer needs about 10 well spread).
    source : str
        What to call the landmarks in messages, usually the file name.
    max_off_surface : float
        Largest distance from the surface, in head sizes (the largest
        bounding-box extent of the vertices ``F`` uses).

    Returns
    -------
    dict[str, (3,) float64]
        Fresh arrays in :data:`NAMES` order.

    Raises
    ------
    AutobonesError
        One line naming ``source`` and the offending landmarks, for: unknown
        names (with the closest valid name), values that are not 3 finite
        numbers, fewer than ``min_count`` landmarks, two landmarks at the same
        point, all landmarks on one line, a set gathered within :data:`MIN_SPREAD`
        head sizes of its centre (RMS; :func:`speck`), landmarks farther than
        ``max_off_surface`` from the mesh (with a hint when a global scale by
        1000, 100, 10, 0.1, 0.01 or 0.001 would put them on it: mismatched
        units), and, when ``frame`` is given, ``_l`` / ``_r`` exchanged: in
        canonical coordinates (+X is the subject's left) every ``_l`` point
        must lie at larger x than its ``_r`` partner. Without a frame the
        left/right check is skipped: the landmarks alone do not tell which
        side is the subject's left.
    """
    clean = _values(landmarks, source)
    if len(clean) < min_count:
        have = f" ({_list(clean)})" if clean else ""
        raise AutobonesError(f"{source}: only {len(clean)} landmark{'s' if len(clean) != 1 else ''}{have}; "
                             f"at least {min_count} well-spread landmarks are needed, add more")
    if not clean:
        return clean
    names = list(clean)
    P = np.array([clean[n] for n in names])
    head = None
    if V is not None or F is not None:
        if V is None or F is None:
            raise TypeError("validate_landmarks: V and F go together")
        V = np.ascontiguousarray(V, dtype=np.float64)
        F = np.ascontiguousarray(F, dtype=np.int64)
        head = head_extent(V, F)
    _check_spread(P, names, head, source)
    if head is not None:
        _check_speck(P, V, F, head, source, max_off_surface)
        _check_surface(P, names, V, F, head, source, max_off_surface)
    if frame is not None:
        _check_sides(clean, frame, source)
    return clean


def landmark_problems(landmarks, V, F, frame=None, min_count=10, max_off_surface=0.05):
    """What :func:`validate_landmarks` would refuse in ``landmarks``, listed per name instead of raised.

    For a landmark editor that shows the checks as the user goes: the same tests and thresholds
    (:func:`surface_offsets`, :func:`unit_hint`, :func:`same_point_pairs`, :func:`on_one_line`,
    :func:`swapped_sides`), so a set with no problem here passes ``validate_landmarks`` with the same
    arguments. Parameters as there.

    Returns
    -------
    dict
        ``{"names": {name: [one-line problem, ...]}, "set": [problem of the set as a whole, ...]}``;
        names without a problem are left out.
    """
    names_out, set_out = {}, []

    def add(name, text):
        names_out.setdefault(name, []).append(text)

    try:
        clean = _values(landmarks, "landmarks")
    except AutobonesError as exc:
        return {"names": {}, "set": [str(exc)]}
    if len(clean) < min_count:
        set_out.append(f"{len(clean)} placed; at least {min_count} well-spread landmarks are needed")
    if not clean:
        return {"names": names_out, "set": set_out}
    names = list(clean)
    P = np.array([clean[n] for n in names])
    V = np.ascontiguousarray(V, dtype=np.float64)
    F = np.ascontiguousarray(F, dtype=np.int64)
    head = head_extent(V, F)
    for i, j in same_point_pairs(P, head):
        add(names[i], f"at the same point as {names[j]}")
        add(names[j], f"at the same point as {names[i]}")
    if on_one_line(P):
        set_out.append(f"all {len(P)} landmarks lie on one line; spread them over the face")
    spread = speck(P, head) if len(clean) >= min_count else None
    if spread is not None:
        set_out.append(f"the landmarks gather within {spread:.2g} head sizes of their centre (a head's spread "
                       f"{MIN_SPREAD:g} or more): another mesh's, or in other units?")
    d = surface_offsets(P, V, F, head)
    far = d > max_off_surface
    for i in np.flatnonzero(far):
        add(names[i], f"off the surface: {d[i]:.2g} head sizes away (at most {max_off_surface:g})")
    hint = unit_hint(P, far, V, F, head, max_off_surface) if far.any() else None
    if hint is not None:
        set_out.append(f"wrong units? scaled by {hint[0]:g} the landmarks lie on the surface ({hint[1]})")
    if frame is not None:
        pairs, swapped, mirrored = swapped_sides(clean, frame)
        if mirrored:
            set_out.append(f"left and right are swapped (mirrored set) in {len(swapped)} of {len(pairs)} pairs; "
                           "_l is the subject's own left (the viewer's right from the front)")
        for base in swapped:
            add(f"{base}_l", f"left/right swapped: on the subject's right, {base}_r is on the left")
            add(f"{base}_r", f"left/right swapped: on the subject's left, {base}_l is on the right")
    return {"names": names_out, "set": set_out}


def landmark_values(landmarks, source="landmarks"):
    """Contract names with 3 finite numbers each, as (3,) float64 copies in :data:`NAMES` order; one
    AutobonesError for unknown names or bad values. Only these checks: none of the set or the mesh."""
    return _values(landmarks, source)


def _values(landmarks, source):
    """Contract names and 3 finite numbers each: (3,) float64 copies in :data:`NAMES` order."""
    if not isinstance(landmarks, Mapping):
        raise AutobonesError(f"{source}: landmarks must map names to [x, y, z], got {type(landmarks).__name__}")
    unknown = [k for k in landmarks if k not in NAME_INDEX]
    if unknown:
        raise AutobonesError(f"{source}: unknown landmark name{'s' if len(unknown) > 1 else ''} "
                             + _list(_suggest(k) for k in unknown)
                             + "; use the contract's names (spec/landmarks.md, autobones.io.landmarks.NAMES)")
    clean, bad = {}, []
    for name in sorted(landmarks, key=NAME_INDEX.get):
        try:
            p = np.array(landmarks[name], dtype=np.float64)
        except (TypeError, ValueError, OverflowError):
            p = None
        if p is None or p.shape != (3,) or not np.isfinite(p).all():
            bad.append(name)
        else:
            clean[name] = p
    if bad:
        raise AutobonesError(f"{source}: {_list(bad)} must be 3 finite numbers [x, y, z] (NaN, infinite or malformed)")
    return clean


def _check_spread(P, names, head, source):
    far = strayed(P)
    if far is not None:
        i, reach = far
        raise AutobonesError(f"{source}: {names[i]} lies {reach:.2g} times the other landmarks' spread from their "
                             f"centre ({P[i].tolist()}); a coordinate mistyped or in another unit?")
    Q, _ = _by_largest(P)
    spread = float((Q.max(axis=0) - Q.min(axis=0)).max())
    if len(P) > 1 and spread == 0.0:
        raise AutobonesError(f"{source}: all {len(P)} landmarks are at the same point {P[0].tolist()}; "
                             f"place each where the contract describes it")
    pairs = same_point_pairs(P, head)
    if pairs:
        shown = ", ".join(f"{names[i]} = {names[j]}" for i, j in pairs[:4])
        more = f" and {len(pairs) - 4} more" if len(pairs) > 4 else ""
        raise AutobonesError(f"{source}: landmarks at the same point ({shown}{more}); "
                             f"each landmark marks a different place, fix the copied coordinates")
    if on_one_line(P):
        raise AutobonesError(f"{source}: all {len(P)} landmarks lie on one line; "
                             f"they must spread over the face (check for a dropped coordinate)")


def _by_largest(P):
    """``(P / max|P|, max|P|)`` for points ``P`` (k, 3) (``P`` itself when all are zero): the checks measure on
    the scaled copy so that huge (finite) coordinates cannot overflow their squares."""
    m = float(np.abs(P).max())
    return (P / m if m > 0 else P), m


# a landmark farther than this many times the set's median distance from its median point is no landmark of
# that head: a coordinate mistyped (1e20), which the checks after read as every other pair "at the same point"
# or all "on one line" (their tolerances scale with the largest coordinate); a head's farthest landmark lies
# 1.5-3 median distances out (the vertex, the menton, an animal's muzzle)
STRAY = 100.0


def strayed(P):
    """(index, reach) of the point of ``P`` (k, 3) farthest from the points' median, when it lies more than
    :data:`STRAY` times their median distance from it (``reach`` that ratio); else None."""
    if len(P) < 4 or not np.isfinite(P).all():
        return None
    Q, _ = _by_largest(P)
    d = np.linalg.norm(Q - np.median(Q, axis=0), axis=1)
    typical = float(np.median(d))
    i = int(np.argmax(d))
    return (i, float(d[i] / typical)) if typical > 0 and d[i] > STRAY * typical else None


def same_point_pairs(P, head=None):
    """Index pairs ``(i, j)`` of the (k, 3) points ``P`` that coincide (within 1e-7 of the head size
    ``head``, or of the points' own spread without one), sorted."""
    if len(P) < 2:
        return []
    from scipy.spatial import cKDTree

    Q, m = _by_largest(P)
    spread = float((Q.max(axis=0) - Q.min(axis=0)).max())
    scale = head / m if head and m > 0 else spread
    return sorted(cKDTree(Q).query_pairs(1e-7 * scale))


def on_one_line(P):
    """True when three or more points ``P`` (k, 3) lie on one line (they cannot fix a frame)."""
    if len(P) < 3:
        return False
    Q, _ = _by_largest(P)
    s = np.linalg.svd(Q - Q.mean(axis=0), compute_uv=False)
    return bool(s[1] <= 1e-6 * s[0])


def surface_offsets(P, V, F, head):
    """Distance of each point ``P`` (k, 3) from the surface of (V, F), in head sizes ``head``
    (input units); ``inf`` for every point when any is not finite."""
    import igl

    from ..geometry.closest import FEW, near_faces

    if not np.isfinite(P).all():
        return np.full(len(P), np.inf)
    Q = np.ascontiguousarray(P, dtype=np.float64)
    # a few landmarks on a scan: only the triangles that can hold their closest points
    Fq = F[near_faces(Q, V, F)] if len(Q) * FEW < len(F) else F
    d2, _, _ = igl.point_mesh_squared_distance(Q, V, np.ascontiguousarray(Fq))
    return np.sqrt(np.asarray(d2, dtype=np.float64)) / head


def unit_hint(P, far, V, F, head, max_off):
    """What the points ``P`` (k, 3) look like when a global scale puts most of them on the surface
    (``'millimetres for a mesh in metres'``...), None otherwise; ``far`` (k,) bool marks those off it now.

    A scale that shrinks the set to a speck (or spreads it over many heads) is no hint: landmarks
    moved 500 units off a head, scaled by 0.001, all fall within half a unit of the origin, which
    may be near the surface, and were called millimetres. Nor is a scale that puts them merely near
    the surface: on the surface means within :data:`HINT_OFF` head sizes (landmarks in centimetres on
    a mesh in inches, scaled by 0.1, lay within 0.016 of Lee Perry-Smith's face and were called
    millimetres; the right scale puts a file's landmarks within 1e-4)."""
    best = None
    for scale, meaning in _UNIT_HINTS:
        with np.errstate(over="ignore", invalid="ignore"):
            scaled = P * scale
        if not MIN_SPREAD <= rms_spread(scaled, head) <= MAX_SPREAD:
            continue
        near = int((surface_offsets(scaled, V, F, head) <= min(max_off, HINT_OFF)).sum())
        if near > int((~far).sum()) and near >= 0.8 * len(P) and (best is None or near > best[0]):
            best = (near, scale, meaning)
    return None if best is None else best[1:]


def head_extent(V, F):
    """The largest bounding-box extent (float, mesh units) of the vertices of ``V`` (n, 3) that triangles of
    ``F`` (m, 3) use: a vertex no triangle uses (an exporter's leftover far away) is no part of the head,
    and counted it made a whole head's landmarks look gathered in a speck."""
    used = V[used_vertices(F, len(V))] if len(F) else V
    return float((used.max(axis=0) - used.min(axis=0)).max())


def rms_spread(P, head):
    """The RMS distance of the points ``P`` (k, 3) from their centroid, in head sizes ``head`` (float);
    inf for points that are not all finite or a head of no size."""
    if not np.isfinite(P).all() or not head > 0:
        return np.inf
    Q, m = _by_largest(P)
    return float(np.sqrt(((Q - Q.mean(axis=0)) ** 2).sum(axis=1).mean())) * (m / head if m > 0 else 0.0)


def speck(P, head):
    """:func:`rms_spread` of the points ``P`` (k, 3) when it is under :data:`MIN_SPREAD` (a set that small
    on the head is no head's landmarks: another mesh's file, or another unit's, whose points can all lie
    near a surface that passes through the origin); else None."""
    spread = rms_spread(P, head) if len(P) >= 3 else np.inf
    return spread if spread < MIN_SPREAD else None


def _check_speck(P, V, F, head, source, max_off):
    # a scan whose origin lies on its face (James' does) took landmarks in metres for its millimetres as
    # on its surface, and the fit then failed with "no reliable correspondence", naming no cause
    spread = speck(P, head)
    if spread is None:
        return
    msg = (f"{source}: the {len(P)} landmarks gather within {spread:.2g} head sizes of their centre (a head's "
           f"landmarks spread {MIN_SPREAD:g} or more)")
    hint = unit_hint(P, np.ones(len(P), dtype=bool), V, F, head, max_off)
    if hint is not None:
        msg += (f"; wrong units? scaled by {hint[0]:g} they lie on the surface, so they look like {hint[1]}: "
                "give the landmarks in the mesh's units")
    else:
        msg += "; are they this mesh's landmarks, in its own coordinates (same frame and units)?"
    raise AutobonesError(msg)


def _check_surface(P, names, V, F, head, source, max_off):
    d = surface_offsets(P, V, F, head)
    far = d > max_off
    if not far.any():
        return
    order = np.argsort(-d)
    worst = ", ".join(f"{names[i]} {d[i]:.2g}" for i in order[:min(4, int(far.sum()))])
    more = f" and {int(far.sum()) - 4} more" if far.sum() > 4 else ""
    msg = (f"{source}: {int(far.sum())} of {counted(len(P), 'landmark')} {'lies' if far.sum() == 1 else 'lie'} "
           "far from the mesh surface "
           f"({worst}{more} head sizes; at most {max_off:g} allowed)")
    hint = unit_hint(P, far, V, F, head, max_off)
    if hint is not None:
        scale, meaning = hint
        msg += (f"; wrong units? scaled by {scale:g} they lie on the surface, so they look like {meaning}: "
                f"give the landmarks in the mesh's units")
    else:
        msg += "; landmarks must be in the mesh's own coordinates (same frame and units) and on its surface"
    raise AutobonesError(msg)


def swapped_sides(clean, frame):
    """The bilateral pairs of ``clean`` whose ``_l`` and ``_r`` are exchanged, as the transfer judges them.

    Returns ``(pairs, swapped, mirrored)``: the base names with both sides given, those of them
    refused, and whether the whole set is mirrored (more than half the pairs have their ``_l`` point
    on the subject's right: then every such pair is refused; otherwise only the pairs clearly across,
    by more than 0.01 head sizes, since a pair near the midline may cross by a hair).
    """
    pairs = [b for b in BILATERAL if f"{b}_l" in clean and f"{b}_r" in clean]
    if not pairs:
        return [], [], False
    L = frame.to_canonical(np.array([clean[f"{b}_l"] for b in pairs]))
    R = frame.to_canonical(np.array([clean[f"{b}_r"] for b in pairs]))
    dx = L[:, 0] - R[:, 0]
    inverted = dx < 0
    mirrored = bool(inverted.sum() * 2 > len(pairs))
    bad = inverted if mirrored else inverted & (dx < -0.01)
    return pairs, [pairs[i] for i in np.flatnonzero(bad)], mirrored


def _check_sides(clean, frame, source):
    pairs, swapped, mirrored = swapped_sides(clean, frame)
    if mirrored:
        raise AutobonesError(
            f"{source}: left and right are swapped (mirrored set): in {len(swapped)} of {len(pairs)} pairs "
            f"the _l point is on the subject's right; _l is the subject's own left (the viewer's right in a "
            f"frontal picture), exchange _l and _r (if they are right, the head's detected up or front is wrong: "
            f"give them explicitly)")
    if swapped:
        raise AutobonesError(
            f"{source}: {_list(swapped)} have _l and _r exchanged "
            f"(the _l point lies on the subject's right); swap the names of that pair")


def _suggest(name):
    text = quoted(name)
    if not isinstance(name, str):
        return text
    close = difflib.get_close_matches(name.strip().lower(), NAMES, n=1, cutoff=0.6)
    return f"{text} (did you mean {close[0]!r}?)" if close else text


def _list(items, limit=6):
    items = [str(i) for i in items]
    shown = items[:limit]
    more = f" and {len(items) - limit} more" if len(items) > limit else ""
    return ", ".join(shown) + more


def shorten(text, limit=60):
    """``text`` on one line (runs of white space made one space), cut to ``limit`` characters."""
    text = " ".join(str(text).split())
    return text if len(text) <= limit else text[:limit - 3] + "..."


def quoted(value):
    """A value from a file, quoted and cut short so a message stays one line."""
    return repr(shorten(value, 40)) if isinstance(value, str) else shorten(repr(value), 40)
