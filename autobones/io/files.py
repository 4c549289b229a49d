"""The one place where a file argument that is not a mesh is opened and read (issue #33).

Definitions JSON, capture CSV, landmark files, rig sidecars and rig-folder JSON all come through
:func:`read_bytes` / :func:`read_text` / :func:`read_json`, so each of them is, before a byte is
parsed:

- a regular file: a FIFO, a device (``/dev/zero``) or a folder is refused in one line, and is never
  opened in a way that could block (the type is checked with ``stat`` before ``open``, and the open is
  ``O_NONBLOCK`` so a file swapped for a FIFO in between cannot hang us either);
- under a size limit that fits its kind (:data:`LIMITS`), read by a bounded reader that never takes
  more than the limit + 1 byte, so a file that grows while read, or lies about its size, is still
  refused rather than read into memory;
- for JSON, nested at most :data:`MAX_JSON_DEPTH` deep, checked by a cheap scan before ``json.loads``
  (whose C scanner would otherwise recurse into a ``RecursionError``, and whose result every reader
  downstream walks recursively too).

Meshes have their own reader (``io/mesh.py``) and are not read here.
"""
from __future__ import annotations

import json
import os
import re
import stat

from ..errors import AutobonesError

MB = 1024 ** 2
# Bytes per kind. The largest real files are far below these: a sidecar of a 1M-vertex scan is ~10 MB,
# a Live Link Face take of 200k frames (55 min at 60 fps) ~30 MB, a landmark file a few kB.
LIMITS = {
    "definitions": 64 * MB,   # expression definitions JSON (pose --definitions)
    "capture": 64 * MB,       # Live Link Face CSV (animate --capture)
    "sidecar": 64 * MB,       # RIG.rig.json
    "rig": 64 * MB,           # a rig folder's JSON (rig.json, arkit/shapes.json, muscles.json)
    "landmarks": 16 * MB,     # landmark files (.json, .pp, .pts, .ljson)
}
KIND_NAMES = {"definitions": "expression definitions", "capture": "capture CSV", "sidecar": "autobones sidecar",
              "rig": "rig JSON file", "landmarks": "landmark file"}
# one override for every kind, in MB: a studio with a larger file raises it for one run
LIMIT_ENV = "AUTOBONES_MAX_FILE_MB"
# what autobones ships or writes nests at most 7 deep (a transferred sidecar); 64 leaves room for users' extras
MAX_JSON_DEPTH = 64
_CHUNK = 1 << 20


def shown(path):
    """``path`` as it goes into a one-line message: as is, or its ``repr`` when it holds a newline or
    another control character (a file named ``a\\nb.json`` must not break the line)."""
    text = os.fspath(path)
    if isinstance(text, bytes):
        text = os.fsdecode(text)
    return repr(text) if any(ord(c) < 32 or ord(c) == 127 for c in text) else text


def limit_bytes(kind):
    """The size limit of ``kind`` in bytes (``AUTOBONES_MAX_FILE_MB`` replaces every kind's)."""
    env = os.environ.get(LIMIT_ENV)
    if env:
        try:
            mb = float(env)
        except ValueError:
            mb = -1.0
        if not 0 < mb < float("inf"):
            raise AutobonesError(f"{LIMIT_ENV}={env!r}: expected a positive number of MB (e.g. 256)")
        return int(mb * MB)
    return LIMITS[kind]


def refuse_not_regular(path, what, mode):
    """Raise the AutobonesError for ``path``, whose ``os.stat`` mode ``mode`` is no regular file
    (a folder, a FIFO, a device, a socket), naming it as the ``what`` it was given as."""
    if stat.S_ISDIR(mode):
        kind = "a folder"
    elif stat.S_ISFIFO(mode):
        kind = "a FIFO (named pipe)"
    elif stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        kind = "a device"
    elif stat.S_ISSOCK(mode):
        kind = "a socket"
    else:
        kind = "not a regular file"
    raise AutobonesError(f"{shown(path)}: {kind}, not a regular file; the {what} must be a file on disk "
                         "(copy a stream to a file first)")


def check_regular(path, what, folder_says):
    """Refuse ``path`` unless it is a regular file: "no such file", ``folder_says`` for a folder (said
    as it is: "no such file" sent users looking for a typo), :func:`refuse_not_regular` for a FIFO,
    a device or a socket (reading one blocks or never ends). ``what`` names its role."""
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        raise AutobonesError(f"{shown(path)}: no such file") from None
    except OSError as exc:
        raise AutobonesError(f"{shown(path)}: cannot read the {what} ({exc.strerror or exc})") from None
    if stat.S_ISDIR(mode):
        raise AutobonesError(f"{shown(path)}: {folder_says}")
    if not stat.S_ISREG(mode):
        refuse_not_regular(path, what, mode)


def _a(what):
    """``what`` with its article: "a capture CSV", "an autobones sidecar", "expression definitions"."""
    if what.endswith("definitions"):
        return what
    return ("an " if what[0].lower() in "aeiou" else "a ") + what


def _too_large(path, what, kind, size_text):
    return AutobonesError(f"{shown(path)}: {size_text}, over the {limit_bytes(kind) / MB:g} MB limit for {_a(what)} "
                          f"(set {LIMIT_ENV} to raise it, e.g. {LIMIT_ENV}=256)")


def read_bytes(path, kind, what=None):
    """The bytes of the regular file ``path``, at most ``LIMITS[kind]`` of them; AutobonesError
    naming the file (missing, not a regular file, unreadable, too large) otherwise.

    ``what`` names the file's role in messages (default: the kind's name).
    """
    what = what or KIND_NAMES[kind]
    path = os.fspath(path)
    limit = limit_bytes(kind)
    try:
        st = os.stat(path)  # before open: opening a FIFO for reading blocks until a writer comes
    except FileNotFoundError:
        raise AutobonesError(f"{shown(path)}: no such file (the {what})") from None
    except OSError as exc:
        raise AutobonesError(f"{shown(path)}: cannot read the {what} ({exc.strerror or exc})") from None
    if not stat.S_ISREG(st.st_mode):
        refuse_not_regular(path, what, st.st_mode)
    if st.st_size > limit:
        raise _too_large(path, what, kind, f"{st.st_size / MB:.1f} MB")
    try:
        # O_NONBLOCK: should the path become a FIFO between stat and open, the open does not wait
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    except OSError as exc:
        raise AutobonesError(f"{shown(path)}: cannot read the {what} ({exc.strerror or exc})") from None
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            refuse_not_regular(path, what, os.fstat(fd).st_mode)
        parts, total = [], 0
        while total <= limit:  # bounded: never more than limit + 1 bytes, whatever the file claims
            chunk = os.read(fd, min(_CHUNK, limit + 1 - total))
            if not chunk:
                break
            parts.append(chunk)
            total += len(chunk)
    except OSError as exc:
        raise AutobonesError(f"{shown(path)}: cannot read the {what} ({exc.strerror or exc})") from None
    finally:
        os.close(fd)
    if total > limit:
        raise _too_large(path, what, kind, "more than that")
    return b"".join(parts)


def read_text(path, kind, what=None, encoding="utf-8"):
    """:func:`read_bytes` decoded (``utf-8-sig`` drops a byte order mark); AutobonesError on bad bytes."""
    raw = read_bytes(path, kind, what)
    try:
        return raw.decode(encoding)
    except UnicodeDecodeError as exc:
        raise AutobonesError(f"{shown(path)}: not {encoding} text, byte {exc.start}: the {what or KIND_NAMES[kind]} "
                             "must be a text file") from None


# a JSON string (escapes included): its brackets are text, not nesting
_STRING = re.compile(rb'"[^"\\]*(?:\\.[^"\\]*)*"', re.S)
_NOT_BRACKETS = bytes(b for b in range(256) if b not in b"[]{}")


def json_depth(raw):
    """The deepest nesting of ``[`` / ``{`` in the JSON bytes ``raw``, strings skipped (a cheap scan:
    regular expressions and ``bytes.translate`` in C; ~0.2 s for 64 MB)."""
    import numpy as np

    brackets = _STRING.sub(b"", raw).translate(None, _NOT_BRACKETS)
    if not brackets:
        return 0
    b = np.frombuffer(brackets, dtype=np.uint8)
    step = np.where((b == ord("[")) | (b == ord("{")), 1, -1).astype(np.int8)
    depth, deepest = 0, 0
    for i in range(0, len(step), _CHUNK):  # in chunks: an int64 running sum of 64 MB would take 512 MB
        run = np.cumsum(step[i:i + _CHUNK], dtype=np.int64) + depth
        deepest, depth = max(deepest, int(run.max())), int(run[-1])
    return deepest


def check_json_depth(raw, path, what, max_depth=MAX_JSON_DEPTH):
    depth = json_depth(raw)
    if depth > max_depth:
        raise AutobonesError(f"{shown(path)}: JSON nested {depth} levels deep, more than the {max_depth} autobones "
                             f"reads in {_a(what)}; the file is damaged or is not {_a(what)}")


def read_json(path, kind, what=None, invalid=None, **loads_kwargs):
    """The JSON document in ``path``: a regular file under its kind's size limit, UTF-8 (a BOM is
    allowed), nested at most :data:`MAX_JSON_DEPTH` deep; AutobonesError naming the file otherwise.
    ``invalid`` starts the message on bad JSON (default ``not readable as a WHAT``); ``loads_kwargs`` go
    to :func:`json.loads` (``object_pairs_hook``, ``parse_constant``)."""
    what = what or KIND_NAMES[kind]
    invalid = invalid or f"not readable as {_a(what)}"
    raw = read_bytes(path, kind, what)
    check_json_depth(raw, path, what)
    try:
        return json.loads(raw.decode("utf-8-sig"), **loads_kwargs)
    except UnicodeDecodeError as exc:
        raise AutobonesError(f"{shown(path)}: {invalid} (not UTF-8 text: byte {exc.start})") from None
    except json.JSONDecodeError as exc:
        raise AutobonesError(f"{shown(path)}: {invalid} (not valid JSON: line {exc.lineno} column {exc.colno}: "
                             f"{exc.msg})") from None
    except RecursionError:  # the scan above bounds depth; kept so no path can end in a traceback
        raise AutobonesError(f"{shown(path)}: {invalid} (JSON nested too deeply)") from None
    except ValueError as exc:  # an integer of thousands of digits
        raise AutobonesError(f"{shown(path)}: {invalid} (not valid JSON: {str(exc)[:80]})") from None
