"""Pictures of ``autobones view`` for the README: gallery/view_rig.png and gallery/view_batch.png.

    python gallery/make_view_shots.py                  # both, made from scratch in a temporary folder
    python gallery/make_view_shots.py --only rig       # or: --only batch

``view_rig.png``: ICT identity 002 transferred with its AU morph targets (one per AU), shown by ``autobones view
head.glb``: the skin coloured by the jaw's weight (the full matrix of the npz), the jaw opened 12 degrees
with its slider, AU12 (lip corner puller) at 0.8 and AU6 at 0.5, landmarks (red) and muscles (pink: lines,
the sphincters as rings) on.
``view_batch.png``: ``autobones batch`` (place, sparse) on seven shared heads and one broken file, shown by
``autobones view rigs/``: thumbnails coloured by each vertex's dominant bone, status per file, the failed
file's one-line reason.

Needs Debian's ``chromium`` and the ``playwright`` Python package (``pip install -e '.[test]'``); the
browser is driven headless through ``executable_path``, never one playwright downloads. The meshes come
from ``../shared/data``.
"""
from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
import threading
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
DATA = ROOT.parent / "shared" / "data"
BATCH_HEADS = ["misc/robot_head_neutral.obj", "misc/robot_head_Surprised.obj", "misc/goathead.obj",
               "misc/fsaverage_head.obj", "misc/fran_cut.obj", "misc/demosthenes-low-res.obj",
               "mediapipe/canonical_face_model.obj"]


def serve(path):
    """A started :class:`autobones.view.ViewServer` for ``path`` (answering in a daemon thread). Open its
    ``url``: the only way in is the token URL it carries (``http://127.0.0.1:PORT/TOKEN/``)."""
    from autobones.view import make_server

    server = make_server(str(path))
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server


def open_page(browser, url, size=(1400, 860)):
    page = browser.new_page(viewport={"width": size[0], "height": size[1]})
    errors = []
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.goto(url)
    page.wait_for_function("window.autobonesViewer && (window.autobonesViewer.ready || window.autobonesViewer.error)",
                           timeout=120000)
    err = page.evaluate("window.autobonesViewer.error")
    if err or errors:
        raise SystemExit(f"{url}: the page failed: {err or errors}")
    return page


def save(page, name):
    from autobones.io.atomic import write_bytes_atomic

    out = HERE / name
    write_bytes_atomic(str(out), page.screenshot(), "the picture")
    print(out)


def rig_shot(browser, work):
    import autobones

    rig = autobones.transfer(DATA / "ict/identity002.obj", DATA / "ict/identity002.landmarks.json")
    rig.save(str(work / "identity002.glb"), expressions=True)
    server = serve(work / "identity002.glb")
    try:
        page = open_page(browser, server.url)
        page.select_option("#weight-source", "npz")
        page.select_option("#weight-bone", "jaw")
        page.wait_for_function("document.querySelector('#legend').textContent.includes('full matrix')")
        page.locator('input[data-bone="jaw"][data-axis="x"]').fill("12")
        page.locator('input[data-morph="AU12"]').fill("0.8")
        page.locator('input[data-morph="AU6"]').fill("0.5")
        page.check("#show-landmarks")
        page.check("#show-muscles")
        page.wait_for_timeout(500)
        save(page, "view_rig.png")
    finally:
        server.shutdown()
        server.server_close()


def batch_shot(browser, work):
    heads = work / "heads"
    for rel in BATCH_HEADS:
        dst = heads / Path(rel).parent.name / Path(rel).name
        dst.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(DATA / rel, dst)
    (heads / "misc" / "scan_export_broken.obj").write_text("v 0 0 0\nv 1 0 0\n")
    subprocess.run([sys.executable, "-m", "autobones", "batch", str(heads), "-o", str(work / "rigs"),
                    "--density", "sparse", "--jobs", "2", "-q"], check=False)  # exit 1: one file fails, on purpose
    server = serve(work / "rigs")
    try:
        page = open_page(browser, server.url)
        page.wait_for_function(f"window.autobonesViewer.thumbnailsLoaded() === {len(BATCH_HEADS)}", timeout=120000)
        page.select_option("#sort", "status")
        save(page, "view_batch.png")
    finally:
        server.shutdown()
        server.server_close()


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--only", choices=("rig", "batch"))
    args = ap.parse_args()
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    if not chromium:
        raise SystemExit("needs Chromium: apt-get install chromium")
    from playwright.sync_api import sync_playwright

    with tempfile.TemporaryDirectory() as tmp, sync_playwright() as p:
        browser = p.chromium.launch(executable_path=chromium, args=[
            "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist", "--no-sandbox"])
        if args.only in (None, "rig"):
            rig_shot(browser, Path(tmp))
        if args.only in (None, "batch"):
            batch_shot(browser, Path(tmp))
        browser.close()


if __name__ == "__main__":
    main()
