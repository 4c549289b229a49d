"""The (up, front) candidates :func:`autobones.orient.detect_frame` scores: directions round the
symmetry plane fixed to the shape, or the input axes when the user forces one of them, and the ones a
cut (neck, bust base, a face capture's opening) leaves.

Goes beyond the papers we implement (they take upright heads). Without a forced axis nothing here
reads the file's axes: the candidates start from the main cut's far side or the sample's own
principal direction (signed by its third moment), so a head turned or scaled in its file gets the same
candidates turned with it, in the same order.
"""
from __future__ import annotations

import numpy as np

from .cut_cues import base_score, cap_score, is_planar_cut, open_shell_facing
from .errors import AutobonesError

# vector area / area of an open surface (cut_cues.open_shell_facing): above OPEN_SHELL a clear cut
# opposite the way it faces is its back (a face-only capture), not a neck cut; above FACE_SHELL it is
# a face-only capture whatever its rim looks like
OPEN_SHELL = 0.22
FACE_SHELL = 0.4
# ups closer than this are neighbours on the circle of candidates (30 degrees apart): a cut clear at
# one up shows at its neighbours too, so an up is "clearly" cut against the ups beyond it
NEIGHBOUR = float(np.cos(np.radians(45.0)))
# a closed mesh's flat cap (cut_cues.cap_score) marks its bottom when it covers this share of the
# surface and this many times any up beyond its neighbours (the goat's base: 0.042 against 0.005)
CAP_MIN = 0.02
CAP_RATIO = 4.0
CAP_SPREAD = 3    # steps of 5 degrees: a cap's own score spreads over its tilt (15 degrees) either side


def shape_candidates(P, normal, cues, steps=12):
    """Signed (up, front) pairs: ``steps`` ups round the symmetry plane (unit ``normal``), from the
    main cut's far side (a neck cut or a bust base: :func:`autobones.cut_cues.cut_cues`) or, with
    none, the sample's longest in-plane axis signed by its third moment, each with both fronts."""
    ref = cues["loop_normal"] if cues is not None and cues["loop_normal"] is not None else None
    if ref is None or np.linalg.norm(ref - (ref @ normal) * normal) < 0.3:
        c = P - P.mean(axis=0)
        c = c - np.outer(c @ normal, normal)
        c = c / max(float(np.abs(c).max()), 1e-300)
        _, E = np.linalg.eigh(c.T @ c)
        ref = E[:, 2] * (-1.0 if ((c @ E[:, 2]) ** 3).sum() < 0 else 1.0)
    a = ref - (ref @ normal) * normal
    a /= np.linalg.norm(a)
    b = np.cross(normal, a)
    ups = [np.cos(t) * a + np.sin(t) * b for t in np.radians(np.arange(steps) * 360.0 / steps)]
    return [(u, f) for u in ups for f in (np.cross(normal, u), np.cross(u, normal))]


def axis_candidates(normal, up_v, front_v):
    """Signed (up, front) pairs when the user forces up or front: up is an input axis projected into
    the symmetry plane, front completes the frame, both within 45 degrees of the forced axes."""
    out = []
    for i in sorted(np.argsort(np.abs(normal))[:2]):
        for sign in (1.0, -1.0):
            u = sign * np.eye(3)[i]
            u = u - (u @ normal) * normal
            u /= np.linalg.norm(u)
            if up_v is not None and u @ up_v < 0.7:
                continue
            for f in (np.cross(normal, u), np.cross(u, normal)):
                if front_v is not None and f @ front_v < 0.7:
                    continue
                out.append((u, f))
    if not out:
        raise AutobonesError("the given --up/--front lies along the head's left-right axis; pick another axis")
    return out


def _rival(ups, score, against):
    """The best score among ``ups`` beyond the neighbours of every up in ``against`` (0 if none)."""
    far = [score[k] for k in ups if all(np.array(k) @ np.array(a) < NEIGHBOUR for a in against)]
    return max(far, default=0.0)


def _capped(ups, cues, normal, steps=72):
    """The candidate ups (keys of ``ups``) nearest the directions whose far ends are flat caps (a
    closed bust's base, and a back cut flat too: :func:`autobones.cut_cues.cap_score`) when they
    clearly are; else []. Caps are looked for ``steps`` directions round the symmetry plane (unit
    ``normal``; a symmetric head's base faces along its midplane): the candidates, 30 degrees
    apart, can miss a cap's own direction by 15 degrees, and the cap then drops out of the tilt it
    is measured within. A cap is a peak of the score round the circle above ``CAP_MIN``; the two
    highest count, and they are clear when the highest is ``CAP_RATIO`` times every direction
    more than ``CAP_SPREAD`` steps from both (the goat's base 0.042 and its back 0.028, 40 degrees
    apart, against at most 0.010 elsewhere)."""
    a = np.array(ups[0]) - (np.array(ups[0]) @ normal) * normal
    a /= np.linalg.norm(a)
    b = np.cross(normal, a)
    t = np.radians(np.arange(steps) * 360.0 / steps)
    dirs = np.cos(t)[:, None] * a + np.sin(t)[:, None] * b
    cap = np.array([cap_score(cues, d) for d in dirs])
    peak = (cap > CAP_MIN) & (cap >= np.roll(cap, 1)) & (cap > np.roll(cap, -1))
    found = sorted(np.flatnonzero(peak), key=lambda i: -cap[i])[:2]   # stable: ties keep the order
    if not found:
        return []
    step = np.arange(steps)
    far = np.ones(steps, dtype=bool)
    for i in found:
        far &= np.minimum((step - i) % steps, (i - step) % steps) > CAP_SPREAD
    if cap[found[0]] <= CAP_RATIO * cap[far].max(initial=0.0):
        return []
    return [max(ups, key=lambda k: np.array(k) @ dirs[i]) for i in found]


def front_part(ref, depth):
    """The canonical reference sample ``ref`` cut to its front part ``depth`` head widths deep (all of
    it when that leaves less than a tenth)."""
    z = ref[:, 2]
    part = ref[z >= z.max() - depth * np.ptp(ref[:, 0])]
    return part if len(part) >= 0.1 * len(ref) else ref


def cut_candidates(P, normal, candidates, cues, ref):
    """The (up, front) candidates a cut allows, the reference to score them against, and whether
    the head was taken for a face-only capture (then, for each candidate, a pair of the reference's
    front parts: see :func:`autobones.reference_overlay.best_part_scores`). A flat cut or an open rim (neck, bust base) marks
    the bottom when one is clear; a face-only capture faces away from its opening, which is its
    back, not its bottom: a shell open that wide, or one whose clear "cut" lies opposite the way it
    faces (then only the fronts along that way stay, scored against as deep a front part of the
    reference head)."""
    score = {}
    facing, openness = open_shell_facing(cues)
    mask = [(u, f) for u, f in candidates if f @ facing > 0.7]
    for u, _ in candidates:
        key = tuple(u)
        if key not in score:
            score[key] = base_score(cues, u)
    ups = sorted(score, key=score.get, reverse=True)  # stable: ties keep the candidates' order
    top = ups[0]
    second = _rival(ups, score, [top])
    winner = top if score[top] > 0.02 and score[top] > 2.0 * second else None
    capped = [] if winner is not None or len(cues["rim_length"]) else _capped(ups, cues, normal)
    near = lambda keys: [(u, f) for u, f in candidates if max(u @ np.array(k) for k in keys) >= NEIGHBOUR]
    if capped:   # a closed mesh has no opening: the face-only test below never holds for it
        return near(capped), ref, False
    # a shell open that wide whose cut lies behind the way it faces: a clear base score, or the planar
    # main loop's far side (12 ups 30 degrees apart share a cut between neighbours, and a shallow
    # capture's rim shows at every end: Lee Perry-Smith's front quarter, 0.129 against 0.068)
    behind = (winner is not None and np.array(winner) @ facing > 0.7) or (
        is_planar_cut(cues) and cues["loop_normal"] @ facing < -0.7)
    if mask and (openness > FACE_SHELL or (openness > OPEN_SHELL and behind)):
        # how deep a part of the reference head the capture matches is not known from the way its
        # opening faces (an opening cut aslant faces off the front: the menpo template's by 33
        # degrees, and a part that deep made its face pitched 47 degrees overlay best): each front
        # is scored against two, as deep as the capture is along that front and as deep as it is
        # thin (its least extent over the fronts kept), and the better counts (the first alone
        # turned James' front quarter upside down, the second alone pitched the template)
        across = max(np.ptp(P @ normal), 1e-300)
        thin = front_part(ref, min(np.ptp(P @ f) for _, f in mask) / across)
        return mask, [(thin, front_part(ref, np.ptp(P @ f) / across)) for _, f in mask], True
    if cues.get("far_loop") is not None:
        # open at both ends (a neck cut and a missing crown): the bottom is one of the two cuts
        return near([tuple(-cues["loop_normal"]), tuple(-cues["far_loop"]["normal"])]), ref, False
    if winner is not None:
        return near([winner]), ref, False
    runner = next((k for k in ups if np.array(k) @ np.array(top) < NEIGHBOUR), None)
    if runner is not None and second > 0.02 and second > 1.5 * _rival(ups, score, [top, runner]):
        # two directions look cut (a neck cut slanted down and back shows at the bottom and at the
        # back): the bottom is one of them, and only their candidates are scored
        return near([top, runner]), ref, False
    if is_planar_cut(cues):
        # a planar cut's far side is the bottom (a neck cut, a bust base) or the back (a face-only
        # capture), or between (a neck cut slanted down and back)
        d = cues["loop_normal"]
        kept = [(u, f) for u, f in candidates if max(-(d @ u), -(d @ f)) > 0.3 and d @ u < 0.3 and d @ f < 0.3]
        return kept or candidates, ref, False
    return candidates, ref, False
