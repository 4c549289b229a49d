"""``autobones landmarks HEAD --edit`` (issue #35): the editor's server-side checks, mirror proposals and
saving without a browser, its command line, and the page itself in headless Chromium (driven as
tests/test_view.py drives the viewer: the system's chromium through playwright, never a downloaded one).

The head is the compact robot of tests/data with its hand-placed landmarks; nothing here needs
/work/shared.
"""
import http.client
import json
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest

import autobones
from autobones.errors import AutobonesError
from autobones.io.landmarks import read_landmarks, validate_landmarks
from autobones.orient import frame_from_landmarks
from autobones.view.editor_server import make_editor_server
from autobones.view.landmark_session import closest_on_surface, open_session
from shared_data import ROOT, data

CLI = [sys.executable, "-m", "cli.main"]
ROBOT = "misc/robot_head_neutral.obj"
ROBOT_MARKS = ROOT / "tests" / "landmarks" / "robot_head_neutral.landmarks.json"
LEE = "misc/LeePerrySmith.obj"
LEE_MARKS = ROOT / "tests" / "landmarks" / "LeePerrySmith.landmarks.json"


@pytest.fixture(scope="module")
def marks():
    return read_landmarks(ROBOT_MARKS)


@pytest.fixture(scope="module")
def session(tmp_path_factory):
    out = tmp_path_factory.mktemp("edit") / "robot.landmarks.json"
    return open_session(str(data(ROBOT)), output=str(out), detect=False)


class Serving:
    """An EditorServer answering in a thread; ``post`` sends the page's JSON requests."""

    def __init__(self, session):
        self.server = make_editor_server(session)
        self.thread = threading.Thread(target=self.server.serve_forever, daemon=True)
        self.thread.start()

    def post(self, route, body, headers=None):
        c = http.client.HTTPConnection("127.0.0.1", self.server.port, timeout=30)
        raw = json.dumps(body).encode()
        c.request("POST", f"/{self.server.token}/api/{route}", raw,
                  {"Content-Type": "application/json", **(headers or {})})
        r = c.getresponse()
        out = r.status, json.loads(r.read() or b"null")
        c.close()
        return out

    def close(self):
        if not self.server.finished.is_set():
            self.server.shutdown()
        self.thread.join(10)
        self.server.server_close()


def _lists(lm):
    return {n: [float(c) for c in p] for n, p in lm.items()}


# ---------------------------------------------------------------- the server's side, no browser

def test_checks_are_transfers_own_listed_per_name(session, marks):
    s = Serving(session)
    try:
        status, ok = s.post("check", {"landmarks": _lists(marks)})
        assert status == 200 and ok == {"names": {}, "set": [], "count": len(marks)}
        # what the page shows clean, transfer's own check takes
        validate_landmarks(marks, session.V, session.F, frame=frame_from_landmarks(session.V, session.F, marks),
                           min_count=10)
        bad = dict(marks)
        bad["exocanthion_l"], bad["exocanthion_r"] = marks["exocanthion_r"], marks["exocanthion_l"]
        bad["pronasale"] = marks["pronasale"] + 0.3 * session.frame.size * session.frame.rotation[2]
        status, got = s.post("check", {"landmarks": _lists(bad)})
        assert status == 200
        assert set(got["names"]) == {"exocanthion_l", "exocanthion_r", "pronasale"}, got
        assert "swapped" in got["names"]["exocanthion_l"][0] and "off the surface" in got["names"]["pronasale"][0]
        with pytest.raises(AutobonesError):  # the same set refused by the check transfer runs
            validate_landmarks(bad, session.V, session.F, frame=session.frame, min_count=10)
        few = {n: marks[n] for n in list(marks)[:4]}
        assert any("at least 10" in t for t in s.post("check", {"landmarks": _lists(few)})[1]["set"])
        mm = {n: p * 1000 for n, p in marks.items()}  # metres given for a mesh in millimetres
        assert any("wrong units" in t for t in s.post("check", {"landmarks": _lists(mm)})[1]["set"])
        status, err = s.post("check", {"landmarks": {"nose": [0, 0, 0]}})
        assert status == 422 and "unknown landmark name" in err["error"]  # the page sends only contract names
    finally:
        s.close()


def test_mirror_proposal_crosses_the_symmetry_plane_onto_the_surface(session, marks):
    s = Serving(session)
    try:
        ex = float(np.linalg.norm(marks["exocanthion_l"] - marks["exocanthion_r"]))
        for name in ("exocanthion_l", "endocanthion_r", "zygion_l", "tragion_r"):
            status, got = s.post("mirror", {"name": name, "point": list(marks[name])})
            assert status == 200 and got["name"] == name[:-1] + ("r" if name.endswith("_l") else "l")
            # the robot is symmetric: the proposal lands by the hand-placed partner
            assert np.linalg.norm(np.array(got["point"]) - marks[got["name"]]) < 0.1 * ex, (name, got)
        status, err = s.post("mirror", {"name": "pronasale", "point": list(marks["pronasale"])})
        assert status == 422 and "midline" in err["error"]
        # requests the page would never send: another page's origin, not JSON
        assert s.post("check", {"landmarks": {}}, {"Origin": "http://evil.example"})[0] == 403
        c = http.client.HTTPConnection("127.0.0.1", s.server.port, timeout=30)
        c.request("POST", f"/{s.server.token}/api/check", b"landmarks=1",
                  {"Content-Type": "application/x-www-form-urlencoded"})
        assert c.getresponse().status == 400
        c.close()
    finally:
        s.close()


def test_a_turned_and_scaled_glb_gets_the_same_proposals_in_its_own_frame(session, marks, tmp_path):
    """The mesh's own frame and units in and out: the robot turned 70 degrees and in millimetres, as a glb
    (load_mesh reads it as every other format), mirrors and checks its turned landmarks as the original."""
    import trimesh

    a = np.radians(70)
    R = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
    move = lambda P: 1000.0 * np.asarray(P) @ R.T + np.array([5.0, -20.0, 300.0])
    glb = tmp_path / "turned.glb"
    trimesh.Trimesh(move(session.V), session.F, process=False).export(glb)
    turned = open_session(str(glb), output=str(tmp_path / "t.json"), detect=False)
    ex = float(np.linalg.norm(marks["exocanthion_l"] - marks["exocanthion_r"]))
    for name in ("exocanthion_l", "zygion_r"):
        partner, p = session.mirror(name, marks[name])
        partner2, q = turned.mirror(name, move(marks[name]))
        assert partner2 == partner and np.linalg.norm(q - move(p)) < 0.02 * 1000 * ex, name
    assert turned.problems(_lists({n: move(p) for n, p in marks.items()}))["names"] == {}
    assert not os.path.exists(tmp_path / "t.json")


def test_save_writes_json_and_pp_atomically_and_done_stops(tmp_path, marks, monkeypatch):
    head = str(data(ROBOT))
    sess = open_session(head, output=str(tmp_path / "r.pp"), detect=False)
    assert sess.output == str(tmp_path / "r.landmarks.json") and sess.pp_output == str(tmp_path / "r.pp")
    s = Serving(sess)
    try:
        import autobones.io.atomic as atomic

        def broken(src, dst):
            raise OSError(28, "No space left on device")

        monkeypatch.setattr(atomic.os, "replace", broken)
        status, err = s.post("save", {"landmarks": _lists(marks)})
        assert status == 422 and "cannot write" in err["error"]
        assert os.listdir(tmp_path) == []  # no partial file, no temporary left behind
        monkeypatch.undo()
        status, got = s.post("save", {"landmarks": _lists(marks)})
        assert status == 200 and got["written"] == [sess.output, sess.pp_output]
        for path in got["written"]:
            back = read_landmarks(path)
            assert list(back) == list(marks) and all(np.array_equal(back[n], marks[n]) for n in marks)
        assert json.loads(Path(sess.output).read_text())["mesh"] == "robot_head_neutral.obj"
        status, got = s.post("done", {})
        assert status == 200 and got["done"]
        s.thread.join(10)
        assert not s.thread.is_alive()  # serve_forever returned
    finally:
        s.close()


def test_start_from_a_file_or_detection_or_empty_with_a_note(tmp_path, marks, monkeypatch):
    head = str(data(ROBOT))
    sess = open_session(head, output=str(tmp_path / "o.json"), source=str(ROBOT_MARKS))
    assert sess.page_facts()["start"] == _lists(marks) and "started from" in sess.note

    def no_face(*a, **k):
        from autobones.landmarks import NoFaceError

        raise NoFaceError("the head: no face found in the pictures; give the landmarks by hand")

    monkeypatch.setattr(autobones, "detect_landmarks", no_face)
    sess = open_session(head, output=str(tmp_path / "o.json"))
    assert sess.start == {} and sess.note.startswith("no landmarks found automatically") and "\n" not in sess.note
    with pytest.raises(AutobonesError, match="needs cheilion_l, cheilion_r placed first"):
        sess.assist(_lists(marks))  # the robot's file has no mouth corners
    given = _five(sess, marks)
    err = None
    try:
        got = sess.assist(_lists(given))
        assert set(got["points"]).isdisjoint(given) and set(got["points"]) == set(got["confidence"])
    except AutobonesError as exc:
        err = str(exc)
    import importlib.util

    if importlib.util.find_spec("autobones.landmarks.assist") is None:  # once it exists, its proposals come back
        assert err and "not available" in err
    assert not os.listdir(tmp_path)


def test_proposals_on_a_persons_face_are_landmarks_assists_own(tmp_path):
    # `landmarks --edit --assist FIVE` and `landmarks --assist FIVE -o OUT` propose the same names: on a
    # person's face the detector's where it finds them (found once per head), the fit's for the rest
    from autobones.io.landmarks import write_landmarks
    from autobones.landmarks.assist import REQUIRED, assist_landmarks

    marks = read_landmarks(LEE_MARKS)
    five = {n: marks[n] for n in REQUIRED}
    write_landmarks(str(tmp_path / "five.landmarks.json"), five)
    sess = open_session(str(data(LEE)), output=str(tmp_path / "o.json"), source=str(tmp_path / "five.landmarks.json"))
    assert sess.detection is None                        # started from the file: nothing detected yet
    out = sess.assist(_lists(five))
    got = out["points"]
    assisted = assist_landmarks(sess.V, sess.F, five, detected="auto")
    cli = assisted.points
    fit = assist_landmarks(sess.V, sess.F, five).points
    assert set(got) == set(cli) - set(five)
    for n in got:
        np.testing.assert_allclose(got[n], cli[n], atol=1e-9, err_msg=n)
    moved = [n for n in got if np.linalg.norm(cli[n] - fit[n]) > 1e-6]
    assert len(moved) >= 10, moved                       # the detector's names replaced the fit's
    # the page is told which: every name the detector moved is listed as its, and only proposed names
    assert set(moved) <= set(out["detected"]) == set(assisted.detected) - set(five), (moved, out["detected"])
    assert sess.detection                                # kept for the next proposal
    blind = open_session(str(data(LEE)), output=str(tmp_path / "o.json"), source=str(tmp_path / "five.landmarks.json"),
                         detect=False)
    out = blind.assist(_lists(five))
    for n, p in out["points"].items():
        np.testing.assert_allclose(p, fit[n], atol=1e-9, err_msg=n)
    assert out["detected"] == []
    assert blind.detection is None
    assert sorted(os.listdir(tmp_path)) == ["five.landmarks.json"]


def test_bad_input_is_one_line_exit_2_nothing_written(tmp_path, capsys, monkeypatch):
    sys.path.insert(0, str(ROOT))
    from cli.main import main

    head = tmp_path / "robot.obj"
    shutil.copy(data(ROBOT), head)
    (tmp_path / "bad.json").write_text('{"landmarks": {"nose": [0, 0, 0]}}')
    monkeypatch.chdir(tmp_path)
    busy = socket.socket()
    busy.bind(("127.0.0.1", 0))
    busy.listen(1)
    try:
        cases = [(["missing.obj"], "no such file"), (["robot.obj", "--from", "bad.json"], "unknown landmark name"),
                 (["robot.obj", "--from", "none.json"], "none.json"),
                 (["robot.obj", "--port", str(busy.getsockname()[1])], "in use"),
                 (["robot.obj", "--port", "http"], "whole number"),
                 (["robot.obj", "-o", "robot.obj"], "is the input file"),
                 (["robot.obj", "--pp", "x.txt"], ".pp")]
        before = sorted(os.listdir(tmp_path))
        for args, needle in cases:
            code = main(["landmarks", *args, "--edit", "--no-browser"])
            cap = capsys.readouterr()
            lines = cap.err.strip().splitlines()
            assert code == 2 and len(lines) == 1 and needle in lines[0], (args, cap.err)
            assert lines[0].startswith("autobones landmarks: error:") and cap.out == ""
        assert main(["landmarks", "robot.obj", "--port", "0"]) == 2  # --port alone: it goes with --edit
        assert "goes with --edit" in capsys.readouterr().err
        assert sorted(os.listdir(tmp_path)) == before
    finally:
        busy.close()


def test_cli_prints_the_url_and_stops_when_the_page_says_done(tmp_path):
    shutil.copy(data(ROBOT), tmp_path / "robot.obj")
    shutil.copy(ROBOT_MARKS, tmp_path / "robot.landmarks.json")
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    # -o naming the --from file outright edits it in place; the default name would be refused
    p = subprocess.Popen(CLI + ["landmarks", "robot.obj", "--edit", "--from", "robot.landmarks.json",
                                "-o", "robot.landmarks.json", "--no-browser", "--port", "0"],
                         cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        m = re.fullmatch(r"http://127\.0\.0\.1:(\d+)/([A-Za-z0-9_-]{22})/\n", p.stdout.readline())
        assert m
        c = http.client.HTTPConnection("127.0.0.1", int(m.group(1)), timeout=30)
        c.request("GET", f"/{m.group(2)}/api/editor")
        facts = json.loads(c.getresponse().read())
        assert facts["head"] == "robot.obj" and len(facts["start"]) == len(read_landmarks(ROBOT_MARKS))
        c.request("POST", f"/{m.group(2)}/api/done", b"{}", {"Content-Type": "application/json"})
        assert c.getresponse().status == 200
        out, err = p.communicate(timeout=30)
    finally:
        if p.poll() is None:
            p.kill()
    assert p.returncode == 0 and "Traceback" not in err and "nothing written" in err, err
    r = subprocess.run(CLI + ["landmarks", "robot.obj", "--edit", "--from", "robot.landmarks.json", "--no-browser"],
                       cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and "is the input file" in r.stderr, r.stderr


# ---------------------------------------------------------------- the page in a real browser

@pytest.fixture(scope="module")
def browser():
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    assert chromium, "headless Chromium is needed: apt-get install chromium (tools/test-setup.sh does)"
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=chromium, args=[
            "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist", "--no-sandbox"])
        yield b
        b.close()


HOOK = "window.autobonesEditor"


def _open(browser, url):
    page = browser.new_page(viewport={"width": 1200, "height": 800})
    errors = []
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.on("response", lambda r: errors.append(f"{r.status} {r.url}") if r.status >= 400 else None)
    page.on("request", lambda r: None if r.url.startswith((url, "data:")) else errors.append(f"outside request: {r.url}"))
    page.goto(url)
    page.wait_for_function(f"{HOOK} && ({HOOK}.ready || {HOOK}.error)", timeout=60000)
    assert page.evaluate(f"{HOOK}.error") is None, errors
    return page, errors


def _settle(page):
    page.wait_for_function(f"{HOOK}.idle()", timeout=30000)


def _visible_vertices(page, V, near, tol):
    """For each point of ``near`` ({name: (3,)}), the nearest vertex the camera sees, and the whole pixel
    it projects to: the surface under that pixel lies within ``tol`` of the vertex (a mouse event's
    position may be rounded to whole pixels, so a vertex on a silhouette, whose neighbour pixel misses
    the head, is passed over)."""
    out = {}
    for name, p in near.items():
        order = np.argsort(np.linalg.norm(V - p, axis=1))[:30]
        for i in order:
            x, y = np.rint(page.evaluate(f"{HOOK}.project({V[i].tolist()})"))
            hits = [page.evaluate(f"{HOOK}.surfaceAt({x + dx}, {y + dy})") for dx, dy in ((0, 0), (0.5, 0.5), (-0.5, -0.5))]
            if all(h is not None and np.linalg.norm(np.array(h) - V[i]) < tol for h in hits):
                out[name] = (int(i), (float(x), float(y)))
                break
    return out


def test_browser_places_drags_undoes_flags_and_saves(browser, tmp_path):
    marks = read_landmarks(LEE_MARKS)  # a smooth human head: 27 hand-placed names, 8838 vertices
    sess = open_session(str(data(LEE)), output=str(tmp_path / "lee.landmarks.json"), detect=False)
    V = sess.V
    ex = float(np.linalg.norm(marks["exocanthion_l"] - marks["exocanthion_r"]))
    s = Serving(sess)
    try:
        page, errors = _open(browser, s.server.url)
        # zoomed in as a person would (the wheel), so that a pixel is well under the 0.5 % asked for
        page.mouse.move(400, 400)
        for _ in range(18):
            page.mouse.wheel(0, -100)
        page.wait_for_timeout(200)
        targets = _visible_vertices(page, V, marks, 0.003 * ex)
        assert len(targets) >= 20 and {"pronasale", "stomion"} <= set(targets), \
            sorted(set(marks) - set(targets))
        # one left/right pair is kept back, to be placed the wrong way round below; ten others clicked
        base = next(b for b in ("endocanthion", "exocanthion", "alare", "cheilion") if {b + "_l", b + "_r"} <= set(targets))
        left, right = base + "_l", base + "_r"
        pair = {n: targets.pop(n) for n in (left, right)}
        targets = dict(list(targets.items())[:10])
        for name, (_, (x, y)) in targets.items():  # click each at its vertex's pixel
            page.evaluate(f"{HOOK}.select('{name}')")
            page.mouse.click(x, y)
            _settle(page)
        state = page.evaluate(f"{HOOK}.state()")
        for name, (i, _) in targets.items():
            assert name in state and state[name]["kind"] == "placed", (name, sorted(state))
            assert np.linalg.norm(np.array(state[name]["p"]) - V[i]) < 0.005 * ex, name

        # drag a placed point onto another vertex, then undo and redo
        name = "pronasale"
        i0 = targets[name][0]
        i1, (x1, y1) = targets["stomion"]
        x0, y0 = page.evaluate(f"{HOOK}.project({V[i0].tolist()})")
        page.mouse.move(x0, y0)
        page.mouse.down()
        for k in range(1, 9):
            page.mouse.move(x0 + (x1 - x0) * k / 8, y0 + (y1 - y0) * k / 8)
        page.mouse.up()
        _settle(page)
        moved = np.array(page.evaluate(f"{HOOK}.state()")[name]["p"])
        assert np.linalg.norm(moved - V[i1]) < 0.005 * ex
        page.keyboard.press("Control+z")
        _settle(page)
        assert np.linalg.norm(np.array(page.evaluate(f"{HOOK}.state()")[name]["p"]) - V[i0]) < 0.005 * ex
        page.keyboard.press("Control+Shift+z")
        _settle(page)
        assert np.linalg.norm(np.array(page.evaluate(f"{HOOK}.state()")[name]["p"]) - V[i1]) < 0.005 * ex
        page.click("#undo")
        _settle(page)
        assert np.linalg.norm(np.array(page.evaluate(f"{HOOK}.state()")[name]["p"]) - V[i0]) < 0.005 * ex

        # a left/right pair placed the wrong way round is flagged beside both names
        for nm, (_, (x, y)) in ((left, pair[right]), (right, pair[left])):
            page.evaluate(f"{HOOK}.select('{nm}')")
            page.mouse.click(x, y)
            _settle(page)
        for nm in (left, right):
            text = page.inner_text(f'.lm[data-name="{nm}"] .problem')
            assert "swapped" in text, (nm, text)
        page.click("#undo")
        page.click("#undo")
        _settle(page)
        assert page.inner_text(f'.lm[data-name="{left}"] .problem') == ""

        assert not os.path.exists(sess.output)  # nothing written before Save
        page.click("#save")
        page.wait_for_function(f"{HOOK}.saved", timeout=30000)
        saved = read_landmarks(sess.output)
        assert set(saved) == {n for n, m in page.evaluate(f"{HOOK}.state()").items() if m["kind"] == "placed"}
        for name, (i, _) in targets.items():
            assert np.linalg.norm(saved[name] - V[i]) < 0.005 * ex, name
        page.click("#done")
        page.wait_for_function(f"{HOOK}.done", timeout=30000)
        s.thread.join(10)
        assert not s.thread.is_alive()
        assert not errors, errors
        page.close()
    finally:
        s.close()


def _five(sess, marks):
    """The five names the assisted proposal needs, on the robot: its eye corners and nose tip, and mouth
    corners put on the surface below the nose (its file has none)."""
    fr = sess.frame
    given = {n: marks[n] for n in ("exocanthion_l", "exocanthion_r", "pronasale")}
    for side, n in ((1.0, "cheilion_l"), (-1.0, "cheilion_r")):
        guess = marks["pronasale"] + fr.size * (-0.15 * fr.rotation[1] + side * 0.1 * fr.rotation[0])
        given[n] = closest_on_surface(guess[None], sess.V, sess.F)[0]
    return given


def test_browser_proposes_the_rest_and_closing_without_save_leaves_no_file(browser, tmp_path, marks):
    sess = open_session(str(data(ROBOT)), output=str(tmp_path / "robot.landmarks.json"), detect=False)
    sess.start = _five(sess, marks)  # as --assist PARTIAL starts it
    s = Serving(sess)
    try:
        page, errors = _open(browser, s.server.url)
        _settle(page)
        state = page.evaluate(f"{HOOK}.state()")
        proposed = {n for n, m in state.items() if m["kind"] == "assist"}
        assert len(proposed) >= 20 and all(0 <= state[n]["conf"] <= 1 for n in proposed), state
        n = sorted(proposed)[0]
        assert "proposed by the fit (confidence" in page.inner_text(f'.lm[data-name="{n}"] .state')
        assert "by the generic head's fit" in page.inner_text("#note")
        page.click(f'.lm[data-name="{n}"] button.accept')
        _settle(page)
        assert page.evaluate(f"{HOOK}.state()")[n]["kind"] == "placed"
        x, y = page.evaluate(f"{HOOK}.project({marks['nasion'].tolist()})")
        page.evaluate(f"{HOOK}.select('nasion')")
        page.mouse.click(x, y)
        _settle(page)
        assert page.evaluate(f"{HOOK}.state()")["nasion"]["kind"] == "placed"
        assert page.locator(".lm img").count() == 44 and not errors, errors
        page.close()
    finally:
        s.close()
    assert os.listdir(tmp_path) == []


def test_browser_says_which_proposals_the_face_detector_made(browser, tmp_path):
    # on a person's face the proposals mix the detector's points and the fit's: each row says which
    from autobones.io.landmarks import write_landmarks
    from autobones.landmarks.assist import REQUIRED

    five = {n: p for n, p in read_landmarks(LEE_MARKS).items() if n in REQUIRED}
    write_landmarks(str(tmp_path / "five.landmarks.json"), five)
    sess = open_session(str(data(LEE)), output=str(tmp_path / "o.json"), source=str(tmp_path / "five.landmarks.json"))
    s = Serving(sess)
    try:
        page, errors = _open(browser, s.server.url)
        _settle(page)
        state = page.evaluate(f"{HOOK}.state()")
        by = {n: m.get("by") for n, m in state.items() if m["kind"] == "assist"}
        detected = {n for n, b in by.items() if b == "detector"}
        assert len(detected) >= 10 and len(by) - len(detected) >= 5, by   # both sources on a face
        d, f = sorted(detected)[0], sorted(set(by) - detected)[0]
        assert "proposed by the face detector (confidence" in page.inner_text(f'.lm[data-name="{d}"] .state')
        assert "proposed by the fit (confidence" in page.inner_text(f'.lm[data-name="{f}"] .state')
        assert f"{len(detected)} by the face detector" in page.inner_text("#note") and not errors, errors
        page.close()
    finally:
        s.close()
    assert sorted(os.listdir(tmp_path)) == ["five.landmarks.json"]
