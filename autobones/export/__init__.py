"""Export a saved rig to other pipelines' formats: USD (UsdSkel) and FBX (through Blender).

Beyond the seeds (issue #17): the rig leaves autobones as glTF; film and game pipelines read
USD and FBX. Each writer reads what ``Rig.save`` writes (``x.glb`` + ``x.rig.json`` +
``x.weights.npz``) and imports its optional dependency (``usd-core``, Blender) only when called.
"""
from __future__ import annotations

import os

from ..errors import AutobonesError

USD_SUFFIXES = (".usd", ".usda", ".usdc", ".usdz")
FBX_SUFFIXES = (".fbx",)


def export_format(out_path):
    """``"usd"`` or ``"fbx"`` from ``out_path``'s suffix; AutobonesError for any other suffix."""
    ext = os.path.splitext(os.fspath(out_path))[1].lower()
    if ext in USD_SUFFIXES:
        return "usd"
    if ext in FBX_SUFFIXES:
        return "fbx"
    raise AutobonesError(f"{os.fspath(out_path)}: cannot tell the format from {ext or 'no suffix'!r}; "
                         f"export writes {', '.join(USD_SUFFIXES + FBX_SUFFIXES)}")

