"""build_rig and LabelledRig on the default head, a rotated millimetre copy of it, and an ICT head."""
import json
import os

import numpy as np
import pytest

from shared_data import ROOT, data

from autobones.rig_building.build import BONES, REGIONS, build_rig, load_muscle_definitions, required_landmarks
from autobones.errors import AutobonesError
from autobones.io.landmarks import MIDLINE, NAMES, read_landmarks
from autobones.io.mesh import load_mesh
from autobones.labelled_rig import LabelledRig

GR = ROOT / "generic_rig"


@pytest.fixture(scope="module")
def head():
    V, F = load_mesh(GR / "default_head.obj")
    lm = read_landmarks(GR / "default_head.landmarks.json")
    return V, F, lm


@pytest.fixture(scope="module")
def rig(head):
    V, F, lm = head
    return build_rig(V, F, lm)


def winding(V, F, P):
    import igl

    return igl.fast_winding_number(np.ascontiguousarray(V, dtype=np.float64), np.ascontiguousarray(F, dtype=np.int64),
                                   np.ascontiguousarray(np.atleast_2d(P), dtype=np.float64))


def surface_distance(V, F, P):
    import igl

    d2, _, _ = igl.point_mesh_squared_distance(np.atleast_2d(P), V, np.asarray(F, dtype=np.int64))
    return np.sqrt(d2)


def nearest_vertex(V, p):
    return int(np.argmin(np.linalg.norm(V - p, axis=1)))


# --- landmarks ------------------------------------------------------------------------------

def test_default_landmarks_complete_on_surface_and_symmetric(head):
    V, F, lm = head
    assert set(lm) == set(NAMES)
    P = np.array([lm[k] for k in NAMES])
    assert surface_distance(V, F, P).max() < 1e-6
    for k in MIDLINE:
        assert lm[k][0] == 0.0, k
    for k in NAMES:
        if k.endswith("_l"):
            r = lm[k[:-2] + "_r"]
            assert np.array_equal(r, lm[k] * [-1, 1, 1]), k
            assert lm[k][0] > 0, k


def test_default_landmarks_anatomical_order(head):
    _, _, lm = head
    y = {k: v[1] for k, v in lm.items()}
    chain = ["menton", "pogonion", "sublabiale", "labiale_inferius", "stomion", "labiale_superius",
             "subnasale", "pronasale", "nasion", "vertex"]
    assert all(y[a] < y[b] for a, b in zip(chain, chain[1:])), chain
    assert lm["pronasale"][2] == max(v[2] for v in lm.values())
    assert lm["exocanthion_l"][0] > lm["endocanthion_l"][0]
    assert y["palpebrale_inferius_l"] < y["palpebrale_superius_l"] < y["brow_middle_l"]


# --- skeleton -------------------------------------------------------------------------------

def test_skeleton_names_parents_and_inside(rig, head):
    V, F, lm = head
    sk = rig.skeleton
    assert list(sk.names) == list(BONES)
    assert [sk.names[p] if p >= 0 else None for p in sk.parents] == [None, "neck", "head", "head", "head"]
    P = np.vstack([sk.heads, sk.tails])
    assert (winding(V, F, P) > 0.5).all()


def test_jaw_pivot_at_the_condyle_in_front_of_the_tragion(rig, head):
    # the condyle: 10-15 mm anterior of the ear canal at its height (mm scaled by ex-ex / 90 mm);
    # the default head is in metres, +Y up, +Z front
    _, _, lm = head
    j = rig.skeleton.heads[rig.skeleton.index("jaw")]
    tr = 0.5 * (lm["tragion_l"] + lm["tragion_r"])
    mm = np.linalg.norm(lm["exocanthion_l"] - lm["exocanthion_r"]) / 90.0
    assert 10 * mm < j[2] - tr[2] < 15 * mm and abs(j[1] - tr[1]) < 2 * mm
    assert abs(j[0]) < 0.002  # one jaw bone on the midline
    tail = rig.skeleton.tails[rig.skeleton.index("jaw")]
    assert tail[1] < lm["stomion"][1] and tail[2] > j[2] + 0.03  # toward the chin


def test_eyes_inside_and_behind_the_corners(rig, head):
    V, F, lm = head
    for s in "lr":
        c = rig.skeleton.heads[rig.skeleton.index(f"eye_{s}")]
        assert winding(V, F, c)[0] > 0.5
        ex, en = lm[f"exocanthion_{s}"], lm[f"endocanthion_{s}"]
        assert c[2] < min(ex[2], en[2]) - 0.005
        assert min(ex[0], en[0]) < c[0] < max(ex[0], en[0])


# --- weights --------------------------------------------------------------------------------

def test_weights_partition_of_unity(rig):
    W = rig.weights
    assert W.shape == (len(rig.vertices), len(BONES))
    assert W.min() >= 0
    np.testing.assert_allclose(W.sum(axis=1), 1.0, atol=1e-9)
    assert np.array_equal(rig.fields["skin_weights"], W)
    # closed eyes on a skin-only head: the eye bones move eyeballs only
    assert W[:, BONES.index("eye_l")].max() == 0 and W[:, BONES.index("eye_r")].max() == 0
    assert W[:, BONES.index("neck")].max() > 0.9 and W[:, BONES.index("head")].max() > 0.9


@pytest.mark.parametrize("name", ["menton", "pogonion", "labiale_inferius"])
def test_jaw_weight_high_on_chin_and_lower_lip(rig, head, name):
    V, _, lm = head
    assert rig.weights[nearest_vertex(V, lm[name]), BONES.index("jaw")] >= 0.9


@pytest.mark.parametrize("name", ["labiale_superius", "subnasale", "pronasale", "vertex", "opisthocranion",
                                  "zygion_l", "tragion_r"])
def test_jaw_weight_low_above_the_mouth(rig, head, name):
    V, _, lm = head
    assert rig.weights[nearest_vertex(V, lm[name]), BONES.index("jaw")] <= 0.1


def test_jaw_weight_zero_on_the_neck(rig, head):
    V, _, lm = head
    neck = V[:, 1] < lm["menton"][1] - 0.03
    assert rig.fields["jaw_weight"][neck].max() < 0.05


# --- regions --------------------------------------------------------------------------------

def test_regions_cover_every_vertex_and_none_empty(rig):
    reg = rig.fields["region"]
    assert rig.labels["region"] == list(REGIONS)
    assert reg.shape == (len(rig.vertices),)
    assert reg.min() >= 0 and reg.max() < len(REGIONS)
    counts = np.bincount(reg, minlength=len(REGIONS))
    assert (counts > 0).all(), dict(zip(REGIONS, counts))
    for name in ("depth_group", "face_half"):
        f = rig.fields[name]
        assert (np.bincount(f, minlength=len(rig.labels[name])) > 0).all()


@pytest.mark.parametrize("landmark,region", [
    ("pronasale", "nose"), ("stomion", "lips"), ("pogonion", "chin"), ("vertex", "scalp"),
    ("superaurale_l", "ears"), ("palpebrale_superius_r", "eyelids"), ("brow_middle_l", "brow"),
    ("zygion_l", "cheeks"), ("gonion_r", "jaw")])
def test_regions_at_landmarks(rig, head, landmark, region):
    V, _, lm = head
    assert REGIONS[rig.fields["region"][nearest_vertex(V, lm[landmark])]] == region


def test_face_half_split_at_the_mouth(rig, head):
    V, _, lm = head
    fh = rig.fields["face_half"]
    assert rig.labels["face_half"][fh[nearest_vertex(V, lm["nasion"])]] == "upper"
    assert rig.labels["face_half"][fh[nearest_vertex(V, lm["pogonion"])]] == "lower"


# --- muscles --------------------------------------------------------------------------------

def test_muscles_definitions_cover_seed_001_types():
    defs = load_muscle_definitions()
    types = {m["type"] for m in defs}
    assert len(types) == 20 and len(defs) == 40
    assert sum(m.get("kind") == "sphincter" for m in defs) == 6     # orbicularis oris (2 parts) and oculi
    assert sum(m.get("kind") == "sheet" for m in defs) == 2         # mentalis
    for m in defs:
        assert abs(sum(m["origin"].values()) - 1) < 1e-9 and abs(sum(m["insertion"].values()) - 1) < 1e-9
        assert set(m["origin"]) | set(m["insertion"]) <= set(NAMES)


def test_muscles_origin_under_skin_insertion_on_skin(rig, head):
    V, F, _ = head
    linear = [m for m in rig.muscles if m.get("kind") not in ("sphincter", "sheet")]
    rings = [m for m in rig.muscles if m.get("kind") in ("sphincter", "sheet")]
    assert len(linear) == 32 and len(rings) == 8
    O = np.array([m["origin"] for m in linear])
    I = np.array([m["insertion"] for m in linear])
    assert (winding(V, F, O) > 0.5).all()
    assert surface_distance(V, F, I).max() < 1e-6
    assert (surface_distance(V, F, O) > surface_distance(V, F, I) + 0.003).all()
    # a sphincter's or sheet's centre and lateral point lie on the skin
    assert surface_distance(V, F, np.array([m[k] for m in rings for k in ("origin", "insertion")])).max() < 1e-6
    for m in rig.muscles:
        f = rig.fields["muscle/" + m["name"]]
        assert f.min() >= 0 and f.max() <= 1 and f.max() > 0.3, m["name"]
        # influence is on the muscle's own side (the two mentalis muscles meet at the midline)
        if m["type"] != "mentalis":
            x = rig.vertices[f > 0.1, 0] * (1 if m["side"] == "l" else -1)
            assert (x < -0.003).mean() < 0.1, m["name"]


def test_muscles_mirror(rig):
    by = {m["name"]: m for m in rig.muscles}
    for name, m in by.items():
        if name.endswith("_l"):
            r = by[name[:-2] + "_r"]
            np.testing.assert_allclose(r["insertion"], m["insertion"] * [-1, 1, 1], atol=2e-3)


# --- other heads, errors --------------------------------------------------------------------

def test_rotated_millimetre_copy_gives_the_same_rig(rig, head):
    V, F, lm = head
    R = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])  # Y-up -> Z-up
    move = lambda P: 1000.0 * np.asarray(P) @ R.T + [5.0, -7.0, 3.0]  # noqa: E731
    rig2 = build_rig(move(V), F, {k: move(v) for k, v in lm.items()})
    np.testing.assert_allclose(rig2.skeleton.heads, move(rig.skeleton.heads), atol=1.0)  # within 1 mm
    assert np.mean(rig2.fields["region"] == rig.fields["region"]) > 0.97
    np.testing.assert_allclose(rig2.fields["jaw_weight"], rig.fields["jaw_weight"], atol=0.1)


def test_ict_head_lacks_ear_and_jaw_landmarks():
    V, F = load_mesh(data("ict/identity000.obj"))
    lm = read_landmarks(data("ict/identity000.landmarks.json"))
    missing = sorted(set(required_landmarks()) - set(lm))
    assert {"tragion_l", "tragion_r", "gonion_l", "gonion_r", "vertex", "zygion_l"} <= set(missing)
    with pytest.raises(AutobonesError) as e:
        build_rig(V, F, lm)
    msg = str(e.value)
    assert f"{len(missing)} landmarks missing" in msg
    for k in missing:
        assert k in msg


def test_missing_landmarks_named(head):
    V, F, lm = head
    cut = {k: v for k, v in lm.items() if k not in ("gonion_l", "pogonion")}
    with pytest.raises(AutobonesError, match="gonion_l, pogonion"):
        build_rig(V, F, cut)


def test_swapped_sides_rejected(head):
    V, F, lm = head
    swapped = {(k[:-2] + ("_r" if k.endswith("_l") else "_l") if k[-2:] in ("_l", "_r") else k): v
               for k, v in lm.items()}
    with pytest.raises(AutobonesError, match="swapped"):
        build_rig(V, F, swapped)


def test_bad_muscle_definition(head):
    V, F, lm = head
    bad = [dict(load_muscle_definitions()[0], origin={"nasion": 0.5, "pronasale": 0.4})]
    with pytest.raises(AutobonesError, match="sum to"):
        build_rig(V, F, lm, muscles=bad)


# --- LabelledRig ----------------------------------------------------------------------------

def test_save_load_round_trip(rig, tmp_path):
    rig.fields["my_field"] = np.linspace(0, 1, len(rig.vertices))
    try:
        folder = rig.save(tmp_path / "rig")
        assert sorted(os.listdir(tmp_path)) == ["rig"]  # no temporary folder left
        back = LabelledRig.load(folder)
    finally:
        del rig.fields["my_field"]
    assert np.array_equal(back.vertices, rig.vertices) and np.array_equal(back.faces, rig.faces)
    assert back.skeleton.names == rig.skeleton.names
    assert np.array_equal(back.skeleton.heads, rig.skeleton.heads)
    assert np.array_equal(back.skeleton.parents, rig.skeleton.parents)
    for k, v in rig.landmarks.items():
        assert np.array_equal(back.landmarks[k], v)
    np.testing.assert_allclose(back.weights, rig.weights, atol=1e-7)
    assert set(back.fields) == set(rig.fields) | {"my_field"}
    for k, v in rig.fields.items():
        if np.issubdtype(np.asarray(v).dtype, np.integer):
            assert np.array_equal(back.fields[k], v), k
        else:
            np.testing.assert_allclose(back.fields[k], v, atol=1e-6, err_msg=k)
    assert back.labels == rig.labels
    for a, b in zip(back.muscles, rig.muscles):
        assert a["name"] == b["name"] and np.array_equal(a["origin"], b["origin"])


def test_save_replaces_existing_folder(rig, tmp_path):
    rig.save(tmp_path / "r")
    rig.save(tmp_path / "r")
    assert sorted(os.listdir(tmp_path)) == ["r"]
    assert sorted(os.listdir(tmp_path / "r")) == ["fields.npz", "mesh.obj", "rig.json"]


def test_load_errors(rig, tmp_path):
    with pytest.raises(AutobonesError, match="no such rig folder"):
        LabelledRig.load(tmp_path / "nothing")
    folder = rig.save(tmp_path / "r")
    os.remove(os.path.join(folder, "fields.npz"))
    with pytest.raises(AutobonesError, match="missing fields.npz"):
        LabelledRig.load(folder)
    folder = rig.save(tmp_path / "r2")
    with open(os.path.join(folder, "rig.json"), "w") as fh:
        fh.write('{"format": "autobones-labelled-rig/1", "skeleton": [')
    with pytest.raises(AutobonesError, match="not readable rig JSON"):
        LabelledRig.load(folder)
    folder = rig.save(tmp_path / "r3")
    with open(os.path.join(folder, "fields.npz"), "wb") as fh:
        fh.write(b"not a zip")
    with pytest.raises(AutobonesError, match="corrupt"):
        LabelledRig.load(folder)


def test_bad_field_shape_rejected(rig, tmp_path):
    rig.fields["bad"] = np.zeros(3)
    try:
        with pytest.raises(AutobonesError, match="bad"):
            rig.save(tmp_path / "r")
    finally:
        del rig.fields["bad"]


def test_committed_default_rig_is_up_to_date(rig):
    back = LabelledRig.load(GR / "default")
    assert np.array_equal(back.vertices, rig.vertices)
    np.testing.assert_allclose(back.weights, rig.weights, atol=1e-6)
    assert np.array_equal(back.fields["region"], rig.fields["region"])
    np.testing.assert_allclose(back.skeleton.heads, rig.skeleton.heads, atol=1e-9)
    assert back.units == "metres"
    meta = json.loads((GR / "default" / "rig.json").read_text())
    assert len(meta["muscles"]) == 40


def test_default_rig_face_belongs_to_head_and_jaw_not_neck():
    from autobones.labelled_rig import LabelledRig
    from autobones.generic_rig import default_rig_path

    rig = LabelledRig.load(default_rig_path())
    names, region = rig.labels["region"], rig.fields["region"]
    neck = rig.weights[:, rig.skeleton.names.index("neck")]
    for face_part in ("lips", "nose", "eyelids", "brow", "forehead"):
        assert neck[region == names.index(face_part)].max() <= 0.05, face_part
    # the lower cheeks reach into the 3 cm neck transition behind the jaw angle
    assert neck[region == names.index("cheeks")].mean() <= 0.05
    assert neck[region == names.index("neck")].mean() >= 0.8
