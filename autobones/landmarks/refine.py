"""Geometric refinement of detected landmarks, where the mesh is more precise than a picture.

Midline names are moved onto the face's own mirror plane, bilateral pairs are made mirror
images of each other (a pair whose sides disagree by more than ``max_mirror_error`` is
flagged; a missing side is replaced by the mirror image of the other), pronasale becomes
the most anterior point of the nose tip region and menton the lowest point of the chin on
the mirror plane.

Frames and units: canonical head frame (+Y up, +Z out of the face, +X toward the subject's
left), canonical units; thresholds in units of the outer-eye-corner distance (ex-ex).
"""
from __future__ import annotations

import numpy as np

from ..io.landmark_names import mirror_name
from ..orient import reflect

#: Degrees between the face's eye-over-mouth line and the vertical in which the nose tip
#: is the most anterior and the menton the lowest midline point (measured on the published
#: ICT and menpo3d landmarks: 15 degrees on both sources).
PROFILE_TILT = 15.0


def symmetry_plane(points):
    """The face's own mirror plane from landmarks: normal along the bilateral pairs' mean right ->
    left vector, offset the median of the midline points and pair midpoints.

    The mean vector, not the unit directions' median: a placement error tilts a wide pair (the ear
    canals, the eye corners) less than a narrow one (the inner eye corners), so the wide pairs count
    more; and it turns with the points, where a per-coordinate median (used until 2026-12-06) is
    taken along the input's axes: the zoo's bunny turned at random moved its plane by up to 2
    degrees, the cat and the armadillo by 1. The automatic landmarks' accuracy, which this plane
    refines, is unchanged (benchmarks/README.md).

    Parameters
    ----------
    points : dict of str -> (3,)

    Returns
    -------
    normal : (3,) float64
        Unit normal pointing toward the subject's left.
    offset : float
        ``normal . p = offset`` on the plane.
    """
    pairs = [(np.asarray(points[n]), np.asarray(points[mirror_name(n)]))
             for n in points if n.endswith("_l") and mirror_name(n) in points]
    # float64 whatever the points' dtype (integer coordinates summed to an integer vector, which
    # cannot be divided in place); no pair, or every pair on one point: no side to tell
    normal = np.sum([a - b for a, b in pairs], axis=0, dtype=np.float64) if pairs else np.zeros(3)
    if not np.linalg.norm(normal) > 0:
        return np.array([1.0, 0.0, 0.0]), 0.0
    normal /= np.linalg.norm(normal)
    on = [np.asarray(p) for n, p in points.items() if not n.endswith(("_l", "_r"))]
    on += [(a + b) / 2.0 for a, b in pairs]
    return normal, float(np.median(np.array(on) @ normal))


def midline_profile(V, F, normal, offset):
    """(k, 3) points where the surface crosses the plane ``normal . p = offset`` (segment ends)."""
    import trimesh

    mesh = trimesh.Trimesh(V, F, process=False)
    seg = trimesh.intersections.mesh_plane(mesh, normal, normal * offset)
    return np.asarray(seg, dtype=np.float64).reshape(-1, 3)


def refine(Vc, F, points, unit, max_mirror_error):
    """Geometric refinement of canonical landmarks (see the module docstring).

    Parameters
    ----------
    Vc : (n, 3) float
        Canonical vertices (+Y up, +Z front).
    F : (m, 3) int
    points : dict of str -> (3,)
        Canonical landmarks.
    unit : float
        ex-ex distance, canonical units.
    max_mirror_error : float
        Flag threshold, ex-ex units.

    Returns
    -------
    points : dict of str -> (3,)
        Refined (not yet snapped to the surface).
    flagged : dict of str -> str
    """
    out = {n: np.array(p, dtype=np.float64) for n, p in points.items()}
    flagged = {}
    n_, c = symmetry_plane(out)
    for n in list(out):
        if n.endswith("_l") and mirror_name(n) in out:
            m = mirror_name(n)
            a, b = out[n], reflect(out[m], n_, c)
            err = float(np.linalg.norm(a - b)) / unit
            if err > max_mirror_error:
                flagged[n] = flagged[m] = (f"left and right are not mirror images "
                                           f"({100 * err:.1f}% of the eye-corner distance apart)")
            mid = (a + b) / 2.0
            out[n], out[m] = mid, reflect(mid, n_, c)
        elif not n.endswith(("_l", "_r")):
            out[n] = out[n] - (out[n] @ n_ - c) * n_
    for n in list(out):
        if n.endswith(("_l", "_r")) and mirror_name(n) not in out:
            # its own views disagreed: the mirror image of the other side stands in
            out[mirror_name(n)] = reflect(out[n], n_, c)
            flagged[mirror_name(n)] = f"mirrored from {n}"
    return on_profile(Vc, F, out, n_, c, unit), flagged


def on_profile(V, F, points, normal, offset, unit, names=("pronasale", "menton")):
    """``pronasale`` as the most anterior and ``menton`` as the lowest point of the midline profile near
    where they are, in the face's own frame (up: the eye corners over the mouth, in the mirror plane).

    Parameters
    ----------
    V : (n, 3) float
        Vertices, any frame and units (the face's frame comes from the points).
    F : (m, 3) int
    points : dict of str -> (3,)
        Landmarks, same frame; needs eye corners and a midline mouth name, else returned unchanged.
    normal, offset : (3,) float, float
        The mirror plane (:func:`symmetry_plane`).
    unit : float
        ex-ex distance, mesh units (the search reaches 0.15 ex-ex for pronasale, 0.25 for menton).
    names : tuple of str
        Which of the two to move.

    Returns
    -------
    dict of str -> (3,)
        A copy of ``points`` with those names moved (points of the profile, on the surface).
    """
    out = dict(points)
    eyes = [out[k] for k in ("exocanthion_l", "exocanthion_r", "endocanthion_l", "endocanthion_r") if k in out]
    mouth = [out[k] for k in ("stomion", "labiale_superius", "labiale_inferius") if k in out]
    if not eyes or not mouth:
        return out
    up = np.mean(eyes, axis=0) - np.mean(mouth, axis=0)
    up -= (up @ normal) * normal
    up /= np.linalg.norm(up)
    front = np.cross(normal, up)
    profile = midline_profile(V, F, normal, offset)
    tilt = np.radians(PROFILE_TILT)
    for name, direction, reach in (
            # the eye-mouth line leans back from the Frankfort vertical, so straight ahead
            # and straight down in the face's frame are turned by PROFILE_TILT
            ("pronasale", np.cos(tilt) * front - np.sin(tilt) * up, 0.15),
            ("menton", -np.cos(tilt) * up + np.sin(tilt) * front, 0.25)):
        if name in names and name in out and len(profile):
            near = profile[np.linalg.norm(profile - out[name], axis=1) < reach * unit]
            if len(near):
                out[name] = near[np.argmax(near @ direction)]
    return out
