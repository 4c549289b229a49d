"""``autobones`` command line. Parses arguments, calls the library, prints one line per result.

Errors a user can fix (bad file, bad option) print as one line on stderr with
exit code 2; ``--debug`` shows the traceback instead.
"""
from __future__ import annotations

import argparse
import logging
import os
import sys
import time

EXIT_USER_ERROR = 2

PLACE_EPILOG = """\
examples:
  autobones place                                 rig the built-in default head -> default_head.rig.glb
  autobones place scan.obj --density dense -o scan.glb
  autobones place scan.ply --density 24           24 facial bones
  autobones place bust.stl --up +z --front -y     when the automatic orientation guesses wrong
  autobones place head.obj --landmarks head.landmarks.json --density dense
                                                  transferred neck, head, jaw and eyes + facial bones

output:
  OUT.glb          skinned glTF 2.0: the input vertices unchanged, joints neck, head,
                   face_00..., the 4 largest weights per vertex
  OUT.rig.json     bones (name, parent, head, tail), detected frame, per-vertex
                   face/middle/back label, facial mask, options, version
  OUT.weights.npz  the full weight matrix 'weights' (n_vertices x n_bones) and 'bone_names'

densities: sparse = 8, medium = 16, dense = 32 facial bones, or any number 1..256.
Inputs: OBJ, PLY, OFF, STL, glTF/GLB, in any frame and unit; +Y-up/+Z-front is not required.
"""


TRANSFER_EPILOG = """\
examples:
  autobones transfer head.obj --landmarks head.landmarks.json -o head.glb
  autobones transfer scan.obj -o scan.glb                   human face: landmarks found automatically
  autobones transfer goat.obj --landmarks goat.pp -o goat.glb            MeshLab picked points
  autobones transfer scan.ply --landmarks scan.ibug68.json --rig my_rig/ -o scan.glb

output: OUT.glb (joints neck, head, jaw, eye_l, eye_r), OUT.rig.json (bones, muscles with
origins and insertions, landmarks used, label class names), OUT.weights.npz (weights and
every transferred field as field/<name>).

Landmark names, frame and file formats: the landmark contract (README). Bad landmarks
(unknown names, left/right swapped, off the surface, wrong units, too few) are refused
with one line naming the problem.
"""

LANDMARKS_EPILOG = """\
examples:
  autobones landmarks scan.obj -o scan.landmarks.json                   found automatically (human faces)
  autobones landmarks scan.obj -o scan.landmarks.json --preview scan.png
  autobones landmarks goat.obj --from goat.pp --preview goat.png        convert a file and draw it
  autobones landmarks bust.stl --up +z --front -y -o bust.landmarks.json

How: the head is turned upright, rendered on the CPU from the front and four views around it
(+-30 deg yaw, +-15 deg pitch), MediaPipe Face Mesh finds 468 points in each picture, they are
lifted onto the surface and combined across views; then midline names go onto the face's
symmetry plane, left/right pairs become mirror images, the nose tip and menton are taken from
the midline profile. A name whose views disagree is dropped, not guessed; a pair whose sides
disagree is flagged. 27 of the contract's names are found (the ones a face picture shows).

Animals, most cartoons and back-of-head scans have no face the detector knows: the command
says so (exit code 2) and writes nothing; give their landmarks by hand (--from, MeshLab .pp).
Needs the optional detector: pip install 'autobones[landmarks]'.

output: the contract's JSON ({"format": "autobones-landmarks/1", "landmarks": {name: [x, y, z]}}),
in the mesh's own frame and units, plus "confidence" per name (1 = every view agrees).
"""

BUILD_EPILOG = """\
examples:
  autobones build-rig base.obj --landmarks base.landmarks.json -o my_rig/
  autobones transfer scan.obj --landmarks scan.landmarks.json --rig my_rig/ -o scan.glb
"""


BATCH_EPILOG = """\
examples:
  autobones batch heads/ -o rigs/ --density dense --jobs 2      place on every mesh, recursively
  autobones batch heads/ -o rigs/ --transfer                    landmarks NAME.landmarks.json / NAME.pp beside each
                                                                mesh; found automatically where there is none
  autobones batch heads/ -o rigs/ --scheduler tcp://scheduler.example:8786    the same, on a Dask cluster

output: OUT/<path relative to INPUT_DIR without extension>.glb, .rig.json, .weights.npz per
mesh, and OUT/batch_report.json (per file: status ok/failed/skipped, error, timings, options).
Meshes whose outputs are up to date (newer than the input, same options) are skipped, so an
interrupted batch is resumed by running it again. Outputs that exist but are out of date are
overwritten only with --force. The output folder may not overlap the input folder.

exit code: 0 when every file is ok or up to date, 1 when any file failed, 2 for a bad
command (missing folder, overlapping folders, bad option).
"""


def _pose_epilog():
    """The pose command's help: examples, then the AUs and emotions of the data file."""
    import json

    try:
        from autobones.generic_rig import expressions_path

        with open(expressions_path(), encoding="utf-8") as fh:
            doc = json.load(fh)
        aus = "\n".join(f"  AU{k:<3} {v.get('name', '')}" for k, v in sorted(doc["action_units"].items(),
                                                                          key=lambda kv: int(kv[0])))
        emotions = "\n".join(f"  {k:<10} " + " + ".join(f"AU{a}" + (f"*{w:g}" if w != 1 else "")
                                                        for a, w in v["au"].items())
                             for k, v in doc["expressions"].items())
    except (OSError, ValueError, KeyError, TypeError, ImportError) as exc:
        aus = emotions = f"  (generic_rig/expressions.json could not be read: {exc})"
    return f"""\
examples:
  autobones pose head.glb --expression happiness -o happy.obj           an emotion preset
  autobones pose head.glb --au 12=0.8 --au 6=0.4 --jaw 10 -o smile.obj  FACS action units, jaw in degrees
  autobones pose head.glb --au 12L=1 -o smirk.obj                       L / R: the subject's left / right half
  autobones pose head.glb --expression surprise=0.5 --gaze 20,0 -o look.glb
  autobones pose head.glb --eyelids upper=1 --head 0,30,0 -o turned.obj

RIG.glb is a rig saved by `autobones transfer` (its muscles drive the skin), with
RIG.rig.json and RIG.weights.npz beside it; the sidecar keeps the expression
definitions the rig was saved with (--definitions FILE poses with others). The posed vertices are written in the
rig's own frame and units, vertex i of the output = vertex i of the input mesh:
OUT.obj (v and f lines) or OUT.glb (a static mesh, no skin).

units: AU and expression intensities 0..1 (1 = the AU's full action; larger values
extrapolate, negative ones reverse); --jaw, --gaze, --head, --neck in degrees; --jaw
adds to the opening AU26/AU27 give. --eyelids PART=V: upper/lower (both eyes) or
upper_l, upper_r, lower_l, lower_r; upper=1 closes the eye. --head/--neck PITCH,YAW,ROLL:
pitch > 0 nods down, yaw > 0 turns to the subject's left. --gaze YAW,PITCH: yaw > 0 to
the subject's left, pitch > 0 up.

action units (generic_rig/expressions.json):
{aus}

emotions (seed 002 Table 3-3):
{emotions}
"""


def build_parser():
    parser = argparse.ArgumentParser(
        prog="autobones",
        description="Rig head meshes without a technical artist: bones, smooth skin weights, skinned glTF.")
    parser.add_argument("--version", action="store_true", help="print the version and exit")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    p = sub.add_parser(
        "place", help="place head, neck and facial bones and skin weights (no landmarks needed)",
        description="Place head, neck and facial bones on a head mesh and bind it with smooth skin "
                    "weights (seed 003: average-linkage depth groups, k-means facial bones, bone heat).",
        epilog=PLACE_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("head", nargs="?", help="head mesh file (default: the built-in default head)")
    p.add_argument("-o", "--output", help="output .glb (default: HEAD_NAME.rig.glb in the current folder)")
    p.add_argument("--density", default="medium",
                   help="facial bones: sparse (8), medium (16, default), dense (32) or a number")
    _axes(p)
    p.add_argument("--seed", type=int, default=0, help="random seed of the k-means restarts (default 0)")
    p.add_argument("--landmarks", help="optional landmark file: transfer the generic rig's neck, head, jaw and "
                                      "eyes first and place the facial bones on the transferred face")
    p.add_argument("--rig", help="generic rig folder for --landmarks (default: the built-in one)")
    p.add_argument("--expressions", action="store_true", help=argparse.SUPPRESS)  # refused: place has no muscles
    _common(p)

    t = sub.add_parser(
        "transfer", help="carry the labelled generic rig onto a landmarked head",
        description="Warp the labelled generic rig onto a head by thin-plate splines from shared landmarks, "
                    "stick it to the surface (dense correspondence), and carry its skeleton (neck, head, jaw, "
                    "eyes), muscles, skin weights and attribute fields onto the head's own vertices "
                    "(seed 004). Writes the same skinned glTF as `place`.",
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
    _common(t)

    q = sub.add_parser(
        "pose", help="pose a saved transferred rig: FACS action units, emotions, jaw, eyelids, gaze",
        description="Pose a rig saved by `autobones transfer` with its skin/muscle model (seed 000 section 4.2): "
                    "FACS action units, emotion presets, muscle contractions, jaw opening, eyelids, eye gaze, "
                    "head and neck turns. Writes the posed mesh.",
        epilog=_pose_epilog(), formatter_class=argparse.RawDescriptionHelpFormatter)
    q.add_argument("rig", metavar="RIG.glb", help="a glb written by autobones transfer, its sidecars beside it")
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
    q.add_argument("--definitions", metavar="FILE",
                   help="expression definitions to pose with (format of generic_rig/expressions.json) instead "
                        "of the ones the rig's sidecar kept")
    _common(q)

    m = sub.add_parser(
        "landmarks", help="find the contract's landmarks on a human head automatically, or draw given ones",
        description="Find the landmark contract's names on a human or human-like head automatically "
                    "(render, detect in 2-D, lift to the surface), write them as the contract's JSON in "
                    "the mesh's own frame, and optionally draw a picture to check them by eye.",
        epilog=LANDMARKS_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    m.add_argument("head", help="head mesh file (OBJ, PLY, OFF, STL, glTF/GLB; any frame and unit)")
    m.add_argument("-o", "--output", help="landmark file to write (.json); default: HEAD_NAME.landmarks.json "
                                          "in the current folder (none with --from and only --preview)")
    m.add_argument("--from", dest="source", metavar="FILE",
                   help="read the landmarks from FILE (contract .json, MeshLab .pp, iBUG-68) instead of detecting")
    m.add_argument("--preview", metavar="PNG", help="also draw a front and a side picture with every landmark named")
    _axes(m)
    _common(m)

    b = sub.add_parser(
        "build-rig", help="build a labelled generic rig from a base head and its landmarks",
        description="Derive a labelled generic rig (skeleton, muscles, skin weights, region labels, muscle "
                    "influence fields) from any base head plus its landmarks, with the same code that built "
                    "the built-in rig. Use the folder with `autobones transfer --rig`.",
        epilog=BUILD_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    b.add_argument("base", help="base head mesh file")
    b.add_argument("--landmarks", required=True, help="the base head's landmark file (names the rig needs: see below)")
    b.add_argument("-o", "--output", required=True, help="output folder (rig.json, mesh.obj, fields.npz)")
    _common(b)

    a = sub.add_parser(
        "batch", help="rig every mesh in a folder tree (local processes or a Dask cluster), resumably",
        description="Run `place` (or `transfer`) on every mesh under INPUT_DIR, mirroring its folders in "
                    "OUT_DIR, on N local processes or a Dask distributed cluster. Each output is written "
                    "under a temporary name and renamed when complete; a rerun skips what is done.",
        epilog=BATCH_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    a.add_argument("input_dir", metavar="INPUT_DIR", help="folder of meshes (OBJ, PLY, OFF, STL, glTF/GLB), "
                                                          "searched recursively; hidden files are ignored")
    a.add_argument("-o", "--output", required=True, metavar="OUT_DIR", help="output folder (outside INPUT_DIR)")
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
    a.add_argument("--jobs", type=int, default=1, metavar="N", help="local worker processes (default 1)")
    a.add_argument("--scheduler", metavar="ADDRESS",
                   help="Dask distributed scheduler (tcp://host:8786) to run on instead of local processes; "
                        "the folders must be on a file system every worker sees at the same path")
    a.add_argument("--force", action="store_true",
                   help="overwrite outputs that exist but are out of date or made with other options")
    a.add_argument("-q", "--quiet", action="store_true", help="no progress bar and no summary table")
    _common(a)
    return parser


def _axes(p, note=""):
    p.add_argument("--up", help=f"input axis that points up: +x -x +y -y +z -z (default: detected{note})")
    p.add_argument("--front", help="input axis the face looks along (default: detected)")


def _common(p):
    p.add_argument("-v", "--verbose", action="count", default=0, help="report stages, timings and the detected frame")
    p.add_argument("--debug", action="store_true", help="show tracebacks instead of one-line errors")


def cmd_place(args):
    import autobones

    if args.expressions:
        from autobones.errors import AutobonesError

        raise AutobonesError("--expressions needs muscles, which place does not make; use "
                             "autobones transfer HEAD --landmarks FILE --expressions -o OUT.glb")
    head = args.head
    out = args.output or _default_out(head)
    t = time.perf_counter()
    rig = autobones.place(head, density=args.density, up=args.up, front=args.front, random_state=args.seed,
                          landmarks=args.landmarks, rig=args.rig)
    written = rig.save(out)
    print(f"{written[0]}: {len(rig.skeleton)} bones ({rig.options['facial_bones']} facial), "
          f"{len(rig.vertices)} vertices, up {rig.frame.up}, front {rig.frame.front}, "
          f"{time.perf_counter() - t:.1f} s; sidecars {os.path.basename(written[1])}, {os.path.basename(written[2])}")
    return 0


def _default_out(head):
    stem = "default_head" if head is None else os.path.splitext(os.path.basename(head))[0]
    return f"{stem}.rig.glb"


def cmd_transfer(args):
    import autobones

    out = args.output or _default_out(args.head)
    t = time.perf_counter()
    rig = autobones.transfer(args.head, args.landmarks, rig=args.rig, up=args.up, front=args.front)
    written = rig.save(out, expressions="sides" if args.expression_sides else args.expressions)
    if rig.options.get("landmarks_source") == "detected":
        conf = rig.extra.get("landmark_confidence", {})
        dropped = rig.extra.get("landmarks_dropped", {})
        print(f"landmarks: {len(conf)} found automatically, mean confidence {sum(conf.values()) / max(len(conf), 1):.2f}"
              + (f"; dropped {', '.join(dropped)}" if dropped else "")
              + f" (check them: autobones landmarks {args.head} --preview PNG)")
    print(f"{written[0]}: {len(rig.skeleton)} bones, {len(rig.extra['muscles'])} muscles, "
          f"{len(rig.fields)} fields, {len(rig.options['landmarks_used'])} landmarks used, "
          f"{len(rig.vertices)} vertices, {time.perf_counter() - t:.1f} s; "
          f"sidecars {os.path.basename(written[1])}, {os.path.basename(written[2])}"
          + (f"; {_morph_target_count(written[1])} morph targets" if args.expressions or args.expression_sides else ""))
    return 0


def _morph_target_count(sidecar):
    import json

    with open(sidecar, encoding="utf-8") as fh:
        return len(json.load(fh)["expressions"]["morph_targets"])


def _number(text, what):
    from autobones.errors import AutobonesError

    try:
        v = float(text)
    except (TypeError, ValueError):
        raise AutobonesError(f"{what}: {text!r} is not a number") from None
    if v != v or v in (float("inf"), float("-inf")):
        raise AutobonesError(f"{what}: {text!r} is not a finite number")
    return v


def _pairs(items, option, default=None):
    """``["12=0.8", "6"]`` -> ``{"12": 0.8, "6": default}``; values summed when a key repeats."""
    from autobones.errors import AutobonesError

    out = {}
    for item in items:
        key, eq, value = item.partition("=")
        key = key.strip()
        if not key:
            raise AutobonesError(f"{option} {item!r}: expected NAME=VALUE")
        if not eq and default is None:
            raise AutobonesError(f"{option} {item!r}: expected NAME=VALUE (e.g. {option} upper=1)")
        out[key] = out.get(key, 0.0) + (_number(value, f"{option} {item}") if eq else default)
    return out


def _vector(text, n, option):
    from autobones.errors import AutobonesError

    if text is None:
        return None
    parts = [p for p in text.replace(" ", "").split(",")]
    if len(parts) != n:
        raise AutobonesError(f"{option} {text!r}: expected {n} comma-separated numbers")
    return [_number(p, f"{option} {text}") for p in parts]


def cmd_pose(args):
    import numpy as np

    import autobones
    from autobones.io.posed import write_posed_mesh

    t = time.perf_counter()
    au = {k.upper().removeprefix("AU"): v for k, v in _pairs(args.au, "--au", default=1.0).items()}
    expression = _pairs(args.expression, "--expression", default=1.0)
    muscles = _pairs(args.muscle, "--muscle")
    eyelids = _pairs(args.eyelids, "--eyelids")
    jaw = _number(args.jaw, "--jaw")
    gaze, look_at = _vector(args.gaze, 2, "--gaze"), _vector(args.look_at, 3, "--look-at")
    head_deg, neck_deg = _vector(args.head_deg, 3, "--head"), _vector(args.neck_deg, 3, "--neck")
    out = args.output or os.path.splitext(os.path.basename(args.rig))[0].removesuffix(".rig") + ".pose.obj"
    if os.path.splitext(out)[1].lower() not in (".obj", ".glb"):
        from autobones.errors import AutobonesError

        raise AutobonesError(f"{out}: the posed mesh is written as .obj or .glb")
    rig = autobones.load_rig(args.rig)
    if not rig.extra.get("muscles"):
        from autobones.errors import AutobonesError

        raise AutobonesError(f"{args.rig}: this rig has no muscles (`autobones place` makes none); pose needs a rig "
                             "saved by autobones transfer HEAD --landmarks FILE -o OUT.glb")
    if args.definitions:
        rig.expression_model(args.definitions)  # pose uses the model built last
    V = rig.pose(au=au or None, expression=expression or None, muscles=muscles or None, jaw_deg=jaw,
                 eyelids=eyelids or None, gaze=gaze, look_at=look_at, head_deg=head_deg, neck_deg=neck_deg)
    what = ", ".join([f"{k} {v:g}" for k, v in expression.items()] + [f"AU{k} {v:g}" for k, v in au.items()]
                     + [f"{k} {v:g}" for k, v in muscles.items()] + ([f"jaw {jaw:g} deg"] if jaw else [])
                     + [f"eyelids {k} {v:g}" for k, v in eyelids.items()]
                     + ([f"gaze {args.gaze}"] if gaze else []) + ([f"look at {args.look_at}"] if look_at else [])
                     + ([f"head {args.head_deg}"] if head_deg else []) + ([f"neck {args.neck_deg}"] if neck_deg else []))
    write_posed_mesh(out, V, rig.faces, comment=f"autobones pose {os.path.basename(args.rig)}: {what or 'neutral'}")
    moved = float(np.linalg.norm(V - rig.vertices, axis=1).max()) if len(V) else 0.0
    print(f"{out}: {what or 'neutral'}; {len(V)} vertices, largest displacement {moved:.4g} "
          f"({moved / rig.frame.size:.1%} of the head size), {time.perf_counter() - t:.1f} s")
    return 0


def cmd_landmarks(args):
    import autobones
    from autobones.io.landmarks import read_landmarks, validate_landmarks, write_landmarks
    from autobones.landmarks.preview import save_preview

    t = time.perf_counter()
    V, F = autobones.load_mesh(args.head)
    if args.source:
        frame = autobones.detect_frame(V, F, up=args.up, front=args.front) if args.up or args.front else None
        lm = validate_landmarks(read_landmarks(args.source), V, F, frame=frame, min_count=1, source=args.source)
        confidence, how = None, f"read from {args.source}"
    else:
        lm = autobones.detect_landmarks((V, F), up=args.up, front=args.front, name=args.head)
        frame, confidence = lm.frame, lm.confidence
        how = f"found automatically, mean confidence {sum(confidence.values()) / max(len(confidence), 1):.2f}"
        if lm.dropped:
            how += "; dropped " + ", ".join(f"{n} ({why})" for n, why in lm.dropped.items())
        if lm.flagged:
            how += "; check " + ", ".join(sorted(lm.flagged))
    out = args.output or (None if args.source and args.preview else
                          os.path.splitext(os.path.basename(args.head))[0] + ".landmarks.json")
    if args.preview:
        save_preview(args.preview, V, F, lm, frame=frame, confidence=confidence)
    if out:
        write_landmarks(out, lm, mesh_name=os.path.basename(args.head),
                        **({"confidence": confidence} if confidence is not None else {}))
    print(f"{out or args.preview}: {len(lm)} landmarks {how}, {time.perf_counter() - t:.1f} s"
          + (f"; preview {args.preview}" if args.preview and out else ""))
    return 0


def cmd_build_rig(args):
    import autobones

    t = time.perf_counter()
    rig = autobones.build_rig(args.base, args.landmarks)
    rig.save(args.output)
    print(f"{args.output}: {len(rig.skeleton)} bones, {len(rig.muscles)} muscles, {len(rig.fields)} fields, "
          f"{len(rig.landmarks)} landmarks, {len(rig.vertices)} vertices, {time.perf_counter() - t:.1f} s")
    return 0


def cmd_batch(args):
    from autobones.batch import make_options, run_batch, summary_table

    options = make_options(transfer=args.transfer, density=args.density, rig=args.rig,
                           expressions="sides" if args.expression_sides else args.expressions)
    show = not args.quiet and sys.stderr.isatty()
    bar = None

    def start(n_run, n_skip, n_refused):
        nonlocal bar
        import shutil

        from tqdm import tqdm

        size = shutil.get_terminal_size((100, 24))  # a terminal of unknown size reports 0 x 0: tqdm would hide the bar
        bar = tqdm(total=n_run, unit="mesh", disable=not show, file=sys.stderr, ncols=min(size.columns, 120),
                   nrows=max(size.lines, 2),
                   desc=f"rigging ({n_skip} up to date)" if n_skip else "rigging")

    def result(rec):
        line = None
        if rec["status"] == "failed":
            line = f"autobones batch: {rec['error']}"
            if args.debug and rec.get("traceback"):
                line += "\n" + rec["traceback"].rstrip()
        elif args.verbose and rec["status"] == "ok":
            line = f"autobones batch: {rec['input']} -> {rec['output']} ({rec['seconds']:.1f} s)"
        if line:
            (bar.write if bar is not None else print)(line, file=sys.stderr)
        if bar is not None and rec["status"] != "skipped" and not rec.get("error_type") == "Refused":
            bar.update(1)

    try:
        report = run_batch(args.input_dir, args.output, options, jobs=args.jobs, scheduler=args.scheduler,
                           force=args.force, on_start=start, on_result=result)
    finally:
        if bar is not None:
            bar.close()
    if not args.quiet:
        print(summary_table(report))
        print(f"report: {os.path.join(args.output, 'batch_report.json')}")
    return 0 if report["counts"]["failed"] == 0 else 1


COMMANDS = {"place": cmd_place, "transfer": cmd_transfer, "pose": cmd_pose, "landmarks": cmd_landmarks,
            "build-rig": cmd_build_rig, "batch": cmd_batch}


def _axis_values(argv):
    """argparse reads ``--front -y`` (or ``--head -10,0,0``) as two options; join such pairs as ``--front=-y``."""
    out, i = [], 0
    while i < len(argv):
        if i + 1 < len(argv) and (
                (argv[i] in ("--up", "--front") and argv[i + 1].lower() in ("-x", "-y", "-z"))
                # pose's vectors: ``--head -10,0,0`` (argparse takes only plain numbers for negative values)
                or (argv[i] in ("--gaze", "--look-at", "--head", "--neck", "--jaw") and argv[i + 1][:2] in
                    {"-" + c for c in "0123456789."})):
            out.append(f"{argv[i]}={argv[i + 1]}")
            i += 2
        else:
            out.append(argv[i])
            i += 1
    return out


def main(argv=None):
    parser = build_parser()
    args = parser.parse_args(_axis_values(sys.argv[1:] if argv is None else list(argv)))
    if args.version:
        import autobones

        print(f"autobones {autobones.__version__}")
        return 0
    if not args.command:
        parser.print_help()
        return EXIT_USER_ERROR
    logging.basicConfig(level=logging.WARNING - 10 * min(args.verbose, 2),
                        format="autobones: %(message)s", stream=sys.stderr)
    from autobones.errors import AutobonesError

    try:
        return COMMANDS[args.command](args)
    except AutobonesError as exc:
        if args.debug:
            raise
        print(f"autobones {args.command}: error: {exc}", file=sys.stderr)
        return EXIT_USER_ERROR
    except KeyboardInterrupt:
        print("autobones: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
