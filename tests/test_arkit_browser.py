"""three.js sees the 52 ARKit names (issue #15): ``autobones view`` on a rig made with
``transfer(..., arkit=True)``, opened in the system's headless Chromium through playwright (as
tests/test_view.py does: never a browser playwright downloads). The page's GLTFLoader parses the glb;
``window.autobonesViewer.morphs`` is the mesh's ``morphTargetDictionary`` keys in index order."""
import json
import re
import signal
import subprocess

import numpy as np
import pytest

import autobones
from autobones.arkit.names import ARKIT_NAMES
from autobones.expressions.definitions import load_expressions
from autobones.io.gltf import read_accessor, read_glb
from shared_data import ROOT, data
from test_view import CLI, ROBOT, ROBOT_MARKS, _env, _open, browser  # noqa: F401  (browser: a fixture)


@pytest.fixture(scope="module")
def arkit_rig(tmp_path_factory):
    """The robot transferred with its 52 ARKit shapes, saved with its 20 AU morph targets too."""
    d = tmp_path_factory.mktemp("arkit_view")
    rig = autobones.transfer(data(ROBOT), ROBOT_MARKS, arkit=True)
    rig.save(str(d / "robot.glb"), expressions=True)
    return d / "robot.glb"


def test_threejs_sees_the_52_arkit_names_and_jaw_open_moves_by_the_glbs_displacement(arkit_rig, browser):  # noqa: F811
    doc, body = read_glb(str(arkit_rig))
    mesh = doc["meshes"][0]
    prim = mesh["primitives"][0]
    names = mesh["extras"]["targetNames"]
    aus = [n for n in names if re.fullmatch(r"AU\d+[LR]?", n)]
    n_aus = len(load_expressions()["action_units"])
    assert len(aus) == n_aus and names == aus + list(ARKIT_NAMES)  # the file: AUs, then ARKit's 52
    size = json.loads(arkit_rig.with_suffix("").with_suffix(".rig.json").read_text())["frame"]["head_size"]

    p = subprocess.Popen(CLI + ["view", str(arkit_rig), "--no-browser"], cwd=ROOT, env=_env(),
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        url = p.stdout.readline().strip()
        assert re.fullmatch(r"http://127\.0\.0\.1:\d+/[A-Za-z0-9_-]{22}/", url), (url, p.poll())
        page, errors = _open(browser, url)
        hook = "window.autobonesViewer"
        # GLTFLoader's morphTargetDictionary: exactly the AUs and ARKit's 52 names, each at its glb index
        seen = page.evaluate(f"{hook}.morphs")
        assert seen == names, seen
        assert [n for n in seen if not n.startswith("AU")] == list(ARKIT_NAMES)
        # jawOpen at 1: three.js's morphed (and rest-skinned) vertices are the glb's rest + its jawOpen target
        P = read_accessor(doc, body, prim["attributes"]["POSITION"]).astype(np.float64)
        delta = read_accessor(doc, body, prim["targets"][names.index("jawOpen")]["POSITION"]).astype(np.float64)
        rest = np.array(page.evaluate(f"{hook}.positions()")).reshape(-1, 3)
        assert rest.shape == P.shape and np.abs(rest - P).max() < 1e-5 * size
        page.evaluate(f"{hook}.setMorph('jawOpen', 1)")
        opened = np.array(page.evaluate(f"{hook}.positions()")).reshape(-1, 3)
        assert np.linalg.norm(delta, axis=1).max() > 1e-2 * size  # the shape really moves the robot's mouth
        assert np.abs(opened - (P + delta)).max() < 1e-4 * size
        # the slider named jawOpen drives the same target (a user's way in)
        page.evaluate(f"{hook}.reset()")
        page.locator('input[data-morph="jawOpen"]').fill("1")
        slid = np.array(page.evaluate(f"{hook}.positions()")).reshape(-1, 3)
        assert np.abs(slid - opened).max() < 1e-6 * size
        assert not errors, errors
        page.close()
    finally:
        if p.poll() is None:
            p.send_signal(signal.SIGINT)
            try:
                p.communicate(timeout=30)
            except subprocess.TimeoutExpired:
                p.kill()
