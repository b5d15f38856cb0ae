"""The Riesz transform of each IMF on the level and in the band it was filtered in (issue 39).

An IMF of iterative filtering on levels (:mod:`hht3d.decomposition.multiresolution`) lives
on level ``ℓ`` and, above its own cut ``ω_c``, holds what the filter passed: its response
``P(G)`` is below 1e-10 under ``ω_c / 2`` (bilaplacian, ``m = 16``).  So its potential
``L^{-1/2} f̃`` needs the quadrature of :func:`~hht3d.spectral.quadrature.quadrature_nodes`
only on ``[λ_lo, M̄]`` with ``λ_lo = (`` :data:`BAND_FLOOR` ``· ω_c)²``, on level ``ℓ``:
fewer shifts (the condition number is ``M̄ / λ_lo``, not ``M̄ / λ_1``) on a smaller system.
The IMFs of one level share the shifts of the lowest cut among them, each shift solved once
for all of them (:func:`~hht3d.spectral.quadrature.quadrature_part`: the largest by Jacobi-CG,
the others factorized).
The Riesz vectors ``∇ L^{-1/2} f̃`` are taken on level ``ℓ`` (Eq. 17), prolonged to the input's
vertices (:class:`~hht3d.geometry.hierarchy.Hierarchy`) and projected on its tangent planes.

An IMF whose level filtered it by a polynomial (:mod:`hht3d.decomposition.filtering`,
"Evaluation") is ``p(A) r + e`` with ``A = M̃⁻¹L`` on its level, and its entry in
``EMDResult.levels`` keeps ``x = r + e`` and its potential ``ψ(A) x``, ``ψ(λ) = λ^{-1/2} P(g(λ))``,
from the filter's own pass; for a ``tol`` below that potential's
(:data:`~hht3d.decomposition.filtering.POTENTIAL_TOLERANCE`) it is one more polynomial in ``A``
(:func:`polynomial_potential`).  ``ψ`` vanishes like ``λ^{2m − 1/2}`` at 0 and is smooth, so its
series converges like the filter's and stays bounded where the IMF has no energy; no
factorization on that level.  It is exact for the filtered part and passes ``e`` through the
filter once more (``e`` lies above the cut, where ``P ≈ 1``).  It is the potential of the
filter's operator, the membrane ``L`` with floored areas, which is the quadrature's cotangent
``L`` only on a level without negative cotangent weights
(:func:`~hht3d.decomposition.envelopes.is_delaunay`): elsewhere the two Riesz transforms differ by
percents (3.5% on spot; 1.7–11% measured on igea and its decimated and subdivided copies), so
the potential is taken from the polynomial only there, or on levels of
:data:`~hht3d.decomposition.filtering.POLYNOMIAL_VERTICES` or more, where the quadrature's
factorizations do not fit; other levels take the band quadrature.  Coarse mesh levels have the
intrinsic Delaunay Laplacian (:mod:`hht3d.geometry.hierarchy`), so only the input's level can
lack it.  Their gradient fits over that Laplacian's neighbours
(:meth:`~hht3d.geometry.hierarchy.Level.gradient`).

Without levels (a decomposition that did not use them) each IMF takes the full quadrature on
the input (:func:`~hht3d.spectral.riesz_transform.riesz`).  The IMFs split into groups,
``k ≡ group (mod groups)``, one task each (:func:`riesz_part`, :func:`combine_riesz_parts`);
:func:`riesz_vectors` takes them in one call and then lets a large surface's hierarchy go.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..decomposition.filtering import (
    POTENTIAL_TOLERANCE,
    polynomial_operator,
    polynomial_series,
    potential_response,
    potential_usable,
)
from ..decomposition.options import EMDOptions
from ..errors import InputError
from ..geometry.hierarchy import hierarchy, release_hierarchy
from ..geometry.surface import Surface
from ..linalg.chebyshev import apply_series
from .eigenpairs import upper_bound
from .options import RieszOptions
from .quadrature import QuadraturePlan, combine_quadrature_parts, quadrature_nodes, quadrature_part
from .riesz_transform import riesz, vertex_gradient

__all__ = [
    "BAND_FLOOR",
    "riesz_part",
    "combine_riesz_parts",
    "riesz_vectors",
    "band_potential",
    "polynomial_potential",
]

#: The band of an IMF with cut ``ω_c`` starts at ``BAND_FLOOR · ω_c``.
BAND_FLOOR = 0.5


def band_potential(surface: Surface, f: np.ndarray, floor: float, tol: float, backend: str | None) -> np.ndarray:
    """``L^{-1/2} f̃`` for signals whose spectra lie above ``floor`` (an eigenvalue), to ``tol`` there.

    Parameters
    ----------
    surface : Surface
    f : (k, n) ndarray
        Signals, solved together (one factorization per shift).
    floor : float
        ``λ_lo``: components below it are not resolved.
    tol : float
        Relative accuracy of the quadrature on ``[λ_lo, M̄]``.
    backend : str, optional
        Sparse solver.

    Returns
    -------
    (k, n) ndarray
    """
    mbar = upper_bound(surface)
    low = min(floor, 0.5 * mbar)
    plan = QuadraturePlan((low, mbar), tol, *quadrature_nodes(low, mbar, tol))
    part = quadrature_part(surface, f, plan, backend=backend)
    return combine_quadrature_parts(surface, [part])


def polynomial_potential(
    surface: Surface, sources: np.ndarray, cuts: Sequence[float], options: EMDOptions, tol: float
) -> np.ndarray | None:
    """``ψ(A) x √t`` for IMFs filtered by the polynomial of :mod:`hht3d.decomposition.filtering` (module notes).

    Parameters
    ----------
    surface : Surface
        The level.
    sources : (k, n) ndarray
        ``x = r + e`` of each IMF (``EMDResult.levels``).
    cuts : sequence of float
        Each IMF's ``cut_frequency`` ``ω_c`` (its filter's width ``t = 1/ω_c²``).
    options : EMDOptions
        The decomposition's ``filter`` and ``order``.
    tol : float
        Uniform error of ``ψ`` (:func:`~hht3d.decomposition.filtering.potential_response`).

    Returns
    -------
    (k, n) ndarray or None
        ``None`` when a series would exceed :data:`~hht3d.decomposition.filtering.MAX_POLYNOMIAL_DEGREE`.

    Examples
    --------
    >>> from hht3d import load, data_path
    >>> from hht3d.decomposition.options import FILTERING_OPTIONS
    >>> surface = load(data_path("sphere_oct4098.ply"))
    >>> z = surface.vertices[:, 2]  # z² = (z² − 1/3) + 1/3: an l = 2 harmonic (λ = 6) and a constant
    >>> u = polynomial_potential(surface, (z**2)[None], [1.0], FILTERING_OPTIONS, 1e-8)[0]
    >>> bool(np.abs(u - (z**2 - 1 / 3) / np.sqrt(6)).max() < 1e-3)  # P(g(6)) = 1 at cut 1; 0 for constants
    True
    """
    top, y2 = polynomial_operator(surface)
    out = []
    for x, cut in zip(sources, cuts):
        t = 1.0 / float(cut) ** 2
        series = polynomial_series(functools.partial(potential_response, t=t, options=options), top, t, tol)
        if series is None:
            return None
        out.append(apply_series(series, y2, x) * np.sqrt(t))
    return np.array(out).reshape(len(out), surface.n_vertices)


def riesz_part(
    surface: Surface,
    decomposition: Any,
    options: RieszOptions,
    backend: str | None = None,
    group: int = 0,
    groups: int = 1,
) -> list[tuple[int, np.ndarray]]:
    """The Riesz vectors ``(n, 3)`` of the IMFs ``k ≡ group (mod groups)`` of ``decomposition``.

    Parameters
    ----------
    surface : Surface
        The input surface.
    decomposition : EMDResult
        Its ``levels`` (empty without the hierarchy) and ``info["imfs"][k]["cut_frequency"]``.
    options : RieszOptions
        ``tol`` and ``gradient`` are used.
    backend : str, optional
    group, groups : int
        This part's IMFs.

    Returns
    -------
    list of (int, (n, 3) ndarray)
        ``(k, riesz vectors)``; add the parts with :func:`combine_riesz_parts`.
    """
    if not (int(groups) == groups >= 1 and int(group) == group and 0 <= group < groups):
        raise InputError(f"need 0 <= group < groups with integers, got group={group!r}, groups={groups!r}")
    mine = range(int(group), decomposition.n_imfs, int(groups))
    if not decomposition.levels:
        return [(k, riesz(surface, decomposition.imfs[k], options, backend=backend)) for k in mine]
    levels = hierarchy(surface)
    normals = surface.normals
    out = []
    for index in sorted({decomposition.levels[k][0] for k in mine}):
        level = levels.level(index)
        if level is None:
            raise InputError(f"{surface.name}: an IMF lies on level {index}, which this surface does not have")
        here = [k for k in mine if decomposition.levels[k][0] == index]
        cuts = [decomposition.info["imfs"][k]["cut_frequency"] for k in here]
        _, _, sources, potentials = zip(*(decomposition.levels[k] for k in here))
        u = None
        polynomial = potential_usable(level.surface)
        if polynomial and all(p is not None for p in potentials) and options.tol >= POTENTIAL_TOLERANCE:
            u = np.array(potentials)
        elif polynomial and all(source is not None for source in sources):
            emd_options = EMDOptions.of(decomposition.info["options"])
            u = polynomial_potential(level.surface, np.array(sources), cuts, emd_options, options.tol)
        if u is None:
            values = np.array([decomposition.levels[k][1] for k in here])
            u = band_potential(level.surface, values, (BAND_FLOOR * min(cuts)) ** 2, options.tol, backend)
        fields = vertex_gradient(level.surface, u, options.gradient, level.gradient(options.gradient))
        for k, field in zip(here, fields.reshape(len(here), -1, 3)):
            vectors = levels.to_finest(field.T, index).T
            out.append((k, vectors - np.sum(vectors * normals, axis=1, keepdims=True) * normals))
    return out


def combine_riesz_parts(surface: Surface, parts: Sequence[list[tuple[int, np.ndarray]]]) -> np.ndarray:
    """The ``(k, n, 3)`` Riesz vectors of all IMFs from every :func:`riesz_part`."""
    found = sorted(((k, v) for part in parts for k, v in part), key=lambda item: item[0])
    return np.array([v for _, v in found]).reshape(len(found), surface.n_vertices, 3)


def riesz_vectors(
    surface: Surface, decomposition: Any, options: RieszOptions, backend: str | None = None
) -> np.ndarray:
    """The ``(k, n, 3)`` Riesz vectors of all IMFs in one part, then the surface's hierarchy released
    (:func:`~hht3d.geometry.hierarchy.release_hierarchy`): the last use of its levels in :func:`hht3d.hht`.

    Each IMF's vectors are moved into the result and let go one at a time, so the IMFs' vectors are not
    held twice (2.4 GB each time for 10 IMFs of a 10M-point cloud), as stacking the part would."""
    part = riesz_part(surface, decomposition, options, backend)
    vectors = np.empty((len(part), surface.n_vertices, 3))
    while part:
        k, field = part.pop()
        vectors[k] = field
        del field
    release_hierarchy(surface)
    return vectors
