"""Where the head turns and where the neck starts: the occiput-C1 pivot and the neck's base, landmark-free.

The bone-setting method ``place`` follows (Orvalho-style: a head bone through the upper part of the
middle depth group, a neck bone below it) puts the head joint wherever the mesh's proportions put
that group's mean: the brow of a long-necked bust, the jaw of a short one. A rigger expects the head
to turn about the top of the spine. Chancey, Ottaviano, Myers & Nightingale (2007, J. Biomech. 40)
measured, relative to the ear canal, the occiput-C1 centre of rotation 22.5 mm posterior and 22.6 mm
inferior (adults, ex-ex about 90 mm, vertex-menton about 230 mm); in head proportions the pivot sits
at the level of the nose base / upper lip, a third of the head's depth in front of the back of the
head, above the neck's narrowest section and behind the jaw's angle. On an animal the same place is
the base of the skull between the ears, behind the jaw's hinge, where the neck enters the head.

Everything here is in the canonical frame (+Y up, +Z front, +X left, head sizes) and uses cues that
need no landmarks, each recorded in :attr:`Joints.cues` (the sidecar's ``joints``) when it was used.
The head joint (``head`` cues):

- ``midline_top``: the vertex is the highest point of the midline strip (horns, ears and a crest
  beside it rise higher);
- ``head_length``: the pivot lies ``PIVOT_DOWN`` of the head's length (the largest front-to-back
  extent of its upper part; about vertex-menton on a human) below the vertex; or ``chin``: of the
  height down to the chin step of the midline profile, when the mesh ends there and that is larger
  (a tall cartoon head; above a neck a chin step may be a beard's or a throat fold's);
- ``above_neck_base``: a long snout makes a head long, not tall, and would put the pivot in the
  neck: it is kept ``PIVOT_FLOOR`` of the height above the bottom and ``BASE_CLEARANCE`` above the
  neck base;
- ``back_of_skull``: its depth is ``PIVOT_BACK`` of the section at its height from the back of the
  head, and at most ``PIVOT_BACK_WIDTH`` of the section's width (a snout or a jaw far in front of
  the neck lengthens the section, not the skull's base);
- ``face_only``: an open shell facing forward (a face mask, orient's face-only capture) has no back
  and no neck to measure: on a human face the pivot is where human faces put it, placed by the face's
  automatic landmarks (``face_landmarks``, :mod:`autobones.rig_transfer.face_joints`: 0.04-0.25 ex-ex
  from Chancey's centre on the shared heads cut into masks where a face is found, 0.10 mean, with the
  head's family held out of the calibration); else far behind
  it, from the nose (``nose``: the midline profile's most anterior point, and the mask's width there
  as the scale, ``nose_width``: on James and the menpo template 0.191 / 0.173 ex-ex from Chancey's
  centre, most of it the mask's pitch in its frame times the 1.5 ex-ex lever; the mask's proportions
  put them 0.389 / 0.297 off), or by its proportions without a midline profile (``proportions``).

The neck joint (``neck`` cues): ``neck_section``, the neck's narrowest horizontal section under the
pivot (bounding width of an area-uniform sample, slab by slab), then ``shoulders``, where the
sections below it widen ``SHOULDERS`` times (a bust's chest: the neck starts there, at C7), or
``bottom_cut``, the mesh's cut when the neck is cut off; ``no_neck`` (added by ``place``,
:func:`autobones.placement.pipeline._no_neck`), a closed head whose chin is its lowest point, or a
head (a face mask) with nothing cut below its chin: nothing below the face is held still. The menton
(``menton_source``: ``chin`` from the profile, else ``proportions``, vertex-menton about 1.2 head
lengths, Farkas 1994) is where the weights' head/neck boundary passes under the chin (:mod:`.locality`).

The proportions were first measured on the SMPL man and woman heads of the zoo (hand-placed tragions,
Chancey's offsets scaled by their ex-ex / 90 mm): the pivot 0.68-0.70 of the head's length below the
vertex, 0.32-0.35 of the section's depth (0.39-0.44 of its width) in front of the back of the head.
``benchmarks/joints.py`` then measured six human heads of three families in the landmarks' frame
(the default head, the SMPL man and woman, ICT identities 000-002 with the tragions of
``tests/landmarks``): Chancey's centre lies 0.695-0.788 of the head's length below the vertex (ICT's
taller crania 0.78-0.79) and 0.26-0.31 of the section's depth from its back; with 0.69 / 0.34 ICT's
pivots sat 0.21-0.23 ex-ex off (0.20-0.22 too high); 0.73 / 0.30 put all six within 0.016-0.128
ex-ex in the frames of the time. Once the frame was a function of the shape alone (ICT's heads
0.4-0.7 deg from their landmarks' frame, 6 deg before), the same six measured 0.71-0.82 of the
length down (ICT 0.80-0.82) and 0.26-0.35 back; 0.77 / 0.30 put the five heads that are not face
masks within 0.087-0.133 ex-ex (benchmarks/README.md, joints.py): one head length's proportion
cannot fit every cranium closer; the ears would.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..geometry.head_share import NECK_BASE

PIVOT_DOWN = 0.77        # of the head's length below the vertex (Chancey's centre on six human heads, shape-only frames: 0.71-0.82)
PIVOT_FLOOR = 0.3        # of the mesh's height: the pivot stays at least this far above its bottom
PIVOT_BACK = 0.30        # of the section's depth at the pivot, from its back (0.26-0.31 on the same heads)
PIVOT_BACK_WIDTH = 0.4   # of the section's width: at most this far in front of its back (0.39-0.44)
PIVOT_DOWN_MASK = 0.71   # a face mask: of its height below its top (vertex-menton: 0.70-0.72)
PIVOT_BEHIND_MASK = 0.58  # a face mask: of its height behind its front (0.55-0.58)
MASK_CHIN = 0.7          # a face mask's chin step lies at least this share of its height below its top
MASK_BEHIND_NOSE = 1.52  # ex-ex: Chancey's centre behind the pronasale (1.35-1.61 on seven human heads)
MASK_BELOW_NOSE = 0.30   # ex-ex: and below it (0.25-0.42)
MASK_WIDTH = 2.0         # ex-ex: a head's width at the nose tip's height (1.66-2.13; James' and the template's masks 1.99 / 2.01)
CHIN_CUT = 0.1          # of the height: a chin this close to the bottom is where the mesh ends
MENTON_DEPTHS = 1.2    # vertex-menton in head depths, when no chin step is found (Farkas 1994)
SLAB = 0.02            # head sizes: height of a profile slab
MIDLINE = 0.06         # head sizes: half-width of the strip the midline profile is taken from
UNDER_CHIN = 0.06      # head sizes: the neck's sections start this far below the pivot
SHOULDERS = 1.5        # a section this many times the narrowest neck's width is the shoulders
BASE_CLEARANCE = 0.15  # of the height: the pivot stays this far above the neck base


@dataclass
class Joints:
    """Canonical ``head`` (occiput-C1 pivot) and ``neck`` (neck base) joints and the cues that placed them.

    Attributes
    ----------
    head, neck : (3,) float
        Canonical joint positions, on the midline (x = 0).
    menton : float
        The menton's height used (found or expected).
    chin_front : float
        Depth of the front of the section at the menton's height (the chin's front).
    menton_source : str
        ``"chin"`` (the profile's step) or ``"proportions"``.
    neck_section : float or None
        Height of the neck's narrowest section, None when the mesh has no neck below the chin.
    cues : dict
        ``{"head": [...], "neck": [...]}``: the names of the cues used (module docstring).
    """

    head: np.ndarray
    neck: np.ndarray
    menton: float
    chin_front: float = 0.0
    menton_source: str = "proportions"
    neck_section: float | None = None
    cues: dict = field(default_factory=dict)

    def to_dict(self):
        """The sidecar's ``joints`` entry (JSON values)."""
        return {"head": {"cues": list(self.cues.get("head", []))},
                "neck": {"cues": list(self.cues.get("neck", []))},
                "menton_height": float(self.menton), "menton_source": self.menton_source,
                "neck_section_height": None if self.neck_section is None else float(self.neck_section)}


def height_profile(S, bottom, top, slab=SLAB, midline=MIDLINE):
    """Slab-by-slab extents of a canonical surface sample ``S`` (k, 3) between ``bottom`` and ``top``.

    Returns a dict of (b,) arrays: ``y`` (slab centres), ``xmin``, ``xmax``, ``zmin``, ``zmax`` (all
    points) and ``mzmin``, ``mzmax`` (the midline strip |x| < ``midline``); NaN where a slab is empty.
    """
    edges = np.arange(bottom, top + slab, slab)
    nb = max(len(edges) - 1, 1)
    k = np.clip(((S[:, 1] - bottom) / slab).astype(np.int64), 0, nb - 1)
    out = {"y": bottom + slab * (np.arange(nb) + 0.5)}
    mid = np.abs(S[:, 0]) < midline
    for name, col, sel in (("x", 0, None), ("z", 2, None), ("mz", 2, mid)):
        lo, hi = np.full(nb, np.inf), np.full(nb, -np.inf)
        kk, v = (k, S[:, col]) if sel is None else (k[sel], S[sel, col])
        np.minimum.at(lo, kk, v)
        np.maximum.at(hi, kk, v)
        empty = ~np.isfinite(lo)
        lo[empty] = hi[empty] = np.nan
        out[name + "min"], out[name + "max"] = lo, hi
    return out


def find_joints(S, bottom, top, chin=None, face_mask=False, base=None, pivot=None):
    """The head pivot and the neck base of a head from its surface sample (module docstring).

    Parameters
    ----------
    S : (k, 3) float
        Area-uniform canonical surface sample (a few thousand points or more).
    bottom, top : float
        The mesh's lowest and highest heights (used vertices).
    chin : float or None
        The menton's height from the midline profile, None when no chin step was found.
    face_mask : bool
        The mesh is a face-only capture (:func:`autobones.geometry.head_share.face_only`).
    base : float, optional
        The neck base's top (:func:`autobones.geometry.head_share.neck_base_height`); default ``NECK_BASE`` of the height.
    pivot : (float, float), optional
        A face mask's pivot (height, depth) from its landmarks (:mod:`autobones.rig_transfer.face_joints`),
        taken instead of the nose rule.

    Returns
    -------
    Joints
    """
    prof = height_profile(S, bottom, top)
    head_cues, neck_cues = [], []
    height = top - bottom
    # the vertex is the skull's top on the midline: horns and ears rise beside it
    strip = S[np.abs(S[:, 0]) < MIDLINE, 1]
    if len(strip) and strip.max() < top - SLAB:
        top = float(strip.max())
        head_cues.append("midline_top")
    length = head_length(prof, top)
    if face_mask:
        y_head, z_head, mask_cues = (*pivot, ["face_landmarks"]) if pivot is not None else \
            _mask_pivot(prof, top, bottom, chin)
        head_cues += ["face_only"] + mask_cues
    else:
        # the head's height scale is its length, front to back, or the length its height down to
        # the chin implies (vertex-menton is MENTON_DEPTHS head lengths) when the mesh ends there and
        # that is larger (a tall cartoon head); a chin step found above a neck may be a beard's or a
        # throat fold's, and is not trusted to scale the head. (Vertex-menton taken as one length
        # put the SMPL woman's pivot 0.25 ex-ex low once her chin step was found at her menton.)
        scale = length
        head_cues.append("head_length")
        if chin is not None and chin - bottom < CHIN_CUT * height and top - chin > MENTON_DEPTHS * length:
            scale = (top - float(chin)) / MENTON_DEPTHS
            head_cues.append("chin")
        y_head = top - PIVOT_DOWN * scale
        base = bottom + NECK_BASE * height if base is None else float(base)
        floor = max(bottom + PIVOT_FLOOR * height, base + BASE_CLEARANCE * height)
        if y_head < floor:
            # a long snout makes the head long, not tall: the pivot stays above the neck's base
            y_head = floor
            head_cues.append("above_neck_base")
        z_head = _section_depth(prof, y_head)
        head_cues.append("back_of_skull")
    menton = float(chin) if chin is not None else max(top - MENTON_DEPTHS * length, bottom)
    neck = None if face_mask else _neck(prof, y_head, bottom)
    if neck is not None:
        y_neck, z_neck = neck["base"], neck["base_z"]
        neck_cues += ["neck_section", neck["base_cue"]]
    else:
        y_neck, z_neck = bottom, z_head
        neck_cues += ["face_only"] if face_mask else ["bottom_cut"]
    return Joints(head=np.array([0.0, y_head, z_head]), neck=np.array([0.0, y_neck, z_neck]), menton=menton,
                  chin_front=_front(prof, menton), menton_source="proportions" if chin is None else "chin",
                  neck_section=None if neck is None else neck["height"],
                  cues={"head": head_cues, "neck": neck_cues})


def _mask_pivot(prof, top, bottom, chin):
    """(height, depth, cues) of a face mask's pivot, far behind the mask (module docstring).

    From the nose (``nose``): the most anterior point of the midline profile, with the mask's width
    there as the scale (``nose_width``): Chancey's centre lies ``MASK_BEHIND_NOSE`` ex-ex behind the
    pronasale and ``MASK_BELOW_NOSE`` below it, and a head is ``MASK_WIDTH`` ex-ex wide at the nose.
    A mask cut in front of the ears is narrower, and its pivot comes out nearer the face (ICT's
    identities cut 0.5 ex-ex in front of the tragions: 0.38-0.39 ex-ex off), still nearer Chancey's
    centre than the mask's height puts it (0.60-1.37: a mask's height is wherever it was cut, a neck
    included). Without a midline profile, by its height (``proportions``): vertex-menton from the chin
    step when one is found far enough down (``chin``)."""
    mz = prof["mzmax"]
    if np.isfinite(mz).any():
        k = int(np.nanargmax(mz))
        y_nose, z_nose = float(prof["y"][k]), float(mz[k])
        width = _at(prof, "xmax", y_nose) - _at(prof, "xmin", y_nose)
        if np.isfinite(width) and width > 0:
            exex = width / MASK_WIDTH
            return y_nose - MASK_BELOW_NOSE * exex, z_nose - MASK_BEHIND_NOSE * exex, ["nose", "nose_width"]
    height = top - bottom
    by_chin = chin is not None and top - float(chin) >= MASK_CHIN * height
    scale = top - float(chin) if by_chin else height
    y_head = top - PIVOT_DOWN_MASK * scale
    return y_head, _front(prof, y_head) - PIVOT_BEHIND_MASK * scale, ["proportions"] + (["chin"] if by_chin else [])


def head_length(prof, top, reach=0.5):
    """Length of the head, front to back: the largest depth of the slabs within ``reach`` (head sizes) of the top
    (``prof`` from :func:`height_profile`). Unlike the depth at one level it hardly moves when the
    head is pitched a few degrees: the slab that holds it changes, its length barely."""
    upper = prof["y"] > top - reach
    d = prof["zmax"][upper] - prof["zmin"][upper]
    return float(np.nanmax(d)) if np.isfinite(d).any() else 1.0


def _at(prof, key, y):
    """``prof[key]`` at height ``y``, linear between the slabs' centres (NaN slabs skipped): continuous
    in ``y``, so a pivot on a slab's edge does not jump with round-off (a rotated or rescaled copy of
    the head gets the same joints). NaN when the profile has no such value."""
    v = prof[key]
    ok = np.isfinite(v)
    return float(np.interp(y, prof["y"][ok], v[ok])) if ok.any() else float("nan")


def _front(prof, y):
    """The most anterior point of the section at height ``y`` (0 if there is none)."""
    z = _at(prof, "zmax", y)
    return z if np.isfinite(z) else 0.0


def _section_depth(prof, y):
    """The pivot's depth from the section at height ``y``: ``PIVOT_BACK`` of its depth in front of
    its back, and no more than ``PIVOT_BACK_WIDTH`` of its width (a snout or a jaw far in front of
    the neck lengthens the section, not the skull's base)."""
    lo, hi = _at(prof, "zmin", y), _at(prof, "zmax", y)
    width = _at(prof, "xmax", y) - _at(prof, "xmin", y)
    if not np.isfinite(lo + hi + width):
        return 0.0
    return float(lo + min(PIVOT_BACK * (hi - lo), PIVOT_BACK_WIDTH * width))


def _neck(prof, below, bottom):
    """The neck under the head: its narrowest section and its base; None with no neck.

    The slabs from ``UNDER_CHIN`` below ``below`` (the pivot: a chin step may be wrong) down to two
    slabs above the bottom (a cut's last slab is partly empty) are scanned downward, keeping the
    narrowest width so far (the neck's waist); the first slab ``SHOULDERS`` times as wide is the
    top of the shoulders (a bust's chest), where the neck starts. With none, the neck runs to the
    bottom cut. The base's depth is its section's middle."""
    y = prof["y"]
    w, d = prof["xmax"] - prof["xmin"], prof["zmax"] - prof["zmin"]
    rows = np.flatnonzero((y < below - UNDER_CHIN) & (y > bottom + 2 * SLAB) & np.isfinite(w) & np.isfinite(d))
    if len(rows) < 2:
        return None
    rows = rows[::-1]  # top down
    waist = np.minimum.accumulate(w[rows])
    wide = np.flatnonzero(w[rows][1:] >= SHOULDERS * waist[:-1]) + 1
    if len(wide):
        k = int(wide[0])
        at, base, base_cue = int(rows[k]), float(y[rows[k]]), "shoulders"
        narrow = int(rows[:k][np.argmin(w[rows[:k]])])
    else:
        at, base, base_cue = int(rows[-1]), float(bottom), "bottom_cut"
        narrow = int(rows[np.argmin(w[rows])])
    centre = 0.5 * (prof["zmin"][at] + prof["zmax"][at])
    return {"height": float(y[narrow]), "depth": float(d[narrow]), "base": base, "base_cue": base_cue,
            "base_z": float(centre)}
