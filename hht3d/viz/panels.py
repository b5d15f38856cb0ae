"""Panels of a figure: one field on the model with a title and a colour bar, and the helpers
that place renderings and colour bars in any Matplotlib figure.

Figures are Matplotlib ``Figure`` objects drawn with the Agg canvas (no
``pyplot``, no global state, no display); the surface images come from
:mod:`hht3d.viz.render`.  Sizes are in pixels; files are written atomically.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import InputError
from ..geometry.surface import Surface
from ..io.atomic import atomic_path
from .render import PERCENTILES, ColorScale, Rendering, color_scale, model_aspect, renderer
from .render.image import check_field, check_size

if TYPE_CHECKING:
    from hht3d.transform import HHTResult


__all__ = [
    "font_points",
    "draw_colorbar",
    "draw_image",
    "field_figure",
    "save_figure",
    "render_png",
    "fractions",
    "check_dpi",
    "check_result",
]


# -- one field with a title and a colour bar -----------------------------------------------------
def font_points(width_pixels: float, dpi: float) -> float:
    """A readable font size (points) for a panel ``width_pixels`` wide: 1/20 of it, 7–16 pt."""
    return float(np.clip(width_pixels / 20 * 72 / dpi, 7.0, 16.0))


def draw_colorbar(
    fig: Any,
    box: Sequence[float],
    scale: ColorScale,
    *,
    label: str | None = None,
    orientation: str = "vertical",
    font: float = 10.0,
) -> None:
    """A colour bar in ``box`` (figure fractions ``[left, bottom, width, height]``) with three
    ticks: the limits and the middle (0 for a symmetric scale)."""
    axes = fig.add_axes(box)
    bar = fig.colorbar(scale.mappable(), cax=axes, orientation=orientation)
    ticks = [scale.vmin, (scale.vmin + scale.vmax) / 2, scale.vmax]
    bar.set_ticks(ticks, labels=[_tick_label(t, scale) for t in ticks])
    bar.ax.tick_params(labelsize=font * 0.85, length=2, pad=1.5)
    bar.outline.set_linewidth(0.5)
    if label:
        bar.set_label(label, fontsize=font * 0.85, labelpad=2)


def _tick_label(value: float, scale: ColorScale) -> str:
    """Three significant digits, without an exponent between 0.01 and 10⁵."""
    size = abs(value)
    if size < 1e-9 * max(abs(scale.vmin), abs(scale.vmax)):
        return "0"
    if 1e-2 <= size < 1e5:
        return f"{value:.{max(0, 2 - int(np.floor(np.log10(size))))}f}"
    return f"{value:.2e}"


def draw_image(
    fig: Any, box: Sequence[float], rendering: Rendering, *, title: str | None = None, font: float = 10.0
) -> None:
    """Show a rendering in ``box`` (figure fractions) on white, with an optional title."""
    axes = fig.add_axes(box)
    axes.imshow(rendering.rgb(), interpolation="none")
    axes.set_axis_off()
    if title:
        axes.set_title(title, fontsize=font, pad=2)


def field_figure(
    surface: Surface,
    values: np.ndarray | None = None,
    *,
    title: str | None = None,
    label: str | None = None,
    size: tuple[float, float] = (800, 800),
    dpi: float = 100,
    view: str | Sequence[float] = "front",
    up: str | Sequence[float] = "y",
    cmap: str | None = None,
    limits: tuple[float, float] | None = None,
    symmetric: bool | None = None,
    percentiles: tuple[float, float] = PERCENTILES,
    backend: str = "auto",
    supersample: int = 2,
    point_size: float | None = None,
) -> Any:
    """A Matplotlib ``Figure`` of one field on the model with a title and a colour bar.

    Parameters
    ----------
    surface, values
        See :func:`hht3d.viz.render.render`; ``values=None`` shows the shaded model without a colour bar.
    title : str, optional
        Default: the surface name.
    label : str, optional
        Colour bar label (e.g. the quantity and its unit).
    size : (int, int)
        Figure width and height in pixels.
    dpi : float
        Dots per inch (sets the font scale; the pixel size stays ``size``).
    view, up, cmap, limits, symmetric, percentiles, backend, supersample, point_size
        See :func:`hht3d.viz.render.render`.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    from matplotlib.figure import Figure

    width, height = check_size(size)
    check_dpi(dpi)
    font = font_points(min(width, height), dpi)
    em = font * dpi / 72
    top, pad = 2.4 * em, 0.6 * em
    side = 6.5 * em if values is not None else 0.0
    image_height = max(int(height - top - pad), 1)
    image_width = max(int(min(width - side - 2 * pad, image_height / model_aspect(surface, view, up))), 1)
    left = (width - image_width - side) / 2
    field = None if values is None else check_field(surface, values)
    scale = (
        None
        if field is None
        else color_scale(field, cmap=cmap, limits=limits, symmetric=symmetric, percentiles=percentiles)
    )
    drawer = renderer(
        surface,
        view=view,
        up=up,
        size=(image_width, image_height),
        backend=backend,
        supersample=supersample,
        point_size=point_size,
    )
    fig = Figure(figsize=(width / dpi, height / dpi), dpi=dpi)
    box = (round(left), round(pad), image_width, image_height)
    draw_image(fig, fractions(box, width, height), drawer.render(field, scale))
    fig.text(
        0.5,
        1 - 0.5 * top / height,
        surface.name if title is None else title,
        ha="center",
        va="center",
        fontsize=font * 1.15,
    )
    if scale is not None:
        bar = (left + image_width + 0.8 * em, height * 0.15, 0.9 * em, height * 0.7 - top)
        draw_colorbar(fig, fractions(bar, width, height), scale, label=label, font=font)
    return fig


def fractions(box: Sequence[float], width: float, height: float) -> list[float]:
    """Pixel box ``(left, bottom, width, height)`` → figure fractions."""
    left, bottom, w, h = box
    return [left / width, bottom / height, w / width, h / height]


def check_dpi(dpi: float) -> None:
    if not (isinstance(dpi, (int, float)) and 10 <= dpi <= 1200):
        raise InputError(f"dpi must be a number in [10, 1200], got {dpi!r}")


def save_figure(fig: Any, path: Path | str) -> Path:
    """Write a Matplotlib figure to a PNG atomically at its own size and dpi; returns the path.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : Path or str
        The PNG to write.

    Returns
    -------
    Path
        The path written.

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> import matplotlib.figure
    >>> from hht3d.viz import save_figure
    >>> fig = matplotlib.figure.Figure(figsize=(2, 1), dpi=50)
    >>> save_figure(fig, Path(tempfile.mkdtemp()) / "empty.png").read_bytes()[1:4]
    b'PNG'
    """
    path = png_path(path)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=fig.dpi, facecolor="white")
    return path


def render_png(path: Path | str, surface: Surface, values: np.ndarray | None = None, **options: Any) -> Path:
    """Render a field with a title and a colour bar to a PNG (atomically); returns the path.

    ``options`` are those of :func:`field_figure` (``title``, ``label``,
    ``size`` in pixels, ``dpi``, ``view``, ``up``, ``cmap``, ``limits``, ...).

    Parameters
    ----------
    path : Path or str
        The PNG to write.
    surface : Surface
        The surface.
    values : ndarray, optional
        The field (default ``None``: the shaded model without a colour bar).
    **options
        Keyword arguments of :func:`field_figure`.

    Returns
    -------
    Path
        The path written.
    """
    path = png_path(path)
    return save_figure(field_figure(surface, values, **options), path)


def png_path(path: Path | str) -> Path:
    path = Path(path)
    if path.suffix.lower() != ".png":
        raise InputError(f"{path}: figures are written as PNG; use a .png file name")
    return path


def check_result(result: HHTResult) -> None:
    if not all(hasattr(result, name) for name in ("surface", "imfs", "monogenic", "spectrum")):
        raise InputError(f"expected an HHTResult (from hht3d.transform.hht), got {type(result).__name__}")
