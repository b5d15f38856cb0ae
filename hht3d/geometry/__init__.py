"""Geometry: the Surface value, mesh cleaning, discrete operators, topology and signals on surfaces."""

from . import cleaning, operators, topology
from .curvature import (
    CAP_ANGLE,
    CLUSTER_AREA_FRACTION,
    MIN_AREA_FRACTION,
    NEEDLE_ANGLE,
    ROUND_OFF_ULPS,
    gaussian_curvature,
    mean_curvature,
    unreliable_vertices,
)
from .normals import FLAT, estimate_point_normals, principal_axes
from .signals import (
    SIGNALS,
    centroid_distance,
    check_signal_path,
    coordinate,
    load_signal,
    luminance,
    signal,
    stored,
)
from .surface import LAPLACIANS, MAX_NEIGHBORS, MIN_VERTICES, Surface, SurfaceOptions
from .validation import as_imfs, as_signals, check_signal, check_surface

__all__ = [
    "FLAT",
    "estimate_point_normals",
    "principal_axes",
    "CAP_ANGLE",
    "CLUSTER_AREA_FRACTION",
    "MIN_AREA_FRACTION",
    "NEEDLE_ANGLE",
    "ROUND_OFF_ULPS",
    "SIGNALS",
    "centroid_distance",
    "check_signal_path",
    "coordinate",
    "gaussian_curvature",
    "load_signal",
    "luminance",
    "mean_curvature",
    "signal",
    "stored",
    "unreliable_vertices",
    "LAPLACIANS",
    "MAX_NEIGHBORS",
    "MIN_VERTICES",
    "Surface",
    "SurfaceOptions",
    "as_imfs",
    "as_signals",
    "check_signal",
    "check_surface",
]
