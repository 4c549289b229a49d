"""What ``autobones landmarks HEAD --edit`` works on: the head, where it starts, the checks, the files it writes.

Issue #35. The page (static/editor.js) places and moves names; everything that judges or writes them is
here, in Python, calling the package's own code, so the editor and ``transfer`` never disagree:

- the checks are :func:`autobones.io.landmark_checks.landmark_problems`, the tests ``transfer`` refuses
  a set with (off the surface, wrong units, left/right swapped, two names at one point, too few), listed
  per name, with the frame ``transfer`` would use (:func:`~autobones.orient.frame_from_landmarks`, else
  the detected one);
- a bilateral name's partner is proposed through the head's symmetry plane
  (:func:`~autobones.orient.detect_frame`: canonical x = 0) and put back on the surface;
- the proposals for the names not placed come from :mod:`autobones.landmarks.assist` (when installed);
- saving writes the contract JSON (and MeshLab ``.pp``) each through a temporary file renamed into
  place; nothing is written before the user saves.

Coordinates in and out are the mesh's own frame and units.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from ..errors import AutobonesError
from ..io.atomic import check_destination, refuse_overwriting_inputs
from ..io.landmark_checks import landmark_problems, landmark_values
from ..io.landmark_names import GROUPS, NAMES, mirror_name, where
from ..orient import detect_frame, frame_from_landmarks
from ..rig_transfer.head_landmarks import MIN_LANDMARKS  # the fewest landmarks transfer takes: the page's "too few"

#: The names the assisted proposal needs placed first (``assist_landmarks``'s ``given``).
ASSIST_NEEDS = ("exocanthion_l", "exocanthion_r", "pronasale", "cheilion_l", "cheilion_r")


@dataclass
class EditSession:
    """One head being landmarked.

    Attributes
    ----------
    head : str
        The mesh file (shown, never written).
    V, F : arrays
        Its vertices (n, 3) float64, own frame and units, and triangles (m, 3) int64.
    frame : autobones.orient.Frame
        Detected once: its plane canonical x = 0 is the head's symmetry plane.
    output, pp_output : str or None
        The contract JSON and the ``.pp`` that Save writes.
    start : dict
        name -> (3,) the page starts from (``--from`` file, detected landmarks, or empty).
    confidence : dict
        name -> [0, 1] for detected starting landmarks.
    note : str or None
        One line for the page (e.g. why it starts empty).
    detect : bool
        Whether automatic detection may run: the proposals use the detector's names on a person's face,
        as ``landmarks --assist`` does (:func:`autobones.landmarks.assist.assist_landmarks`).
    """

    head: str
    V: np.ndarray
    F: np.ndarray
    frame: object
    output: str
    pp_output: str = None
    start: dict = field(default_factory=dict)
    confidence: dict = field(default_factory=dict)
    note: str = None
    rig: str = None
    saved: list = field(default_factory=list)
    detect: bool = True
    up: str = None        # the axes given on the command line, for a detection at the first proposal
    front: str = None
    # the head's automatic landmarks, found once (at the start, or at the first proposal on a person's
    # face) and kept: None not yet tried, False found none
    detection: object = None

    def page_facts(self):
        """What the page needs to start: names by group with where each goes, the start, the display frame."""
        lo, hi = self.V.min(axis=0), self.V.max(axis=0)
        return {
            "head": os.path.basename(self.head),
            "output": self.output, "pp_output": self.pp_output,
            "groups": [{"name": g, "names": [{"name": n, "where": where(n), "side": _side(n)} for n in names]}
                       for g, names in GROUPS],
            "start": {n: [float(c) for c in p] for n, p in self.start.items()},
            "confidence": {n: round(float(c), 3) for n, c in self.confidence.items()},
            "note": self.note,
            "vertices": len(self.V), "triangles": len(self.F),
            # the page draws V - center (float32 keeps its precision near the head) and adds center back
            "center": [float(c) for c in (lo + hi) / 2], "size": float((hi - lo).max()),
            **display_axes(self.V, self.F, self.frame, self.start),
            "min_count": MIN_LANDMARKS, "assist_needs": list(ASSIST_NEEDS), "assist_error": assist_missing(),
        }

    def mesh_bytes(self):
        """The mesh for the page: float32 (V - center) then uint32 triangle indices, little-endian."""
        center = (self.V.min(axis=0) + self.V.max(axis=0)) / 2
        return (self.V - center).astype("<f4").tobytes() + self.F.astype("<u4").tobytes()

    def parse(self, landmarks):
        """The page's ``{name: [x, y, z]}`` as contract names and finite (3,) arrays; AutobonesError otherwise."""
        return landmark_values(landmarks, "the page's landmarks")

    def problems(self, landmarks):
        """Per-name problems of the page's landmarks, as ``transfer`` would judge them (module docstring)."""
        lm = self.parse(landmarks)
        frame = frame_from_landmarks(self.V, self.F, lm) if lm else None
        out = landmark_problems(lm, self.V, self.F, frame=frame or self.frame, min_count=MIN_LANDMARKS)
        out["count"] = len(lm)
        return out

    def mirror(self, name, point):
        """``(partner name, (3,) point)``: ``point`` reflected through the symmetry plane, on the surface.

        AutobonesError for a midline name (it has no partner)."""
        partner = mirror_name(name)
        if partner == name:
            raise AutobonesError(f"{name} is a midline name; it has no partner to mirror")
        p = np.asarray(point, dtype=np.float64).reshape(3)
        c = self.frame.to_canonical(p[None])
        c[:, 0] *= -1.0  # canonical x = 0 is the plane
        return partner, closest_on_surface(self.frame.from_canonical(c), self.V, self.F)[0]

    def assist(self, landmarks):
        """The assisted proposal for every name not placed: ``{"points", "confidence", "detected"}``.

        ``detected`` lists the proposed names taken from the automatic detector (the rest: the fit's)."""
        lm = self.parse(landmarks)
        missing = [n for n in ASSIST_NEEDS if n not in lm]
        if missing:
            raise AutobonesError(f"the proposal needs {', '.join(missing)} placed first")
        if assist_missing():
            raise AutobonesError(assist_missing())
        from ..landmarks.assist import assist_landmarks

        # every name placed is given: the fit follows all the user has placed, not only the five it needs;
        # on a person's face the detector's names where it finds them, as `landmarks --assist` proposes
        got = assist_landmarks(self.V, self.F, lm, rig=self.rig, detected=self._detected if self.detect else None)
        points = {n: [float(c) for c in np.asarray(p, dtype=np.float64).reshape(3)]
                  for n, p in got.points.items() if n in NAMES and n not in lm}
        conf = {n: round(float(got.confidence.get(n, 0.0)), 3) for n in points}
        # the page says where each proposal came from: a detector's point and a fitted one deserve
        # different trust (the detector's are measured on people's faces, the fit's on every family)
        return {"points": points, "confidence": conf, "detected": sorted(set(got.detected) & set(points))}

    def _detected(self):
        """The head's automatic landmarks (None: none found or the detector not installed), found once."""
        if self.detection is None:
            import autobones

            try:
                self.detection = autobones.detect_landmarks((self.V, self.F), up=self.up, front=self.front,
                                                            name=self.head) or False
            except AutobonesError:
                self.detection = False
        return self.detection or None

    def save(self, landmarks):
        """Write the landmarks (the contract JSON, and the ``.pp`` when asked), each atomically.

        Both destinations are checked before either is written. Returns the paths written."""
        from ..io.landmarks import write_landmarks, write_picked_points

        lm = self.parse(landmarks)
        if not lm:
            raise AutobonesError("no landmarks placed; nothing to save")
        outs = [p for p in (self.output, self.pp_output) if p]
        for p in outs:
            check_destination(p, "the landmark file")
        mesh = os.path.basename(self.head)
        write_landmarks(self.output, lm, mesh_name=mesh)
        if self.pp_output:
            write_picked_points(self.pp_output, lm, mesh_name=mesh)
        self.saved = outs
        return outs


def display_axes(V, F, frame, landmarks):
    """``{"up", "front"}`` the page's camera starts from: the mesh's own axes nearest the head's up and
    front (what the modeller chose, as ``autobones view`` shows a rig), the head's from its landmarks when
    they tell it (an animal's detected frame can sit 45 degrees off), else from ``frame``; the exact
    directions when both round to one axis."""
    from ..orient import nearest_axis, parse_axis

    fr = (frame_from_landmarks(V, F, landmarks) if landmarks else None) or frame
    up, front = fr.rotation[1], fr.rotation[2]
    au, af = parse_axis(nearest_axis(up)), parse_axis(nearest_axis(front))
    if abs(float(np.dot(au, af))) < 0.5:
        up, front = au, af
    return {"up": [float(c) for c in up], "front": [float(c) for c in front]}


def assist_missing():
    """None when :mod:`autobones.landmarks.assist` can be imported, else one line saying it cannot."""
    import importlib.util

    if importlib.util.find_spec("autobones.landmarks.assist") is None:
        return "assisted proposals are not available: this autobones has no autobones.landmarks.assist"
    return None


def _side(name):
    return "l" if name.endswith("_l") else "r" if name.endswith("_r") else "mid"


def closest_on_surface(P, V, F):
    """(k, 3) closest points of the surface (V, F) to the points ``P`` (k, 3)."""
    import igl

    _, _, C = igl.point_mesh_squared_distance(np.ascontiguousarray(P, dtype=np.float64), V, F)
    return np.asarray(C, dtype=np.float64).reshape(-1, 3)


def edit_outputs(head, output=None, pp=None, source=None):
    """``(json path, .pp path or None)`` that the editor saves to, refused before anything is served.

    ``output`` ending in ``.pp`` writes that ``.pp`` and the contract JSON beside it
    (``NAME.landmarks.json``); without ``output``, ``HEAD_NAME.landmarks.json`` in the current folder.
    An output is never the mesh; it is the ``--from`` file only when named with ``-o`` outright
    (editing a landmark file in place), never by default.
    """
    explicit = output is not None and not output.lower().endswith(".pp")  # the JSON named outright
    if output and output.lower().endswith(".pp"):
        pp = pp or output
        output = os.path.join(os.path.dirname(output), os.path.basename(output)[:-3] + ".landmarks.json")
    output = output or os.path.splitext(os.path.basename(head))[0] + ".landmarks.json"
    if pp is not None and not pp.lower().endswith(".pp"):
        raise AutobonesError(f"--pp {pp}: MeshLab picked points are written as .pp")
    refuse_overwriting_inputs([output, pp], [head])
    if not explicit:  # a name the user did not write (the default, or beside -o X.pp) never replaces the file read
        refuse_overwriting_inputs([output], [source])
    for p in (output, pp):
        if p:
            check_destination(p, "the landmark file")
    return output, pp


def open_session(head, output=None, pp=None, source=None, up=None, front=None, detect=True, rig=None):
    """An :class:`EditSession` for the mesh file ``head``; AutobonesError (nothing written) for a
    missing or unreadable mesh or ``--from`` file, or an output that would replace an input.

    Starts from ``source`` (contract JSON, ``.pp``, iBUG-68; names and values checked, their places on
    the page) when given, else from automatic detection when ``detect`` (human faces; no face found:
    empty, with a note saying why), else empty. ``rig``: the generic rig folder the assisted proposals
    fit (None: the built-in one).
    """
    import autobones
    from ..io.landmarks import read_landmarks

    output, pp = edit_outputs(head, output, pp, source)
    start = read_landmarks(source) if source else {}
    V, F = autobones.load_mesh(head)
    V = np.ascontiguousarray(V, dtype=np.float64)
    F = np.ascontiguousarray(F, dtype=np.int64)
    frame = detect_frame(V, F, up=up, front=front)
    confidence, note, detection = {}, None, None
    if source:
        note = f"started from {os.path.basename(source)} ({len(start)} landmarks)"
    elif detect:
        try:
            detection = autobones.detect_landmarks((V, F), up=up, front=front, name=head)
            start, confidence = dict(detection), dict(detection.confidence)
            note = f"{len(start)} landmarks found automatically: check each"
        except AutobonesError as exc:
            detection = False
            note = f"no landmarks found automatically ({str(exc).split(';')[0]}); place them by hand"
    return EditSession(head=head, V=V, F=F, frame=frame, output=output, pp_output=pp, start=start,
                       confidence=confidence, note=note, rig=rig, detect=detect, detection=detection,
                       up=up, front=front)

