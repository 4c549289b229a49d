"""Operations on per-vertex weight matrices ``(n_vertices, n_bones)``."""
import numpy as np


def prune_weights(W, fraction=0.01):
    """Zero the weights below ``fraction`` of each row's largest, renormalise the rest.

    Parameters
    ----------
    W : (n, b) float
        Non-negative weights, rows summing to 1.

    Returns
    -------
    (n, b) float, rows summing to 1.
    """
    W = np.where(W < fraction * W.max(axis=1, keepdims=True), 0.0, W)
    return W / W.sum(axis=1, keepdims=True)
