"""autobones.io.landmarks: every input format gives the same contract landmarks; bad files and bad
landmarks are refused with one clear line."""
import json
import os

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from autobones.errors import AutobonesError
from autobones.io.landmarks import (
    BILATERAL, IBUG68, MIDLINE, NAMES, mirror_name, read_landmarks, validate_landmarks, write_landmarks)
from autobones.io.mesh import load_mesh
from autobones.orient import detect_frame

from shared_data import data, landmark_files

SHARED = landmark_files()


def _error(fn, *args, **kwargs):
    """Call, expect one AutobonesError, and return its one-line message."""
    with pytest.raises(AutobonesError) as info:
        fn(*args, **kwargs)
    msg = str(info.value)
    assert msg and "\n" not in msg and "\r" not in msg, repr(msg)
    assert len(msg) < 600, msg
    return msg


@pytest.fixture(scope="module")
def ict():
    V, F = load_mesh(data("ict/generic_neutral_mesh.obj"))
    lm = read_landmarks(data("ict/generic_neutral_mesh.landmarks.json"))
    return V, F, detect_frame(V, F), lm


# --- names ---------------------------------------------------------------------------------------

def test_names_are_the_44_of_the_contract_in_fixed_order():
    assert len(NAMES) == 44 and len(set(NAMES)) == 44
    assert NAMES[:12] == MIDLINE and len(BILATERAL) == 16
    assert NAMES[12:16] == ("exocanthion_l", "exocanthion_r", "endocanthion_l", "endocanthion_r")
    for name in NAMES:
        assert mirror_name(mirror_name(name)) == name
        assert (mirror_name(name) == name) == (name in MIDLINE)
    assert mirror_name("cheilion_l") == "cheilion_r"
    with pytest.raises(ValueError):
        mirror_name("nose")


def test_ibug_table_maps_27_names_with_left_and_right_as_the_spec_says():
    assert len(IBUG68) == 27 and set(IBUG68) <= set(NAMES)
    assert all(0 <= i < 68 for idx in IBUG68.values() for i in idx)
    assert IBUG68["exocanthion_r"] == (36,) and IBUG68["exocanthion_l"] == (45,)
    assert IBUG68["stomion"] == (62, 66) and IBUG68["palpebrale_inferius_l"] == (46, 47)
    # mirrored names map to mirrored iBUG points: the table has no side typo
    for name, idx in IBUG68.items():
        assert (mirror_name(name) in IBUG68) and (len(IBUG68[mirror_name(name)]) == len(idx))


# --- shared files ---------------------------------------------------------------------------------

def test_shared_files_exist():
    assert len(SHARED) >= 6, SHARED


@pytest.mark.parametrize("path", SHARED, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_shared_files_read_as_contract_names_and_round_trip_bit_exactly(path, tmp_path):
    lm = read_landmarks(path)
    assert len(lm) == 27 and set(lm) <= set(NAMES)
    assert list(lm) == [n for n in NAMES if n in lm]
    raw = json.loads(path.read_text())["landmarks"]
    for name, p in lm.items():
        assert p.dtype == np.float64 and p.shape == (3,)
        assert p.tobytes() == np.array(raw[name], dtype=np.float64).tobytes()
    out = tmp_path / "again.landmarks.json"
    write_landmarks(out, lm, mesh_name="head.obj")
    back = read_landmarks(out)
    assert list(back) == list(lm)
    for name in lm:
        assert back[name].tobytes() == lm[name].tobytes()
    doc = json.loads(out.read_text())
    assert doc["format"] == "autobones-landmarks/1" and doc["mesh"] == "head.obj"
    assert os.listdir(tmp_path) == ["again.landmarks.json"]  # no temporary left behind


@pytest.mark.parametrize("path", SHARED, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_shared_files_lie_on_their_mesh(path):
    mesh = next(m for m in (path.with_name(path.name.replace(".landmarks.json", e)) for e in (".obj", ".ply"))
                if m.is_file())
    V, F = load_mesh(mesh)
    assert len(validate_landmarks(read_landmarks(path), V, F, source=path.name)) == 27


def test_write_refuses_bad_landmarks_and_keeps_the_old_file(tmp_path, ict):
    out = tmp_path / "a.json"
    write_landmarks(out, ict[3])
    before = out.read_bytes()
    _error(write_landmarks, out, {"pronasale": [0, 0, np.nan]})
    _error(write_landmarks, out, {"nose_tip": [0, 0, 1]})
    assert out.read_bytes() == before
    assert sorted(os.listdir(tmp_path)) == ["a.json"]
    _error(write_landmarks, tmp_path / "missing" / "b.json", ict[3])


# --- the iBUG-68 formats agree ------------------------------------------------------------------

def _ibug_points(seed=3):
    rng = np.random.default_rng(seed)
    return rng.uniform(-10, 10, size=(68, 3)) * np.array([1.0, 1.3, 0.7])


def _expected(P):
    return {name: P[list(idx)].mean(axis=0) for name, idx in IBUG68.items()}


def _write_all_formats(tmp_path, P):
    rows = [[float(c) for c in p] for p in P]
    paths = {}
    paths["list.json"] = tmp_path / "list.json"
    paths["list.json"].write_text(json.dumps(rows))
    paths["wrapped.json"] = tmp_path / "wrapped.json"
    paths["wrapped.json"].write_text(json.dumps({"landmarks": rows}, indent=1))
    paths["pts"] = tmp_path / "face.pts"
    paths["pts"].write_text("version: 1\nn_points: 68\n{\n" + "".join(
        f"{p[0]!r} {p[1]!r} {p[2]!r}\n" for p in rows) + "}\n")
    paths["ljson"] = tmp_path / "face.ljson"
    paths["ljson"].write_text(json.dumps({
        "version": 2, "landmarks": {"points": rows, "connectivity": [[i, i + 1] for i in range(67)]},
        "labels": [{"label": "all", "mask": list(range(68))}]}))
    expected = _expected(P)
    paths["pp"] = tmp_path / "face.pp"
    paths["pp"].write_text(
        '<!DOCTYPE PickedPoints>\n<PickedPoints>\n <DocumentData>\n  <DataFileName name="face.obj"/>\n'
        ' </DocumentData>\n'
        + "".join(f' <point x="{float(p[0])!r}" y="{float(p[1])!r}" z="{float(p[2])!r}" active="1" name="{n}"/>\n'
                  for n, p in expected.items())
        + ' <point x="1" y="2" z="3" active="0" name="not_a_landmark"/>\n</PickedPoints>\n')
    return paths


def test_every_ibug_format_gives_the_same_averaged_landmarks(tmp_path):
    P = _ibug_points()
    paths = _write_all_formats(tmp_path, P)
    results = {k: read_landmarks(p) for k, p in paths.items()}
    ref = results["list.json"]
    assert list(ref) == [n for n in NAMES if n in IBUG68]
    np.testing.assert_allclose(ref["stomion"], (P[62] + P[66]) / 2, rtol=0, atol=1e-12)
    np.testing.assert_allclose(ref["palpebrale_superius_l"], (P[43] + P[44]) / 2, rtol=0, atol=1e-12)
    np.testing.assert_allclose(ref["palpebrale_inferius_r"], (P[40] + P[41]) / 2, rtol=0, atol=1e-12)
    assert ref["exocanthion_r"].tobytes() == P[36].tobytes()
    assert ref["exocanthion_l"].tobytes() == P[45].tobytes()
    assert ref["menton"].tobytes() == P[8].tobytes()
    for kind, lm in results.items():
        assert list(lm) == list(ref), kind
        for name in ref:
            assert lm[name].tobytes() == ref[name].tobytes(), (kind, name)


def test_format_is_told_by_content_not_extension(tmp_path, ict):
    paths = _write_all_formats(tmp_path, _ibug_points())
    ref = read_landmarks(paths["list.json"])
    for kind, path in paths.items():
        odd = tmp_path / f"renamed_{kind.replace('.', '_')}.txt"
        odd.write_bytes(path.read_bytes())
        assert {k: v.tolist() for k, v in read_landmarks(odd).items()} == {k: v.tolist() for k, v in ref.items()}
    contract = tmp_path / "contract.pp"
    write_landmarks(contract, ict[3])
    assert set(read_landmarks(contract)) == set(ict[3])


def test_whitespace_bom_and_case_are_tolerated(tmp_path):
    P = _ibug_points()
    ref = read_landmarks(_write_all_formats(tmp_path, P)["list.json"])
    for i, (kind, path) in enumerate(_write_all_formats(tmp_path, P).items()):
        odd = tmp_path / f"bom{i}{path.suffix}"
        odd.write_bytes(b"\xef\xbb\xbf\n \t\r\n" + path.read_bytes().replace(b"\n", b"\r\n") + b"\n\n  ")
        lm = read_landmarks(odd)
        assert all(lm[n].tobytes() == ref[n].tobytes() for n in ref), kind
    utf16 = tmp_path / "utf16.json"
    utf16.write_bytes(b"\xff\xfe" + json.dumps({"landmarks": {" Pronasale ": [1, 2, 3], "menton": [1, -5, 2],
                                                               "nasion": [0, 3, 2.5]}}).encode("utf-16-le"))
    assert set(read_landmarks(utf16)) == {"pronasale", "menton", "nasion"}


def test_ljson_missing_points_leave_their_landmarks_out(tmp_path):
    rows = _ibug_points().tolist()
    rows[62] = None
    rows[45] = [float("nan")] * 3
    path = tmp_path / "holes.ljson"
    path.write_text(json.dumps({"landmarks": {"points": rows}}))
    lm = read_landmarks(path)
    assert "stomion" not in lm and "exocanthion_l" not in lm and len(lm) == 25


# --- named landmarks: errors --------------------------------------------------------------------

def _write_contract(tmp_path, body, name="lm.json"):
    path = tmp_path / name
    path.write_text(body if isinstance(body, str) else json.dumps(body))
    return path


def test_unknown_name_is_named_with_a_suggestion(tmp_path, ict):
    lm = {k: v.tolist() for k, v in ict[3].items()}
    lm["pronasal"] = lm.pop("pronasale")
    path = _write_contract(tmp_path, {"format": "autobones-landmarks/1", "landmarks": lm})
    msg = _error(read_landmarks, path)
    assert "lm.json" in msg and "'pronasal'" in msg and "did you mean 'pronasale'" in msg
    msg = _error(validate_landmarks, {**ict[3], "exocanthion_left": [1, 2, 3]}, source="mine.pp")
    assert "mine.pp" in msg and "'exocanthion_left'" in msg and "exocanthion_l" in msg
    assert "nose_tip" in _error(validate_landmarks, {"nose_tip": [0, 0, 0]})


def test_duplicated_names_are_refused(tmp_path):
    body = '{"format": "autobones-landmarks/1", "landmarks": {"menton": [0, -7, 10], "nasion": [0, 3, 10],' \
           ' "menton": [0, -7.5, 10.4]}}'
    assert "'menton'" in _error(read_landmarks, _write_contract(tmp_path, body))
    case = '{"landmarks": {"Menton": [0, -7, 10], "menton ": [0, -7.5, 10.4], "nasion": [0, 3, 10]}}'
    assert "'menton'" in _error(read_landmarks, _write_contract(tmp_path, case, "case.json"))
    pp = tmp_path / "dup.pp"
    pp.write_text('<PickedPoints><point x="0" y="1" z="2" name="nasion"/>'
                  '<point x="0" y="5" z="2" name="nasion"/><point x="0" y="-5" z="2" name="menton"/></PickedPoints>')
    assert "'nasion'" in _error(read_landmarks, pp)


def test_too_few_landmarks(ict):
    few = {k: ict[3][k] for k in list(ict[3])[:5]}
    msg = _error(validate_landmarks, few, source="few.json")
    assert "few.json" in msg and "only 5" in msg and "10" in msg
    assert len(validate_landmarks(few, min_count=5)) == 5
    assert "only 0" in _error(validate_landmarks, {})


def test_non_finite_coordinates(tmp_path, ict):
    path = _write_contract(tmp_path, '{"landmarks": {"menton": [0, NaN, 10], "nasion": [0, 3, 10]}}')
    assert "menton" in _error(read_landmarks, path)
    path = _write_contract(tmp_path, '{"landmarks": {"menton": [0, 1e999, 10], "nasion": [0, 3, 10]}}', "inf.json")
    assert "menton" in _error(read_landmarks, path)
    bad = {**ict[3], "nasion": np.array([0.0, np.nan, 10.0])}
    assert "nasion" in _error(validate_landmarks, bad)
    assert "nasion" in _error(validate_landmarks, {**ict[3], "nasion": [1.0, 2.0]})


def test_landmarks_at_one_point_or_on_one_line(tmp_path, ict):
    same = {**ict[3], "stomion": ict[3]["labiale_inferius"].copy()}
    msg = _error(validate_landmarks, same)
    assert "stomion" in msg and "labiale_inferius" in msg and "same point" in msg
    zeros = _write_contract(tmp_path, json.dumps([[0.0, 0.0, 0.0]] * 68), "zeros.json")
    assert "same point" in _error(read_landmarks, zeros)
    line = {n: [float(i), 2.0 * i, 0.0] for i, n in enumerate(NAMES[:12])}
    assert "one line" in _error(validate_landmarks, line)


# --- against the mesh ---------------------------------------------------------------------------

def test_real_landmarks_pass_with_mesh_and_frame(ict):
    V, F, frame, lm = ict
    out = validate_landmarks(lm, V, F, frame)
    assert list(out) == list(lm) and all(out[n] is not lm[n] for n in lm)


def test_mirrored_set_is_refused(ict):
    V, F, frame, lm = ict
    mirrored = {mirror_name(n): p for n, p in lm.items()}
    msg = _error(validate_landmarks, mirrored, V, F, frame, source="mirrored.json")
    assert "mirrored.json" in msg and "left and right are swapped" in msg
    # without a frame the swap cannot be told and is not checked
    assert len(validate_landmarks(mirrored, V, F)) == 27


def test_one_exchanged_pair_is_named(ict):
    V, F, frame, lm = ict
    one = dict(lm)
    one["cheilion_l"], one["cheilion_r"] = lm["cheilion_r"], lm["cheilion_l"]
    msg = _error(validate_landmarks, one, V, F, frame)
    assert "cheilion" in msg and "exocanthion" not in msg


def test_millimetres_for_a_centimetre_mesh_hint_at_units(ict):
    V, F, frame, lm = ict
    mm = {n: p * 10.0 for n, p in lm.items()}
    msg = _error(validate_landmarks, mm, V, F, source="mm.json")
    assert "mm.json" in msg and "units" in msg and "millimetres" in msg and "centimetres" in msg
    assert "head sizes" in msg
    metres = {n: p * 0.01 for n, p in lm.items()}
    assert "metres for a mesh in centimetres" in _error(validate_landmarks, metres, V, F)


def test_landmarks_off_the_surface(ict):
    V, F, frame, lm = ict
    head = (V.max(axis=0) - V.min(axis=0)).max()
    moved = dict(lm)
    moved["pronasale"] = lm["pronasale"] + np.array([0.0, 0.0, 0.2 * head])
    msg = _error(validate_landmarks, moved, V, F, source="off.json")
    assert "off.json" in msg and "pronasale" in msg and "1 of 27" in msg and "0.2 head sizes" in msg
    assert "millimetres" not in msg
    shifted = {n: p + np.array([0.0, 0.0, 0.3 * head]) for n, p in lm.items()}
    msg = _error(validate_landmarks, shifted, V, F)
    assert "27 of 27" in msg and "own coordinates" in msg
    # so far that a scale by 0.1-0.001 shrinks the set to a speck near the surface: no units hint (these
    # were called millimetres for a mesh in centimetres, centimetres and millimetres for one in metres)
    for heads in (3.0, 30.0, 300.0):
        far_off = {n: p + np.array([0.0, 0.0, heads * head]) for n, p in lm.items()}
        msg = _error(validate_landmarks, far_off, V, F)
        assert "27 of 27" in msg and "own coordinates" in msg and "wrong units" not in msg
    # a looser tolerance accepts the single moved landmark
    assert len(validate_landmarks(moved, V, F, max_off_surface=0.3)) == 27


def test_a_speck_of_landmarks_on_a_scan_whose_origin_is_on_its_face():
    """James' scan (millimetres) has its origin on his face, so landmarks in metres, or the goat's (a
    12-unit cluster), all lie within 0.05 head sizes of his surface: before, the first were taken and the fit
    failed with "no reliable correspondence", the second were refused as left and right swapped."""
    from pathlib import Path

    from autobones.io.landmark_checks import landmark_problems

    p = data("menpo3d/james.obj")
    V, F = load_mesh(p)
    lm = read_landmarks(p.with_suffix(".landmarks.json"))
    metres = {n: np.asarray(x) * 0.001 for n, x in lm.items()}
    msg = _error(validate_landmarks, metres, V, F, source="m.json")
    assert "m.json" in msg and "gather within" in msg and "metres for a mesh in millimetres" in msg
    goat = read_landmarks(Path(__file__).parent / "landmarks" / "goathead.landmarks.json")
    msg = _error(validate_landmarks, goat, V, F, detect_frame(V, F))
    assert "gather within" in msg and "this mesh's landmarks" in msg and "swapped" not in msg
    # the editor's live check says the same, once enough are placed to judge the set
    assert any("gather within" in t for t in landmark_problems(metres, V, F)["set"])
    assert not any("gather within" in t for t in landmark_problems(dict(list(metres.items())[:5]), V, F)["set"])
    assert len(validate_landmarks(lm, V, F)) == len(lm)


# --- hostile files --------------------------------------------------------------------------------

HOSTILE = {
    "empty.json": b"",
    "blank.json": b" \n\t\r\n ",
    "bom_only.pp": b"\xef\xbb\xbf",
    "random.json": bytes(np.random.default_rng(0).integers(0, 256, 4096, dtype=np.uint8)),
    "nul.pts": b"version: 1\x00\x00",
    "text.json": b"hello, landmarks",
    "deep.json": b"[" * 200000 + b"]" * 200000,
    "deep_obj.json": b'{"a":' * 100000 + b"1" + b"}" * 100000,
    "deep.pp": b"<a>" * 100000 + b"</a>" * 100000,
    "laughs.pp": (b'<?xml version="1.0"?><!DOCTYPE lolz [<!ENTITY lol "lol">'
                  + b"".join(b'<!ENTITY lol%d "%s">' % (i, (b"&lol%d;" % (i - 1) if i else b"&lol;") * 10)
                             for i in range(9))
                  + b']><PickedPoints><point name="&lol8;" x="0" y="0" z="0"/></PickedPoints>'),
    "huge.json": b'{"landmarks": {"menton": [0, 1e400, 0], "nasion": [0, 1, 0]}}',
    "huge_int.json": b'{"landmarks": {"menton": [0, ' + b"9" * 5000 + b', 0], "nasion": [0, 1, 0]}}',
    "huge_int_pts.pts": b"version: 1\nn_points: 68\n{\n" + b"1e999 0 0\n" * 68 + b"}\n",
    "list67.json": json.dumps(np.random.default_rng(1).normal(size=(67, 3)).tolist()).encode(),
    "list69.ljson": json.dumps({"landmarks": {"points": np.random.default_rng(1).normal(size=(69, 3)).tolist()}}).encode(),
    "list2d.json": json.dumps(np.random.default_rng(1).normal(size=(68, 2)).tolist()).encode(),
    "pts2d.pts": b"version: 1\nn_points: 68\n{\n" + b"1 2\n" * 68 + b"}\n",
    "pts_truncated.pts": b"version: 1\nn_points: 68\n{\n" + b"1 2 3\n" * 30,
    "pts_count.pts": b"version: 1\nn_points: 68\n{\n" + b"1 2 3\n" * 67 + b"}\n",
    "pts_words.pts": b"version: 1\nn_points: 68\n{\n" + b"one two three\n" * 68 + b"}\n",
    "no_points.pp": b"<!DOCTYPE PickedPoints>\n<PickedPoints><DocumentData/></PickedPoints>",
    "inactive.pp": b'<PickedPoints><point name="nasion" x="0" y="1" z="2" active="0"/></PickedPoints>',
    "no_y.pp": b'<PickedPoints><point name="nasion" x="0" z="2"/><point name="menton" x="0" y="-5" z="2"/></PickedPoints>',
    "no_name.pp": b'<PickedPoints><point x="0" y="1" z="2"/></PickedPoints>',
    "bad_num.pp": b'<PickedPoints><point name="nasion" x="0" y="one" z="2"/></PickedPoints>',
    "broken.pp": b'<PickedPoints><point name="nasion" x="0" y="1" z="2"></PickedPoints>',
    "missing_coord.json": b'{"landmarks": {"menton": [0, 1], "nasion": [0, 1, 0]}}',
    "string_coord.json": b'{"landmarks": {"menton": [0, "1", 2], "nasion": [0, 1, 0]}}',
    "bool_coord.json": b'{"landmarks": {"menton": [0, true, 2], "nasion": [0, 1, 0]}}',
    "null_value.json": b'{"landmarks": {"menton": null}}',
    "no_landmarks.json": b'{"format": "autobones-landmarks/1", "mesh": "x.obj"}',
    "empty_landmarks.json": b'{"format": "autobones-landmarks/1", "landmarks": {}}',
    "wrong_format.json": b'{"format": "something/2", "landmarks": {"menton": [0, 1, 2]}}',
    "scalar.json": b"42",
    "string.json": b'"landmarks"',
    "identical.json": b'{"landmarks": {"menton": [1, 2, 3], "nasion": [1, 2, 3], "pronasale": [1, 2, 3]}}',
    "on_a_line.json": b'{"landmarks": {"menton": [0, -7, 0], "nasion": [0, 3, 0], "pronasale": [0, 1, 0]}}',
    "all_null.ljson": json.dumps({"landmarks": {"points": [None] * 68}}).encode(),
    "truncated.json": b'{"format": "autobones-landmarks/1", "landmarks": {"menton": [0, 1,',
}


@pytest.mark.parametrize("name", sorted(HOSTILE))
def test_hostile_files_give_one_line_errors(name, tmp_path):
    path = tmp_path / name
    path.write_bytes(HOSTILE[name])
    msg = _error(read_landmarks, path)
    assert name in msg


def test_hostile_messages_say_what_is_wrong(tmp_path):
    def msg(name):
        path = tmp_path / name
        path.write_bytes(HOSTILE[name])
        return _error(read_landmarks, path)

    assert "67 points" in msg("list67.json") and "68" in msg("list67.json")
    assert "69 points" in msg("list69.ljson")
    assert "empty" in msg("empty.json")
    assert "2-D" in msg("list2d.json") and "2-D" in msg("pts2d.pts")
    assert "entity" in msg("laughs.pp").lower()
    assert "no <point" in msg("no_points.pp")
    assert "no y coordinate" in msg("no_y.pp")
    assert "67 points" in msg("pts_count.pts") or "n_points: 68" in msg("pts_count.pts")
    assert "not valid JSON" in msg("truncated.json")
    assert "something/2" in msg("wrong_format.json")
    assert "same point" in msg("identical.json")
    assert "one line" in msg("on_a_line.json")


def test_missing_file(tmp_path):
    assert "no such" in _error(read_landmarks, tmp_path / "absent.json")


# --- fuzzing -------------------------------------------------------------------------------------

def _check_result(lm):
    assert isinstance(lm, dict) and lm
    assert list(lm) == [n for n in NAMES if n in lm]
    for p in lm.values():
        assert isinstance(p, np.ndarray) and p.shape == (3,) and p.dtype == np.float64
        assert np.isfinite(p).all()


def _read_fuzzed(tmp_path_factory, payload, suffix):
    path = tmp_path_factory.mktemp("fuzz") / f"f{suffix}"
    path.write_bytes(payload)
    try:
        lm = read_landmarks(path)
    except AutobonesError as exc:
        assert "\n" not in str(exc)
        return None
    _check_result(lm)
    return lm


FUZZ = settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])


@FUZZ
@given(payload=st.binary(max_size=2000), suffix=st.sampled_from([".json", ".pp", ".pts", ".ljson", ""]))
def test_fuzz_random_bytes(tmp_path_factory, payload, suffix):
    _read_fuzzed(tmp_path_factory, payload, suffix)


numbers = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-10**30, 10**30))
triples = st.lists(numbers, min_size=0, max_size=4)
names = st.one_of(st.sampled_from(NAMES), st.text(max_size=12))
json_values = st.recursive(
    st.none() | st.booleans() | numbers | st.text(max_size=8),
    lambda kids: st.lists(kids, max_size=5) | st.dictionaries(st.text(max_size=8), kids, max_size=5),
    max_leaves=20)
documents = st.one_of(
    json_values,
    st.fixed_dictionaries({"format": st.sampled_from(["autobones-landmarks/1", "x"]),
                           "landmarks": st.dictionaries(names, st.one_of(triples, json_values), max_size=14)}),
    st.fixed_dictionaries({"landmarks": st.dictionaries(st.sampled_from(NAMES), triples, min_size=3, max_size=20)}),
    st.lists(st.one_of(st.none(), triples), min_size=66, max_size=70),
    st.fixed_dictionaries({"landmarks": st.fixed_dictionaries(
        {"points": st.lists(st.lists(st.floats(-1e3, 1e3), min_size=3, max_size=3), min_size=68, max_size=68)})}),
)


@FUZZ
@given(doc=documents, suffix=st.sampled_from([".json", ".ljson", ".txt"]))
def test_fuzz_random_json(tmp_path_factory, doc, suffix):
    payload = json.dumps(doc).encode()  # NaN and Infinity as JS literals, which json accepts
    _read_fuzzed(tmp_path_factory, payload, suffix)


@FUZZ
@given(points=st.lists(st.fixed_dictionaries({
    "name": names, "x": st.one_of(numbers.map(repr), st.text(max_size=5)),
    "y": numbers.map(repr), "z": numbers.map(repr), "active": st.sampled_from(["0", "1"])}), max_size=12))
def test_fuzz_picked_points(tmp_path_factory, points):
    from xml.sax.saxutils import quoteattr

    body = "<PickedPoints>" + "".join(
        "<point " + " ".join(f"{k}={quoteattr(str(v))}" for k, v in p.items()) + "/>" for p in points) + "</PickedPoints>"
    _read_fuzzed(tmp_path_factory, body.encode("utf-8", "surrogatepass"), ".pp")


def test_fuzz_valid_ibug_lists_always_read(tmp_path):
    rng = np.random.default_rng(7)
    for k in range(20):
        P = rng.normal(size=(68, 3)) * rng.uniform(1e-3, 1e3)
        path = tmp_path / f"{k}.json"
        path.write_text(json.dumps(P.tolist()))
        lm = read_landmarks(path)
        _check_result(lm)
        assert len(lm) == 27


def test_huge_finite_coordinates_do_not_overflow(tmp_path, ict):
    pp = tmp_path / "huge.pp"
    pp.write_text('<PickedPoints><point name="vertex" x="0" y="0" z="1.3407807929942597e+154"/>'
                  '<point name="opisthocranion" x="0" y="0" z="0"/>'
                  '<point name="menton" x="1e308" y="-1e308" z="1e308"/></PickedPoints>')
    # relative to 1e308 the first two coincide: an error, not an overflow
    assert "vertex = opisthocranion" in _error(read_landmarks, pp)
    pp.write_text('<PickedPoints><point name="vertex" x="0" y="0" z="1e307"/>'
                  '<point name="opisthocranion" x="0" y="0" z="-1e307"/>'
                  '<point name="menton" x="1e308" y="-1e308" z="1e308"/></PickedPoints>')
    _check_result(read_landmarks(pp))
    V, F = ict[0], ict[1]
    far = {n: p * 1e305 for n, p in ict[3].items()}
    assert "far from the mesh" in _error(validate_landmarks, far, V, F)


def test_quoted_file_values_stay_short_and_on_one_line():
    from autobones.io.landmark_checks import quoted, shorten

    assert shorten("a \n\t b") == "a b"
    long = "x" * 30 + "\n" + "y" * 80
    assert len(shorten(long)) == 60 and shorten(long).endswith("...") and "\n" not in shorten(long)
    assert "\n" not in quoted(long) and len(quoted(long)) <= 42 and quoted("nasion") == "'nasion'"
    assert quoted(12345678901234567890 ** 3).endswith("...")


def test_name_index_is_the_position_in_names():
    from autobones.io.landmark_names import NAME_INDEX

    assert [NAMES[i] for i in NAME_INDEX.values()] == list(NAME_INDEX) == list(NAMES)


def test_a_vertex_no_triangle_uses_is_no_part_of_the_head(tmp_path):
    """An exporter's leftover vertex far away made the head 20 times its size: a whole head's landmarks were
    refused as "gathered within 0.0086 head sizes", and the automatic landmarks' pictures framed it (no face)."""
    from autobones.io.landmark_checks import landmark_problems

    p = data("menpo3d/james.obj")
    V, F = load_mesh(p)
    lm = read_landmarks(p.with_suffix(".landmarks.json"))
    far = np.vstack([V, V.mean(axis=0) + 20 * np.ptp(V, axis=0)])
    assert len(validate_landmarks(lm, far, F)) == len(lm)
    assert not landmark_problems(lm, far, F)["set"]


@pytest.mark.parametrize("factor", [2.54, 1 / 25.0, 25.0])
def test_no_units_hint_for_a_scale_that_is_not_a_power_of_ten(factor):
    """Landmarks in centimetres on a mesh in inches (2.54) were called "millimetres for a mesh in centimetres":
    scaled by 0.1 they came near, not onto, the surface. A hint is given only where the scale puts them on it."""
    p = data("menpo3d/james.obj")
    V, F = load_mesh(p)
    lm = read_landmarks(p.with_suffix(".landmarks.json"))
    msg = _error(validate_landmarks, {n: np.asarray(x) * factor for n, x in lm.items()}, V, F)
    assert "wrong units" not in msg, msg
    msg = _error(validate_landmarks, {n: np.asarray(x) * 0.001 for n, x in lm.items()}, V, F)
    assert "metres for a mesh in millimetres" in msg


@pytest.mark.parametrize("far", [1e6, 1e20])
def test_one_landmark_mistyped_far_away_is_named(far):
    """One coordinate typed 1e20 made every other pair "at the same point" (the tolerance scaled with the
    largest coordinate); the landmark is named instead. A head's farthest landmark lies under 5 median
    distances out (the 31 landmark files of the shared data and the tests)."""
    p = data("menpo3d/james.obj")
    lm = read_landmarks(p.with_suffix(".landmarks.json"))
    bad = {**lm, "pronasale": np.full(3, far)}
    msg = _error(validate_landmarks, bad)
    assert "pronasale lies" in msg and "same point" not in msg, msg
    assert len(validate_landmarks(lm)) == len(lm)
