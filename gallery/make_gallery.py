"""Regenerate the gallery pictures from real autobones results.

    python gallery/make_gallery.py            # all pictures into gallery/ (needs ../shared/data)
    python gallery/make_gallery.py --out /tmp/pics --only default_head   # any folder; this one needs no shared data
    python gallery/make_gallery.py --only ict_neutral
    python gallery/make_gallery.py --only landmarks     # the four landmark previews below
    python gallery/make_gallery.py --only expressions   # the six emotions on four heads
    python gallery/make_gallery.py --only arkit         # arkit_shapes and arkit_capture

Each picture is a rig made by ``autobones.place`` right now (no cached data),
rendered by ``autobones.render`` from the front, three-quarter and side views in
the head's detected canonical frame: skin coloured by the skin weights (each
bone a colour, blended by weight), bones drawn as segments with their heads as
dots; a second row shows the face / middle / back depth groups and the facial
mask (fig. 1 of the bone-placement paper `place` implements).

``transfer_*``: the generic rig carried onto a landmarked head. ``landmarks_detected_*``:
landmarks found by ``autobones.detect_landmarks`` on three human heads of different
kinds (a scan, a sculpt, a statue), drawn by ``autobones.landmarks.preview`` from the front and
the side with each name's detection confidence; ``landmarks_given_goat``: the same
preview of a landmark file placed by hand (no face detector works on a goat).

``place_head_turn``: the head bone of a dense ``place`` rig turned 15 degrees (linear blend
skinning) on the default head, a bust, ICT's identity000 and the SMPL woman, the skin tinted orange
by how far each vertex moved (relative to the largest motion): the face and skull turn as one, the neck
twists, its base stays. ``transfer_head_turn``: the same on ``transfer`` rigs (ICT identity000, the SMPL
woman, Lee Perry-Smith, the cow) turned 30 degrees, the jaw turning whole to its lower border
(``gallery/head_turn_gallery.py``).

``joints_side_views``: five heads from the left (the default head, ICT identity002, spot, the cow, the
cat) with ``place``'s head and neck joints, ``transfer``'s head and jaw joints, and the occiput-C1 centre
and condyle predicted from the tragions as rings (``gallery/joints_gallery.py``).

``jaw_open_goat_robot``: the transferred jaw weight (green) on the goat and the robot, the jaw
closed and opened 20 degrees by linear blend skinning: no torn flap.

``transfer_teeth_jaw_open``: ICT identity001's 32 teeth and mouth bag alone, jaw weight in green, the jaw
opened 23 degrees by linear blend skinning; top: before ``rig_transfer/mouth_parts.py`` (the lower teeth
half left behind, the molars stretched), bottom: now (``gallery/teeth_gallery.py``).

``expressions_*``: the six emotion prototypes of ``generic_rig/expressions.json``
(Erdoğdu 2010, Table 3-3) on a transferred rig (default head, ICT identity002, the robot, the goat
and the james scan), neutral first, all from the front at one scale, in three rows: posed by
:class:`autobones.expressions.ExpressionModel` (the wire-deformer rig of Bibliowicz 2005), the
same with the layered tissue pass (``pose(tissue=True)``, Lee, Terzopoulos & Waters 1995), and
``pose``'s shapes layer (``pose(expression=..., layer="shapes")`` on a rig made with ``arkit=True``:
each emotion's AUs drive ICT-FaceKit's ARKit shapes carried onto the head through the ``au_arkit``
table; anger's AU23 and AU25 have no ARKit shape and are posed by the muscles on top);
the skin is tinted orange by how far each vertex moved (relative to the largest motion in the
picture).

``arkit_shapes``: the ARKit blendshapes carried by ``autobones.transfer(..., arkit=True)`` onto
four heads (rows, top to bottom: the james scan, the ICT identity002 sculpt, the robot, the goat),
columns neutral, jawOpen, mouthSmileLeft, eyeBlinkLeft, browInnerUp, mouthPucker, cheekPuff, each
posed at weight 1 by ``rig.pose(arkit=...)``; front view, one scale a head, tinted orange by motion
relative to the row's largest (ARKit's Left is the subject's left: the picture's right). The scan's
lips and lids are one closed surface, so its jawOpen stretches a closed mouth and its blink only
lowers the lid skin; the robot and the goat have no lids to close (their blinks dent the eyeball /
the skin above the eye).

``arkit_capture``: a synthetic 2 s, 30 fps Live Link Face CSV written in code (a blink, a smile,
the jaw opening, the head turning 20 degrees to the subject's left with a half smile and the left
outer brow up), read by ``autobones.arkit.capture.read_capture`` and played on ICT identity002 at
five frames (rest and each peak): the ARKit weights by ``rig.pose(arkit=...)``, the head yaw by the
head bone, the shapes turned with the head; front view, tinted by the shapes' displacement.
"""
from __future__ import annotations

import argparse
import colorsys
import os
import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np

import autobones
from autobones import render

HERE = Path(__file__).resolve().parent
DATA = HERE.parent.parent / "shared" / "data"

HEADS = {
    "default_head": (None, "dense"),
    "ict_neutral": ("ict/generic_neutral_mesh.obj", "dense"),
    "lee_perry_smith": ("misc/LeePerrySmith.obj", "medium"),
    "demosthenes": ("misc/demosthenes-low-res.obj", "medium"),
    "goat": ("misc/goathead.obj", "sparse"),
    "robot": ("misc/robot_head_neutral.obj", "sparse"),
}


def bone_colours(n):
    """(n, 3) distinct colours in [0, 1], golden-ratio hues."""
    return np.array([colorsys.hsv_to_rgb((0.13 + i * 0.618034) % 1.0, 0.65, 0.95) for i in range(n)])


def rig_picture(rig, size=420):
    C = rig.frame.to_canonical(rig.vertices)
    H = rig.frame.to_canonical(rig.skeleton.heads)
    T = rig.frame.to_canonical(rig.skeleton.tails)
    views = ("front", "three_quarter", "side")
    skin = rig.weights @ bone_colours(len(rig.skeleton))
    top = render.render_views(C, rig.faces, vertex_colors=skin, views=views, size=(size, size),
                              points=H, segments=np.stack([H, T], axis=1), point_color=(20, 20, 20),
                              segment_color=(20, 20, 20))
    groups = np.array([[0.9, 0.3, 0.3], [0.35, 0.75, 0.35], [0.35, 0.45, 0.9]])[rig.labels]
    groups[~rig.facial_mask & (rig.labels == 0)] = [0.85, 0.6, 0.85]  # face group below the chin (neck)
    bottom = render.render_views(C, rig.faces, vertex_colors=groups, views=views, size=(size, size))
    return np.concatenate([top, bottom], axis=0)


TRANSFERS = {  # name: (mesh, landmark file), relative to ../shared/data or the project
    "ict_identity002": ("ict/identity002.obj", "ict/identity002.landmarks.json"),
    "james": ("menpo3d/james.obj", "menpo3d/james.landmarks.json"),
    "goat": ("misc/goathead.obj", "tests/landmarks/goathead.landmarks.json"),
    "robot": ("misc/robot_head_neutral.obj", "tests/landmarks/robot_head_neutral.landmarks.json"),
}

EXPRESSION_HEADS = {  # name: (mesh or None for the default head, landmark file)
    "default_head": (None, "generic_rig/default_head.landmarks.json"),
    "ict_identity002": ("ict/identity002.obj", "ict/identity002.landmarks.json"),
    "robot": ("misc/robot_head_neutral.obj", "tests/landmarks/robot_head_neutral.landmarks.json"),
    "goat": ("misc/goathead.obj", "tests/landmarks/goathead.landmarks.json"),
    "james": ("menpo3d/james.obj", "menpo3d/james.landmarks.json"),
}

def landmark_path(rel):
    """A landmark file named in the tables above: in the project (``tests/``, ``generic_rig/``) or under
    ../shared/data."""
    return HERE.parent / rel if rel.startswith(("tests/", "generic_rig/")) else DATA / rel


REGION_COLOURS = np.array([colorsys.hsv_to_rgb((0.07 + i * 0.618034) % 1.0, 0.45, 0.95) for i in range(16)])


def transfer_picture(rig, size=420):
    """Top: jaw weights (green) with the skeleton (blue) and muscles (red); bottom: regions."""
    C = rig.frame.to_canonical(rig.vertices)
    views = ("front", "three_quarter", "side")
    jaw = rig.weights[:, rig.skeleton.names.index("jaw")]
    skin = np.array([0.85, 0.85, 0.85]) * (1 - jaw[:, None]) + np.array([0.15, 0.75, 0.2]) * jaw[:, None]
    bones = np.stack([rig.frame.to_canonical(rig.skeleton.heads), rig.frame.to_canonical(rig.skeleton.tails)], 1)
    muscles = render.muscle_segments(rig.muscles, rig.frame.to_canonical)   # lines, and rings for the sphincters
    top = render.render_views(C, rig.faces, vertex_colors=skin, views=views, size=(size, size),
                              segments=np.concatenate([bones, muscles]), points=bones[:, 0],
                              point_color=(20, 40, 200), segment_color=(200, 30, 30))
    regions = REGION_COLOURS[rig.fields["region"] % len(REGION_COLOURS)]
    bottom = render.render_views(C, rig.faces, vertex_colors=regions, views=views, size=(size, size))
    return np.concatenate([top, bottom], axis=0)


DETECTED = {  # name: mesh relative to ../shared/data; landmarks found automatically
    "james": "menpo3d/james.obj",                       # a scan
    "lee_perry_smith": "misc/LeePerrySmith.obj",        # a sculpt
    "demosthenes": "misc/demosthenes-low-res.obj",      # a statue
}
GIVEN = {  # name: (mesh, landmark file relative to the project)
    "goat": ("misc/goathead.obj", "tests/landmarks/goathead.landmarks.json"),
}
LANDMARK_PICTURES = [f"landmarks_detected_{k}" for k in DETECTED] + [f"landmarks_given_{k}" for k in GIVEN]


def landmark_picture(name, out):
    """Write ``landmarks_detected_<name>.png`` or ``landmarks_given_<name>.png`` into ``out``."""
    from autobones.io.landmarks import read_landmarks
    from autobones.io.mesh import load_mesh
    from autobones.landmarks.preview import save_preview

    path = Path(out) / f"{name}.png"
    if name.startswith("landmarks_detected_"):
        mesh = DATA / DETECTED[name[len("landmarks_detected_"):]]
        V, F = load_mesh(mesh)
        lm = autobones.detect_landmarks((V, F))
        save_preview(path, V, F, lm, frame=lm.frame, confidence=lm.confidence)
        extra = (f"; dropped {', '.join(lm.dropped) or '-'}; flagged {', '.join(lm.flagged) or '-'}; "
                 f"mean confidence {np.mean(list(lm.confidence.values())):.2f}")
    else:
        rel, marks = GIVEN[name[len("landmarks_given_"):]]
        V, F = load_mesh(DATA / rel)
        lm = read_landmarks(HERE.parent / marks)
        save_preview(path, V, F, lm)
        extra = f" from {marks}"
    print(f"{path}: {len(lm)} landmarks{extra}")


def expression_picture(name, out, size=420):
    """``expressions_<name>.png``: neutral and the six emotions side by side, front view, in three
    rows: the wire-deformer rig alone (Bibliowicz 2005), with the layered tissue pass (Lee,
    Terzopoulos & Waters 1995), and ``pose``'s shapes layer (:mod:`autobones.expressions.au_shapes`:
    the AUs the ``au_arkit`` table maps drive ICT-FaceKit's ARKit shapes carried onto the head, the
    others the muscles), what ``pose --expression`` gives on a rig made with ``--arkit``."""
    from autobones.expressions.definitions import au_arkit_table
    from autobones.expressions.model import ExpressionModel

    mesh, marks = EXPRESSION_HEADS[name]
    marks = landmark_path(marks)
    rig = autobones.transfer(None if mesh is None else DATA / mesh, marks, arkit=True)
    model = ExpressionModel().fit(rig)
    emotions = ["neutral"] + list(model.expressions)
    rows = {"wires": [], "wires + tissue": [], "shapes layer (ARKit)": []}
    table = {a for row in au_arkit_table(model.doc_) for a in row["au"]}
    unmapped = {e: [f"AU{au}" for au in model.expressions[e]["au"] if int(str(au).rstrip("LR")) not in table]
                for e in model.expressions}
    for e in emotions:
        if e == "neutral":
            for r in rows.values():
                r.append(rig.vertices)
            continue
        rows["wires"].append(model.pose(expression=e))
        rows["wires + tissue"].append(model.pose(expression=e, tissue=True))
        rows["shapes layer (ARKit)"].append(rig.pose(expression=e, layer="shapes"))
    V0 = rig.frame.to_canonical(rig.vertices)
    moved = {k: [np.linalg.norm(P - rig.vertices, axis=1) for P in r] for k, r in rows.items()}
    top = max(float(m.max()) for ms in moved.values() for m in ms) or 1.0
    step = 1.1 * float(np.ptp(V0[:, 0]))
    drop = 1.12 * float(np.ptp(V0[:, 1]))
    F = np.asarray(rig.faces)
    Vall, Fall, Call, marks_at, labels = [], [], [], [], []
    base = np.array([0.85, 0.85, 0.85])
    hot = np.array([1.0, 0.45, 0.1])
    for j, (row, poses) in enumerate(rows.items()):
        for k, (P, m) in enumerate(zip(poses, moved[row])):
            off = np.array([k * step, -j * drop, 0.0])
            V = rig.frame.to_canonical(P)
            Vall.append(V + off)
            Fall.append(F + sum(len(v) for v in Vall[:-1]))
            a = np.clip(m / top, 0.0, 1.0)[:, None] ** 0.7
            Call.append((1 - a) * base + a * hot)
            if j == 0 or k == 0:
                marks_at.append(np.array([V0[:, 0].mean(), V0[:, 1].min() - 0.03 * np.ptp(V0[:, 1]), V0[:, 2].max()])
                                + off)
                labels.append(emotions[k] if k else (row if j else f"{emotions[0]} | {row}"))
    V, F2, C = np.concatenate(Vall), np.concatenate(Fall), np.concatenate(Call)
    width = int(size * len(emotions) * step / max(drop, 1e-12) / 1.1) or size
    img = render.render_views(V, F2, vertex_colors=C, views=("front",), size=(width, size * len(rows)),
                              points=np.array(marks_at), point_labels=labels, point_color=(60, 60, 60))
    path = Path(out) / f"expressions_{name}.png"
    render.save_png(path, img)
    print(f"{path}: rows {', '.join(rows)}; columns {', '.join(emotions)}; largest motion {top:.3g} (mesh units); "
          "AUs without an ARKit shape (the muscles pose them in the shapes layer too): " + "; ".join(f"{e} {' '.join(u)}" for e, u in unmapped.items() if u))


SPHINCTER_HEADS = ("default_head", "ict_identity002", "james", "robot", "goat")  # keys of EXPRESSION_HEADS
SPHINCTER_AUS = (6, 18, 22, 23, 24)


def sphincters_picture(out, width=1800):
    """``expressions_sphincters.png``: the action units of the sphincters (Waters 1987's rings:
    orbicularis oculi for AU6, orbicularis oris for AU18, AU22, AU23, AU24) at intensity 1 on each head
    of :data:`SPHINCTER_HEADS`, front view, tinted by motion (one scale a row); one row a head."""
    from autobones.expressions.model import ExpressionModel

    rows = []
    for name in SPHINCTER_HEADS:
        mesh, marks = EXPRESSION_HEADS[name]
        marks = landmark_path(marks)
        rig = autobones.transfer(None if mesh is None else DATA / mesh, marks)
        model = ExpressionModel().fit(rig)
        poses = [rig.vertices] + [model.pose(au={a: 1.0}) for a in SPHINCTER_AUS]
        labels = [name] + [f"AU{a} {model.action_units[str(a)]['name'].lower()}" for a in SPHINCTER_AUS]
        img, top = motion_strip(rig, poses, labels, width)
        rows.append(img)
        print(f"{name}: largest motion {top:.3g} mesh units")
    path = Path(out) / "expressions_sphincters.png"
    render.save_png(path, np.concatenate(rows, axis=0))             # motion_strip makes each row ``width`` wide
    print(f"{path}: {', '.join(SPHINCTER_HEADS)}; AU{', AU'.join(map(str, SPHINCTER_AUS))}")


JAW_HEADS = ("goat", "robot")  # keys of TRANSFERS


def jaw_open_picture(out, degrees=20.0, size=380):
    """``jaw_open_goat_robot.png``: each head transferred, its jaw weight in green, closed and with
    the jaw bone turned ``degrees`` open by linear blend skinning (what a glTF viewer does), three
    quarter and side views; one row a head."""
    from teeth_gallery import opened_jaw

    rows = []
    for name in JAW_HEADS:
        mesh, marks = TRANSFERS[name]
        rig = autobones.transfer(DATA / mesh, HERE.parent / marks)
        C, opened, jaw, pivot = opened_jaw(rig, degrees)
        colours = np.array([0.85, 0.85, 0.85]) * (1 - jaw) + np.array([0.15, 0.75, 0.2]) * jaw
        views = ("three_quarter", "side")
        rows.append(np.concatenate([render.render_views(P, rig.faces, vertex_colors=colours, views=views,
                                                        size=(size, size), points=pivot[None],
                                                        point_color=(20, 40, 200))
                                    for P in (C, opened)], axis=1))
    path = Path(out) / "jaw_open_goat_robot.png"
    render.save_png(path, np.concatenate(rows, axis=0))
    print(f"{path}: {', '.join(JAW_HEADS)}, jaw closed and opened {degrees:g} degrees")


def symmetric_picture(out, size=360):
    """``transfer_symmetric_robot.png``: the robot transferred with the symmetric fit off (top) and on
    (bottom, ``--symmetric auto``), posed happy; front and up-from-below views tinted by motion, each
    row labelled with how much more the left moves than the right (area-weighted)."""
    from autobones.expressions.model import ExpressionModel
    from autobones.geometry.areas import vertex_areas
    from autobones.landmarks.refine import symmetry_plane

    mesh, marks = TRANSFERS["robot"]
    rows, poses = [], []
    for mode in ("off", "auto"):
        rig = autobones.transfer(DATA / mesh, HERE.parent / marks, symmetric=mode)
        poses.append((mode, rig, ExpressionModel().fit(rig).pose(expression="happiness")))
    top = max(float(np.linalg.norm(P - rig.vertices, axis=1).max()) for _, rig, P in poses)
    for mode, rig, P in poses:
        motion = np.linalg.norm(P - rig.vertices, axis=1)
        normal, offset = symmetry_plane({k: np.asarray(v) for k, v in rig.landmarks.items()})
        side = rig.vertices @ normal - offset
        area = vertex_areas(rig.vertices, rig.faces)   # area-weighted: the robot's vertices are not mirror pairs
        ratio = (area * motion)[side > 0].sum() / max((area * motion)[side < 0].sum(), 1e-300)
        a = np.clip(motion / top, 0.0, 1.0)[:, None] ** 0.7
        colours = (1 - a) * np.array([0.85, 0.85, 0.85]) + a * np.array([1.0, 0.45, 0.1])
        C = rig.frame.to_canonical(P)
        note = f"symmetric {mode}: left moves {ratio:.2f}x the right"
        mark = np.array([[C[:, 0].min(), C[:, 1].min() - 0.04, C[:, 2].max()]])
        rows.append(np.concatenate([
            render.render_views(C, rig.faces, vertex_colors=colours, views=(view,), size=(size, size),
                                points=mark if k == 0 else None, point_labels=[note] if k == 0 else None,
                                point_color=(40, 40, 40))
            for k, view in enumerate(("front", "three_quarter"))], axis=1))
        print(f"robot, symmetric {mode} ({'applied' if rig.options['symmetric']['applied'] else 'not applied'}): "
              f"happiness left/right motion {ratio:.3f}")
    path = Path(out) / "transfer_symmetric_robot.png"
    render.save_png(path, np.concatenate(rows, axis=0))
    print(f"{path}: the robot's happiness, symmetric fit off and auto")


def motion_strip(rig, poses, labels, width, note=None, moved=None):
    """Front views of ``poses`` (each (n, 3), input frame) side by side at one scale, ``width``
    pixels in all (the height follows the head's shape), the skin tinted orange by how far each
    vertex moved from the rest (or by ``moved``, one (n,) array a pose, mesh units), relative to
    the largest of all poses; each labelled below; ``note`` (str) is written under the strip's
    left end. Returns (image (h, w, 3) uint8, largest motion in mesh units)."""
    V0 = rig.frame.to_canonical(rig.vertices)
    if moved is None:
        moved = [np.linalg.norm(P - rig.vertices, axis=1) for P in poses]
    top = max(float(m.max()) for m in moved) or 1.0
    step = 1.1 * float(np.ptp(V0[:, 0]))
    F = np.asarray(rig.faces)
    Vall, Fall, Call, marks_at = [], [], [], []
    base = np.array([0.85, 0.85, 0.85])
    hot = np.array([1.0, 0.45, 0.1])
    below = V0[:, 1].min() - 0.04 * np.ptp(V0[:, 1])
    for k, (P, m) in enumerate(zip(poses, moved)):
        off = np.array([k * step, 0.0, 0.0])
        Vall.append(rig.frame.to_canonical(P) + off)
        Fall.append(F + k * len(P))
        a = np.clip(m / top, 0.0, 1.0)[:, None] ** 0.7
        Call.append((1 - a) * base + a * hot)
        marks_at.append(np.array([V0[:, 0].mean(), below, V0[:, 2].max()]) + off)
    labels = list(labels)
    if note is not None:  # a second marker line under the first column
        marks_at.append(np.array([V0[:, 0].min(), below - 0.06 * np.ptp(V0[:, 1]), V0[:, 2].max()]))
        labels.append(note)
    V, F2, C = np.concatenate(Vall), np.concatenate(Fall), np.concatenate(Call)
    height = float(np.ptp(V0[:, 1])) * 1.12
    size = max(int(width * 1.1 * height / (len(poses) * step)), 1)
    img = render.render_views(V, F2, vertex_colors=C, views=("front",), size=(width, size),
                              points=np.array(marks_at), point_labels=labels, point_color=(60, 60, 60))
    return img, top


ARKIT_PICTURES = ["arkit_shapes", "arkit_capture"]  # made by arkit_gallery.py


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--only", nargs="*", choices=sorted(HEADS) + [f"transfer_{k}" for k in TRANSFERS]
                    + LANDMARK_PICTURES + ["landmarks"] + [f"expressions_{k}" for k in EXPRESSION_HEADS]
                    + ["expressions", "expressions_sphincters", "jaw_open_goat_robot", "place_head_turn",
                       "transfer_head_turn", "transfer_symmetric_robot", "joints_side_views",
                       "transfer_teeth_jaw_open"]
                    + ARKIT_PICTURES + ["arkit"],
                    help="'landmarks': the four landmark previews; 'expressions': the emotions on four heads; "
                         "'arkit': arkit_shapes and arkit_capture")
    ap.add_argument("--out", default=str(HERE), metavar="DIR",
                    help="folder to write the pictures into (default: gallery/); it must exist. Pictures are made in "
                         "a temporary folder inside it and moved in only when every one is made")
    args = ap.parse_args(argv)
    expression_pictures = [f"expressions_{k}" for k in EXPRESSION_HEADS]
    names = args.only or (list(HEADS) + [f"transfer_{k}" for k in TRANSFERS] + LANDMARK_PICTURES
                          + expression_pictures + ["expressions_sphincters", "jaw_open_goat_robot", "place_head_turn",
                                                   "transfer_head_turn", "transfer_symmetric_robot", "joints_side_views",
                                                   "transfer_teeth_jaw_open"]
                          + ARKIT_PICTURES)
    names = [m for n in names for m in (LANDMARK_PICTURES if n == "landmarks" else
                                         expression_pictures if n == "expressions" else
                                         ARKIT_PICTURES if n == "arkit" else [n])]
    out = Path(args.out)
    if not out.is_dir():
        print(f"make_gallery: {out}: no such folder; create it or give another --out", file=sys.stderr)
        return 2
    if any(name != "default_head" for name in names) and not (DATA / "misc").is_dir():
        # the pictures are of the shared data set's heads (only tests/data's subset travels with the clone)
        print(f"make_gallery: needs the shared data set at {DATA} (ict/, misc/, menpo3d/, zoo/ with their "
              "landmarks, as ../shared/data beside the repository); not found, nothing written "
              "(--only default_head needs none)", file=sys.stderr)
        return 2
    staging = Path(tempfile.mkdtemp(prefix=".gallery-", dir=out))
    try:
        make(names, staging)
        made = sorted(staging.glob("*.png"))
        for path in made:  # every picture made: now they replace the old ones, each in one rename
            os.replace(path, out / path.name)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    print(f"{out}: {len(made)} picture{'' if len(made) == 1 else 's'} (made in a temporary folder, then moved in)")
    return 0


def make(names, out):
    """Make the pictures ``names`` into the folder ``out``."""
    args = argparse.Namespace(out=str(out))
    for name in names:
        if name == "arkit_shapes":
            from arkit_gallery import arkit_shapes_picture

            arkit_shapes_picture(args.out)
            continue
        if name == "arkit_capture":
            from arkit_gallery import arkit_capture_picture

            arkit_capture_picture(args.out)
            continue
        if name == "jaw_open_goat_robot":
            jaw_open_picture(args.out)
            continue
        if name == "joints_side_views":   # issue #32: the joints and their anatomical targets
            from joints_gallery import joints_side_views

            joints_side_views(args.out)
            continue
        if name in ("place_head_turn", "transfer_head_turn"):
            from head_turn_gallery import head_turn_picture

            head_turn_picture(args.out, command=name.split("_")[0])
            continue
        if name == "transfer_symmetric_robot":
            symmetric_picture(args.out)
            continue
        if name == "transfer_teeth_jaw_open":   # the mouth's separate parts (rig_transfer/mouth_parts.py)
            from teeth_gallery import teeth_picture

            teeth_picture(args.out)
            continue
        if name == "expressions_sphincters":
            sphincters_picture(args.out)
            continue
        if name.startswith("expressions_"):
            expression_picture(name[len("expressions_"):], args.out)
            continue
        if name.startswith("landmarks_"):
            landmark_picture(name, args.out)
            continue
        if name.startswith("transfer_"):
            mesh, marks = TRANSFERS[name[len("transfer_"):]]
            marks = landmark_path(marks)
            rig = autobones.transfer(DATA / mesh, marks)
            path = Path(args.out) / f"{name}.png"
            render.save_png(path, transfer_picture(rig))
            print(f"{path}: {len(rig.options['landmarks_used'])} landmarks, {len(rig.muscles)} muscles")
            continue
        rel, density = HEADS[name]
        rig = autobones.place(None if rel is None else DATA / rel, density=density)
        path = Path(args.out) / f"place_{name}.png"
        render.save_png(path, rig_picture(rig))
        print(f"{path}: {len(rig.skeleton)} bones, up {rig.frame.up}, front {rig.frame.front}")


if __name__ == "__main__":
    sys.exit(main())
