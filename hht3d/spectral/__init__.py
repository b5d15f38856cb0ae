"""Riesz transform (Sec. 4.2, Alg. 1), monogenic signal and Hilbert spectra (Sec. 4.3, Alg. 2).

Data flow: :mod:`.shifts` and :mod:`.eigenpairs` → :mod:`.quadrature` →
:mod:`.riesz_transform` (:func:`fractional_laplacian`, :func:`riesz`) →
:mod:`.frequency` → :mod:`.monogenic_signal` (:func:`monogenic`) →
:mod:`.spectrum`, with the settings in :mod:`.options`; :mod:`.multilevel` takes the Riesz
transform of each IMF of iterative filtering on its level of the hierarchy.
"""

from .eigenpairs import DENSE_MAX_VERTICES, dense_eigenpairs, smallest_eigenpairs, spectral_bounds
from .frequency import instantaneous_frequency
from .monogenic_signal import MonogenicSignal, monogenic, monogenic_from_potential, monogenic_from_riesz
from .options import (
    FREQUENCY_METHODS,
    GRADIENTS,
    POTENTIALS,
    RIESZ_DEFAULTS,
    RieszOptions,
    __getattr__,  # noqa: F401  (the former name METHODS)
)
from .quadrature import QuadraturePlan, combine_quadrature_parts, quadrature_nodes, quadrature_part, quadrature_plan
from .resolution import resolution_report, resolvable_frequency
from .riesz_transform import fractional_laplacian, riesz, vertex_gradient
from .spectrum import HilbertSpectrum

__all__ = [
    "fractional_laplacian",
    "riesz",
    "vertex_gradient",
    "monogenic",
    "monogenic_from_potential",
    "monogenic_from_riesz",
    "MonogenicSignal",
    "HilbertSpectrum",
    "RieszOptions",
    "RIESZ_DEFAULTS",
    "POTENTIALS",
    "GRADIENTS",
    "FREQUENCY_METHODS",
    "instantaneous_frequency",
    "resolvable_frequency",
    "resolution_report",
    "spectral_bounds",
    "smallest_eigenpairs",
    "dense_eigenpairs",
    "DENSE_MAX_VERTICES",
    "quadrature_nodes",
    "QuadraturePlan",
    "quadrature_plan",
    "quadrature_part",
    "combine_quadrature_parts",
]
