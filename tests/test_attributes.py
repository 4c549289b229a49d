"""autobones.attributes: fields carried onto another head with another triangulation, inpainting."""
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
