"""Orthographic cameras: world -> pixel maps for the CPU renderer.

Conventions
-----------
World frame
    Whatever frame the vertices are in; :func:`autobones.render.views.render_views` assumes
    the canonical head frame (+Y up, +Z out of the face, +X toward the subject's own left ear).
Camera frame
    OpenGL convention: the camera looks along its -Z axis, +Y is up in the
    image, +X is right in the image. :func:`look_at` builds the world -> camera
    matrix.
Projection
    Orthographic. A camera-space point (xc, yc, zc) lands on pixel coordinates
    ``x = (W - 1)/2 + scale * (xc - center[0])`` (columns, rightward) and
    ``y = (H - 1)/2 - scale * (yc - center[1])`` (rows, downward), so pixel
    ``[row, col]`` of an image array has its centre at ``(x, y) = (col, row)``;
    the same convention as Pillow's drawing coordinates. Depth is ``-zc``: the
    distance in world units in front of the camera plane, growing away from the
    camera. There is no near or far plane.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import AutobonesError


def unit_vector(v, what):
    """``v`` as a unit (3,) float64 vector; ``what`` names it in the error when ``v`` is not 3 finite
    numbers or is the zero vector."""
    v = np.asarray(v, dtype=np.float64).reshape(-1)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise AutobonesError(f"{what} must be 3 finite numbers, got {v!r}")
    n = np.linalg.norm(v)
    if n < 1e-12:
        raise AutobonesError(f"{what} must not be the zero vector")
    return v / n


def look_at(eye, target, up):
    """World -> camera matrix of a camera at ``eye`` looking at ``target``.

    Parameters
    ----------
    eye, target : (3,) float
        Camera position and the point it looks at, world coordinates and units.
    up : (3,) float
        World direction that should appear upward in the image; must not be
        parallel to ``target - eye``.

    Returns
    -------
    (4, 4) float64
        Homogeneous rigid transform world -> camera; OpenGL convention: the
        camera looks along its -Z axis, +Y up, +X right.

    Examples
    --------
    >>> M = look_at((0, 0, 5), (0, 0, 0), (0, 1, 0))
    >>> (M @ [0, 0, 0, 1])[:3]
    array([ 0.,  0., -5.])
    """
    eye = np.asarray(eye, dtype=np.float64).reshape(3)
    target = np.asarray(target, dtype=np.float64).reshape(3)
    z = unit_vector(eye - target, "look_at: eye - target")
    up = unit_vector(up, "look_at: up")
    x = np.cross(up, z)
    nx = np.linalg.norm(x)
    if nx < 1e-9:
        raise AutobonesError(
            "look_at: 'up' is parallel to the viewing direction; pass an up vector "
            "perpendicular to it (e.g. (0, 0, -1) for a view from above)")
    x /= nx
    y = np.cross(z, x)
    M = np.eye(4)
    M[0, :3], M[1, :3], M[2, :3] = x, y, z
    M[:3, 3] = -M[:3, :3] @ eye
    return M


@dataclass
class Camera:
    """An orthographic camera.

    Attributes
    ----------
    view : (4, 4) float64
        World -> camera rigid transform (camera looks along its -Z).
    scale : float
        Pixels per world unit.
    center : (2,) float64
        Camera-space (x, y) shown at the image centre, world units.
    width, height : int
        Image size in pixels.
    """

    view: np.ndarray
    scale: float
    center: np.ndarray
    width: int
    height: int

    @property
    def direction(self):
        """(3,) float64 unit world direction the camera looks along."""
        return -self.view[2, :3].copy()

    def project(self, P):
        """Project world points to pixel coordinates.

        Parameters
        ----------
        P : (k, 3) float
            World points.

        Returns
        -------
        px : (k, 2) float64
            Pixel coordinates (x = column, y = row; pixel centres at integers).
        depth : (k,) float64
            Distance in front of the camera plane, world units.
        """
        P = np.asarray(P, dtype=np.float64).reshape(-1, 3)
        C = P @ self.view[:3, :3].T + self.view[:3, 3]
        px = np.empty((len(P), 2))
        px[:, 0] = (self.width - 1) / 2.0 + self.scale * (C[:, 0] - self.center[0])
        px[:, 1] = (self.height - 1) / 2.0 - self.scale * (C[:, 1] - self.center[1])
        return px, -C[:, 2]

    def ray(self, px):
        """World rays through pixel coordinates.

        Parameters
        ----------
        px : (k, 2) float
            Pixel coordinates (x = column, y = row).

        Returns
        -------
        origins : (k, 3) float64
            World points on the camera plane (depth 0).
        directions : (k, 3) float64
            Unit world directions (all equal to :attr:`direction`); the point
            at depth ``d`` is ``origins + d * directions``.
        """
        px = np.asarray(px, dtype=np.float64).reshape(-1, 2)
        C = np.zeros((len(px), 3))
        C[:, 0] = (px[:, 0] - (self.width - 1) / 2.0) / self.scale + self.center[0]
        C[:, 1] = -(px[:, 1] - (self.height - 1) / 2.0) / self.scale + self.center[1]
        R, t = self.view[:3, :3], self.view[:3, 3]
        origins = (C - t) @ R
        directions = np.broadcast_to(self.direction, origins.shape).copy()
        return origins, directions


def image_size(size):
    """``(width, height)`` as two positive ints, from any pair of numbers."""
    try:
        W, H = (int(s) for s in size)
    except (TypeError, ValueError):
        raise AutobonesError(f"image size must be (width, height), got {size!r}") from None
    if W < 1 or H < 1:
        raise AutobonesError(f"image size must be positive, got {size!r}")
    return W, H


def orthographic_camera(V, view_dir, up=(0.0, 1.0, 0.0), size=(512, 512), margin=0.05):
    """An orthographic camera that frames the points ``V``.

    Parameters
    ----------
    V : (n, 3) float
        Points to frame, world coordinates (e.g. a mesh's vertices).
    view_dir : (3,) float
        Direction from the points toward the camera: the camera sits on the
        ``+view_dir`` side and looks along ``-view_dir``. In the canonical head
        frame ``(0, 0, 1)`` is a front view of the face.
    up : (3,) float
        World direction shown upward in the image; not parallel to ``view_dir``.
    size : (int, int)
        Image (width, height) in pixels.
    margin : float
        Empty border on each side, as a fraction of the image size.

    Returns
    -------
    Camera
        The bounding box of ``V``'s projection is centred and fills the image
        minus the margins in its limiting direction. Every point of ``V`` has a
        positive depth.
    """
    W, H = image_size(size)
    V = np.asarray(V, dtype=np.float64).reshape(-1, 3)
    V = V[np.all(np.isfinite(V), axis=1)]
    d = unit_vector(view_dir, "view_dir")
    if len(V) == 0:
        mid, radius = np.zeros(3), 1.0
    else:
        mid = (V.min(axis=0) + V.max(axis=0)) / 2.0
        radius = float(np.linalg.norm(V - mid, axis=1).max())
    radius = radius if radius > 0 else 1.0
    view = look_at(mid + 2.0 * radius * d, mid, up)
    C = (V @ view[:3, :3].T + view[:3, 3])[:, :2] if len(V) else np.zeros((1, 2))
    lo, hi = C.min(axis=0), C.max(axis=0)
    span = hi - lo
    usable = np.array([W, H], dtype=np.float64) * (1.0 - 2.0 * float(margin))
    usable = np.maximum(usable, 1.0)
    with np.errstate(divide="ignore"):
        s = np.where(span > 1e-12 * radius, usable / np.where(span > 0, span, 1.0), np.inf)
    scale = float(s.min())
    if not np.isfinite(scale):  # a single point
        scale = float(min(usable) / (2.0 * radius))
    return Camera(view=view, scale=scale, center=(lo + hi) / 2.0, width=W, height=H)
