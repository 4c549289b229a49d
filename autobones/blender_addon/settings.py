"""The add-on's preferences (which autobones to run) and the panel's options (a scene property).

Beyond the papers: the add-on runs autobones in a subprocess of a Python the user names, so
Blender's own Python needs nothing installed; the options mirror ``autobones place`` and
``autobones transfer`` (``--density``, ``--landmarks``, ``--arkit``, ``--expressions``).
"""
import json
import os

import bpy

NAMES_FILE = "landmark_names.json"  # written into the zip by autobones.blender_zip from the contract


def landmark_names():
    """The landmark contract's 44 names in their fixed order (empty when the zip lacks the table)."""
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), NAMES_FILE)
    try:
        with open(path, encoding="utf-8") as fh:
            return [str(n) for n in json.load(fh)["names"]]
    except (OSError, ValueError, KeyError):
        return []


_NAMES = landmark_names()


def _name_items(self, context):
    # Blender keeps enum items alive only while referenced: a module-level list
    return _NAME_ITEMS


_NAME_ITEMS = [(n, n, f"the contract's landmark {n}") for n in _NAMES]


class AutobonesPreferences(bpy.types.AddonPreferences):
    """Where autobones is: a Python with autobones installed, or the ``autobones`` executable."""

    bl_idname = __package__

    autobones_path: bpy.props.StringProperty(
        name="autobones", subtype="FILE_PATH", default="",
        description="A Python interpreter with autobones installed (run as python -m autobones) or the "
                    "autobones executable; empty: autobones found on PATH")

    def draw(self, context):
        self.layout.prop(self, "autobones_path", text="Python or autobones")
        self.layout.label(text="Empty: the autobones command on PATH. Blender's own Python needs nothing installed.")


class AutobonesSettings(bpy.types.PropertyGroup):
    """The panel's options, kept per scene."""

    method: bpy.props.EnumProperty(
        name="Method", default="PLACE",
        items=[("PLACE", "Place", "autobones place: bones from the mesh's shape, no landmarks needed"),
               ("TRANSFER", "Transfer", "autobones transfer: the labelled generic rig carried by landmarks "
                                        "(jaw, eyes, muscles; ARKit shapes and expressions)")])
    density: bpy.props.EnumProperty(
        name="Density", default="medium", description="place's facial bones",
        items=[("sparse", "Sparse (8)", "8 facial bones"), ("medium", "Medium (16)", "16 facial bones"),
               ("dense", "Dense (32)", "32 facial bones")])
    landmarks: bpy.props.EnumProperty(
        name="Landmarks", default="AUTO",
        items=[("AUTO", "Automatic", "transfer: found on a human face (autobones[landmarks]); place: none"),
               ("FILE", "File", "a landmark file in the mesh's own frame (contract .json, MeshLab .pp, iBUG-68)"),
               ("EMPTIES", "Empties", "empties parented to the mesh, named after the contract's landmarks")])
    landmarks_file: bpy.props.StringProperty(name="Landmark file", subtype="FILE_PATH", default="")
    arkit: bpy.props.BoolProperty(name="ARKit shapes", default=False,
                                  description="transfer --arkit: ARKit's 52 blendshapes as shape keys")
    expressions: bpy.props.BoolProperty(name="Expressions", default=False,
                                        description="transfer --expressions: one shape key per FACS action unit")
    output_dir: bpy.props.StringProperty(
        name="Keep files in", subtype="DIR_PATH", default="",
        description="folder that keeps the rig's glb and sidecars; empty: a temporary folder, removed after import")
    landmark_name: bpy.props.EnumProperty(name="Landmark", items=_name_items,
                                          description="the contract name of the next landmark to place")
    shape_key_filter: bpy.props.StringProperty(name="Filter", default="",
                                               description="show only shape keys whose name contains this")


CLASSES = (AutobonesPreferences, AutobonesSettings)


def preferences(context):
    """This add-on's preferences object."""
    return context.preferences.addons[__package__].preferences


def register():
    """Register the preferences and the per-scene settings (``scene.autobones``)."""
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Scene.autobones = bpy.props.PointerProperty(type=AutobonesSettings)


def unregister():
    """Undo :func:`register`."""
    del bpy.types.Scene.autobones
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
