"""Choosing a renderer, and rendering a field in one call."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ...errors import InputError
from ...geometry.surface import Surface
from .colors import PERCENTILES, color_scale
from .image import Rendering, check_field
from .offscreen import Open3DRenderer, open3d_problem
from .software import SoftwareRenderer
from .view import camera

__all__ = ["RENDERERS", "available_backends", "renderer", "render"]

#: Renderers; ``"auto"`` is ``"software"``, the one that is always available.
RENDERERS = ("auto", "software", "open3d")


def available_backends() -> list[str]:
    """Renderers that work on this machine: ``"software"`` always; ``"open3d"`` if a child
    process can create an Open3D offscreen renderer (a few seconds, once per process)."""
    return ["software"] + (["open3d"] if not open3d_problem() else [])


def renderer(
    surface: Surface,
    *,
    view: str | Sequence[float] = "front",
    up: str | Sequence[float] = "y",
    size: tuple[int, int] = (800, 800),
    backend: str = "auto",
    supersample: int = 2,
    point_size: float | None = None,
) -> SoftwareRenderer | Open3DRenderer:
    """A renderer of ``surface`` from one view; call ``.render(values, scale)`` per field.

    Parameters
    ----------
    surface : Surface
        A mesh or point cloud.
    view, up
        See :func:`hht3d.viz.render.camera`.
    size : (int, int)
        Image width and height in pixels.
    backend : {"auto", "software", "open3d"}
        ``"auto"``: the software renderer (see the module docstring).
    supersample : int
        Software renderer: samples per pixel side (anti-aliasing), 1–4.
    point_size : float, optional
        Point clouds: splat diameter in pixels (default from the point spacing).

    Raises
    ------
    InputError
        Unknown backend, or a requested backend that is unavailable here.
    """
    if backend not in RENDERERS:
        raise InputError(f"unknown render backend {backend!r}; choose one of {RENDERERS}")
    if not isinstance(surface, Surface):
        raise InputError(f"expected a Surface to render, got {type(surface).__name__}")
    cam = camera(view, up)
    if backend == "open3d":
        return Open3DRenderer(surface, cam, size, point_size=point_size)
    return SoftwareRenderer(surface, cam, size, supersample=supersample, point_size=point_size)


def render(
    surface: Surface,
    values: np.ndarray | None = None,
    *,
    view: str | Sequence[float] = "front",
    up: str | Sequence[float] = "y",
    size: tuple[int, int] = (800, 800),
    cmap: str | None = None,
    limits: tuple[float, float] | None = None,
    symmetric: bool | None = None,
    percentiles: tuple[float, float] = PERCENTILES,
    backend: str = "auto",
    supersample: int = 2,
    point_size: float | None = None,
) -> Rendering:
    """Render a per-vertex field (or, with ``values=None``, the shaded model) to an RGBA image.

    Parameters
    ----------
    surface : Surface
    values : (n,) array_like, optional
        The field; NaN shows grey.
    view, up, size, backend, supersample, point_size
        See :func:`renderer`.
    cmap, limits, symmetric, percentiles
        See :func:`hht3d.viz.render.color_scale`.

    Returns
    -------
    Rendering
    """
    field = None if values is None else check_field(surface, values)
    scale = (
        None
        if field is None
        else color_scale(field, cmap=cmap, limits=limits, symmetric=symmetric, percentiles=percentiles)
    )
    drawer = renderer(
        surface, view=view, up=up, size=size, backend=backend, supersample=supersample, point_size=point_size
    )
    return drawer.render(field, scale)
