"""Thin-plate spline warp of 3-D space from landmark pairs.

Orvalho, Zacur & Susin 2008, §3.1 (equation 1), with Bookstein's (1989) algebra as Erdoğdu 2010
(§4.4.2) sets it out,
carried to three dimensions: the kernel is U(r) = r, the fundamental solution
of the biharmonic equation in 3-D (Erdoğdu's r² log r² is the 2-D kernel),
plus an affine part::

    f(x) = a_0 + A x + sum_i w_i U(||x - p_i||)

The weights solve ``[[K - lam I, P], [P^T, 0]] [W; a] = [Q; 0]`` with
``K_ij = ||p_i - p_j||`` and ``P = [1 | p]``. In 3-D, K is conditionally
*negative* definite, the bending energy is ``-trace(W^T K W)``, and the
smoothing term therefore enters as ``-lam I`` (the usual ``+lam I`` of the
2-D kernel would make the system indefinite). With ``lam = 0`` the warp is exact
at the landmarks and minimises bending energy; ``lam > 0`` is the smoothing
spline for noisy landmarks (Wahba; Donato and Belongie 2002), tending to the
least-squares affine map as ``lam`` grows.

``transform`` evaluates the warp in chunks, so memory is ``O(chunk * k)``,
never ``O(n^2)`` over mesh vertices.
"""
from __future__ import annotations

import numpy as np

from ..errors import AutobonesError, counted

# Rows of query points per chunk in ``transform``: chunk x k distances at a time.
CHUNK = 8192


def as_points(X, name):
    """Return ``X`` as a finite ``(k, 3)`` float64 array or raise AutobonesError."""
    if isinstance(X, dict):
        raise AutobonesError(f"{name}: pass an array; for landmark dicts use landmark_arrays(src, dst)")
    X = np.asarray(X, dtype=np.float64)
    if X.ndim != 2 or X.shape[1] != 3:
        raise AutobonesError(f"{name}: expected points of shape (k, 3), got {X.shape}")
    if not np.isfinite(X).all():
        raise AutobonesError(f"{name}: contains NaN or infinite coordinates")
    return X


def landmark_arrays(src, dst):
    """Pair two landmark dicts by name.

    Parameters
    ----------
    src, dst : dict of str -> (3,) float
        Landmarks ``{name: [x, y, z]}`` of the source and target meshes, each in
        its own mesh's frame and units.

    Returns
    -------
    names : list of str
        The names both dicts carry, sorted.
    P, Q : (k, 3) float64
        Source and target positions of those names, row for row.

    Raises
    ------
    AutobonesError
        When the two dicts share fewer than 4 names.
    """
    names = sorted(set(src) & set(dst))
    if len(names) < 4:
        raise AutobonesError(
            f"source and target share only {counted(len(names), 'landmark name')} ({', '.join(names) or 'none'}); "
            "a 3-D warp needs at least 4 common, well-spread landmarks (10 or more recommended)")
    P = np.array([src[n] for n in names], dtype=np.float64)
    Q = np.array([dst[n] for n in names], dtype=np.float64)
    return names, P, Q


def check_landmarks(P, name="landmarks"):
    """Raise AutobonesError if points cannot define a 3-D thin-plate spline.

    Parameters
    ----------
    P : (k, 3) float
        Landmark positions, any units.
    name : str
        What to call the set in messages.

    Raises
    ------
    AutobonesError
        Fewer than 4 points, two points at the same place, or all points on
        one plane or line (the affine part would be undetermined).
    """
    P = as_points(P, name)
    k = len(P)
    if k < 4:
        raise AutobonesError(
            f"{name}: {counted(k, 'point')}; a 3-D warp needs at least 4 landmarks not on one plane (10 or more recommended)")
    C = P - P.mean(axis=0)
    scale = np.sqrt((C**2).sum(axis=1).mean())
    if scale == 0:
        raise AutobonesError(f"{name}: all {k} landmarks are at the same place; place them on distinct features")
    D = np.linalg.norm(P[:, None, :] - P[None, :, :], axis=2)
    D[np.diag_indices(k)] = np.inf
    i, j = np.unravel_index(np.argmin(D), D.shape)
    if D[i, j] <= 1e-9 * scale:
        raise AutobonesError(
            f"{name}: landmarks {i} and {j} are at the same place {P[i].tolist()}; "
            "remove the duplicate or move it to its own feature")
    s = np.linalg.svd(C, compute_uv=False)
    if s[2] <= 1e-4 * s[0]:
        shape = "on one line" if s[1] <= 1e-4 * s[0] else "on one plane"
        raise AutobonesError(
            f"{name}: all {k} landmarks lie {shape}, so the warp is undetermined across it; "
            "add landmarks off that plane (e.g. the nose tip or the back of the head)")
    return P


class ThinPlateSpline:
    """Bookstein thin-plate spline from 3-D source landmarks to target landmarks.

    Parameters
    ----------
    regularization : float, default 0.0
        Smoothing, dimensionless: ``lam = regularization * mean landmark
        distance`` enters the kernel diagonal. 0 interpolates exactly;
        larger values trade exactness at the landmarks for a smoother warp
        (use ~0.01-1 for landmarks placed by hand with noise); very large
        values give the least-squares affine map.

    Attributes
    ----------
    control_points_ : (k, 3) float64
        Source landmarks the kernels are centred on (source units).
    coef_ : (k, 3) float64
        Kernel weights ``w_i`` (target units per source unit).
    affine_ : (4, 3) float64
        Affine part: ``f_affine(x) = affine_[0] + x @ affine_[1:]``.
    bending_energy_ : float
        ``-trace(W^T K W)`` >= 0, proportional to the bending energy of the warp
        (0 for an affine map).

    Examples
    --------
    >>> import numpy as np
    >>> P = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1.]])
    >>> tps = ThinPlateSpline().fit(P, 2 * P + 1)
    >>> np.allclose(tps.transform([[0.5, 0.5, 0.5]]), [[2, 2, 2]])
    True
    """

    def __init__(self, regularization=0.0):
        self.regularization = regularization

    def fit(self, src, dst):
        """Solve for the warp taking ``src[i]`` to ``dst[i]``.

        Parameters
        ----------
        src : (k, 3) float
            Source landmarks, source mesh frame and units.
        dst : (k, 3) float
            Target landmarks, target mesh frame and units.

        Returns
        -------
        self : ThinPlateSpline

        Raises
        ------
        AutobonesError
            Mismatched shapes, fewer than 4 landmarks, duplicates, all on a
            plane or line, or a negative regularization.
        """
        P = check_landmarks(src, "source landmarks")
        Q = as_points(dst, "target landmarks")
        if Q.shape != P.shape:
            raise AutobonesError(
                f"source has {counted(len(P), 'landmark')} but target has {len(Q)}; pass the same landmarks in the same order")
        reg = float(self.regularization)
        if not np.isfinite(reg) or reg < 0:
            raise AutobonesError(f"regularization must be a finite number >= 0, got {self.regularization}")
        k = len(P)
        K = np.linalg.norm(P[:, None, :] - P[None, :, :], axis=2)
        lam = reg * K.sum() / (k * (k - 1))
        L = np.zeros((k + 4, k + 4))
        L[:k, :k] = K - lam * np.eye(k)
        L[:k, k] = 1.0
        L[:k, k + 1:] = P
        L[k, :k] = 1.0
        L[k + 1:, :k] = P.T
        rhs = np.zeros((k + 4, 3))
        rhs[:k] = Q
        sol = np.linalg.solve(L, rhs)
        self.control_points_ = P
        self.system_ = L
        self.coef_ = sol[:k]
        self.affine_ = sol[k:]
        self.bending_energy_ = -float(np.einsum("ij,ik,kj->", self.coef_, K, self.coef_))
        return self

    def transform(self, X):
        """Warp points.

        Parameters
        ----------
        X : (n, 3) float
            Points in the source frame and units.

        Returns
        -------
        Y : (n, 3) float64
            Warped points in the target frame and units. Memory is
            ``O(CHUNK * k)`` whatever ``n``.
        """
        if not hasattr(self, "coef_"):
            raise AutobonesError("ThinPlateSpline.transform called before fit")
        X = as_points(X, "points to warp")
        Y = self.affine_[0] + X @ self.affine_[1:]
        C = self.control_points_
        for s in range(0, len(X), CHUNK):
            # differences, not |x|^2 + |c|^2 - 2 x.c: exact zeros at the landmarks
            r = np.linalg.norm(X[s:s + CHUNK, None, :] - C[None, :, :], axis=2)
            Y[s:s + CHUNK] += r @ self.coef_
        return Y

    def cardinal(self, X):
        """The warp's weights of each landmark's target at ``X`` (n, 3) (source frame): (n, k), so that
        ``cardinal(X) @ dst`` is the warp of ``X`` fitted to ``dst`` (the same spline, any targets).
        ``O(n * k)`` memory: for a sample of points, not a whole dense mesh."""
        if not hasattr(self, "coef_"):
            raise AutobonesError("ThinPlateSpline.cardinal called before fit")
        X = as_points(X, "points")
        C = self.control_points_
        k = len(C)
        inv = np.linalg.solve(self.system_, np.eye(k + 4)[:, :k])                  # (k + 4, k)
        return np.c_[np.linalg.norm(X[:, None, :] - C[None, :, :], axis=2), np.ones(len(X)), X] @ inv

    def jacobian(self, X):
        """(n, 3, 3): the warp's derivative at each point of ``X`` (n, 3) in the row convention of
        :meth:`transform` (``dY = dX @ J``); ``O(n * k)`` memory."""
        if not hasattr(self, "coef_"):
            raise AutobonesError("ThinPlateSpline.jacobian called before fit")
        X = as_points(X, "points")
        d = X[:, None, :] - self.control_points_[None, :, :]
        u = d / np.maximum(np.linalg.norm(d, axis=2, keepdims=True), 1e-300)      # grad of U(r) = r
        return self.affine_[1:][None] + np.einsum("ila,lb->iab", u, self.coef_)

    def fit_transform(self, src, dst, X):
        """``fit(src, dst).transform(X)``."""
        return self.fit(src, dst).transform(X)
