"""The viewer's local web server: the page, the rigs of the folder given, and a small JSON API.

Beyond the seeds (issue #17). Python's ``http.server`` bound to 127.0.0.1 only, read-only (GET and HEAD;
every other method is refused with 405), with a bounded pool of worker threads and a deadline on every
request's headers (:mod:`autobones.view.connections`). Every URL starts with the server's random token
(:mod:`autobones.view.guard`, issue #33): ``http://127.0.0.1:PORT/TOKEN/``; without it, 403. Paths from the
URL are resolved against the folder and refused when they leave it: ``..`` segments, absolute or drive
paths, hidden names, and symbolic links that point outside (403); inside it, only the rigs the page shows
and their sidecars are served (anything else is 404, as a missing file). Requests whose ``Host`` header
is not this server's own address are refused too (a web page elsewhere cannot read the folder through
DNS rebinding).

Routes (each under ``/TOKEN``; ``/TOKEN`` alone redirects to ``/TOKEN/``)
------
``/``                       the page (static/index.html); ``?rig=REL`` opens one rig of a batch folder
``/static/...``             the page's scripts and the bundled three.js (package data)
``/files/REL``              a rig's glb (or its ``.rig.json``, ``.weights.npz``): :func:`~.guard.served_files`
``/api/site``               ``{"mode": "rig"|"batch", "rig": REL|null, "title"}``
``/api/rig?path=REL``       :func:`autobones.view.site.rig_facts`
``/api/batch``              :func:`autobones.view.site.batch_listing`
``/api/weights?path=REL&bone=NAME``  ``{"bone", "weights": [n floats]}``: the full matrix's column
``/api/thumb?path=REL``     PNG thumbnail (:mod:`autobones.view.thumbnails`)
"""
from __future__ import annotations

import errno
import json
import logging
import mimetypes
import os
from http import HTTPStatus
from urllib.parse import parse_qs, urlsplit

from ..errors import AutobonesError
from ..io.jsonable import strict_dumps
from .connections import BoundedHTTPServer, TimedHandler
from .guard import Refused, new_token, resolve_under, served_files, split_token
from .site import batch_listing, batch_record, bone_weights, glb_generator, open_site, rig_facts
from .thumbnails import ThumbnailCache

log = logging.getLogger(__name__)

HOST = "127.0.0.1"
STATIC = os.path.join(os.path.dirname(os.path.realpath(__file__)), "static")  # real: resolve_under compares real paths
TYPES = {".js": "text/javascript; charset=utf-8", ".html": "text/html; charset=utf-8", ".css": "text/css",
         ".json": "application/json", ".glb": "model/gltf-binary", ".png": "image/png", ".txt": "text/plain",
         ".md": "text/plain; charset=utf-8", ".npz": "application/octet-stream"}


class ViewServer(BoundedHTTPServer):
    """A bounded HTTP server on 127.0.0.1 serving one :class:`~autobones.view.site.Site`.

    Attributes: ``site``, ``token``, ``url`` (``http://127.0.0.1:PORT/TOKEN/``: the only way in),
    ``thumbnails`` (the cache), ``served`` (:func:`~autobones.view.guard.served_files`).
    """

    allow_reuse_address = False  # two viewers must not share a port

    def __init__(self, site, port=0):
        self.site = site
        self.token = new_token()
        self.served = served_files(site)
        self.thumbnails = ThumbnailCache()
        listen(self, port, ViewHandler)


def listen(server, port, handler):
    """Bind ``server`` (a :class:`BoundedHTTPServer` being made) to 127.0.0.1:``port`` and set its ``port``
    and ``url`` (``http://127.0.0.1:PORT/TOKEN/``, ``server.token`` set already); AutobonesError when
    the port is taken or cannot be listened on."""
    try:
        BoundedHTTPServer.__init__(server, (HOST, int(port)), handler)
    except OSError as exc:
        if exc.errno == errno.EADDRINUSE:
            raise AutobonesError(f"--port {port}: the port is in use; choose another or leave --port out "
                                 "(a free one is picked)") from None
        raise AutobonesError(f"--port {port}: cannot listen on {HOST} ({exc.strerror or exc})") from None
    server.port = server.server_address[1]
    server.url = f"http://{HOST}:{server.port}/{server.token}/"


def parse_port(port):
    """``--port`` as a whole number 0..65535 (0: a free one); AutobonesError otherwise."""
    try:
        port = int(str(port).strip())
    except (TypeError, ValueError):
        raise AutobonesError(f"--port {port!r}: give a whole number 1..65535") from None
    if not 0 <= port <= 65535:
        raise AutobonesError(f"--port {port}: give a whole number 1..65535")
    return port


def make_server(path, port=0):
    """A :class:`ViewServer` for ``path`` (a rig .glb or a batch output folder), listening, not yet serving.

    Parameters
    ----------
    path : str
        What to show; see :func:`autobones.view.site.open_site` for what is refused.
    port : int
        TCP port on 127.0.0.1; 0 picks a free one.

    Call ``server.serve_forever()`` to answer requests (``server.url``), ``server.shutdown()`` from
    another thread to stop, ``server.server_close()`` to release the port.
    """
    port = parse_port(port)  # before the folder is read: a bad option costs nothing
    return ViewServer(open_site(path), port)


class ViewHandler(TimedHandler):
    """GET and HEAD only; see the module docstring for the routes."""

    server_version = "autobones-view"
    protocol_version = "HTTP/1.1"

    def log_message(self, format, *args):  # noqa: A002 - the base class's name
        log.debug("%s %s", self.address_string(), format % args)

    # read-only: every method that could change something is refused
    def _refuse_method(self):
        self.close_connection = True  # its body, if any, is not read
        self._send_error(HTTPStatus.METHOD_NOT_ALLOWED, "read-only: GET and HEAD only", {"Allow": "GET, HEAD"})

    do_POST = do_PUT = do_DELETE = do_PATCH = do_OPTIONS = do_TRACE = do_CONNECT = _refuse_method

    def do_HEAD(self):
        self._answer(head=True)

    def do_GET(self):
        self._answer(head=False)

    def _answer(self, head):
        self._head_only = head
        try:
            return self._route()
        except Refused:
            return self._send_error(HTTPStatus.FORBIDDEN, "outside the folder served")
        except AutobonesError as exc:
            return self._send_error(HTTPStatus.NOT_FOUND, str(exc))
        except (BrokenPipeError, ConnectionResetError, TimeoutError):  # the client left, or took too long
            self.close_connection = True
            return None
        except Exception as exc:  # a bug: answer 500 and keep serving; one line in the log, the traceback at -vv
            log.warning("%s failed: %s: %s", self.path, type(exc).__name__, exc)
            log.debug("traceback", exc_info=True)
            return self._send_error(HTTPStatus.INTERNAL_SERVER_ERROR, f"{type(exc).__name__}: {exc}")

    def _gate(self):
        """``(route, query)`` of a request from this server's own page, or None once refused (403 for a
        foreign Host or a missing token) or redirected (``/TOKEN`` -> ``/TOKEN/``)."""
        host = (self.headers.get("Host") or "").lower()
        port = self.server.port
        if host not in (f"127.0.0.1:{port}", f"localhost:{port}"):
            self._send_error(HTTPStatus.FORBIDDEN, "unknown Host")
            return None
        url = urlsplit(self.path)
        ok, route = split_token(url.path, self.server.token)
        if not ok:  # the same answer for any path: nothing about the folder is told without the token
            self._send_error(HTTPStatus.FORBIDDEN, "no token: open the URL that autobones printed")
            return None
        if route is None:  # /TOKEN: the page's relative URLs need the trailing slash
            where = f"/{self.server.token}/" + (f"?{url.query}" if url.query else "")
            self._send_bytes(b"", "text/plain", False, HTTPStatus.MOVED_PERMANENTLY, {"Location": where})
            return None
        return route, {k: v[-1] for k, v in parse_qs(url.query).items()}

    def _route(self):
        gated = self._gate()
        if gated is None:
            return None
        route, query = gated
        if route in ("/", "/index.html"):
            return self._send_file(os.path.join(STATIC, "index.html"), cache=False)
        if route.startswith("/static/"):
            return self._send_file(resolve_under(STATIC, route[len("/static/"):]))
        if route.startswith("/files/"):
            return self._send_rig_file(route[len("/files/"):])
        if route.startswith("/api/"):
            return self._api(route[len("/api/"):], query)
        return self._send_error(HTTPStatus.NOT_FOUND, "no such page")

    def _api(self, name, query):
        site = self.server.site
        if name == "site":
            title = os.path.basename(site.root) if site.mode == "batch" else site.rig
            return self._send_json({"mode": site.mode, "rig": site.rig, "title": title})
        if name == "batch":
            if site.mode != "batch":
                return self._send_error(HTTPStatus.NOT_FOUND, "not a batch folder")
            return self._send_json(batch_listing(site))
        if name in ("rig", "weights", "thumb"):
            rel = query.get("path", "")
            path = self._rig_path(rel)
            if path is None:
                return self._send_error(HTTPStatus.NOT_FOUND, f"{rel}: not a rig written by autobones")
            if name == "rig":
                return self._send_json(rig_facts(site.root, self._rel(path), batch_record(site, self._rel(path))))
            if name == "weights":
                w = bone_weights(path, query.get("bone", ""))
                # 7 significant digits, not 5 decimals: a weight of 1.05e-4 went out as 1e-4 and the page, which
                # greys what is not above 1e-4 as the glb's own colours do, greyed it
                return self._send_json({"bone": query.get("bone"), "weights": [float(f"{x:.7g}") for x in w]})
            return self._send_bytes(self.server.thumbnails.get(path), "image/png", cache=False)
        return self._send_error(HTTPStatus.NOT_FOUND, "no such API")

    def _rel(self, path):
        return os.path.relpath(path, self.server.site.root).replace(os.sep, "/")

    def _rig_path(self, rel):
        """Real path of the rig glb ``rel`` when the page shows it, None otherwise (Refused when outside)."""
        path = resolve_under(self.server.site.root, rel)
        if self.server.served.get(path) != path or not os.path.isfile(path) or glb_generator(path) != "autobones":
            return None
        return path

    def _send_rig_file(self, rel):
        """A rig the page shows or one of its sidecars; any other file of the folder is 404 (not 403: a
        request does not learn whether it exists)."""
        path = resolve_under(self.server.site.root, rel)
        glb = self.server.served.get(path)
        if glb is None or glb_generator(glb) != "autobones":
            return self._send_error(HTTPStatus.NOT_FOUND, "no such file among the rigs shown")
        return self._send_file(path, cache=False)

    def _send_file(self, path, cache=True):
        if not os.path.isfile(path):
            return self._send_error(HTTPStatus.NOT_FOUND, "no such file")
        try:
            with open(path, "rb") as fh:
                data = fh.read()
        except OSError:
            return self._send_error(HTTPStatus.NOT_FOUND, "cannot read the file")
        ext = os.path.splitext(path)[1].lower()
        ctype = TYPES.get(ext) or mimetypes.guess_type(path)[0] or "application/octet-stream"
        return self._send_bytes(data, ctype, cache)

    def _send_json(self, obj):
        return self._send_bytes(strict_dumps(obj).encode("utf-8"), "application/json", cache=False)

    def _send_bytes(self, data, ctype, cache=True, status=HTTPStatus.OK, extra=None):
        self.send_response(status)
        self.send_header("Content-Type", ctype)
        self.send_header("Content-Length", str(len(data)))
        self.send_header("Cache-Control", "max-age=3600" if cache else "no-store")
        self.send_header("X-Content-Type-Options", "nosniff")
        self.send_header("Referrer-Policy", "no-referrer")  # the token is in every URL: never sent on
        for k, v in (extra or {}).items():
            self.send_header(k, v)
        self.end_headers()
        if not getattr(self, "_head_only", False):
            self.wfile.write(data)

    def _send_error(self, status, message, extra=None):
        body = json.dumps({"error": message, "status": int(status)}).encode("utf-8")
        return self._send_bytes(body, "application/json", cache=False, status=status, extra=extra)
