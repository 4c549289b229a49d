"""Rebuild ``autobones/sample_data/`` (what ``autobones samples DIR`` writes) from ``tests/data``.

Run from the repository root: ``python tools/build_samples.py``. The meshes are the test meshes
(``tests/data``, licences in ``tests/data/LICENSES.md``) whose licences allow redistribution, stored
gzipped as the OBJ text ``tests/shared_data.py`` writes (so the landmark files, made in the
original OBJ frames, stay exact). The bust's landmarks are found by ``autobones landmarks`` (the
Demosthenes scan has no hand-placed ones); the capture CSV is synthetic (made here).
"""
import gzip
import math
import shutil
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT))

OUT = ROOT / "autobones" / "sample_data"
# sample name -> (family, mesh in tests/data, its landmark file)
HEADS = {
    "scan": ("menpo3d", "james.obj", ROOT / "tests/data/menpo3d/james.landmarks.json"),
    "bust": ("misc", "demosthenes-low-res.obj", None),  # landmarks detected below
    "robot": ("misc", "robot_head_neutral.obj", ROOT / "tests/landmarks/robot_head_neutral.landmarks.json"),
    "goat": ("misc", "goathead.obj", ROOT / "tests/landmarks/goathead.landmarks.json"),
}


def main():
    import numpy as np

    from shared_data import data, mesh_bytes

    OUT.mkdir(exist_ok=True)
    for name, (family, mesh, lm) in HEADS.items():
        with np.load(ROOT / "tests" / "data" / family / "meshes.npz") as z:
            text = mesh_bytes(z, mesh, f"{family}/{mesh}")
        # mtime 0: the same bytes on every rebuild, so git sees no change when nothing changed
        (OUT / f"{name}.obj.gz").write_bytes(gzip.compress(text, compresslevel=9, mtime=0))
        if lm is not None:
            shutil.copyfile(lm, OUT / f"{name}.landmarks.json")
        else:
            write_detected(data(f"{family}/{mesh}"), OUT / f"{name}.landmarks.json", f"{name}.obj")
    (OUT / "take.csv").write_text(capture_csv())
    print(f"wrote {OUT}")


def write_detected(mesh, out, mesh_name):
    """The contract's landmarks found automatically on ``mesh`` (needs autobones[landmarks])."""
    import autobones
    from autobones.io.landmarks import write_landmarks

    lm = autobones.detect_landmarks(str(mesh))
    write_landmarks(out, lm, mesh_name=mesh_name, confidence=lm.confidence)


def capture_csv(seconds=1.5, fps=60):
    """A short synthetic Live Link Face take: a smile that rises and falls, one blink, the jaw
    opening a little, the head turning 10 degrees and back; every other shape at 0."""
    from autobones.arkit.names import ARKIT_NAMES, CAPTURE_ANGLES, capture_column

    cols = ["Timecode", "BlendShapeCount"] + [capture_column(n) for n in ARKIT_NAMES] + list(CAPTURE_ANGLES)
    rows = [",".join(cols)]
    n = int(seconds * fps)
    for i in range(n):
        s = math.sin(math.pi * i / (n - 1))  # 0 -> 1 -> 0 over the take
        blink = max(0.0, 1.0 - abs(i - n // 3) / 6)  # a blink a third of the way in, 12 frames long
        w = {"mouthSmileLeft": 0.8 * s, "mouthSmileRight": 0.8 * s, "jawOpen": 0.3 * s,
             "eyeBlinkLeft": blink, "eyeBlinkRight": blink}
        angles = {"HeadYaw": math.radians(10) * s}
        f, sec = i % fps, i // fps
        values = [f"{w.get(name, 0.0):.4f}" for name in ARKIT_NAMES] + [f"{angles.get(a, 0.0):.4f}"
                                                                       for a in CAPTURE_ANGLES]
        rows.append(",".join([f"00:00:{sec:02d}:{f:02d}.000", str(len(ARKIT_NAMES))] + values))
    return "\n".join(rows) + "\n"


if __name__ == "__main__":
    main()
