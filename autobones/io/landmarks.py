"""Read and write landmark files: the 44-name contract of ``spec/landmarks.md``.

Orvalho, Zacur & Susin 2008 (§2) tag the generic rig with 44 anthropometric landmarks
(lambda) and (§3) the face model with any subset of them (phi, "positioned manually by the
artist"); the transfer (§3.1) fits a thin-plate spline between the two. They take the
landmarks as given; this module goes beyond them to read them from the files users already have:

- the contract JSON (``"format": "autobones-landmarks/1"``, names -> 3-vectors);
- MeshLab picked points (``.pp``, XML ``<point name= x= y= z= active=/>``);
- an ordered iBUG/Multi-PIE 68-point list: a ``.json`` list of 68 triples (or
  ``{"landmarks": [...]}``), an iBUG ``.pts`` text file, or a menpo ``.ljson``;
  converted to contract names with :data:`IBUG68` (27 landmarks).

The format is recognised by content, not extension. Coordinates are kept in
the mesh's own frame and units; nothing is converted. Every problem with a
file is one :class:`~autobones.errors.AutobonesError` naming the file, never a
parser traceback. The names table lives in :mod:`autobones.io.landmark_names` and the
checks (:func:`validate_landmarks`: names, values, distance to the surface, left/right
swaps) in :mod:`autobones.io.landmark_checks`; both are re-exported here.
"""
from __future__ import annotations

import json
import logging
import os
import re

import numpy as np

from ..errors import AutobonesError, counted
from .atomic import write_text_atomic
from .files import read_bytes, shown
from .landmark_checks import quoted, shorten, validate_landmarks
from .landmark_names import BILATERAL, MIDLINE, NAME_INDEX, NAMES, mirror_name

__all__ = ["BILATERAL", "FORMAT", "IBUG68", "IBUG_COUNT", "MIDLINE", "NAMES", "NAME_INDEX", "mirror_name",
           "picked_points_text", "read_landmarks", "resolve_landmarks", "validate_landmarks", "write_landmarks",
           "write_picked_points"]

log = logging.getLogger(__name__)

FORMAT = "autobones-landmarks/1"

#: iBUG-68 (0-based) indices averaged to give each contract name. Points 36-41
#: are the subject's right eye, 42-47 the left.
IBUG68 = {
    "menton": (8,),
    "brow_outer_r": (17,), "brow_middle_r": (19,), "brow_inner_r": (21,),
    "brow_inner_l": (22,), "brow_middle_l": (24,), "brow_outer_l": (26,),
    "nasion": (27,), "pronasale": (30,), "subnasale": (33,),
    "alare_r": (31,), "alare_l": (35,),
    "exocanthion_r": (36,), "endocanthion_r": (39,), "endocanthion_l": (42,), "exocanthion_l": (45,),
    "palpebrale_superius_r": (37, 38), "palpebrale_inferius_r": (40, 41),
    "palpebrale_superius_l": (43, 44), "palpebrale_inferius_l": (46, 47),
    "cheilion_r": (48,), "crista_philtri_r": (50,), "labiale_superius": (51,),
    "crista_philtri_l": (52,), "cheilion_l": (54,),
    "labiale_inferius": (57,),
    "stomion": (62, 66),
}

IBUG_COUNT = 68

# ---------------------------------------------------------------------------------------------
# reading

class _Duplicate(Exception):
    def __init__(self, key):
        super().__init__(key)
        self.key = key


def _no_duplicates(pairs):
    out = {}
    for key, value in pairs:
        if key in out:
            raise _Duplicate(key)
        out[key] = value
    return out


def read_landmarks(path):
    """Read a landmark file into contract names.

    Parameters
    ----------
    path : str or os.PathLike
        A contract JSON, a MeshLab ``.pp``, or an iBUG-68 list (``.json``,
        ``.pts``, ``.ljson``). The format is told by content; the extension
        only sharpens error messages.

    Returns
    -------
    dict[str, (3,) float64]
        Contract name -> position in the mesh's own frame and units, in
        :data:`NAMES` order. iBUG lists give the 27 names of :data:`IBUG68`
        (fewer when some points are marked missing, as ``null`` or all-NaN).

    Raises
    ------
    AutobonesError
        Missing, empty, binary or malformed file; unknown or duplicated names;
        missing or non-finite coordinates; an iBUG list without exactly 68
        3-D points; no landmarks; landmarks at the same point or all on one
        line. At least one landmark is required here; how many the transfer
        needs is :func:`validate_landmarks`'s ``min_count``.
    """
    path = os.fspath(path)
    raw = read_bytes(path, "landmarks")  # a regular file (no FIFO or device), at most LIMITS["landmarks"] read
    if not raw:
        raise AutobonesError(f"{shown(path)}: the landmark file is empty")
    try:
        landmarks = _parse(raw, path)
    except AutobonesError:
        raise
    except (RecursionError, MemoryError):
        raise AutobonesError(f"{path}: the file is nested too deeply or too large to be a landmark file") from None
    except Exception as exc:  # any other parser failure is the file's fault
        raise AutobonesError(
            f"{path}: not a readable landmark file ({exc.__class__.__name__}: {shorten(str(exc))})") from None
    return validate_landmarks(landmarks, min_count=1, source=path)


def _decode(raw, path):
    for bom, codec in ((b"\xef\xbb\xbf", "utf-8"), (b"\xff\xfe\x00\x00", "utf-32-le"),
                       (b"\x00\x00\xfe\xff", "utf-32-be"), (b"\xff\xfe", "utf-16-le"),
                       (b"\xfe\xff", "utf-16-be")):
        if raw.startswith(bom):
            raw, encoding = raw[len(bom):], codec
            break
    else:
        encoding = "utf-8"
    try:
        text = raw.decode(encoding)
    except UnicodeDecodeError:
        raise AutobonesError(
            f"{path}: binary data, not a landmark file (expected text: JSON, MeshLab .pp XML or iBUG .pts)") from None
    if "\x00" in text:
        raise AutobonesError(f"{path}: binary data (NUL bytes), not a landmark file")
    return text


def _parse(raw, path):
    text = _decode(raw, path)
    body = text.strip().lstrip("\ufeff").strip()
    ext = os.path.splitext(path)[1].lower()
    if not body:
        raise AutobonesError(f"{path}: the landmark file holds only whitespace")
    if body[0] in "[{":
        try:
            data = json.loads(body, object_pairs_hook=_no_duplicates)
        except _Duplicate as dup:
            raise AutobonesError(
                f"{path}: key {quoted(dup.key)} appears twice; give each landmark once") from None
        except json.JSONDecodeError as exc:
            if _looks_like_pts(body):
                return _parse_pts(body, path)
            raise AutobonesError(
                f"{path}: not valid JSON (line {exc.lineno} column {exc.colno}: {exc.msg})") from None
        except ValueError as exc:  # e.g. an integer with thousands of digits
            raise AutobonesError(f"{path}: not valid JSON ({shorten(str(exc))})") from None
        return _from_json(data, path)
    if body[0] == "<":
        return _parse_pp(body, path)
    if ext == ".pts" or _looks_like_pts(body):
        return _parse_pts(body, path)
    if ext in (".json", ".ljson", ".pp"):
        kind = "XML" if ext == ".pp" else "JSON"
        raise AutobonesError(f"{path}: not {kind} (it starts with {quoted(body[:20])}); not a landmark file")
    raise AutobonesError(
        f"{path}: not a landmark file; expected autobones JSON, a MeshLab .pp, "
        f"or an iBUG-68 list (.json, .pts, .ljson)")


def _from_json(data, path):
    if isinstance(data, list):
        return _from_ibug(data, path, "the JSON list")
    if not isinstance(data, dict):
        raise AutobonesError(f"{path}: JSON {type(data).__name__} is not a landmark file")
    fmt = data.get("format")
    if fmt is not None and fmt != FORMAT:
        raise AutobonesError(f"{path}: unknown format {quoted(fmt)}; expected {FORMAT!r}")
    if "landmarks" not in data:
        if "groups" in data:  # menpo ljson version 1
            return _from_ljson_v1(data["groups"], path)
        raise AutobonesError(
            f"{path}: no 'landmarks' key; expected {{\"format\": \"{FORMAT}\", \"landmarks\": {{name: [x, y, z]}}}}")
    lms = data["landmarks"]
    if isinstance(lms, list):
        return _from_ibug(lms, path, "'landmarks'")
    if not isinstance(lms, dict):
        raise AutobonesError(f"{path}: 'landmarks' must map names to [x, y, z], got a JSON {_json_type(lms)}")
    if fmt is None and "points" in lms:  # menpo ljson version 2
        if not isinstance(lms["points"], list):
            raise AutobonesError(f"{path}: 'landmarks.points' must be a list of [x, y, z], "
                                 f"got a JSON {_json_type(lms['points'])}")
        return _from_ibug(lms["points"], path, "'landmarks.points'")
    if not lms:
        raise AutobonesError(f"{path}: 'landmarks' is empty; add at least 10 named landmarks")
    out = {}
    for key, value in lms.items():
        out[_add(out, key, path)] = _triple(value, path, f"landmark {quoted(key)}")
    return out


def _from_ljson_v1(groups, path):
    if not isinstance(groups, list):
        raise AutobonesError(f"{path}: 'groups' must be a list of landmark groups")
    points = []
    for group in groups:
        entries = group.get("landmarks") if isinstance(group, dict) else None
        if not isinstance(entries, list):
            raise AutobonesError(f"{path}: every entry of 'groups' needs a 'landmarks' list")
        for entry in entries:
            points.append(entry.get("point") if isinstance(entry, dict) else entry)
    return _from_ibug(points, path, "'groups'")


def _from_ibug(points, path, where):
    if len(points) != IBUG_COUNT:
        raise AutobonesError(
            f"{path}: {where} holds {counted(len(points), 'point')}; an iBUG list needs exactly {IBUG_COUNT} "
            f"(or use named landmarks: {{\"format\": \"{FORMAT}\", \"landmarks\": {{...}}}})")
    P = np.full((IBUG_COUNT, 3), np.nan)
    for i, value in enumerate(points):
        if value is None:
            continue  # menpo writes a point that was not placed as null
        P[i] = _triple(value, path, f"point {i}", allow_all_nan=True)
    return _ibug_to_names(P, path)


def _ibug_to_names(P, path):
    missing = np.isnan(P).all(axis=1)
    out = {}
    for name, idx in IBUG68.items():
        if missing[list(idx)].any():
            continue
        out[name] = P[list(idx)].mean(axis=0)
    if missing.any():
        log.warning("%s: %d iBUG points are not placed; %d landmarks left out",
                    path, int(missing.sum()), len(IBUG68) - len(out))
    if not out:
        raise AutobonesError(f"{path}: no iBUG point that a contract landmark uses is placed")
    return out


def _looks_like_pts(body):
    lines = [ln.strip() for ln in body.splitlines() if ln.strip()]
    return "{" in lines and any(re.match(r"(version|n_points)\s*:", ln) for ln in lines[:3]) or (
        bool(lines) and lines[0] == "{" and (len(lines) < 2 or lines[1][:1] not in "\"}"))


def _parse_pts(body, path):
    lines = [ln.strip() for ln in body.splitlines()]
    n_points, start = None, None
    for i, line in enumerate(lines):
        if not line:
            continue
        if line == "{":
            start = i + 1
            break
        key, sep, value = line.partition(":")
        if not sep:
            raise AutobonesError(
                f"{path}:{i + 1}: expected 'version: 1', 'n_points: 68' or '{{' in an iBUG .pts header")
        if key.strip().lower() == "n_points":
            try:
                n_points = int(value.strip())
            except ValueError:
                raise AutobonesError(f"{path}:{i + 1}: n_points {quoted(value.strip())} is not a whole number") from None
    if start is None:
        raise AutobonesError(f"{path}: no '{{' opening the point list; not an iBUG .pts file")
    rows, closed = [], False
    for i in range(start, len(lines)):
        line = lines[i]
        if not line:
            continue
        if line == "}":
            closed = True
            break
        parts = line.split()
        if len(parts) == 2:
            raise AutobonesError(f"{path}:{i + 1}: 2-D point (x y); landmarks must be 3-D (x y z)")
        if len(parts) != 3:
            raise AutobonesError(f"{path}:{i + 1}: expected 3 coordinates 'x y z', found {counted(len(parts), 'value')}")
        try:
            rows.append([float(p) for p in parts])
        except ValueError:
            raise AutobonesError(f"{path}:{i + 1}: {quoted(line)} is not three numbers") from None
    if not closed:
        raise AutobonesError(f"{path}: the point list is not closed with '}}'; the file is truncated")
    if n_points is not None and n_points != len(rows):
        raise AutobonesError(f"{path}: the header says n_points: {n_points} but the file holds {counted(len(rows), 'point')}")
    if len(rows) != IBUG_COUNT:
        raise AutobonesError(f"{path}: {counted(len(rows), 'point')} found; an iBUG .pts needs exactly {IBUG_COUNT}")
    P = np.array(rows, dtype=np.float64)
    bad = np.isnan(P).any(axis=1) & ~np.isnan(P).all(axis=1)
    bad |= np.isinf(P).any(axis=1)
    if bad.any():
        raise AutobonesError(f"{path}: point {int(np.argmax(bad))} has NaN or infinite coordinates")
    return _ibug_to_names(P, path)


def _parse_pp(body, path):
    from xml.parsers import expat

    points = []

    def start(tag, attrs):
        if tag == "point":
            points.append(attrs)

    def refuse(*_):
        raise AutobonesError(f"{path}: XML entity declarations are not allowed in a .pp file")

    parser = expat.ParserCreate()
    parser.StartElementHandler = start
    parser.EntityDeclHandler = refuse
    parser.UnparsedEntityDeclHandler = refuse
    try:
        parser.Parse(body.encode("utf-8"), True)
    except expat.ExpatError as exc:
        raise AutobonesError(
            f"{path}: not valid XML (line {exc.lineno} column {exc.offset}: {expat.ErrorString(exc.code)})") from None
    if not points:
        raise AutobonesError(f"{path}: no <point .../> elements; pick points in MeshLab and save them as .pp")
    out = {}
    for k, attrs in enumerate(points):
        if str(attrs.get("active", "1")).strip() == "0":
            continue
        name = attrs.get("name")
        if name is None:
            raise AutobonesError(f"{path}: point #{k + 1} has no name; name it with a contract landmark name")
        coords = []
        for axis in "xyz":
            if axis not in attrs:
                raise AutobonesError(f"{path}: point {quoted(name)} has no {axis} coordinate")
            try:
                coords.append(float(attrs[axis]))
            except ValueError:
                raise AutobonesError(f"{path}: point {quoted(name)}: {axis}={quoted(attrs[axis])} is not a number") from None
        out[_add(out, name, path)] = np.array(coords)
    if not out:
        raise AutobonesError(f"{path}: every point is inactive (active=\"0\"); no landmarks to use")
    return out


def _add(out, key, path):
    """Normalise a file's landmark name (surrounding space, case) and refuse a repeat."""
    name = key.strip().lower() if isinstance(key, str) else key
    if name in out:
        raise AutobonesError(f"{path}: landmark {quoted(name)} appears twice; give each landmark once")
    return name


def _triple(value, path, what, allow_all_nan=False):
    if not isinstance(value, (list, tuple)):
        raise AutobonesError(f"{path}: {what} must be [x, y, z], got a JSON {_json_type(value)}")
    if len(value) == 2:
        raise AutobonesError(f"{path}: {what} is 2-D [x, y]; landmarks must be 3-D [x, y, z]")
    if len(value) != 3:
        raise AutobonesError(f"{path}: {what} has {counted(len(value), 'coordinate')}; expected [x, y, z]")
    for v in value:
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise AutobonesError(f"{path}: {what} has a coordinate that is not a number ({quoted(v)})")
    try:
        p = np.array([float(v) for v in value], dtype=np.float64)
    except OverflowError:
        p = np.full(3, np.inf)
    if not np.isfinite(p).all() and not (allow_all_nan and np.isnan(p).all()):
        raise AutobonesError(f"{path}: {what} has NaN or infinite coordinates")
    return p


def _json_type(value):
    return {dict: "object", list: "array", str: "string", bool: "boolean", type(None): "null",
            int: "number", float: "number"}.get(type(value), type(value).__name__)


# ---------------------------------------------------------------------------------------------
# writing

def resolve_landmarks(landmarks):
    """A landmark file path or a dict -> (dict name -> (3,) float64, source for messages).

    Files are read with :func:`read_landmarks`; a dict is taken as given (validate it with
    :func:`validate_landmarks`).
    """
    if isinstance(landmarks, (str, bytes, os.PathLike)):
        return read_landmarks(landmarks), os.fsdecode(landmarks)
    from collections.abc import Mapping

    if not isinstance(landmarks, Mapping):  # a list of points has no names to go by
        raise AutobonesError(f"landmarks: expected a file path or a dict name -> (x, y, z), not "
                             f"{type(landmarks).__name__}")
    out = {}
    for k, v in landmarks.items():
        try:
            p = np.asarray(v, dtype=np.float64)
        except (TypeError, ValueError):
            p = None
        if not isinstance(k, str) or p is None or p.shape != (3,) or not np.isfinite(p).all():
            raise AutobonesError(f"landmarks: {str(k)[:40]!r} must be a name with 3 finite numbers, got "
                                 f"{str(v)[:40]!r}")
        out[k] = p
    return out, "landmarks"


def _json_number(x):
    """``x`` as JSON: its shortest repr, or null when it is not finite (strict JSON has no NaN)."""
    return repr(x) if np.isfinite(x) else "null"


def write_landmarks(path, landmarks, mesh_name=None, confidence=None):
    """Write landmarks as contract JSON, atomically (a temporary file renamed into place).

    Parameters
    ----------
    path : str or os.PathLike
        Destination; its folder must exist.
    landmarks : mapping str -> (3,) float
        Contract names -> positions in the mesh's own frame and units.
        Checked with :func:`validate_landmarks` (``min_count=1``).
    mesh_name : str or None
        Written as the informative ``"mesh"`` field when given.
    confidence : mapping str -> float or None
        Written as an informative ``"confidence"`` object (automatic landmarks); readers
        of the contract ignore it.

    Names are written in :data:`NAMES` order, one per line; floats are written
    with Python's shortest round-trip repr, so reading gives back the same bits.
    """
    path = os.fspath(path)
    clean = validate_landmarks(landmarks, min_count=1, source=path)
    lines = ["{", f'  "format": {json.dumps(FORMAT)},']
    if mesh_name is not None:
        mesh = os.fspath(mesh_name) if isinstance(mesh_name, os.PathLike) else str(mesh_name)
        lines.append(f'  "mesh": {json.dumps(mesh)},')
    lines.append('  "landmarks": {')
    items = [f'    {json.dumps(name)}: [{", ".join(repr(float(c)) for c in p)}]' for name, p in clean.items()]
    lines.append(",\n".join(items))
    if confidence:
        lines.append("  },")
        lines.append('  "confidence": {')
        lines.append(",\n".join(f"    {json.dumps(n)}: {_json_number(round(float(confidence[n]), 3))}"
                                for n in clean if n in confidence))
    lines.append("  }")
    lines.append("}")
    text = "\n".join(lines) + "\n"
    write_text_atomic(path, text, "the landmark file")


def picked_points_text(landmarks, mesh_name=None):
    """Landmarks as MeshLab picked points (``.pp`` XML, what its PickPoints tool saves and
    :func:`read_landmarks` reads): one ``<point x= y= z= active="1" name=/>`` per name, in the
    order given, coordinates as Python's shortest round-trip repr."""
    from xml.sax.saxutils import quoteattr

    rows = [f' <point x="{float(p[0])!r}" y="{float(p[1])!r}" z="{float(p[2])!r}" active="1" name={quoteattr(n)}/>'
            for n, p in landmarks.items()]
    head = [f"  <DataFileName name={quoteattr(str(mesh_name))}/>"] if mesh_name is not None else []
    return "\n".join(["<!DOCTYPE PickedPoints>", "<PickedPoints>", " <DocumentData>", *head, " </DocumentData>",
                      *rows, "</PickedPoints>", ""])


def write_picked_points(path, landmarks, mesh_name=None):
    """Write landmarks as a MeshLab ``.pp`` file, atomically; checked as :func:`write_landmarks` does."""
    path = os.fspath(path)
    clean = validate_landmarks(landmarks, min_count=1, source=path)
    write_text_atomic(path, picked_points_text(clean, mesh_name), "the picked-points file")
