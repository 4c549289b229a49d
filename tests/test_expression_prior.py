"""autobones.rig_transfer.expression_prior: the expression a head wears, solved and worn by the fit (issue #34 item 1).

The packaged ARKit set (ICT-FaceKit's skin, 51 shapes and 20 identity modes) is the space; ICT is linear,
so ICT identity000 wearing a shape is its neutral skin plus the shape's displacement, vertex for vertex:
the truth of every correspondence below. Left-out tests take the shape and its mirror out of the space
and identity000's own mode out of the identity modes.
"""
import json
import os

import fast_simplification
import numpy as np
import pytest

import autobones
from autobones.arkit.shapes import load_shapes, shapes_folder
from autobones.errors import AutobonesError
from autobones.geometry.closest import closest_points
from autobones.io.mesh import load_mesh
from autobones.rig_transfer.correspondence import dense_correspondence
from autobones.rig_transfer.expression_prior import (NOT_SKIN, check_space, fit_expression, shape_set_expression,
                                                     space_from_deltas, weights_by_name)

from shared_data import data


@pytest.fixture(scope="module")
def ict():
    """The packaged set, identity000's skin (same vertices), the set's landmarks' barycentric rows, the
    vertices any shape moves (the face)."""
    S = load_shapes()
    skin = np.load(os.path.join(shapes_folder(), "ict_arkit.npz"))["skin_index"]
    identity000 = load_mesh(data("ict/identity000.obj"))[0][skin]
    names = sorted(S.landmarks)
    _, lface, lbary, _ = closest_points(np.array([S.landmarks[n] for n in names]), S.vertices, S.faces)
    face = np.zeros(len(S.vertices), dtype=bool)
    for d in S.deltas.values():
        face |= np.linalg.norm(d, axis=1) > 0.01
    return S, identity000, names, (lface, lbary), face


def _target(ict, shape, decimate=True):
    """identity000 wearing ``shape`` (the truth, vertex for vertex), its landmarks, and the surface given
    to the fit: decimated to half its triangles, so it shares no vertex with the truth."""
    S, identity000, names, (lface, lbary), _ = ict
    truth = identity000 + (S.deltas[shape] if shape else 0.0)
    lm = {n: lbary[i] @ truth[S.faces[lface[i]]] for i, n in enumerate(names)}
    if not decimate:
        return truth, lm, truth, S.faces
    VT, FT = fast_simplification.simplify(truth.astype(np.float32), S.faces.astype(np.int32), target_reduction=0.5)
    return truth, lm, VT.astype(np.float64), FT.astype(np.int64)


def _left_out(ict, shape):
    """The set's space without ``shape`` and its mirror partner, identity modes without identity000's."""
    S = ict[0]
    pair = {shape, shape.replace("Left", "Right"), shape.replace("Right", "Left")}
    space = space_from_deltas({k: v for k, v in S.deltas.items() if k not in pair}, len(S.vertices))
    space["identity"] = S.identity[1:]
    return space


def _error(ict, R, truth, lm):
    """Mean and 95th percentile over the face of |fitted - true| in % of the target's ex-ex."""
    exex = np.linalg.norm(lm["exocanthion_l"] - lm["exocanthion_r"])
    e = 100 * np.linalg.norm(R - truth, axis=1)[ict[4]] / exex
    return e.mean(), np.percentile(e, 95)


@pytest.mark.parametrize("shape", ["mouthPucker", "mouthFunnel"])
def test_left_out_expression_fit_within_the_bounds(ict, shape):
    """A pucker and a funnel the space does not hold, on another identity's decimated surface: the fit
    wearing the expression found is within 1 % mean / 3 % p95 of ex-ex on the face and better than the
    neutral fit (measured 0.49 / 1.82 against 0.69 / 3.00, and 0.58 / 2.11 against 0.78 / 2.90)."""
    S = ict[0]
    truth, lm, VT, FT = _target(ict, shape)
    src = {n: S.landmarks[n] for n in lm}
    details = {}
    R = dense_correspondence(S.vertices, S.faces, VT, FT, src, lm, expressions=_left_out(ict, shape),
                             details=details)[0]
    neutral = dense_correspondence(S.vertices, S.faces, VT, FT, src, lm)[0]
    mean, p95 = _error(ict, R, truth, lm)
    mean0, p950 = _error(ict, neutral, truth, lm)
    assert details["expression"]["weights"], details
    assert mean <= 1.0 and p95 <= 3.0, (mean, p95)
    assert mean < 0.85 * mean0 and p95 < 0.8 * p950, (mean, p95, mean0, p950)


def test_a_left_out_smile_is_not_forced():
    """A smile the space does not hold gains too little over the identity alone (0.43 < MIN_GAIN): the
    fit stays neutral, exactly the fit without the space, rather than risk a wrong expression."""
    S = load_shapes()
    skin = np.load(os.path.join(shapes_folder(), "ict_arkit.npz"))["skin_index"]
    truth = load_mesh(data("ict/identity000.obj"))[0][skin] + S.deltas["mouthSmileLeft"]
    names = sorted(S.landmarks)
    _, lface, lbary, _ = closest_points(np.array([S.landmarks[n] for n in names]), S.vertices, S.faces)
    lm = {n: lbary[i] @ truth[S.faces[lface[i]]] for i, n in enumerate(names)}
    pair = {"mouthSmileLeft", "mouthSmileRight"}
    space = space_from_deltas({k: v for k, v in S.deltas.items() if k not in pair}, len(S.vertices))
    details = {}
    w = fit_expression(S.vertices, S.faces, np.array([S.landmarks[n] for n in names]),
                       np.array([lm[n] for n in names]), truth, S.faces, space, identity=S.identity[1:],
                       details=details)
    assert not w.any() and 0.2 < details["gain"] < 0.5, details


def test_a_left_out_smile_slides_less_from_the_local_warp(ict):
    """The smile the space does not hold is fitted neutral; started from the landmarks' spline near them
    and their affine map far from them (``transfer``'s warp on a human face), the face slides less than
    from the spline, whose reach carries the mouth corners' move over the cheeks."""
    S = ict[0]
    truth, lm, VT, FT = _target(ict, "mouthSmileLeft")
    src = {n: S.landmarks[n] for n in lm}
    errors = {}
    for far_field in ("spline", "local"):
        details = {}
        R = dense_correspondence(S.vertices, S.faces, VT, FT, src, lm, expressions=_left_out(ict, "mouthSmileLeft"),
                                 details=details, far_field=far_field)[0]
        assert details["expression"]["weights"] == {} and details["far_field"] == far_field, details
        errors[far_field] = _error(ict, R, truth, lm)
    (mean, p95), (mean0, p950) = errors["local"], errors["spline"]
    assert mean < 0.8 * mean0 and p95 < 0.7 * p950, errors


def test_the_expression_found_is_the_one_worn(ict):
    """In the space, an open jaw and a smile are found as themselves (every other weight small: the part
    of identity000 its left-out mode would explain) and a neutral identity as none."""
    S = ict[0]
    for shape, expect in (("jawOpen", "jawOpen"), ("mouthSmileLeft", "mouthSmileLeft"), (None, None)):
        _, lm, VT, FT = _target(ict, shape, decimate=False)
        weights, details = shape_set_expression(S, VT, FT, lm, identity=S.identity[1:])
        top = max(weights, key=weights.get)
        if expect is None:
            assert not any(weights.values()) and details["weights"] == {}, details
        else:
            assert top == expect and weights[top] > 0.75, details
            assert max(v for k, v in weights.items() if k != top) < 0.25, details   # the rest small


def test_a_neutral_real_scan_stays_neutral():
    """james (a real one-surface scan, not ICT): no expression is taken from his own face's shape."""
    S = load_shapes()
    V, F = load_mesh(data("menpo3d/james.obj"))[:2]
    lm = json.loads(open(data("menpo3d/james.landmarks.json")).read())["landmarks"]
    weights, details = shape_set_expression(S, V, F, lm, identity=S.identity)
    assert not any(weights.values()) and details["gain"] < 0.4, details
    # transferred, the generic fits his closed mouth from the landmarks' local warp, and says so
    assert autobones.transfer((V, F), lm).options["expression_fit"]["warp"] == "local"


def test_transfer_records_and_wears_the_expression():
    """``transfer`` solves the expression once, the generic skin wears it in its fit, the sidecar says
    which; ``expression_fit=False`` fits the neutral skin and says so."""
    V, F = load_mesh(data("ict/mouthSmile_L.obj"))[:2]
    lm = json.loads(open(data("ict/generic_neutral_mesh.landmarks.json")).read())["landmarks"]
    N = load_mesh(data("ict/generic_neutral_mesh.obj"))[0]
    names = sorted(lm)
    _, lface, lbary, _ = closest_points(np.array([lm[n] for n in names]), N, F)
    lm = {n: lbary[i] @ V[F[lface[i]]] for i, n in enumerate(names)}    # the landmarks as the face moved
    rig = autobones.transfer((V, F), lm)
    record = rig.options["expression_fit"]
    assert max(record["weights"], key=record["weights"].get) == "mouthSmileLeft", record
    assert record["generic"].get("mouthSmileLeft", 0) > 0.5 and record["gain"] >= 0.4, record
    assert record["warp"] == "local", record           # a human face: the landmarks' local warp
    off = autobones.transfer((V, F), lm, expression_fit=False)
    assert "off" in off.options["expression_fit"]
    assert not np.array_equal(off.weights, rig.weights)            # the fit did change


def test_space_helpers():
    n = 4
    deltas = {"jawOpen": np.ones((n, 3)), "eyeLookUpLeft": np.ones((n, 3)), "mouthClose": np.ones((n, 3)),
              "cheekPuff": np.zeros((n, 3))}
    space = space_from_deltas(deltas, n)
    assert space["names"] == ["jawOpen"] and space["basis"].shape == (1, n, 3)
    assert all(not k.startswith(NOT_SKIN) for k in space["names"])
    assert space_from_deltas({"cheekPuff": np.zeros((n, 3))}, n) is None
    assert np.array_equal(weights_by_name(["a", "b", "jawOpen"], {"a": 2.0, "jawOpen": -0.5}), [1.0, 0.0, 0.0])
    with pytest.raises(AutobonesError, match="basis"):
        check_space({"names": ["a"], "basis": np.zeros((1, n + 1, 3))}, n)
    with pytest.raises(AutobonesError, match="NaN"):
        check_space({"names": ["a"], "basis": np.full((1, n, 3), np.nan)}, n)
    with pytest.raises(AutobonesError, match="names"):
        check_space([1, 2], n)


def test_fit_expression_is_deterministic(ict):
    S = ict[0]
    _, lm, VT, FT = _target(ict, "mouthPucker", decimate=False)
    P = np.array([S.landmarks[n] for n in sorted(lm)])
    Q = np.array([lm[n] for n in sorted(lm)])
    space = _left_out(ict, "mouthPucker")
    a = fit_expression(S.vertices, S.faces, P, Q, VT, FT, space, identity=space["identity"])
    b = fit_expression(S.vertices, S.faces, P, Q, VT, FT, space, identity=space["identity"])
    assert np.array_equal(a, b) and a.max() > 0.3


def test_automatic_landmarks_leave_the_fit_neutral(monkeypatch):
    """With detected landmarks the detector's biases would read as an expression: the fit stays
    neutral and the sidecar says why (the detection itself is stubbed: this is about the record)."""
    from autobones.rig_transfer import pipeline

    V, F = load_mesh(data("menpo3d/james.obj"))[:2]
    lm = json.loads(open(data("menpo3d/james.landmarks.json")).read())["landmarks"]
    real = pipeline.head_landmarks

    def as_detected(*args):
        got, frame, _, shared = real(*args)
        return got, frame, type("Detected", (), {"confidence": {}, "dropped": [], "flagged": []})(), shared

    monkeypatch.setattr(pipeline, "head_landmarks", as_detected)
    monkeypatch.setattr(pipeline, "generic_detected_landmarks", lambda generic, rig=None: None)
    rig = autobones.transfer((V, F), lm)
    assert "automatic landmarks" in rig.options["expression_fit"]["off"]
