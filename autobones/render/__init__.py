"""A small CPU renderer: cameras, a z-buffer rasteriser, shading and PNG drawing.

Used to picture a head for the landmark detector, for previews and for the gallery.
Modules: :mod:`~autobones.render.camera` (orthographic cameras and the pixel conventions),
:mod:`~autobones.render.raster` (depth buffer, surface points, Lambert shading),
:mod:`~autobones.render.draw` (markers, segments, PNG files) and
:mod:`~autobones.render.views` (side-by-side pictures of a head).
"""
from .camera import Camera, look_at, orthographic_camera
from .draw import draw_points, draw_segments, encode_png, save_png
from .raster import RenderBuffers, rasterize, shade, surface_points
from .views import VIEWS, muscle_segments, render_views

__all__ = ["Camera", "RenderBuffers", "VIEWS", "draw_points", "draw_segments", "encode_png", "look_at",
           "muscle_segments", "orthographic_camera", "rasterize", "render_views", "save_png", "shade",
           "surface_points"]
