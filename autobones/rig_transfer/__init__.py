"""``autobones transfer``: a labelled generic rig carried onto a landmarked head.

After Orvalho, Zacur & Susin 2008 ("Transferring the Rig and Animations from a Character to
Different Face Models"), one module a stage:

- ``correspondence``: thin-plate-spline warp from the landmarks, then a staged least-squares fit
  of the generic surface to the head (after Bibliowicz 2005, ch. 5), giving a dense correspondence;
- ``stick``: closest-point projection of the fitted surface onto the head, with fold detection;
- ``fields``: per-vertex attributes copied through the correspondence, inpainted where it is unreliable;
- ``labelled_rig`` and ``build``: the generic rig's type, and building one from a base head;
- ``pipeline``: :func:`transfer`, which runs them and returns a :class:`autobones.rig.Rig`.
"""
from .pipeline import transfer

__all__ = ["transfer"]
