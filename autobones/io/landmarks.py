"""Read, write and check landmark files: the 44-name contract of ``spec/landmarks.md``.

Seed 004 §2 tags the generic rig with 44 anthropometric landmarks (lambda) and
§3 the face model with any subset of them (phi, "positioned manually by the
artist"); the transfer (§3.1) fits a thin-plate spline between the two. The seed takes the landmarks as given;
this module goes beyond it to read them from the files users already have:

- the contract JSON (``"format": "autobones-landmarks/1"``, names -> 3-vectors);
- MeshLab picked points (``.pp``, XML ``<point name= x= y= z= active=/>``);
- an ordered iBUG/Multi-PIE 68-point list: a ``.json`` list of 68 triples (or
  ``{"landmarks": [...]}``), an iBUG ``.pts`` text file, or a menpo ``.ljson``;
  converted to contract names with :data:`IBUG68` (27 landmarks).

The format is recognised by content, not extension. Coordinates are kept in
the mesh's own frame and units; nothing is converted. Every problem with a
file is one :class:`~autobones.errors.AutobonesError` naming the file, never a
parser traceback. :func:`validate_landmarks` adds the checks that need the
mesh: distance to the surface (with a hint when the units differ) and a
left/right swap test in the head's canonical frame.
"""
from __future__ import annotations

import difflib
import json
import logging
import os
import re
from collections.abc import Mapping

import numpy as np

from ..errors import AutobonesError
from .atomic import write_text_atomic

log = logging.getLogger(__name__)

FORMAT = "autobones-landmarks/1"

#: Midline names, top of the head to the chin then around (spec order).
MIDLINE = (
    "vertex", "opisthocranion", "glabella", "nasion", "pronasale", "subnasale",
    "labiale_superius", "stomion", "labiale_inferius", "sublabiale", "pogonion", "menton",
)

#: Bilateral base names; each exists as ``NAME_l`` (subject's left) and ``NAME_r``.
BILATERAL = (
    "exocanthion", "endocanthion", "palpebrale_superius", "palpebrale_inferius",
    "brow_inner", "brow_middle", "brow_outer", "alare", "crista_philtri", "cheilion",
    "zygion", "gonion", "tragion", "superaurale", "subaurale", "frontotemporale",
)

#: The 44 contract names in their fixed order: the 12 midline names, then for
#: each bilateral base name in :data:`BILATERAL` order ``NAME_l`` then ``NAME_r``.
NAMES = MIDLINE + tuple(f"{base}_{side}" for base in BILATERAL for side in ("l", "r"))

_ORDER = {name: i for i, name in enumerate(NAMES)}

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

# Landmark files are tiny; anything larger is not one.
MAX_FILE_BYTES = 16 * 1024**2

# Global scales tried when landmarks miss the surface, and what each one means.
_UNIT_HINTS = (
    (0.001, "millimetres for a mesh in metres"),
    (1000.0, "metres for a mesh in millimetres"),
    (0.1, "millimetres for a mesh in centimetres"),
    (10.0, "centimetres for a mesh in millimetres"),
    (0.01, "centimetres for a mesh in metres"),
    (100.0, "metres for a mesh in centimetres"),
)


def mirror_name(name):
    """The same landmark on the other side: ``'x_l'`` <-> ``'x_r'``; a midline name is itself.

    Raises ``ValueError`` for a name outside :data:`NAMES`.
    """
    if name not in _ORDER:
        raise ValueError(f"{name!r} is not a landmark name of the contract")
    if name in MIDLINE:
        return name
    return name[:-1] + ("r" if name.endswith("_l") else "l")


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
    if not os.path.isfile(path):
        raise AutobonesError(f"{path}: no such landmark file")
    size = os.path.getsize(path)
    if size == 0:
        raise AutobonesError(f"{path}: the landmark file is empty")
    if size > MAX_FILE_BYTES:
        raise AutobonesError(f"{path}: {size / 1024**2:.0f} MiB is far too large for a landmark file")
    try:
        with open(path, "rb") as fh:
            raw = fh.read()
    except OSError as exc:
        raise AutobonesError(f"{path}: cannot read the landmark file ({exc.strerror or exc})") from None
    try:
        landmarks = _parse(raw, path)
    except AutobonesError:
        raise
    except (RecursionError, MemoryError):
        raise AutobonesError(f"{path}: the file is nested too deeply or too large to be a landmark file") from None
    except Exception as exc:  # any other parser failure is the file's fault
        raise AutobonesError(
            f"{path}: not a readable landmark file ({exc.__class__.__name__}: {_short(str(exc))})") from None
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
                f"{path}: key {_q(dup.key)} appears twice; give each landmark once") from None
        except json.JSONDecodeError as exc:
            if _looks_like_pts(body):
                return _parse_pts(body, path)
            raise AutobonesError(
                f"{path}: not valid JSON (line {exc.lineno} column {exc.colno}: {exc.msg})") from None
        except ValueError as exc:  # e.g. an integer with thousands of digits
            raise AutobonesError(f"{path}: not valid JSON ({_short(str(exc))})") from None
        return _from_json(data, path)
    if body[0] == "<":
        return _parse_pp(body, path)
    if ext == ".pts" or _looks_like_pts(body):
        return _parse_pts(body, path)
    if ext in (".json", ".ljson", ".pp"):
        kind = "XML" if ext == ".pp" else "JSON"
        raise AutobonesError(f"{path}: not {kind} (it starts with {_q(body[:20])}); not a landmark file")
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
        raise AutobonesError(f"{path}: unknown format {_q(fmt)}; expected {FORMAT!r}")
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
        out[_add(out, key, path)] = _triple(value, path, f"landmark {_q(key)}")
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
            f"{path}: {where} holds {len(points)} points; an iBUG list needs exactly {IBUG_COUNT} "
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
                raise AutobonesError(f"{path}:{i + 1}: n_points {_q(value.strip())} is not a whole number") from None
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
            raise AutobonesError(f"{path}:{i + 1}: expected 3 coordinates 'x y z', found {len(parts)} values")
        try:
            rows.append([float(p) for p in parts])
        except ValueError:
            raise AutobonesError(f"{path}:{i + 1}: {_q(line)} is not three numbers") from None
    if not closed:
        raise AutobonesError(f"{path}: the point list is not closed with '}}'; the file is truncated")
    if n_points is not None and n_points != len(rows):
        raise AutobonesError(f"{path}: the header says n_points: {n_points} but {len(rows)} points follow")
    if len(rows) != IBUG_COUNT:
        raise AutobonesError(f"{path}: {len(rows)} points found; an iBUG .pts needs exactly {IBUG_COUNT}")
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
                raise AutobonesError(f"{path}: point {_q(name)} has no {axis} coordinate")
            try:
                coords.append(float(attrs[axis]))
            except ValueError:
                raise AutobonesError(f"{path}: point {_q(name)}: {axis}={_q(attrs[axis])} is not a number") from None
        out[_add(out, name, path)] = np.array(coords)
    if not out:
        raise AutobonesError(f"{path}: every point is inactive (active=\"0\"); no landmarks to use")
    return out


def _add(out, key, path):
    """Normalise a file's landmark name (surrounding space, case) and refuse a repeat."""
    name = key.strip().lower() if isinstance(key, str) else key
    if name in out:
        raise AutobonesError(f"{path}: landmark {_q(name)} appears twice; give each landmark once")
    return name


def _triple(value, path, what, allow_all_nan=False):
    if not isinstance(value, (list, tuple)):
        raise AutobonesError(f"{path}: {what} must be [x, y, z], got a JSON {_json_type(value)}")
    if len(value) == 2:
        raise AutobonesError(f"{path}: {what} is 2-D [x, y]; landmarks must be 3-D [x, y, z]")
    if len(value) != 3:
        raise AutobonesError(f"{path}: {what} has {len(value)} coordinates; expected [x, y, z]")
    for v in value:
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise AutobonesError(f"{path}: {what} has a coordinate that is not a number ({_q(v)})")
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


def _short(text, limit=60):
    text = " ".join(str(text).split())
    return text if len(text) <= limit else text[:limit - 3] + "..."


def _q(value):
    """A value from a file, quoted and cut short so a message stays one line."""
    return repr(_short(value, 40)) if isinstance(value, str) else _short(repr(value), 40)


# ---------------------------------------------------------------------------------------------
# writing

def resolve_landmarks(landmarks):
    """A landmark file path or a dict -> (dict name -> (3,) float64, source for messages).

    Files are read with :func:`read_landmarks`; a dict is taken as given (validate it with
    :func:`validate_landmarks`).
    """
    if isinstance(landmarks, (str, bytes, os.PathLike)):
        return read_landmarks(landmarks), os.fsdecode(landmarks)
    return {k: np.asarray(v, dtype=np.float64) for k, v in dict(landmarks).items()}, "landmarks"


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
        lines.append(",\n".join(f"    {json.dumps(n)}: {round(float(confidence[n]), 3)!r}"
                                for n in clean if n in confidence))
    lines.append("  }")
    lines.append("}")
    text = "\n".join(lines) + "\n"
    write_text_atomic(path, text, "the landmark file")


# ---------------------------------------------------------------------------------------------
# checking

def validate_landmarks(landmarks, V=None, F=None, frame=None, min_count=10, source="landmarks",
                       max_off_surface=0.05):
    """Check a landmark dict against the contract and, optionally, the mesh it belongs to.

    Parameters
    ----------
    landmarks : mapping str -> (3,) float
        Contract names -> positions in the mesh's own frame and units.
    V : (n, 3) float or None
        Mesh vertices, same frame and units as the landmarks.
    F : (m, 3) int or None
        Mesh triangles; given together with ``V``.
    frame : autobones.orient.Frame or None
        The head's canonical frame (``autobones.orient.detect_frame(V, F)``);
        enables the left/right check.
    min_count : int
        Fewest landmarks accepted (the transfer needs about 10 well spread).
    source : str
        What to call the landmarks in messages, usually the file name.
    max_off_surface : float
        Largest distance from the surface, in head sizes (the largest
        bounding-box extent of ``V``).

    Returns
    -------
    dict[str, (3,) float64]
        Fresh arrays in :data:`NAMES` order.

    Raises
    ------
    AutobonesError
        One line naming ``source`` and the offending landmarks, for: unknown
        names (with the closest valid name), values that are not 3 finite
        numbers, fewer than ``min_count`` landmarks, two landmarks at the same
        point, all landmarks on one line, landmarks farther than
        ``max_off_surface`` from the mesh (with a hint when a global scale by
        1000, 100, 10, 0.1, 0.01 or 0.001 would put them on it: mismatched
        units), and, when ``frame`` is given, ``_l`` / ``_r`` exchanged: in
        canonical coordinates (+X is the subject's left) every ``_l`` point
        must lie at larger x than its ``_r`` partner. Without a frame the
        left/right check is skipped: the landmarks alone do not tell which
        side is the subject's left.
    """
    if not isinstance(landmarks, Mapping):
        raise AutobonesError(f"{source}: landmarks must map names to [x, y, z], got {type(landmarks).__name__}")
    unknown = [k for k in landmarks if k not in _ORDER]
    if unknown:
        raise AutobonesError(f"{source}: unknown landmark name{'s' if len(unknown) > 1 else ''} "
                             + _list(_suggest(k) for k in unknown)
                             + "; use the contract's names (spec/landmarks.md, autobones.io.landmarks.NAMES)")
    clean, bad = {}, []
    for name in sorted(landmarks, key=_ORDER.get):
        try:
            p = np.array(landmarks[name], dtype=np.float64)
        except (TypeError, ValueError, OverflowError):
            p = None
        if p is None or p.shape != (3,) or not np.isfinite(p).all():
            bad.append(name)
        else:
            clean[name] = p
    if bad:
        raise AutobonesError(f"{source}: {_list(bad)} must be 3 finite numbers [x, y, z] (NaN, infinite or malformed)")
    if len(clean) < min_count:
        have = f" ({_list(clean)})" if clean else ""
        raise AutobonesError(f"{source}: only {len(clean)} landmark{'s' if len(clean) != 1 else ''}{have}; "
                             f"at least {min_count} well-spread landmarks are needed, add more")
    if not clean:
        return clean
    names = list(clean)
    P = np.array([clean[n] for n in names])
    head = None
    if V is not None or F is not None:
        if V is None or F is None:
            raise TypeError("validate_landmarks: V and F go together")
        V = np.ascontiguousarray(V, dtype=np.float64)
        F = np.ascontiguousarray(F, dtype=np.int64)
        head = float((V.max(axis=0) - V.min(axis=0)).max())
    _check_spread(P, names, head, source)
    if head is not None:
        _check_surface(P, names, V, F, head, source, max_off_surface)
    if frame is not None:
        _check_sides(clean, frame, source)
    return clean


def _check_spread(P, names, head, source):
    # work on P / max|P| so that huge (finite) coordinates cannot overflow
    m = float(np.abs(P).max())
    Q = P / m if m > 0 else P
    spread = float((Q.max(axis=0) - Q.min(axis=0)).max())
    if len(P) > 1 and spread == 0.0:
        raise AutobonesError(f"{source}: all {len(P)} landmarks are at the same point {P[0].tolist()}; "
                             f"place each where the contract describes it")
    scale = head / m if head and m > 0 else spread
    tol = 1e-7 * scale
    if len(P) > 1:
        from scipy.spatial import cKDTree

        pairs = sorted(cKDTree(Q).query_pairs(tol))
        if pairs:
            shown = ", ".join(f"{names[i]} = {names[j]}" for i, j in pairs[:4])
            more = f" and {len(pairs) - 4} more" if len(pairs) > 4 else ""
            raise AutobonesError(f"{source}: landmarks at the same point ({shown}{more}); "
                                 f"each landmark marks a different place, fix the copied coordinates")
    if len(P) >= 3:
        s = np.linalg.svd(Q - Q.mean(axis=0), compute_uv=False)
        if s[1] <= 1e-6 * s[0]:
            raise AutobonesError(f"{source}: all {len(P)} landmarks lie on one line; "
                                 f"they must spread over the face (check for a dropped coordinate)")


def _check_surface(P, names, V, F, head, source, max_off):
    import igl

    def off(Q):
        if not np.isfinite(Q).all():
            return np.full(len(Q), np.inf)
        d2, _, _ = igl.point_mesh_squared_distance(np.ascontiguousarray(Q), V, F)
        return np.sqrt(np.asarray(d2, dtype=np.float64)) / head

    d = off(P)
    far = d > max_off
    if not far.any():
        return
    order = np.argsort(-d)
    worst = ", ".join(f"{names[i]} {d[i]:.2g}" for i in order[:min(4, int(far.sum()))])
    more = f" and {int(far.sum()) - 4} more" if far.sum() > 4 else ""
    msg = (f"{source}: {int(far.sum())} of {len(P)} landmarks lie far from the mesh surface "
           f"({worst}{more} head sizes; at most {max_off:g} allowed)")
    best = None
    for scale, meaning in _UNIT_HINTS:
        with np.errstate(over="ignore"):
            scaled = P * scale
        near = int((off(scaled) <= max_off).sum())
        if near > int((~far).sum()) and near >= 0.8 * len(P) and (best is None or near > best[0]):
            best = (near, scale, meaning)
    if best is not None:
        _, scale, meaning = best
        msg += (f"; wrong units? scaled by {scale:g} they lie on the surface, so they look like {meaning}: "
                f"give the landmarks in the mesh's units")
    else:
        msg += "; landmarks must be in the mesh's own coordinates (same frame and units) and on its surface"
    raise AutobonesError(msg)


def _check_sides(clean, frame, source):
    pairs = [b for b in BILATERAL if f"{b}_l" in clean and f"{b}_r" in clean]
    if not pairs:
        return
    L = frame.to_canonical(np.array([clean[f"{b}_l"] for b in pairs]))
    R = frame.to_canonical(np.array([clean[f"{b}_r"] for b in pairs]))
    dx = L[:, 0] - R[:, 0]
    inverted = dx < 0
    if inverted.sum() * 2 > len(pairs):
        raise AutobonesError(
            f"{source}: left and right are swapped (mirrored set): in {int(inverted.sum())} of {len(pairs)} pairs "
            f"the _l point is on the subject's right; _l is the subject's own left (the viewer's right in a "
            f"frontal picture), exchange _l and _r (if they are right, the head's detected up or front is wrong: "
            f"give them explicitly)")
    clear = inverted & (dx < -0.01)  # a pair close to the midline may cross by a hair
    if clear.any():
        raise AutobonesError(
            f"{source}: {_list(pairs[i] for i in np.flatnonzero(clear))} have _l and _r exchanged "
            f"(the _l point lies on the subject's right); swap the names of that pair")


def _suggest(name):
    text = repr(_short(name, 40)) if isinstance(name, str) else _short(repr(name), 40)
    if not isinstance(name, str):
        return text
    close = difflib.get_close_matches(name.strip().lower(), NAMES, n=1, cutoff=0.6)
    return f"{text} (did you mean {close[0]!r}?)" if close else text


def _list(items, limit=6):
    items = [str(i) for i in items]
    shown = items[:limit]
    more = f" and {len(items) - limit} more" if len(items) > limit else ""
    return ", ".join(shown) + more
