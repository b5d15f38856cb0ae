"""The software renderer: a NumPy z-buffer with supersampling (see :mod:`hht3d.viz.render`)."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from typing import cast

import numpy as np

from ...errors import InputError
from ...geometry.surface import Surface
from .colors import ColorScale, color_scale
from .image import MAX_SAMPLES, MODEL_GREY, Framing, Rendering, check_field, check_size, lambert, splat_radius
from .view import Camera

__all__ = ["SoftwareRenderer"]


@dataclass(frozen=True)
class _Fragments:
    """The visible surface sample of every covered supersampled pixel."""

    pixel: np.ndarray  # (m,) flat index into the (H, W) supersampled image
    vertex: np.ndarray  # (m, 3) vertices whose values are blended
    weight: np.ndarray  # (m, 3) blend weights (barycentric; points: 1, 0, 0)
    shade: np.ndarray  # (m,) Lambert factor


class SoftwareRenderer:
    """NumPy z-buffer renderer (see :mod:`hht3d.viz.render`); build it with :func:`hht3d.viz.render.renderer`."""

    name = "software"

    def __init__(
        self,
        surface: Surface,
        cam: Camera,
        size: tuple[int, int],
        *,
        supersample: int = 2,
        point_size: float | None = None,
    ) -> None:
        self.surface, self.camera = surface, cam
        self.width, self.height = check_size(size)
        if not isinstance(supersample, (int, np.integer)) or not 1 <= supersample <= 4:
            raise InputError(f"supersample must be an integer in [1, 4], got {supersample!r}")
        self.supersample = int(supersample)
        if self.width * self.height * self.supersample**2 > MAX_SAMPLES:
            raise InputError(
                f"{self.width}×{self.height} pixels with supersample={self.supersample} need "
                f"more than {MAX_SAMPLES:,} samples; lower the size or the supersampling"
            )
        self.point_size = _check_point_size(point_size)
        self._fragments: _Fragments | None = None

    def render(self, values: np.ndarray | None = None, scale: ColorScale | None = None) -> Rendering:
        """Draw ``values`` (n,) with ``scale`` (default: :func:`hht3d.viz.render.color_scale` of the values), or the
        plain shaded model when ``values`` is None."""
        fragments = self._rasterized()
        if values is None:
            colors = np.broadcast_to(MODEL_GREY, (len(fragments.pixel), 3))
        else:
            values = check_field(self.surface, values)
            scale = scale or color_scale(values)
            colors = scale(np.einsum("ij,ij->i", values[fragments.vertex], fragments.weight))
        s = self.supersample
        image = np.zeros((self.height * s * self.width * s, 4))
        image[fragments.pixel, :3] = colors * fragments.shade[:, None]
        image[fragments.pixel, 3] = 1.0
        image = image.reshape(self.height, s, self.width, s, 4).mean(axis=(1, 3))
        alpha = image[..., 3:]
        image[..., :3] = np.divide(image[..., :3], alpha, out=np.zeros_like(image[..., :3]), where=alpha > 0)
        return Rendering(image, scale, self.name)

    def _rasterized(self) -> _Fragments:
        if self._fragments is None:
            self._fragments = self._rasterize()
        return self._fragments

    def _rasterize(self) -> _Fragments:
        s = self.supersample
        width, height = self.width * s, self.height * s
        projected = self.camera.project(self.surface.vertices)
        framing = Framing(projected[:, :2], width, height)
        xy, depth = framing.pixels(projected[:, :2]), projected[:, 2]
        if self.surface.is_mesh:
            pixel, vertex, weight = _rasterize_triangles(xy, depth, cast(np.ndarray, self.surface.faces), width, height)
        else:
            radius = splat_radius(self.surface, self.point_size, framing.pixels_per_unit, s)
            pixel, vertex, weight = _rasterize_points(xy, depth * framing.pixels_per_unit, radius, width, height)
        normals = np.einsum("mk,mkj->mj", weight, self.surface.normals[vertex])
        length = np.linalg.norm(normals, axis=1, keepdims=True)
        normals = np.divide(normals, length, out=np.zeros_like(normals), where=length > 0)
        return _Fragments(pixel, vertex, weight, lambert(normals, self.camera.light))


def _check_point_size(point_size: float | None) -> float | None:
    if point_size is None:
        return None
    if not (isinstance(point_size, (int, float, np.number)) and 0 < point_size <= 64):
        raise InputError(f"point_size must be a diameter in (0, 64] output pixels, got {point_size!r}")
    return float(point_size)


class _DepthBuffer:
    """Keeps, per pixel, the nearest candidate's owner and blend weights."""

    def __init__(self, n_pixels: int):
        self.depth = np.full(n_pixels, -np.inf)
        self.owner = np.full(n_pixels, -1, dtype=np.int64)
        self.weights = np.zeros((n_pixels, 2), dtype=np.float32)

    def offer(self, pixel: np.ndarray, depth: np.ndarray, owner: np.ndarray, weights: np.ndarray) -> None:
        np.maximum.at(self.depth, pixel, depth)
        nearest = depth >= self.depth[pixel]
        self.owner[pixel[nearest]] = owner[nearest]
        self.weights[pixel[nearest]] = weights[nearest]

    def covered(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        pixel = np.flatnonzero(self.owner >= 0)
        return pixel, self.owner[pixel], self.weights[pixel].astype(np.float64)


def _chunks(counts: np.ndarray, budget: int = 2_000_000) -> Iterator[slice]:
    """Split items into consecutive runs whose counts sum to about ``budget``."""
    ends = np.searchsorted(np.cumsum(counts), np.arange(budget, counts.sum() + budget, budget), side="right")
    start = 0
    for end in np.unique(np.clip(ends, 1, len(counts))):
        if end > start:
            yield slice(start, end)
            start = end


def _expand(low: np.ndarray, span: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every pixel of each item's box: (item index, column, row) for boxes ``low + [0, span)``."""
    counts = span[:, 0] * span[:, 1]
    item = np.repeat(np.arange(len(counts)), counts)
    local = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
    columns = span[item, 0]
    return item, low[item, 0] + local % columns, low[item, 1] + local // columns


def _rasterize_triangles(
    xy: np.ndarray, depth: np.ndarray, faces: np.ndarray, width: int, height: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Z-buffered triangle coverage: per covered pixel, the face's vertices and barycentrics."""
    corners = xy[faces]
    low = np.maximum(np.ceil(corners.min(axis=1) - 0.5), 0).astype(np.int64)
    high = np.minimum(np.floor(corners.max(axis=1) - 0.5), [width - 1, height - 1]).astype(np.int64)
    edge1, edge2 = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    det = edge1[:, 0] * edge2[:, 1] - edge1[:, 1] * edge2[:, 0]
    visible = np.flatnonzero(np.all(high >= low, axis=1) & (np.abs(det) > 1e-12))
    low, span = low[visible], (high - low + 1)[visible]
    origin, edge1, edge2, inverse = corners[visible, 0], edge1[visible], edge2[visible], 1.0 / det[visible]
    z = depth[faces[visible]]
    buffer = _DepthBuffer(width * height)
    for part in _chunks(span[:, 0] * span[:, 1]):
        local, column, row = _expand(low[part], span[part])
        face = local + part.start
        dx = column + 0.5 - origin[face, 0]
        dy = row + 0.5 - origin[face, 1]
        b1 = (dx * edge2[face, 1] - dy * edge2[face, 0]) * inverse[face]
        b2 = (edge1[face, 0] * dy - edge1[face, 1] * dx) * inverse[face]
        inside = (b1 >= -1e-9) & (b2 >= -1e-9) & (b1 + b2 <= 1 + 1e-9)
        face, b1, b2 = face[inside], b1[inside], b2[inside]
        zf = z[face]
        candidate_depth = zf[:, 0] + b1 * (zf[:, 1] - zf[:, 0]) + b2 * (zf[:, 2] - zf[:, 0])
        buffer.offer(row[inside] * width + column[inside], candidate_depth, face, np.column_stack([b1, b2]))
    pixel, face, weights = buffer.covered()
    b1, b2 = weights.T
    weight = np.column_stack([1 - b1 - b2, b1, b2])
    return pixel, faces[visible[face]], weight


def _rasterize_points(
    xy: np.ndarray, depth: np.ndarray, radius: float, width: int, height: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Depth-tested disc splats of ``radius`` pixels (depth in pixel units)."""
    reach = int(np.ceil(radius))
    inside = np.all((xy >= -reach) & (xy < [width + reach, height + reach]), axis=1)
    points = np.flatnonzero(inside)
    low = np.floor(xy[points]).astype(np.int64) - reach
    span = np.full((len(points), 2), 2 * reach + 1)
    buffer = _DepthBuffer(width * height)
    for part in _chunks(span[:, 0] * span[:, 1]):
        local, column, row = _expand(low[part], span[part])
        point = points[local + part.start]
        d2 = (column + 0.5 - xy[point, 0]) ** 2 + (row + 0.5 - xy[point, 1]) ** 2
        keep = (d2 <= radius**2) & (column >= 0) & (column < width) & (row >= 0) & (row < height)
        point, column, row = point[keep], column[keep], row[keep]
        bulge = np.sqrt(radius**2 - d2[keep])  # a sphere's front: nearer at the disc centre
        buffer.offer(row * width + column, depth[point] + bulge, point, np.zeros((len(point), 2)))
    pixel, point, _ = buffer.covered()
    return pixel, np.repeat(point[:, None], 3, axis=1), np.tile([1.0, 0.0, 0.0], (len(point), 1))
