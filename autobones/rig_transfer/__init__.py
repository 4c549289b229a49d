"""``autobones transfer``: a labelled generic rig carried onto a landmarked head.

After Orvalho, Zacur & Susin 2008 ("Transferring the Rig and Animations from a Character to
Different Face Models"), one module a stage:

- ``correspondence``: thin-plate-spline warp from the landmarks, then a staged least-squares fit
  of the generic surface to the head (after Bibliowicz 2005, ch. 5), giving a dense correspondence;
- ``stick``: closest-point projection of the fitted surface onto the head, with fold detection;
- ``under_skin``: a second TPS on a spread subsample of the correspondence carries the skeleton and
  the muscle origins; muscle insertions ride the correspondence;
- ``fields``: per-vertex attributes copied through the correspondence, inpainted where it is unreliable;
- ``eyes``: modelled eyeballs bound rigidly to the eye bones, the eye bones centred in them;
- ``mouth_parts``: the mouth's separate parts (teeth, a mouth bag) on the jaw or the skull, teeth whole;
- ``pipeline``: :func:`transfer`, which runs them and returns a :class:`autobones.rig.Rig`.

The generic rig's type is :class:`autobones.labelled_rig.LabelledRig`; :mod:`autobones.rig_building`
builds one from a base head.
"""
from .pipeline import transfer

__all__ = ["transfer"]
