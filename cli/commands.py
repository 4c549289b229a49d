"""The ``autobones`` commands: each calls the library and prints one line (errors: see :mod:`.main`)."""
from __future__ import annotations

import os
import sys
import time

from .pose_names import check_pose_names
from .progress import progress, stopwatch
from .values import number, pairs, seed, vector


def cmd_place(args):
    import autobones

    if args.expressions:
        from autobones.errors import AutobonesError

        raise AutobonesError("--expressions needs muscles, which place does not make; use "
                             "autobones transfer HEAD --landmarks FILE --expressions -o OUT.glb")
    head = args.head
    out = args.output or _default_out(head)
    random_state = seed(args.seed, "--seed")
    _check_outputs(_rig_saved(out), [head, args.landmarks])
    t = time.perf_counter()
    with progress(args, "placing bones"):
        rig = autobones.place(head, density=args.density, up=args.up, front=args.front, random_state=random_state,
                              landmarks=args.landmarks, rig=args.rig)
        written = rig.save(out)
    print(f"{written[0]}: {len(rig.skeleton)} bones ({rig.options['facial_bones']} facial), "
          f"{len(rig.vertices)} vertices, up {rig.frame.up}, front {rig.frame.front}, "
          f"{time.perf_counter() - t:.1f} s; sidecars {os.path.basename(written[1])}, {os.path.basename(written[2])}")
    joints = (rig.other or {}).get("joints") or {}
    head = joints.get("head", {})
    if "no_neck" in joints.get("neck", {}).get("cues", []) and "face_only" not in head.get("cues", []):
        # a face mask's own line below says its neck has nothing to bend
        print("joints: no neck (a closed head ending at its chin): the whole head turns with the head bone and the "
              "neck bone weighs nothing (sidecar joints.neck)")
    if "face_only" in head.get("cues", []):   # a mask's pivot is a guess from a face's proportions: say so
        how = ("from the face's automatic landmarks by a human's proportions" if "face_landmarks" in head["cues"]
               else "behind the nose by a face's proportions"
               + (f" (automatic landmarks: {head['face_landmarks']})" if head.get("face_landmarks") else ""))
        print(f"joints: a face mask (open at the back, no neck): the head pivot is placed {how} and the neck has "
              "nothing to bend; rig the whole head for its own pivot (sidecar joints.head)")
    return 0


def _rig_outputs(out):
    """The three files ``Rig.save(out)`` writes (just ``out`` when it is no .glb: an input rig's name)."""
    from autobones.rig import sidecar_paths

    return [out, *sidecar_paths(out)] if out.lower().endswith(".glb") else [out]


def _check_outputs(outputs, inputs):
    """Refuse, before any work, an output that cannot be written: one of the files read (``place a.glb
    -o a.glb``), in a missing or read-only folder, or where a folder stands (``autobones.io.atomic.check_outputs``)."""
    from autobones.io.atomic import check_outputs

    check_outputs(outputs, inputs)


def _rig_saved(out):
    """The files ``Rig.save(out)`` writes, refused at once when ``out`` is no .glb."""
    from autobones.rig import rig_outputs

    return rig_outputs(out)


def _default_out(head):
    stem = "default_head" if head is None else os.path.splitext(os.path.basename(head))[0]
    return f"{stem}.rig.glb"


def cmd_transfer(args):
    import autobones

    out = args.output or _default_out(args.head)
    if args.tissue and not (args.expressions or args.expression_sides):
        from autobones.errors import AutobonesError

        raise AutobonesError("--tissue refines the AU morph targets: add --expressions (or pose with "
                             "autobones pose RIG.glb --tissue)")
    _check_outputs(_rig_saved(out), [args.head, args.landmarks])
    t = time.perf_counter()
    with progress(args, "transferring the rig" + (" and its ARKit shapes" if args.arkit else "")):
        rig = autobones.transfer(args.head, args.landmarks, rig=args.rig, up=args.up, front=args.front,
                                 arkit=args.arkit, symmetric=args.symmetric, expression_fit=args.expression_fit)
    watch = stopwatch()  # the transfer's own stages are logged inside it
    with progress(args, "writing" + (" the morph targets" if args.expressions or args.expression_sides else "")):
        written = rig.save(out, expressions="sides" if args.expression_sides else args.expressions,
                           tissue=args.tissue)
    watch.lap("write")
    if rig.options.get("landmarks_source") == "detected":
        conf = rig.landmark_confidence or {}
        dropped = rig.landmarks_dropped or []
        print(f"landmarks: {len(conf)} found automatically, mean confidence {sum(conf.values()) / max(len(conf), 1):.2f}"
              + (f"; dropped {', '.join(dropped)}" if dropped else "")
              + f" (check them: autobones landmarks {args.head} --preview PNG)")
    if rig.options.get("joints_from_face"):   # a human's proportions, not this head's: the user can do better
        print("joints: head and jaw placed from the face's landmarks by a human's proportions (the file has no "
              "ears); add tragion_l and tragion_r to place them from the ear canals (sidecar options.joints_from_face)")
    worn = (rig.options.get("expression_fit") or {}).get("weights") or {}
    if worn:   # a scan's expression is news to the user: the rig's rest pose wears it
        print("expression: the head seems to wear " + ", ".join(f"{k} {v:.2f}" for k, v in list(worn.items())[:4])
              + "; the generic skin wore it in the fit (--no-expression-fit: fit it neutral)")
    print(f"{written[0]}: {len(rig.skeleton)} bones, {len(rig.muscles or [])} muscles, "
          f"{len(rig.fields)} fields, {len(rig.options['landmarks_used'])} landmarks used, "
          f"{len(rig.vertices)} vertices, {time.perf_counter() - t:.1f} s; "
          f"sidecars {os.path.basename(written[1])}, {os.path.basename(written[2])}"
          + (f"; {_morph_target_count(written[1])} morph targets" if args.expressions or args.expression_sides else "")
          + (f"; {len(rig.arkit_targets)} ARKit shapes" + _flipped_note(rig.arkit) if args.arkit else ""))
    return 0


def _flipped_note(record):
    """``; triangles turned over at weight 1: mouthClose 5 (ICT's own 597), ...`` for the shapes that fold any."""
    record = record or {}
    src = record.get("source_flipped_triangles", {})
    # after the fold repair, mouthClose judged on top of jawOpen as ARKit drives it; older records: each alone
    counts = record.get("folds", {}).get("after_repair", record.get("flipped_triangles", {}))
    bad = {n: c for n, c in counts.items() if c}
    return ("; triangles turned over at weight 1: " + ", ".join(f"{n} {c} (ICT's own {src.get(n, 0)})"
                                                              for n, c in bad.items())) if bad else ""


def _morph_target_count(sidecar):
    from autobones.io.files import read_json

    return len(read_json(sidecar, "sidecar")["expressions"]["morph_targets"])


def cmd_pose(args):
    import numpy as np

    import autobones
    from autobones.errors import AutobonesError
    from autobones.expressions.au_shapes import resolve_layer
    from autobones.expressions.definitions import load_expressions, parse_au_key
    from autobones.io.posed import FORMATS, write_posed_mesh

    t = time.perf_counter()
    au = {parse_au_key(k)[0]: v for k, v in pairs(args.au, "--au", default=1.0).items()}
    expression = pairs(args.expression, "--expression", default=1.0)
    muscles = pairs(args.muscle, "--muscle")
    eyelids = pairs(args.eyelids, "--eyelids")
    arkit = pairs(args.arkit, "--arkit", default=1.0)
    jaw = number(args.jaw, "--jaw")
    gaze, look_at = vector(args.gaze, 2, "--gaze"), vector(args.look_at, 3, "--look-at")
    head_deg, neck_deg = vector(args.head_deg, 3, "--head"), vector(args.neck_deg, 3, "--neck")
    out = args.output or os.path.splitext(os.path.basename(args.rig))[0].removesuffix(".rig") + ".pose.obj"
    if os.path.splitext(out)[1].lower() not in FORMATS:  # refused before the rig is read
        raise AutobonesError(f"{out}: the posed mesh is written as .obj or .glb")
    _check_outputs([out], [*_rig_outputs(args.rig), args.definitions])
    # read and checked before the rig: a bad file is refused without loading (or fitting) anything
    watch = stopwatch()
    definitions = load_expressions(args.definitions) if args.definitions else None
    rig = autobones.load_rig(args.rig)
    watch.lap("read")
    turns_only = (head_deg or neck_deg) and not arkit and definitions is None and rig.only_turns(
        au or None, expression or None, muscles or None, jaw, eyelids or None, gaze, look_at, args.tissue)
    if not rig.muscles and not (arkit and rig.arkit_targets) and not turns_only:
        raise AutobonesError(f"{args.rig}: this rig has no muscles (`autobones place` makes none): it poses only "
                             "--head and --neck; the rest needs a rig saved by autobones transfer HEAD --landmarks "
                             "FILE -o OUT.glb")
    layer = resolve_layer(args.layer, bool(rig.arkit_targets))  # --layer shapes on a rig without: refused here
    # names checked before the skin/muscle model is built (seconds on a large head): a typo costs nothing
    check_pose_names(rig, definitions, expression, au, muscles, eyelids, arkit, shapes=layer == "shapes")
    if rig.muscles and (definitions is not None or au or expression or muscles or eyelids or jaw or gaze or look_at
                        or head_deg or neck_deg or args.tissue):
        with progress(args, "building the skin/muscle model"):
            rig.expression_model(definitions)  # pose uses the model built last
        watch.lap("model")
    with progress(args, "posing"):
        V = rig.pose(au=au or None, expression=expression or None, muscles=muscles or None, jaw_deg=jaw,
                     eyelids=eyelids or None, gaze=gaze, look_at=look_at, head_deg=head_deg, neck_deg=neck_deg,
                     arkit=arkit or None, tissue=args.tissue, layer=layer)
    watch.lap("pose")
    what = ", ".join([f"{k} {v:g}" for k, v in expression.items()] + [f"AU{k} {v:g}" for k, v in au.items()]
                     + [f"{k} {v:g}" for k, v in muscles.items()] + ([f"jaw {jaw:g} deg"] if jaw else [])
                     + [f"eyelids {k} {v:g}" for k, v in eyelids.items()]
                     + ([f"gaze {args.gaze}"] if gaze else []) + ([f"look at {args.look_at}"] if look_at else [])
                     + ([f"head {args.head_deg}"] if head_deg else []) + ([f"neck {args.neck_deg}"] if neck_deg else [])
                     + [f"{k} {v:g}" for k, v in arkit.items()] + (["tissue"] if args.tissue else [])
                     + (["mapped AUs through the ARKit shapes"] if layer == "shapes" and (au or expression) else []))
    write_posed_mesh(out, V, rig.faces, comment=f"autobones pose {os.path.basename(args.rig)}: {what or 'neutral'}")
    watch.lap("write")
    moved = float(np.linalg.norm(V - rig.vertices, axis=1).max()) if len(V) else 0.0
    print(f"{out}: {what or 'neutral'}; {len(V)} vertices, largest displacement {moved:.4g} "
          f"({moved / rig.frame.size:.1%} of the head size), {time.perf_counter() - t:.1f} s")
    return 0


def _assist_source(found):
    """Where ``--assist``'s proposals came from (an ``Assisted``), for its one line."""
    if found.detected:
        return f"a person's face: {len(found.detected)} from the automatic detector, the rest from the generic head's fit"
    if found.human:
        return "a person's face, no automatic landmarks agreeing with yours: all from the generic head's fit"
    return "not a person's face: all from the generic head's fit"


def cmd_landmarks(args):
    if args.edit:
        return _edit_landmarks(args)
    from autobones.errors import AutobonesError

    for given, option in ((args.pp, "--pp"), (args.port, "--port"), (args.no_browser, "--no-browser")):
        if given:
            raise AutobonesError(f"{option} goes with --edit (the landmark editor in the browser)")
    import autobones
    from autobones.io.landmarks import read_landmarks, validate_landmarks, write_landmarks
    from autobones.landmarks.preview import save_preview

    t = time.perf_counter()
    out = args.output or (None if args.source and args.preview else
                          os.path.splitext(os.path.basename(args.head))[0] + ".landmarks.json")
    from autobones.errors import AutobonesError

    if args.rig and not args.assist:
        raise AutobonesError("--rig is the generic rig --assist fits: give --assist PARTIAL too")
    if args.source and args.assist:
        raise AutobonesError("--from reads every landmark from a file and --assist proposes them from a few: "
                             "give one of them")
    _check_outputs([out, args.preview], [args.head, args.source, args.assist])
    watch = stopwatch()
    V, F = autobones.load_mesh(args.head)
    watch.lap("load")
    if args.assist:
        from autobones.landmarks.assist import assist_landmarks

        given = validate_landmarks(read_landmarks(args.assist), V, F, min_count=1, source=args.assist)
        with progress(args, "fitting the generic head"):
            # on a human face the detector's names replace the fit's where it finds them
            found = assist_landmarks(V, F, given, rig=args.rig, detected="auto")
        lm, frame, confidence = found.points, found.frame, found.confidence
        proposed = [n for n in lm if n not in given]
        how = (f"from {args.assist} ({len(given)} given), {len(proposed)} proposed, mean confidence "
               f"{sum(confidence[n] for n in proposed) / max(len(proposed), 1):.2f}; {_assist_source(found)}")
        if found.omitted:
            how += "; omitted " + ", ".join(sorted(found.omitted))
        watch.lap("assist")
    elif args.source:
        frame = autobones.detect_frame(V, F, up=args.up, front=args.front) if args.up or args.front else None
        lm = validate_landmarks(read_landmarks(args.source), V, F, frame=frame, min_count=1, source=args.source)
        watch.lap("check")
        confidence, how = None, f"read from {args.source}"
    else:
        with progress(args, "finding landmarks"):
            lm = autobones.detect_landmarks((V, F), up=args.up, front=args.front, name=args.head)
        frame, confidence = lm.frame, lm.confidence
        how = f"found automatically, mean confidence {sum(confidence.values()) / max(len(confidence), 1):.2f}"
        if lm.dropped:
            how += "; dropped " + ", ".join(f"{n} ({why})" for n, why in lm.dropped.items())
        if lm.flagged:
            how += "; check " + ", ".join(sorted(lm.flagged))
    if args.preview:
        save_preview(args.preview, V, F, lm, frame=frame, confidence=confidence)
        watch.lap("preview")
    if out:
        write_landmarks(out, lm, mesh_name=os.path.basename(args.head),
                        **({"confidence": confidence} if confidence is not None else {}))
        watch.lap("write")
    print(f"{out or args.preview}: {len(lm)} landmarks {how}, {time.perf_counter() - t:.1f} s"
          + (f"; preview {args.preview}" if args.preview and out else ""))
    return 0


def _edit_landmarks(args):
    """``landmarks HEAD --edit``: serve the editor until the page says done or Ctrl-C."""
    from autobones.errors import AutobonesError
    from autobones.view.editor_server import make_editor_server
    from autobones.view.landmark_session import open_session
    from autobones.view.server import parse_port

    if args.preview:
        raise AutobonesError("--preview draws landmarks from a file; with --edit, save them first, then "
                             "autobones landmarks HEAD --from SAVED --preview PNG")
    if args.source and args.assist:
        raise AutobonesError("--from and --assist both name the landmarks to start from: give one of them")
    port = parse_port(args.port if args.port is not None else 0)  # refused before the mesh is read
    watch = stopwatch()
    with progress(args, "reading the head" + ("" if args.source or args.assist else " and finding landmarks")):
        # --assist PARTIAL: its names placed, and the page proposes the rest from them at once
        session = open_session(args.head, output=args.output, pp=args.pp, source=args.source or args.assist,
                               up=args.up, front=args.front, rig=args.rig)
    watch.lap("load")
    server = make_editor_server(session, port)
    watch.lap("serve")
    print(server.url, flush=True)  # first line: scripts read the URL from here
    print(f"autobones landmarks: editing {args.head}; Save writes {session.output}"
          + (f" and {session.pp_output}" if session.pp_output else "") + "; Done on the page or Ctrl-C stops",
          file=sys.stderr, flush=True)
    _serve(server, "landmarks", args.no_browser)
    print(f"autobones landmarks: saved {', '.join(session.saved)}" if session.saved
          else "autobones landmarks: closed without saving; nothing written", file=sys.stderr)
    return 0


def cmd_samples(args):
    from autobones.samples import write_samples

    watch = stopwatch()
    written = write_samples(args.folder, force=args.force)
    watch.lap("write")
    print(f"{args.folder}: {len(written)} files ({', '.join(p.name for p in written if p.suffix == '.obj')}, "
          f"their landmarks, take.csv); licences in {os.path.join(args.folder, 'LICENSES.md')}")
    return 0


def cmd_build_rig(args):
    import autobones

    from autobones.errors import AutobonesError

    folder = os.path.realpath(args.output)
    for inp in (args.base, args.landmarks, args.shapes):  # the output folder is replaced as a whole
        if inp and (os.path.realpath(inp) == folder or os.path.realpath(inp).startswith(folder + os.sep)):
            raise AutobonesError(f"{args.output}: the output folder holds the input {inp}, and is replaced as a "
                                 "whole; choose another folder (-o)")
    from autobones.labelled_rig import check_rig_folder

    check_rig_folder(args.output)   # before the build, as the save will: a mistyped -o costs nothing
    t = time.perf_counter()
    shapes = None
    if args.shapes:  # read and checked before anything is built or written
        from autobones.arkit.studio import read_studio_shapes, write_shape_set

        shapes = read_studio_shapes(args.shapes)
    watch = stopwatch()
    with progress(args, "building the rig"):
        rig = autobones.build_rig(args.base, args.landmarks)
        rig.save(args.output)
    watch.lap("build")
    if shapes is not None:
        write_shape_set(shapes, args.output)
    from autobones.rig_transfer.expression_space import build_expression_space

    with progress(args, "carrying the ARKit shapes onto the base (its expression space)"):
        build_expression_space(args.output)   # what transfer's expression fit poses this base with
    watch.lap("expression space")
    print(f"{args.output}: {len(rig.skeleton)} bones, {len(rig.muscles)} muscles, {len(rig.fields)} fields, "
          f"{len(rig.landmarks)} landmarks, {len(rig.vertices)} vertices"
          + (f", ARKit shapes {len(shapes.deltas)} given ({len(shapes.meta['absent'])} absent)" if shapes else "")
          + f", {time.perf_counter() - t:.1f} s")
    return 0


def cmd_batch(args):
    from autobones.batch import make_options, run_batch, summary_table

    options = make_options(transfer=args.transfer, density=args.density, rig=args.rig,
                           expressions="sides" if args.expression_sides else args.expressions, arkit=args.arkit,
                           symmetric=args.symmetric, tissue=args.tissue, expression_fit=args.expression_fit)
    show = not args.quiet and sys.stderr.isatty()
    bar = None
    watch = stopwatch()

    def start(n_run, n_skip, n_refused):
        nonlocal bar
        watch.lap("plan")
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
            # one write for the line and its newline: stderr writes through, and a worker's warning written
            # between the two landed on this line (CI: "...(first: vertex 3)inconsistent_winding.obj: ...")
            (bar.write if bar is not None else print)(line + "\n", file=sys.stderr, end="")
        if bar is not None and rec["status"] != "skipped" and not rec.get("error_type") == "Refused":
            bar.update(1)

    try:
        report = run_batch(args.input_dir, args.output, options, jobs=args.jobs, scheduler=args.scheduler,
                           force=args.force, on_start=start, on_result=result)
    finally:
        if bar is not None:
            bar.close()
    watch.lap("rig")
    if not args.quiet:
        print(summary_table(report))
        print(f"report: {os.path.join(args.output, 'batch_report.json')}")
    return 0 if report["counts"]["failed"] == 0 else 1


def cmd_view(args):
    from autobones.view import make_server

    watch = stopwatch()
    server = make_server(args.path, args.port)
    watch.lap("serve")
    print(server.url, flush=True)  # first line: scripts read the URL from here
    print(f"autobones view: showing {args.path} ({server.site.mode}); Ctrl-C to stop", file=sys.stderr, flush=True)
    _serve(server, "view", args.no_browser)
    return 0


def _serve(server, command, no_browser):
    """Open the page (unless ``no_browser``) and serve until the page says done or Ctrl-C."""
    if not no_browser:
        import webbrowser

        webbrowser.open(server.url)
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        print(f"autobones {command}: stopped", file=sys.stderr)
    finally:
        server.server_close()


def cmd_export(args):
    from autobones.errors import AutobonesError
    from autobones.export import export_format

    # the output naming the input first: `export a.glb -o a.glb` is that, not a question of suffix
    _check_outputs([args.output], [args.rig, *_rig_outputs(args.rig)[1:]])
    fmt = export_format(args.output)
    t = time.perf_counter()
    if fmt == "usd":
        from autobones.export.usd import write_usd

        watch = stopwatch()
        with progress(args, "writing USD"):
            r = write_usd(args.rig, args.output, meters_per_unit=args.meters_per_unit)
        watch.lap("usd")
        errors = [f for f in r["validation"] if f[0] == "Error"]
        print(f"{r['path']}: UsdSkel, {r['joints']} joints, {r['vertices']} vertices, {r['influences']} influences per "
              f"vertex, {r['blend_shapes']} blend shapes, {r['animations']} animations; upAxis {r['up_axis']}, "
              f"metersPerUnit {r['meters_per_unit']:g}; USD validation: {len(errors)} errors, "
              f"{len(r['validation']) - len(errors)} warnings; {time.perf_counter() - t:.1f} s")
        for kind, name, message in r["validation"]:
            print(f"  {kind} {name}: {message}", file=sys.stderr)
        return 0
    if args.meters_per_unit is not None:
        raise AutobonesError("--meters-per-unit applies to USD output only")
    from autobones.export.fbx import write_fbx

    watch = stopwatch()
    with progress(args, "writing FBX in Blender"):
        r = write_fbx(args.rig, args.output)
    watch.lap("fbx")
    print(f"{r['path']}: FBX (Blender {r['blender']}), {r['bones']} bones, {r['vertices']} vertices, "
          f"{r['influences']} influences per vertex, {r['shape_keys']} shape keys, {r['markers']} markers, "
          f"{r['animations']} animations; {time.perf_counter() - t:.1f} s")
    return 0


def cmd_animate(args):
    from autobones.arkit.animation import save_animated_rig
    from autobones.arkit.capture import read_capture
    from autobones.errors import AutobonesError

    if not args.output.lower().endswith(".glb"):
        raise AutobonesError(f"{args.output}: the animation is written as a .glb")
    _check_outputs(_rig_outputs(args.output), [*_rig_outputs(args.rig), args.capture])
    t = time.perf_counter()
    watch = stopwatch()
    capture = read_capture(args.capture, fps=number(args.fps, "--fps"))
    watch.lap("capture")
    with progress(args, "writing the animation"):
        written = save_animated_rig(args.rig, capture, args.output, bones=not args.no_bones)
    watch.lap("animation")
    from autobones.errors import counted

    print(f"{args.output}: {counted(len(capture.times), 'frame')}, {capture.times[-1]:.2f} s, "
          f"{len(capture.weights)} ARKit shapes" + ("" if args.no_bones or not capture.angles else ", head and eye turns")
          + f", {time.perf_counter() - t:.1f} s; sidecars {os.path.basename(written[1])}, "
          f"{os.path.basename(written[2])}")
    return 0


def cmd_blender_addon(args):
    from autobones.blender_zip import write_addon_zip

    watch = stopwatch()
    r = write_addon_zip(args.output)
    watch.lap("write")
    print(f"{r['path']}: Blender add-on {r['module']} ({r['files']} files, {r['bytes']} bytes); install it in "
          f"Blender with Edit > Preferences > Add-ons > Install..., then see the sidebar's autobones tab")
    return 0


COMMANDS = {"place": cmd_place, "samples": cmd_samples, "transfer": cmd_transfer, "pose": cmd_pose, "landmarks": cmd_landmarks,
            "build-rig": cmd_build_rig, "batch": cmd_batch, "view": cmd_view,
            "export": cmd_export, "animate": cmd_animate, "blender-addon": cmd_blender_addon}
