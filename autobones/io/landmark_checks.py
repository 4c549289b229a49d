"""Checks of landmark values against the contract and the mesh they belong to.

:func:`validate_landmarks` checks names and values, then, given the mesh, the distance to its
surface (with a hint when the units differ) and, given the head's canonical frame
(+X the subject's left), that no ``_l`` / ``_r`` pair is exchanged. Every problem is one
:class:`~autobones.errors.AutobonesError` naming the source. :func:`shorten` and
:func:`quoted` keep the values quoted in messages on one line (the file readers use them too).
"""
from __future__ import annotations

import difflib
from collections.abc import Mapping

import numpy as np

from ..errors import AutobonesError, counted
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
        bounding-box extent of ``V``).

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
        point, all landmarks on one line, landmarks farther than
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
        head = float((V.max(axis=0) - V.min(axis=0)).max())
    _check_spread(P, names, head, source)
    if head is not None:
        _check_surface(P, names, V, F, head, source, max_off_surface)
    if frame is not None:
        _check_sides(clean, frame, source)
    return clean


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
    # work on P / max|P| so that huge (finite) coordinates cannot overflow
    m = float(np.abs(P).max())
    Q = P / m if m > 0 else P
    spread = float((Q.max(axis=0) - Q.min(axis=0)).max())
    if len(P) > 1 and spread == 0.0:
        raise AutobonesError(f"{source}: all {len(P)} landmarks are at the same point {P[0].tolist()}; "
                             f"place each where the contract describes it")
    scale = head / m if head and m > 0 else spread
    tol = 1e-7 * scale
    if len(P) > 1:
        from scipy.spatial import cKDTree

        pairs = sorted(cKDTree(Q).query_pairs(tol))
        if pairs:
            shown = ", ".join(f"{names[i]} = {names[j]}" for i, j in pairs[:4])
            more = f" and {len(pairs) - 4} more" if len(pairs) > 4 else ""
            raise AutobonesError(f"{source}: landmarks at the same point ({shown}{more}); "
                                 f"each landmark marks a different place, fix the copied coordinates")
    if len(P) >= 3:
        s = np.linalg.svd(Q - Q.mean(axis=0), compute_uv=False)
        if s[1] <= 1e-6 * s[0]:
            raise AutobonesError(f"{source}: all {len(P)} landmarks lie on one line; "
                                 f"they must spread over the face (check for a dropped coordinate)")


def _check_surface(P, names, V, F, head, source, max_off):
    import igl

    from ..geometry.closest import FEW, near_faces

    def off(Q):
        if not np.isfinite(Q).all():
            return np.full(len(Q), np.inf)
        Q = np.ascontiguousarray(Q, dtype=np.float64)
        # a few landmarks on a scan: only the triangles that can hold their closest points
        Fq = F[near_faces(Q, V, F)] if len(Q) * FEW < len(F) else F
        d2, _, _ = igl.point_mesh_squared_distance(Q, V, np.ascontiguousarray(Fq))
        return np.sqrt(np.asarray(d2, dtype=np.float64)) / head

    d = off(P)
    far = d > max_off
    if not far.any():
        return
    order = np.argsort(-d)
    worst = ", ".join(f"{names[i]} {d[i]:.2g}" for i in order[:min(4, int(far.sum()))])
    more = f" and {int(far.sum()) - 4} more" if far.sum() > 4 else ""
    msg = (f"{source}: {int(far.sum())} of {counted(len(P), 'landmark')} {'lies' if far.sum() == 1 else 'lie'} "
           "far from the mesh surface "
           f"({worst}{more} head sizes; at most {max_off:g} allowed)")
    best = None
    for scale, meaning in _UNIT_HINTS:
        with np.errstate(over="ignore"):
            scaled = P * scale
        near = int((off(scaled) <= max_off).sum())
        if near > int((~far).sum()) and near >= 0.8 * len(P) and (best is None or near > best[0]):
            best = (near, scale, meaning)
    if best is not None:
        _, scale, meaning = best
        msg += (f"; wrong units? scaled by {scale:g} they lie on the surface, so they look like {meaning}: "
                f"give the landmarks in the mesh's units")
    else:
        msg += "; landmarks must be in the mesh's own coordinates (same frame and units) and on its surface"
    raise AutobonesError(msg)


def _check_sides(clean, frame, source):
    pairs = [b for b in BILATERAL if f"{b}_l" in clean and f"{b}_r" in clean]
    if not pairs:
        return
    L = frame.to_canonical(np.array([clean[f"{b}_l"] for b in pairs]))
    R = frame.to_canonical(np.array([clean[f"{b}_r"] for b in pairs]))
    dx = L[:, 0] - R[:, 0]
    inverted = dx < 0
    if inverted.sum() * 2 > len(pairs):
        raise AutobonesError(
            f"{source}: left and right are swapped (mirrored set): in {int(inverted.sum())} of {len(pairs)} pairs "
            f"the _l point is on the subject's right; _l is the subject's own left (the viewer's right in a "
            f"frontal picture), exchange _l and _r (if they are right, the head's detected up or front is wrong: "
            f"give them explicitly)")
    clear = inverted & (dx < -0.01)  # a pair close to the midline may cross by a hair
    if clear.any():
        raise AutobonesError(
            f"{source}: {_list(pairs[i] for i in np.flatnonzero(clear))} have _l and _r exchanged "
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
