"""The built-in default head, the generic rig built on it, and its data files."""
import os

HERE = os.path.dirname(os.path.abspath(__file__))


def default_head_path():
    """Path of the committed default head mesh (metres, +Y up, +Z front)."""
    return os.path.join(HERE, "default_head.obj")


def default_rig_path():
    """Folder of the built-in labelled generic rig (rig.json, mesh.obj, fields.npz)."""
    return os.path.join(HERE, "default")


def muscles_path():
    """The muscle definitions (generic_rig/muscles.json) that build_rig reads by default."""
    return os.path.join(HERE, "muscles.json")


def expressions_path():
    """Action units, emotion prototypes and skin/muscle model parameters (generic_rig/expressions.json)."""
    return os.path.join(HERE, "expressions.json")
