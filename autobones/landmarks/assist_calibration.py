"""Where to read each name off the fitted generic skin: the generic's landmarks moved to where hand-placed
ones land (issue #35).

The built-in generic head's landmarks were placed by geometric rules on a procedural head with closed
eyes (``generic_rig/place_default_landmarks.py``); read off a fitted generic they sit where those rules
put them, not where a person places the names on a real face: measured over the nine landmarked human
heads (benchmarks/landmarks.py --assist) the error of most names is one offset shared by every head
(the brows 7-13 % of ex-ex lower-and-inward, the lids 10-12 %, the nasion 8 % low), with a spread of
2-5 % around it. So each name is read off the generic skin where the hand-placed landmarks of human heads
land on it on average:

1. :func:`pull_back`: a head's landmarks, on the generic skin fitted to it
   (:func:`autobones.landmarks.assist.fit_generic`, from the same five names the assistant is given),
   carried back to the generic's rest skin (the closest point of the fitted skin, its barycentric
   coordinates in the rest triangle);
2. :func:`calibrate`: per name, the mean of those rest points over the heads, each source family
   weighing the same (four ICT identities share one topology and convention), snapped to the skin.

:func:`built_in_reading` is that calibration for the built-in rig, computed by
``tools/calibrate_assist.py`` from the shared data set's human heads and stored in
``assist_calibration.json`` beside this module; names no human head carries keep the generic's own.
Frames: rest points in the generic rig's frame and units.
"""
from __future__ import annotations

import functools
import json
import os

import numpy as np

from ..geometry.closest import closest_points

CALIBRATION_PATH = os.path.join(os.path.dirname(os.path.abspath(__file__)), "assist_calibration.json")
FORMAT = "autobones-assist-calibration/1"


def pull_back(points, Vg, Fg, P):
    """Points on a head carried back to the generic rest skin through a fit.

    Parameters
    ----------
    points : (k, 3) float
        Points on the head (its frame and units).
    Vg, Fg : (n, 3) float, (m, 3) int
        The generic's rest skin (its frame).
    P : (n, 3) float
        Each generic vertex's point on the head (the fitted skin, head frame).

    Returns
    -------
    (k, 3) float64
        The rest-skin points at the barycentric coordinates of each point's closest point on the fitted skin.
    """
    _, face, bary, _ = closest_points(np.asarray(points, dtype=np.float64), P, Fg)
    return np.einsum("ij,ijk->ik", bary, Vg[Fg[face]])


def calibrate(samples, Vg, Fg):
    """Per name, the family-weighted mean of the pulled-back points, snapped to the generic skin.

    Parameters
    ----------
    samples : list of (str, dict str -> (3,))
        (family, {name: rest point}) per head; every family weighs the same, its heads equally.
    Vg, Fg : (n, 3) float, (m, 3) int
        The generic's rest skin.

    Returns
    -------
    dict str -> (3,) float64, dict str -> int
        The reading per name (on the skin) and how many heads it came from, names sorted.
    """
    per_family = {}
    for family, pts in samples:
        per_family[family] = per_family.get(family, 0) + 1
    total, weight, count = {}, {}, {}
    for family, pts in samples:
        w = 1.0 / per_family[family]
        for n, p in pts.items():
            total[n] = total.get(n, 0.0) + w * np.asarray(p, dtype=np.float64)
            weight[n] = weight.get(n, 0.0) + w
            count[n] = count.get(n, 0) + 1
    names = sorted(total)
    if not names:
        return {}, {}
    mean = np.array([total[n] / weight[n] for n in names])
    on_skin, *_ = closest_points(mean, Vg, Fg)
    return dict(zip(names, on_skin)), {n: count[n] for n in names}


@functools.lru_cache(maxsize=1)
def _stored(path):
    with open(path, encoding="utf-8") as fh:
        data = json.load(fh)
    if data.get("format") != FORMAT:
        raise ValueError(f"{path}: not an {FORMAT} file")
    return {n: np.asarray(p, dtype=np.float64) for n, p in data["reading"].items()}


def built_in_reading():
    """The built-in rig's calibrated reading: dict name -> (3,) (a fresh copy), {} when none is stored."""
    if not os.path.isfile(CALIBRATION_PATH):
        return {}
    return {n: p.copy() for n, p in _stored(CALIBRATION_PATH).items()}


def write_reading(path, reading, counts, heads):
    """Store a reading (``reading`` name -> (3,), ``counts`` name -> heads, ``heads`` the names of the
    heads it came from) as the JSON :func:`built_in_reading` reads."""
    data = {"format": FORMAT, "heads": list(heads), "counts": {n: int(counts[n]) for n in reading},
            "reading": {n: [float(x) for x in reading[n]] for n in reading}}
    with open(path, "w", encoding="utf-8") as fh:
        json.dump(data, fh, indent=1)
        fh.write("\n")
