"""The symmetric correspondence (autobones.rig_transfer.symmetry, issue #16 item 4): mirror partners of the
generic skin land on mirror points of a symmetric head; real scans and one-sided expressions keep their asymmetry."""
from pathlib import Path

import numpy as np
import pytest

import autobones
from autobones.generic_rig import HERE as GENERIC_DIR, default_head_path
from autobones.io.landmarks import read_landmarks
from autobones.io.mesh import load_mesh
from autobones.landmarks.refine import symmetry_plane
from autobones.orient import reflect
from autobones.rig_transfer.pipeline import load_generic
from autobones.rig_transfer.symmetry import Symmetry, mirror_operator, surface_asymmetry, symmetrize
from shared_data import data

TEST_LANDMARKS = Path(__file__).resolve().parent / "landmarks"


def _exex(lm):
    return float(np.linalg.norm(np.asarray(lm["exocanthion_l"]) - np.asarray(lm["exocanthion_r"])))


def test_mirror_operator_pairs_the_generic_skin_vertex_for_vertex():
    generic = load_generic()
    V, F = generic.vertices, generic.faces
    plane = symmetry_plane(generic.landmarks)
    M, has = mirror_operator(V, F, plane, 1e-3 * _exex(generic.landmarks))
    assert has.all()
    assert np.allclose(M.sum(axis=1), 1.0)
    # each vertex's partner is a vertex (the generic skin is built mirror-symmetric), its mirror image
    assert np.abs(M.max(axis=1).toarray().ravel() - 1.0).max() < 1e-6
    assert np.abs(reflect(M @ V, *plane) - V).max() < 1e-6 * np.ptp(V, axis=0).max()


def test_symmetrize_makes_partners_mirror_images():
    generic = load_generic()
    V, F = generic.vertices, generic.faces
    plane = symmetry_plane(generic.landmarks)
    M, has = mirror_operator(V, F, plane, 1e-3 * _exex(generic.landmarks))
    X = V + np.random.default_rng(0).normal(scale=0.01 * _exex(generic.landmarks), size=V.shape)
    Y = symmetrize(X, M, has, plane)
    assert np.abs(reflect(M @ Y, *plane) - Y).max() < 1e-9 * np.ptp(V, axis=0).max()


def _robot():
    V, F = load_mesh(data("misc/robot_head_neutral.obj"))
    return V, F, read_landmarks(TEST_LANDMARKS / "robot_head_neutral.landmarks.json")


def _mirror_error(V, F, lm, symmetric):
    """The correspondence's mirror error on the head, % of ex-ex: generic vertex v and its partner m(v)."""
    details = {}
    rig = autobones.transfer((V, F), lm, details=details, symmetric=symmetric)
    generic = load_generic()
    gplane = symmetry_plane(generic.landmarks)
    M, _ = mirror_operator(generic.vertices, generic.faces, gplane, 1e-3 * _exex(generic.landmarks))
    P = details["correspondence"]
    plane = symmetry_plane(rig.landmarks)
    err = 100 * np.linalg.norm(reflect(P, *plane) - M @ P, axis=1) / _exex(rig.landmarks)
    return err, rig


def test_a_symmetric_head_gets_a_symmetric_correspondence():
    V, F, lm = _robot()
    on, rig = _mirror_error(V, F, lm, "auto")
    off, rig_off = _mirror_error(V, F, lm, "off")
    assert rig.options["symmetric"]["applied"] and not rig_off.options["symmetric"]["applied"]
    assert rig.options["symmetric"]["head_asymmetry"] < 0.025
    # measured: off 2.8 / 11.1 % (mean / p95), on 0.0 / 0.0
    assert np.percentile(off, 95) > 3.0
    assert np.percentile(on, 95) < 0.3 and on.mean() < 0.1


def test_a_real_scan_keeps_its_own_asymmetry():
    V, F = load_mesh(data("menpo3d/james.obj"))
    lm = read_landmarks(data("menpo3d/james.landmarks.json"))
    rig = autobones.transfer((V, F), lm, symmetric="auto")
    assert not rig.options["symmetric"]["applied"]
    # both gates hold it back: its published landmark pairs and its surface are no mirror images
    assert rig.options["symmetric"]["landmark_mismatch"] > 0.01                       # measured 0.048
    far = surface_asymmetry(V, F, symmetry_plane(lm), _exex(lm))
    assert np.percentile(far, 75) > 0.025                                              # measured 0.037


def test_a_one_sided_expression_or_a_goat_is_left_as_it_is():
    """A symmetric head wearing a one-sided expression: its landmark pairs are no mirror images."""
    V, F = load_mesh(default_head_path())
    lm = read_landmarks(Path(GENERIC_DIR) / "default_head.landmarks.json")
    generic = load_generic()
    assert Symmetry("auto").fit(generic.vertices, generic.faces, generic.landmarks, V, F, lm).applied_
    unit = _exex(lm)
    corner = np.asarray(lm["cheilion_l"])
    bump = np.exp(-((V - corner) ** 2).sum(axis=1) / (0.25 * unit) ** 2)
    V2 = V + 0.08 * unit * bump[:, None] * np.array([0.3, 0.6, 0.2])   # the left corner drawn up and out
    lm2 = {**lm, "cheilion_l": corner + 0.08 * unit * np.array([0.3, 0.6, 0.2])}
    sym = Symmetry("auto").fit(generic.vertices, generic.faces, generic.landmarks, V2, F, lm2)
    assert not sym.applied_ and sym.record_["landmark_mismatch"] > 0.05
    assert sym.fit_option() is None
    Vg, Fg = load_mesh(data("misc/goathead.obj"))
    goat = Symmetry("auto").fit(generic.vertices, generic.faces, generic.landmarks, Vg, Fg,
                                read_landmarks(TEST_LANDMARKS / "goathead.landmarks.json"))
    assert not goat.applied_                                 # hand-placed pairs 3.6 % of ex-ex apart
    forced = Symmetry("on").fit(generic.vertices, generic.faces, generic.landmarks, Vg, Fg,
                                read_landmarks(TEST_LANDMARKS / "goathead.landmarks.json"))
    assert forced.applied_ and forced.fit_option() is not None


def test_automatic_landmarks_leave_auto_off():
    """Automatic landmarks are a little off even on an exactly symmetric head (the default head: pairs 1.6 %
    of ex-ex apart, their plane tilted by about a degree), and symmetrising about that plane moved the
    correspondence by 1.9 / 4.0 % of ex-ex (mean / p95): auto stays off with them."""
    rig = autobones.transfer(None, None)
    assert rig.options["landmarks_source"] == "detected"
    assert rig.options["symmetric"]["applied"] is False and rig.options["symmetric"]["reason"] == "automatic landmarks"
    # the face found in the detected frame's front views settles which way it looks: no close call kept
    assert rig.frame.front_check is None


def test_symmetric_mode_is_checked():
    V, F, lm = _robot()
    with pytest.raises(autobones.AutobonesError, match="symmetric must be one of"):
        autobones.transfer((V, F), lm, symmetric="yes")
