"""autobones.placement.facial_bones: symmetric k-means facial bones, deterministic, best of restarts."""
import numpy as np
import pytest

from autobones.errors import AutobonesError
from autobones.placement.facial_bones import DENSITIES, FacialBones, bone_count, bones_for_mask

MIRROR = np.array([-1.0, 1.0, 1.0])


def _symmetric_blobs(seed=0):
    rng = np.random.default_rng(seed)
    centres = np.array([[0.3, 0.2, 0.5], [0.0, 0.0, 0.6], [0.2, -0.3, 0.5], [0.0, 0.4, 0.5]])
    pts = [c + 0.02 * rng.normal(size=(300, 3)) for c in centres]
    half = np.vstack(pts[:1] + pts[2:3])
    mid = np.vstack([pts[1], pts[3]])
    mid[:, 0] = np.abs(mid[:, 0])
    X = np.vstack([half, half * MIRROR, mid, mid * MIRROR])
    return X


@pytest.mark.parametrize("k", [1, 2, 5, 6, 9])
def test_centres_are_mirror_symmetric_with_exact_count(k):
    X = _symmetric_blobs()
    m = FacialBones(n_bones=k, random_state=0).fit(X)
    C = m.cluster_centers_
    assert C.shape == (k, 3)
    np.testing.assert_allclose(C[m.partner_] * MIRROR, C, atol=1e-12)
    np.testing.assert_array_equal(m.partner_[m.partner_], np.arange(k))


def test_finds_the_blobs_and_lower_error_than_one_restart():
    X = _symmetric_blobs()
    m = FacialBones(n_bones=6, n_init=8, random_state=0).fit(X)
    expected = np.array([[0.3, 0.2, 0.5], [-0.3, 0.2, 0.5], [0, 0, 0.6], [0.2, -0.3, 0.5], [-0.2, -0.3, 0.5], [0, 0.4, 0.5]])
    d = np.linalg.norm(m.cluster_centers_[:, None] - expected[None], axis=2).min(axis=0)
    assert d.max() < 0.02
    one = FacialBones(n_bones=6, n_init=1, random_state=3).fit(X)
    assert m.inertia_ <= one.inertia_ + 1e-12


def test_deterministic_bit_for_bit():
    X = _symmetric_blobs(1)
    a = FacialBones(n_bones=7, random_state=5).fit(X)
    b = FacialBones(n_bones=7, random_state=5).fit(X)
    assert a.cluster_centers_.tobytes() == b.cluster_centers_.tobytes()
    np.testing.assert_array_equal(a.labels_, b.labels_)


def test_labels_are_nearest_centres():
    X = _symmetric_blobs(2)
    m = FacialBones(n_bones=5).fit(X)
    d = np.linalg.norm(X[:, None] - m.cluster_centers_[None], axis=2)
    np.testing.assert_array_equal(m.labels_, d.argmin(axis=1))


def test_bone_counts():
    assert bone_count("sparse") == DENSITIES["sparse"] == 8
    assert bone_count("medium") == 16 and bone_count("dense") == 32 and bone_count("24") == 24 and bone_count(3) == 3
    for bad in ["lots", "0", "-3", "1000", "2.5"]:
        with pytest.raises(AutobonesError):
            bone_count(bad)


def test_too_few_points_is_a_clear_error():
    with pytest.raises(AutobonesError, match=r"lower --density \(at most 5\)"):
        FacialBones(n_bones=10).fit(np.zeros((5, 3)))


def test_a_named_density_fits_a_small_mask_and_a_number_is_taken_as_asked():
    assert bones_for_mask(16, "medium", 5000) == 16 and bones_for_mask(8, "Sparse", 8) == 8   # enough: as asked
    assert bones_for_mask(16, "medium", 10) == 5 and bones_for_mask(32, "dense", 1) == 1       # one per two vertices
    assert bones_for_mask(16, 16, 10) == 16 and bones_for_mask(16, "16", 10) == 16            # a number: as asked


def test_a_low_poly_head_takes_the_default_density_with_fewer_bones(caplog):
    """A 63-vertex copy of the robot head: its facial mask (about 20 vertices) is too small for dense's 32
    bones; the named density places one per two mask vertices and says so, a number is refused."""
    import autobones
    from autobones.geometry.proxy import quadric_simplify
    from shared_data import data

    V, F = autobones.load_mesh(data("misc/robot_head_neutral.obj"))
    Vd, Fd = quadric_simplify(V, F.astype(np.int32), 1 - 50 / len(V))
    head = (np.asarray(Vd, dtype=np.float64), np.asarray(Fd, dtype=np.int64))
    with caplog.at_level("WARNING", logger="autobones"):
        rig = autobones.place(head, density="dense")
    mask = int(rig.facial_mask.sum())
    assert mask < 32 and rig.options["facial_bones"] == mask // 2 and rig.options["facial_bones_asked"] == 32
    assert sum(n.startswith("face_") for n in rig.skeleton.names) == mask // 2
    assert abs(rig.weights.sum(axis=1) - 1).max() < 1e-9 and "too few for the 32 facial bones" in caplog.text
    with pytest.raises(AutobonesError, match=f"at most {mask}"):
        autobones.place(head, density=32)
