"""A landmark warp that bends near the landmarks and stays affine far from them.

Goes beyond the seeds (issue #34 item 1). Bookstein's spline (:class:`~autobones.geometry.tps.ThinPlateSpline`)
has the 3-D kernel U(r) = r, which grows with distance: a few landmarks moved together (a smile's mouth corners,
18 % of ex-ex) bend the whole head, and the fit that starts from the warp keeps part of that bend as a
tangential slide (the spline alone put ICT identities' ears 5.3-7.0 % of ex-ex off on a smile they wear,
against 0.8-2.4 % neutral). This warp is the spline within ``core`` of the nearest landmark, fading as a
Gaussian of width ``width`` into the landmarks' least-squares affine map (both in units of the landmarks'
RMS distance from their centroid)::

    f(x) = A(x) + g(d(x)) (s(x) - A(x)),   g(d) = exp(-max(d - core, 0)^2 / (2 width^2))

with ``s`` the spline, ``A`` the affine map, ``d`` the distance to the nearest source landmark. It is exact at
the landmarks (g = 1 there) and equivariant under a similarity of either side.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..errors import AutobonesError
from .tps import CHUNK, ThinPlateSpline, as_points

# In units of the landmarks' RMS radius: the spline whole within CORE of a landmark, a Gaussian of width WIDTH
# beyond. At 0.25 an open jaw's cheeks slid 2.7 % of ex-ex against the spline's 1.2 % (its hinge leaves
# a broad residual only the spline's reach carries); at 0.5 1.9 %, and the smile, pucker and funnel keep
# most of the gain (benchmarks/README.md, "a warp local to the landmarks").
CORE = 0.5
WIDTH = 0.5


def landmark_radius(P):
    """The landmarks' RMS distance from their centroid (float, their units) for ``P`` (k, 3): the scale the
    fit's reach near the landmarks is measured in."""
    return float(np.sqrt(((P - P.mean(axis=0)) ** 2).sum(axis=1).mean()))


def nearest_landmark(P, X):
    """How far each point of ``X`` (n, 3) lies from the nearest landmark of ``P`` (k, 3), both in one frame
    and unit: ``d`` (n,), and :func:`landmark_radius` of ``P`` ``r`` (float)."""
    return cKDTree(P).query(X)[0], landmark_radius(P)


class LocalLandmarkWarp:
    """The landmarks' spline near them, their least-squares affine map far from them (module doc).

    Parameters
    ----------
    core, width : float
        Distances from the nearest landmark, in units of the source landmarks' RMS radius: the spline
        holds whole within ``core`` and fades over ``width`` beyond it.

    Attributes
    ----------
    spline_ : ThinPlateSpline
        The exact spline of the landmarks.
    affine_ : (4, 3) float64
        The spline's own affine part (``affine_[0] + x @ affine_[1:]``), as :class:`ThinPlateSpline`
        exposes it: the landmarks' overall scale and turn.
    far_ : (4, 3) float64
        The landmarks' least-squares affine map, the warp far from them.
    radius_ : float
        The source landmarks' RMS distance from their centroid (source units).
    """

    def __init__(self, core=CORE, width=WIDTH):
        self.core = core
        self.width = width

    def fit(self, src, dst):
        """Fit to landmarks ``src`` (k, 3) -> ``dst`` (k, 3), each in its mesh's frame and units.

        Returns self; raises AutobonesError on landmarks the spline refuses or a non-positive width."""
        if not (np.isfinite(self.core) and self.core >= 0 and np.isfinite(self.width) and self.width > 0):
            raise AutobonesError(f"core must be >= 0 and width > 0, got {self.core}, {self.width}")
        self.spline_ = ThinPlateSpline().fit(src, dst)
        P = self.spline_.control_points_
        Q = as_points(dst, "target landmarks")
        H = np.c_[np.ones(len(P)), P]
        self.far_ = np.linalg.lstsq(H, Q, rcond=None)[0]
        self.affine_ = self.spline_.affine_
        self.radius_ = landmark_radius(P)
        return self

    def blend(self, X):
        """The spline's share at each point of ``X`` (n, 3), source frame: (n,) in [0, 1], 1 within ``core``
        of a landmark (0 where the Gaussian underflows, far away)."""
        if not hasattr(self, "spline_"):
            raise AutobonesError("LocalLandmarkWarp used before fit")
        d, _ = nearest_landmark(self.spline_.control_points_, as_points(X, "points"))
        over = np.maximum(d / max(self.radius_, 1e-300) - self.core, 0.0) / self.width
        return np.exp(-0.5 * over ** 2)

    def transform(self, X):
        """Warp points ``X`` (n, 3), source frame and units -> (n, 3) target frame and units;
        memory ``O(CHUNK * k)`` as the spline's."""
        if not hasattr(self, "spline_"):
            raise AutobonesError("LocalLandmarkWarp used before fit")
        X = as_points(X, "points to warp")
        Y = np.empty_like(X)
        for s in range(0, len(X), CHUNK):
            x = X[s:s + CHUNK]
            far = self.far_[0] + x @ self.far_[1:]
            Y[s:s + CHUNK] = far + self.blend(x)[:, None] * (self.spline_.transform(x) - far)
        return Y
