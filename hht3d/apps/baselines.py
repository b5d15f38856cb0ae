"""Baselines the paper compares with (Figs. 6 and 8).

* :func:`imf_enhancement` — Hu et al. (2014): scale the first IMF of the
  mean-curvature signal by a factor, then reconstruct (Fig. 6b).
* :func:`manifold_harmonics_filter` — Vallet & Lévy (2008): filter the
  vertex coordinates in the Laplacian eigenbasis with a gain of the
  eigen-frequency (Fig. 6d).
* :func:`heat_kernel_signature` and :func:`hks_features` — Sun et al.
  (2009): feature points as local maxima of the heat kernel signature
  (Fig. 8).

Eigenpairs are the smallest non-zero ones of ``L φ = λ M φ`` from
:func:`hht3d.spectral.riesz_transform.smallest_eigenpairs` (shift-invert Lanczos, cached on the
surface).  An eigenfunction with eigenvalue ``λ`` oscillates like
``cos(ω x)`` with ``ω = √λ`` radians per unit length, the unit of the
instantaneous frequency of :mod:`hht3d.spectral.monogenic_signal`, so the gains of
:mod:`hht3d.apps.filters` apply to both filters unchanged.
"""

from __future__ import annotations

import math
import numbers
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..decomposition.extrema import local_extrema
from ..decomposition.options import MAX_IMFS
from ..errors import HHT3DDeprecationWarning, InputError
from ..geometry.signals import fluctuation
from ..geometry.surface import Surface
from ..geometry.validation import as_imfs, check_surface
from ..records import Record, option
from ..spectral.eigenpairs import smallest_eigenpairs
from ..spectral.options import RieszOptions
from .features import FeatureOptions, FeatureResult, features_from_counts
from .filters import evaluate_gain
from .reconstruction import ReconstructionOptions, reconstruct_from_change

__all__ = [
    "EnhancementOptions",
    "HarmonicFilterOptions",
    "HKSOptions",
    "imf_enhancement",
    "manifold_harmonics_filter",
    "heat_kernel_signature",
    "hks_features",
    "HKS_TIME_FRACTION",
    "MAX_FACTOR",
]

#: Default HKS time as a fraction of ``t_max = 4 ln 10 / λ_1`` (Sun et al. 2009).
HKS_TIME_FRACTION = 0.1
#: IMF factor of the enhancement baseline (far above useful values; stops a typo).
MAX_FACTOR = 1e3
_EIGENPAIRS = RieszOptions.specs()["eigenpairs"]


@dataclass(frozen=True)
class EnhancementOptions(ReconstructionOptions):
    """The settings of :func:`imf_enhancement`: the IMF and its factor, and the reconstruction's."""

    label = "IMF enhancement"

    factor: float = option(2.5, "multiply the IMF by this", minimum=-MAX_FACTOR, maximum=MAX_FACTOR)
    index: int = option(0, "which IMF, from 0 (the finest)", minimum=0, maximum=MAX_IMFS - 1)


@dataclass(frozen=True)
class HarmonicFilterOptions(Record):
    """The settings of :func:`manifold_harmonics_filter`."""

    label = "manifold harmonics"

    eigenpairs: int = option(300, "Laplacian eigenpairs of the basis", like=_EIGENPAIRS)
    keep_remainder: bool = option(True, "keep the part of the shape beyond the basis")


@dataclass(frozen=True)
class HKSOptions(Record):
    """The settings of :func:`hks_features` (and the ``eigenpairs`` of :func:`heat_kernel_signature`)."""

    label = "HKS"

    time: float | None = option(
        None, "diffusion time (default: a fraction of 4 ln 10 / λ1)", kind="float", minimum=0, open_minimum=True
    )
    eigenpairs: int = option(100, "eigenpairs in the heat-kernel sum", like=_EIGENPAIRS)
    ring: int = option(2, "neighbourhood in edges", like=FeatureOptions.specs()["ring"])
    merge_radius: float | None = option(
        None, "merge maxima closer than this (model units)", like=FeatureOptions.specs()["merge_radius"]
    )


def imf_enhancement(
    surface: Surface,
    imfs: np.ndarray,
    options: EnhancementOptions | dict | None = None,
    *,
    weights: np.ndarray | None = None,
    backend: str | None = None,
    name: str | None = None,
    **overrides: Any,
) -> Surface:
    """Hu et al. (2014): multiply one IMF of the mean curvature by ``factor`` and reconstruct.

    The signal becomes ``s' = s + (factor − 1) f_index`` everywhere, whatever
    the local frequency (the global processing the paper contrasts with
    Eq. 26); the geometry follows by Eq. (27)
    (:func:`~hht3d.apps.reconstruction.reconstruct_from_change`).

    Parameters
    ----------
    surface : Surface
    imfs : (k, n) array_like, EMDResult or HHTResult
        IMFs of ``mean_curvature(surface)``.
    options : EnhancementOptions or dict, optional
        ``factor`` (default 2.5, the paper's Fig. 6b; formerly the third
        positional argument, still accepted as a number for one release with a
        DeprecationWarning), ``index`` (which IMF, from 0, the finest, IMF1)
        and the settings of :func:`~hht3d.apps.reconstruction.reconstruct_from_change`.
    weights, backend, name
        See :func:`~hht3d.apps.reconstruction.reconstruct_from_change`.
    **overrides
        Settings that replace those of ``options``.

    Returns
    -------
    Surface
    """
    if isinstance(options, numbers.Real):
        warnings.warn(
            f"imf_enhancement(surface, imfs, {options!r}) is deprecated; write factor={options!r}",
            HHT3DDeprecationWarning,
            stacklevel=2,
        )
        options = {"factor": options}
    options = EnhancementOptions.of(options, **overrides)
    surface = check_surface(surface)
    f = as_imfs(surface, imfs)
    if not options.index < len(f):
        raise InputError(f"IMF index must be an integer in [0, {len(f)}), got {options.index!r}")
    reconstruction = ReconstructionOptions.of({k: getattr(options, k) for k in ReconstructionOptions.specs()})
    return reconstruct_from_change(
        surface, (options.factor - 1.0) * f[options.index], reconstruction, weights=weights, backend=backend, name=name
    )


def manifold_harmonics_filter(
    surface: Surface,
    gain: Callable[[np.ndarray], Any],
    options: HarmonicFilterOptions | dict | None = None,
    *,
    backend: str | None = None,
    name: str | None = None,
    **overrides: Any,
) -> Surface:
    """Vallet & Lévy (2008): filter the coordinates in the manifold-harmonic basis.

    With M-orthonormal eigenvectors ``φ_j`` (``L φ_j = λ_j M φ_j``) and
    coefficients ``c_j = φ_jᵀ M V``,

        V' = V + Σ_j (μ(√λ_j) − 1) φ_j c_j         (keep_remainder=True)
        V' = V̄ + Σ_j μ(√λ_j) φ_j c_j                (keep_remainder=False)

    over the ``eigenpairs`` smallest non-zero eigenvalues.  ``V̄`` is the
    area-weighted centroid of each connected component (the kernel part),
    which is never filtered.  The default keeps the part of ``V`` beyond
    the computed band unchanged (gain 1 above the band); Vallet & Lévy's
    truncated synthesis (``keep_remainder=False``) also drops it, a
    low-pass at ``√λ_p``.

    Parameters
    ----------
    surface : Surface
    gain : callable
        ``μ(ω)`` with ``ω = √λ`` (e.g. :class:`~hht3d.apps.filters.BandBoost`).
    options : HarmonicFilterOptions or dict, optional
        ``eigenpairs`` (default 300, the paper's choice for Eq. 18) and ``keep_remainder``.
    backend : str, optional
        Sparse solver for the eigensolver's shift-invert.
    name : str, optional
        Default ``"<name>_mhb"``.
    **overrides
        Settings that replace those of ``options``.

    Returns
    -------
    Surface
    """
    options = HarmonicFilterOptions.of(options, **overrides)
    surface = check_surface(surface)
    values, vectors = smallest_eigenpairs(surface, options.eigenpairs, backend=backend)
    mu = evaluate_gain(gain, np.sqrt(values))
    v = surface.vertices
    coefficients = vectors.T @ (surface.mass_diagonal[:, None] * v)  # (p, 3)
    if options.keep_remainder:
        new = v + vectors @ ((mu - 1.0)[:, None] * coefficients)
    else:
        centroid = v - fluctuation(surface, v.T).T
        new = centroid + vectors @ (mu[:, None] * coefficients)
    return Surface(
        new,
        surface.faces,
        colors=surface.colors,
        attributes=dict(surface.attributes),
        laplacian=surface.laplacian,
        n_neighbors=surface.n_neighbors,
        name=name or f"{surface.name}_mhb",
        origin=surface.origin,
        header=surface.header,
    )


def heat_kernel_signature(
    surface: Surface, times: float | np.ndarray, *, eigenpairs: int = 100, backend: str | None = None
) -> np.ndarray:
    """Heat kernel signature ``k_t(x, x) = Σ_i e^{−λ_i t} φ_i(x)²`` (Sun et al. 2009).

    The sum runs over the kernel (``φ_0² = 1/area`` of the component) and
    the ``eigenpairs`` smallest non-zero eigenpairs; the truncation error at
    a vertex is below ``e^{−λ_p t}`` times the remaining ``Σ φ_i(x)²``, small
    for the large times used for feature detection.

    Parameters
    ----------
    surface : Surface
    times : float or (T,) array_like
        Diffusion times (> 0), in squared model units.
    eigenpairs : int
    backend : str, optional

    Returns
    -------
    (T, n) ndarray (``(n,)`` for a scalar ``times``)
    """
    surface = check_surface(surface)
    t = np.asarray(times, dtype=np.float64)
    if t.ndim > 1 or t.size == 0 or not np.all(np.isfinite(t)) or np.any(t <= 0):
        raise InputError(f"HKS times must be positive finite numbers, got {times!r}")
    values, vectors = smallest_eigenpairs(surface, HKSOptions.check("eigenpairs", eigenpairs), backend=backend)
    labels = surface.component_labels
    component_area = np.bincount(labels, weights=surface.mass_diagonal)
    hks = np.exp(-np.outer(np.atleast_1d(t), values)) @ (vectors**2).T + 1.0 / component_area[labels]
    return hks[0] if t.ndim == 0 else hks


def hks_features(
    surface: Surface, options: HKSOptions | dict | None = None, *, backend: str | None = None, **overrides: Any
) -> FeatureResult:
    """Sun et al. (2009): feature points as the local maxima of the HKS at one time.

    A vertex is a feature when its ``k_t(x, x)`` is at least that of every
    vertex in its ``ring``-ring and larger than one of them
    (:func:`hht3d.decomposition.local_extrema`, ``extrema="relaxed"`` with ``ratio=1``).

    Parameters
    ----------
    surface : Surface
    options : HKSOptions or dict, optional
        ``time``: diffusion time; default ``HKS_TIME_FRACTION · 4 ln 10 / λ_1``,
        a fraction of the largest time of Sun et al.'s range, which scales with
        the model (so the features do not depend on its size).  ``eigenpairs``:
        eigenpairs in the HKS sum (default 100).  ``ring``: neighbourhood in
        edges (default 2, as Sun et al.).  ``merge_radius``: merge maxima closer
        than this (model units), keeping the largest HKS.
    backend : str, optional
    **overrides
        Settings that replace those of ``options``.

    Returns
    -------
    FeatureResult
        One scale: ``maxima[0]`` are the local maxima, ``minima[0]`` is
        empty, ``counts`` are 1.
    """
    options = HKSOptions.of(options, **overrides)
    surface = check_surface(surface)
    time = options.time
    if time is None:
        values, _ = smallest_eigenpairs(surface, options.eigenpairs, backend=backend)
        time = HKS_TIME_FRACTION * 4.0 * math.log(10.0) / float(values[0])
    hks = heat_kernel_signature(surface, time, eigenpairs=options.eigenpairs, backend=backend)
    maxima, _ = local_extrema(surface, hks, extrema="relaxed", ring=options.ring, ratio=1.0)
    return features_from_counts(surface, [maxima], [np.empty(0, dtype=np.int64)], 1, options.merge_radius, scores=hks)
