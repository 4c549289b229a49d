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
