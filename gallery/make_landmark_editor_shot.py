"""A picture of ``autobones landmarks HEAD --edit`` for the README and the docs: gallery/landmark_editor.png.

    python gallery/make_landmark_editor_shot.py                 # into gallery/
    python gallery/make_landmark_editor_shot.py --out /tmp/pics

The cow of the shared data set (``zoo/cowHead.obj``, no face detector knows it) opened in the editor with
about half of its hand-placed landmarks (``zoo/cowHead.landmarks.json``: 8 of its 15 names, the five the
assisted proposal needs among them) as if read with ``--from``; the page then proposes every other name
from them (hollow markers, each with its confidence), checks the set as ``transfer`` would, and shows
beside each name where it goes on the generic head. The view is turned to three quarters by a mouse drag,
as a person would, and one proposed name is selected. Nothing is saved.

Needs Debian's ``chromium`` and the ``playwright`` Python package (``pip install -e '.[test]'``); the browser
is driven headless through ``executable_path``, never one playwright downloads.
"""
from __future__ import annotations

import argparse
import shutil
import sys
import threading
from pathlib import Path

HERE = Path(__file__).resolve().parent
DATA = HERE.parent.parent / "shared" / "data"
HEAD = "zoo/cowHead.obj"
MARKS = "zoo/cowHead.landmarks.json"
# about half the hand-placed names: the five the proposal needs, and three midline ones to hold the frame
PLACED = ("vertex", "nasion", "pronasale", "menton", "exocanthion_l", "exocanthion_r", "cheilion_l", "cheilion_r")
SELECTED = "glabella"
DRAG = (-40, 0)  # pixels: the view turned toward the cow's right side, a little from above


def shoot(out_png):
    from playwright.sync_api import sync_playwright

    from autobones.io.atomic import write_bytes_atomic
    from autobones.io.landmarks import read_landmarks
    from autobones.view.editor_server import make_editor_server
    from autobones.view.landmark_session import open_session

    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    if chromium is None:
        raise SystemExit("make_landmark_editor_shot: needs Debian's chromium (apt-get install chromium)")
    marks = read_landmarks(DATA / MARKS)
    # -o as a person gives it, a name in the current folder (the page shows it); never saved here
    session = open_session(str(DATA / HEAD), output="cowHead.landmarks.json", detect=False)
    session.start = {n: marks[n] for n in PLACED}
    session.note = f"started from cowHead.landmarks.json ({len(PLACED)} of its {len(marks)} names)"
    server = make_editor_server(session)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=chromium, args=[
                "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist", "--no-sandbox"])
            page = browser.new_page(viewport={"width": 1400, "height": 860})
            errors = []
            page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
            page.goto(server.url)
            hook = "window.autobonesEditor"
            page.wait_for_function(f"{hook} && ({hook}.ready || {hook}.error)", timeout=120000)
            page.wait_for_function(f"{hook}.idle()", timeout=120000)
            if page.evaluate(f"{hook}.error") or errors:
                raise SystemExit(f"make_landmark_editor_shot: the page failed: {page.evaluate(f'{hook}.error') or errors}")
            page.mouse.move(300, 760)  # a drag on empty background turns the view to three quarters
            page.mouse.down()
            page.mouse.move(300 + DRAG[0], 760 + DRAG[1], steps=12)
            page.mouse.up()
            for _ in range(4):
                page.mouse.wheel(0, -100)
            page.evaluate(f"{hook}.select('{SELECTED}')")
            page.wait_for_timeout(600)  # the name pictures and the last frame
            page.wait_for_function("[...document.querySelectorAll('.lm img')].every((i) => "  # those in sight
                                   "i.getBoundingClientRect().top > innerHeight || (i.complete && i.naturalWidth > 0))",
                                   timeout=60000)
            page.wait_for_timeout(300)
            png = page.screenshot()
            browser.close()
    finally:
        server.shutdown()
        server.server_close()
    write_bytes_atomic(out_png, png, "the picture")
    return out_png


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default=str(HERE), help="folder to write landmark_editor.png in (default: gallery/)")
    args = ap.parse_args(argv)
    if not (DATA / MARKS).is_file():
        print(f"make_landmark_editor_shot: needs the shared data set at {DATA} ({HEAD} and its landmarks); "
              "not found, nothing written", file=sys.stderr)
        return 2
    print(shoot(Path(args.out) / "landmark_editor.png"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
