"""The public entry points whose own modules do not check their arguments (issue #33 item 8).

``place``, ``transfer``, ``transfer_attributes`` and ``detect_frame`` live in modules other developers
own (``placement/``, ``rig_transfer/``, ``orient.py``); their arguments are checked here, at the entry point
``autobones/__init__.py`` exports, with :mod:`autobones.arguments`, and the call then goes on
unchanged. A wrong type is an :class:`AutobonesError` naming the argument (``rig=42``: "rig:
expected ..."), never an ``AttributeError`` or ``UFuncTypeError`` from inside.
"""
from __future__ import annotations

import functools
import numbers
import os

from .arguments import float_array, index_array
from .errors import AutobonesError, counted
from .orient import detect_frame as _detect_frame
from .placement.pipeline import place as _place
from .rig_transfer.fields import transfer_attributes as _transfer_attributes
from .rig_transfer.pipeline import transfer as _transfer


def _check_rig_argument(rig):
    from .labelled_rig import LabelledRig

    if rig is not None and not isinstance(rig, (str, os.PathLike, LabelledRig)):
        raise AutobonesError(f"rig: expected a rig folder (path), a LabelledRig or None (the built-in rig), "
                             f"not {type(rig).__name__}")


def _check_axis(value, name):
    if value is not None and not isinstance(value, str):
        raise AutobonesError(f"{name}: expected an axis such as '+y' or None, not {type(value).__name__}")


def _check_landmarks_argument(landmarks, name, optional=True):
    from collections.abc import Mapping

    if landmarks is None and optional:
        return
    if not isinstance(landmarks, (str, bytes, os.PathLike, Mapping)):
        raise AutobonesError(f"{name}: expected a landmark file path or a dict name -> (x, y, z), not "
                             f"{type(landmarks).__name__}")


@functools.wraps(_transfer)
def transfer(head, landmarks=None, rig=None, up=None, front=None, control_points=400, *args, **kwargs):
    _check_landmarks_argument(landmarks, "landmarks")
    _check_rig_argument(rig)
    _check_axis(up, "up")
    _check_axis(front, "front")
    if isinstance(control_points, bool) or not isinstance(control_points, numbers.Integral) or control_points < 1:
        raise AutobonesError(f"control_points: expected a whole number >= 1, not {control_points!r:.40}")
    return _transfer(head, landmarks, rig, up, front, int(control_points), *args, **kwargs)


@functools.wraps(_place)
def place(mesh=None, density="medium", up=None, front=None, random_state=0, landmarks=None, rig=None):
    _check_landmarks_argument(landmarks, "landmarks")
    _check_rig_argument(rig)
    if rig is not None and landmarks is None:
        # the generic rig is used only to transfer the neck, head, jaw and eyes from landmarks: taken
        # silently, a rig given alone looked used
        raise AutobonesError("rig= (--rig) is the generic rig place transfers from with landmarks=; give "
                             "landmarks= (--landmarks FILE) too, or leave the rig out")
    _check_axis(up, "up")
    _check_axis(front, "front")
    return _place(mesh, density, up, front, random_state, landmarks, rig)


@functools.wraps(_transfer_attributes)
def transfer_attributes(source_mesh, target_mesh, fields, source_landmarks, target_landmarks, *args, **kwargs):
    from collections.abc import Mapping

    if not isinstance(fields, Mapping):
        raise AutobonesError(f"fields: expected a dict name -> (n,) or (n, k) array, not {type(fields).__name__}")
    _check_landmarks_argument(source_landmarks, "source_landmarks", optional=False)
    _check_landmarks_argument(target_landmarks, "target_landmarks", optional=False)
    return _transfer_attributes(source_mesh, target_mesh, fields, source_landmarks, target_landmarks, *args, **kwargs)


@functools.wraps(_detect_frame)
def detect_frame(V, F, up=None, front=None, *args, **kwargs):
    # int vertices (a UFuncTypeError inside) become float64; fractional or out-of-range faces are refused
    V = float_array(V, "V", (None, 3))
    if len(V) < 4:
        raise AutobonesError(f"V: {counted(len(V), 'vertex', 'vertices')}; a head mesh has more")
    F = index_array(F, "F", (None, 3), len(V))
    _check_axis(up, "up")
    _check_axis(front, "front")
    return _detect_frame(V, F, up, front, *args, **kwargs)
