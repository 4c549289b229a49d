"""Expressions: a muscle-driven skin model posed by FACS action units, emotions and direct controls.

The skin/muscle model of Bibliowicz 2005 (wire deformers pulled by muscle joints, point
constraints), on the muscles of Lee, Terzopoulos & Waters 1995 and the sphincters of Waters 1987,
driven by the FACS action units and emotion prototypes of Erdoğdu 2010; :class:`ExpressionModel` is fitted once to a transferred
rig, then poses it; ``morph_targets`` bakes one glTF morph target per action unit.
"""
from .model import ExpressionModel

__all__ = ["ExpressionModel"]
