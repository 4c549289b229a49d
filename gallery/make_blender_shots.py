"""Pictures of the Blender add-on (issue #37) for gallery/ and docs/blender.md, from real Blender runs.

    python gallery/make_blender_shots.py        # needs blender (3.4+), xvfb-run (Debian: xvfb) and Pillow

- ``gallery/blender_addon.png``: a screenshot of Blender 3.4's own window (under Xvfb): the built-in
  default head rigged by the add-on's Rig button (transfer, landmark file, ARKit), the sidebar's
  autobones tab with its Rig, Landmarks and Pose panels, the jaw bone turned 8 degrees and the mouthSmile shape
  keys at 1; the armature drawn in front.
- ``docs/images/blender_landmarks.png``: the same window with the 44 landmark empties on the skin.
- ``docs/images/blender_progress.png``: the status bar while autobones runs (the modal Rig).
- ``docs/images/blender_poses.png``: Blender's workbench render (``blender -b``) of the head at rest and
  with the ARKit shape keys jawOpen 0.8, mouthSmile 1, eyeBlink + browInnerUp 1.

The Blender side is gallery/blender_shots_scene.py. Only files of this repository are used.
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from PIL import Image, ImageDraw

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
SCENE = HERE / "blender_shots_scene.py"
HEAD = ROOT / "generic_rig" / "default_head.obj"
LANDMARKS = ROOT / "generic_rig" / "default_head.landmarks.json"
POSES = [("rest", "rest"), ("jawOpen", "jawOpen 0.8"), ("smile", "mouthSmileLeft/Right 1"),
         ("blink_brows", "eyeBlink + browInnerUp 1")]


def blender_env(scripts):
    """Blender's environment: its own Python first on PATH (Debian), a throw-away user scripts folder."""
    exe = shutil.which("blender")
    return dict(os.environ, BLENDER_USER_SCRIPTS=str(scripts),
                PATH=os.path.dirname(os.path.realpath(exe)) + os.pathsep + os.environ.get("PATH", ""))


def run_blender(args, work, what):
    done = subprocess.run(args, capture_output=True, text=True, timeout=600, env=blender_env(work / "scripts"))
    if done.returncode != 0 or "Traceback" in done.stdout + done.stderr:
        sys.exit(f"{what} failed:\n{(done.stdout + done.stderr)[-3000:]}")


def crop_view(shot, areas, left=440):
    """The 3D view of a whole-window screenshot (Blender's y runs up from the bottom), from x = ``left``."""
    im = Image.open(shot).convert("RGB")
    x, y, w, h = areas["view3d"]
    H = areas["window"][1]
    return im.crop((left, H - (y + h), x + w, H - y))


def poses_strip(folder):
    """The four workbench renders side by side, each labelled."""
    ims = [Image.open(folder / f"render_{name}.png").convert("RGBA") for name, _ in POSES]
    w, h = ims[0].size
    out = Image.new("RGB", (w * len(ims), h + 30), "white")
    draw = ImageDraw.Draw(out)
    for k, (im, (_, label)) in enumerate(zip(ims, POSES)):
        tile = Image.new("RGBA", im.size, (255, 255, 255, 255))
        tile.alpha_composite(im)
        out.paste(tile.convert("RGB"), (k * w, 0))
        draw.text((k * w + 10, h + 8), label, fill="black")
    return out


def main():
    for tool in ("blender", "xvfb-run"):
        if shutil.which(tool) is None:
            sys.exit(f"{tool} is not on PATH (Debian: apt-get install blender python3-numpy xvfb)")
    sys.path.insert(0, str(ROOT))
    from autobones.blender_zip import write_addon_zip

    with tempfile.TemporaryDirectory(prefix="autobones-blender-shots-") as tmp:
        work = Path(tmp)
        zip_path = work / "autobones_blender.zip"
        write_addon_zip(zip_path)
        empty = work / "empty.blend"  # opening a file skips the splash screen
        run_blender(["blender", "-b", "--factory-startup", "--python-expr",
                     f"import bpy; bpy.ops.wm.read_factory_settings(use_empty=True); "
                     f"bpy.ops.wm.save_as_mainfile(filepath={str(empty)!r})"], work, "an empty scene")
        common = [str(zip_path), sys.executable, str(HEAD), str(LANDMARKS), str(work)]
        run_blender(["xvfb-run", "-a", "-s", "-screen 0 1600x1000x24", "blender", "--factory-startup",
                     "--enable-event-simulate", str(empty), "--python", str(SCENE), "--", "ui", *common],
                    work, "Blender's window under Xvfb")
        run_blender(["blender", "-b", "--factory-startup", "--python", str(SCENE), "--", "render", *common],
                     work, "the workbench renders")
        areas = json.loads((work / "areas.json").read_text())
        images = ROOT / "docs" / "images"
        images.mkdir(parents=True, exist_ok=True)
        crop_view(work / "pose.png", areas).save(HERE / "blender_addon.png", optimize=True)
        crop_view(work / "landmarks.png", areas).save(images / "blender_landmarks.png", optimize=True)
        progress = Image.open(work / "progress.png").convert("RGB")
        W, H = progress.size
        progress.crop((0, H - 26, 760, H)).save(images / "blender_progress.png", optimize=True)
        poses_strip(work).save(images / "blender_poses.png", optimize=True)
    print("wrote gallery/blender_addon.png, docs/images/blender_landmarks.png, blender_progress.png, blender_poses.png")


if __name__ == "__main__":
    main()
