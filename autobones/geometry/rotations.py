"""Rotations: about the axes, from Euler angles, between two directions, the best similarity between point sets,
the rotation factors of matrices, the +X turn of points and their turn about any axis, the 24 axis turns."""
import numpy as np
from scipy.optimize import linear_sum_assignment


def rotate_between(a, b, v):
    """Rotate each row of ``v`` (n, 3) by the smallest rotation taking unit ``a`` (n, 3) to unit
    ``b`` (n, 3), row by row (Rodrigues' formula)."""
    k = np.cross(a, b)
    s = np.linalg.norm(k, axis=1, keepdims=True)
    c = np.einsum("ij,ij->i", a, b)[:, None]
    k = k / np.maximum(s, 1e-12)
    return v * c + np.cross(k, v) * s + k * np.einsum("ij,ij->i", k, v)[:, None] * (1.0 - c)


def axis_turn(A):
    """The axis-aligned rotation nearest the linear part ``A`` (3, 3) of a row-vector map
    ``x -> x @ A + t``: (3, 3), a signed permutation with det +1, applied as ``x @ R``.

    Each source axis goes to the target axis it is most aligned with after the polar
    rotation of ``A``: the 24 axis turns are the ways a mesh file can choose its up and
    front. The identity for a head modelled facing the generic's way (tilted by less than
    about 45 degrees: such heads fit exactly as before); never farther from the polar
    rotation than the identity is.
    """
    U, _, Vt = np.linalg.svd(np.asarray(A, dtype=np.float64))
    R = U @ Vt
    R = R * np.where(np.linalg.det(R) < 0, -1.0, 1.0)   # mirrored landmarks: the nearest rotation
    T = np.zeros((3, 3))
    rows, cols = linear_sum_assignment(-np.abs(R))
    T[rows, cols] = np.sign(R[rows, cols])
    if np.linalg.det(T) < 0:   # keep it a rotation: flip the least certain axis
        k = int(np.argmin(np.abs(R[rows, cols])))
        T[rows[k], cols[k]] *= -1.0
    return T


def axis_rotation(axis, deg):
    """(3, 3) right-handed rotation about the frame's axis ``axis`` (0, 1, 2: X, Y, Z) by ``deg``
    degrees, applied to column vectors (``R @ x``)."""
    a = np.radians(float(deg))
    c, s = np.cos(a), np.sin(a)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    R = np.eye(3)
    R[i, i], R[i, j], R[j, i], R[j, j] = c, -s, s, c
    return R


def euler_rotation(deg):
    """(3, 3) rotation ``Rz @ Ry @ Rx`` from (pitch, yaw, roll) degrees about +X, +Y, +Z (missing
    trailing angles are 0), applied to column vectors."""
    p, y, r = (list(np.ravel(deg).astype(float)) + [0.0, 0.0, 0.0])[:3]
    return axis_rotation(2, r) @ axis_rotation(1, y) @ axis_rotation(0, p)


def align_rotation(a, b):
    """(3, 3) smallest rotation taking unit vector ``a`` (3,) to unit vector ``b`` (3,), applied to
    column vectors; opposite vectors give the half turn about +Y."""
    v, c = np.cross(a, b), float(a @ b)
    if c < -0.999999:
        return axis_rotation(1, 180.0)
    K = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    return np.eye(3) + K + K @ K / (1.0 + c)


def similarity(P, Q, weights=None):
    """Least-squares similarity (Umeyama 1991) taking points ``P`` (k, 3) onto ``Q`` (k, 3) about their
    means: scale ``s`` and proper rotation ``R`` (3, 3) minimising ``sum ||s R (p - mean p) - (q - mean q)||^2``
    (the translation is ``mean q - s R mean p``). With ``weights`` (k,) (non-negative, not all 0) each
    term of the sum and the means are weighted (``np.average``'s)."""
    P0, Q0 = P - np.average(P, axis=0, weights=weights), Q - np.average(Q, axis=0, weights=weights)
    wP0 = P0 if weights is None else P0 * np.asarray(weights, dtype=np.float64)[:, None]
    U, S, Vt = np.linalg.svd(Q0.T @ wP0)
    d = np.sign(np.linalg.det(U @ Vt)) or 1.0
    D = np.diag([1.0, 1.0, d])
    R = U @ D @ Vt
    s = float(np.trace(np.diag(S) @ D) / max(float((wP0 * P0).sum()), 1e-300))
    return s, R


def polar_rotations(M):
    """The rotation factor of each (3, 3) matrix of ``M`` (m, 3, 3) (polar decomposition, made proper:
    det +1, the nearest rotation to a mirroring map), (m, 3, 3); applied as the matrices were."""
    U, _, Vt = np.linalg.svd(M)
    d = np.sign(np.linalg.det(U @ Vt))
    d[d == 0] = 1.0
    U[:, :, 2] *= d[:, None]
    return U @ Vt


def x_turn(P, angle):
    """Displacement (m, 3) of points ``P`` (m, 3), given relative to a pivot, turned by ``angle``
    (radians, scalar or (m,)) about the +X axis (in the canonical frame: the lid and jaw joints'
    axis, the subject's left)."""
    ca, sa = np.cos(angle), np.sin(angle)
    return np.c_[np.zeros(len(P)), (ca - 1.0) * P[:, 1] - sa * P[:, 2], sa * P[:, 1] + (ca - 1.0) * P[:, 2]]


def line_turn(P, axis, angle):
    """Displacement (m, 3) of points ``P`` (m, 3), given relative to a point of the line, turned by
    ``angle`` (radians, scalar or (m,)) right-handedly about the unit direction ``axis`` (3,)
    (Rodrigues' formula); :func:`x_turn` when ``axis`` is +X."""
    u = np.asarray(axis, dtype=np.float64)
    ang = np.broadcast_to(np.asarray(angle, dtype=np.float64), (len(P),))[:, None]
    ca, sa = np.cos(ang), np.sin(ang)
    return (ca - 1.0) * P + sa * np.cross(u, P) + (1.0 - ca) * (P @ u)[:, None] * u[None, :]
