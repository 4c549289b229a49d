"""The add-on's operators: rig the active mesh, place / snap / write landmarks, reset the pose.

Beyond the papers (issue #37). ``autobones.rig`` runs autobones to the end when called from a script
or ``blender -b`` (``execute``) and in the background with progress in the status bar when pressed in
the UI (``invoke`` + a modal timer; Esc stops it). Every problem a user can fix is one line in
Blender's report (a script sees it as the RuntimeError ``bpy.ops`` raises), never a traceback.
"""
import os
import re
import shutil
import tempfile
import time

import bpy
from bpy_extras.io_utils import ExportHelper

from . import landmark_empties, result, runner
from .runner import AddonError
from .settings import landmark_names, preferences


def _mesh(context):
    """The active object when it is a mesh; AddonError saying what to select otherwise."""
    obj = context.active_object
    if obj is None or obj.type != "MESH":
        what = "nothing is active" if obj is None else f"the active object {obj.name} is a {obj.type.lower()}"
        raise AddonError(f"autobones: select a mesh object to rig ({what})")
    return obj


def _work_folder(settings):
    """(folder for the run's files, whether it is a temporary one to remove afterwards)."""
    if settings.output_dir.strip():
        folder = os.path.abspath(bpy.path.abspath(settings.output_dir))
        if not os.path.isdir(folder):
            raise AddonError(f"autobones: the folder to keep files in does not exist: {folder}")
        return folder, False
    return tempfile.mkdtemp(prefix="autobones-blender-"), True


def _landmark_file(settings, obj, folder, stem):
    """The ``--landmarks`` file for the run (None for automatic / none)."""
    if settings.landmarks == "FILE":
        path = bpy.path.abspath(settings.landmarks_file).strip()
        if not path:
            raise AddonError("autobones: choose a landmark file (or landmarks from empties / automatic)")
        return os.path.abspath(path)
    if settings.landmarks == "EMPTIES":
        landmarks = landmark_empties.collect(obj)
        if not landmarks:
            raise AddonError(f"autobones: {obj.name} has no landmark empties; place some in the Landmarks panel")
        return runner.write_landmarks(os.path.join(folder, stem + ".landmarks.json"), landmarks, stem + ".obj")
    return None


def prepare(context):
    """Everything a run needs: (mesh object, command, output glb, folder, remove folder afterwards)."""
    obj = _mesh(context)
    if obj.mode != "OBJECT":  # edit-mode changes reach the mesh data only in object mode
        try:
            bpy.ops.object.mode_set(mode="OBJECT")
        except RuntimeError as exc:
            raise AddonError(runner.one_line(f"autobones: cannot leave {obj.mode.lower()} mode: {exc}")) from None
    settings = context.scene.autobones
    cmd = runner.autobones_command(preferences(context).autobones_path)
    folder, temporary = _work_folder(settings)
    try:
        stem = re.sub(r"[^A-Za-z0-9_-]+", "_", obj.name) or "mesh"
        mesh_path = os.path.join(folder, stem + ".obj")
        runner.write_obj(mesh_path, obj.data)
        landmarks = _landmark_file(settings, obj, folder, stem)
        out = os.path.join(folder, stem + ".glb")
        return obj, cmd + runner.rig_arguments(settings, mesh_path, out, landmarks), out, folder, temporary
    except OSError as exc:  # a full disk, a folder that takes no files
        if temporary:
            shutil.rmtree(folder, ignore_errors=True)
        raise AddonError(runner.one_line(f"autobones: cannot write the mesh in {folder}: {exc}")) from None
    except BaseException:
        if temporary:
            shutil.rmtree(folder, ignore_errors=True)
        raise


def _summary(obj, made, seconds=None):
    took = "" if seconds is None else f", {seconds:.1f} s"
    return (f"autobones: rigged {obj.name}: {made['bones']} bones, {made['vertex_groups']} vertex groups (up to "
            f"{made['influences']} weights a vertex), {made['shape_keys']} shape keys, {made['landmarks']} "
            f"landmarks{took}")


class AUTOBONES_OT_rig(bpy.types.Operator):
    """Rig the active mesh with autobones (place or transfer, as set in the panel)"""

    bl_idname = "autobones.rig"
    bl_label = "Rig with autobones"
    bl_options = {"REGISTER", "UNDO"}

    _job = _timer = _run = None

    def execute(self, context):
        try:
            obj, cmd, out, folder, temporary = prepare(context)
            try:
                runner.run(cmd)
                made = result.import_result(context, obj, out)
            finally:
                if temporary:
                    shutil.rmtree(folder, ignore_errors=True)
        except AddonError as exc:
            self.report({"ERROR"}, runner.one_line(exc))
            return {"CANCELLED"}
        self.report({"INFO"}, _summary(obj, made))
        return {"FINISHED"}

    def invoke(self, context, event):
        if bpy.app.background or context.window is None:
            return self.execute(context)
        try:
            self._run = prepare(context)
            self._job = runner.Job(self._run[1])
        except AddonError as exc:
            self._cleanup(context)
            self.report({"ERROR"}, runner.one_line(exc))
            return {"CANCELLED"}
        self._started = time.monotonic()
        self._timer = context.window_manager.event_timer_add(0.2, window=context.window)
        context.window_manager.modal_handler_add(self)
        context.workspace.status_text_set("autobones: starting (Esc stops)")
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        if event.type == "ESC":
            self._job.cancel()
            self._cleanup(context)
            self.report({"WARNING"}, "autobones: stopped")
            return {"CANCELLED"}
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        if self._job.poll() is None:
            context.workspace.status_text_set(f"autobones: {self._job.status()} (Esc stops)")
            return {"RUNNING_MODAL"}
        try:
            self._job.result()
            obj, out = self._run[0], self._run[2]
            if obj.name not in context.scene.objects:  # deleted (ReferenceError) or moved away meanwhile
                raise AddonError("autobones: the mesh left the scene while autobones ran; nothing imported")
            made = result.import_result(context, obj, out)
        except ReferenceError:
            self._cleanup(context)
            self.report({"ERROR"}, "autobones: the mesh was deleted while autobones ran; nothing imported")
            return {"CANCELLED"}
        except AddonError as exc:
            self._cleanup(context)
            self.report({"ERROR"}, runner.one_line(exc))
            return {"CANCELLED"}
        self._cleanup(context)
        self.report({"INFO"}, _summary(obj, made, time.monotonic() - self._started))
        return {"FINISHED"}

    def _cleanup(self, context):
        if self._timer is not None:
            context.window_manager.event_timer_remove(self._timer)
            self._timer = None
        if context.workspace is not None:
            context.workspace.status_text_set(None)
        if self._run is not None and self._run[4]:
            shutil.rmtree(self._run[3], ignore_errors=True)
        self._run = None


class AUTOBONES_OT_add_landmark(bpy.types.Operator):
    """Put a landmark empty on the active mesh's surface at the 3D cursor (Shift+right-click on the skin
    places the cursor), named from the contract"""

    bl_idname = "autobones.add_landmark"
    bl_label = "Add landmark at cursor"
    bl_options = {"REGISTER", "UNDO"}

    name: bpy.props.StringProperty(name="Name", default="", description="contract name; empty: the panel's choice")
    location: bpy.props.FloatVectorProperty(name="Location", size=3, subtype="XYZ",
                                            description="world position; unset: the 3D cursor")

    def execute(self, context):
        try:
            obj = _mesh(context)
        except AddonError as exc:
            self.report({"ERROR"}, runner.one_line(exc))
            return {"CANCELLED"}
        settings = context.scene.autobones
        name = self.name or settings.landmark_name
        if name not in landmark_names():
            self.report({"ERROR"}, f"autobones: {name!r} is not a landmark name of the contract")
            return {"CANCELLED"}
        world = self.location if self.properties.is_property_set("location") else context.scene.cursor.location
        empty = landmark_empties.put_landmark(obj, name, obj.matrix_world.inverted() @ world.copy(), snap=True)
        nxt = landmark_empties.next_unplaced(obj)
        if nxt is not None:
            settings.landmark_name = nxt
        self.report({"INFO"}, f"autobones: {empty.name} on {obj.name}; next: {nxt or 'all placed'}")
        return {"FINISHED"}


class AUTOBONES_OT_snap_landmarks(bpy.types.Operator):
    """Move every landmark empty of the active mesh onto its surface (the closest point)"""

    bl_idname = "autobones.snap_landmarks"
    bl_label = "Snap landmarks to surface"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        try:
            obj = _mesh(context)
        except AddonError as exc:
            self.report({"ERROR"}, runner.one_line(exc))
            return {"CANCELLED"}
        landmarks = landmark_empties.collect(obj)
        landmark_empties.put_landmarks(obj, landmarks, snap=True)
        self.report({"INFO"}, f"autobones: {len(landmarks)} landmarks snapped to {obj.name}")
        return {"FINISHED"}


class AUTOBONES_OT_write_landmarks(bpy.types.Operator, ExportHelper):
    """Write the active mesh's landmark empties as a landmark file autobones reads (the mesh's own frame)"""

    bl_idname = "autobones.write_landmarks"
    bl_label = "Write landmarks"
    filename_ext = ".json"
    filter_glob: bpy.props.StringProperty(default="*.json", options={"HIDDEN"})

    def execute(self, context):
        try:
            obj = _mesh(context)
            landmarks = landmark_empties.collect(obj)
            if not landmarks:
                raise AddonError(f"autobones: {obj.name} has no landmark empties to write")
            folder = os.path.dirname(os.path.abspath(self.filepath))
            if not os.path.isdir(folder):
                raise AddonError(f"autobones: the folder {folder} does not exist")
            runner.write_landmarks(self.filepath, landmarks, obj.name)
        except (AddonError, OSError) as exc:
            self.report({"ERROR"}, runner.one_line(exc))
            return {"CANCELLED"}
        self.report({"INFO"}, f"autobones: {len(landmarks)} landmarks written to {self.filepath}")
        return {"FINISHED"}


class AUTOBONES_OT_reset_pose(bpy.types.Operator):
    """Put the active mesh's rig back at rest: every bone unturned, every shape key at 0"""

    bl_idname = "autobones.reset_pose"
    bl_label = "Reset pose"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        mesh = result.rig_mesh(context.active_object)
        arm = result.rig_armature(mesh) if mesh is not None else None
        if arm is None:
            self.report({"ERROR"}, "autobones: the active object has no autobones rig")
            return {"CANCELLED"}
        for pb in arm.pose.bones:
            pb.location, pb.rotation_euler, pb.scale = (0, 0, 0), (0, 0, 0), (1, 1, 1)
            pb.rotation_quaternion = (1, 0, 0, 0)
        for kb in result.rig_shape_keys(mesh):
            kb.value = 0.0
        return {"FINISHED"}


CLASSES = (AUTOBONES_OT_rig, AUTOBONES_OT_add_landmark, AUTOBONES_OT_snap_landmarks, AUTOBONES_OT_write_landmarks,
           AUTOBONES_OT_reset_pose)


# Blender's own helper: registers CLASSES in order, unregisters them in reverse
register, unregister = bpy.utils.register_classes_factory(CLASSES)
