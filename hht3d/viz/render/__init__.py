"""Render per-vertex scalar fields on a mesh or point cloud to images, with no display or GPU.

A :class:`Camera` looks at the model orthographically from a named view
(``front``, ``back``, ``left``, ``right``, ``top``, ``bottom``) or from an
``(azimuth, elevation)`` pair in degrees, about a chosen ``up`` axis.  A
renderer frames the model in the image and turns a field into pixels:

- ``"software"`` (always available): a NumPy z-buffer.  Triangles are
  rasterised with barycentric interpolation of the field (Gouraud on the
  value, then the colour map per pixel) and of the normals (Lambert shading
  from a light beside the eye, two-sided); points are splatted as small
  depth-tested discs.  The geometry is rasterised once per renderer, so
  colouring more fields from the same view costs little.  Edges are
  anti-aliased by supersampling.
- ``"open3d"``: Open3D's Filament ``OffscreenRenderer`` (needs EGL or a
  Vulkan driver; on Debian ``libvulkan1`` + ``mesa-vulkan-drivers`` give a
  CPU one).  Vertex colours are shaded the same way, then drawn unlit, with
  no anti-aliasing.  Meant for machines with a GPU driver: on Mesa's CPU
  Vulkan driver some renders busy-wait for minutes (seen on a 50k-vertex
  model), and one process may hold only one offscreen renderer, so calls
  are serialised.

``"auto"`` is the software renderer: it is always available, deterministic,
anti-aliased, and faster than a CPU Filament once several fields share one
view (the composite figures of :mod:`hht3d.viz.figures`); see
``benchmarks/results/render.md``.  Asking for ``"open3d"`` where it cannot
run raises :class:`~hht3d.errors.InputError` saying why (found in a child
process, since Filament aborts the process that fails to start it).

:func:`render` returns a :class:`Rendering` (RGBA, alpha = model coverage);
:func:`hht3d.viz.panels.field_figure` / :func:`hht3d.viz.panels.render_png` add a
title and a colour bar.

Modules: :mod:`~hht3d.viz.render.view` (the camera), :mod:`~hht3d.viz.render.colors`
(colour scales), :mod:`~hht3d.viz.render.image` (what the renderers share),
:mod:`~hht3d.viz.render.software` (the z-buffer), :mod:`~hht3d.viz.render.offscreen`
(Open3D) and :mod:`~hht3d.viz.render.backends` (choosing one).
"""

from .backends import RENDERERS, available_backends, render, renderer
from .colors import PERCENTILES, SEQUENTIAL_CMAP, SYMMETRIC_CMAP, ColorScale, color_scale
from .image import Rendering
from .offscreen import Open3DRenderer
from .software import SoftwareRenderer
from .view import UP_AXES, VIEWS, Camera, camera, model_aspect

__all__ = [
    "RENDERERS",
    "UP_AXES",
    "VIEWS",
    "Camera",
    "ColorScale",
    "Rendering",
    "SoftwareRenderer",
    "Open3DRenderer",
    "available_backends",
    "camera",
    "color_scale",
    "model_aspect",
    "render",
    "renderer",
]
