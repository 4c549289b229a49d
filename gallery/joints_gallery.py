"""``joints_side_views.png``: where ``place`` and ``transfer`` put the head, neck and jaw joints (issue #32).

    python gallery/make_gallery.py --only joints_side_views

Five heads from the left, each in its landmarks' own frame (``benchmarks/zoo_checks.landmark_frame``, the
frame ``benchmarks/joints.py`` measures in), the skin drawn lighter so the joints read: filled dots are
joints (``place``: head red, neck orange; ``transfer``: head blue, jaw green), hollow rings their
anatomical targets from the tragions (occiput-C1 centre of rotation red, condyle green; Chancey et al.
2007 scaled by ex-ex / 90 mm), the black dot the tragions' midpoint. The cow has no tragions (its
landmarks stop at the ear's top, superaurale): joints only.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import autobones
from autobones import render
from autobones.generic_rig import default_head_path
from autobones.io.landmarks import read_landmarks
from autobones.io.mesh import load_mesh

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
DATA = ROOT.parent / "shared" / "data"
sys.path.insert(0, str(ROOT / "benchmarks"))
import joints as jb  # noqa: E402
import zoo_checks as zc  # noqa: E402

# name -> (mesh, landmarks): relative to ../shared/data unless under the project (None: the default head);
# licences: the default head is the project's, ICT MIT, spot public domain, cow Apache-2.0, cat CC BY 4.0
SIDE_HEADS = {
    "default head": (None, "generic_rig/default_head.landmarks.json"),
    "ICT identity002": ("ict/identity002.obj", "ict/identity002.landmarks.json"),
    "spot (cow toy)": ("zoo/spot.obj", "zoo/spot.landmarks.json"),
    "cowHead": ("zoo/cowHead.obj", "zoo/cowHead.landmarks.json"),
    "cat": ("zoo/cat.obj", "zoo/cat.landmarks.json"),
}
JOINT_COLOURS = {"P head": (220, 30, 30), "P neck": (245, 150, 20), "T head": (30, 80, 230), "T jaw": (20, 160, 60)}
TARGET_COLOURS = {"C1": (220, 30, 30), "condyle": (20, 160, 60), "tragions": (0, 0, 0)}


def head_landmarks(mesh, marks):
    """(V, F, landmarks with the tragions of tests/landmarks where the shared file has none)."""
    V, F = load_mesh(default_head_path() if mesh is None else DATA / mesh)
    path = ROOT / marks if marks.startswith("generic_rig/") else DATA / marks
    return V, F, jb.with_tragions(read_landmarks(path), Path(marks).name.split(".")[0])


def panel(title, mesh, marks, size):
    """One side view with the joints and targets drawn; also the figures as text."""
    from PIL import Image, ImageDraw

    V, F, lm = head_landmarks(mesh, marks)
    ref = zc.landmark_frame(V, F, lm)
    u = zc.unit(lm, V)
    R = np.stack([ref["left"], ref["up"], ref["front"]])
    o = V.mean(axis=0)
    to = lambda P: (np.asarray(P, dtype=np.float64).reshape(-1, 3) - o) @ R.T / u  # noqa: E731
    prig, trig = autobones.place((V, F)), autobones.transfer((V, F), lm)
    points = {"P head": jb.joint(prig, "head"), "P neck": jb.joint(prig, "neck"),
              "T head": jb.joint(trig, "head"), "T jaw": jb.joint(trig, "jaw")}
    c1, condyle = jb.targets(lm, ref, u)
    targets = {} if c1 is None else {"C1": c1, "condyle": condyle,
                                     "tragions": 0.5 * (lm["tragion_l"] + lm["tragion_r"])}
    C = to(V)
    img = render.render_views(C, F, vertex_colors=np.full((len(V), 3), 0.93), views=("side",), size=(size, size))
    img = (0.55 * img + 0.45 * 255).astype(np.uint8)          # lighter skin: the joints inside read
    cam = render.orthographic_camera(C, (1.0, 0.0, 0.0), size=(size, size))
    for name, p in targets.items():
        px, _ = cam.project(to(p))
        img = render.draw_points(img, px, color=TARGET_COLOURS[name], radius=3 if name == "tragions" else 9,
                                 filled=name == "tragions")
    for name, p in points.items():
        if p is not None:
            px, _ = cam.project(to(p))
            img = render.draw_points(img, px, color=JOINT_COLOURS[name], radius=5)
    off = lambda name, t: np.linalg.norm(points[name] - t) / u  # noqa: E731
    figures = [] if c1 is None else [f"P head {off('P head', c1):.2f}, T head {off('T head', c1):.2f}",
                                     f"T jaw {off('T jaw', condyle):.2f} ex-ex"]
    pic = Image.fromarray(img)
    draw = ImageDraw.Draw(pic)
    draw.text((8, 6), title, fill=(0, 0, 0))
    for k, line in enumerate(figures or ["no tragions: joints only"]):
        draw.text((8, 22 + 14 * k), line, fill=(60, 60, 60))
    return np.asarray(pic), figures


def legend(width):
    from PIL import Image, ImageDraw

    pic = Image.new("RGB", (width, 28), (255, 255, 255))
    draw = ImageDraw.Draw(pic)
    x = 8
    for name, colour in JOINT_COLOURS.items():
        draw.ellipse((x, 9, x + 10, 19), fill=colour)
        draw.text((x + 14, 8), f"{name} joint", fill=(0, 0, 0))
        x += 110
    for name, colour in (("occiput-C1 target", TARGET_COLOURS["C1"]), ("condyle target", TARGET_COLOURS["condyle"])):
        draw.ellipse((x, 7, x + 14, 21), outline=colour, width=2)
        draw.text((x + 18, 8), name, fill=(0, 0, 0))
        x += 150
    draw.ellipse((x + 3, 11, x + 9, 17), fill=(0, 0, 0))
    draw.text((x + 14, 8), "tragions' midpoint (P = place, T = transfer)", fill=(0, 0, 0))
    return np.asarray(pic)


def joints_side_views(out, size=380):
    panels = []
    for title, (mesh, marks) in SIDE_HEADS.items():
        img, figures = panel(title, mesh, marks, size)
        panels.append(img)
        print(f"  {title}: {'; '.join(figures) or 'no tragions'}")
    row = np.concatenate(panels, axis=1)
    img = np.concatenate([row, legend(row.shape[1])], axis=0)
    path = Path(out) / "joints_side_views.png"
    render.save_png(path, img)
    print(f"{path}: {len(panels)} heads")
