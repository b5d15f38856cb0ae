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

import numpy as np

from ..decomposition.extrema import local_extrema
from ..errors import InputError
from ..geometry.signals import fluctuation
from ..spectral.eigenpairs import smallest_eigenpairs
from ..geometry.surface import Surface
from ..geometry.validation import as_imfs, check_distance, check_surface, finite
from .features import FeatureResult, features_from_counts
from .filters import evaluate_gain
from .reconstruction import BOUNDARY_WEIGHT, INTERIOR_WEIGHT, reconstruct_from_change

__all__ = [
    "imf_enhancement",
    "manifold_harmonics_filter",
    "heat_kernel_signature",
    "hks_features",
    "HKS_TIME_FRACTION",
]

#: Default HKS time as a fraction of ``t_max = 4 ln 10 / λ_1`` (Sun et al. 2009).
HKS_TIME_FRACTION = 0.1


def imf_enhancement(surface: Surface, imfs, factor: float = 2.5, *, index: int = 0,
                    interior_weight: float = INTERIOR_WEIGHT, boundary_weight: float = BOUNDARY_WEIGHT,
                    weights=None, backend: str | None = None, name: str | None = None,
                    preserve_scale: bool = True) -> Surface:
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
    factor : float
        Default 2.5 (the paper's Fig. 6b).
    index : int
        Which IMF, from 0 (the finest, IMF1).
    interior_weight, boundary_weight, weights, backend, name, preserve_scale
        See :func:`~hht3d.apps.reconstruction.reconstruct_from_change`.

    Returns
    -------
    Surface
    """
    surface = check_surface(surface)
    f = as_imfs(surface, imfs)
    factor = finite("factor", factor)
    if int(index) != index or not 0 <= index < len(f):
        raise InputError(f"IMF index must be an integer in [0, {len(f)}), got {index!r}")
    return reconstruct_from_change(surface, (factor - 1.0) * f[int(index)], interior_weight=interior_weight,
                                   boundary_weight=boundary_weight, weights=weights, backend=backend,
                                   name=name, preserve_scale=preserve_scale)


def _check_count(eigenpairs) -> int:
    if isinstance(eigenpairs, bool) or int(eigenpairs) != eigenpairs or eigenpairs < 1:
        raise InputError(f"eigenpairs must be a positive integer, got {eigenpairs!r}")
    return int(eigenpairs)


def manifold_harmonics_filter(surface: Surface, gain, *, eigenpairs: int = 300, keep_remainder: bool = True,
                              backend: str | None = None, name: str | None = None) -> Surface:
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
    eigenpairs : int
        Number of eigenpairs (default 300, the paper's choice for Eq. 18).
    keep_remainder : bool
    backend : str, optional
        Sparse solver for the eigensolver's shift-invert.
    name : str, optional
        Default ``"<name>_mhb"``.

    Returns
    -------
    Surface
    """
    surface = check_surface(surface)
    values, vectors = smallest_eigenpairs(surface, _check_count(eigenpairs), backend=backend)
    mu = evaluate_gain(gain, np.sqrt(values))
    v = surface.vertices
    coefficients = vectors.T @ (surface.mass_diagonal[:, None] * v)  # (p, 3)
    if keep_remainder:
        new = v + vectors @ ((mu - 1.0)[:, None] * coefficients)
    else:
        centroid = v - fluctuation(surface, v.T).T
        new = centroid + vectors @ (mu[:, None] * coefficients)
    return Surface(new, surface.faces, colors=surface.colors, attributes=dict(surface.attributes),
                   laplacian=surface.laplacian, n_neighbors=surface.n_neighbors,
                   name=name or f"{surface.name}_mhb")


def heat_kernel_signature(surface: Surface, times, *, eigenpairs: int = 100,
                          backend: str | None = None) -> np.ndarray:
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
    values, vectors = smallest_eigenpairs(surface, _check_count(eigenpairs), backend=backend)
    labels = surface.component_labels
    component_area = np.bincount(labels, weights=surface.mass_diagonal)
    hks = np.exp(-np.outer(np.atleast_1d(t), values)) @ (vectors ** 2).T + 1.0 / component_area[labels]
    return hks[0] if t.ndim == 0 else hks


def hks_features(surface: Surface, *, time: float | None = None, eigenpairs: int = 100, ring: int = 2,
                 merge_radius: float | None = None, backend: str | None = None) -> FeatureResult:
    """Sun et al. (2009): feature points as the local maxima of the HKS at one time.

    A vertex is a feature when its ``k_t(x, x)`` is at least that of every
    vertex in its ``ring``-ring and larger than one of them
    (:func:`hht3d.decomposition.local_extrema`, ``rule="strict"``).

    Parameters
    ----------
    surface : Surface
    time : float, optional
        Diffusion time; default ``HKS_TIME_FRACTION · 4 ln 10 / λ_1``, a
        fraction of the largest time of Sun et al.'s range, which scales
        with the model (so the features do not depend on its size).
    eigenpairs : int
        Eigenpairs in the HKS sum (default 100).
    ring : int
        Neighbourhood in edges (default 2, as Sun et al.).
    merge_radius : float, optional
        Merge maxima closer than this (model units), keeping the largest HKS.
    backend : str, optional

    Returns
    -------
    FeatureResult
        One scale: ``maxima[0]`` are the local maxima, ``minima[0]`` is
        empty, ``counts`` are 1.
    """
    surface = check_surface(surface)
    check_distance("merge_radius", merge_radius)
    count = _check_count(eigenpairs)
    if time is None:
        values, _ = smallest_eigenpairs(surface, count, backend=backend)
        time = HKS_TIME_FRACTION * 4.0 * math.log(10.0) / float(values[0])
    hks = heat_kernel_signature(surface, finite("time", time), eigenpairs=count, backend=backend)
    maxima, _ = local_extrema(surface, hks, rule="strict", ring=ring)
    return features_from_counts(surface, [maxima], [np.empty(0, dtype=np.int64)], 1, merge_radius,
                                scores=hks)
