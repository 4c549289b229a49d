"""The gallery's ARKit pictures (``arkit_shapes``, ``arkit_capture``; see ``make_gallery.py``'s docstring),
kept apart so that make_gallery.py stays a readable size. Run through ``python gallery/make_gallery.py``."""
from __future__ import annotations

from pathlib import Path

import numpy as np

import autobones
from autobones import render
from make_gallery import DATA, landmark_path, motion_strip

ARKIT_HEADS = {  # label: (mesh under ../shared/data, landmark file under ../shared/data or the project)
    "james (scan)": ("menpo3d/james.obj", "menpo3d/james.landmarks.json"),
    "ICT identity002 (sculpt)": ("ict/identity002.obj", "ict/identity002.landmarks.json"),
    "robot": ("misc/robot_head_neutral.obj", "tests/landmarks/robot_head_neutral.landmarks.json"),
    "goat": ("misc/goathead.obj", "tests/landmarks/goathead.landmarks.json"),
}
ARKIT_SHAPES = ("jawOpen", "mouthSmileLeft", "eyeBlinkLeft", "browInnerUp", "mouthPucker", "cheekPuff")


def arkit_rig(label):
    """The head ``label`` of :data:`ARKIT_HEADS` transferred with its ARKit shapes."""
    mesh, marks = ARKIT_HEADS[label]
    marks = landmark_path(marks)
    return autobones.transfer(DATA / mesh, marks, arkit=True)


def arkit_shapes_picture(out, width=2800):
    """``arkit_shapes.png``: each head of :data:`ARKIT_HEADS` transferred with ``arkit=True``, neutral
    and the :data:`ARKIT_SHAPES` posed at weight 1 by ``rig.pose(arkit=...)``, front view, one row a
    head at its own scale, tinted by motion relative to the row's largest."""
    rows = []
    for label in ARKIT_HEADS:
        rig = arkit_rig(label)
        poses = [rig.vertices] + [rig.pose(arkit={n: 1.0}) for n in ARKIT_SHAPES]
        flips = rig.arkit["flipped_triangles"]
        img, top = motion_strip(rig, poses, ["neutral"] + list(ARKIT_SHAPES), width, note=label)
        rows.append(img)
        print(f"{label}: largest motion {top:.3g} (mesh units); folded triangles "
              + ", ".join(f"{n} {flips.get(n, 0)}" for n in ARKIT_SHAPES))
    path = Path(out) / "arkit_shapes.png"
    render.save_png(path, np.concatenate(rows, axis=0))
    print(f"{path}: {', '.join(ARKIT_HEADS)}; neutral, {', '.join(ARKIT_SHAPES)}")


CAPTURE_HEAD = "ICT identity002 (sculpt)"  # key of ARKIT_HEADS
CAPTURE_FPS = 30.0
CAPTURE_FRAMES = {6: "blink", 21: "smile", 36: "jaw open", 53: "head turn, half smile"}  # frame: what peaks


def write_capture_csv(path, seconds=2.0, fps=CAPTURE_FPS):
    """A synthetic Live Link Face CSV (the layout :func:`autobones.arkit.capture.read_capture` reads):
    a blink peaking at 0.2 s, a smile at 0.7 s, the jaw open at 1.2 s, then the head turning 20
    degrees toward the subject's left (reached at 1.77 s, then held) with a half smile and the left
    brow raised; smooth bumps and ramps."""
    from autobones.arkit.names import ARKIT_NAMES, CAPTURE_ANGLES, capture_column

    t = np.arange(int(round(seconds * fps))) / fps

    def bump(start, end):  # 0 outside [start, end], sin^2 up to 1 at the middle
        x = np.clip((t - start) / (end - start), 0.0, 1.0)
        return np.sin(np.pi * x) ** 2

    w = {n: np.zeros_like(t) for n in ARKIT_NAMES}
    late = np.clip((t - 1.4) / 0.3, 0.0, 1.0)
    for side in ("Left", "Right"):
        w[f"eyeBlink{side}"] = bump(0.0, 0.4)
        w[f"mouthSmile{side}"] = bump(0.4, 1.0) + 0.5 * late
    w["jawOpen"] = 0.8 * bump(0.9, 1.5)
    w["browOuterUpLeft"] = late
    angles = {n: np.zeros_like(t) for n in CAPTURE_ANGLES}
    ramp = np.clip((t - 1.3) / 0.47, 0.0, 1.0)
    angles["HeadYaw"] = np.radians(20.0) * (3 * ramp ** 2 - 2 * ramp ** 3)
    header = ["Timecode", "BlendShapeCount"] + [capture_column(n) for n in ARKIT_NAMES] + list(CAPTURE_ANGLES)
    lines = [",".join(header)]
    for i in range(len(t)):
        s, f = divmod(i, int(fps))
        lines.append(",".join([f"00:00:{s:02d}:{f:02d}.000", str(len(ARKIT_NAMES) + len(CAPTURE_ANGLES))]
                              + [f"{w[n][i]:.5f}" for n in ARKIT_NAMES]
                              + [f"{angles[n][i]:.5f}" for n in CAPTURE_ANGLES]))
    Path(path).write_text("\n".join(lines) + "\n", encoding="utf-8")


def arkit_capture_picture(out, width=2000):
    """``arkit_capture.png``: a synthetic capture (:func:`write_capture_csv`) read by
    ``read_capture`` and played on :data:`CAPTURE_HEAD` at the frames :data:`CAPTURE_FRAMES` (and
    frame 0): the frame's ARKit weights posed by ``rig.pose(arkit=...)``, its head angles by the head
    bone (``rig.pose(head_deg=...)``, linear blend skinning) with the shapes' displacements turned
    with the head as a glTF player does (the face follows the head bone fully); front view, tinted
    by the shapes' displacement (not the head turn, which would swamp it)."""
    import tempfile

    from autobones.arkit.animation import canonical_turns
    from autobones.arkit.capture import read_capture

    rig = arkit_rig(CAPTURE_HEAD)
    with tempfile.TemporaryDirectory() as tmp:
        csv_path = Path(tmp) / "synthetic_live_link_face.csv"
        write_capture_csv(csv_path)
        cap = read_capture(csv_path, fps=CAPTURE_FPS)
    frames = {0: "rest", **CAPTURE_FRAMES}
    poses, labels, moved = [], [], []
    R, s = rig.frame.rotation, rig.frame.size
    for i, what in frames.items():
        weights = {n: float(v[i]) for n, v in cap.weights.items() if v[i] != 0}
        yaw, pitch, roll = (float(cap.angles[c][i]) for c in ("HeadYaw", "HeadPitch", "HeadRoll"))
        offset = rig.arkit_offset(weights)
        if not (yaw or pitch or roll):
            P = rig.vertices if offset is None else rig.vertices + offset
        else:
            P = rig.pose(head_deg=tuple(np.degrees([pitch, yaw, roll])))
            if offset is not None:  # canonical displacement, turned with the head, back to the input frame
                turn = canonical_turns([yaw], [pitch], [roll])[0]
                P = P + ((offset @ R.T / s) @ turn.T * s) @ R
        poses.append(P)
        moved.append(np.zeros(len(P)) if offset is None else np.linalg.norm(offset, axis=1))
        shown = ", ".join(f"{n} {v:.2f}" for n, v in sorted(weights.items()) if v >= 0.05) or "-"
        turn_text = f"; head yaw {np.degrees(yaw):.0f} deg" if yaw else ""
        labels.append(f"{cap.times[i]:.2f} s {what}")
        print(f"frame {i} ({cap.times[i]:.2f} s, {what}): {shown}{turn_text}")
    img, top = motion_strip(rig, poses, labels, width, moved=moved,
                            note=f"{CAPTURE_HEAD}, {len(cap.times)} frames at {CAPTURE_FPS:g} fps")
    path = Path(out) / "arkit_capture.png"
    render.save_png(path, img)
    print(f"{path}: {len(frames)} frames of {len(cap.times)}; largest shape motion {top:.3g} (mesh units)")


