"""The AU <-> ARKit table in generic_rig/expressions.json (issue #16 item 3) and its loader."""
import copy

import pytest

from autobones.arkit.names import ARKIT_NAMES, ict_names
from autobones.errors import AutobonesError
from autobones.expressions.definitions import au_arkit_table, load_expressions

# the pairs issue #16 item 3 lists: ARKit stem -> the AUs it stands for
ISSUE_16 = {"browInnerUp": [1], "browOuterUp": [2], "browDown": [4], "eyeWide": [5], "cheekSquint": [6],
            "eyeSquint": [7], "noseSneer": [9], "mouthUpperUp": [10], "mouthSmile": [12], "mouthDimple": [14],
            "mouthFrown": [15], "mouthLowerDown": [16], "mouthShrugLower": [17], "mouthPucker": [18],
            "mouthStretch": [20], "mouthFunnel": [22], "mouthPress": [24], "jawOpen": [26, 27], "eyeBlink": [43, 45]}


def to_arkit(ict):
    """ICT's ``_L`` / ``_R`` -> ARKit's ``Left`` / ``Right``; a shape ICT splits that ARKit keeps whole
    (browInnerUp) maps to the whole one."""
    for suffix, side in (("_L", "Left"), ("_R", "Right")):
        if ict.endswith(suffix):
            stem = ict[: -len(suffix)]
            return stem + side if stem + side in ARKIT_NAMES else stem
    return ict


def test_packaged_definitions_load_with_the_table():
    doc = load_expressions()
    for key in ("model", "muscle_types", "action_units", "expressions", "au_arkit"):
        assert key in doc
    rows = au_arkit_table(doc)
    assert rows == au_arkit_table()  # None: the packaged file
    assert len(rows) == len(ISSUE_16)


def test_every_name_is_an_arkit_name_and_the_ict_names_agree():
    for row in au_arkit_table():
        mapped = [to_arkit(n) for n in row["ict"]]
        assert all(n in ARKIT_NAMES for n in mapped), row
        assert sorted(set(mapped)) == sorted(row["arkit"]), row
        # the same ICT halves the ARKit shape builder sums
        assert sorted(n for a in row["arkit"] for n in ict_names(a)) == sorted(row["ict"]), row


def test_every_au_the_issue_lists_is_there_with_its_shape():
    rows = au_arkit_table()
    got = {}
    for row in rows:
        stems = {to_arkit(n).removesuffix("Left").removesuffix("Right") for n in row["ict"]}
        assert len(stems) == 1, row
        got[stems.pop()] = row["au"]
    assert got == ISSUE_16
    aus = [a for row in rows for a in row["au"]]
    assert len(aus) == len(set(aus))  # each AU in one row only


def test_names_and_sources():
    doc = load_expressions()
    for row in au_arkit_table(doc):
        assert len(row["facs"]) == len(row["au"]) and all(row["facs"])
        # the AUs the model defines carry the same FACS name
        for a, name in zip(row["au"], row["facs"]):
            if str(a) in doc["action_units"]:
                assert doc["action_units"][str(a)]["name"] == name
        assert "issue #16" in row["source"] and "Ekman, Friesen & Hager 2002" in row["source"]
        assert all(f"BlendShapeLocation.{a}" in row["source"] for a in row["arkit"])


def test_bad_tables_raise():
    doc = load_expressions()
    missing = {k: v for k, v in doc.items() if k != "au_arkit"}
    with pytest.raises(AutobonesError, match="au_arkit"):
        au_arkit_table(missing)
    bad = copy.deepcopy(doc)
    del bad["au_arkit"]["rows"][3]["ict"]
    with pytest.raises(AutobonesError, match="row 3"):
        au_arkit_table(bad)
    bad = copy.deepcopy(doc)
    bad["au_arkit"]["rows"][0]["facs"] = []
    with pytest.raises(AutobonesError, match="row 0"):
        au_arkit_table(bad)
