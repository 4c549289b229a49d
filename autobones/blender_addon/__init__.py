"""autobones inside Blender: an add-on that rigs the active head mesh where technical artists work.

Beyond the papers (issue #37): the people who rig heads live in Blender, and the tools they pay for
(Faceit, Auto-Rig Pro) are add-ons that rig the selected mesh in place. This package is that add-on's
source; ``autobones blender-addon -o autobones_blender.zip`` (:mod:`autobones.blender_zip`) packs it,
with the landmark contract's names, into a zip that Blender 3.4+ installs through Preferences ->
Add-ons -> Install. Blender imports it as ``autobones_blender``.

The add-on never imports autobones: it exports the active mesh (its own frame and units, vertex order
kept), runs ``autobones place`` or ``transfer`` in a subprocess of the Python (or ``autobones``
executable) the preferences name, and imports the result onto the same object: an armature parented
to it, one vertex group per bone with every weight of the rig's ``.weights.npz``, a shape key per
morph target, the landmarks as named empties and the sidecar as a text block.

Modules: :mod:`.settings` (preferences and the panel's options), :mod:`.runner` (mesh and landmark
files, the subprocess), :mod:`.glb` (the result's joints and morph targets), :mod:`.vertex_groups`
(full weights, shared with :mod:`autobones.export.blender_fbx`), :mod:`.result` (the result in the
scene), :mod:`.landmark_empties` (placing and writing landmarks), :mod:`.operators`, :mod:`.panel`.

Importing this package needs no Blender (``bl_info`` only); :func:`register` imports the modules that
use ``bpy``.
"""

bl_info = {
    "name": "autobones",
    "author": "autobones",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Sidebar > autobones",
    "description": "Rig the active head mesh with autobones: armature, full skin weights, shape keys, landmarks",
    "category": "Rigging",
}


def _modules():
    from . import operators, panel, settings

    return settings, operators, panel


def register():
    """Register the preferences, the scene settings, the operators and the panels (Blender calls this)."""
    for module in _modules():
        module.register()


def unregister():
    """Undo :func:`register`, in reverse order."""
    for module in reversed(_modules()):
        module.unregister()
