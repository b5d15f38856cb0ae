"""The Open3D (Filament) offscreen renderer, and whether it can start here (see :mod:`hht3d.viz.render`)."""

from __future__ import annotations

import contextlib
import functools
import os
import subprocess
import sys
import threading
from collections.abc import Iterator
from typing import Any, cast

import numpy as np

from ...errors import InputError
from ...geometry.surface import Surface
from .colors import ColorScale, color_scale
from .image import MODEL_GREY, Framing, Rendering, check_field, check_size, lambert, splat_radius
from .view import Camera

__all__ = ["Open3DRenderer", "open3d_problem"]


@contextlib.contextmanager
def _quiet_stdout() -> Iterator[None]:
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
    renderer: Any = None
    size: tuple[int, int] | None = None

    @classmethod
    def get(cls, width: int, height: int) -> Any:
        """The offscreen renderer at this size; call with :attr:`lock` held."""
        if cls.size != (width, height):
            import open3d as o3d
            from open3d.visualization import rendering

            problem = open3d_problem()
            if problem:
                raise InputError(
                    f"the 'open3d' render backend is unavailable here ({problem}); use "
                    "backend='software', or install an EGL/Vulkan driver (Debian: "
                    "libvulkan1 mesa-vulkan-drivers)"
                )
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
def open3d_problem() -> str:
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
    """Open3D Filament offscreen renderer; build it with :func:`hht3d.viz.render.renderer`.

    Raises
    ------
    InputError
        When Open3D cannot create an offscreen renderer here (no EGL/Vulkan).
    """

    name = "open3d"

    def __init__(
        self, surface: Surface, cam: Camera, size: tuple[int, int], *, point_size: float | None = None
    ) -> None:
        from open3d.visualization import rendering

        self.surface, self.camera = surface, cam
        self.width, self.height = check_size(size)
        with _Offscreen.lock:
            _Offscreen.get(self.width, self.height)
        projected = cam.project(surface.vertices)
        self._framing = Framing(projected[:, :2], self.width, self.height)
        self._depth = projected[:, 2]
        self._material = rendering.MaterialRecord()
        self._material.shader = "defaultUnlit"
        self._material.point_size = 2 * splat_radius(surface, point_size, self._framing.pixels_per_unit, 1)
        self._shade = lambert(surface.normals, cam.light)

    def _aim(self, offscreen: Any) -> None:
        """White background, no tone mapping, and an orthographic view of the framed box with
        the eye one depth range before the nearest point."""
        from open3d.visualization import rendering

        offscreen.scene.set_background([1.0, 1.0, 1.0, 1.0])
        offscreen.scene.view.set_post_processing(False)
        half = np.array([self.width, self.height]) / (2 * self._framing.pixels_per_unit)
        depth_range = max(float(np.ptp(self._depth)), 1e-9)
        cam, (x, y) = self.camera, self._framing.center
        center = x * cam.right + y * cam.up + self._depth.max() * cam.toward
        offscreen.scene.camera.set_projection(
            rendering.Camera.Projection.Ortho,
            -half[0],
            half[0],
            -half[1],
            half[1],
            0.5 * depth_range,
            2.5 * depth_range,
        )
        offscreen.scene.camera.look_at(center, center + depth_range * cam.toward, cam.up)

    def render(self, values: np.ndarray | None = None, scale: ColorScale | None = None) -> Rendering:
        """Draw ``values`` (n,) with ``scale`` (default: :func:`hht3d.viz.render.color_scale` of the values), or the
        plain shaded model when ``values`` is None."""
        if values is None:
            colors = np.broadcast_to(MODEL_GREY, (self.surface.n_vertices, 3))
        else:
            values = check_field(self.surface, values)
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

    def _geometry(self, colors: np.ndarray) -> Any:
        import open3d as o3d

        vectors = o3d.utility.Vector3dVector
        geometry: Any
        if self.surface.is_mesh:
            geometry = o3d.geometry.TriangleMesh(
                vectors(self.surface.vertices), o3d.utility.Vector3iVector(cast(np.ndarray, self.surface.faces))
            )
            geometry.vertex_colors = vectors(colors)
        else:
            geometry = o3d.geometry.PointCloud(vectors(self.surface.vertices))
            geometry.colors = vectors(colors)
        return geometry
