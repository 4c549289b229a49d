"""The add-on's panel in the 3D view's sidebar (N), tab "autobones": Rig, Landmarks, Pose.

Beyond the papers (issue #37): the three jobs a technical artist does with a head in Blender, in
the order they do them. Pose shows the rig's jaw, head, neck and eye bones as rotation fields
(X nods: each bone's X axis runs across the head) and its shape keys (ARKit's 52, the AUs) as sliders.
"""
import bpy

from . import landmark_empties, result
from .result import POSE_BONES
from .settings import landmark_names


class _Sidebar:
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "autobones"


class AUTOBONES_PT_rig(_Sidebar, bpy.types.Panel):
    """Rig the active mesh."""

    bl_label = "autobones"

    def draw(self, context):
        s, layout = context.scene.autobones, self.layout
        obj = context.active_object
        layout.label(text=f"Mesh: {obj.name}" if obj is not None and obj.type == "MESH" else "Select a mesh",
                     icon="MESH_DATA")
        layout.prop(s, "method", expand=True)
        if s.method == "PLACE":
            _labelled(layout, "Density", s, "density")
        _labelled(layout, "Landmarks", s, "landmarks")
        if s.landmarks == "FILE":
            layout.prop(s, "landmarks_file", text="")
        elif s.landmarks == "EMPTIES" and obj is not None and obj.type == "MESH":
            layout.label(text=f"{len(landmark_empties.landmark_empties(obj))} landmark empties")
        if s.method == "TRANSFER":
            row = layout.row()
            row.prop(s, "arkit", text="ARKit")
            row.prop(s, "expressions", text="AUs")
        _labelled(layout, "Keep files", s, "output_dir")
        layout.operator("autobones.rig", icon="ARMATURE_DATA")


def _labelled(layout, label, data, prop):
    """A label and a field on one row, the label given room (the sidebar is narrow)."""
    split = layout.split(factor=0.38)
    split.label(text=label)
    split.prop(data, prop, text="")


class AUTOBONES_PT_landmarks(_Sidebar, bpy.types.Panel):
    """Place the contract's landmarks on the active mesh and write them out."""

    bl_label = "Landmarks"
    bl_parent_id = "AUTOBONES_PT_rig"

    def draw(self, context):
        s, layout = context.scene.autobones, self.layout
        obj = context.active_object
        if not landmark_names():
            layout.label(text="Reinstall the zip from autobones blender-addon", icon="ERROR")
            return
        _labelled(layout, "Name", s, "landmark_name")
        layout.operator("autobones.add_landmark", icon="EMPTY_SINGLE_ARROW")
        layout.label(text="Shift+right-click: cursor on skin")
        layout.operator("autobones.snap_landmarks", text="Snap to surface", icon="SNAP_FACE")
        layout.operator("autobones.write_landmarks", text="Write landmark file", icon="EXPORT")
        if obj is not None and obj.type == "MESH":
            placed = len(landmark_empties.landmark_empties(obj))
            layout.label(text=f"{placed} of {len(landmark_names())} placed (10+)")


class AUTOBONES_PT_pose(_Sidebar, bpy.types.Panel):
    """Pose the rig: bones and shape keys."""

    bl_label = "Pose"
    bl_parent_id = "AUTOBONES_PT_rig"

    @classmethod
    def poll(cls, context):
        return result.rig_mesh(context.active_object) is not None

    def draw(self, context):
        s, layout = context.scene.autobones, self.layout
        mesh = result.rig_mesh(context.active_object)
        arm = result.rig_armature(mesh)
        col = layout.column(align=True)
        col.label(text="Bones (X nods), degrees")
        for name in POSE_BONES:
            pb = arm.pose.bones.get(name)
            if pb is not None:
                split = col.split(factor=0.2, align=True)
                split.label(text=name)
                split.row(align=True).prop(pb, "rotation_euler", text="")
        keys = result.rig_shape_keys(mesh)
        if keys:
            layout.prop(s, "shape_key_filter", icon="VIEWZOOM")
            col = layout.column(align=True)
            for kb in keys:
                if s.shape_key_filter.lower() in kb.name.lower():
                    col.prop(kb, "value", text=kb.name, slider=True)
        layout.operator("autobones.reset_pose", icon="LOOP_BACK")


CLASSES = (AUTOBONES_PT_rig, AUTOBONES_PT_landmarks, AUTOBONES_PT_pose)


# Blender's own helper: registers CLASSES in order, unregisters them in reverse
register, unregister = bpy.utils.register_classes_factory(CLASSES)
