"""``autobones view`` (autobones/view): path safety, 127.0.0.1 only, read-only, the CLI, and a real browser.

The browser tests drive the system's headless Chromium (Debian's ``chromium``; tools/test-setup.sh
installs it) through playwright, never a browser playwright downloads. They open the page on a
transferred rig with morph targets and on a batch output folder, read skinned vertices back from the
page (``window.autobonesViewer``) and check them against the glb's own arrays.
"""
import glob
import http.client
import io
import json
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import threading
import tomllib
from pathlib import Path

import numpy as np
import pytest

import autobones
from autobones.batch import make_options, run_batch
from autobones.errors import AutobonesError
from autobones.expressions.definitions import load_expressions
from autobones.io.gltf import read_accessor, read_glb
from autobones.view import make_server, resolve_under
from autobones.view.server import STATIC, Refused
from autobones.view.site import batch_listing, open_site
from shared_data import ROOT, data

CLI = [sys.executable, "-m", "cli.main"]
ROBOT = "misc/robot_head_neutral.obj"
ROBOT_MARKS = ROOT / "tests" / "landmarks" / "robot_head_neutral.landmarks.json"


def _env():
    return dict(os.environ, PYTHONPATH=str(ROOT))


@pytest.fixture(scope="module")
def rig_dir(tmp_path_factory):
    """A transferred robot rig with its AU morph targets (one per AU): robot.glb, .rig.json, .weights.npz."""
    d = tmp_path_factory.mktemp("rig")
    rig = autobones.transfer(data(ROBOT), ROBOT_MARKS)
    rig.save(str(d / "robot.glb"), expressions=True)
    return d


@pytest.fixture(scope="module")
def batch_dir(tmp_path_factory):
    """What ``autobones batch`` writes for two good meshes (one in a sub-folder) and one bad file."""
    base = tmp_path_factory.mktemp("batch")
    heads = base / "heads"
    (heads / "sub").mkdir(parents=True)
    shutil.copy(data(ROBOT), heads / "robot.obj")
    shutil.copy(data("misc/goathead.obj"), heads / "sub" / "goat.obj")
    (heads / "bad.obj").write_text("v 0 0 0\n")
    rep = run_batch(str(heads), str(base / "rigs"), make_options(density="sparse"), jobs=1)
    assert rep["counts"] == {"ok": 2, "failed": 1, "skipped": 0}
    return base / "rigs"


class Serving:
    """A ViewServer answering in a thread; ``get`` sends a raw request path (no client-side normalising),
    after the server's token (``/TOKEN/...``) unless ``token=False``."""

    def __init__(self, path):
        self.server = make_server(str(path))
        self.thread = threading.Thread(target=self.server.serve_forever, daemon=True)
        self.thread.start()

    def request(self, method, target, host=None, body=None, token=True):
        if token:
            target = f"/{self.server.token}{target}"
        c = http.client.HTTPConnection("127.0.0.1", self.server.port, timeout=30)
        c.putrequest(method, target, skip_host=True, skip_accept_encoding=True)
        c.putheader("Host", host or f"127.0.0.1:{self.server.port}")
        if body is not None:
            c.putheader("Content-Length", str(len(body)))
        c.endheaders(body)
        r = c.getresponse()
        out = (r.status, dict(r.getheaders()), r.read())
        c.close()
        return out

    def get(self, target, **kw):
        return self.request("GET", target, **kw)

    def close(self):
        self.server.shutdown()
        self.server.server_close()


@pytest.fixture(scope="module")
def batch_server(batch_dir):
    s = Serving(batch_dir)
    yield s
    s.close()


def _snapshot(folder):
    """{relative path: (size, mtime_ns)} of everything under ``folder``: proves nothing was written."""
    return {str(p.relative_to(folder)): (p.stat().st_size, p.stat().st_mtime_ns) for p in Path(folder).rglob("*")}


# ---------------------------------------------------------------- path safety and the server

def test_resolve_under_refuses_everything_outside_the_folder(tmp_path):
    root = tmp_path / "root"
    (root / "sub").mkdir(parents=True)
    (root / "sub" / "a.txt").write_text("a")
    (tmp_path / "secret.txt").write_text("secret")
    os.symlink(tmp_path / "secret.txt", root / "link_out.txt")
    os.symlink(tmp_path, root / "dir_out")
    os.symlink(root / "sub" / "a.txt", root / "link_in.txt")
    real = os.path.realpath(root)
    for bad in ["../secret.txt", "sub/../../secret.txt", "/etc/passwd", "%2e%2e/secret.txt", "..%2fsecret.txt",
                "sub/%2E%2E/%2e%2e/secret.txt", "C:/Windows", "sub\\..\\..\\secret.txt", ".hidden", "sub/.git/x",
                "link_out.txt", "dir_out/secret.txt", "a\x00b", "%00"]:
        with pytest.raises(Refused):
            resolve_under(real, bad)
    assert resolve_under(real, "sub/a.txt") == os.path.join(real, "sub", "a.txt")
    assert resolve_under(real, "./sub//a.txt") == os.path.join(real, "sub", "a.txt")
    assert resolve_under(real, "link_in.txt") == os.path.join(real, "sub", "a.txt")  # a link inside stays allowed
    assert resolve_under(real, "") == real


def test_server_refuses_traversal_writes_and_foreign_hosts(batch_dir, batch_server, tmp_path):
    s = batch_server
    outside = Path(batch_dir).parent / "heads" / "robot.obj"  # a real file just outside the folder served
    assert outside.is_file()
    os.symlink(outside, tmp_path / "x")  # (a link made elsewhere: the served folder itself is never written)
    before = _snapshot(batch_dir)
    for target in ["/files/../heads/robot.obj", "/files/%2e%2e/heads/robot.obj", "/files/sub/..%2f..%2fheads/robot.obj",
                   "/files//etc/passwd", "/files/.hidden", "/static/../server.py", "/static/%2e%2e/server.py",
                   "/api/thumb?path=../heads/robot.obj", "/api/rig?path=%2Fetc%2Fpasswd",
                   "/api/weights?path=..%2Fheads%2Frobot.obj&bone=neck"]:
        status, _, body = s.get(target)
        assert status == 403, (target, status, body[:200])
        assert b"v " not in body and b"root:" not in body
    assert s.get("/files/no_such.glb")[0] == 404
    assert s.get("/elsewhere")[0] == 404
    status, _, body = s.get("/files/robot.rig.glb")
    assert status == 200 and body == (Path(batch_dir) / "robot.rig.glb").read_bytes()
    status, headers, body = s.request("HEAD", "/files/robot.rig.glb")
    assert status == 200 and body == b"" and int(headers["Content-Length"]) == (Path(batch_dir) / "robot.rig.glb").stat().st_size
    for method in ("POST", "PUT", "DELETE", "PATCH"):
        status, headers, _ = s.request(method, "/files/robot.rig.glb", body=b"overwritten")
        assert status == 405 and headers.get("Allow") == "GET, HEAD", method
    # DNS rebinding: a page elsewhere that resolves its own name to 127.0.0.1 is refused
    assert s.get("/api/site", host="attacker.example")[0] == 403
    assert s.get("/api/site", host=f"localhost:{s.server.port}")[0] == 200
    assert _snapshot(batch_dir) == before


def test_listens_on_127_0_0_1_only(batch_server):
    port = batch_server.server.port
    assert batch_server.server.server_address[0] == "127.0.0.1"
    assert batch_server.server.url == f"http://127.0.0.1:{port}/{batch_server.server.token}/"
    others = ["127.0.0.2"]  # all of 127/8 is loopback on Linux: bound to 127.0.0.1 only, .2 must be refused
    try:  # the machine's own outward address, when it has one
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as u:
            u.connect(("10.255.255.255", 1))
            ip = u.getsockname()[0]
        if not ip.startswith("127."):
            others.append(ip)
    except OSError:
        pass
    for ip in others:
        with pytest.raises(OSError):
            socket.create_connection((ip, port), timeout=3).close()
    socket.create_connection(("127.0.0.1", port), timeout=3).close()


def test_api_serves_the_rig_facts_full_weights_and_thumbnails(batch_dir, batch_server):
    from PIL import Image

    s = batch_server
    before = _snapshot(batch_dir)
    site = json.loads(s.get("/api/site")[2])
    assert site["mode"] == "batch"
    listing = json.loads(s.get("/api/batch")[2])
    by_out = {f["output"]: f for f in listing["files"]}
    assert set(by_out) == {"bad.rig.glb", "robot.rig.glb", "sub/goat.rig.glb"}
    assert by_out["bad.rig.glb"]["status"] == "failed" and not by_out["bad.rig.glb"]["viewable"]
    assert "no faces" in by_out["bad.rig.glb"]["error"] and "\n" not in by_out["bad.rig.glb"]["error"]
    assert by_out["sub/goat.rig.glb"]["viewable"] and by_out["sub/goat.rig.glb"]["status"] == "ok"
    facts = json.loads(s.get("/api/rig?path=sub/goat.rig.glb")[2])
    meta = json.loads((Path(batch_dir) / "sub" / "goat.rig.json").read_text())
    assert [b["name"] for b in facts["bones"]] == [b["name"] for b in meta["bones"]]
    assert facts["frame"]["rotation"] == meta["frame"]["rotation"] and facts["vertices"] == meta["vertex_count"]
    assert facts["status"] == "ok" and set(facts["timings"]) and facts["seconds"] > 0  # from the batch record
    with np.load(Path(batch_dir) / "sub" / "goat.weights.npz") as z:
        names = [str(n) for n in z["bone_names"]]
        col = z["weights"][:, names.index("head")]
    w = json.loads(s.get("/api/weights?path=sub/goat.rig.glb&bone=head")[2])["weights"]
    assert len(w) == len(col) and np.abs(np.array(w) - col).max() < 1e-5
    assert s.get("/api/weights?path=sub/goat.rig.glb&bone=nope")[0] == 404
    assert s.get("/api/thumb?path=bad.rig.glb")[0] == 404
    status, headers, png = s.get("/api/thumb?path=sub/goat.rig.glb")
    assert status == 200 and headers["Content-Type"] == "image/png"
    img = np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(int)
    assert img.shape == (160, 320, 3)
    drawn = (np.abs(img - 255).sum(axis=2) > 30).mean()  # white background
    assert 0.05 < drawn < 0.9 and len(np.unique(img.reshape(-1, 3), axis=0)) > 50
    assert s.get("/api/thumb?path=sub/goat.rig.glb")[2] == png  # the cache (and the renderer) are deterministic
    assert _snapshot(batch_dir) == before  # read-only: no thumbnail or anything else written into the folder


def test_rig_facts_picture_a_sphincter_as_its_ring(rig_dir):
    from autobones.view.site import rig_facts

    facts = rig_facts(str(rig_dir), "robot.glb")
    meta = json.loads((rig_dir / "robot.rig.json").read_text())
    size = meta["frame"]["head_size"]
    rings = [m for m in facts["muscles"] if m["kind"] == "sphincter"]
    assert {m["type"] for m in rings} >= {"orbicularis_oris", "orbicularis_oculi"}
    for m in facts["muscles"]:
        S = np.array(m["segments"])
        if m["kind"] not in ("sphincter", "sheet"):
            assert S.shape == (1, 2, 3) and np.allclose(S[0], [m["origin"], m["insertion"]])
            continue
        # a chain of segments (closed, or half an ellipse for one side of the mouth) round the centre, about
        # as far out as the corner: the ring, not a line from the centre to the corner
        assert S.shape[0] >= 16 and np.allclose(S[1:, 0], S[:-1, 1])
        r = np.linalg.norm(S[:, 0] - np.array(m["origin"]), axis=1)
        corner = np.linalg.norm(np.subtract(m["insertion"], m["origin"]))
        assert r.max() > 0.6 * corner and r.max() < 4 * corner and corner > 0.01 * size
        if m["kind"] == "sphincter":
            assert r.min() > 0.3 * corner
        else:  # mentalis: a patch below the mouth line
            assert ((S[:, 0] - np.array(m["origin"])) @ np.array(meta["frame"]["rotation"][1]) < 0.1 * corner).all()
    # a sidecar whose frame is unreadable still lists every muscle, each by its two ends
    from autobones.view.site import _muscles
    plain = _muscles({"muscles": meta["muscles"], "frame": None})
    assert [len(m["segments"]) for m in plain] == [1] * len(meta["muscles"])


def test_thumbnails_are_drawn_once_per_file_version(batch_dir, tmp_path, monkeypatch):
    from autobones.view import thumbnails

    shutil.copytree(batch_dir, tmp_path / "c")
    glb = str(tmp_path / "c" / "robot.rig.glb")
    calls = []
    real = thumbnails.thumbnail_png
    monkeypatch.setattr(thumbnails, "thumbnail_png", lambda p, size: calls.append(p) or real(p, size))
    cache = thumbnails.ThumbnailCache(max_items=1)
    a = cache.get(glb)
    assert cache.get(glb) == a and len(calls) == 1
    os.utime(glb, ns=(0, os.stat(glb).st_mtime_ns + 10**9))  # the rig was rewritten: drawn again
    cache.get(glb)
    cache.get(str(tmp_path / "c" / "sub" / "goat.rig.glb"))  # max_items 1: the robot is dropped
    cache.get(glb)
    assert len(calls) == 4


def test_batch_listing_shows_the_sidecars_warnings(batch_dir, tmp_path):
    folder = tmp_path / "copy"
    shutil.copytree(batch_dir, folder)
    side = folder / "robot.rig.json"
    meta = json.loads(side.read_text())
    meta["landmarks_dropped"] = ["menton"]
    meta["arkit"] = {"flipped_triangles": {"eyeBlink_L": 3, "jawOpen": 0}}
    side.write_text(json.dumps(meta))
    (folder / "sub" / "goat.rig.json").unlink()
    files = {f["output"]: f for f in batch_listing(open_site(folder))["files"]}
    # the robot's front is a close call (0.3 % of the reference's overlay): the sidecar's, said once though
    # the batch record says it too
    assert [w["kind"] for w in files["robot.rig.glb"]["warnings"]] == ["landmarks dropped", "ARKit triangles turned over",
                                                                       "front a close call"]
    assert "menton" in files["robot.rig.glb"]["warnings"][0]["text"]
    assert "eyeBlink_L (3)" in files["robot.rig.glb"]["warnings"][1]["text"] and "jawOpen" not in files["robot.rig.glb"]["warnings"][1]["text"]
    assert [w["kind"] for w in files["sub/goat.rig.glb"]["warnings"]] == ["rig files missing"]
    assert not files["sub/goat.rig.glb"]["viewable"] and files["bad.rig.glb"]["warnings"] == []
    # without a report: every autobones glb under the folder
    (folder / "batch_report.json").unlink()
    site = open_site(folder)
    assert site.report is None and site.rigs == ["robot.rig.glb", "sub/goat.rig.glb"]


def test_batch_folders_named_before_the_rig_glb_rule_still_show(batch_dir, tmp_path):
    """Batches before issue #36's naming rule wrote ``NAME.glb``: such a folder (its report naming them)
    still lists and opens; an old ``NAME.glb`` left beside ``NAME.rig.glb`` (their sidecars shared) is
    not listed twice."""
    from autobones.view.site import rig_facts

    folder = tmp_path / "old"
    shutil.copytree(batch_dir, folder)
    rep = json.loads((folder / "batch_report.json").read_text())
    for f in rep["files"]:
        old = f["output"].removesuffix(".rig.glb") + ".glb"
        if (folder / f["output"]).exists():
            (folder / f["output"]).rename(folder / old)
        f["output"] = old
    (folder / "batch_report.json").write_text(json.dumps(rep))
    files = {f["output"]: f for f in batch_listing(open_site(folder))["files"]}
    assert sorted(files) == ["bad.glb", "robot.glb", "sub/goat.glb"]
    assert files["robot.glb"]["viewable"] and files["sub/goat.glb"]["viewable"]
    assert rig_facts(str(folder), "sub/goat.glb")["vertices"] == files["sub/goat.glb"]["vertices"]
    # without a report: the old names found; beside a NAME.rig.glb, only that one
    (folder / "batch_report.json").unlink()
    assert open_site(folder).rigs == ["robot.glb", "sub/goat.glb"]
    shutil.copy(folder / "robot.glb", folder / "robot.rig.glb")
    assert open_site(folder).rigs == ["robot.rig.glb", "sub/goat.glb"]


def test_bad_inputs_are_one_line_and_exit_2(rig_dir, tmp_path):
    import trimesh

    empty = tmp_path / "empty"
    empty.mkdir()
    other = tmp_path / "other"
    other.mkdir()
    trimesh.creation.icosphere().export(other / "sphere.glb")  # a glb, but not written by autobones
    (tmp_path / "notes.txt").write_text("hello")
    lonely = tmp_path / "lonely"
    lonely.mkdir()
    shutil.copy(rig_dir / "robot.glb", lonely / "robot.glb")  # its sidecars missing
    busy = socket.socket()
    busy.bind(("127.0.0.1", 0))
    busy.listen(1)
    try:
        cases = [([str(tmp_path / "missing.glb")], "no such file"), ([str(empty)], "no batch_report.json"),
                 ([str(other)], "no batch_report.json"), ([str(other / "sphere.glb")], "not a rig written by autobones"),
                 ([str(tmp_path / "notes.txt")], "not a .glb"), ([str(lonely / "robot.glb")], "sidecar"),
                 ([str(rig_dir / "robot.glb"), "--port", str(busy.getsockname()[1])], "in use"),
                 ([str(rig_dir / "robot.glb"), "--port", "http"], "whole number")]
        for args, needle in cases:
            r = subprocess.run(CLI + ["view", *args, "--no-browser"], cwd=ROOT, env=_env(), capture_output=True,
                               text=True, timeout=120)
            assert r.returncode == 2, (args, r.stdout, r.stderr)
            lines = r.stderr.strip().splitlines()
            assert len(lines) == 1 and lines[0].startswith("autobones view: error:") and needle in lines[0], (args, r.stderr)
            assert r.stdout == ""  # no URL for a page that will not be served
    finally:
        busy.close()
    with pytest.raises(AutobonesError):
        open_site(tmp_path / "notes.txt")


def test_cli_prints_the_url_first_and_stops_cleanly_on_ctrl_c(rig_dir):
    # Ctrl-C as at a terminal: a test run started as a background job (`pytest &`) has SIGINT ignored, which
    # the child would inherit (and Python then installs no KeyboardInterrupt handler)
    p = subprocess.Popen(CLI + ["view", str(rig_dir / "robot.glb"), "--no-browser"], cwd=ROOT, env=_env(),
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        first = p.stdout.readline()  # flushed at once: a script can read it while the server runs
        m = re.fullmatch(r"http://127\.0\.0\.1:(\d+)/([A-Za-z0-9_-]{22})/\n", first)  # the token URL
        assert m, first
        c = http.client.HTTPConnection("127.0.0.1", int(m.group(1)), timeout=30)
        c.request("GET", f"/{m.group(2)}/api/site")
        site = json.loads(c.getresponse().read())
        assert site == {"mode": "rig", "rig": "robot.glb", "title": "robot.glb"}
        p.send_signal(signal.SIGINT)  # with a browser's keep-alive connection still open (c)
        out, err = p.communicate(timeout=30)
        c.close()
    finally:
        if p.poll() is None:
            p.kill()
    assert p.returncode == 0 and "Traceback" not in err, err
    assert out == "" and "stopped" in err


def test_page_assets_are_bundled_and_installed(tmp_path):
    """The import map's files exist with three.js's licence, the page names no outside URL, and every
    file under static/ matches pyproject's package-data (what ``pip install .`` copies)."""
    index = (Path(STATIC) / "index.html").read_text()
    imports = json.loads(re.search(r'<script type="importmap">(.*?)</script>', index, re.S).group(1))["imports"]
    # relative URLs: the page lives under /TOKEN/, and so must every request it makes
    assert (Path(STATIC) / "vendor" / "three.module.min.js").is_file() and imports["three"] == "./static/vendor/three.module.min.js"
    for name in ("controls/OrbitControls.js", "loaders/GLTFLoader.js", "utils/BufferGeometryUtils.js"):
        assert (Path(STATIC) / imports["three/addons/"][len("./static/"):] / name).is_file()
    for page in ("index.html", "app.js"):
        assert not re.search(r"""(?:src|href)=["']/|['"`]/(?:api|files|static)/""", (Path(STATIC) / page).read_text()), page
    assert "MIT License" in (Path(STATIC) / "vendor" / "LICENSE").read_text()
    for page in ("index.html", "app.js", "style.css"):
        assert not re.search(r"https?://", (Path(STATIC) / page).read_text()), page  # offline: no CDN
    conf = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    assert "autobones.view" in conf["packages"]
    patterns = conf["package-data"]["autobones.view"]
    pkg = Path(STATIC).parent
    covered = {os.path.realpath(p) for pat in patterns for p in glob.glob(str(pkg / pat)) if os.path.isfile(p)}
    missed = [p.relative_to(pkg).as_posix() for p in Path(STATIC).rglob("*")
              if p.is_file() and os.path.realpath(p) not in covered]
    assert not missed, f"not installed by pip install .: {missed}"


# ---------------------------------------------------------------- a real browser

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


def _open(browser, url):
    """A page at ``url`` once the viewer is ready, and the list its console errors go to."""
    page = browser.new_page(viewport={"width": 1100, "height": 720})
    errors = []
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.on("requestfailed", lambda r: errors.append(f"request failed: {r.url} ({r.failure})"))

    # the page must need nothing but this server: no CDN, no web font, no outside request (watched, not
    # intercepted: playwright's interception reports a streamed fetch that completed as aborted); and every
    # request it makes (the glb, the API, the thumbnails) carries the token: it starts with the token URL
    page.on("request", lambda r: None if r.url.startswith((url, "data:")) else errors.append(f"outside request: {r.url}"))
    page.goto(url)
    page.wait_for_function("window.autobonesViewer && (window.autobonesViewer.ready || window.autobonesViewer.error)",
                           timeout=60000)
    assert page.evaluate("window.autobonesViewer.error") is None, errors
    return page, errors


def _axis_rotation(axis, angle):
    """(3, 3) right-handed rotation by ``angle`` radians about the unit ``axis`` (Rodrigues)."""
    a = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def _ramp(w):
    """The page's weight colours: exactly 0 grey, then blue, cyan, green, yellow, red at 1 (app.js RAMP)."""
    stops = np.array([[0.13, 0.25, 1.0], [0.0, 0.78, 1.0], [0.13, 0.82, 0.25], [1.0, 0.88, 0.0], [1.0, 0.13, 0.0]])
    t = np.minimum(w, 1) * 4
    i = np.minimum(np.floor(t), 3).astype(int)
    f = (t - i)[:, None]
    return np.where((w > 1e-4)[:, None], stops[i] * (1 - f) + stops[i + 1] * f, 0.8)


def _not_blank(png, min_drawn=0.05):
    from PIL import Image

    img = np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(int)
    background = np.median(img.reshape(-1, 3), axis=0)
    drawn = (np.abs(img - background).sum(axis=2) > 40).mean()
    assert drawn > min_drawn and len(np.unique(img.reshape(-1, 3), axis=0)) > 100, drawn
    return img


def test_browser_rig_page_poses_morphs_and_colours(rig_dir, browser):
    server = Serving(rig_dir / "robot.glb")
    try:
        page, errors = _open(browser, server.server.url)
        doc, body = read_glb(str(rig_dir / "robot.glb"))
        prim = doc["meshes"][0]["primitives"][0]
        P = read_accessor(doc, body, prim["attributes"]["POSITION"]).astype(np.float64)
        J = read_accessor(doc, body, prim["attributes"]["JOINTS_0"])
        Wt = read_accessor(doc, body, prim["attributes"]["WEIGHTS_0"])
        names = [doc["nodes"][j]["name"] for j in doc["skins"][0]["joints"]]
        meta = json.loads((rig_dir / "robot.rig.json").read_text())
        size = meta["frame"]["head_size"]
        hook = "window.autobonesViewer"
        assert page.evaluate(f"{hook}.bones") == names
        rest = np.array(page.evaluate(f"{hook}.positions()")).reshape(-1, 3)
        assert rest.shape == P.shape and np.abs(rest - P).max() < 1e-5 * size  # three.js skinning of the rest pose

        # the jaw's pitch slider, moved as a user does: the jaw's vertices move, the chin goes down, others stay
        page.locator('input[data-bone="jaw"][data-axis="x"]').fill("20")
        opened = np.array(page.evaluate(f"{hook}.positions()")).reshape(-1, 3)
        jaw_w = (Wt * (J == names.index("jaw"))).sum(axis=1)
        moved = np.linalg.norm(opened - rest, axis=1)
        assert moved.max() > 0.05 * size
        assert np.all(moved[jaw_w == 0] < 1e-6 * size)  # no jaw influence: not moved
        # exactly linear blend skinning with the jaw turned 20 degrees about the head frame's +X (pitch > 0
        # opens: a point in front of and below the pivot goes down) at the jaw bone's head
        jaw = next(b for b in meta["bones"] if b["name"] == "jaw")
        pivot, axis = np.array(jaw["head"]), np.array(meta["frame"]["rotation"][0])
        Rm = _axis_rotation(axis, np.radians(20.0))
        expect = rest + jaw_w[:, None] * ((rest - pivot) @ Rm.T + pivot - rest)
        assert np.abs(opened - expect).max() < 1e-4 * size

        # a morph target slider adds the glb's own displacement (before skinning, the jaw back at rest)
        page.click("#reset")
        targets = doc["meshes"][0]["extras"]["targetNames"]
        assert page.evaluate(f"{hook}.morphs") == targets
        assert len(targets) == len(load_expressions()["action_units"])
        k = targets.index("AU26") if "AU26" in targets else 0
        delta = read_accessor(doc, body, prim["targets"][k]["POSITION"]).astype(np.float64)
        page.locator(f'input[data-morph="{targets[k]}"]').fill("1")
        morphed = np.array(page.evaluate(f"{hook}.positions()")).reshape(-1, 3)
        assert np.abs(delta).max() > 1e-3 * size
        assert np.abs(morphed - (P + delta)).max() < 1e-4 * size

        # the skin coloured by the jaw's weight: no influence is grey, full influence is red
        page.select_option("#weight-bone", "jaw")
        page.wait_for_function(f"{hook}.weightColours()[0] !== undefined")
        col = np.array(page.evaluate(f"{hook}.weightColours()")).reshape(-1, 3)
        assert np.allclose(col, _ramp(jaw_w), atol=1e-5)
        page.select_option("#weight-source", "npz")  # the full matrix from the server
        page.wait_for_function("document.querySelector('#legend').textContent.includes('full matrix')")
        with np.load(rig_dir / "robot.weights.npz") as z:
            full = z["weights"][:, [str(b) for b in z["bone_names"]].index("jaw")]
        col = np.array(page.evaluate(f"{hook}.weightColours()")).reshape(-1, 3)
        assert np.allclose(col, _ramp(full), atol=1e-4)  # the npz column as the server sends it
        page.select_option("#weight-bone", "*")  # every vertex the colour of its largest influence, as the thumbnails
        from autobones.view.thumbnails import bone_palette
        col = np.array(page.evaluate(f"{hook}.weightColours()")).reshape(-1, 3)
        assert np.allclose(col, bone_palette(len(names))[J[np.arange(len(J)), np.argmax(Wt, axis=1)]], atol=1e-5)
        # muscles: at rest the page draws the sidecar's segments (a sphincter as its ring); turning the head
        # carries each ring rigidly (pairwise distances kept) with its centre's marker
        page.click("#reset")
        from autobones.view.site import rig_facts
        facts = rig_facts(str(rig_dir), "robot.glb")
        drawn = np.array(page.evaluate(f"{hook}.muscleLines()")).reshape(-1, 2, 3)
        want = [np.array(m["segments"]) for m in facts["muscles"]]
        assert drawn.shape[0] == sum(len(w) for w in want) > len(want)
        assert np.abs(drawn - np.concatenate(want)).max() < 1e-5 * size
        page.evaluate(f"{hook}.setBone('head', [10, 25, 0])")
        turned = np.array(page.evaluate(f"{hook}.muscleLines()")).reshape(-1, 2, 3)
        at = np.cumsum([0] + [len(w) for w in want])
        for m, a, b in zip(facts["muscles"], at[:-1], at[1:]):
            if m["kind"] not in ("sphincter", "sheet"):
                continue
            P0, P1 = drawn[a:b, 0], turned[a:b, 0]
            assert np.abs(P1 - P0).max() > 0.01 * size
            d0 = np.linalg.norm(P0[:, None] - P0[None], axis=2)
            assert np.abs(np.linalg.norm(P1[:, None] - P1[None], axis=2) - d0).max() < 1e-4 * size
        page.click("#reset")
        page.evaluate(f"{hook}.showOverlays(true)")
        page.wait_for_timeout(300)
        _not_blank(page.locator("#view canvas").screenshot())
        assert not errors, errors
        page.close()
    finally:
        server.close()


def _animated_copy(src, dst):
    """``dst``: the rig glb ``src`` (and its sidecars) with a 1 s glTF animation turning the jaw 25 degrees."""
    from autobones.io.gltf import pack_glb
    from autobones.rig import sidecar_paths

    doc, body = read_glb(str(src))
    jaw = next(i for i, nd in enumerate(doc["nodes"]) if nd.get("name") == "jaw")
    x, y, z, w = doc["nodes"][jaw].get("rotation", [0, 0, 0, 1])
    h = np.radians(25.0) / 2  # rest * (25 degrees about the joint's local x)
    c, sn = np.cos(h), np.sin(h)
    turned = [w * sn + x * c, y * c + z * sn, z * c - y * sn, w * c - x * sn]
    body = bytearray(body) + b"\0" * (-len(body) % 4)
    off = len(body)
    body += np.array([0.0, 1.0], np.float32).tobytes() + np.array([[x, y, z, w], turned], np.float32).tobytes()
    views, accs = len(doc["bufferViews"]), len(doc["accessors"])
    doc["bufferViews"] += [{"buffer": 0, "byteOffset": off, "byteLength": 8},
                           {"buffer": 0, "byteOffset": off + 8, "byteLength": 32}]
    doc["accessors"] += [{"bufferView": views, "componentType": 5126, "count": 2, "type": "SCALAR", "min": [0.0],
                          "max": [1.0]}, {"bufferView": views + 1, "componentType": 5126, "count": 2, "type": "VEC4"}]
    doc["animations"] = [{"name": "jaw", "samplers": [{"input": accs, "output": accs + 1}],
                          "channels": [{"sampler": 0, "target": {"node": jaw, "path": "rotation"}}]}]
    doc["buffers"][0]["byteLength"] = len(body)
    Path(dst).write_bytes(pack_glb(doc, bytes(body)))
    for a, b in zip(sidecar_paths(str(src)), sidecar_paths(str(dst))):
        shutil.copy(a, b)


def test_browser_plays_a_glb_animation(rig_dir, browser, tmp_path):
    _animated_copy(rig_dir / "robot.glb", tmp_path / "anim.glb")
    server = Serving(tmp_path / "anim.glb")
    try:
        page, errors = _open(browser, server.server.url)
        hook = "window.autobonesViewer"
        rest = np.array(page.evaluate(f"{hook}.positions()"))
        page.click("#play")
        page.wait_for_timeout(400)
        moving = np.array(page.evaluate(f"{hook}.positions()"))
        assert np.abs(moving - rest).max() > 1e-3
        assert not errors, errors
        page.close()
    finally:
        server.close()


def test_browser_batch_page_filters_and_opens_a_rig(batch_dir, browser, tmp_path):
    folder = tmp_path / "rigs"
    shutil.copytree(batch_dir, folder)
    meta = json.loads((folder / "robot.rig.json").read_text())
    meta["landmarks_dropped"] = ["menton"]  # one rig with a warning, as the detector writes it
    (folder / "robot.rig.json").write_text(json.dumps(meta))
    server = Serving(folder)
    try:
        page, errors = _open(browser, server.server.url)
        hook = "window.autobonesViewer"
        assert sorted(page.evaluate(f"{hook}.visible()")) == ["bad.rig.glb", "robot.rig.glb", "sub/goat.rig.glb"]
        assert "no faces" in page.locator('.card[data-output="bad.rig.glb"] .err').inner_text()
        assert "menton" in page.locator('.card[data-output="robot.rig.glb"] .warn').first.inner_text()
        page.wait_for_function(f"{hook}.thumbnailsLoaded() === 2", timeout=60000)
        _not_blank(page.screenshot(), min_drawn=0.05)
        page.uncheck('input[data-status="ok"]')
        assert page.evaluate(f"{hook}.visible()") == ["bad.rig.glb"]
        page.check('input[data-status="ok"]')
        page.select_option("#warning-filter", "some")
        assert page.evaluate(f"{hook}.visible()") == ["robot.rig.glb"]
        page.select_option("#warning-filter", "kind:landmarks dropped")
        assert page.evaluate(f"{hook}.visible()") == ["robot.rig.glb"]
        page.select_option("#warning-filter", "none")
        assert sorted(page.evaluate(f"{hook}.visible()")) == ["bad.rig.glb", "sub/goat.rig.glb"]
        page.uncheck('input[data-status="failed"]')
        page.fill("#search", "goat")
        assert page.evaluate(f"{hook}.visible()") == ["sub/goat.rig.glb"]
        page.click('.card[data-output="sub/goat.rig.glb"]')
        page.wait_for_function(f"{hook} && {hook}.mode === 'rig' && ({hook}.ready || {hook}.error)", timeout=60000)
        assert page.evaluate(f"{hook}.error") is None, errors
        assert page.evaluate(f"{hook}.rig") == "sub/goat.rig.glb" and "neck" in page.evaluate(f"{hook}.bones")
        assert page.evaluate(f"{hook}.facts.timings")  # the batch record's timings beside the rig
        assert not errors, errors
        page.close()
    finally:
        server.close()
