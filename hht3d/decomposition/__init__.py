"""Empirical mode decomposition on surfaces (Sec. 4.1) and its quality figures."""
from .decompose import (STOPPING_RULES, ENVELOPES, EXTREMA_RULES, GUARD_TENSIONS, PAPER_OPTIONS,
                        RFG_THRESHOLDS, MASS_FLOOR, TIE_RTOL, EMDOptions, EMD_DEFAULTS, EMDResult,
                        local_extrema, extrema_spacing, envelope_operator, EnvelopeSolver,
                        envelope_interpolation, check_emd_options, Sifter, emd, eemd_member, combine_eemd,
                        eemd)
from .quality import (ENERGY_RATIO_LIMIT, ORTHOGONALITY_LIMIT, SPIKE_LIMIT, QualityWarning, Quality,
                      fluctuation, decomposition_quality)
