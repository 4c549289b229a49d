"""Argument checks of the public API (issue #33 item 8) and the writers' last line of defence.

The functions ``autobones/__init__.py`` exports check what they are given here, before any work, so
a wrong type, shape or value is an :class:`AutobonesError` (a ``ValueError``) naming the argument,
not a ``TypeError``, ``IndexError`` or ``UFuncTypeError`` from deep inside, a silently truncated
array (fractional faces cut by ``astype``), or NaN in the result. Meshes are checked by
``io/mesh.py``'s ``check_mesh`` (ragged and fractional faces included); landmarks by
``io/landmarks.py``'s ``resolve_landmarks``.

:func:`finite_output` is what every writer (glb, OBJ, USD) calls on the numbers it is about to
write: nothing non-finite is ever written, whatever produced it.
"""
from __future__ import annotations

import math
import numbers
import os

import numpy as np

from .errors import AutobonesError, counted


def path_argument(value, name):
    """``value`` as a str path; AutobonesError naming ``name`` for None, a number, anything not a path."""
    if not isinstance(value, (str, bytes, os.PathLike)):
        raise AutobonesError(f"{name}: expected a file path (str or os.PathLike), not {type(value).__name__}")
    return os.fsdecode(os.fspath(value))


def real(value, name, low=-math.inf, high=math.inf):
    """``value`` as a finite float in ``[low, high]``; AutobonesError naming ``name`` otherwise."""
    if isinstance(value, bool) or not isinstance(value, (numbers.Real, np.floating, np.integer)):
        raise AutobonesError(f"{name}: expected a number, not {type(value).__name__} {str(value)[:20]!r}")
    x = float(value)
    if not math.isfinite(x):
        raise AutobonesError(f"{name}: {x} is not a finite number")
    if not low <= x <= high:
        raise AutobonesError(f"{name}: {x:g} is outside [{low:g}, {high:g}]")
    return x


def float_array(value, name, shape):
    """``value`` as a finite float64 array of ``shape`` (None: any length on that axis);
    AutobonesError naming ``name`` for another type, shape or a NaN / infinite entry."""
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise AutobonesError(f"{name}: expected an array of numbers of shape {_shape(shape)}, not "
                             f"{type(value).__name__}") from None
    if a.ndim != len(shape) or any(s is not None and s != t for s, t in zip(shape, a.shape)):
        raise AutobonesError(f"{name}: expected shape {_shape(shape)}, got {a.shape}")
    bad = ~np.isfinite(a)
    if bad.any():
        raise AutobonesError(f"{name}: {counted(int(bad.sum()), 'NaN or infinite value')}")
    return a


def index_array(value, name, shape, count):
    """``value`` as an int64 array of ``shape`` with entries in ``[0, count)``: integer dtype, or
    floats that are whole (1.5 is refused, never cut to 1)."""
    a = np.asarray(value)
    if a.dtype.kind == "f" and np.isfinite(a).all() and (a == np.round(a)).all():
        a = a.astype(np.int64)
    if a.dtype.kind not in "iu":
        raise AutobonesError(f"{name}: expected whole indices, got {a.dtype} values")
    if a.ndim != len(shape) or any(s is not None and s != t for s, t in zip(shape, a.shape)):
        raise AutobonesError(f"{name}: expected shape {_shape(shape)}, got {a.shape}")
    if a.size and (a.min() < 0 or a.max() >= count):
        raise AutobonesError(f"{name}: indices must be in [0, {count - 1}], got {int(a.min())}..{int(a.max())}")
    return a.astype(np.int64)


def _shape(shape):
    return "(" + ", ".join("n" if s is None else str(s) for s in shape) + ("," if len(shape) == 1 else "") + ")"


def finite_output(path, what, *arrays):
    """AutobonesError unless every array is finite: the last check before ``path`` is written
    (``what``: the file's role). Whatever upstream let a NaN or an infinity through (an AU at 1e308,
    a capture weight of 1e308), the file is not written and the message says how many."""
    for name, a in arrays:
        a = np.asarray(a)
        if a.dtype.kind in "fc" and a.size and not np.isfinite(a).all():
            bad = int((~np.isfinite(a)).sum())
            raise AutobonesError(f"{os.fspath(path) if path else what}: not written: {counted(bad, 'NaN or infinite value')} in "
                                 f"the {name} (out-of-range inputs); {what} is never written with them")


# Out-of-range pose controls are refused, not posed (issue #33 item 6: an AU at 1e308 put every vertex
# at infinity). 1 is a unit's full action and "larger extrapolates", so up to 10 times it is allowed;
# angles (gaze, head, neck) within half a turn either way, the jaw within a right angle.
MAX_INTENSITY = 10.0
MAX_ANGLE = 180.0


def intensity_mixes(au, expression, muscles, eyelids):
    """The intensity dicts of ``ExpressionModel.parameters`` (an expression name is ``{name: 1}``), each
    value a finite number within ``±MAX_INTENSITY``; AutobonesError naming the control and key otherwise."""
    from collections.abc import Mapping

    if isinstance(expression, str):
        expression = {expression: 1.0}
    out = []
    for name, mix in (("au", au), ("expression", expression), ("muscles", muscles), ("eyelids", eyelids)):
        if mix is None:
            out.append(None)
            continue
        if not isinstance(mix, Mapping):
            raise AutobonesError(f"{name}: expected a dict (key -> intensity), not {type(mix).__name__}")
        out.append({k: real(v, f"{name} {k}", -MAX_INTENSITY, MAX_INTENSITY) for k, v in mix.items()})
    return out


def pose_angles(gaze, look_at, head_deg, neck_deg):
    """``gaze`` (2,), ``look_at`` (3,), ``head_deg`` and ``neck_deg`` (3,) as finite float arrays (None
    kept), the angles within ``±MAX_ANGLE`` degrees; AutobonesError naming the argument otherwise
    (``head_deg=[inf, 0, 0]`` returned NaN vertices)."""
    out = []
    for name, value, n in (("gaze", gaze, 2), ("look_at", look_at, 3), ("head_deg", head_deg, 3),
                           ("neck_deg", neck_deg, 3)):
        a = None if value is None else float_array(value, name, (n,))
        if a is not None and name != "look_at" and np.abs(a).max() > MAX_ANGLE:
            raise AutobonesError(f"{name}: {a.tolist()} degrees, outside [-{MAX_ANGLE:g}, {MAX_ANGLE:g}]")
        out.append(a)
    return out
