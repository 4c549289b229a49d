"""Paths to the third-party meshes in ../shared/data, and small synthetic meshes for tests."""
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data"


def data(rel):
    """Path of a shared mesh; fails (never skips) when the shared folder is missing."""
    path = DATA / rel
    assert path.is_file(), f"missing test mesh {path}: the shared data folder must sit beside the checkout"
    return path


def icosphere(subdivisions=3, radius=1.0):
    import trimesh

    m = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)
    return np.asarray(m.vertices), np.asarray(m.faces)


BLENDER_SCRIPT = ROOT / "tests" / "blender_check.py"
BLENDER_INSTALL = "install it with: apt-get install blender python3-numpy (or bash tools/test-setup.sh)"


def run_blender_check(glb, report_path):
    """Run tests/blender_check.py on ``glb`` in headless Blender; return its JSON report.

    Fails (never skips) when Blender or its numpy is missing.
    """
    import json
    import os
    import shutil
    import subprocess

    import pytest

    blender = shutil.which("blender")
    if blender is None:
        pytest.fail(f"blender is not on PATH; {BLENDER_INSTALL}")
    cmd = [blender, "-b", "--factory-startup", "--python-exit-code", "1",
           "-P", str(BLENDER_SCRIPT), "--", str(glb), str(report_path)]
    # Blender's embedded (system) Python locates its standard library from the first
    # python3.X on PATH: a pyenv or virtualenv interpreter running pytest would hijack
    # it and hide the system numpy the glTF importer needs. Put Blender's own folder first.
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONHOME", "PYTHONPATH")}
    env["PATH"] = os.path.dirname(os.path.realpath(blender)) + os.pathsep + env.get("PATH", "")
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=300, env=env)
    log = (out.stdout + out.stderr)[-3000:]
    if "No module named 'numpy'" in log:
        pytest.fail(f"Blender's Python has no numpy, which its glTF importer needs; {BLENDER_INSTALL}\n{log}")
    assert out.returncode == 0 and os.path.exists(report_path), f"{' '.join(cmd)} failed:\n{log}"
    with open(report_path) as fh:
        return json.load(fh)
