"""The ICT-FaceKit heads benchmarks/expressions.py runs on, and how it scores and reports them.

The data's paths and the four expression meshes, the skin regions of the table (``REGIONS``), the
score ``explained`` and its per-region form (``region_masks``, ``region_scores``), ``rig_head``
(transfer, then the expression model), the copy-through baseline (``copy_through``), and the
number format and machine line of the printed tables. Shared by every part of that benchmark.
"""
from __future__ import annotations

import platform
import subprocess
import time
from pathlib import Path

import numpy as np

import autobones

ICT = Path(__file__).resolve().parents[2] / "shared" / "data" / "ict"
NEUTRAL = ICT / "generic_neutral_mesh.obj"
LANDMARKS = ICT / "generic_neutral_mesh.landmarks.json"
EXPRESSIONS = ["jawOpen", "mouthSmile_L", "eyeBlink_L", "browInnerUp_L"]
REGIONS = [("brow", ("forehead", "brow")), ("eyelids", ("eyelids",)), ("nose", ("nose",)),
           ("cheeks", ("cheeks",)), ("lips", ("lips",)), ("chin/jaw", ("chin", "jaw"))]


def explained(fitted, X, V, sel=None):
    """1 - ||fitted - X|| / ||X - V|| over the vertices ``sel`` (all if None); nan if nothing moves."""
    if sel is not None:
        fitted, X, V = fitted[sel], X[sel], V[sel]
    d = np.linalg.norm(X - V)
    return np.nan if d == 0 else 1.0 - np.linalg.norm(fitted - X) / d


def machine():
    """The tables' machine line: system, CPU model, core count, Python."""
    cpu = platform.processor() or ""
    try:
        for line in subprocess.run(["lscpu"], capture_output=True, text=True).stdout.splitlines():
            if line.startswith("Model name"):
                cpu = line.split(":", 1)[1].strip()
    except OSError:
        pass
    import os

    return (f"{platform.system()} {platform.machine()}, {cpu}, {os.cpu_count()} cores, "
            f"Python {platform.python_version()}")


def fmt(x):
    """A score as the tables print it: percent, one decimal; "-" for nan."""
    return "-" if np.isnan(x) else f"{100 * x:.1f}"


def copy_through(P_src, P_dst, gF, V_src, F_src, D_src, V_dst):
    """Per-vertex displacement copied from one head to another through the transfer's dense
    correspondence: each generic vertex g sits at P_src[g] on the source and P_dst[g] on the
    target; it takes the source displacement at its point (barycentric on the source triangle),
    and each target vertex takes the displacement at its closest point on the generic mesh laid
    on the target (P_dst, gF). Returns (n_dst, 3)."""
    from autobones.rig_transfer.under_skin import ride

    return ride(V_dst, P_dst, gF, ride(P_src, V_src, F_src, D_src))


def region_masks(rig, skin):
    """Named boolean masks: "all", "skin", "parts" (everything not skin: eyeballs, eyelashes,
    eye-occlusion shells, teeth, tongue...) and the skin's regions (transferred ``region``)."""
    labels = list(rig.field_labels["region"])
    reg = np.asarray(rig.fields["region"]).astype(int)
    out = {"all": np.ones(len(skin), bool), "skin": skin, "parts": ~skin}
    for name, members in REGIONS:
        out[name] = skin & np.isin(reg, [labels.index(m) for m in members if m in labels])
    return out


def region_scores(Y, X, V, masks):
    """explained per mask; nan ('-') where the mask carries under 10 % of the skin's
    displacement norm (a region the expression hardly moves)."""
    ds = np.linalg.norm((X - V)[masks["skin"]])
    out = {}
    for name, m in masks.items():
        d = np.linalg.norm((X - V)[m])
        out[name] = np.nan if (name not in ("all", "skin", "parts") and d < 0.1 * ds) or d == 0 else \
            explained(Y, X, V, m)
    return out


def rig_head(name, head, landmarks):
    """``autobones.transfer`` of ``head`` (path or (V, F)) with ``landmarks`` (path or dict), then
    ``ExpressionModel().fit``. Returns (rig, model, correspondence (n_generic, 3), region masks)."""
    from autobones.expressions.model import ExpressionModel

    t = time.perf_counter()
    det = {}
    rig = autobones.transfer(head, landmarks, details=det)
    model = ExpressionModel().fit(rig)
    print(f"rigged {name}: transfer + model fit {time.perf_counter() - t:.1f} s", flush=True)
    return rig, model, det["correspondence"], region_masks(rig, model.skin_)

