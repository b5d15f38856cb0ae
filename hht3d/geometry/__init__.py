"""Geometry: the Surface value, mesh cleaning, discrete operators, topology and signals on surfaces."""
from .normals import FLAT, estimate_point_normals, principal_axes
from .surface import MIN_VERTICES, LAPLACIANS, MAX_NEIGHBORS, Surface, SurfaceOptions
from . import cleaning
from . import operators
from . import topology
from .signals import (MIN_AREA_FRACTION, CLUSTER_AREA_FRACTION, ROUND_OFF_ULPS, NEEDLE_ANGLE, CAP_ANGLE,
                      unreliable_vertices, mean_curvature, gaussian_curvature, centroid_distance, coordinate,
                      luminance, stored, check_signal_path, load_signal, SIGNALS, signal)
from .validation import check_surface, check_signal, as_signals, as_imfs
