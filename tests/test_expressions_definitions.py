"""expressions.definitions (the data file's model parameters, AU keys), rig_inputs, face_unit."""
import copy
from types import SimpleNamespace

import numpy as np
import pytest

from autobones.errors import AutobonesError
from autobones.expressions.definitions import (MODEL_DEFAULTS, load_expressions, model_parameters, muscle_types,
                                               parse_au_key)
from autobones.expressions.model import face_unit
from autobones.expressions.morph_targets import target_keys
from autobones.expressions.rig_inputs import rig_inputs

DOC = load_expressions()


def test_the_file_overrides_the_defaults_and_missing_optional_keys_fall_back():
    before = copy.deepcopy(DOC)
    p = model_parameters(DOC)
    assert DOC == before                                       # the definitions are not changed
    for key, value in DOC["model"].items():
        if isinstance(value, dict):
            assert all(p[key][k] == v for k, v in value.items()), key
        else:
            assert p[key] == value, key
    assert p["skull"]["blend"] == MODEL_DEFAULTS["skull"]["blend"]     # not in the shipped file
    old = copy.deepcopy(DOC)                                    # an older user file without some keys
    for key in ("cheek_spread", "jaw_glide", "mouth_parts"):
        del old["model"][key]
    del old["model"]["eyelids"]["smoothing"]
    q = model_parameters(old)
    assert q["cheek_spread"] == 0.0 and q["jaw_glide"] == [0.0, 0.0]
    assert q["mouth_parts"] == MODEL_DEFAULTS["mouth_parts"]
    assert q["eyelids"]["smoothing"] == q["smoothing"]         # the lids fall back to the muscles' smoothing
    assert q["eyelids"]["width_margin"] == DOC["model"]["eyelids"]["width_margin"]


@pytest.mark.parametrize("path, name", [(("rest_weight",), "model.rest_weight"),
                                        (("lips", "cut_width"), "model.lips.cut_width"),
                                        (("eyelids",), "model.eyelids")])
def test_a_missing_required_key_is_named(path, name):
    doc = copy.deepcopy(DOC)
    where = doc["model"]
    for k in path[:-1]:
        where = where[k]
    del where[path[-1]]
    with pytest.raises(AutobonesError, match=name.replace(".", r"\.")):
        model_parameters(doc)


def test_muscle_types_fill_the_optional_keys():
    types = muscle_types({"muscle_types": {"a": {"wire": [0.3, 1.1], "dropoff": 2.0}, "b": {"shortening": 0.3,
                                                                                            "slide": True}}})
    assert types["a"] == {"wire": [0.3, 1.1], "dropoff": 2.0, "shortening": 0.0, "slide": False, "galea": None,
                          "sphincter": None, "sheet": None}
    assert types["b"]["shortening"] == 0.3 and types["b"]["slide"] is True
    assert set(muscle_types(DOC)) == set(DOC["muscle_types"])


@pytest.mark.parametrize("key, out", [(12, ("12", "12", None)), ("AU12", ("12", "12", None)),
                                      (" au12l ", ("12L", "12", "l")), ("6R", ("6R", "6", "r")),
                                      ("AU", ("", "", None))])
def test_au_keys(key, out):
    assert parse_au_key(key) == out


def test_morph_target_keys_parse_au_keys_the_same_way():
    assert target_keys(["6", "12"], [" au12l", 6, "AU6R"]) == ["12L", "6", "6R"]
    with pytest.raises(AutobonesError):
        target_keys(["6", "12"], ["13L"])


def test_rig_inputs_reads_the_rig_and_defaults_to_empty():
    rig = SimpleNamespace(muscles=[{"name": "m"}], landmarks={"stomion": [0, 0, 0]},
                          field_labels={"region": ["a"]})
    got = rig_inputs(rig)
    assert got.muscles == [{"name": "m"}] and got.landmarks == {"stomion": [0, 0, 0]}
    assert got.field_labels == {"region": ["a"]}
    assert rig_inputs(SimpleNamespace()) == ([], {}, {})


def test_face_unit_is_the_exocanthion_distance_else_the_eyes():
    L = {"exocanthion_l": np.array([0.5, 0.0, 0.0]), "exocanthion_r": np.array([-0.5, 0.0, 0.0])}
    eyes = {"l": np.array([0.3, 0.0, 0.0]), "r": np.array([-0.3, 0.0, 0.0])}
    assert face_unit(L, eyes) == 1.0
    assert face_unit({}, eyes) == pytest.approx(1.48 * 0.6)
    with pytest.raises(AutobonesError):
        face_unit({}, {"l": eyes["l"]})
