"""autobones.rig_transfer.fields: fields carried onto another head with another triangulation, inpainting."""
import json

import fast_simplification
import numpy as np
import pytest

from autobones.rig_transfer.fields import inpaint, sample_fields, transfer_attributes
from autobones.io.mesh import load_mesh

from shared_data import data, icosphere


@pytest.fixture(scope="module")
def ict_transfer():
    """identity000's fields carried onto identity001 remeshed to half its triangles."""
    from sklearn.cluster import KMeans

    Vs, Fs = load_mesh(data("ict/identity000.obj"))
    Vt, Ft = load_mesh(data("ict/identity001.obj"))
    ls = json.load(open(data("ict/identity000.landmarks.json")))["landmarks"]
    lt = json.load(open(data("ict/identity001.landmarks.json")))["landmarks"]
    scalar = np.sin(Vs[:, 1] / 8) + 0.5 * np.cos(Vs[:, 0] / 6) + Vs[:, 2] / 20  # smooth, cm units
    regions = KMeans(12, n_init=2, random_state=0).fit_predict(Vs).astype(np.int64)
    Vr, Fr = fast_simplification.simplify(Vt.astype(np.float32), Ft.astype(np.int32), target_reduction=0.5)
    Vr, Fr = Vr.astype(np.float64), Fr.astype(np.int64)
    out = transfer_attributes((Vs, Fs), (Vr, Fr), {"scalar": scalar, "region": regions}, ls, lt)
    # ground truth: identity001 shares identity000's vertex list, so a field on identity001 is the
    # source field itself; read it at each remeshed vertex's closest point on identity001
    face, bary, _ = sample_fields(Vt, Ft, Vr)
    truth_s = np.einsum("ki,ki->k", bary, scalar[Ft[face]])
    truth_r = regions[Ft[face][np.arange(len(face)), bary.argmax(axis=1)]]
    return out, truth_s, truth_r, np.ptp(scalar)


def test_labels_land_on_the_right_vertices(ict_transfer):
    out, _, truth_r, _ = ict_transfer
    assert out["region"].dtype == np.int64
    assert (out["region"] == truth_r).mean() >= 0.97


def test_scalar_field_within_two_percent_of_its_range(ict_transfer):
    out, truth_s, _, rng = ict_transfer
    err = np.abs(out["scalar"] - truth_s) / rng
    assert err.mean() <= 0.02 and np.quantile(err, 0.95) <= 0.02, (err.mean(), np.quantile(err, 0.95))


def test_inpaint_keeps_known_values_and_fills_harmonically():
    V, F = icosphere(3)
    f = V[:, 1]  # linear fields are nearly harmonic on a sphere's caps; check smooth fill
    known = np.abs(V[:, 1]) > 0.3
    g = inpaint(V, F, f, known)
    np.testing.assert_array_equal(g[known], f[known])
    assert np.abs(g[~known] - f[~known]).max() < 0.1
    assert g[~known].min() >= f[known].min() and g[~known].max() <= f[known].max()  # maximum principle


def test_inpaint_gives_unreached_parts_the_nearest_value():
    V1, F1 = icosphere(2)
    V = np.vstack([V1, V1 + [5, 0, 0]])
    F = np.vstack([F1, F1 + len(V1)])
    known = np.zeros(len(V), bool)
    known[: len(V1)] = True
    vals = np.column_stack([np.ones(len(V)), V[:, 0]])
    g = inpaint(V, F, vals, known)
    assert np.isfinite(g).all() and np.allclose(g[len(V1):, 0], 1.0)


def test_field_length_must_match():
    from autobones.errors import AutobonesError

    V, F = icosphere(2)
    with pytest.raises(AutobonesError, match="rows"):
        transfer_attributes((V, F), (V, F), {"f": np.zeros(3)}, {}, {})


def test_local_frames_recover_a_rigid_motion_and_scale_and_stay_rotations_under_shear():
    from scipy.spatial.transform import Rotation

    from autobones.rig_transfer.fields import local_frames

    V, F = icosphere(2)
    R = Rotation.from_rotvec(np.radians(73.0) * np.array([1.0, 2.0, -0.5]) / np.sqrt(5.25)).as_matrix()
    Rf, scale = local_frames(V, 3.0 * V @ R.T + [1.0, -2.0, 0.5], F, np.arange(len(F)))
    assert np.abs(Rf - R).max() < 1e-12 and np.abs(scale - 3.0).max() < 1e-12
    shear = np.array([[1.0, 0.6, 0.0], [0.0, 1.0, 0.0], [0.2, 0.0, 1.3]])
    Rs, s = local_frames(V, V @ shear.T, F, np.arange(len(F)))
    assert np.abs(Rs @ Rs.transpose(0, 2, 1) - np.eye(3)).max() < 1e-12
    assert np.all(np.linalg.det(Rs) > 0) and np.all(s > 0)


@pytest.fixture(scope="module")
def head_on_its_side():
    """The default head and a displacement field on it (normal bulge plus a swirl about the up
    axis), and the same head turned 90 degrees about the front axis (lying on its side),
    scaled 2x and moved."""
    from autobones.geometry.normals import vertex_normals
    from autobones.io.landmarks import read_landmarks
    from autobones.io.mesh import default_head
    from shared_data import ROOT

    V, F = default_head()
    lm = read_landmarks(ROOT / "generic_rig" / "default_head.landmarks.json")
    D = 0.01 * vertex_normals(V, F) + 0.05 * np.cross([0.0, 1.0, 0.0], V - V.mean(axis=0))
    R = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    move = lambda P: 2.0 * np.asarray(P) @ R.T + [0.3, -1.0, 2.0]  # noqa: E731
    return V, F, lm, D, R, move


def test_displacements_turn_and_scale_with_the_head(head_on_its_side):
    """Same mesh: every copied (not inpainted) vector is 2 R d to 1e-9 of the largest (measured
    3e-13); copied as plain numbers they point the wrong way."""
    from autobones.rig_transfer.correspondence import dense_correspondence
    from autobones.rig_transfer.fields import transfer_fields

    V, F, lm, D, R, move = head_on_its_side
    Vt, lmt = move(V), {k: move(v) for k, v in lm.items()}
    want = 2.0 * D @ R.T
    big = np.linalg.norm(want, axis=1).max()
    P, _, _, ok = dense_correspondence(V, F, Vt, F, lm, lmt)
    out, copied = transfer_fields(P, F, {"d": D}, Vt, F, source_reliable=ok, vectors=["d"], V_rest=V)
    assert copied.mean() > 0.97
    assert np.linalg.norm(out["d"] - want, axis=1)[copied].max() < 1e-9 * big
    plain = transfer_attributes((V, F), (Vt, F), {"d": D}, lm, lmt)["d"]
    assert np.linalg.norm(plain - want, axis=1).max() > 0.5 * big
    unit = transfer_attributes((V, F), (Vt, F), {"n": D / np.linalg.norm(D, axis=1, keepdims=True)}, lm, lmt,
                               directions=["n"])["n"]
    assert np.median(np.abs(np.linalg.norm(unit, axis=1) - 1.0)) < 1e-9  # directions are not scaled


def test_displacements_onto_a_decimated_head_on_its_side(head_on_its_side):
    """Target remeshed to half its vertices: the median error is 2.2 % of the largest vector (plain
    copy: 70 %), measured against the source field at each target vertex's preimage."""
    from autobones.geometry.closest import closest_points

    V, F, lm, D, R, move = head_on_its_side
    Vd, Fd = fast_simplification.simplify(move(V).astype(np.float32), F.astype(np.int32), target_reduction=0.5)
    Vd, Fd = Vd.astype(np.float64), Fd.astype(np.int64)
    lmt = {k: move(v) for k, v in lm.items()}
    pre = (Vd - [0.3, -1.0, 2.0]) @ R / 2.0
    _, face, bary = closest_points(pre, V, F)[:3]
    want = 2.0 * np.einsum("ki,kij->kj", bary, D[F[face]]) @ R.T
    big = np.linalg.norm(want, axis=1).max()
    got = transfer_attributes((V, F), (Vd, Fd), {"d": D}, lm, lmt, vectors=["d"])["d"]
    assert np.median(np.linalg.norm(got - want, axis=1)) < 0.05 * big


def test_vector_fields_must_be_n_by_3_floats():
    from autobones.errors import AutobonesError

    V, F = icosphere(1)
    lm = {f"p{i}": V[i] for i in range(0, len(V), 4)}
    with pytest.raises(AutobonesError, match="must be \\(n, 3\\) floats"):
        transfer_attributes((V, F), (V, F), {"d": np.zeros(len(V))}, lm, lm, vectors=["d"])
