"""Posing the joints: lid and jaw turns, and the head, neck and eye bones by linear blend skinning.

Stage 4 of the expression model (Bibliowicz 2005, §4.2): the lid joints turn their skin about
the eye pivots, the jaw turns each vertex about its pivot by its jaw weight times the angle
(blending the angle, not the positions: linear blending would pull half-weighted skin under the
chin toward the pivot, into the neck), then head, neck and eyes move by linear blend skinning.
All in the canonical frame (+Y up, +Z front), head sizes; angles in degrees.
"""
from __future__ import annotations

import numpy as np

from ..errors import AutobonesError
from ..geometry.rotations import align_rotation, axis_rotation, euler_rotation, line_turn, x_turn


def turn_lids(d, V, amounts, weights, close_deg, lower_range, pivots, hinges=None):
    """Displacement ``d`` (n, 3) with the lid joints turned (a new array).

    ``V`` (n, 3) rest vertices; ``amounts`` (4,) per lid joint (order ``lids.LIDS``; upper 1
    closes the lid by ``close_deg`` (2,) of its eye, lower 1 raises by ``lower_range`` of it);
    ``weights`` (4, n) lid weights; ``pivots`` (2, 3) eye pivots. Each vertex turns about +X
    through its eye's pivot by its weight times the angle, from where ``d`` put it
    (Bibliowicz 2005). ``hinges``, optional, (points (2, 3), unit axes (2, 3), closing angles
    (2,) degrees, share (n,), joints (4,) bool: which lid joints hinge) (``lids.lid_hinges``):
    for those joints a vertex's displacement is
    ``1 - share`` times that turn plus ``share`` times the turn by its weight times the amount
    times the hinge's own closing angle about the hinge line (through the eye corners), for a
    lid that closes (amount > 0: orbicularis sweeps the margin down about the canthi); a lid that
    opens (amount < 0: the levator draws the tarsal plate back over the eyeball) turns about the
    eye pivot only.
    """
    d = np.array(d, dtype=np.float64)
    for q in np.flatnonzero(amounts):
        e = q % 2
        w = weights[q]
        rows = np.flatnonzero(w > 0)
        if len(rows) == 0:
            continue
        scale = amounts[q] * w[rows] * (-lower_range if q >= 2 else 1.0)
        P = V[rows] + d[rows]
        turn = x_turn(P - pivots[e], np.radians(close_deg[e]) * scale)
        if hinges is not None and amounts[q] > 0 and hinges[4][q] and hinges[3][rows].any():
            h = hinges[3][rows, None]
            turn = (1.0 - h) * turn + h * line_turn(P - hinges[0][e], hinges[1][e], np.radians(hinges[2][e]) * scale)
        d[rows] += turn
    return d


def turn_jaw(d, V, jaw_deg, weight, pivot, glide):
    """Displacement ``d`` (n, 3) with the jaw opened by ``jaw_deg`` (in place; returned).

    Each vertex with jaw ``weight`` (n,) > 0 turns about +X through ``pivot`` (3,) by its weight
    times the angle, and moves by its weight times ``glide`` (3,) per degree (the condyle gliding
    down and forward along the articular eminence as the jaw opens).
    """
    rows = np.flatnonzero(weight > 0)
    ang = np.radians(float(jaw_deg)) * weight[rows]
    d[rows] += x_turn(V[rows] + d[rows] - pivot, ang)
    step = glide * float(jaw_deg)
    if np.any(step):
        d[rows] += weight[rows, None] * step[None, :]
    return d


def _eye_rotation(eye_pivot, base, look_at, gaze, ahead=(0.0, 0.0, 1.0)):
    """Rotation (3, 3) of one eye in the head's rest frame, or None: from looking ``ahead`` (3,),
    aimed at ``look_at`` (3,) canonical point in the posed world, carried back through ``base``; or
    (yaw, pitch) ``gaze``."""
    if look_at is not None:
        # the target is given in the posed world: bring it into the head's rest frame
        tgt = base[0].T @ (look_at - base[1])
        dvec = tgt - eye_pivot
        return align_rotation(np.asarray(ahead, dtype=np.float64), dvec / max(np.linalg.norm(dvec), 1e-300))
    if gaze is not None and np.any(np.asarray(gaze, dtype=float)):
        yaw, pitch = (list(np.ravel(gaze).astype(float)) + [0.0])[:2]
        return axis_rotation(1, yaw) @ axis_rotation(0, -pitch)
    return None


def bone_transforms(names, pivots, jaw_deg, gaze, look_at, head_deg, neck_deg, parents=None, basis=None):
    """World transforms of the bones that move: bone index -> (R (3, 3), t (3,)), x -> R x + t.

    Parameters
    ----------
    names : list of str
        Bone names (``neck``, ``head``, ``jaw``, ``eye_l``, ``eye_r`` are used).
    pivots : (b, 3) float
        Bone pivots (heads), canonical.
    jaw_deg : float
        Jaw opening (a rigid jaw turn; 0 when the jaw is posed by :func:`turn_jaw`).
    gaze : (yaw, pitch) degrees or None
        Both eyes, yaw toward the subject's left, pitch up.
    look_at : (3,) float or None
        Canonical point both eyes aim at (takes precedence over ``gaze``).
    head_deg, neck_deg : (pitch, yaw, roll) degrees or None
        About +X, +Y, +Z at the head / neck pivots.
    parents : list of int, optional
        Each bone's parent (-1 for a root): every other bone under the head (``place``'s facial
        bones) then moves with the head, and under the neck alone with the neck.
    basis : (3, 3) float, optional
        Rows: the left, up and front the head, neck and gaze angles are about, in the canonical frame
        (a transferred rig's anatomical axes, :attr:`autobones.orient.Frame.turn_axes`, where its
        canonical frame leans with the face); default the canonical axes.

    Raises AutobonesError when a control needs a bone the rig lacks.
    """
    def local(name, R):
        c = pivots[names.index(name)]
        return R, c - R @ c

    def need(name, what):
        if name not in names:
            raise AutobonesError(f"{what}: the rig has no {name!r} bone")

    basis = None if basis is None else np.asarray(basis, dtype=np.float64)

    def about(R):   # a rotation about the basis' axes, in canonical coordinates
        return R if basis is None else basis.T @ R @ basis

    world = {}
    base = (np.eye(3), np.zeros(3))
    if neck_deg is not None and np.any(np.asarray(neck_deg, dtype=float)):
        need("neck", "neck_deg")
        base = local("neck", about(euler_rotation(neck_deg)))
        world["neck"] = base
    if head_deg is not None and np.any(np.asarray(head_deg, dtype=float)):
        need("head", "head_deg")
        Rh, th = local("head", about(euler_rotation(head_deg)))
        base = (base[0] @ Rh, base[0] @ th + base[1])
    if "head" in names and (np.any(base[0] != np.eye(3)) or np.any(base[1])):
        world["head"] = base
    if jaw_deg:
        need("jaw", "jaw_deg")
        Rj, tj = local("jaw", axis_rotation(0, jaw_deg))
        world["jaw"] = (base[0] @ Rj, base[0] @ tj + base[1])
    elif "jaw" in names and "head" in world:
        world["jaw"] = base
    gazing = gaze is not None and np.any(np.asarray(gaze, dtype=float))
    for s in "lr":
        eye = f"eye_{s}"
        Re = None
        if look_at is not None or gazing:
            need(eye, "look_at" if look_at is not None else "gaze")
            # at rest the eyes look along the head's front (the basis', not a leaning frame's)
            Re = _eye_rotation(pivots[names.index(eye)], base, look_at, gaze,
                               ahead=(0.0, 0.0, 1.0) if basis is None else basis[2])
            if Re is not None and look_at is None:
                Re = about(Re)   # a gaze's yaw and pitch are about the head's axes; an aim is a point
        if Re is not None:
            Rl, tl = local(eye, Re)
            world[eye] = (base[0] @ Rl, base[0] @ tl + base[1])
        elif eye in names and "head" in world:
            world[eye] = base
    if parents is not None:
        # bones the controls above do not name ride on their nearest moving ancestor (parents come first)
        for b, name in enumerate(names):
            if name not in world and parents[b] >= 0 and names[parents[b]] in world:
                world[name] = world[names[parents[b]]]
    return {names.index(name): T for name, T in world.items()}


def blend_bones(d, V, W, transforms):
    """Displacement ``d`` (n, 3) with the bone ``transforms`` (:func:`bone_transforms`) applied by
    linear blend skinning with skin weights ``W`` (n, b) to the points ``V + d`` (in place;
    returned)."""
    if transforms:
        P = V + d
        for b, (Rb, tb) in transforms.items():
            w = W[:, b]
            rows = np.flatnonzero(w != 0)
            if len(rows):
                d[rows] += w[rows, None] * (P[rows] @ (Rb - np.eye(3)).T + tb)
    return d
