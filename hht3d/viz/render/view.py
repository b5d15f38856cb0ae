"""The orthographic camera: named views, up axes, projection and the light beside the eye."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ...errors import InputError
from ...geometry.surface import Surface

__all__ = ["VIEWS", "UP_AXES", "Camera", "camera", "model_aspect"]

#: Named views as ``(azimuth, elevation)`` in degrees.  Azimuth turns the eye about the up
#: axis towards the model's right (as seen in the front view); elevation raises it.
VIEWS = {
    "front": (0.0, 0.0),
    "back": (180.0, 0.0),
    "right": (90.0, 0.0),
    "left": (-90.0, 0.0),
    "top": (0.0, 90.0),
    "bottom": (0.0, -90.0),
}
#: Named up axes.  The front view looks at the model from +z (up ±x or ±y) or from −y (up ±z).
UP_AXES = ("x", "y", "z", "-x", "-y", "-z")


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


def camera(view: str | Sequence[float] = "front", up: str | Sequence[float] = "y") -> Camera:
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


def _view_angles(view: str | Sequence[float]) -> tuple[float, float]:
    if isinstance(view, str):
        if view not in VIEWS:
            raise InputError(
                f"unknown view {view!r}; choose one of {', '.join(VIEWS)} or give (azimuth, elevation) in degrees"
            )
        return VIEWS[view]
    try:
        azimuth, elevation = (float(a) for a in view)
    except (TypeError, ValueError):
        raise InputError(
            f"view must be a name ({', '.join(VIEWS)}) or (azimuth, elevation) in degrees, got {view!r}"
        ) from None
    if not (np.isfinite(azimuth) and np.isfinite(elevation)):
        raise InputError(f"view angles must be finite, got {view!r}")
    return azimuth, elevation


def _up_vector(up: str | Sequence[float]) -> np.ndarray:
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


def model_aspect(surface: Surface, view: str | Sequence[float] = "front", up: str | Sequence[float] = "y") -> float:
    """Height / width of the model as seen from a view, kept within [0.5, 2]."""
    extent = np.ptp(camera(view, up).project(surface.vertices)[:, :2], axis=0)
    return float(np.clip(extent[1] / max(extent[0], 1e-300), 0.5, 2.0))
