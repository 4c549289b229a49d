"""``autobones build-rig``: a labelled generic rig from a base head and its landmarks.

Builds the layers of Orvalho, Zacur & Susin 2008 (§2) on any base head: skeleton (neck, head, jaw,
eyes), skin weights, the jaw field, region labels, depth groups (as ``place`` segments a head), and
the muscles of Lee, Terzopoulos & Waters 1995 with their influence fields. The result is a
:class:`autobones.labelled_rig.LabelledRig` that ``transfer`` carries onto other heads.
"""
from .build import build_rig

__all__ = ["build_rig"]
