"""Local extrema of a per-vertex signal and their mean spacing (Sec. 4.1, Sec. 5.2).

Examples
--------
>>> import numpy as np
>>> from hht3d import Surface
>>> from hht3d.decomposition.extrema import local_extrema
>>> grid = np.stack(np.meshgrid(np.arange(5.0), np.arange(5.0)), -1).reshape(-1, 2)
>>> faces = np.array([[i * 5 + j, i * 5 + j + 1, i * 5 + j + 6] for i in range(4) for j in range(4)]
...                  + [[i * 5 + j, i * 5 + j + 6, i * 5 + j + 5] for i in range(4) for j in range(4)])
>>> surface = Surface(np.c_[grid, np.zeros(25)], faces)
>>> maxima, minima = local_extrema(surface, -((grid - 2.0) ** 2).sum(1))
>>> maxima.tolist()
[12]
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..geometry.surface import Surface
from ..geometry.validation import check_signal, check_surface
from ..records import renamed_keywords
from .options import EMDOptions

__all__ = ["local_extrema", "extrema_masks", "active_extrema", "extrema_spacing", "TIE_RTOL"]

#: Neighbouring values closer than this fraction of the signal's range are ties.
TIE_RTOL = 1e-9


def local_extrema(
    surface: Surface,
    f: np.ndarray,
    options: EMDOptions | dict | None = None,
    *,
    tie_rtol: float = TIE_RTOL,
    **overrides: Any,
) -> tuple[np.ndarray, np.ndarray]:
    """Indices of the local maxima and minima of a per-vertex signal.

    Parameters
    ----------
    surface : Surface
    f : (n,) array_like
    options : EMDOptions or dict, optional
        The extremum settings of :class:`~hht3d.decomposition.options.EMDOptions`:
        ``extrema`` (formerly the keyword ``rule``): ``"strict"``, ``f_i`` is
        ``≥`` every neighbour in its 1-ring; ``"relaxed"``, the rule of
        Sec. 5.2, ``f_i ≥ f_j`` for at least a fraction ``ratio`` (the
        paper's ``t`` in ``(0.5, 1]``) of its ``ring``-ring,
        ``|N⁺(i)| ≥ t |N_k(i)|`` (default the two-ring).  ``"relaxed"`` with
        ``ratio=1`` is the strict rule on the ``ring``-ring.  Minima likewise
        with ``≤``.
    tie_rtol : float
        Values closer than ``tie_rtol · (max f − min f)`` count as equal.
    **overrides
        Settings that replace those of ``options``.

    Returns
    -------
    max_idx, min_idx : ndarray of int
        Sorted vertex indices.

    Notes
    -----
    Ties: a maximum must also be *strictly* greater than at least one
    neighbour (a minimum strictly smaller), so a constant patch, the interior
    of a plateau, a constant signal and an isolated vertex give no extrema,
    while a flat ridge (e.g. a signal constant across a strip) gives a line of
    maxima.  Equality is up to ``tie_rtol`` of the signal's range, so a ridge
    that is flat up to solver round-off (about 1e-12 of the range after an
    envelope solve) is still one ridge; the tolerance scales with the signal
    and ignores constant offsets.

    Examples
    --------
    >>> from hht3d import data_path, load
    >>> from hht3d.decomposition import local_extrema
    >>> sphere = load(data_path("sphere_oct4098.ply"))
    >>> maxima, minima = local_extrema(sphere, sphere.vertices[:, 2])  # the height: one pole each
    >>> len(maxima), len(minima)
    (1, 1)
    """
    options = EMDOptions.of(options, **renamed_keywords(overrides, {"rule": "extrema"}, "local_extrema"))
    is_max, is_min = extrema_masks(surface, check_signal(check_surface(surface), f), options, tie_rtol)
    return np.flatnonzero(is_max), np.flatnonzero(is_min)


def extrema_masks(
    surface: Surface, f: np.ndarray, options: EMDOptions, tie_rtol: float = TIE_RTOL
) -> tuple[np.ndarray, np.ndarray]:
    """Boolean maximum and minimum masks of the ``extrema``, ``ring`` and ``ratio`` of ``options``
    (see :func:`local_extrema`)."""
    ring, ratio = (1, 1.0) if options.extrema == "strict" else (options.ring, options.ratio)
    adj = surface.ring(ring)
    degree = np.diff(adj.indptr)
    rows = np.repeat(np.arange(len(f)), degree)
    diff = f[rows] - f[adj.indices]
    tol = tie_rtol * (np.max(f) - np.min(f))
    n = len(f)
    n_above = np.bincount(rows[diff > tol], minlength=n)  # neighbours clearly below f_i
    n_below = np.bincount(rows[diff < -tol], minlength=n)  # neighbours clearly above f_i
    need = ratio * degree
    is_max = (degree - n_below >= need) & (n_above > 0)
    is_min = (degree - n_above >= need) & (n_below > 0)
    return is_max, is_min


def active_extrema(surface: Surface, h: np.ndarray, options: EMDOptions) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The maximum and minimum masks a decomposition uses, and the mask of *passive* components.

    Open-boundary vertices are no extrema unless ``options.boundary_extrema``; a connected component
    that lacks a maximum or a minimum is passive: it has no oscillation to take and stays in the
    residue (:mod:`.decompose`, "Components")."""
    is_max, is_min = extrema_masks(surface, h, options)
    if not options.boundary_extrema:
        boundary = surface.boundary_vertices
        is_max, is_min = is_max & ~boundary, is_min & ~boundary
    labels, k = surface.component_labels, surface.n_components
    has_max = np.bincount(labels[is_max], minlength=k) > 0
    has_min = np.bincount(labels[is_min], minlength=k) > 0
    passive = ~(has_max & has_min)[labels]
    return is_max & ~passive, is_min & ~passive, passive


def extrema_spacing(surface: Surface, n_extrema: int) -> float:
    """``d = √(A / n)``: the mean spacing of ``n`` extrema spread over the surface area ``A``.

    Parameters
    ----------
    surface : Surface
        The surface whose area ``A`` (sum of the lumped mass) is spread.
    n_extrema : int
        The number of extrema ``n`` (at least 1 is used).

    Returns
    -------
    float
        The spacing ``d``, in the surface's length unit.

    Examples
    --------
    >>> from hht3d import data_path, load
    >>> from hht3d.decomposition import extrema_spacing
    >>> sphere = load(data_path("sphere_oct4098.ply"))  # the unit sphere, area 4π
    >>> round(extrema_spacing(sphere, 100), 3)  # √(4π / 100)
    0.354
    """
    return math.sqrt(float(surface.mass_diagonal.sum()) / max(int(n_extrema), 1))
