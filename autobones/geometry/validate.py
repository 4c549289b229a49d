"""Checking plain mesh arrays at a function's boundary."""
import numpy as np

from ..errors import AutobonesError


def mesh_arrays(V, F, name="mesh", allow_no_faces=False, finite=True):
    """``V`` as contiguous float64 ``(n, 3)`` and ``F`` as contiguous int64 ``(m, 3)``, or one
    :class:`AutobonesError` naming ``name`` and what is wrong (shape, non-integer or out-of-range
    indices, NaN or infinite coordinates). ``allow_no_faces`` accepts ``m = 0``; ``finite=False``
    lets non-finite coordinates through (a renderer drops the triangles they touch)."""
    V = np.ascontiguousarray(V, dtype=np.float64)
    F = np.asarray(F)
    if F.size == 0 and allow_no_faces:
        F = F.reshape(0, 3)
    if V.ndim != 2 or V.shape[1] != 3 or (len(V) == 0 and not allow_no_faces):
        raise AutobonesError(f"{name}: vertices must have shape (n, 3), got {V.shape}")
    if F.ndim != 2 or F.shape[1] != 3 or (len(F) == 0 and not allow_no_faces):
        raise AutobonesError(f"{name}: faces must have shape (m, 3) (triangles), got {F.shape}")
    if not np.issubdtype(F.dtype, np.integer) and not np.all(np.mod(F, 1) == 0):
        raise AutobonesError(f"{name}: faces must hold integer vertex indices")
    F = np.ascontiguousarray(F, dtype=np.int64)
    if len(F) and (F.min() < 0 or F.max() >= len(V)):
        raise AutobonesError(f"{name}: face indices out of range 0..{len(V) - 1}")
    if finite and not np.isfinite(V).all():
        raise AutobonesError(f"{name}: vertices contain NaN or infinite coordinates")
    return V, F
