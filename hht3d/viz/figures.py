"""Figures of an HHT result: the paper's Fig. 4 layout and plots of the Hilbert spectrum.

Single fields with a title and a colour bar are :mod:`hht3d.viz.panels`.

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

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError
from ..spectral.spectrum import SCALES, HilbertSpectrum
from ..transform import HHTResult
from .panels import (
    check_dpi,
    check_result,
    draw_colorbar,
    draw_image,
    field_figure,
    font_points,
    fractions,
    save_figure,
)
from .render import PERCENTILES, SEQUENTIAL_CMAP, SYMMETRIC_CMAP, color_scale, model_aspect, renderer
from .render.image import check_size

__all__ = ["FREQUENCY_CMAP", "AMPLITUDE_CMAP", "IMF_CMAP", "hht_figure", "spectrum_figure", "write_figures"]

#: Colour maps of the composite figure.
IMF_CMAP = SYMMETRIC_CMAP
FREQUENCY_CMAP = SEQUENTIAL_CMAP
AMPLITUDE_CMAP = "plasma"


# -- the composite figure (paper Fig. 4) --------------------------------------------------------
class _Grid:
    """Pixel layout of the composite: a title band, then three rows of panels, each a title,
    an image and a horizontal colour bar below it."""

    def __init__(
        self, columns: int, image_aspect: float, size: tuple[float, float] | None, dpi: float, panel_width: int
    ) -> None:
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
            raise InputError(
                f"figure size {size!r} leaves panels of {self.image_width}×{self.image_height} "
                f"pixels for {columns} columns; make it larger"
            )
        self.width, self.height = int(width), int(height)

    @property
    def image_size(self) -> tuple[int, int]:
        return self.image_width, self.image_height

    def _row_top(self, row: int) -> float:
        return self.height - self.heading - row * (self.title + self.image_height + self.bar_band)

    def image_box(self, row: int, column: int) -> list[float]:
        left = column * self.column_width + (self.column_width - self.image_width) / 2
        bottom = self._row_top(row) - self.title - self.image_height
        return fractions((round(left), round(bottom), self.image_width, self.image_height), self.width, self.height)

    def bar_box(self, row: int, column: int) -> list[float]:
        width = 0.8 * self.image_width
        left = column * self.column_width + (self.column_width - width) / 2
        bottom = self._row_top(row) - self.title - self.image_height - 0.75 * self.em
        return fractions((left, bottom, width, 0.5 * self.em), self.width, self.height)

    def row_label_position(self, row: int, column: int) -> tuple[float, float]:
        """Figure fractions of the right end of a row label that ends left of ``column``."""
        middle = self._row_top(row) - self.title - self.image_height / 2
        return (column * self.column_width - self.gap) / self.width, middle / self.height


def hht_figure(
    result: HHTResult,
    *,
    size: tuple[float, float] | None = None,
    dpi: float = 100,
    panel_width: int = 240,
    view: str | Sequence[float] = "front",
    up: str | Sequence[float] = "y",
    backend: str = "auto",
    supersample: int = 2,
    signal_name: str = "signal",
    percentiles: tuple[float, float] = PERCENTILES,
) -> Any:
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

    Returns
    -------
    matplotlib.figure.Figure
        The figure.

    Raises
    ------
    InputError
        Not an HHT result, or a bad size, view, backend or dpi.
    """
    from matplotlib.figure import Figure

    check_result(result)
    check_dpi(dpi)
    if int(panel_width) != panel_width or not 64 <= panel_width <= 2048:
        raise InputError(f"panel_width must be an integer in [64, 2048] pixels, got {panel_width!r}")
    surface, k = result.surface, result.n_imfs
    grid = _Grid(k + 3, model_aspect(surface, view, up), size, dpi, int(panel_width))
    drawer = renderer(surface, view=view, up=up, size=grid.image_size, backend=backend, supersample=supersample)
    fig = Figure(figsize=(grid.width / dpi, grid.height / dpi), dpi=dpi)
    fig.text(
        0.5,
        1 - 0.5 * grid.heading / grid.height,
        f"{surface.name}: Hilbert–Huang transform of the {signal_name} "
        f"({surface.n_vertices:,} vertices, {k} IMF{'' if k == 1 else 's'})",
        ha="center",
        va="center",
        fontsize=grid.font * 1.25,
    )
    draw_image(fig, grid.image_box(0, 0), drawer.render(), title="model", font=grid.font)
    mono = result.monogenic
    panels: list[tuple[int, int, np.ndarray, str, dict]] = [
        (0, 1, result.signal, signal_name, {}),
        (0, k + 2, result.residue, "residue", {}),
    ]
    for i in range(k):
        panels += [
            (0, i + 2, result.imfs[i], f"IMF {i + 1}", {"cmap": IMF_CMAP, "symmetric": True}),
            (1, i + 2, mono.frequency[i], f"ω, IMF {i + 1}", {"cmap": FREQUENCY_CMAP, "symmetric": False}),
            (2, i + 2, mono.amplitude[i], f"a, IMF {i + 1}", {"cmap": AMPLITUDE_CMAP, "symmetric": False}),
        ]
    for row, column, values, title, options in panels:
        scale = color_scale(values, percentiles=percentiles, **options)
        draw_image(fig, grid.image_box(row, column), drawer.render(values, scale), title=title, font=grid.font)
        draw_colorbar(fig, grid.bar_box(row, column), scale, orientation="horizontal", font=grid.font)
    limit = f"resolution limit\n≈ {result.spectrum.resolvable_frequency:.3g}"
    for row, text in ((1, f"instantaneous\nfrequency ω\n(rad / unit length)\n{limit}"), (2, "local\namplitude a")):
        fig.text(*grid.row_label_position(row, 2), text, ha="right", va="center", fontsize=grid.font * 1.1)
    return fig


# -- Hilbert spectrum plots ------------------------------------------------------------------------
def spectrum_figure(
    result: HHTResult,
    *,
    bins: int = 64,
    scale: str = "log",
    limits: tuple[float, float] | None = None,
    size: tuple[float, float] = (1400, 520),
    dpi: float = 100,
) -> Any:
    """Plots of the Hilbert spectrum as a Matplotlib ``Figure``.

    Left: the area-weighted marginal spectrum ``h(ω) = Σ_v A_v H(ω, v)``.
    Right: the frequency–energy distribution of each IMF (its share of ``h``)
    with its energy-weighted mean frequency dashed.  Both show the share of
    the total IMF energy ``Σ_k ∫ a_k² dA`` per frequency bin, in percent.
    A dash-dotted line marks the surface's resolution limit (the median of
    ``π/√A_v``, :func:`hht3d.spectral.resolution.resolvable_frequency`; the axis
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

    Returns
    -------
    matplotlib.figure.Figure
        The figure.

    Raises
    ------
    InputError
        Not an HHT result, no IMF energy, or bad bins, scale, limits, size or dpi.
    """
    from matplotlib.figure import Figure

    check_result(result)
    check_dpi(dpi)
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
            axes.axvline(
                resolution.limit, color="#8b1a1a", linestyle="-.", linewidth=1.1, label="resolution limit π/√A"
            )
        axes.set_ylim(bottom=0)
        axes.set_xlabel("instantaneous frequency ω (rad / unit length)", fontsize=font)
        axes.set_ylabel("share of the IMF energy per bin (%)", fontsize=font)
        axes.tick_params(labelsize=font * 0.9)
        axes.grid(alpha=0.3, linewidth=0.5)
    right.set_ylim(top=2.4 * right.get_ylim()[1])  # the legend sits above the curves, not on them
    right.legend(fontsize=font * 0.85, loc="upper right", framealpha=0.9, edgecolor="none")
    shown = 100 * marginal.sum() / total
    fig.suptitle(
        f"{result.surface.name}: Hilbert spectrum ({bins} {scale} bins; "
        f"{shown:.1f}% of the energy within the plotted range)\nresolution limit π/√A ≈ "
        f"{resolution.limit:.3g} (median over vertices); {100 * resolution.energy_share:.2g}% of the "
        "energy above the vertices' limits",
        fontsize=font * 1.15,
    )
    return fig


def _plot_marginal(axes: Any, edges: np.ndarray, share: np.ndarray, font: float) -> None:
    axes.stairs(share, edges, fill=True, color="#4c72b0", alpha=0.35)
    axes.stairs(share, edges, color="#1f3f73", linewidth=1.2)
    axes.set_title(r"marginal spectrum $h(\omega) = \sum_v A_v\, H(\omega, v)$", fontsize=font)


def _plot_imfs(
    axes: Any,
    spectrum: HilbertSpectrum,
    edges: np.ndarray,
    scale: str,
    limits: tuple[float, float] | None,
    total: float,
    font: float,
) -> None:
    import matplotlib

    k = spectrum.frequency.shape[0]
    colors = matplotlib.colormaps["plasma"](np.linspace(0.0, 0.85, k))
    means = spectrum.mean_frequency()
    shares = 100 * spectrum.imf_energy() / total
    for i in range(k):
        one = HilbertSpectrum(spectrum.frequency[i : i + 1], spectrum.amplitude[i : i + 1], spectrum.area)
        _, energy = one.marginal(len(edges) - 1, scale, limits)
        axes.stairs(
            100 * energy / total,
            edges,
            color=colors[i],
            linewidth=1.4,
            label=f"IMF {i + 1}: {shares[i]:.1f}% of energy, mean ω {means[i]:.3g}",
        )
        if np.isfinite(means[i]):
            axes.axvline(means[i], color=colors[i], linestyle="--", linewidth=0.9)
    axes.set_title("frequency–energy distribution of each IMF", fontsize=font)


# -- the standard set --------------------------------------------------------------------------------
def write_figures(
    result: HHTResult,
    folder: Path | str,
    *,
    stem: str | None = None,
    view: str | Sequence[float] = "front",
    up: str | Sequence[float] = "y",
    backend: str = "auto",
    dpi: float = 100,
    hht_size: tuple[float, float] | None = None,
    spectrum_size: tuple[float, float] = (1400, 520),
    field_size: tuple[float, float] = (900, 800),
    bins: int = 64,
    scale: str = "log",
    signal_name: str = "signal",
) -> dict[str, Path]:
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
    check_result(result)
    folder = Path(folder)
    stem = stem or result.surface.name
    figures = {
        "hht": lambda: hht_figure(
            result, size=hht_size, dpi=dpi, view=view, up=up, backend=backend, signal_name=signal_name
        ),
        "spectrum": lambda: spectrum_figure(result, bins=bins, scale=scale, size=spectrum_size, dpi=dpi),
        "signal": lambda: field_figure(
            result.surface,
            result.signal,
            size=field_size,
            dpi=dpi,
            view=view,
            up=up,
            backend=backend,
            title=f"{result.surface.name}: {signal_name}",
        ),
    }
    return {name: save_figure(build(), folder / f"{stem}_{name}.png") for name, build in figures.items()}
