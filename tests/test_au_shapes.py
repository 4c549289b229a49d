"""Action units through the head's own ARKit shapes (issue #34 item 2): Rig.pose(layer=...), autobones pose --layer."""
import dataclasses
import os
import subprocess
import sys

import numpy as np
import pytest

import autobones
from autobones.arkit.shapes import NPZ, load_shapes, shapes_folder
from autobones.errors import AutobonesError
from autobones.expressions import au_shapes
from autobones.expressions.definitions import au_arkit_table
from shared_data import ROOT, data


@pytest.fixture(scope="module")
def rig():
    """ICT identity001: held out, the packaged shapes come from ICT's generic neutral."""
    return autobones.transfer(data("ict/identity001.obj"), data("ict/identity001.landmarks.json"), arkit=True)


@pytest.fixture(scope="module")
def plain(rig):
    """The same rig without its ARKit shapes (as transfer without --arkit leaves it)."""
    return dataclasses.replace(rig, arkit=None, arkit_targets=None)


def truth(au):
    """ICT's own displacement of ``au`` on its skin vertices (ICT is linear: identity + expression, so
    the generic neutral's shapes are every identity's), and those vertices' indices in ICT's order."""
    S = load_shapes()
    with np.load(os.path.join(shapes_folder(), NPZ)) as z:
        skin = z["skin_index"].astype(np.int64)
    row = next(r for r in au_arkit_table() if au in r["au"])
    return sum(S.deltas[n] for n in row["arkit"]), skin


@pytest.mark.parametrize("au", [12, 26])
def test_mapped_aus_explain_icts_own_shapes(rig, au):
    """Measured 97.3 % (AU12) and 96.2 % (AU26) on identity001; muscles 52 % and 42 %."""
    T, skin = truth(au)
    got = (rig.pose(au={au: 1.0}) - rig.vertices)[skin]
    explained = 1 - np.linalg.norm(got - T) / np.linalg.norm(T)
    assert explained >= 0.80, explained
    muscles = (rig.pose(au={au: 1.0}, layer="muscles") - rig.vertices)[skin]
    assert explained > 1 - np.linalg.norm(muscles - T) / np.linalg.norm(T)


def test_muscles_layer_and_a_rig_without_shapes_pose_as_before(rig, plain):
    model = rig.expression_model()
    mix = dict(au={12: 0.7, "4L": 0.5, 23: 0.3}, expression={"anger": 0.5}, jaw_deg=5.0, gaze=(5.0, 0.0))
    old = model.pose(**mix)
    assert np.array_equal(rig.pose(**mix, layer="muscles"), old)
    assert np.array_equal(plain.pose(**mix), old)   # auto on a rig without shapes: the muscles, bit for bit
    assert np.array_equal(plain.pose(**mix, layer="muscles"), old)
    with pytest.raises(AutobonesError, match="no ARKit shapes; make it with autobones transfer HEAD --arkit"):
        plain.pose(au={12: 1}, layer="shapes")
    with pytest.raises(AutobonesError, match="layer: 'both' is not one of auto, shapes, muscles"):
        rig.pose(au={12: 1}, layer="both")


def test_emotions_split_between_the_layers_and_shared_shapes_take_the_max(rig):
    T = rig.arkit_targets
    V = rig.vertices
    happy = V + T["mouthSmileLeft"] + T["mouthSmileRight"] + T["cheekSquintLeft"] + T["cheekSquintRight"]
    np.testing.assert_allclose(rig.pose(expression="happiness"), happy, atol=1e-9)
    # anger: AU4, 5, 7 through the shapes, AU23 and AU25 (not in the table) through the muscles
    shapes = sum(T[s + side] for s in ("browDown", "eyeWide", "eyeSquint") for side in ("Left", "Right"))
    np.testing.assert_allclose(rig.pose(expression="anger"),
                               rig.expression_model().pose(au={"23": 1.0, "25": 1.0}) + shapes, atol=1e-9)
    # jawOpen stands for AU26 and AU27: together the larger weight, not the sum
    assert np.array_equal(rig.pose(au={26: 1.0, 27: 0.6}), rig.pose(au={26: 1.0}))
    weights, rest = au_shapes.split_mix({"12": 0.3, "12L": 0.5, "1L": 1.0, "99": 1.0}, au_arkit_table(), set(T))
    assert weights == {"mouthSmileLeft": 0.8, "mouthSmileRight": 0.3} and rest == {"1L": 1.0, "99": 1.0}


def test_12L_moves_only_the_subjects_left_side(rig):
    """ICT's own mouthSmile_L drags the lips a little past the midline (0.22 cm at most on its right
    half, 1.5 % of its squared motion): the subject's right corner stays, the left one moves."""
    x = rig.frame.to_canonical(rig.vertices)[:, 0]   # canonical +X: the subject's left
    corner = {s: np.argmin(np.linalg.norm(rig.vertices - rig.landmarks["cheilion_" + s], axis=1)) for s in "lr"}
    for key, side, other in (("12L", "l", "r"), ("12R", "r", "l")):
        d = np.linalg.norm(rig.pose(au={key: 1.0}) - rig.vertices, axis=1)
        assert d[corner[other]] < 0.01 * d[corner[side]], key
        half = x > 0 if side == "l" else x < 0
        assert (d[half] ** 2).sum() > 0.9 * (d ** 2).sum(), key


def run(args, cwd):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.run([sys.executable, "-m", "cli.main"] + args, cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=600)


def test_cli_layer_option(rig, plain, tmp_path):
    from autobones.io.mesh import load_mesh

    rig.save(tmp_path / "id1.glb")
    out = run(["pose", "id1.glb", "--au", "16", "--layer", "shapes", "-o", "lower.obj"], tmp_path)
    assert out.returncode == 0, out.stderr   # AU16 has no muscle definition, but the table maps it
    V, _ = load_mesh(str(tmp_path / "lower.obj"))
    want = rig.vertices + rig.arkit_targets["mouthLowerDownLeft"] + rig.arkit_targets["mouthLowerDownRight"]
    np.testing.assert_allclose(V, want, atol=1e-4)
    plain.save(tmp_path / "plain.glb")
    bad = run(["pose", "plain.glb", "--au", "12", "--layer", "shapes", "-o", "x.obj"], tmp_path)
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "transfer HEAD --arkit" in bad.stderr
    assert not (tmp_path / "x.obj").exists()
