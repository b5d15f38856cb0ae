"""The settings of the Riesz transform and the monogenic signal, checked once.

:class:`RieszOptions` is to :func:`~hht3d.spectral.riesz`,
:func:`~hht3d.spectral.monogenic`, :func:`~hht3d.transform.hht` and their
lazy twins in :mod:`hht3d.graph` what
:class:`~hht3d.decomposition.options.EMDOptions` is to EMD: one frozen,
validated record whose fields declare their range and description
(:mod:`hht3d.records`); the pipeline's parameters and the JSON Schema read
them.  The sparse-solver ``backend`` is passed apart.

Examples
--------
>>> from hht3d.spectral.options import RIESZ_DEFAULTS, RieszOptions
>>> RIESZ_DEFAULTS.tol, RIESZ_DEFAULTS.eigenpairs
(1e-08, 300)
>>> RieszOptions.of(method="spectral").as_dict()
{'gradient': 'lsq', 'frequency': 'phase', 'method': 'spectral', 'tol': 1e-08, 'eigenpairs': 300}
"""
from __future__ import annotations

from dataclasses import dataclass

from ..records import Record, option

__all__ = ["RieszOptions", "RIESZ_DEFAULTS", "METHODS", "GRADIENTS", "FREQUENCY_METHODS", "MIN_TOL",
           "MAX_EIGENPAIRS"]

#: Ways to apply ``L^{-α}`` (:func:`hht3d.spectral.riesz_transform.fractional_laplacian`).
METHODS = ("quadrature", "spectral", "dense")
#: Vertex gradients: Eq. (17) least squares, or area-averaged per-face FEM gradients.
GRADIENTS = ("lsq", "fem")
#: Estimators of Eq. 23 (:func:`hht3d.spectral.frequency.instantaneous_frequency`).
FREQUENCY_METHODS = ("phase", "gradient")
#: Tightest quadrature tolerance: below it round-off in the weights dominates.
MIN_TOL = 1e-13
#: Laplacian eigenpairs (the paper uses 300); the eigenvectors are a dense (vertices, eigenpairs) block.
MAX_EIGENPAIRS = 2000


@dataclass(frozen=True)
class RieszOptions(Record):
    """How ``L^{-1/2}``, the Riesz transform and the monogenic quantities are computed.

    ``gradient``: vertex gradient of the Riesz transform and of ``∇φ``
    (Eq. 17 least squares, or area-averaged FEM gradients on meshes);
    ``frequency``: estimator of Eq. 23
    (:func:`hht3d.spectral.frequency.instantaneous_frequency`); ``method``:
    how ``L^{-1/2}`` is applied
    (:func:`hht3d.spectral.riesz_transform.fractional_laplacian`); ``tol``:
    relative accuracy of the quadrature; ``eigenpairs``: non-zero eigenpairs
    of ``method="spectral"``.
    """

    label = "Riesz"

    gradient: str = option("lsq", "tangent gradient of the monogenic signal", choices=GRADIENTS)
    frequency: str = option("phase", "Eq. 23 estimator: edge phase increments (exact for plane waves up to the "
                            "resolution limit) or the paper's gradients", choices=FREQUENCY_METHODS)
    method: str = option("quadrature", "L^{-1/2}: exact quadrature, spectral truncation or dense",
                         choices=METHODS)
    tol: float = option(1e-8, "relative accuracy of the quadrature", minimum=MIN_TOL, maximum=1,
                        open_maximum=True)
    eigenpairs: int = option(300, "eigenpairs of method: spectral", minimum=1, maximum=MAX_EIGENPAIRS)


#: The defaults of every function taking Riesz settings.
RIESZ_DEFAULTS = RieszOptions()
