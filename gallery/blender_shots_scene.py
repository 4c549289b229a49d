"""Blender side of gallery/make_blender_shots.py: the add-on in a real Blender, pictured.

    blender --factory-startup --enable-event-simulate EMPTY.blend -P blender_shots_scene.py -- \
        ui ZIP PYTHON HEAD LANDMARKS OUT
    blender -b --factory-startup -P blender_shots_scene.py -- render ZIP PYTHON HEAD LANDMARKS OUT

``ui`` (a window, under Xvfb): installs the zip, opens the sidebar's autobones tab (Ctrl+wheel over it,
simulated), presses Rig (``INVOKE_DEFAULT``: the modal run with progress in the status bar), poses
the result and saves whole-window screenshots (``progress.png``, ``pose.png``, ``landmarks.png``),
``areas.json`` (where the 3D view and the status bar are, to crop them) and ``ui.json`` (how often each
panel drew, the status lines shown; tests/test_blender_addon.py checks them).
``render`` (``-b``): rigs through the operator's script path and renders the head with Blender's
workbench engine at rest and in three ARKit poses (``render_<pose>.png``).
The head is the OBJ as given (+Y up), turned upright by its object transform: the add-on rigs the
mesh in its own frame whatever the object's transform.
"""
import json
import math
import os
import sys
import traceback

import bpy
from mathutils import Euler

ARGS = sys.argv[sys.argv.index("--") + 1:]
MODE, ZIP, PYTHON, HEAD, LANDMARKS, OUT = ARGS
POSES = {"rest": {}, "jawOpen": {"jawOpen": 0.8}, "smile": {"mouthSmileLeft": 1.0, "mouthSmileRight": 1.0},
         "blink_brows": {"eyeBlinkLeft": 1.0, "eyeBlinkRight": 1.0, "browInnerUp": 1.0}}


SEEN = {"draws": {}, "status": [], "lines": []}  # panel draws, status-bar lines, the job's -v lines (ui.json)


def _watch():
    """Count each panel's draws and keep each status line the modal run shows (tests/test_blender_addon.py)."""
    from autobones_blender import panel, runner

    for cls in reversed(panel.CLASSES):  # a registered panel's methods are fixed: re-register it wrapped
        bpy.utils.unregister_class(cls)
    for cls in panel.CLASSES:
        cls.draw = _counted(cls.draw, cls.__name__)
        bpy.utils.register_class(cls)
    status = runner.Job.status

    def shown(job):
        line = status(job)
        if not SEEN["status"] or SEEN["status"][-1] != line:
            SEEN["status"].append(line)
        return line
    runner.Job.status = shown
    result = runner.Job.result

    def finished(job):
        try:
            return result(job)   # drains the job's pipes first
        finally:
            SEEN["lines"] = list(job.lines)   # every stage the job read, shown or not (the bar shows the latest)
    runner.Job.result = finished


def _counted(draw, name):
    """``draw`` counting its calls in SEEN (Blender wants exactly (self, context))."""
    def counted(self, context):
        SEEN["draws"][name] = SEEN["draws"].get(name, 0) + 1
        draw(self, context)
    return counted


def setup():
    bpy.ops.preferences.addon_install(filepath=ZIP, overwrite=True)
    bpy.ops.preferences.addon_enable(module="autobones_blender")
    _watch()
    bpy.context.preferences.addons["autobones_blender"].preferences.autobones_path = PYTHON
    V, F = [], []
    with open(HEAD) as fh:
        for line in fh:
            p = line.split()
            if p and p[0] == "v":
                V.append([float(c) for c in p[1:4]])
            elif p and p[0] == "f":
                F.append([int(c.split("/")[0]) - 1 for c in p[1:]])
    mesh = bpy.data.meshes.new("head")
    mesh.from_pydata(V, [], F)
    mesh.polygons.foreach_set("use_smooth", [True] * len(F))
    obj = bpy.data.objects.new("head", mesh)
    bpy.context.scene.collection.objects.link(obj)
    obj.rotation_euler = (math.radians(90), 0, 0)  # the file's +Y up stood up in Blender's +Z-up world
    bpy.context.view_layer.objects.active = obj
    obj.select_set(True)
    s = bpy.context.scene.autobones
    s.method, s.landmarks, s.landmarks_file, s.arkit = "TRANSFER", "FILE", LANDMARKS, True
    return obj


def set_pose(obj, shapes, jaw=0.0):
    from autobones_blender import result

    for kb in result.rig_shape_keys(obj):
        kb.value = shapes.get(kb.name, 0.0)
    result.rig_armature(obj).pose.bones["jaw"].rotation_euler = (math.radians(jaw), 0, 0)
    bpy.context.view_layer.update()


def render():
    obj = setup()
    bpy.ops.autobones.rig()
    scene = bpy.context.scene
    scene.render.engine = "BLENDER_WORKBENCH"
    scene.display.shading.light, scene.display.shading.color_type = "STUDIO", "SINGLE"
    scene.display.shading.single_color = (0.8, 0.62, 0.52)
    scene.render.resolution_x, scene.render.resolution_y = 400, 480
    scene.render.film_transparent = True
    cam = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    scene.collection.objects.link(cam)
    cam.data.type, cam.data.ortho_scale = "ORTHO", 0.3
    cam.location = (0.07, -0.5, 0.06)  # in front of the face (the file's +Z is Blender's -Y after the turn)
    cam.rotation_euler = Euler((math.radians(90), 0, math.radians(8)))
    scene.camera = cam
    for name, shapes in POSES.items():
        set_pose(obj, shapes)
        scene.render.filepath = os.path.join(OUT, f"render_{name}.png")
        bpy.ops.render.render(write_still=True)


def _view3d():
    win = bpy.context.window_manager.windows[0]
    area = next(a for a in win.screen.areas if a.type == "VIEW_3D")
    return win, area, {r.type: r for r in area.regions}


def _shot(name):
    win = bpy.context.window_manager.windows[0]
    with bpy.context.temp_override(window=win, screen=win.screen):
        bpy.ops.screen.screenshot(filepath=os.path.join(OUT, name))


class UI:
    """The window steps, one per timer tick (the UI must draw between them)."""

    def __init__(self):
        self.steps = [self.start, self.sidebar, self.rig, self.wait, self.pose, self.shot_pose, self.landmarks,
                      self.shot_landmarks, self.quit]
        self.obj = None

    def __call__(self):
        if not self.steps:
            return None
        try:
            again = self.steps[0]()
        except Exception:  # noqa: BLE001 -- say what broke and leave: a window left open waits forever
            traceback.print_exc()
            SEEN["failed"] = self.steps[0].__name__
            self.steps = [self.quit]
            return 0.1
        if not again:
            self.steps.pop(0)
        return 0.4

    def start(self):
        self.obj = setup()
        win, area, regs = _view3d()
        space = area.spaces[0]
        space.show_region_ui = True
        space.overlay.show_floor, space.overlay.show_axis_x, space.overlay.show_axis_y = False, False, False
        r3d = space.region_3d
        r3d.view_rotation = Euler((math.radians(82), 0, math.radians(28))).to_quaternion()
        r3d.view_location, r3d.view_distance = (0.0, 0.0, 0.08), 0.55
        r3d.view_perspective = "PERSP"

    def sidebar(self):
        win, area, regs = _view3d()
        ui = regs["UI"]
        x, y = ui.x + ui.width - 8, ui.y + ui.height // 2
        for _ in range(3):  # Item, Tool, View, autobones: Ctrl+wheel down cycles the tabs
            win.event_simulate(type="MOUSEMOVE", value="NOTHING", x=x, y=y)
            win.event_simulate(type="WHEELDOWNMOUSE", value="PRESS", x=x, y=y, ctrl=True)
        # widen the sidebar by dragging its left edge, so the labels are not cut
        ex, ey = ui.x + 2, ui.y + ui.height // 2
        win.event_simulate(type="MOUSEMOVE", value="NOTHING", x=ex, y=ey)
        win.event_simulate(type="LEFTMOUSE", value="PRESS", x=ex, y=ey)
        win.event_simulate(type="MOUSEMOVE", value="NOTHING", x=ex - 110, y=ey)
        win.event_simulate(type="LEFTMOUSE", value="RELEASE", x=ex - 110, y=ey)

    def rig(self):
        win, area, regs = _view3d()
        with bpy.context.temp_override(window=win, area=area, region=regs["WINDOW"]):
            bpy.ops.autobones.rig("INVOKE_DEFAULT")
        self.ticks = 0

    def wait(self):
        from autobones_blender import result

        self.ticks += 1
        if self.ticks == 3:
            _shot("progress.png")
        if result.rig_armature(self.obj) is None:
            # transfer --arkit takes ~15 s alone; on a loaded machine (2 cores, a test run beside) several
            # times that: wait up to 400 s (1,000 ticks) before giving up
            return self.ticks < 1000
        return False

    def pose(self):
        bpy.context.scene.autobones.shape_key_filter = "mouthSmile"
        set_pose(self.obj, POSES["smile"], jaw=8.0)
        for child in self.obj.children:
            child.hide_set(child.type == "EMPTY")  # the bones and the smile; landmarks get their own picture
        win, area, regs = _view3d()
        r3d = area.spaces[0].region_3d
        r3d.view_rotation = Euler((math.radians(84), 0, math.radians(24))).to_quaternion()
        r3d.view_location, r3d.view_distance = (0.0, 0.0, 0.07), 0.42

    def shot_pose(self):
        _shot("pose.png")
        win, area, regs = _view3d()
        status = next(a for a in win.screen.areas if a.type == "STATUSBAR") if any(
            a.type == "STATUSBAR" for a in win.screen.areas) else None
        with open(os.path.join(OUT, "areas.json"), "w") as fh:
            json.dump({"window": [win.width, win.height], "view3d": [area.x, area.y, area.width, area.height],
                       "statusbar": [status.x, status.y, status.width, status.height] if status else None}, fh)

    def landmarks(self):
        from autobones_blender import result

        set_pose(self.obj, {}, jaw=0.0)
        for child in self.obj.children:
            child.hide_set(child.type == "ARMATURE")
        s = bpy.context.scene.autobones
        s.landmarks, s.landmark_name = "EMPTIES", "cheilion_l"
        win, area, regs = _view3d()
        r3d = area.spaces[0].region_3d
        r3d.view_rotation = Euler((math.radians(88), 0, math.radians(18))).to_quaternion()
        r3d.view_location, r3d.view_distance = (0.0, -0.05, 0.1), 0.3

    def shot_landmarks(self):
        _shot("landmarks.png")

    def quit(self):
        with open(os.path.join(OUT, "ui.json"), "w") as fh:
            json.dump(SEEN, fh, indent=1)
        bpy.ops.wm.quit_blender()


if MODE == "render":
    render()
else:
    bpy.app.timers.register(UI(), first_interval=1.0)
