"""Left/right symmetry of a transferred rig (issue #4: the goat's lopsided expressions).

The goat is modelled with its muzzle along -X (the generic rig faces +Z): before the fit's
shape term was turned into the head file's axes, the generic's right side slid across the
goat's midline, its right-side muscles with it, and a symmetric smile moved one cheek only.
The mirror plane is fitted to the head's bilateral landmark pairs; lengths are in units of
the exocanthion distance (ex-ex). Full table on four heads: ``benchmarks/symmetry.py``.
"""
import numpy as np
import pytest
from scipy.spatial import cKDTree

import autobones
from autobones.landmarks.refine import symmetry_plane
from autobones.expressions.model import ExpressionModel
from autobones.rig_transfer.correspondence import dense_correspondence
from autobones.geometry.rotations import axis_turn
from autobones.orient import reflect
from autobones.rig_transfer.pipeline import load_generic

from shared_data import ROOT, data

GOAT = (data("misc/goathead.obj"), ROOT / "tests" / "landmarks" / "goathead.landmarks.json")


@pytest.fixture(scope="module")
def goat():
    rig = autobones.transfer(*GOAT)
    lm = rig.extra["landmarks"]
    plane = symmetry_plane(lm)
    exex = float(np.linalg.norm(np.subtract(lm["exocanthion_l"], lm["exocanthion_r"])))
    return rig, plane, exex


def test_goat_muscle_pairs_are_mirror_images(goat):
    """Each muscle's origin and insertion mirror onto its partner's: measured at most 0.04 / 0.10
    ex-ex (the goat's own landmark pairs mismatch by up to 0.04, its mouth is crooked); before the
    fix 0.95 / 0.94."""
    rig, plane, exex = goat
    mus = {m["name"]: m for m in rig.extra["muscles"]}
    pairs = [k for k in mus if k.endswith("_l") and k[:-2] + "_r" in mus]
    assert len(pairs) == 20
    for end in ("origin", "insertion"):
        miss = [np.linalg.norm(reflect(mus[k][end], *plane) - np.asarray(mus[k[:-2] + "_r"][end])) / exex
                for k in pairs]
        assert max(miss) < 0.15, (end, dict(zip(pairs, np.round(miss, 3))))


def test_goat_symmetric_expression_moves_both_sides_alike(goat):
    """Happiness and AU12 on both sides: ``||D - mirror(D)|| / ||D||`` over the skin, mirror(D) the
    reflected displacement of each vertex's nearest skin vertex across the plane. Measured 0.28 /
    0.24, left/right balance 0.81 (a displacement exactly symmetric in space scores 0.11 on this
    slightly asymmetric mesh); before the fix 1.44 / 1.45, the left side moving 77 times as much
    as the right."""
    rig, plane, _ = goat
    model = ExpressionModel().fit(rig)
    V, skin = rig.vertices, model.skin_
    idx = np.flatnonzero(skin)
    partner = idx[cKDTree(V[idx]).query(reflect(V, *plane))[1]]
    n = plane[0]
    side = V @ n - plane[1]
    for kw in ({"expression": "happiness"}, {"au": {12: 1.0}}):
        D = model.pose(**kw) - V
        M = D[partner] - 2.0 * (D[partner] @ n)[:, None] * n
        asym = np.linalg.norm((D - M)[skin]) / np.linalg.norm(D[skin])
        moved = np.linalg.norm(D, axis=1) * skin
        balance = moved[side > 0].sum() / moved[side < 0].sum()
        assert asym < 0.5 and 0.67 < balance < 1.5, (kw, asym, balance)


def test_correspondence_does_not_depend_on_the_target_files_axes():
    """The generic skin fitted onto the default head and onto the same head turned a quarter turn
    about its up axis (the goat's file convention) lands on the same points, turned."""
    generic = load_generic()
    V, F = generic.vertices, generic.faces
    R = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])   # x @ R: +Z front -> -X front
    lm = dict(generic.landmarks)
    P = dense_correspondence(V, F, V, F, lm, lm)[0]
    Q = dense_correspondence(V, F, V @ R, F, lm, {k: np.asarray(v) @ R for k, v in lm.items()})[0]
    size = np.ptp(V, axis=0).max()
    assert np.abs(Q - P @ R).max() < 1e-6 * size
    assert np.allclose(axis_turn(2.0 * R), R) and np.allclose(axis_turn(np.eye(3) * 3.0), np.eye(3))
