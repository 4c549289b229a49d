"""Landmarks as empties on a mesh: placed on its surface, named from the contract, read back, written out.

Beyond the papers: Orvalho, Zacur & Susin (2008, §3) have the artist position the face model's
landmarks by hand; in Blender that is an empty per landmark, snapped to the skin. The empties are
children of the mesh object and carry their contract name in a custom property (Blender renames a
second ``pronasale`` to ``pronasale.001``), so one scene can hold several landmarked heads. Their
positions are read in the mesh's own frame and units, the frame autobones gets the mesh in.
"""
import bpy
from mathutils import Vector

from .settings import landmark_names

PROP = "autobones_landmark"  # custom property: the empty's contract name


def _contract_name(empty, names):
    """The contract name an empty stands for, or None."""
    name = empty.get(PROP)
    if isinstance(name, str) and name in names:
        return name
    base = empty.name.rsplit(".", 1)[0] if "." in empty.name else empty.name
    return base if base in names else None


def landmark_empties(obj):
    """{contract name: empty} of the mesh ``obj``: its child empties named from the contract, or, when it
    has none, the scene's empties whose name is exactly a contract name (made by hand)."""
    names = set(landmark_names())
    found = {}
    for child in obj.children:
        name = _contract_name(child, names) if child.type == "EMPTY" else None
        if name is not None and name not in found:
            found[name] = child
    if not found:
        found = {o.name: o for o in bpy.data.objects if o.type == "EMPTY" and o.name in names and o.parent is None}
    return found


def collect(obj):
    """{contract name: (x, y, z)} of ``obj``'s landmark empties, in the mesh's own frame and units,
    contract order."""
    found = landmark_empties(obj)
    to_local = obj.matrix_world.inverted()

    def local(empty):  # a child's own matrix needs no round trip through the world (float32) frame
        return empty.matrix_local.translation if empty.parent == obj else to_local @ empty.matrix_world.translation

    return {n: tuple(local(found[n])) for n in landmark_names() if n in found}


def head_size(obj):
    """Diagonal of the mesh's bounding box, in its own units."""
    corners = [Vector(c) for c in obj.bound_box]
    return max((a - b).length for a in corners for b in corners) or 1.0


def snapped(obj, local):
    """The point of ``obj``'s surface closest to ``local`` (mesh frame); ``local`` when there is none."""
    hit, point, _, _ = obj.closest_point_on_mesh(Vector(local))
    return point if hit else Vector(local)


def put_landmark(obj, name, local, snap=True):
    """Make or move ``obj``'s landmark empty ``name`` to ``local`` (mesh frame, snapped to the surface
    when ``snap``); returns the empty."""
    names = set(landmark_names())
    empty = next((c for c in obj.children if c.type == "EMPTY" and _contract_name(c, names) == name), None)
    if empty is None:
        empty = bpy.data.objects.new(name, None)
        for collection in obj.users_collection:
            collection.objects.link(empty)
        empty.parent = obj
        empty[PROP] = name
    empty.empty_display_type = "SPHERE"
    empty.empty_display_size = 0.006 * head_size(obj)
    empty.matrix_parent_inverse.identity()  # its location is then the point in the mesh's own frame
    empty.location = snapped(obj, local) if snap else Vector(local)
    empty.show_name = True
    return empty


def put_landmarks(obj, landmarks, snap=False):
    """:func:`put_landmark` for every ``{name: (x, y, z)}`` (mesh frame); returns the empties."""
    names = set(landmark_names())
    return [put_landmark(obj, n, p, snap) for n, p in landmarks.items() if n in names]


def next_unplaced(obj):
    """The first contract name ``obj`` has no landmark empty for, or None."""
    have = landmark_empties(obj)
    return next((n for n in landmark_names() if n not in have), None)
