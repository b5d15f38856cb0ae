"""Colour scales: a colour map with robust, optionally symmetric limits (NaN grey)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ...errors import InputError

__all__ = ["ColorScale", "color_scale", "BAD_COLOR", "PERCENTILES", "SYMMETRIC_CMAP", "SEQUENTIAL_CMAP"]

#: The colour of NaN values.
BAD_COLOR = np.array([0.55, 0.55, 0.55])
#: Robust colour limits: these percentiles of a field's values, so a few outliers do not wash it out.
PERCENTILES = (1.0, 99.0)
#: Colour map of signed fields (diverging, white at 0).
SYMMETRIC_CMAP = "RdBu_r"
#: Colour map of one-signed fields.
SEQUENTIAL_CMAP = "viridis"


@dataclass(frozen=True)
class ColorScale:
    """A colour map with limits: maps values to RGB and draws a colour bar.

    Attributes
    ----------
    cmap : str
        A Matplotlib colour map name.
    vmin, vmax : float
        Limits; values beyond them take the end colours, NaN is grey.
    """

    cmap: str
    vmin: float
    vmax: float

    def __call__(self, values: np.ndarray) -> np.ndarray:
        """RGB in [0, 1] of ``values`` (any shape) → shape ``values.shape + (3,)``."""
        import matplotlib

        values = np.asarray(values, dtype=np.float64)
        scaled = np.clip((values - self.vmin) / (self.vmax - self.vmin), 0.0, 1.0)
        rgb = matplotlib.colormaps[self.cmap](np.nan_to_num(scaled, nan=0.0))[..., :3]
        rgb[np.isnan(values)] = BAD_COLOR
        return rgb

    def mappable(self) -> Any:
        """A Matplotlib ``ScalarMappable`` for ``Figure.colorbar``."""
        from matplotlib.cm import ScalarMappable
        from matplotlib.colors import Normalize

        return ScalarMappable(Normalize(self.vmin, self.vmax), self.cmap)


def color_scale(
    values: np.ndarray,
    *,
    cmap: str | None = None,
    limits: tuple[float, float] | None = None,
    symmetric: bool | None = None,
    percentiles: tuple[float, float] = PERCENTILES,
) -> ColorScale:
    """Choose colour limits for a field: robust percentiles, symmetric about 0 for signed fields.

    Parameters
    ----------
    values : array_like
        The field; NaN and infinite values are ignored.
    cmap : str, optional
        Default ``"RdBu_r"`` (diverging) when symmetric, else ``"viridis"``.
    limits : (float, float), optional
        Explicit ``(vmin, vmax)``; overrides percentiles and symmetry.
    symmetric : bool, optional
        Limits ``±max(|p_low|, |p_high|)``.  Default: when the percentile range
        holds both signs and the smaller side is at least a tenth of the larger
        (an IMF, a curvature with convex and concave parts).
    percentiles : (float, float)
        Robust range of the values, ignoring outliers.

    Raises
    ------
    InputError
        No finite value, an unknown colour map, bad limits or percentiles.
    """
    if cmap is not None:
        _check_cmap(cmap)
    if limits is not None:
        vmin, vmax = _checked_limits(limits)
        return ColorScale(cmap or SEQUENTIAL_CMAP, vmin, vmax)
    values = np.asarray(values, dtype=np.float64)
    finite = values[np.isfinite(values)]
    if finite.size == 0:
        raise InputError("the field has no finite values to colour")
    low, high = _checked_percentiles(percentiles)
    vmin, vmax = (float(v) for v in np.percentile(finite, [low, high]))
    if symmetric is None:
        symmetric = vmin < 0 < vmax and min(-vmin, vmax) >= 0.1 * max(-vmin, vmax)
    if symmetric:
        bound = max(abs(vmin), abs(vmax))
        vmin, vmax = -bound, bound
    if vmax <= vmin:
        pad = abs(vmin) * 0.5 or 1.0
        vmin, vmax = vmin - pad, vmax + pad
    return ColorScale(cmap or (SYMMETRIC_CMAP if symmetric else SEQUENTIAL_CMAP), vmin, vmax)


def _check_cmap(cmap: str) -> None:
    import matplotlib

    if cmap not in matplotlib.colormaps:
        raise InputError(
            f"unknown colour map {cmap!r}; use a Matplotlib name such as 'viridis', 'magma', 'RdBu_r' or 'coolwarm'"
        )


def _checked_limits(limits: Any) -> tuple[float, float]:
    try:
        vmin, vmax = (float(v) for v in limits)
    except (TypeError, ValueError):
        raise InputError(f"colour limits must be (vmin, vmax), got {limits!r}") from None
    if not (np.isfinite(vmin) and np.isfinite(vmax) and vmax > vmin):
        raise InputError(f"colour limits must be finite with vmin < vmax, got {limits!r}")
    return vmin, vmax


def _checked_percentiles(percentiles: tuple[float, float]) -> tuple[float, float]:
    try:
        low, high = (float(p) for p in percentiles)
    except (TypeError, ValueError):
        raise InputError(f"percentiles must be (low, high), got {percentiles!r}") from None
    if not 0 <= low < high <= 100:
        raise InputError(f"percentiles must satisfy 0 <= low < high <= 100, got {percentiles!r}")
    return low, high
