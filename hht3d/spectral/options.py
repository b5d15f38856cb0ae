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
>>> RieszOptions.of(potential="spectral").as_dict()
{'gradient': 'lsq', 'frequency': 'phase', 'potential': 'spectral', 'tol': 1e-08, 'eigenpairs': 300}
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any

from ..errors import HHT3DDeprecationWarning
from ..records import Record, option

__all__ = [
    "RieszOptions",
    "RIESZ_DEFAULTS",
    "POTENTIALS",
    "GRADIENTS",
    "FREQUENCY_METHODS",
    "MIN_TOL",
    "MAX_EIGENPAIRS",
]

#: Ways to apply ``L^{-α}``, the potential (:func:`hht3d.spectral.riesz_transform.fractional_laplacian`).
POTENTIALS = ("quadrature", "spectral", "dense")
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
    (:func:`hht3d.spectral.frequency.instantaneous_frequency`); ``potential``:
    how ``L^{-1/2}`` is applied
    (:func:`hht3d.spectral.riesz_transform.fractional_laplacian`; formerly
    ``method``, still accepted by :meth:`of` with a DeprecationWarning);
    ``tol``: relative tolerance of the quadrature; ``eigenpairs``: non-zero
    eigenpairs of ``potential="spectral"``.
    """

    label = "Riesz"
    renamed = {"method": "potential"}

    gradient: str = option("lsq", "tangent gradient of the monogenic signal", choices=GRADIENTS)
    frequency: str = option(
        "phase",
        "frequency method of Eq. 23: edge phase increments (exact for plane waves up "
        "to the resolution limit) or the paper's gradients",
        choices=FREQUENCY_METHODS,
    )
    potential: str = option(
        "quadrature", "L^{-1/2}: exact quadrature, spectral truncation or dense", choices=POTENTIALS
    )
    tol: float = option(1e-8, "relative tolerance of the quadrature", minimum=MIN_TOL, maximum=1, open_maximum=True)
    eigenpairs: int = option(300, "eigenpairs of potential: spectral", minimum=1, maximum=MAX_EIGENPAIRS)


#: The defaults of every function taking Riesz settings.
RIESZ_DEFAULTS = RieszOptions()


def __getattr__(name: str) -> Any:
    """``METHODS``, the former name of :data:`POTENTIALS`, for one release."""
    if name == "METHODS":
        warnings.warn("hht3d.spectral.METHODS is now POTENTIALS", HHT3DDeprecationWarning, stacklevel=2)
        return POTENTIALS
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
