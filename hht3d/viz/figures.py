"""Figures: one field with a title and a colour bar, an HHT result in the paper's Fig. 4 layout,
and plots of the Hilbert spectrum.

- :func:`field_figure` / :func:`render_png`: one field on the model (or
  the shaded model) with a title and a colour bar; :func:`draw_image` and
  :func:`draw_colorbar` place a rendering and a colour bar in any figure.
- :func:`hht_figure`: the model (shaded), the signal, every IMF and the
  residue in one row; the instantaneous frequency (Eq. 23) and the local
  amplitude (Eq. 21) of each IMF in the two rows below, each panel with its
  own title and colour bar.  IMFs use a diverging colour map symmetric about
  0; every limit is a robust percentile range.
- :func:`spectrum_figure`: the area-weighted marginal spectrum
  ``h(ω) = Σ_v A_v H(ω, v)`` and the frequency–energy distribution of each
  IMF, as shares of the total energy per frequency bin (log or linear bins),
  with the surface's resolution limit ``π/√A`` marked
  (:mod:`hht3d.spectral.frequency`).
- :func:`write_figures`: the standard set of PNGs of a result in a folder.

Figures are Matplotlib ``Figure`` objects drawn with the Agg canvas (no
``pyplot``, no global state, no display); the surface images come from
:mod:`hht3d.viz.render`.  Sizes are in pixels; files are written atomically.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import InputError
from ..transform import HHTResult
from ..io.atomic import atomic_path
from .render import ColorScale, Rendering, color_scale, model_aspect, renderer
from .render.image import check_field, check_size
from ..spectral.spectrum import SCALES, HilbertSpectrum
from ..geometry.surface import Surface

__all__ = ["FREQUENCY_CMAP", "AMPLITUDE_CMAP", "IMF_CMAP", "field_figure", "render_png", "draw_image",
           "draw_colorbar", "font_points", "hht_figure", "spectrum_figure", "write_figures", "save_figure"]

#: Colour maps of the composite figure.
IMF_CMAP = "RdBu_r"
FREQUENCY_CMAP = "viridis"
AMPLITUDE_CMAP = "plasma"


# -- one field with a title and a colour bar -----------------------------------------------------
def font_points(width_pixels: float, dpi: float) -> float:
    """A readable font size (points) for a panel ``width_pixels`` wide: 1/20 of it, 7–16 pt."""
    return float(np.clip(width_pixels / 20 * 72 / dpi, 7.0, 16.0))


def draw_colorbar(fig, box, scale: ColorScale, *, label: str | None = None, orientation: str = "vertical",
                  font: float = 10.0) -> None:
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


def draw_image(fig, box, rendering: Rendering, *, title: str | None = None, font: float = 10.0) -> None:
    """Show a rendering in ``box`` (figure fractions) on white, with an optional title."""
    axes = fig.add_axes(box)
    axes.imshow(rendering.rgb(), interpolation="none")
    axes.set_axis_off()
    if title:
        axes.set_title(title, fontsize=font, pad=2)


def field_figure(surface: Surface, values=None, *, title: str | None = None, label: str | None = None,
                 size=(800, 800), dpi: float = 100, view="front", up="y", cmap: str | None = None,
                 limits=None, symmetric: bool | None = None, percentiles=(1.0, 99.0),
                 backend: str = "auto", supersample: int = 2, point_size: float | None = None):
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
    """
    from matplotlib.figure import Figure

    width, height = check_size(size)
    _check_dpi(dpi)
    font = font_points(min(width, height), dpi)
    em = font * dpi / 72
    top, pad = 2.4 * em, 0.6 * em
    side = 6.5 * em if values is not None else 0.0
    image_height = max(int(height - top - pad), 1)
    image_width = max(int(min(width - side - 2 * pad, image_height / model_aspect(surface, view, up))), 1)
    left = (width - image_width - side) / 2
    field = None if values is None else check_field(surface, values)
    scale = None if field is None else color_scale(field, cmap=cmap, limits=limits, symmetric=symmetric,
                                                   percentiles=percentiles)
    drawer = renderer(surface, view=view, up=up, size=(image_width, image_height), backend=backend,
                      supersample=supersample, point_size=point_size)
    fig = Figure(figsize=(width / dpi, height / dpi), dpi=dpi)
    box = (round(left), round(pad), image_width, image_height)
    draw_image(fig, _fractions(box, width, height), drawer.render(field, scale))
    fig.text(0.5, 1 - 0.5 * top / height, surface.name if title is None else title, ha="center",
             va="center", fontsize=font * 1.15)
    if scale is not None:
        bar = (left + image_width + 0.8 * em, height * 0.15, 0.9 * em, height * 0.7 - top)
        draw_colorbar(fig, _fractions(bar, width, height), scale, label=label, font=font)
    return fig


def _fractions(box, width: float, height: float) -> list[float]:
    """Pixel box ``(left, bottom, width, height)`` → figure fractions."""
    left, bottom, w, h = box
    return [left / width, bottom / height, w / width, h / height]


def _check_dpi(dpi) -> None:
    if not (isinstance(dpi, (int, float)) and 10 <= dpi <= 1200):
        raise InputError(f"dpi must be a number in [10, 1200], got {dpi!r}")


def save_figure(fig, path) -> Path:
    """Write a Matplotlib figure to a PNG atomically at its own size and dpi; returns the path."""
    path = _png_path(path)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=fig.dpi, facecolor="white")
    return path


def render_png(path, surface: Surface, values=None, **options):
    """Render a field with a title and a colour bar to a PNG (atomically); returns the path.

    ``options`` are those of :func:`field_figure` (``title``, ``label``,
    ``size`` in pixels, ``dpi``, ``view``, ``up``, ``cmap``, ``limits``, ...).
    """
    path = _png_path(path)
    return save_figure(field_figure(surface, values, **options), path)


def _png_path(path) -> Path:
    path = Path(path)
    if path.suffix.lower() != ".png":
        raise InputError(f"{path}: figures are written as PNG; use a .png file name")
    return path


# -- the composite figure (paper Fig. 4) --------------------------------------------------------
class _Grid:
    """Pixel layout of the composite: a title band, then three rows of panels, each a title,
    an image and a horizontal colour bar below it."""

    def __init__(self, columns: int, image_aspect: float, size, dpi: float, panel_width: int):
        width, height = (columns * panel_width, None) if size is None else check_size(size)
        self.column_width = width / columns
        self.font = font_points(self.column_width, dpi)
        em = self.font * dpi / 72
        self.em = em
        self.gap = 0.5 * em
        self.heading, self.title, self.bar_band = 2.6 * em, 1.7 * em, 2.9 * em
        self.image_width = int(self.column_width - 2 * self.gap)
        fixed = self.heading + 3 * (self.title + self.bar_band) + self.gap
        if height is None:
            self.image_height = int(round(self.image_width * image_aspect))
            height = int(round(fixed + 3 * self.image_height))
        else:
            self.image_height = int((height - fixed) / 3)
        if self.image_width < 16 or self.image_height < 16:
            raise InputError(f"figure size {size!r} leaves panels of {self.image_width}×{self.image_height} "
                             f"pixels for {columns} columns; make it larger")
        self.width, self.height = int(width), int(height)

    @property
    def image_size(self) -> tuple[int, int]:
        return self.image_width, self.image_height

    def _row_top(self, row: int) -> float:
        return self.height - self.heading - row * (self.title + self.image_height + self.bar_band)

    def image_box(self, row: int, column: int) -> list[float]:
        left = column * self.column_width + (self.column_width - self.image_width) / 2
        bottom = self._row_top(row) - self.title - self.image_height
        return _fractions((round(left), round(bottom), self.image_width, self.image_height),
                          self.width, self.height)

    def bar_box(self, row: int, column: int) -> list[float]:
        width = 0.8 * self.image_width
        left = column * self.column_width + (self.column_width - width) / 2
        bottom = self._row_top(row) - self.title - self.image_height - 0.75 * self.em
        return _fractions((left, bottom, width, 0.5 * self.em), self.width, self.height)

    def row_label_position(self, row: int, column: int) -> tuple[float, float]:
        """Figure fractions of the right end of a row label that ends left of ``column``."""
        middle = self._row_top(row) - self.title - self.image_height / 2
        return (column * self.column_width - self.gap) / self.width, middle / self.height


def hht_figure(result: HHTResult, *, size=None, dpi: float = 100, panel_width: int = 240, view="front",
               up="y", backend: str = "auto", supersample: int = 2, signal_name: str = "signal",
               percentiles=(1.0, 99.0)):
    """The composite figure of the paper's Fig. 4 as a Matplotlib ``Figure``.

    Row 1: the shaded model, the signal, IMF 1 … k (finest first) and the
    residue.  Rows 2 and 3, under the IMFs: instantaneous frequency
    ``ω_k = |∇φ_k|`` (Eq. 23) and local amplitude ``a_k`` (Eq. 21).

    Parameters
    ----------
    result : HHTResult
    size : (int, int), optional
        Width and height in pixels.  Default: ``panel_width`` per column and
        a height that fits the model's aspect.
    dpi : float
        Dots per inch: scales the fonts relative to the pixels.
    panel_width : int
        Column width in pixels when ``size`` is not given.
    view, up, backend, supersample
        See :func:`hht3d.viz.render.renderer`.
    signal_name : str
        Title of the signal panel (e.g. ``"mean curvature"``).
    percentiles : (float, float)
        Robust colour limits of every panel.

    Raises
    ------
    InputError
        Not an HHT result, or a bad size, view, backend or dpi.
    """
    from matplotlib.figure import Figure

    _check_result(result)
    _check_dpi(dpi)
    if int(panel_width) != panel_width or not 64 <= panel_width <= 2048:
        raise InputError(f"panel_width must be an integer in [64, 2048] pixels, got {panel_width!r}")
    surface, k = result.surface, result.n_imfs
    grid = _Grid(k + 3, model_aspect(surface, view, up), size, dpi, int(panel_width))
    drawer = renderer(surface, view=view, up=up, size=grid.image_size, backend=backend,
                      supersample=supersample)
    fig = Figure(figsize=(grid.width / dpi, grid.height / dpi), dpi=dpi)
    fig.text(0.5, 1 - 0.5 * grid.heading / grid.height,
             f"{surface.name}: Hilbert–Huang transform of the {signal_name} "
             f"({surface.n_vertices:,} vertices, {k} IMF{'' if k == 1 else 's'})", ha="center", va="center",
             fontsize=grid.font * 1.25)
    draw_image(fig, grid.image_box(0, 0), drawer.render(), title="model", font=grid.font)
    mono = result.monogenic
    panels = [(0, 1, result.signal, signal_name, {}), (0, k + 2, result.residue, "residue", {})]
    for i in range(k):
        panels += [(0, i + 2, result.imfs[i], f"IMF {i + 1}", {"cmap": IMF_CMAP, "symmetric": True}),
                   (1, i + 2, mono.frequency[i], f"ω, IMF {i + 1}", {"cmap": FREQUENCY_CMAP, "symmetric": False}),
                   (2, i + 2, mono.amplitude[i], f"a, IMF {i + 1}", {"cmap": AMPLITUDE_CMAP, "symmetric": False})]
    for row, column, values, title, options in panels:
        scale = color_scale(values, percentiles=percentiles, **options)
        draw_image(fig, grid.image_box(row, column), drawer.render(values, scale), title=title, font=grid.font)
        draw_colorbar(fig, grid.bar_box(row, column), scale, orientation="horizontal", font=grid.font)
    limit = f"resolution limit\n≈ {result.spectrum.resolvable_frequency:.3g}"
    for row, text in ((1, f"instantaneous\nfrequency ω\n(rad / unit length)\n{limit}"), (2, "local\namplitude a")):
        fig.text(*grid.row_label_position(row, 2), text, ha="right", va="center", fontsize=grid.font * 1.1)
    return fig


def _check_result(result) -> None:
    if not isinstance(result, HHTResult):
        raise InputError(f"expected an HHTResult (from hht3d.transform.hht), got {type(result).__name__}")


# -- Hilbert spectrum plots ------------------------------------------------------------------------
def spectrum_figure(result: HHTResult, *, bins: int = 64, scale: str = "log", limits=None,
                    size=(1400, 520), dpi: float = 100):
    """Plots of the Hilbert spectrum as a Matplotlib ``Figure``.

    Left: the area-weighted marginal spectrum ``h(ω) = Σ_v A_v H(ω, v)``.
    Right: the frequency–energy distribution of each IMF (its share of ``h``)
    with its energy-weighted mean frequency dashed.  Both show the share of
    the total IMF energy ``Σ_k ∫ a_k² dA`` per frequency bin, in percent.
    A dash-dotted line marks the surface's resolution limit (the median of
    ``π/√A_v``, :func:`hht3d.spectral.frequency.resolvable_frequency`; the axis
    extends to it when it lies less than twice beyond the data), and the
    title gives the share of the energy above each vertex's limit.

    Parameters
    ----------
    result : HHTResult
    bins : int
        Number of frequency bins.
    scale : {"log", "linear"}
        Bin spacing and frequency axis.
    limits : (float, float), optional
        Frequency range.  Default: the range holding all but 0.1 % of the
        energy at either end (positive frequencies on a log axis).
    size : (int, int)
        Width and height in pixels.
    dpi : float

    Raises
    ------
    InputError
        Not an HHT result, no IMF energy, or bad bins, scale, limits, size or dpi.
    """
    from matplotlib.figure import Figure

    _check_result(result)
    _check_dpi(dpi)
    width, height = check_size(size)
    if scale not in SCALES:
        raise InputError(f"unknown frequency scale {scale!r}; choose one of {SCALES}")
    spectrum = result.spectrum
    total = float(spectrum.imf_energy().sum())
    if not total > 0:
        raise InputError(f"{result.surface.name}: the IMFs carry no energy; there is no spectrum to plot")
    limits = spectrum.frequency_limits(scale) if limits is None else limits
    edges, marginal = spectrum.marginal(bins, scale, limits)
    resolution = spectrum.resolution
    right_end = resolution.limit if edges[-1] < resolution.limit < 2 * edges[-1] else edges[-1]
    font = font_points(width / 2.6, dpi)
    fig = Figure(figsize=(width / dpi, height / dpi), dpi=dpi, layout="constrained")
    left, right = fig.subplots(1, 2, sharex=True)
    _plot_marginal(left, edges, 100 * marginal / total, font)
    _plot_imfs(right, spectrum, edges, scale, limits, total, font)
    for axes in (left, right):
        axes.set_xscale(scale)
        axes.set_xlim(edges[0], right_end)
        if edges[0] < resolution.limit <= right_end:
            axes.axvline(resolution.limit, color="#8b1a1a", linestyle="-.", linewidth=1.1,
                         label="resolution limit π/√A")
        axes.set_ylim(bottom=0)
        axes.set_xlabel("instantaneous frequency ω (rad / unit length)", fontsize=font)
        axes.set_ylabel("share of the IMF energy per bin (%)", fontsize=font)
        axes.tick_params(labelsize=font * 0.9)
        axes.grid(alpha=0.3, linewidth=0.5)
    right.set_ylim(top=2.4 * right.get_ylim()[1])  # the legend sits above the curves, not on them
    right.legend(fontsize=font * 0.85, loc="upper right", framealpha=0.9, edgecolor="none")
    shown = 100 * marginal.sum() / total
    fig.suptitle(f"{result.surface.name}: Hilbert spectrum ({bins} {scale} bins; "
                 f"{shown:.1f}% of the energy within the plotted range)\nresolution limit π/√A ≈ "
                 f"{resolution.limit:.3g} (median over vertices); {100 * resolution.energy_share:.2g}% of the "
                 "energy above the vertices' limits", fontsize=font * 1.15)
    return fig


def _plot_marginal(axes, edges, share, font: float) -> None:
    axes.stairs(share, edges, fill=True, color="#4c72b0", alpha=0.35)
    axes.stairs(share, edges, color="#1f3f73", linewidth=1.2)
    axes.set_title(r"marginal spectrum $h(\omega) = \sum_v A_v\, H(\omega, v)$", fontsize=font)


def _plot_imfs(axes, spectrum: HilbertSpectrum, edges, scale: str, limits, total: float, font: float) -> None:
    import matplotlib

    k = spectrum.frequency.shape[0]
    colors = matplotlib.colormaps["plasma"](np.linspace(0.0, 0.85, k))
    means = spectrum.mean_frequency()
    shares = 100 * spectrum.imf_energy() / total
    for i in range(k):
        one = HilbertSpectrum(spectrum.frequency[i:i + 1], spectrum.amplitude[i:i + 1], spectrum.area)
        _, energy = one.marginal(len(edges) - 1, scale, limits)
        axes.stairs(100 * energy / total, edges, color=colors[i], linewidth=1.4,
                    label=f"IMF {i + 1}: {shares[i]:.1f}% of energy, mean ω {means[i]:.3g}")
        if np.isfinite(means[i]):
            axes.axvline(means[i], color=colors[i], linestyle="--", linewidth=0.9)
    axes.set_title("frequency–energy distribution of each IMF", fontsize=font)


# -- the standard set --------------------------------------------------------------------------------
def write_figures(result: HHTResult, folder, *, stem: str | None = None, view="front", up="y",
                  backend: str = "auto", dpi: float = 100, hht_size=None, spectrum_size=(1400, 520),
                  field_size=(900, 800), bins: int = 64, scale: str = "log",
                  signal_name: str = "signal") -> dict[str, Path]:
    """Write the standard figures of an HHT result as PNGs in ``folder``.

    Files (``stem`` defaults to the surface name):

    - ``{stem}_hht.png``: :func:`hht_figure` (model, signal, IMFs, residue,
      frequency and amplitude maps);
    - ``{stem}_spectrum.png``: :func:`spectrum_figure`;
    - ``{stem}_signal.png``: the signal alone, large, with a colour bar.

    Parameters
    ----------
    result : HHTResult
    folder : str or Path
        Created if missing.
    stem : str, optional
    view, up, backend
        See :func:`hht3d.viz.render.renderer`.
    dpi : float
    hht_size, spectrum_size, field_size : (int, int)
        Sizes in pixels (``hht_size=None`` fits the model's aspect).
    bins, scale
        See :func:`spectrum_figure`.
    signal_name : str
        Name of the signal in titles.

    Returns
    -------
    dict of str to Path
        ``{"hht": ..., "spectrum": ..., "signal": ...}``.
    """
    _check_result(result)
    folder = Path(folder)
    stem = stem or result.surface.name
    figures = {
        "hht": lambda: hht_figure(result, size=hht_size, dpi=dpi, view=view, up=up, backend=backend,
                                  signal_name=signal_name),
        "spectrum": lambda: spectrum_figure(result, bins=bins, scale=scale, size=spectrum_size, dpi=dpi),
        "signal": lambda: field_figure(result.surface, result.signal, size=field_size, dpi=dpi, view=view,
                                       up=up, backend=backend, title=f"{result.surface.name}: {signal_name}"),
    }
    return {name: save_figure(build(), folder / f"{stem}_{name}.png") for name, build in figures.items()}
