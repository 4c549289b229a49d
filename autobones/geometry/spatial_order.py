"""An order of points by where they lie, not by how a file numbers them.

A random draw over points (k-means++ seeds, a subsample) picks index ``i`` where a uniform number falls
in the cumulative weights. Taken in the file's order, renumbering the vertices or one vertex joining a
mask changes every later pick to an unrelated point, and a different k-means layout wins. Taken in a
space-filling (Morton) order the picks are the same points when the points are the same, and a nearby
point when a weight or a member changes a little.
"""
import numpy as np

BITS = 10  # cells per axis 2^10: about a thousandth of the points' extent


def _spread_bits(q):
    """Integers ``q`` (< 2^BITS) with two zero bits after each bit (3-D Morton interleave)."""
    q = q.astype(np.uint64)
    out = np.zeros_like(q)
    for b in range(BITS):
        out |= ((q >> np.uint64(b)) & np.uint64(1)) << np.uint64(3 * b)
    return out


def spatial_order(X, tie=None):
    """Permutation (k,) int64 sorting points ``X`` (k, 3) (any units) along a Morton curve over their
    bounding box, ties (points in one cell) by x, then y, then z, then ``tie`` (k,) when given (a weight:
    an unwelded seam's two copies of a vertex carry different areas): the same order for the same
    points given in any order (points equal in all of these keep their given order)."""
    X = np.asarray(X, dtype=np.float64)
    if len(X) == 0:
        return np.zeros(0, dtype=np.int64)
    lo = X.min(axis=0)
    span = np.maximum(np.ptp(X, axis=0), 1e-300)
    q = np.clip(((X - lo) / span * (1 << BITS)).astype(np.int64), 0, (1 << BITS) - 1)
    key = _spread_bits(q[:, 0]) | (_spread_bits(q[:, 1]) << np.uint64(1)) | (_spread_bits(q[:, 2]) << np.uint64(2))
    keys = (X[:, 2], X[:, 1], X[:, 0], key)
    return np.lexsort(keys if tie is None else (np.asarray(tie, dtype=np.float64), *keys)).astype(np.int64)
