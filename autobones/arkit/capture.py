"""Read a face-capture recording: the CSV Live Link Face (Epic Games' iPhone app) writes.

Goes beyond the seeds (issue #15). The layout (Epic's documentation of Live Link Face and
Unreal's ``EARFaceBlendShape``): a header row ``Timecode, BlendShapeCount``, then one column per
ARKit shape with the name capitalised (``EyeBlinkLeft`` ... ``TongueOut``), then the head and
eye angles ``HeadYaw, HeadPitch, HeadRoll, LeftEyeYaw, LeftEyePitch, LeftEyeRoll,
RightEyeYaw, RightEyePitch, RightEyeRoll`` (radians); one row per frame. ``Timecode`` is
``HH:MM:SS:FF.fff`` (SMPTE with a fractional frame, at the recording's frame rate, which the
file does not state: ``fps``); a plain number is taken as a frame number at that rate.

Strict on what it returns: a row with a missing or non-numeric field, a column it does not
know, a shape column missing, or a time that does not increase is an AutobonesError naming
the file, line and column.
"""
from __future__ import annotations

import csv
import io
import math
import os
import re
from dataclasses import dataclass

import numpy as np

from ..errors import AutobonesError, counted
from ..io.files import read_text, shown
from .names import ARKIT_NAMES, CAPTURE_ANGLES, capture_column

# frames a take may hold: 55 min at 60 fps. A row costs ~1.5 kB while read (61 fields as str): 200k
# frames peak at ~0.4 GB and ~5 s, where a 1M-row file took 5 GB
MAX_FRAMES = 200_000
_TIMECODE = re.compile(r"^\s*(\d+):(\d{1,2}):(\d{1,2})[:;](\d+(?:\.\d*)?)\s*$")


@dataclass
class Capture:
    """A recording: ``times`` (f,) seconds from the first frame, strictly increasing;
    ``weights`` dict ARKit name -> (f,) float; ``angles`` dict column -> (f,) radians
    (the :data:`CAPTURE_ANGLES` present); ``source`` the file name."""

    times: np.ndarray
    weights: dict
    angles: dict
    source: str



# What a take may hold (issue #33 item 6: weights of 1e308 became infinite animation keys). ARKit's
# shape weights run 0..1; one unit of slack either way keeps a retargeted or exaggerated take. The
# angles are radians: at most a full turn either way.
WEIGHT_RANGE = (-1.0, 2.0)
ANGLE_RANGE = (-2 * math.pi, 2 * math.pi)

def parse_time(text, fps):
    """Seconds of a Live Link Face timecode ``HH:MM:SS:FF.fff`` (or a plain frame number) at ``fps``."""
    m = _TIMECODE.match(text)
    if m:
        h, mi, s, f = int(m[1]), int(m[2]), int(m[3]), float(m[4])
        return 3600 * h + 60 * mi + s + f / fps
    v = float(text)  # ValueError for anything else
    if not math.isfinite(v):
        raise ValueError(text)
    return v / fps


def read_capture(path, fps=60.0):
    """The :class:`Capture` in a Live Link Face CSV file.

    Parameters
    ----------
    path : str or os.PathLike
    fps : float
        Frame rate of the timecode's frame field (Live Link Face records at 60 by default).
    """
    path = os.fspath(path)
    if not fps > 0 or not math.isfinite(fps):
        raise AutobonesError(f"--fps {fps}: the frame rate must be a positive number")
    known = {capture_column(n): n for n in ARKIT_NAMES}
    text = read_text(path, "capture", encoding="utf-8-sig")  # a regular file under its size limit
    rows = []
    try:
        for row in csv.reader(io.StringIO(text, newline="")):
            if len(rows) > MAX_FRAMES:  # the header and MAX_FRAMES frames at most: memory grows by the row
                raise AutobonesError(f"{shown(path)}: more than {MAX_FRAMES} frames (55 min at 60 fps); split "
                                     "the take into shorter ones")
            if any(c.strip() for c in row):
                rows.append(row)
    except csv.Error as exc:
        raise AutobonesError(f"{shown(path)}: cannot read it as a CSV file ({exc})") from None
    rows = [r for r in rows if any(c.strip() for c in r)]
    if not rows:
        raise AutobonesError(f"{path}: empty file; expected Live Link Face's CSV (Timecode, BlendShapeCount, "
                             "EyeBlinkLeft, ...)")
    header = [c.strip() for c in rows[0]]
    if header[:2] != ["Timecode", "BlendShapeCount"]:
        raise AutobonesError(f"{path}: line 1: the header starts {', '.join(header[:2])!r}, expected "
                             "'Timecode, BlendShapeCount' (Live Link Face's CSV)")
    cols = header[2:]
    unknown = [c for c in cols if c not in known and c not in CAPTURE_ANGLES]
    if unknown:
        raise AutobonesError(f"{path}: line 1: unknown column {unknown[0]!r}; expected the 52 ARKit shapes "
                             "(EyeBlinkLeft ... TongueOut) and HeadYaw ... RightEyeRoll")
    dup = sorted({c for c in cols if cols.count(c) > 1})
    if dup:
        raise AutobonesError(f"{path}: line 1: column {dup[0]!r} appears twice")
    missing = [capture_column(n) for n in ARKIT_NAMES if capture_column(n) not in cols]
    if missing:
        raise AutobonesError(f"{path}: line 1: no column {missing[0]!r} ({counted(len(missing), 'ARKit shape')} missing)")
    if len(rows) < 2:
        raise AutobonesError(f"{path}: no frames after the header")
    width = len(header)
    times, values = [], np.empty((len(rows) - 1, len(cols)))
    for i, row in enumerate(rows[1:]):
        line = i + 2
        if len(row) != width:
            raise AutobonesError(f"{path}: line {line}: {counted(len(row), 'field')}, the header has {width}")
        try:
            t = parse_time(row[0], fps)
        except ValueError:
            raise AutobonesError(f"{path}: line {line}: timecode {row[0]!r} is not HH:MM:SS:FF.fff") from None
        if times and not t > times[-1]:
            raise AutobonesError(f"{path}: line {line}: time {row[0]!r} does not come after the previous "
                                 "frame's (the rows must be in increasing time)")
        times.append(t)
        for j, text in enumerate(row[2:]):
            try:
                v = float(text)
            except ValueError:
                v = float("nan")
            if not math.isfinite(v):
                raise AutobonesError(f"{path}: line {line}: column {cols[j]}: {text!r} is not a finite number")
            low, high = ANGLE_RANGE if cols[j] in CAPTURE_ANGLES else WEIGHT_RANGE
            if not low <= v <= high:  # 1e308 is finite, and infinite in the glb's float32 keys
                raise AutobonesError(f"{path}: line {line}: column {cols[j]}: {text[:24]!r} is outside [{low:g}, "
                                     f"{high:g}] ({'radians' if cols[j] in CAPTURE_ANGLES else 'a shape weight'})")
            values[i, j] = v
    T = np.asarray(times)
    return Capture(times=T - T[0], source=os.path.basename(path),
                   weights={known[c]: values[:, j] for j, c in enumerate(cols) if c in known},
                   angles={c: values[:, j] for j, c in enumerate(cols) if c in CAPTURE_ANGLES})
