"""The landmark editor's local web server: ``autobones landmarks HEAD --edit`` (issue #35).

The viewer's server (:mod:`autobones.view.server`) with the same guards: 127.0.0.1 only, a random token
first in every URL, the request's Host checked, bounded connections. Unlike the viewer it takes POST,
for the page's JSON requests only (``Content-Type: application/json``, at most :data:`MAX_BODY` bytes,
an ``Origin`` header, when sent, this server's own): a page elsewhere can neither read the token nor
send such a request here without it. Every judgement and every file written is the
:class:`~autobones.view.landmark_session.EditSession`'s.

Routes (each under ``/TOKEN``)
------
GET  ``/``                      the editor page (static/editor.html)
GET  ``/static/...``            its scripts, the bundled three.js
GET  ``/api/editor``            :meth:`EditSession.page_facts`
GET  ``/api/mesh``              :meth:`EditSession.mesh_bytes` (float32 positions, then uint32 triangles)
GET  ``/api/picture?name=N``    PNG: where N goes on the generic head (:mod:`~autobones.view.landmark_pictures`)
POST ``/api/check``             ``{"landmarks"}`` -> :meth:`EditSession.problems`
POST ``/api/mirror``            ``{"name", "point"}`` -> ``{"name", "point"}``: the partner's proposal
POST ``/api/assist``            ``{"landmarks"}`` -> ``{"points", "confidence", "detected"}`` for the names not placed
POST ``/api/save``              ``{"landmarks"}`` -> ``{"written": [paths]}``
POST ``/api/done``              ``{}``: the server stops after answering
"""
from __future__ import annotations

import json
import os
import threading
from http import HTTPStatus

from ..errors import AutobonesError
from .connections import BoundedHTTPServer
from .guard import new_token, resolve_under
from .landmark_pictures import LandmarkPictures
from .server import STATIC, ViewHandler, listen, parse_port

MAX_BODY = 1 << 20  # 44 names of three numbers fit in a few kilobytes


class EditorServer(BoundedHTTPServer):
    """A bounded HTTP server on 127.0.0.1 for one :class:`~autobones.view.landmark_session.EditSession`.

    Attributes: ``session``, ``token``, ``url``, ``port``, ``pictures``, ``finished`` (set when the page
    says done).
    """

    allow_reuse_address = False  # two servers must not share a port

    def __init__(self, session, port=0):
        self.session = session
        self.token = new_token()
        self.pictures = LandmarkPictures()
        self.finished = threading.Event()
        listen(self, parse_port(port), EditorHandler)


def make_editor_server(session, port=0):
    """An :class:`EditorServer` for ``session``, listening, not yet serving (``serve_forever()``)."""
    return EditorServer(session, port)


class EditorHandler(ViewHandler):
    """GET for the page and its data, POST for the page's JSON requests (module docstring)."""

    server_version = "autobones-landmarks"

    def do_POST(self):
        self._head_only = False
        try:
            return self._post()
        except AutobonesError as exc:  # the user's to fix (a name, a file): shown on the page
            return self._send_error(HTTPStatus.UNPROCESSABLE_ENTITY, str(exc))
        except (BrokenPipeError, ConnectionResetError, TimeoutError):
            self.close_connection = True
            return None

    def _route(self):
        gated = self._gate()
        if gated is None:
            return None
        route, query = gated
        session = self.server.session
        if route in ("/", "/index.html", "/editor.html"):
            return self._send_file(os.path.join(STATIC, "editor.html"), cache=False)
        if route.startswith("/static/"):
            return self._send_file(resolve_under(STATIC, route[len("/static/"):]))
        if route == "/api/editor":
            return self._send_json(session.page_facts())
        if route == "/api/mesh":
            return self._send_bytes(session.mesh_bytes(), "application/octet-stream", cache=False)
        if route == "/api/picture":
            return self._send_bytes(self.server.pictures.png(query.get("name", "")), "image/png")
        return self._send_error(HTTPStatus.NOT_FOUND, "no such page")

    def _post(self):
        gated = self._gate()
        if gated is None:
            return None
        route, _ = gated
        body = self._json_body()
        if body is None:
            return None
        session = self.server.session
        marks = body.get("landmarks", {})
        if route == "/api/check":
            return self._send_json(session.problems(marks))
        if route == "/api/mirror":
            name, point = session.mirror(str(body.get("name")), body.get("point"))
            return self._send_json({"name": name, "point": [float(c) for c in point]})
        if route == "/api/assist":
            return self._send_json(session.assist(marks))
        if route == "/api/save":
            return self._send_json({"written": session.save(marks)})
        if route == "/api/done":
            self.close_connection = True
            self._send_json({"done": True, "saved": session.saved})
            self.server.finished.set()
            # shutdown() waits for serve_forever to return: from another thread, never this request's own
            threading.Thread(target=self.server.shutdown, daemon=True).start()
            return None
        return self._send_error(HTTPStatus.NOT_FOUND, "no such API")

    def _json_body(self):
        """The request's JSON object, or None once refused (wrong type, too large, foreign origin, not JSON)."""
        origin = self.headers.get("Origin")
        if origin is not None and origin not in (f"http://127.0.0.1:{self.server.port}",
                                                 f"http://localhost:{self.server.port}"):
            self.close_connection = True
            self._send_error(HTTPStatus.FORBIDDEN, "requests from another page are refused")
            return None
        ctype = (self.headers.get("Content-Type") or "").split(";")[0].strip().lower()
        try:
            length = int(self.headers.get("Content-Length") or -1)
        except ValueError:
            length = -1
        if ctype != "application/json" or not 0 <= length <= MAX_BODY:
            self.close_connection = True  # its body, if any, is not read
            self._send_error(HTTPStatus.BAD_REQUEST, f"send JSON (application/json) of at most {MAX_BODY} bytes")
            return None
        try:
            body = json.loads(self.rfile.read(length) or b"{}")
        except (ValueError, RecursionError):
            body = None
        if not isinstance(body, dict):
            self._send_error(HTTPStatus.BAD_REQUEST, "the request body is not a JSON object")
            return None
        return body
