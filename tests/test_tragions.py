"""tests/landmarks/*.tragions.json (issue #32): on the skin, one each side of the face's midplane, beside
the head behind the eyes, at an adult's width; ICT's identities share the neutral's two vertices."""
import json
from pathlib import Path

import numpy as np
import pytest

from autobones.geometry.closest import closest_points
from autobones.io.landmarks import read_landmarks
from autobones.io.mesh import load_mesh
from autobones.landmarks.refine import symmetry_plane

from shared_data import data

LANDMARKS = Path(__file__).resolve().parent / "landmarks"
HEADS = ["menpo3d/james.obj", "menpo3d/template.ply", "ict/generic_neutral_mesh.obj", "ict/identity000.obj",
         "ict/identity001.obj", "ict/identity002.obj", "misc/LeePerrySmith.obj"]


def _head(rel):
    V, F = load_mesh(data(rel))
    stem = rel.split("/")[1].rsplit(".", 1)[0]
    own = LANDMARKS / f"{stem}.landmarks.json"   # detected ones where the shared head has none
    path = own if own.exists() else data(f"{rel.split('/')[0]}/{stem}.landmarks.json")
    lm = {k: np.asarray(v, float) for k, v in json.load(open(path))["landmarks"].items()}
    tr = {k: np.asarray(v, float) for k, v in read_landmarks(LANDMARKS / f"{stem}.tragions.json").items()}
    return V, F, lm, tr


@pytest.mark.parametrize("rel", HEADS, ids=[h.split("/")[1].split(".")[0] for h in HEADS])
def test_tragions_on_the_skin_beside_the_head_behind_the_eyes(rel):
    V, F, lm, tr = _head(rel)
    assert sorted(tr) == ["tragion_l", "tragion_r"]
    size = float(np.ptp(V, axis=0).max())
    P = np.array([tr["tragion_l"], tr["tragion_r"]])
    d = np.linalg.norm(closest_points(P, V, F)[0] - P, axis=1)
    assert d.max() < 1e-6 * size
    ex = float(np.linalg.norm(lm["exocanthion_l"] - lm["exocanthion_r"]))
    normal, offset = symmetry_plane(lm)   # toward the subject's left
    side = (P @ normal - offset) / ex
    assert 0.6 < side[0] < 1.1 and -1.1 < side[1] < -0.6    # the left one on the left
    assert abs(side[0] + side[1]) < 0.1                      # mirror images across the midplane
    # behind the eyes, along the face's front: left x up, up menton -> nasion
    eyes = 0.5 * (lm["exocanthion_l"] + lm["exocanthion_r"])
    up = lm["nasion"] - lm["menton"]
    front = np.cross(normal, up - (up @ normal) * normal)
    front /= np.linalg.norm(front)
    assert (lm["pronasale"] - eyes) @ front > 0
    behind = ((eyes - P) @ front) / ex
    assert np.all((0.4 < behind) & (behind < 1.2))


def test_ict_identities_share_the_neutral_tragion_vertices():
    V0, _ = load_mesh(data("ict/generic_neutral_mesh.obj"))
    t0 = read_landmarks(LANDMARKS / "generic_neutral_mesh.tragions.json")
    ids = {k: int(np.argmin(np.linalg.norm(V0 - p, axis=1))) for k, p in t0.items()}
    assert all(np.array_equal(V0[i], t0[k]) for k, i in ids.items())
    for k in range(3):
        V, _ = load_mesh(data(f"ict/identity00{k}.obj"))
        t = read_landmarks(LANDMARKS / f"identity00{k}.tragions.json")
        assert all(np.allclose(V[i], t[n], rtol=0, atol=1e-12) for n, i in ids.items())
        assert not np.allclose(V[ids["tragion_l"]], V0[ids["tragion_l"]])   # a different head, the same vertex
