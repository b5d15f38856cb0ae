"""Applications of the Hilbert–Huang transform on surfaces (Sec. 5).

* :mod:`~hht3d.apps.filters` — gains ``μ(ω)`` and Hilbert-spectrum filtering
  of a signal (Eq. 26);
* :mod:`~hht3d.apps.reconstruction` — new vertex positions from a filtered
  mean-curvature signal (Eq. 27);
* :mod:`~hht3d.apps.geometry_filter` — both steps in one call, the weights following the gain;
* :mod:`~hht3d.apps.features` — prominent feature points from IMF extrema
  statistics (Sec. 5.2);
* :mod:`~hht3d.apps.baselines` — the methods the paper compares with: IMF1
  enhancement (Hu et al. 2014), manifold-harmonics filtering (Vallet & Lévy
  2008) and heat-kernel-signature features (Sun et al. 2009).

A band-stop of the Hilbert spectrum moves vertices and keeps the faces
(Eqs. 26-27); prominent features are vertices of the mesh (Sec. 5.2):

>>> import numpy as np
>>> from hht3d import data_path, hht, load
>>> from hht3d.geometry.signals import mean_curvature
>>> from hht3d.apps import BandStop, filter_geometry, prominent_features
>>> surface = load(data_path("spot.ply"))
>>> result = hht(surface, mean_curvature(surface), max_imfs=3)
>>> smooth = filter_geometry(result, BandStop(low=40.0, high=120.0, width=10.0))  # a Surface
>>> bool(np.abs(smooth.vertices - surface.vertices).max() > 0), np.array_equal(smooth.faces, surface.faces)
(True, True)
>>> features = prominent_features(surface, result.imfs)   # features.vertices, features.counts
>>> bool(set(features.vertices) <= set(range(surface.n_vertices)))
True
"""

from .baselines import (
    HKS_TIME_FRACTION,
    EnhancementOptions,
    HarmonicFilterOptions,
    HKSOptions,
    heat_kernel_signature,
    hks_features,
    imf_enhancement,
    manifold_harmonics_filter,
)
from .features import (
    FEATURE_EMD_OPTIONS,
    FeatureOptions,
    FeatureResult,
    features_from_counts,
    merge_hits,
    prominent_features,
    repeatability,
)
from .filters import (
    GAINS,
    BandBoost,
    BandStop,
    Constant,
    Gain,
    HighBoost,
    LowPass,
    PiecewiseLinear,
    filter_signal,
    gains_of,
    make_gain,
)
from .geometry_filter import FilterOptions, automatic_weight, edit_frequency, filter_geometry
from .reconstruction import (
    BOUNDARY_WEIGHT,
    INTERIOR_WEIGHT,
    ReconstructionOptions,
    check_mean_curvature_signal,
    position_weights,
    reconstruct,
    reconstruct_from_change,
)

__all__ = [
    # filters (Eq. 26)
    "Gain",
    "Constant",
    "LowPass",
    "HighBoost",
    "BandStop",
    "BandBoost",
    "PiecewiseLinear",
    "GAINS",
    "make_gain",
    "gains_of",
    "filter_signal",
    # reconstruction (Eq. 27)
    "ReconstructionOptions",
    "FilterOptions",
    "INTERIOR_WEIGHT",
    "BOUNDARY_WEIGHT",
    "position_weights",
    "reconstruct",
    "reconstruct_from_change",
    "check_mean_curvature_signal",
    "filter_geometry",
    "edit_frequency",
    "automatic_weight",
    # features (Sec. 5.2)
    "FeatureOptions",
    "FEATURE_EMD_OPTIONS",
    "FeatureResult",
    "prominent_features",
    "features_from_counts",
    "merge_hits",
    "repeatability",
    # baselines
    "EnhancementOptions",
    "HarmonicFilterOptions",
    "HKSOptions",
    "imf_enhancement",
    "manifold_harmonics_filter",
    "heat_kernel_signature",
    "hks_features",
    "HKS_TIME_FRACTION",
]
