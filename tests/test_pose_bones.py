"""Turning the head and neck of any rig, ``place``'s included: ``Rig.turn_bones`` and ``autobones pose
--head / --neck`` on a rig with no muscles, by linear blend skinning with the rig's own weights."""
import os
import subprocess
import sys

import numpy as np
import pytest

import autobones
from autobones.errors import AutobonesError
from autobones.geometry.rotations import axis_rotation

from shared_data import ROOT


@pytest.fixture(scope="module")
def placed(rigs, tmp_path_factory):
    """The default head rigged by ``place`` (sparse), saved and loaded back as a user's file is."""
    folder = tmp_path_factory.mktemp("placed")
    rigs(None, density="sparse").save(folder / "placed.glb")
    return folder, autobones.load_rig(folder / "placed.glb")


def _lbs_turn(rig, yaw):
    """The head and everything under it turned ``yaw`` degrees about the head frame's up axis through
    the head joint, written out independently of ``bones.py``: (n, 3) input frame."""
    S = rig.skeleton
    moved = np.zeros(len(S), dtype=bool)
    for j in range(len(S)):  # parents come before their children
        moved[j] = S.names[j] == "head" or (S.parents[j] >= 0 and moved[S.parents[j]])
    share = rig.weights[:, moved].sum(axis=1, keepdims=True)
    C = rig.frame.to_canonical(rig.vertices)
    p = rig.frame.to_canonical(S.heads[[S.names.index("head")]])[0]
    turned = (C - p) @ axis_rotation(1, yaw).T + p
    return rig.frame.from_canonical(C + share * (turned - C))


def test_a_placed_rig_turns_its_head_as_a_gltf_player_does(placed):
    _, rig = placed
    assert not rig.muscles
    V = rig.pose(head_deg=(0.0, 30.0, 0.0))
    assert np.allclose(V, _lbs_turn(rig, 30.0), atol=1e-9 * rig.frame.size)
    motion = np.linalg.norm(V - rig.vertices, axis=1)
    assert motion.max() > 0.1 * rig.frame.size   # the face swings
    C = rig.frame.to_canonical(rig.vertices)
    low = C[:, 1] <= C[:, 1].min() + 0.05 * np.ptp(C[:, 1])
    assert motion[low].max() <= 0.01 * motion.max()   # the neck's base stays
    assert np.array_equal(rig.pose(head_deg=(0.0, 0.0, 0.0)), rig.vertices)
    # every bone hangs under the neck: a neck turn turns the whole head and neck rigidly about its joint
    neck = rig.turn_bones(neck_deg=(0.0, 30.0, 0.0))
    p = rig.frame.to_canonical(rig.skeleton.heads[[rig.skeleton.names.index("neck")]])[0]
    rigid = rig.frame.from_canonical((C - p) @ axis_rotation(1, 30.0).T + p)
    assert np.allclose(neck, rigid, atol=1e-6 * rig.frame.size)   # the glb's float32 weights sum to 1 within 1e-7


def test_a_placed_rig_still_refuses_what_needs_muscles(placed):
    _, rig = placed
    with pytest.raises(AutobonesError, match="no muscles"):
        rig.pose(head_deg=(0.0, 30.0, 0.0), au={12: 1.0})


def test_cli_turns_a_placed_rigs_head_and_refuses_the_rest_in_one_line(placed, tmp_path):
    folder, rig = placed
    env = dict(os.environ, PYTHONPATH=str(ROOT))

    def run(*args):
        return subprocess.run([sys.executable, "-m", "cli.main", "pose", str(folder / "placed.glb"), *args],
                              cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)

    r = run("--head", "0,30,0", "-o", "turned.obj")
    assert r.returncode == 0, r.stderr
    V, _ = autobones.load_mesh(tmp_path / "turned.obj")
    assert np.allclose(V, _lbs_turn(rig, 30.0), atol=1e-6 * rig.frame.size)   # the OBJ's printed digits
    r = run("--head", "0,30,0", "--au", "12", "-o", "smile.obj")
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1 and "no muscles" in r.stderr
    assert "--head and --neck" in r.stderr and not (tmp_path / "smile.obj").exists()
