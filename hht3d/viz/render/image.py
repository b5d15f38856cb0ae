"""What both renderers share: the image, its size, framing the model, shading and point splats."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ...errors import InputError
from ...geometry.surface import Surface
from .colors import ColorScale

__all__ = [
    "Rendering",
    "Framing",
    "MAX_SIZE",
    "MAX_SAMPLES",
    "MODEL_GREY",
    "check_size",
    "check_field",
    "lambert",
    "splat_radius",
]

#: Largest image side in pixels, and most (supersampled) pixels the software renderer fills.
MAX_SIZE = 8192
MAX_SAMPLES = 2**25
#: The colour of the model without a field.
MODEL_GREY = np.array([0.78, 0.78, 0.76])
#: Shading of a face turned away from the light.
AMBIENT = 0.35
#: Margin around the model, as a fraction of the image side.
MARGIN = 0.03


@dataclass(frozen=True)
class Rendering:
    """A rendered field.

    Attributes
    ----------
    rgba : (h, w, 4) ndarray
        Colours in [0, 1]; alpha is the fraction of the pixel the model covers.
    scale : ColorScale or None
        The colour scale of the field (``None`` for the plain shaded model).
    backend : str
        The renderer that drew it.
    """

    rgba: np.ndarray
    scale: ColorScale | None
    backend: str

    @property
    def mask(self) -> np.ndarray:
        """Pixels mostly covered by the model (h, w) bool."""
        return self.rgba[..., 3] > 0.5

    def rgb(self, background: tuple[float, float, float] = (1.0, 1.0, 1.0)) -> np.ndarray:
        """The image over a background colour as (h, w, 3) uint8."""
        alpha = self.rgba[..., 3:]
        mixed = self.rgba[..., :3] * alpha + np.asarray(background, dtype=np.float64) * (1 - alpha)
        return np.round(np.clip(mixed, 0, 1) * 255).astype(np.uint8)


class Framing:
    """Maps camera coordinates to pixel coordinates so the model fills the image."""

    def __init__(self, xy: np.ndarray, width: int, height: int, margin: float = MARGIN):
        low, high = xy.min(axis=0), xy.max(axis=0)
        extent = np.maximum(high - low, 1e-9 * float(np.max(high - low)) + 1e-300)
        self.center = (low + high) / 2
        self.width, self.height = width, height
        self.pixels_per_unit = float(min(width * (1 - 2 * margin) / extent[0], height * (1 - 2 * margin) / extent[1]))

    def pixels(self, xy: np.ndarray) -> np.ndarray:
        """Pixel coordinates (column, row from the top), pixel centres at half integers."""
        p = (xy - self.center) * self.pixels_per_unit
        return np.column_stack([self.width / 2 + p[:, 0], self.height / 2 - p[:, 1]])


def lambert(normals: np.ndarray, light: np.ndarray) -> np.ndarray:
    """Two-sided Lambert shading factor in [AMBIENT, 1]."""
    return AMBIENT + (1 - AMBIENT) * np.abs(normals @ light)


def check_size(size: Any) -> tuple[int, int]:
    try:
        width, height = (int(s) for s in size)
    except (TypeError, ValueError):
        raise InputError(f"size must be (width, height) in pixels, got {size!r}") from None
    if not (tuple(size) == (width, height) and 1 <= width <= MAX_SIZE and 1 <= height <= MAX_SIZE):
        raise InputError(f"size must be two integers in [1, {MAX_SIZE}] pixels, got {size!r}")
    return width, height


def check_field(surface: Surface, values: np.ndarray) -> np.ndarray:
    try:
        field = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"{surface.name}: the field to render is not numeric") from None
    if field.shape != (surface.n_vertices,):
        raise InputError(
            f"{surface.name}: the field to render has shape {field.shape}; expected "
            f"({surface.n_vertices},), one value per vertex"
        )
    return field


def splat_radius(surface: Surface, point_size: float | None, pixels_per_unit: float, supersample: int) -> float:
    """Disc radius in supersampled pixels: ``point_size / 2`` output pixels, or by default
    0.8 × the median nearest-neighbour spacing (at least one output pixel)."""
    if point_size is not None:
        return max(point_size / 2 * supersample, 0.5)
    from scipy.spatial import cKDTree

    points = surface.vertices
    sample = points[:: max(1, len(points) // 20000)]
    spacing = float(np.median(cKDTree(points).query(sample, k=2)[0][:, 1]))
    return max(0.8 * spacing * pixels_per_unit, 1.0 * supersample)
