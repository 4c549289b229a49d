"""The commands' help texts: examples, outputs, units (argparse epilogs)."""
from __future__ import annotations

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

SAMPLES_EPILOG = """\
examples:
  autobones samples s/                      then, for instance:
  autobones place s/scan.obj -o scan.glb
  autobones transfer s/robot.obj --landmarks s/robot.landmarks.json --arkit -o robot.glb
  autobones animate robot.glb --capture s/take.csv -o robot.anim.glb

written: default_head, scan, bust, robot, goat (.obj and .landmarks.json each), goat.pp,
take.csv, README.md (what to try on each) and LICENSES.md (sources, licences, attribution).
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

Landmark names, frame and file formats: docs/guide/transfer.md (the landmark contract). Bad landmarks
(unknown names, left/right swapped, off the surface, wrong units, too few) are refused
with one line naming the problem.
"""

LANDMARKS_EPILOG = """\
examples:
  autobones landmarks scan.obj -o scan.landmarks.json                   found automatically (human faces)
  autobones landmarks scan.obj -o scan.landmarks.json --preview scan.png
  autobones landmarks goat.obj --from goat.pp --preview goat.png        convert a file and draw it
  autobones landmarks bust.stl --up +z --front -y -o bust.landmarks.json
  autobones landmarks cow.obj --assist cow5.json -o cow.landmarks.json   the rest from 5 placed names
  autobones landmarks cow.obj --edit -o cow.landmarks.json              place and check them in the browser
  autobones landmarks goat.obj --edit --from goat.pp -o goat.pp         edit a MeshLab file (and its JSON)

How: the head is turned upright, rendered on the CPU from the front and four views around it
(+-30 deg yaw, +-15 deg pitch), MediaPipe Face Mesh finds 468 points in each picture, they are
lifted onto the surface and combined across views; then midline names go onto the face's
symmetry plane, left/right pairs become mirror images, the nose tip and menton are taken from
the midline profile. A name whose views disagree is dropped, not guessed; a pair whose sides
disagree is flagged. 27 of the contract's names are found (the ones a face picture shows).

Animals, most cartoons and back-of-head scans have no face the detector knows: the command
says so (exit code 2) and writes nothing; give their landmarks by hand (--from, MeshLab .pp), or
place five (the outer eye corners, the nose tip, the mouth corners) and let --assist propose the
rest: the generic head is fitted to the mesh through them and its landmarks read off it
("confidence" then falls with the distance from the placed names and where the fit meets the
surface poorly; check the proposals, they are a start, not a measurement).
Finding them automatically needs the optional detector: pip install 'autobones[landmarks]'.

--edit: a page on 127.0.0.1 (the first line printed is its URL; --no-browser opens none, --port 0
picks a free port). Click the head to place the selected name, drag a point to move it, Ctrl+Z /
Ctrl+Shift+Z undo and redo; a left or right name's partner is proposed across the symmetry plane, and
once exocanthion_l/_r, pronasale and cheilion_l/_r are placed the rest are proposed as with --assist.
transfer's checks (off the surface, units, left/right swapped, too few) show beside each name as you
go. Save writes -o atomically (and a MeshLab .pp with --pp, or when -o ends in .pp); closing the page
without saving writes nothing; Done or Ctrl-C stops. It starts from --from or --assist, else from
automatic detection (no face found: empty, with a note on the page).

output: the contract's JSON ({"format": "autobones-landmarks/1", "landmarks": {name: [x, y, z]}}),
in the mesh's own frame and units, plus "confidence" per name (1 = every view agrees).
"""

BUILD_EPILOG = """\
examples:
  autobones build-rig base.obj --landmarks base.landmarks.json -o my_rig/
  autobones transfer scan.obj --landmarks scan.landmarks.json --rig my_rig/ -o scan.glb
  autobones build-rig base.obj --landmarks base.landmarks.json -o my_rig/ --shapes studio_arkit/
  autobones transfer scan.obj --landmarks scan.landmarks.json --rig my_rig/ --arkit -o scan.glb
                                        the studio's ARKit shapes (not ICT-FaceKit's) on the scan
"""

BATCH_EPILOG = """\
examples:
  autobones batch heads/ -o rigs/ --density dense --jobs 2      place on every mesh, recursively
  autobones batch heads/ -o rigs/ --transfer                    landmarks NAME.landmarks.json / NAME.pp beside each
                                                                mesh; found automatically where there is none
  autobones batch heads/ -o rigs/ --scheduler tcp://scheduler.example:8786    the same, on a Dask cluster

output: OUT/<path relative to INPUT_DIR without extension>.rig.glb, .rig.json, .weights.npz per
mesh (the names place and transfer give), and OUT/batch_report.json (per file: status
ok/failed/skipped, error, timings, options). Meshes whose outputs are up to date (newer than
the input, same options) are skipped, so an interrupted batch is resumed by running it again.
Outputs that exist but are out of date are overwritten only with --force. The output folder
may not overlap the input folder.

exit code: 0 when every file is ok or up to date, 1 when any file failed, 2 for a bad
command (missing folder, overlapping folders, bad option).
"""

VIEW_EPILOG = """\
examples:
  autobones view head.glb                 one rig: orbit, pose, weights, expressions, landmarks, muscles
  autobones view rigs/                    a batch output folder: thumbnails and the QA report; click to open
  autobones view rigs/ --no-browser --port 8765       print the URL only (a remote machine: ssh -L 8765:...)

The first line printed is the page's URL (http://127.0.0.1:PORT/); the server listens on
127.0.0.1 only, serves only the files under the rig's folder (or the folder given), never
writes anything, and stops with Ctrl-C. three.js is bundled: no network is needed.

on the rig page: drag to orbit, wheel to zoom; colour the skin by a bone's weight (the glb's
4 largest influences or the full matrix of x.weights.npz); pitch/yaw/roll sliders per bone
(degrees, about the head frame's axes; pitch > 0 opens the jaw, nods the head down); a
slider per morph target (AU1..., 0..1); landmarks, muscles and the skeleton on request.
"""

EXPORT_EPILOG = """\
examples:
  autobones export head.glb -o head.usda          UsdSkel as text (.usdc / .usd: binary, .usdz: package)
  autobones export head.glb -o head.fbx           FBX through Blender run headless (Blender on PATH)
  autobones export scan.glb -o scan.usdc --meters-per-unit 0.01     a scan in centimetres, said outright

RIG.glb is what place, transfer or batch wrote, with RIG.rig.json and RIG.weights.npz
beside it (the weights file holds every influence; the glb only the four largest).

USD (needs usd-core: pip install 'autobones[usd]'): SkelRoot /Rig with a Skeleton (one joint
per bone, joint paths neck/head/jaw..., bind = rest = the glb's pose), the Mesh bound with every
non-zero weight per vertex, one BlendShape per morph target (AU12...), a SkelAnimation per glb
animation, and the frame, landmarks and muscles in /Rig's customData["autobones"]. Points stay in
the rig's own frame and units. upAxis: Y or Z when the rig's up is +y or +z, else Y with a
rotation on /Rig. metersPerUnit: the power of ten that makes the head about 0.3 m (a metre,
centimetre or millimetre human head comes out right); give --meters-per-unit otherwise.
The file is checked with USD's own validators; their findings are listed on stderr.

FBX (needs Blender >= 3.4 on PATH; Debian: apt-get install blender): armature, mesh with one
vertex group per bone holding every weight, shape keys, muscle markers as empties, Y up.

bad input (not an autobones glb, sidecars missing, unknown suffix, -o = the input): one line,
exit code 2, nothing written.
"""

BLENDER_ADDON_EPILOG = """\
examples:
  autobones blender-addon                          -> autobones_blender.zip
  autobones blender-addon -o ~/addons/autobones_blender.zip

In Blender (3.4 or newer): Edit > Preferences > Add-ons > Install... > the zip, tick
"Rigging: autobones". Its preference names the Python that has autobones installed (or the
autobones executable); empty: autobones on PATH. Blender's own Python needs nothing.

The sidebar (N) of the 3D view gets an autobones tab: Rig the active mesh with place or
transfer (landmarks from a file, from empties, or automatic; --arkit, --expressions), place
landmarks as empties on the skin and write them out, pose the jaw, head, neck and eyes and the
shape keys. See docs/blender.md.

bad output (not .zip, an existing file that is not a zip, a missing folder): one line, exit
code 2, nothing written.
"""


def pose_epilog():
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

emotions (Erdoğdu 2010, Table 3-3):
{emotions}
"""


ANIMATE_EPILOG = """\
examples:
  autobones transfer head.obj --landmarks head.landmarks.json --arkit -o head.glb
  autobones animate head.glb --capture take.csv -o take.glb

The CSV is what Live Link Face records: a header Timecode, BlendShapeCount, one column per ARKit
shape (EyeBlinkLeft ... TongueOut, ARKit's names capitalised; Left is the subject's left), then
HeadYaw, HeadPitch, HeadRoll, LeftEyeYaw ... RightEyeRoll in radians (optional); one row per
frame, Timecode HH:MM:SS:FF.fff increasing. An unknown column, a bad row or a time that does not
increase is refused (exit 2) and nothing is written.
"""
