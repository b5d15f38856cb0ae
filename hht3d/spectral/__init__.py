"""Riesz transform (Sec. 4.2, Alg. 1), monogenic signal and Hilbert spectra (Sec. 4.3, Alg. 2)."""
from .options import (METHODS, GRADIENTS, FREQUENCY_METHODS, MIN_TOL, RieszOptions, RIESZ_DEFAULTS)
from .riesz_transform import (DENSE_MAX_VERTICES, SAFETY, remove_kernel, shifted_matrix, shifted_solve,
                              shift_analysis, spectral_bounds, quadrature_nodes, QuadraturePlan,
                              quadrature_plan, quadrature_part, combine_quadrature_parts,
                              smallest_eigenpairs, fractional_laplacian, riesz, vertex_gradient)
from .frequency import (instantaneous_frequency, resolvable_frequency, resolvable_from_area,
                        ResolutionReport, resolution_report)
from .monogenic_signal import (MonogenicSignal, monogenic, monogenic_from_potential)
from .spectrum import (SCALES, HilbertSpectrum)
