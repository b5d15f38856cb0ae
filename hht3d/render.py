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
view (the composite figures of :mod:`hht3d.figures`); see
``benchmarks/results/render.md``.  Asking for ``"open3d"`` where it cannot
run raises :class:`~hht3d.errors.InputError` saying why (found in a child
process, since Filament aborts the process that fails to start it).

:func:`render` returns a :class:`Rendering` (RGBA, alpha = model coverage);
:func:`field_figure` / :func:`render_png` add a title and a colour bar.
"""
from __future__ import annotations

import contextlib
import functools
import os
import subprocess
import sys
import threading
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import InputError
from .io import atomic_path
from .surface import Surface

__all__ = ["BACKENDS", "UP_AXES", "VIEWS", "Camera", "ColorScale", "Rendering",
           "available_backends", "camera", "color_scale", "draw_colorbar", "draw_image", "field_figure",
           "font_points", "model_aspect", "render", "render_png", "renderer", "save_figure"]

#: Named views as ``(azimuth, elevation)`` in degrees.  Azimuth turns the eye about the up
#: axis towards the model's right (as seen in the front view); elevation raises it.
VIEWS = {"front": (0.0, 0.0), "back": (180.0, 0.0), "right": (90.0, 0.0), "left": (-90.0, 0.0),
         "top": (0.0, 90.0), "bottom": (0.0, -90.0)}
#: Named up axes.  The front view looks at the model from +z (up ±x or ±y) or from −y (up ±z).
UP_AXES = ("x", "y", "z", "-x", "-y", "-z")
#: Renderers; ``"auto"`` is ``"software"``, the one that is always available.
BACKENDS = ("auto", "software", "open3d")

#: Largest image side in pixels, and most (supersampled) pixels the software renderer fills.
MAX_SIZE = 8192
MAX_SAMPLES = 2 ** 25
_MODEL_GREY = np.array([0.78, 0.78, 0.76])
_BAD_COLOR = np.array([0.55, 0.55, 0.55])
_AMBIENT = 0.35
_MARGIN = 0.03


# -- camera ------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Camera:
    """An orthographic camera given by its image axes.

    Attributes
    ----------
    right, up : (3,) ndarray
        World directions of the image's x (to the right) and y (upwards).
    toward : (3,) ndarray
        From the model towards the eye; larger ``p · toward`` is nearer.
    """

    right: np.ndarray
    up: np.ndarray
    toward: np.ndarray

    def project(self, points: np.ndarray) -> np.ndarray:
        """Camera coordinates ``(x right, y up, depth towards the eye)`` of ``points`` (n, 3)."""
        return points @ np.column_stack([self.right, self.up, self.toward])

    @property
    def light(self) -> np.ndarray:
        """Unit direction towards the light: beside the eye, a little up and to the left."""
        light = self.toward + 0.4 * self.up - 0.3 * self.right
        return light / np.linalg.norm(light)


def camera(view="front", up="y") -> Camera:
    """The camera of a named view or of ``(azimuth, elevation)`` degrees.

    Parameters
    ----------
    view : str or (float, float)
        A name of :data:`VIEWS` or ``(azimuth, elevation)`` in degrees.
    up : str or (3,) array_like
        The model's up axis: one of :data:`UP_AXES` or a vector.  Spot and the
        Stanford models are ``"y"``-up; many scans are ``"z"``-up.

    Raises
    ------
    InputError
        Unknown view name, malformed angles or a zero up vector.
    """
    azimuth, elevation = np.radians(_view_angles(view))
    up_axis = _up_vector(up)
    front = _front_vector(up_axis)
    side = np.cross(up_axis, front)
    horizontal = np.cos(azimuth) * front + np.sin(azimuth) * side
    toward = np.cos(elevation) * horizontal + np.sin(elevation) * up_axis
    image_up = np.cos(elevation) * up_axis - np.sin(elevation) * horizontal
    return Camera(right=np.cross(image_up, toward), up=image_up, toward=toward)


def _view_angles(view) -> tuple[float, float]:
    if isinstance(view, str):
        if view not in VIEWS:
            raise InputError(f"unknown view {view!r}; choose one of {', '.join(VIEWS)} "
                             "or give (azimuth, elevation) in degrees")
        return VIEWS[view]
    try:
        azimuth, elevation = (float(a) for a in view)
    except (TypeError, ValueError):
        raise InputError(f"view must be a name ({', '.join(VIEWS)}) or (azimuth, elevation) in degrees, "
                         f"got {view!r}") from None
    if not (np.isfinite(azimuth) and np.isfinite(elevation)):
        raise InputError(f"view angles must be finite, got {view!r}")
    return azimuth, elevation


def _up_vector(up) -> np.ndarray:
    if isinstance(up, str):
        if up not in UP_AXES:
            raise InputError(f"unknown up axis {up!r}; choose one of {UP_AXES} or give a 3-vector")
        vector = np.zeros(3)
        vector["xyz".index(up[-1])] = -1.0 if up.startswith("-") else 1.0
        return vector
    vector = np.asarray(up, dtype=np.float64)
    if vector.shape != (3,) or not np.all(np.isfinite(vector)) or np.linalg.norm(vector) == 0:
        raise InputError(f"up must be one of {UP_AXES} or a finite non-zero 3-vector, got {up!r}")
    return vector / np.linalg.norm(vector)


def _front_vector(up: np.ndarray) -> np.ndarray:
    reference = np.array([0.0, -1.0, 0.0]) if abs(up[2]) > 0.9 else np.array([0.0, 0.0, 1.0])
    front = reference - (reference @ up) * up
    return front / np.linalg.norm(front)


# -- colours -----------------------------------------------------------------------------------
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

    def __call__(self, values) -> np.ndarray:
        """RGB in [0, 1] of ``values`` (any shape) → shape ``values.shape + (3,)``."""
        import matplotlib

        values = np.asarray(values, dtype=np.float64)
        scaled = np.clip((values - self.vmin) / (self.vmax - self.vmin), 0.0, 1.0)
        rgb = matplotlib.colormaps[self.cmap](np.nan_to_num(scaled, nan=0.0))[..., :3]
        rgb[np.isnan(values)] = _BAD_COLOR
        return rgb

    def mappable(self):
        """A Matplotlib ``ScalarMappable`` for ``Figure.colorbar``."""
        from matplotlib.cm import ScalarMappable
        from matplotlib.colors import Normalize

        return ScalarMappable(Normalize(self.vmin, self.vmax), self.cmap)


def color_scale(values, *, cmap: str | None = None, limits=None, symmetric: bool | None = None,
                percentiles=(1.0, 99.0)) -> ColorScale:
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
        return ColorScale(cmap or "viridis", vmin, vmax)
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
    return ColorScale(cmap or ("RdBu_r" if symmetric else "viridis"), vmin, vmax)


def _check_cmap(cmap: str) -> None:
    import matplotlib

    if cmap not in matplotlib.colormaps:
        raise InputError(f"unknown colour map {cmap!r}; use a Matplotlib name such as 'viridis', "
                         "'magma', 'RdBu_r' or 'coolwarm'")


def _checked_limits(limits) -> tuple[float, float]:
    try:
        vmin, vmax = (float(v) for v in limits)
    except (TypeError, ValueError):
        raise InputError(f"colour limits must be (vmin, vmax), got {limits!r}") from None
    if not (np.isfinite(vmin) and np.isfinite(vmax) and vmax > vmin):
        raise InputError(f"colour limits must be finite with vmin < vmax, got {limits!r}")
    return vmin, vmax


def _checked_percentiles(percentiles) -> tuple[float, float]:
    try:
        low, high = (float(p) for p in percentiles)
    except (TypeError, ValueError):
        raise InputError(f"percentiles must be (low, high), got {percentiles!r}") from None
    if not 0 <= low < high <= 100:
        raise InputError(f"percentiles must satisfy 0 <= low < high <= 100, got {percentiles!r}")
    return low, high


# -- the image ----------------------------------------------------------------------------------
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

    def rgb(self, background=(1.0, 1.0, 1.0)) -> np.ndarray:
        """The image over a background colour as (h, w, 3) uint8."""
        alpha = self.rgba[..., 3:]
        mixed = self.rgba[..., :3] * alpha + np.asarray(background, dtype=np.float64) * (1 - alpha)
        return np.round(np.clip(mixed, 0, 1) * 255).astype(np.uint8)


class _Framing:
    """Maps camera coordinates to pixel coordinates so the model fills the image."""

    def __init__(self, xy: np.ndarray, width: int, height: int, margin: float = _MARGIN):
        low, high = xy.min(axis=0), xy.max(axis=0)
        extent = np.maximum(high - low, 1e-9 * float(np.max(high - low)) + 1e-300)
        self.center = (low + high) / 2
        self.width, self.height = width, height
        self.pixels_per_unit = float(min(width * (1 - 2 * margin) / extent[0],
                                         height * (1 - 2 * margin) / extent[1]))

    def pixels(self, xy: np.ndarray) -> np.ndarray:
        """Pixel coordinates (column, row from the top), pixel centres at half integers."""
        p = (xy - self.center) * self.pixels_per_unit
        return np.column_stack([self.width / 2 + p[:, 0], self.height / 2 - p[:, 1]])


def _lambert(normals: np.ndarray, light: np.ndarray) -> np.ndarray:
    """Two-sided Lambert shading factor in [_AMBIENT, 1]."""
    return _AMBIENT + (1 - _AMBIENT) * np.abs(normals @ light)


def _check_size(size) -> tuple[int, int]:
    try:
        width, height = (int(s) for s in size)
    except (TypeError, ValueError):
        raise InputError(f"size must be (width, height) in pixels, got {size!r}") from None
    if not (tuple(size) == (width, height) and 1 <= width <= MAX_SIZE and 1 <= height <= MAX_SIZE):
        raise InputError(f"size must be two integers in [1, {MAX_SIZE}] pixels, got {size!r}")
    return width, height


# -- software renderer --------------------------------------------------------------------------
@dataclass(frozen=True)
class _Fragments:
    """The visible surface sample of every covered supersampled pixel."""

    pixel: np.ndarray    # (m,) flat index into the (H, W) supersampled image
    vertex: np.ndarray   # (m, 3) vertices whose values are blended
    weight: np.ndarray   # (m, 3) blend weights (barycentric; points: 1, 0, 0)
    shade: np.ndarray    # (m,) Lambert factor


class SoftwareRenderer:
    """NumPy z-buffer renderer (see the module docstring); build it with :func:`renderer`."""

    name = "software"

    def __init__(self, surface: Surface, cam: Camera, size, *, supersample: int = 2,
                 point_size: float | None = None):
        self.surface, self.camera = surface, cam
        self.width, self.height = _check_size(size)
        if not isinstance(supersample, (int, np.integer)) or not 1 <= supersample <= 4:
            raise InputError(f"supersample must be an integer in [1, 4], got {supersample!r}")
        self.supersample = int(supersample)
        if self.width * self.height * self.supersample ** 2 > MAX_SAMPLES:
            raise InputError(f"{self.width}×{self.height} pixels with supersample={self.supersample} need "
                             f"more than {MAX_SAMPLES:,} samples; lower the size or the supersampling")
        self.point_size = _check_point_size(point_size)
        self._fragments: _Fragments | None = None

    def render(self, values=None, scale: ColorScale | None = None) -> Rendering:
        """Draw ``values`` (n,) with ``scale`` (default: :func:`color_scale` of the values), or the
        plain shaded model when ``values`` is None."""
        fragments = self._rasterized()
        if values is None:
            colors = np.broadcast_to(_MODEL_GREY, (len(fragments.pixel), 3))
        else:
            values = _field(self.surface, values)
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
        framing = _Framing(projected[:, :2], width, height)
        xy, depth = framing.pixels(projected[:, :2]), projected[:, 2]
        if self.surface.is_mesh:
            pixel, vertex, weight = _rasterize_triangles(xy, depth, self.surface.faces, width, height)
        else:
            radius = _splat_radius(self.surface, self.point_size, framing.pixels_per_unit, s)
            pixel, vertex, weight = _rasterize_points(xy, depth * framing.pixels_per_unit, radius,
                                                      width, height)
        normals = np.einsum("mk,mkj->mj", weight, self.surface.normals[vertex])
        length = np.linalg.norm(normals, axis=1, keepdims=True)
        normals = np.divide(normals, length, out=np.zeros_like(normals), where=length > 0)
        return _Fragments(pixel, vertex, weight, _lambert(normals, self.camera.light))


def _check_point_size(point_size):
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

    def offer(self, pixel, depth, owner, weights) -> None:
        np.maximum.at(self.depth, pixel, depth)
        nearest = depth >= self.depth[pixel]
        self.owner[pixel[nearest]] = owner[nearest]
        self.weights[pixel[nearest]] = weights[nearest]

    def covered(self):
        pixel = np.flatnonzero(self.owner >= 0)
        return pixel, self.owner[pixel], self.weights[pixel].astype(np.float64)


def _chunks(counts: np.ndarray, budget: int = 2_000_000):
    """Split items into consecutive runs whose counts sum to about ``budget``."""
    ends = np.searchsorted(np.cumsum(counts), np.arange(budget, counts.sum() + budget, budget), side="right")
    start = 0
    for end in np.unique(np.clip(ends, 1, len(counts))):
        if end > start:
            yield slice(start, end)
            start = end


def _expand(low: np.ndarray, span: np.ndarray):
    """Every pixel of each item's box: (item index, column, row) for boxes ``low + [0, span)``."""
    counts = span[:, 0] * span[:, 1]
    item = np.repeat(np.arange(len(counts)), counts)
    local = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
    columns = span[item, 0]
    return item, low[item, 0] + local % columns, low[item, 1] + local // columns


def _rasterize_triangles(xy, depth, faces, width, height):
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


def _rasterize_points(xy, depth, radius: float, width: int, height: int):
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
        keep = (d2 <= radius ** 2) & (column >= 0) & (column < width) & (row >= 0) & (row < height)
        point, column, row = point[keep], column[keep], row[keep]
        bulge = np.sqrt(radius ** 2 - d2[keep])  # a sphere's front: nearer at the disc centre
        buffer.offer(row * width + column, depth[point] + bulge, point, np.zeros((len(point), 2)))
    pixel, point, _ = buffer.covered()
    return pixel, np.repeat(point[:, None], 3, axis=1), np.tile([1.0, 0.0, 0.0], (len(point), 1))


def _splat_radius(surface: Surface, point_size, pixels_per_unit: float, supersample: int) -> float:
    """Disc radius in supersampled pixels: ``point_size / 2`` output pixels, or by default
    0.8 × the median nearest-neighbour spacing (at least one output pixel)."""
    if point_size is not None:
        return max(point_size / 2 * supersample, 0.5)
    from scipy.spatial import cKDTree

    points = surface.vertices
    sample = points[:: max(1, len(points) // 20000)]
    spacing = float(np.median(cKDTree(points).query(sample, k=2)[0][:, 1]))
    return max(0.8 * spacing * pixels_per_unit, 1.0 * supersample)


# -- Open3D renderer ------------------------------------------------------------------------------
@contextlib.contextmanager
def _quiet_stdout():
    """Silence C-level writes to stdout (Filament prints its engine set-up there)."""
    sys.stdout.flush()
    saved = os.dup(1)
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), 1)
            yield
    finally:
        os.dup2(saved, 1)
        os.close(saved)


class _Offscreen:
    """The process's one Open3D ``OffscreenRenderer``.

    Filament aborts the whole process when one of two live offscreen
    renderers is destroyed, so every :class:`Open3DRenderer` borrows this one
    (under the lock) and it is replaced, never duplicated, when the image size
    changes.
    """

    lock = threading.Lock()
    renderer = None
    size: tuple[int, int] | None = None

    @classmethod
    def get(cls, width: int, height: int):
        """The offscreen renderer at this size; call with :attr:`lock` held."""
        if cls.size != (width, height):
            import open3d as o3d
            from open3d.visualization import rendering

            problem = _open3d_problem()
            if problem:
                raise InputError(f"the 'open3d' render backend is unavailable here ({problem}); use "
                                 "backend='software', or install an EGL/Vulkan driver (Debian: "
                                 "libvulkan1 mesa-vulkan-drivers)")
            cls.renderer, cls.size = None, None  # destroy the old one before making the next
            with _quiet_stdout(), o3d.utility.VerbosityContextManager(o3d.utility.VerbosityLevel.Error):
                cls.renderer = rendering.OffscreenRenderer(width, height)
            cls.size = (width, height)
        return cls.renderer


_PROBE = """
import open3d as o3d
o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)
o3d.visualization.rendering.OffscreenRenderer(8, 8)
"""


@functools.lru_cache(maxsize=1)
def _open3d_problem() -> str:
    """Why Open3D cannot render offscreen here ("" when it can), found once per process in a
    child process: without a working EGL/Vulkan driver Filament may abort the process."""
    try:
        probe = subprocess.run([sys.executable, "-c", _PROBE], capture_output=True, text=True, timeout=120)
    except subprocess.TimeoutExpired:
        return "creating an offscreen renderer did not finish in 120 s"
    if probe.returncode == 0:
        return ""
    lines = [line for line in probe.stderr.splitlines() if line.strip()]
    return lines[-1].strip() if lines else f"the probe process exited with code {probe.returncode}"


class Open3DRenderer:
    """Open3D Filament offscreen renderer; build it with :func:`renderer`.

    Raises
    ------
    InputError
        When Open3D cannot create an offscreen renderer here (no EGL/Vulkan).
    """

    name = "open3d"

    def __init__(self, surface: Surface, cam: Camera, size, *, point_size: float | None = None):
        from open3d.visualization import rendering

        self.surface, self.camera = surface, cam
        self.width, self.height = _check_size(size)
        with _Offscreen.lock:
            _Offscreen.get(self.width, self.height)
        projected = cam.project(surface.vertices)
        self._framing = _Framing(projected[:, :2], self.width, self.height)
        self._depth = projected[:, 2]
        self._material = rendering.MaterialRecord()
        self._material.shader = "defaultUnlit"
        self._material.point_size = 2 * _splat_radius(surface, point_size, self._framing.pixels_per_unit, 1)
        self._shade = _lambert(surface.normals, cam.light)

    def _aim(self, offscreen) -> None:
        """White background, no tone mapping, and an orthographic view of the framed box with
        the eye one depth range before the nearest point."""
        from open3d.visualization import rendering

        offscreen.scene.set_background([1.0, 1.0, 1.0, 1.0])
        offscreen.scene.view.set_post_processing(False)
        half = np.array([self.width, self.height]) / (2 * self._framing.pixels_per_unit)
        depth_range = max(float(np.ptp(self._depth)), 1e-9)
        cam, (x, y) = self.camera, self._framing.center
        center = x * cam.right + y * cam.up + self._depth.max() * cam.toward
        offscreen.scene.camera.set_projection(rendering.Camera.Projection.Ortho, -half[0], half[0], -half[1],
                                              half[1], 0.5 * depth_range, 2.5 * depth_range)
        offscreen.scene.camera.look_at(center, center + depth_range * cam.toward, cam.up)

    def render(self, values=None, scale: ColorScale | None = None) -> Rendering:
        """Draw ``values`` (n,) with ``scale`` (default: :func:`color_scale` of the values), or the
        plain shaded model when ``values`` is None."""
        if values is None:
            colors = np.broadcast_to(_MODEL_GREY, (self.surface.n_vertices, 3))
        else:
            values = _field(self.surface, values)
            scale = scale or color_scale(values)
            colors = scale(values)
        geometry = self._geometry(np.clip(colors * self._shade[:, None], 0, 1))
        with _Offscreen.lock:
            offscreen = _Offscreen.get(self.width, self.height)
            self._aim(offscreen)
            offscreen.scene.add_geometry("field", geometry, self._material)
            try:
                image = np.asarray(offscreen.render_to_image(), dtype=np.float64)[..., :3] / 255.0
                depth = np.asarray(offscreen.render_to_depth_image())
            finally:
                offscreen.scene.clear_geometry()
        alpha = (depth < 1.0).astype(np.float64)[..., None]
        return Rendering(np.concatenate([image, alpha], axis=2), scale, self.name)

    def _geometry(self, colors: np.ndarray):
        import open3d as o3d

        vectors = o3d.utility.Vector3dVector
        if self.surface.is_mesh:
            geometry = o3d.geometry.TriangleMesh(vectors(self.surface.vertices),
                                                 o3d.utility.Vector3iVector(self.surface.faces))
            geometry.vertex_colors = vectors(colors)
        else:
            geometry = o3d.geometry.PointCloud(vectors(self.surface.vertices))
            geometry.colors = vectors(colors)
        return geometry


# -- public entry points -------------------------------------------------------------------------
def available_backends() -> list[str]:
    """Renderers that work on this machine: ``"software"`` always; ``"open3d"`` if a child
    process can create an Open3D offscreen renderer (a few seconds, once per process)."""
    return ["software"] + (["open3d"] if not _open3d_problem() else [])


def renderer(surface: Surface, *, view="front", up="y", size=(800, 800), backend: str = "auto",
             supersample: int = 2, point_size: float | None = None):
    """A renderer of ``surface`` from one view; call ``.render(values, scale)`` per field.

    Parameters
    ----------
    surface : Surface
        A mesh or point cloud.
    view, up
        See :func:`camera`.
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
    if backend not in BACKENDS:
        raise InputError(f"unknown render backend {backend!r}; choose one of {BACKENDS}")
    if not isinstance(surface, Surface):
        raise InputError(f"expected a Surface to render, got {type(surface).__name__}")
    cam = camera(view, up)
    if backend == "open3d":
        return Open3DRenderer(surface, cam, size, point_size=point_size)
    return SoftwareRenderer(surface, cam, size, supersample=supersample, point_size=point_size)


def render(surface: Surface, values=None, *, view="front", up="y", size=(800, 800), cmap: str | None = None,
           limits=None, symmetric: bool | None = None, percentiles=(1.0, 99.0), backend: str = "auto",
           supersample: int = 2, point_size: float | None = None) -> Rendering:
    """Render a per-vertex field (or, with ``values=None``, the shaded model) to an RGBA image.

    Parameters
    ----------
    surface : Surface
    values : (n,) array_like, optional
        The field; NaN shows grey.
    view, up, size, backend, supersample, point_size
        See :func:`renderer`.
    cmap, limits, symmetric, percentiles
        See :func:`color_scale`.

    Returns
    -------
    Rendering
    """
    field = None if values is None else _field(surface, values)
    scale = None if field is None else color_scale(field, cmap=cmap, limits=limits, symmetric=symmetric,
                                                   percentiles=percentiles)
    drawer = renderer(surface, view=view, up=up, size=size, backend=backend, supersample=supersample,
                      point_size=point_size)
    return drawer.render(field, scale)


def _field(surface: Surface, values) -> np.ndarray:
    try:
        field = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"{surface.name}: the field to render is not numeric") from None
    if field.shape != (surface.n_vertices,):
        raise InputError(f"{surface.name}: the field to render has shape {field.shape}; expected "
                         f"({surface.n_vertices},), one value per vertex")
    return field


# -- figures with a title and a colour bar ------------------------------------------------------------
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
        See :func:`render`; ``values=None`` shows the shaded model without a colour bar.
    title : str, optional
        Default: the surface name.
    label : str, optional
        Colour bar label (e.g. the quantity and its unit).
    size : (int, int)
        Figure width and height in pixels.
    dpi : float
        Dots per inch (sets the font scale; the pixel size stays ``size``).
    view, up, cmap, limits, symmetric, percentiles, backend, supersample, point_size
        See :func:`render`.
    """
    from matplotlib.figure import Figure

    width, height = _check_size(size)
    _check_dpi(dpi)
    font = font_points(min(width, height), dpi)
    em = font * dpi / 72
    top, pad = 2.4 * em, 0.6 * em
    side = 6.5 * em if values is not None else 0.0
    image_height = max(int(height - top - pad), 1)
    image_width = max(int(min(width - side - 2 * pad, image_height / model_aspect(surface, view, up))), 1)
    left = (width - image_width - side) / 2
    field = None if values is None else _field(surface, values)
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


def model_aspect(surface: Surface, view="front", up="y") -> float:
    """Height / width of the model as seen from a view, kept within [0.5, 2]."""
    extent = np.ptp(camera(view, up).project(surface.vertices)[:, :2], axis=0)
    return float(np.clip(extent[1] / max(extent[0], 1e-300), 0.5, 2.0))


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
