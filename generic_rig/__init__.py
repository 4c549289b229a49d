"""The built-in default head (and, later, the generic rig built on it)."""
import os

HERE = os.path.dirname(os.path.abspath(__file__))


def default_head_path():
    """Path of the committed default head mesh (metres, +Y up, +Z front)."""
    return os.path.join(HERE, "default_head.obj")
