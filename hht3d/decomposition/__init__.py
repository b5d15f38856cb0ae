"""Empirical mode decomposition on surfaces (Sec. 4.1) and its quality figures.

Data flow: :mod:`.extrema` → :mod:`.envelopes` → :mod:`.sifting` →
:mod:`.decompose` (:func:`emd`) → :mod:`.ensemble` (:func:`eemd`), with the
settings in :mod:`.options` and the figures in :mod:`.quality`.
"""

from . import options
from .decompose import EMDResult, emd
from .ensemble import combine_eemd, eemd, eemd_member
from .envelopes import EnvelopeSolver, envelope_interpolation, envelope_operator
from .extrema import extrema_spacing, local_extrema
from .options import (
    CUTS,
    EMD_DEFAULTS,
    ENSEMBLE_DEFAULTS,
    ENVELOPES,
    EVALUATIONS,
    EXTREMA_RULES,
    FILTERING_OPTIONS,
    FILTERS,
    GUARD_TENSIONS,
    METHODS,
    MULTIRESOLUTION,
    PAPER_OPTIONS,
    STOPPING_RULES,
    EMDOptions,
    EnsembleOptions,
    start_tension,
)
from .quality import (
    ALIASED_AREA_LIMIT,
    DOMINANT_SHARE_LIMIT,
    ENERGY_RATIO_LIMIT,
    LEAKAGE_LIMIT,
    ORTHOGONALITY_LIMIT,
    SPIKE_LIMIT,
    Quality,
    QualityWarning,
)

__all__ = [
    "EMDResult",
    "emd",
    "eemd",
    "eemd_member",
    "combine_eemd",
    "local_extrema",
    "extrema_spacing",
    "envelope_operator",
    "envelope_interpolation",
    "EnvelopeSolver",
    "Quality",
    "QualityWarning",
    "ENERGY_RATIO_LIMIT",
    "ORTHOGONALITY_LIMIT",
    "LEAKAGE_LIMIT",
    "SPIKE_LIMIT",
    "DOMINANT_SHARE_LIMIT",
    "ALIASED_AREA_LIMIT",
]
__all__ += options.__all__  # the settings, their presets and choices
