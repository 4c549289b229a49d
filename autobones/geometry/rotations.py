"""Rotations: about the canonical axes, between two directions, and the 24 axis turns."""
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
