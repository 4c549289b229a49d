"""``autobones view`` against hostile local clients (issue #33 item 9): the token, the files served, a
bounded worker pool and a deadline on every request's headers.

Every socket here goes to 127.0.0.1; every wait is bounded (select with a timeout, loops bounded in
count). The server's own limits are used as they ship (16 workers, 48 waiting, 5 s for headers), so the
two connection tests take about 5 s each.
"""
import http.client
import math
import select
import socket
import threading
import time

import pytest

import bad_inputs
from shared_data import data
from test_view import Serving

VIEW_CASES = bad_inputs.view_cases()


@pytest.fixture(scope="module")
def view_folder(tmp_path_factory):
    import autobones

    base = tmp_path_factory.mktemp("view_limits")
    autobones.place(data(bad_inputs.ROBOT), density="sparse").save(str(base / "robot.glb"))
    return bad_inputs.write_view_folder(base / "case", base / "robot.glb")


@pytest.fixture(scope="module")
def server(view_folder):
    s = Serving(view_folder)
    yield s
    s.close()


def _fill(target, token):
    wrong = ("A" if token[0] != "A" else "B") + token[1:]
    return target.format(token=token, wrong=wrong)


@pytest.mark.parametrize("name", sorted(VIEW_CASES))
def test_view_case(server, view_folder, name):
    target, status, case = VIEW_CASES[name]
    got, headers, body = server.get(_fill(target, server.server.token), token=False)
    assert got == status, (name, got, body[:200])
    if case.expect == "ok":
        assert body == (view_folder / target.rsplit("/", 1)[1]).read_bytes()
    else:
        assert headers["Content-Type"] == "application/json" and len(body) < 200  # a one-line JSON error only
        assert b"private" not in body and b"secret" not in body and b"glTF" not in body


def test_token_url_redirect_and_a_fresh_token_per_server(view_folder, server):
    token = server.server.token
    assert len(token) == 22 and server.server.url.endswith(f"/{token}/")
    status, headers, _ = server.get(f"/{token}?rig=robot.rig.glb", token=False)
    assert status == 301 and headers["Location"] == f"/{token}/?rig=robot.rig.glb"  # the page's relative URLs need the /
    assert server.get("/", token=True)[0] == 200
    assert server.get("/api/rig?path=robot.rig.glb")[0] == 200 and server.get("/api/thumb?path=robot.rig.glb")[0] == 200
    assert server.get("/static/app.js")[2].startswith(b"//")
    assert server.get("/", token=True)[1]["Referrer-Policy"] == "no-referrer"
    other = Serving(view_folder)
    try:
        assert other.server.token != token
        assert other.get(f"/{token}/", token=False)[0] == 403  # one server's token opens no other
    finally:
        other.close()


def _wait_closed(socks, bound):
    """{socket: seconds until the server closed it} for those closed within ``bound`` seconds."""
    t0, closed, open_ = time.monotonic(), {}, set(socks)
    while open_ and time.monotonic() - t0 < bound:
        ready, _, _ = select.select(list(open_), [], [], 0.2)
        for s in ready:
            try:
                end = s.recv(4096) == b""
            except OSError:  # reset: closed too
                end = True
            if end:
                closed[s] = time.monotonic() - t0
                open_.discard(s)
    return closed


def _workers(port):
    return [t for t in threading.enumerate() if t.name.startswith(f"autobones-view-{port}-")]


def test_100_idle_sockets_use_at_most_the_pool_and_are_closed_in_time(view_folder):
    s = Serving(view_folder)
    srv = s.server
    bound = srv.header_seconds + math.ceil(srv.waiting / srv.workers) * srv.grace_seconds
    try:
        before = threading.active_count()
        idle = [socket.create_connection(("127.0.0.1", srv.port), timeout=5) for _ in range(srv.workers)]
        # a real request behind the busy workers: it waits in the queue, and is answered once they free
        real = http.client.HTTPConnection("127.0.0.1", srv.port, timeout=30)
        real.request("GET", f"/{srv.token}/api/site")
        idle += [socket.create_connection(("127.0.0.1", srv.port), timeout=5) for _ in range(100 - srv.workers)]
        t0 = time.monotonic()
        time.sleep(0.5)
        assert len(_workers(srv.port)) <= srv.workers and srv.thread_count() <= srv.workers
        assert threading.active_count() - before <= srv.workers  # was: +100 (one thread per socket)
        closed = _wait_closed(idle, bound + 3.0)
        elapsed = time.monotonic() - t0
        assert len(closed) == 100, f"{100 - len(closed)} of 100 idle sockets still open after {elapsed:.1f} s"
        early = [t for t in closed.values() if t < 1.0]  # beyond the pool and the queue: answered 503 at once
        assert len(early) == 100 - srv.workers - (srv.waiting - 1), sorted(closed.values())[:5]
        assert max(closed.values()) < bound + 2.0, max(closed.values())
        r = real.getresponse()
        assert r.status == 200 and b'"mode"' in r.read()
        real.close()
        assert len(_workers(srv.port)) <= srv.workers
        assert s.get("/api/site")[0] == 200  # still serving
    finally:
        for sock in idle:
            sock.close()
        s.close()


def test_slowloris_and_idle_keep_alive_are_closed_by_the_deadline(view_folder, server):
    srv = server.server
    keep = http.client.HTTPConnection("127.0.0.1", srv.port, timeout=30)
    keep.request("GET", f"/{srv.token}/api/site")
    r = keep.getresponse()
    assert r.status == 200 and r.getheader("Connection") != "close"
    r.read()  # the connection stays open for the next request, until it has been idle for header_seconds
    slow = socket.create_connection(("127.0.0.1", srv.port), timeout=5)
    t0 = time.monotonic()  # the slow connection's deadline counts from its accept, just before this
    slow.sendall(f"GET /{srv.token}/api/site HTTP/1.1\r\n".encode())
    header = f"Host: 127.0.0.1:{srv.port}\r\nX-Slow: {'a' * 40}\r\n\r\n".encode()
    closed_at = None
    for i in range(len(header)):  # one byte a second: never a complete request, each read well within 5 s
        try:
            slow.sendall(header[i:i + 1])
        except OSError:
            closed_at = time.monotonic() - t0
            break
        ready, _, _ = select.select([slow], [], [], 1.0)
        if ready:
            assert slow.recv(4096) == b""  # closed without an answer
            closed_at = time.monotonic() - t0
            break
        if time.monotonic() - t0 > 15:
            break
    slow.close()
    assert closed_at is not None, "the slowloris connection is still open after 15 s"
    assert srv.header_seconds - 1 < closed_at < srv.header_seconds + 2, closed_at  # was: open as long as it sends
    ready, _, _ = select.select([keep.sock], [], [], 3.0)  # the idle keep-alive one went at the same deadline
    assert ready and keep.sock.recv(1) == b""
    keep.close()
