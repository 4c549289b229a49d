"""``autobones view``: a local browser viewer of one rig or of a batch output folder (issue #17).

Beyond the seeds: a rig is only useful once someone has looked at it. :mod:`~autobones.view.site`
reads what the folder holds (rig facts, the batch report), :mod:`~autobones.view.thumbnails` draws
the batch page's pictures with the project's own renderer, :mod:`~autobones.view.server` serves
the page (``static/``, three.js bundled inside the package, no network needed) on 127.0.0.1, read-only,
behind a random token in its URL (:mod:`~autobones.view.guard`) and with bounded connections
(:mod:`~autobones.view.connections`).

Example
-------
>>> from autobones.view import make_server
>>> srv = make_server("rigs/")          # or "head.glb"
>>> print(srv.url); srv.serve_forever()   # http://127.0.0.1:PORT/TOKEN/
"""
from .guard import resolve_under
from .server import ViewServer, make_server
from .site import Site, open_site

__all__ = ["Site", "ViewServer", "make_server", "open_site", "resolve_under"]
