"""2-D overlays and picture files: markers, labels and line segments drawn with Pillow; PNG bytes
and files.

Images are (H, W, 3) uint8 RGB arrays; pixel coordinates are x = column, y = row with pixel
centres at integers (:mod:`autobones.render.camera`), Pillow's drawing convention.
"""
from __future__ import annotations

import numpy as np

from ..errors import AutobonesError, counted


def _rgb_image(image):
    image = np.asarray(image)
    if image.ndim != 3 or image.shape[2] != 3 or image.dtype != np.uint8:
        raise AutobonesError(
            f"image must be an (H, W, 3) uint8 array, got {image.dtype} {image.shape}")
    return image


def _colors(color, k):
    c = np.asarray(color)
    if c.ndim == 1:
        c = np.broadcast_to(c, (k, c.shape[0]))
    if c.shape != (k, 3) and c.shape != (k, 4):
        raise AutobonesError(f"color must be one RGB triple or one per item ({k}), got {c.shape}")
    if np.issubdtype(c.dtype, np.floating) and c.size and c.max() <= 1.0:
        c = c * 255.0
    return [tuple(int(round(v)) for v in row[:3]) for row in c]


def draw_points(image, px, labels=None, color=(255, 0, 0), radius=3, filled=True):
    """Draw round markers, optionally labelled, on an image.

    Parameters
    ----------
    image : (H, W, 3) uint8
        Not modified.
    px : (k, 2) float
        Pixel coordinates (x = column, y = row); non-finite rows are skipped.
    labels : sequence of k str or None
        Text drawn to the upper right of each marker.
    color : (3,) or (k, 3)
        RGB, uint8 range (floats all <= 1 are taken as [0, 1]).
    radius : float
        Marker radius in pixels.
    filled : bool or (k,) bool
        False draws a ring (e.g. for points hidden behind the surface).

    Returns
    -------
    (H, W, 3) uint8
        A new image with the markers.
    """
    from PIL import Image, ImageDraw, ImageFont

    image = _rgb_image(image)
    px = np.asarray(px, dtype=np.float64).reshape(-1, 2)
    k = len(px)
    cols = _colors(color, k)
    fill = np.broadcast_to(np.asarray(filled, dtype=bool), (k,))
    if labels is not None and len(labels) != k:
        raise AutobonesError(f"{counted(len(labels), 'label')} for {counted(k, 'point')}")
    pil = Image.fromarray(image)
    draw = ImageDraw.Draw(pil)
    font = ImageFont.load_default() if labels is not None else None
    r = float(radius)
    for i in range(k):
        x, y = px[i]
        if not (np.isfinite(x) and np.isfinite(y)):
            continue
        box = [x - r, y - r, x + r, y + r]
        if fill[i]:
            draw.ellipse(box, fill=cols[i], outline=(0, 0, 0))
        else:
            draw.ellipse(box, outline=cols[i], width=max(1, int(round(r / 3))))
        if labels is not None and labels[i] is not None and str(labels[i]):
            draw.text((x + r + 2, y - r - 10), str(labels[i]), fill=cols[i], font=font)
    return np.asarray(pil).copy()


def draw_segments(image, p0, p1, color=(0, 90, 255), width=2):
    """Draw line segments on an image.

    Parameters
    ----------
    image : (H, W, 3) uint8
        Not modified.
    p0, p1 : (k, 2) float
        Segment end points in pixel coordinates (x = column, y = row);
        segments with a non-finite end are skipped.
    color : (3,) or (k, 3)
        RGB, uint8 range (floats all <= 1 are taken as [0, 1]).
    width : int
        Line width in pixels.

    Returns
    -------
    (H, W, 3) uint8
        A new image with the segments.
    """
    from PIL import Image, ImageDraw

    image = _rgb_image(image)
    p0 = np.asarray(p0, dtype=np.float64).reshape(-1, 2)
    p1 = np.asarray(p1, dtype=np.float64).reshape(-1, 2)
    if p0.shape != p1.shape:
        raise AutobonesError(f"p0 and p1 must have the same shape, got {p0.shape} and {p1.shape}")
    cols = _colors(color, len(p0))
    pil = Image.fromarray(image)
    draw = ImageDraw.Draw(pil)
    for i in range(len(p0)):
        if not (np.all(np.isfinite(p0[i])) and np.all(np.isfinite(p1[i]))):
            continue
        draw.line([tuple(p0[i]), tuple(p1[i])], fill=cols[i], width=int(width))
    return np.asarray(pil).copy()


def encode_png(image):
    """PNG file bytes of an (H, W, 3) or (H, W, 4) uint8 RGB(A) or (H, W) uint8 grey image."""
    import io

    from PIL import Image

    image = np.asarray(image)
    ok = image.dtype == np.uint8 and (image.ndim == 2 or (image.ndim == 3 and image.shape[2] in (3, 4)))
    if not ok:
        raise AutobonesError(
            f"PNG image must be uint8 (H, W), (H, W, 3) or (H, W, 4), got {image.dtype} {image.shape}")
    buf = io.BytesIO()
    Image.fromarray(image).save(buf, format="PNG")
    return buf.getvalue()


def save_png(path, image):
    """Write :func:`encode_png` of ``image`` to ``path``, atomically."""
    from ..io.atomic import write_bytes_atomic

    return write_bytes_atomic(path, encode_png(image), "the picture")
