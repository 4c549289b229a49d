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


def export_rig(rig_path, out_path, **kwargs):
    """Write the rig saved as ``rig_path`` (a glb written by autobones, sidecars beside it) to
    ``out_path``, the format chosen by its suffix (:data:`USD_SUFFIXES`: :func:`.usd.write_usd`;
    ``.fbx``: :func:`.fbx.write_fbx`). Returns the writer's result."""
    fmt = export_format(out_path)
    if fmt == "usd":
        from .usd import write_usd

        return write_usd(rig_path, out_path, **kwargs)
    from .fbx import write_fbx

    return write_fbx(rig_path, out_path, **kwargs)
