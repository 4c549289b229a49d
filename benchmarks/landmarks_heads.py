"""The heads ``benchmarks/landmarks.py`` measures, relative to the shared data set (``../shared/data``)."""
from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data"
HEADS = {  # name: (mesh, published landmarks), relative to DATA
    "ict neutral": ("ict/generic_neutral_mesh.obj", "ict/generic_neutral_mesh.landmarks.json"),
    "ict identity000": ("ict/identity000.obj", "ict/identity000.landmarks.json"),
    "ict identity001": ("ict/identity001.obj", "ict/identity001.landmarks.json"),
    "ict identity002": ("ict/identity002.obj", "ict/identity002.landmarks.json"),
    "menpo3d template": ("menpo3d/template.ply", "menpo3d/template.landmarks.json"),
    "menpo3d james": ("menpo3d/james.obj", "menpo3d/james.landmarks.json"),
}
QUICK_HEADS = ["ict neutral", "ict identity001", "menpo3d james"]
ICT = ["ict neutral", "ict identity000", "ict identity001", "ict identity002"]
NO_FACE = {"goat": "misc/goathead.obj", "koala": "misc/koala_low_resolution.obj",
           "robot": "misc/robot_head_neutral.obj"}
# --time adds heads without published landmarks: a denser scan, and a bust scan's density ("loop x2":
# demosthenes Loop-subdivided twice when the table is made)
TIME_HEADS = {**{h: m for h, (m, _) in HEADS.items()}, "LeePerrySmith": "misc/LeePerrySmith.obj",
              "demosthenes": "misc/demosthenes-low-res.obj", "demosthenes loop x2": "misc/demosthenes-low-res.obj"}
