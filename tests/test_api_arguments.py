"""The Python API's wrong arguments (issue #33 item 8): every case of ``bad_inputs.api_cases`` raises
AutobonesError, a ValueError, naming the argument; never a TypeError, IndexError, AttributeError or
UFuncTypeError from inside, and never a NaN result."""
import copy
import json
import types

import numpy as np
import pytest

import bad_inputs
from shared_data import data

CASES = bad_inputs.api_cases()


@pytest.fixture(scope="module")
def ctx():
    import autobones
    from autobones.generic_rig import expressions_path

    V, F = bad_inputs.robot()
    lm = json.loads(bad_inputs.ROBOT_LANDMARKS.read_text())["landmarks"]
    rig = autobones.transfer(data(bad_inputs.ROBOT), landmarks=str(bad_inputs.ROBOT_LANDMARKS))
    defs = json.loads(open(expressions_path()).read())
    return types.SimpleNamespace(V=V, F=F, lm=lm, rig=rig, defs=defs)


def test_autobones_error_is_a_value_error():
    from autobones import AutobonesError

    assert issubclass(AutobonesError, ValueError)


@pytest.mark.parametrize("name", sorted(CASES))
def test_api_case_raises_autobones_error_naming_the_argument(ctx, name):
    from autobones import AutobonesError

    call, needle, why = CASES[name]
    c = types.SimpleNamespace(**{**vars(ctx), "defs": copy.deepcopy(ctx.defs)})
    with pytest.raises(AutobonesError) as info:
        call(c)
    assert type(info.value) is AutobonesError or issubclass(type(info.value), AutobonesError)
    assert needle in str(info.value) and "\n" not in str(info.value), (name, str(info.value))
    assert why


def test_int_vertices_are_taken_as_numbers(ctx):
    """detect_frame on int arrays (was: UFuncTypeError): the same frame as the float64 copy."""
    import autobones

    Vi = np.round(ctx.V * 1000).astype(np.int64)
    a = autobones.detect_frame(Vi, ctx.F.astype(np.int32))
    b = autobones.detect_frame(Vi.astype(np.float64), ctx.F)
    assert np.allclose(a.rotation, b.rotation) and a.size == b.size


def test_whole_float_faces_and_in_range_controls_still_work(ctx):
    """What is right is not refused: faces given as whole floats, an AU at 2 (extrapolated), the
    head turned 30 degrees: finite results."""
    import autobones

    V, F = autobones.load_mesh(data(bad_inputs.ROBOT))
    assert autobones.detect_frame(V, F.astype(np.float64)).size > 0
    P = ctx.rig.pose(au={12: 2.0}, head_deg=[0, 30, 0], gaze=(10, 5))
    assert np.isfinite(P).all() and np.abs(P - ctx.rig.vertices).max() > 0


def test_arrays_out_of_range_are_not_called_a_corrupt_file(tmp_path):
    """A (V, F) pair with a face index past its vertices names the range, and says "file is corrupt"
    only of a file that reads so."""
    import autobones
    from autobones import AutobonesError

    with pytest.raises(AutobonesError) as info:
        autobones.place(([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 5]] * 4))
    assert "out of range (0..2)" in str(info.value) and "file" not in str(info.value)
    obj = tmp_path / "bad.obj"
    obj.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n" + "f 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 9\n")
    with pytest.raises(AutobonesError) as info:
        autobones.place(str(obj))
    assert "bad.obj" in str(info.value)
