"""The ``autobones`` argument parser: one function per command, the options they share."""
from __future__ import annotations

import argparse

from .help_texts import (ANIMATE_EPILOG, BATCH_EPILOG, BLENDER_ADDON_EPILOG, BUILD_EPILOG, EXPORT_EPILOG,
                         LANDMARKS_EPILOG, PLACE_EPILOG, TRANSFER_EPILOG, VIEW_EPILOG, pose_epilog)


class OneLineParser(argparse.ArgumentParser):
    """argparse, except that a usage error is one line on stderr and a hint, exit code 2 (the
    README's promise for every error): ``autobones place: error: ... (see autobones place --help)``.
    Sub-parsers are made of the same class (argparse's ``add_subparsers`` uses the parent's type)."""

    def error(self, message):
        message = " ".join(str(message).split())  # argparse's own messages may wrap; a file name may hold \n
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser():
    """The parser of ``autobones COMMAND ...`` (argparse)."""
    parser = OneLineParser(
        prog="autobones",
        description="Rig head meshes without a technical artist: bones, smooth skin weights, skinned glTF.")
    parser.add_argument("--version", action="store_true", help="print the version and exit")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    add_place(sub)
    add_samples(sub)  # second: what a new user runs before anything else
    add_transfer(sub)
    add_pose(sub)
    add_landmarks(sub)
    add_build_rig(sub)
    add_batch(sub)
    add_view(sub)
    add_export(sub)
    add_animate(sub)
    add_blender_addon(sub)
    parser.command_parsers = sub.choices  # name -> its parser: an unknown option is that command's error
    return parser


def add_place(sub):
    """The ``place`` command's arguments."""
    p = sub.add_parser(
        "place", help="place head, neck and facial bones and skin weights (no landmarks needed)",
        description="Place head, neck and facial bones on a head mesh and bind it with smooth skin "
                    "weights (average-linkage depth groups, k-means facial bones, bone heat).",
        epilog=PLACE_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("head", nargs="?", help="head mesh file (default: the built-in default head)")
    p.add_argument("-o", "--output", help="output .glb (default: HEAD_NAME.rig.glb in the current folder)")
    p.add_argument("--density", default="medium",
                   help="facial bones: sparse (8), medium (16, default), dense (32) or a number")
    _axes(p)
    p.add_argument("--seed", default="0", help="random seed of the k-means restarts, a whole number >= 0 (default 0)")
    p.add_argument("--landmarks", help="optional landmark file: transfer the generic rig's neck, head, jaw and "
                                      "eyes first and place the facial bones on the transferred face")
    p.add_argument("--rig", help="generic rig folder for --landmarks (default: the built-in one)")
    p.add_argument("--expressions", action="store_true", help=argparse.SUPPRESS)  # refused: place has no muscles
    _common(p)


def add_samples(sub):
    """The ``samples`` command's arguments."""
    from .help_texts import SAMPLES_EPILOG

    s = sub.add_parser(
        "samples", help="write sample heads (scan, bust, cartoon, animal), their landmarks and a capture take",
        description="Write ready inputs for every command in the documentation into DIR: the default head, a "
                    "scan, a bust, a cartoon robot and a goat, each with its landmarks, and a short face-capture "
                    "take (CSV); their licences and attribution in DIR/LICENSES.md.",
        epilog=SAMPLES_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    s.add_argument("folder", metavar="DIR", help="folder to write (created; refused when it holds anything, "
                                                 "unless --force)")
    s.add_argument("--force", action="store_true", help="write into a folder that is not empty, replacing the "
                                                        "sample files in it (other files are kept)")
    _common(s)


def add_transfer(sub):
    """The ``transfer`` command's arguments."""
    t = sub.add_parser(
        "transfer", help="carry the labelled generic rig onto a landmarked head",
        description="Warp the labelled generic rig onto a head by thin-plate splines from shared landmarks, "
                    "stick it to the surface (dense correspondence), and carry its skeleton (neck, head, jaw, "
                    "eyes), muscles, skin weights and attribute fields onto the head's own vertices "
                    "(Orvalho, Zacur & Susin 2008). Writes the same skinned glTF as `place`.",
        epilog=TRANSFER_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    t.add_argument("head", help="head mesh file (OBJ, PLY, OFF, STL, glTF/GLB; any frame and unit)")
    t.add_argument("--landmarks",
                   help="landmark file in the head's frame: contract .json, MeshLab .pp, or an iBUG-68 "
                        ".json/.pts/.ljson; at least 10 names shared with the rig (default: found "
                        "automatically on a human face, see `autobones landmarks`)")
    t.add_argument("--rig", help="generic rig folder made by `autobones build-rig` (default: the built-in one)")
    t.add_argument("-o", "--output", help="output .glb (default: HEAD_NAME.rig.glb in the current folder)")
    _axes(t, "; used to check left/right")
    t.add_argument("--expressions", action="store_true",
                   help="also write each FACS action unit as a morph target (AU1 ... AU43, intensity 1, "
                        "computed on this head; see `autobones pose --help`)")
    t.add_argument("--expression-sides", action="store_true",
                   help="with the morph targets, also each AU's left and right halves (AU12L, AU12R); "
                        "implies --expressions")
    t.add_argument("--tissue", action="store_true",
                   help="with --expressions: refine each morph target by the layered soft tissue under the skin "
                        "(Lee, Terzopoulos & Waters 1995): skin over a shortening muscle bulges, the tissue keeps "
                        "its volume and stays off the skull; about 0.1-1 s more per target")
    t.add_argument("--arkit", action="store_true",
                   help="also write ARKit's 52 face blendshapes as morph targets named as ARKit does (eyeBlinkLeft, "
                        "jawOpen, ...; Left = the subject's left), made for this head from ICT-FaceKit's set (or the "
                        "--rig folder's own set, build-rig --shapes) by deformation transfer; tongueOut is "
                        "written empty (ICT has none)")
    t.add_argument("--symmetric", choices=("auto", "on", "off"), default="auto",
                   help="keep the dense correspondence mirror-symmetric, so a symmetric head's points do not slide "
                        "across its midline: auto (default) when the head's landmark pairs are mirror images (within "
                        "1%% of the eye-corner distance) and the head and the rig's skin are symmetric about their "
                        "landmarks' planes (sculpts, cartoons, robots; not real scans, whose own asymmetry the rig "
                        "follows, nor a one-sided expression, nor automatic landmarks); the sidecar's options.symmetric "
                        "says what was measured")
    t.add_argument("--no-expression-fit", dest="expression_fit", action="store_false",
                   help="fit the neutral generic skin even if the head wears an expression. By default the expression "
                        "the head seems to wear (an open jaw, a smile, a pucker) is solved with ICT-FaceKit's ARKit "
                        "shapes and identity modes and the generic skin wears it in the fit, so the skin does not slide "
                        "where the landmarks say nothing; neutral heads, and heads no human face fits (animals), stay "
                        "neutral, and so does every head with automatic landmarks (give a landmark file); the sidecar's "
                        "options.expression_fit says what was found")
    _common(t)


def add_pose(sub):
    """The ``pose`` command's arguments."""
    q = sub.add_parser(
        "pose", help="pose a saved transferred rig: FACS action units, emotions, jaw, eyelids, gaze",
        description="Pose a rig saved by `autobones transfer` with its skin/muscle model (Bibliowicz 2005, "
                    "section 4.2): FACS action units, emotion presets, muscle contractions, jaw opening, "
                    "eyelids, eye gaze, head and neck turns. Writes the posed mesh. A rig from `autobones "
                    "place` has no muscles: it poses --head and --neck (its bones, by linear blend skinning).",
        epilog=pose_epilog(), formatter_class=argparse.RawDescriptionHelpFormatter)
    q.add_argument("rig", metavar="RIG.glb", help="a glb written by autobones transfer (or place: --head and --neck "
                   "only), its sidecars beside it")
    q.add_argument("-o", "--output", help="posed mesh, .obj or .glb (default: RIG_NAME.pose.obj in the current folder)")
    q.add_argument("--expression", action="append", default=[], metavar="NAME[=W]",
                   help="an emotion preset at intensity W (default 1); repeat to mix")
    q.add_argument("--au", action="append", default=[], metavar="N=V",
                   help="action unit N (12, AU12, 12L, 12R) at intensity V (default 1); repeat for more")
    q.add_argument("--muscle", action="append", default=[], metavar="NAME=V",
                   help="a muscle (zygomaticus_major_l) or muscle type (both sides) contracted by V")
    q.add_argument("--jaw", default="0", metavar="DEG", help="jaw opening in degrees (default 0)")
    q.add_argument("--eyelids", action="append", default=[], metavar="PART=V",
                   help="eyelid amount: upper, lower, upper_l, upper_r, lower_l, lower_r (upper=1 closes)")
    q.add_argument("--gaze", metavar="YAW,PITCH", help="both eyes turned, degrees")
    q.add_argument("--look-at", metavar="X,Y,Z", help="a point (rig frame and units) both eyes aim at")
    q.add_argument("--head", dest="head_deg", metavar="PITCH,YAW,ROLL", help="head rotation, degrees")
    q.add_argument("--neck", dest="neck_deg", metavar="PITCH,YAW,ROLL", help="neck rotation, degrees")
    q.add_argument("--arkit", action="append", default=[], metavar="NAME=W",
                   help="an ARKit shape (jawOpen, eyeBlinkLeft, ...) at weight W (default 1; ARKit's range 0..1, up to 2 "
                        "overdrives it), on a rig made with transfer --arkit; repeat to mix; adds on top of AUs and bones")
    q.add_argument("--layer", choices=["auto", "shapes", "muscles"], default="auto",
                   help="what poses the AUs the au_arkit table maps (AU12 -> mouthSmile, AU26 -> jawOpen, ...; "
                        "--expression expands to its AUs): shapes = the head's own ARKit shapes (a rig made with "
                        "transfer --arkit), muscles = the skin/muscle model, auto (default) = shapes where the rig "
                        "has them, else muscles. Other AUs, --muscle, --jaw, --eyelids, gaze, head, neck and "
                        "--tissue always use the muscle model. An option of its own, not a reuse of --muscle, "
                        "which already names muscle contractions")
    q.add_argument("--tissue", action="store_true",
                   help="refine the pose by the layered soft tissue under the skin (Lee, Terzopoulos & Waters "
                        "1995): skin over a shortening muscle bulges (the cheek in a smile), the tissue keeps its "
                        "volume and stays off the skull")
    q.add_argument("--definitions", metavar="FILE",
                   help="expression definitions to pose with (format of generic_rig/expressions.json) instead "
                        "of the ones the rig's sidecar kept")
    _common(q)


def add_landmarks(sub):
    """The ``landmarks`` command's arguments."""
    m = sub.add_parser(
        "landmarks", help="find the contract's landmarks on a human head automatically, draw given ones, "
                          "or place them by hand in the browser (--edit)",
        description="Find the landmark contract's names on a human or human-like head automatically "
                    "(render, detect in 2-D, lift to the surface), write them as the contract's JSON in "
                    "the mesh's own frame, and optionally draw a picture to check them by eye.",
        epilog=LANDMARKS_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    m.add_argument("head", help="head mesh file (OBJ, PLY, OFF, STL, glTF/GLB; any frame and unit)")
    m.add_argument("-o", "--output", help="landmark file to write (.json); default: HEAD_NAME.landmarks.json "
                                          "in the current folder (none with --from and only --preview)")
    m.add_argument("--from", dest="source", metavar="FILE",
                   help="read the landmarks from FILE (contract .json, MeshLab .pp, iBUG-68) instead of detecting")
    m.add_argument("--assist", metavar="PARTIAL",
                   help="propose the other names from a few placed in PARTIAL (at least exocanthion_l/_r, "
                        "pronasale, cheilion_l/_r): the generic head fitted to the mesh; any head, animals too")
    m.add_argument("--rig", help="generic rig folder for --assist (default: the built-in one)")
    m.add_argument("--preview", metavar="PNG", help="also draw a front and a side picture with every landmark named")
    m.add_argument("--edit", action="store_true",
                   help="place, move and check them by hand in the browser (starting from --from, else from "
                        "automatic detection); Save writes -o, nothing is written before")
    m.add_argument("--pp", metavar="FILE.pp", help="with --edit: also save MeshLab picked points (as -o X.pp does)")
    m.add_argument("--port", help="with --edit: port on 127.0.0.1 (default: a free one)")
    m.add_argument("--no-browser", action="store_true", help="with --edit: print the URL only, open no browser")
    _axes(m)
    _common(m)


def add_build_rig(sub):
    """The ``build-rig`` command's arguments."""
    b = sub.add_parser(
        "build-rig", help="build a labelled generic rig from a base head and its landmarks",
        description="Derive a labelled generic rig (skeleton, muscles, skin weights, region labels, muscle "
                    "influence fields) from any base head plus its landmarks, with the same code that built "
                    "the built-in rig. Use the folder with `autobones transfer --rig`.",
        epilog=BUILD_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    b.add_argument("base", help="base head mesh file")
    b.add_argument("--landmarks", required=True, help="the base head's landmark file (names the rig needs: see below)")
    b.add_argument("-o", "--output", required=True, help="output folder (rig.json, mesh.obj, fields.npz)")
    b.add_argument("--shapes", metavar="FOLDER",
                   help="a studio's own ARKit shape set, stored in the rig folder (arkit/) so `transfer --rig "
                        "DIR --arkit` carries it instead of ICT-FaceKit's: neutral.obj, neutral.landmarks.json "
                        "and one posed mesh per ARKit name (jawOpen.obj, eyeBlinkLeft.obj, ...) with the "
                        "neutral's vertices in order; names without a mesh are absent (empty targets)")
    _common(b)


def add_batch(sub):
    """The ``batch`` command's arguments."""
    a = sub.add_parser(
        "batch", help="rig every mesh in a folder tree (local processes or a Dask cluster), resumably",
        description="Run `place` (or `transfer`) on every mesh under INPUT_DIR, mirroring its folders in "
                    "OUT_DIR, on N local processes or a Dask distributed cluster. Each output is written "
                    "under a temporary name and renamed when complete; a rerun skips what is done.",
        epilog=BATCH_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    a.add_argument("input_dir", metavar="INPUT_DIR", help="folder of meshes (OBJ, PLY, OFF, STL, glTF/GLB), "
                                                          "searched recursively; hidden files are ignored")
    a.add_argument("-o", "--output", required=True, metavar="OUT_DIR", help="output folder (outside INPUT_DIR): "
                                                                        "NAME.rig.glb and its sidecars per mesh")
    a.add_argument("--density", default="medium",
                   help="facial bones for place: sparse (8), medium (16, default), dense (32) or a number")
    a.add_argument("--transfer", action="store_true",
                   help="transfer the labelled rig instead of placing bones; uses NAME.landmarks.json "
                        "(or NAME.pp, .pts, .ljson) beside each NAME.obj, else finds them automatically "
                        "(human faces; needs autobones[landmarks])")
    a.add_argument("--rig", metavar="DIR", help="generic rig folder for --transfer (default: the built-in one)")
    a.add_argument("--expressions", action="store_true",
                   help="with --transfer: one morph target per FACS action unit in each glb (see `autobones pose --help`)")
    a.add_argument("--expression-sides", action="store_true",
                   help="with --transfer: also each AU's left and right halves (AU12L, AU12R); implies --expressions")
    a.add_argument("--tissue", action="store_true",
                   help="with --transfer --expressions: morph targets refined by the layered tissue (see transfer --help)")
    a.add_argument("--arkit", action="store_true",
                   help="with --transfer: ARKit's 52 face blendshapes as morph targets in each glb "
                        "(see transfer --help)")
    a.add_argument("--symmetric", choices=("auto", "on", "off"), default="auto",
                   help="with --transfer: keep each correspondence mirror-symmetric (see transfer --help; default auto)")
    a.add_argument("--no-expression-fit", dest="expression_fit", action="store_false",
                   help="with --transfer: fit the neutral generic skin (see transfer --help)")
    a.add_argument("--jobs", type=int, default=1, metavar="N", help="local worker processes (default 1)")
    a.add_argument("--scheduler", metavar="ADDRESS",
                   help="Dask distributed scheduler (tcp://host:8786) to run on instead of local processes; "
                        "the folders must be on a file system every worker sees at the same path")
    a.add_argument("--force", action="store_true",
                   help="overwrite outputs that exist but are out of date or made with other options")
    a.add_argument("-q", "--quiet", action="store_true", help="no progress bar and no summary table")
    _common(a)


def add_view(sub):
    """The ``view`` command's arguments."""
    w = sub.add_parser(
        "view", help="look at a rig or a batch output folder in the browser (local, read-only)",
        description="Serve a page on 127.0.0.1 showing one rig (orbit, pose the bones, colour the skin by a "
                    "bone's weight, morph target sliders, landmarks and muscles) or a batch output folder "
                    "(thumbnails, status and warnings from the report, filters). Stops with Ctrl-C.",
        epilog=VIEW_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    w.add_argument("path", metavar="RIG.glb|FOLDER", help="a rig written by autobones (its sidecars beside it) or "
                                                            "a folder written by `autobones batch`")
    w.add_argument("--port", default="0", help="port on 127.0.0.1 (default: a free one)")
    w.add_argument("--no-browser", action="store_true", help="do not open the system browser; print the URL only")
    _common(w)


def add_export(sub):
    """The ``export`` command's arguments."""
    e = sub.add_parser(
        "export", help="write a saved rig as USD (UsdSkel) or FBX (through Blender)",
        description="Write a rig saved by autobones (RIG.glb with RIG.rig.json and RIG.weights.npz beside it) "
                    "for other pipelines: USD (.usd/.usda/.usdc/.usdz, UsdSkel: skeleton, every skin weight, "
                    "blend shapes, animation) or FBX (armature, vertex groups, shape keys; Blender runs headless). "
                    "The suffix of -o picks the format.",
        epilog=EXPORT_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    e.add_argument("rig", metavar="RIG.glb",
                   help="a glb written by autobones (place, transfer, batch), its sidecars beside it")
    e.add_argument("-o", "--output", required=True, metavar="OUT",
                   help="OUT.usda, OUT.usdc, OUT.usd, OUT.usdz or OUT.fbx")
    e.add_argument("--meters-per-unit", type=float, metavar="M",
                   help="USD: metres per mesh unit (default: guessed from the head size, see below)")
    _common(e)


def add_animate(sub):
    """The ``animate`` command's arguments."""
    n = sub.add_parser(
        "animate", help="turn a face-capture recording (Live Link Face CSV) into a glTF animation of a rig",
        description="Copy a rig made with `autobones transfer --arkit` with one animation added: the recording's "
                    "52 ARKit shape weights as morph-target weight keys, and its head and eye angles as "
                    "rotations of the head and eye joints. Plays in three.js, Blender and engines.",
        epilog=ANIMATE_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    n.add_argument("rig", metavar="RIG.glb", help="a glb written by autobones transfer --arkit (sidecars beside it)")
    n.add_argument("--capture", required=True, metavar="TAKE.csv",
                   help="a Live Link Face CSV: Timecode, BlendShapeCount, EyeBlinkLeft ... TongueOut, "
                        "HeadYaw ... RightEyeRoll")
    n.add_argument("-o", "--output", required=True, metavar="OUT.glb", help="the animated glb to write")
    n.add_argument("--fps", default="60",
                   help="frame rate of the timecode's frame field (default 60, Live Link Face's)")
    n.add_argument("--no-bones", action="store_true", help="morph-target weights only, no head and eye turns")
    _common(n)


def add_blender_addon(sub):
    """The ``blender-addon`` command's arguments."""
    z = sub.add_parser(
        "blender-addon", help="write the Blender add-on (a zip to install in Blender 3.4+)",
        description="Write autobones' Blender add-on as a zip: install it in Blender (Edit > Preferences > "
                    "Add-ons > Install...) to rig the active mesh from the 3D view's sidebar.",
        epilog=BLENDER_ADDON_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    z.add_argument("-o", "--output", default="autobones_blender.zip", metavar="OUT.zip",
                   help="the zip to write (default: autobones_blender.zip in the current folder)")
    _common(z)


def _axes(p, note=""):
    p.add_argument("--up", help=f"input axis that points up: +x -x +y -y +z -z (default: detected{note})")
    p.add_argument("--front", help="input axis the face looks along (default: detected)")


def _common(p):
    p.add_argument("-v", "--verbose", action="count", default=0, help="report stages, timings and the detected frame")
    p.add_argument("--debug", action="store_true", help="show tracebacks instead of one-line errors")
