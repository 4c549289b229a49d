"""Who may read what through the viewer: the URL's token, paths kept inside the folder, and the files served.

Issue #33 item 9: the server listened on 127.0.0.1, but 127.0.0.1 is every local user's, and it served
every non-hidden file under the rig's folder. Now each server draws a random token
(:func:`secrets.token_urlsafe`, 128 bits) and answers only requests whose first path segment is that
token (``http://127.0.0.1:PORT/TOKEN/...``); the page's own requests are relative URLs, so they carry it
without a cookie (a cookie is per host, not per port: every local user's server on 127.0.0.1 would be
sent it). Under the token only the viewer's files are served: the rigs it shows, their two sidecars,
and its static assets; any other file of the folder is 404, as if it did not exist.
"""
from __future__ import annotations

import hmac
import os
import secrets
from urllib.parse import unquote

from ..rig import sidecar_paths


class Refused(Exception):
    """A request path that leaves the folder served (HTTP 403)."""


def new_token():
    """A fresh URL-safe token (22 characters, 128 random bits)."""
    return secrets.token_urlsafe(16)


def split_token(path, token):
    """``(ok, rest)`` for a URL path: ``ok`` when its first segment is ``token`` (compared in constant
    time), ``rest`` the path after it (``None`` for ``/TOKEN`` alone, ``/`` or longer otherwise)."""
    _, _, tail = path.partition("/")
    first, slash, rest = tail.partition("/")
    ok = hmac.compare_digest(first.encode("utf-8", "surrogatepass"), token.encode("ascii"))
    return ok, ("/" + rest if slash else None)


def resolve_under(root, rel):
    """Real path of the URL path ``rel`` inside folder ``root``, or :class:`Refused`.

    Parameters
    ----------
    root : str
        Real (symlink-free, absolute) path of the folder served.
    rel : str
        '/'-separated path, percent-decoded already or not (decoded once more here is harmless:
        a literal '%2e%2e' is refused either way).

    Returns
    -------
    str
        The real path; it may not exist (the caller answers 404).

    Refused when ``rel`` has a ``..`` segment, is absolute or a drive path, has a backslash or NUL,
    a hidden (dot) name, or resolves (through symbolic links) outside ``root``.
    """
    rel = unquote(rel)
    if "\x00" in rel or "\\" in rel or rel.startswith("/") or (len(rel) > 1 and rel[1] == ":"):
        raise Refused(rel)
    parts = [p for p in rel.split("/") if p not in ("", ".")]
    if any(p == ".." or p.startswith(".") for p in parts):
        raise Refused(rel)
    path = os.path.realpath(os.path.join(root, *parts))
    if path != root and not path.startswith(root.rstrip(os.sep) + os.sep):
        raise Refused(rel)  # a symbolic link that points out of the folder
    return path


def served_files(site):
    """``{real path: real path of its rig's glb}`` for every file ``/files/`` may serve: each rig the
    page shows (the one rig; the batch report's outputs; or the rigs found under a folder without a
    report) and its ``.rig.json`` and ``.weights.npz``. Nothing else of the folder is served.

    Real paths, taken once when the server starts: a request is matched after :func:`resolve_under`
    has resolved it the same way, so a link inside the folder to a rig serves that rig and nothing more.
    """
    if site.mode == "rig":
        rels = [site.rig]
    elif site.report is not None:
        rels = [f["output"] for f in site.report["files"] if isinstance(f, dict) and isinstance(f.get("output"), str)]
    else:
        rels = list(site.rigs)
    out = {}
    for rel in rels:
        try:
            glb = resolve_under(site.root, rel)
        except Refused:  # a report naming a path outside the folder: never served
            continue
        if glb.lower().endswith(".glb"):
            for p in (glb, *sidecar_paths(glb)):
                out[p] = glb
    return out
