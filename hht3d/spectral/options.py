"""The settings of the Riesz transform and the monogenic signal, and their defaults, in one place.

:class:`RieszOptions` is to :func:`hht3d.spectral.riesz_transform.riesz`,
:func:`hht3d.spectral.monogenic_signal.monogenic`, :func:`hht3d.transform.hht` and their lazy
mirrors in :mod:`hht3d.graph.stages` what :class:`hht3d.decomposition.decompose.EMDOptions` is to
:func:`hht3d.decomposition.decompose.emd`: one frozen record of the settings, whose field
defaults are the functions' keyword defaults (:data:`RIESZ_DEFAULTS`).  The
functions keep their keyword arguments; a default changed here changes them
all, the pipeline parameters (``hht3d ops``) and the JSON Schema.

Examples
--------
>>> from hht3d.spectral.options import RIESZ_DEFAULTS, RieszOptions
>>> RIESZ_DEFAULTS.tol, RIESZ_DEFAULTS.eigenpairs
(1e-08, 300)
>>> RieszOptions(method="spectral").recorded()
{'gradient': 'lsq', 'frequency': 'phase', 'method': 'spectral', 'tol': 1e-08, 'eigenpairs': 300}
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

__all__ = ["RieszOptions", "RIESZ_DEFAULTS", "METHODS", "GRADIENTS", "FREQUENCY_METHODS", "MIN_TOL"]

#: Ways to apply ``L^{-α}`` (:func:`hht3d.spectral.riesz_transform.fractional_laplacian`).
METHODS = ("quadrature", "spectral", "dense")
#: Vertex gradients: Eq. (17) least squares, or area-averaged per-face FEM gradients.
GRADIENTS = ("lsq", "fem")
#: Estimators of Eq. 23 (:func:`hht3d.spectral.frequency.instantaneous_frequency`).
FREQUENCY_METHODS = ("phase", "gradient")
#: Tightest quadrature tolerance: below it round-off in the weights dominates.
MIN_TOL = 1e-13


@dataclass(frozen=True)
class RieszOptions:
    """How ``L^{-1/2}``, the Riesz transform and the monogenic quantities are computed.

    Parameters
    ----------
    gradient : {"lsq", "fem"}
        Vertex gradient of the Riesz transform and of ``∇φ`` (Eq. 17 least
        squares, or area-averaged FEM gradients on meshes).
    frequency : {"phase", "gradient"}
        Estimator of Eq. 23 (:func:`hht3d.spectral.frequency.instantaneous_frequency`).
    method : {"quadrature", "spectral", "dense"}
        How ``L^{-1/2}`` is applied (:func:`hht3d.spectral.riesz_transform.fractional_laplacian`).
    tol : float
        Relative accuracy of the quadrature (checked by
        :func:`hht3d.spectral.riesz_transform.quadrature_nodes`, where it is used).
    eigenpairs : int
        Non-zero eigenpairs of ``method="spectral"`` (the paper uses 300).
    backend : str, optional
        Sparse solver of :mod:`hht3d.linalg.backends.backends`; default the fastest installed.

    Notes
    -----
    A record, not a check: each setting is checked by the function that
    uses it, when it uses it (as before this object existed), so a lazy
    graph fails in the task that needs the setting.
    """

    gradient: str = "lsq"
    frequency: str = "phase"
    method: str = "quadrature"
    tol: float = 1e-8
    eigenpairs: int = 300
    backend: str | None = None

    def recorded(self) -> dict:
        """The settings a result records (``HHTResult.info["riesz"]``): all but the backend."""
        record = asdict(self)
        del record["backend"]
        return record


#: The defaults of every function taking Riesz settings.
RIESZ_DEFAULTS = RieszOptions()
