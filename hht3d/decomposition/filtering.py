"""Iterative filtering on surfaces: each IMF is a fixed high-pass filter of the residue (issue 38).

Iterative filtering (Lin, Wang & Zhou 2009; Cicone & Zhou 2021) replaces the
envelope mean of sifting by a low-pass filter whose width comes from the
extrema spacing.  On a surface the low-pass is a resolvent,

    W_k = (M̃ + K_k)⁻¹ M̃,     K_k = t_k² L M̃⁻¹ L  (``filter="bilaplacian"``)
                               K_k = t_k L          (``filter="membrane"``),

with ``L`` the membrane part of the stiffness matrix and ``M̃`` the vertex
areas floored at :data:`~hht3d.decomposition.envelopes.MASS_FLOOR` of their
median (as the local-mean correction of :mod:`.sifting`), so that
``W_k = g(A)`` is a function of ``A = M̃⁻¹L`` alone (see "Evaluation").  The
IMF and the new residue are

    f_k = P(W_k) r_{k−1},    r_k = r_{k−1} − f_k,    P(G) = 1 − I_G(m, m),

where ``I_x(m, m)`` is the regularized incomplete beta function: a symmetric
Bernstein polynomial of degree ``2m − 1`` with ``0 ≤ P ≤ 1`` on ``[0, 1]``,
``P(0) = 1`` (fast oscillations stay in the IMF) and ``P(1) = 0`` (constants
and slow parts go to the residue).  Its transition narrows as ``1/√m``;
``m = 2`` is the smoothstep ``1 − 3G² + 2G³`` of the local-mean correction.

**No cancellation, by construction.**  ``W_k`` is self-adjoint in the ``M̃``
inner product with its spectrum in ``(0, 1]``, so in its eigenbasis
``⟨f_k, r_k⟩_M̃ = Σ P(1 − P) c² ≥ 0``: each step's energy ratio is at most 1
on every signal and every mesh whose areas are above the floor (``M̃ = M``),
and beyond it only the floored vertices' share can differ; no guard is
needed.  Leakage comes only from energy in the filter's transition band.

The cut
-------
With ``d`` the mean spacing of the residue's extrema (:func:`extrema_spacing`),
the filter passes half of frequency ``ω_c = π / (ξ d)``, ``ξ = cut_ratio``:
``t_k = 1 / ω_c²``, so ``G = 1 / (1 + (ω/ω_c)⁴)`` (bilaplacian) or
``1 / (1 + (ω/ω_c)²)`` (membrane) at a Laplacian eigenfunction of frequency
``ω`` (eigenvalue ``ω²``).  ``cut="global"`` uses one ``d`` for the whole
surface; ``cut="local"`` the local spacing ``d(x) = 1/√ρ(x)``, ``ρ`` the
extrema count per area smoothed over :data:`LOCAL_SMOOTHING` spacings by
one membrane solve, and bounded to within :data:`LOCAL_RANGE` of ``d``:

    K_k = L S M̃⁻¹ S L,   S = diag(t(x)),        (bilaplacian)
    K_k = Σ_edges w_ij (t_i + t_j)/2 (e_i − e_j)(e_i − e_j)ᵀ   (membrane),

both symmetric positive semidefinite with the constants in their kernel, so
the no-cancellation argument holds unchanged.

Evaluation
----------
``evaluation="solves"``: per IMF one numeric factorization of ``M + K_k`` on
the pattern the envelopes share (:class:`~hht3d.decomposition.envelopes.EnvelopeSolver`;
one symbolic analysis per run) and ``2m − 1`` solves, in the Clenshaw
recurrence of ``P`` in Chebyshev form (stable for any ``m``); ``cut="local"``
adds one factorization for the density.  On SuperLU the bilaplacian's global cut
factorizes the complex second-order system of :mod:`.resolvent` instead.  The factor's fill grows faster than
the mesh and dominates the memory of large surfaces.

``evaluation="polynomial"`` (global cut): ``W = g(A)``, ``A = M̃⁻¹ L``,
``g(λ) = 1/(1 + (tλ)²)`` (``1/(1 + tλ)`` for the membrane), so the IMF
``P(g(A)) r`` is one function of ``A``, applied as a Chebyshev series to within
:data:`POLYNOMIAL_TOLERANCE` (:mod:`hht3d.linalg.chebyshev`): sparse products
only, memory linear in the vertices, no factorization.  It is the solves' filter
(the IMFs agree to 1e-7 on spot and nefertiti, whose smallest areas are floored).
Its degree grows like ``√(λ̄) / ω_c``, ``λ̄ ≥ λ_max(A)``, which the worst-shaped
vertices set.  ``"auto"`` takes the polynomial on surfaces of
:data:`POLYNOMIAL_VERTICES` or more, where a factorization's fill no longer fits, on every
coarse level of :mod:`.multiresolution` (their intrinsic Delaunay Laplacian keeps ``λ̄ h²`` at 40-76 on
igea's and nefertiti's levels, whose IMFs took 1,063-1,519 degrees), and with a slow backend (SuperLU, a
plain install) from :data:`~hht3d.linalg.SLOW_FALLBACK_VERTICES` on, where its factorizations
dominate.  An IMF whose series would
exceed :data:`MAX_POLYNOMIAL_DEGREE` (a cut far below the surface's resolution: the degree
doubles as the cut halves, so on levels it stays bounded) is filtered by solves.

Stopping
--------
The decomposition stops at ``max_imfs``, when the residue has fewer than 2
maxima or 2 minima, or no fewer maxima and no fewer minima than before the
last IMF (the cut took nothing away: what is left is a trend whose extrema
are not an oscillation of their spacing), or when its fluctuation energy falls below
``energy_threshold`` of the signal's (:func:`~hht3d.decomposition.emd`).  A
connected component without a maximum or a minimum stays in the residue, as
with sifting.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from .. import linalg
from ..geometry.surface import Surface
from ..linalg.chebyshev import Recurrence, apply_series, chebyshev_series, recurrence_matrix, spectral_radius_bound
from ..linalg.estimate import COSTS, SLOW_FALLBACK_VERTICES
from .envelopes import EnvelopeSolver, floored_mass, is_delaunay, membrane_laplacian
from .extrema import active_extrema
from .options import EMDOptions
from .resolvent import apply_passband, passband, resolvent

__all__ = [
    "Filterer",
    "passband",
    "apply_passband",
    "opposite_distances",
    "EXTREMA_FREQUENCY",
    "LOCAL_SMOOTHING",
    "LOCAL_RANGE",
    "POLYNOMIAL_TOLERANCE",
    "POLYNOMIAL_VERTICES",
    "MAX_POLYNOMIAL_DEGREE",
    "uses_polynomial",
    "filter_response",
    "polynomial_operator",
    "polynomial_series",
    "potential_response",
    "potential_usable",
    "POTENTIAL_TOLERANCE",
]

#: ``κ``: a signal whose extrema lie ``d`` from their nearest opposite ones oscillates at ``κ / d``.
EXTREMA_FREQUENCY = math.pi
#: The local cut's extrema density is smoothed over this many mean spacings (membrane resolvent).
LOCAL_SMOOTHING = 2.0
#: The local spacing stays within this factor of the global one (either way).
LOCAL_RANGE = 4.0
#: Uniform error of the polynomial pass band (module notes, "Evaluation").
POLYNOMIAL_TOLERANCE = 1e-7
#: Uniform error of the series of the Riesz potential (``potential_response``), RieszOptions' default ``tol``.
POTENTIAL_TOLERANCE = 1e-8
#: ``evaluation="auto"`` takes the polynomial from this many vertices on.
POLYNOMIAL_VERTICES = 2_000_000
#: An IMF whose polynomial would need a higher degree is filtered by solves (the degree doubles as the cut halves).
MAX_POLYNOMIAL_DEGREE = 4096


def uses_polynomial(
    options: EMDOptions, n_vertices: int, backend: str | None = None, coarse: bool = False, potential: bool = False
) -> bool:
    """Whether the filter of a surface of ``n_vertices`` is applied as a Chebyshev polynomial: asked for, or
    ``"auto"`` on a ``coarse`` level of :mod:`.multiresolution` (well-shaped by construction, so of low degree),
    on a level where its pass also gives the IMFs' Riesz potential (``potential``: :func:`potential_usable`, so
    the level needs no band quadrature), from :data:`POLYNOMIAL_VERTICES` on, or from
    :data:`~hht3d.linalg.SLOW_FALLBACK_VERTICES` with a slow backend (SuperLU); never with a local cut."""
    if options.cut != "global" or options.evaluation == "solves":
        return False
    if options.evaluation == "polynomial" or coarse or potential or n_vertices >= POLYNOMIAL_VERTICES:
        return True
    cost = COSTS.get(linalg.check_backend(backend))
    return cost is not None and cost.slow and n_vertices >= SLOW_FALLBACK_VERTICES


def potential_usable(surface: Surface) -> bool:
    """Whether the polynomial's Riesz potential on ``surface`` is the Riesz quadrature's: its membrane operator is
    the cotangent Laplacian (:func:`~hht3d.decomposition.envelopes.is_delaunay`), or the surface is too large
    (:data:`POLYNOMIAL_VERTICES`) for the quadrature's factorizations (:mod:`hht3d.spectral.multilevel`)."""
    return surface.n_vertices >= POLYNOMIAL_VERTICES or is_delaunay(surface)


def filter_response(lam: np.ndarray, t: float, options: EMDOptions) -> np.ndarray:
    """``P(g(λ))``: the share of an eigenfunction of eigenvalue ``λ`` that the filter of width ``t`` keeps
    in the IMF (module notes)."""
    power = 2 if options.filter == "bilaplacian" else 1
    return passband(1.0 / (1.0 + (t * np.asarray(lam)) ** power), options.order)


def potential_response(lam: np.ndarray, t: float, options: EMDOptions) -> np.ndarray:
    """``ψ(λ) = P(g(λ)) / √(tλ)``: the Riesz potential ``λ^{-1/2} P(g(λ))`` of the IMF's filter over ``√t``, of
    order 1 and vanishing like ``λ^{2m − 1/2}`` at 0, so its series converges like the filter's."""
    lam = np.asarray(lam, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(lam > 0, filter_response(lam, t, options) / np.sqrt(t * lam), 0.0)


def polynomial_operator(surface: Surface) -> tuple[float, Recurrence]:
    """``λ̄ ≥ λ_max(M̃⁻¹L)`` (membrane ``L``, floored areas ``M̃``) and the
    :func:`~hht3d.linalg.chebyshev.recurrence_matrix` of the polynomial filter on ``surface``."""
    lap, mass = membrane_laplacian(surface), floored_mass(surface)
    top = spectral_radius_bound(lap, mass)
    return top, recurrence_matrix(lap, mass, top)


def polynomial_series(
    function: Callable[[np.ndarray], np.ndarray], top: float, t: float, tol: float
) -> np.ndarray | None:
    """The Chebyshev series on ``[0, λ̄]`` of a function that changes at ``1/t`` (a filter of width ``t``),
    ``None`` beyond :data:`MAX_POLYNOMIAL_DEGREE`."""
    if math.pi * math.sqrt(2 * top * t) > 2 * MAX_POLYNOMIAL_DEGREE:  # its first points alone would be more
        return None
    series = chebyshev_series(function, top, tol, scale=1.0 / t)
    return series if len(series) - 1 <= MAX_POLYNOMIAL_DEGREE else None


def opposite_distances(points: np.ndarray, is_max: np.ndarray, is_min: np.ndarray) -> np.ndarray:
    """The distance from each extremum (maxima, then minima) to the nearest extremum of the other kind.

    For ``sin(ωx)`` it is ``π/ω`` on a line, a strip or a surface alike, unlike a spacing from the
    extrema count per area, which depends on how the extrema fill the surface."""
    maxima, minima = points[is_max], points[is_min]
    return np.concatenate([cKDTree(minima).query(maxima)[0], cKDTree(maxima).query(minima)[0]])


class Filterer:
    """Extracts IMFs one at a time from a residue by the filter of the module notes; ``eligible``, if
    given, masks the vertices that may be extrema (all by default); ``coarse`` (a coarse level of
    :mod:`.multiresolution`) and ``potential`` (Riesz potentials from the pass) as for :func:`uses_polynomial`."""

    def __init__(
        self,
        surface: Surface,
        options: EMDOptions,
        backend: str | None,
        eligible: np.ndarray | None = None,
        coarse: bool = False,
        potential: bool = False,
    ):
        self.surface = surface
        self.options = options
        self.eligible = eligible
        self.backend = backend
        self.with_potential = potential
        self.polynomial = uses_polynomial(options, surface.n_vertices, backend, coarse, potential)
        self._solver: EnvelopeSolver | None = None
        self._recurrence: tuple[float, Recurrence] | None = None
        self.mass = floored_mass(surface)
        self.n_solves = self.n_products = 0
        self.n_complex = 0  # factorizations of the complex system of resolvent()
        self.counts = (math.inf, math.inf)

    @property
    def solver(self) -> EnvelopeSolver:
        """The solves' factorizations on the envelopes' pattern (made on first use)."""
        if self._solver is None:
            self._solver = EnvelopeSolver(self.surface, self.backend)
        return self._solver

    @property
    def n_factorizations(self) -> int:
        return self.n_complex + (0 if self._solver is None else self._solver.n_factorizations)

    @property
    def backend_name(self) -> str:
        """What applied the filters: the solves' backend, ``"chebyshev"`` (the polynomial), or both joined by ``+``."""
        solves = [linalg.check_backend(self.backend)] if self.n_factorizations or not self.n_products else []
        return "+".join((["chebyshev"] if self.n_products else []) + solves)

    def imf(self, residue: np.ndarray) -> tuple[np.ndarray, dict] | None:
        """``P(W_k) r_{k−1}`` and its diagnostics; ``None`` when :meth:`cut` finds no oscillation."""
        start, factorizations = time.perf_counter(), self.n_factorizations
        cut = self.cut(residue)
        if cut is None:
            return None
        t, passive, info = cut
        imf = self.filtered(t, residue, info)
        imf[passive] = 0.0
        info.update(factorizations=self.n_factorizations - factorizations, seconds=time.perf_counter() - start)
        return imf, info

    def cut(self, residue: np.ndarray) -> tuple[np.ndarray, np.ndarray, dict] | None:
        """The filter width ``t`` per vertex (module notes, "The cut"), the passive vertices (components
        without both kinds of extrema) and the diagnostics; ``None`` when the residue has < 2 maxima or
        minima, or no fewer of either than the residue before the last IMF (the cut took nothing: a trend)."""
        is_max, is_min, passive = active_extrema(self.surface, residue, self.options)
        if self.eligible is not None:
            is_max, is_min = is_max & self.eligible, is_min & self.eligible
        counts = (int(is_max.sum()), int(is_min.sum()))
        if min(counts) < 2 or (counts[0] >= self.counts[0] and counts[1] >= self.counts[1]):
            return None
        self.counts = counts
        distances = opposite_distances(self.surface.vertices, is_max, is_min)
        spacing = float(np.median(distances))
        cut = EXTREMA_FREQUENCY / (self.options.cut_ratio * spacing)
        t = np.full(len(residue), 1.0 / cut**2)
        if self.options.cut == "local":
            t = t * (self._local_spacing(is_max | is_min, distances) / spacing) ** 2
        info = {"n_maxima": counts[0], "n_minima": counts[1], "spacing": spacing, "cut_frequency": cut}
        return t, passive, {**info, "stop": "filter"}

    def filtered(self, t: np.ndarray, residue: np.ndarray, info: dict) -> np.ndarray:
        """``P(W) r`` with the filter of width ``t`` (per vertex); the polynomial's degree goes in ``info``."""
        return self.filtered_with_potential(t, residue, info, potential=False)[0]

    def filtered_with_potential(
        self, t: np.ndarray, residue: np.ndarray, info: dict, potential: bool = True
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """``P(W) r`` and, when the filter is a polynomial, its Riesz potential ``L^{-1/2} P(W) r`` from the same
        pass (module notes, "Evaluation"); ``None`` for solves."""
        width = float(t[0])
        series = self._series(lambda lam: filter_response(lam, width, self.options), width, POLYNOMIAL_TOLERANCE)
        if series is None:
            global_bilaplacian = self.options.filter == "bilaplacian" and np.ptp(t) == 0
            solve, complex_system = resolvent(
                self.surface,
                self.mass,
                width if global_bilaplacian else None,
                self.backend,
                lambda: self.solver.factorize(self._system(t)).solve,
            )
            self.n_complex += complex_system
            self.n_solves += 2 * self.options.order - 1
            return apply_passband(solve, self.mass, residue, self.options.order), None
        info["degree"] = len(series) - 1
        extra = self._potential_series(width) if potential else None
        rows = [series] if extra is None else [series, extra]
        stacked = np.zeros((len(rows), max(map(len, rows))))
        for row, found in zip(stacked, rows):
            row[: len(found)] = found
        self.n_products += stacked.shape[1] - 1
        out = apply_series(stacked, self._operator()[1], residue)
        return out[0], None if extra is None else out[1] * math.sqrt(width)

    def potential(self, t: np.ndarray, x: np.ndarray, tol: float = POTENTIAL_TOLERANCE) -> np.ndarray | None:
        """``L^{-1/2} P(W) x`` by the polynomial, its series to ``tol`` (``None`` when its degree would be too
        high, or for solves)."""
        width = float(t[0])
        series = self._potential_series(width, tol)
        if series is None:
            return None
        self.n_products += len(series) - 1
        return apply_series(series, self._operator()[1], x) * math.sqrt(width)

    def _series(self, function: Callable[[np.ndarray], np.ndarray], width: float, tol: float) -> np.ndarray | None:
        """:func:`polynomial_series` on this surface's ``λ̄``; ``None`` for solves."""
        return polynomial_series(function, self._operator()[0], width, tol) if self.polynomial else None

    def _potential_series(self, width: float, tol: float = POTENTIAL_TOLERANCE) -> np.ndarray | None:
        return self._series(lambda lam: potential_response(lam, width, self.options), width, tol)

    def _operator(self) -> tuple[float, Recurrence]:
        """:func:`polynomial_operator` of the surface (made once)."""
        if self._recurrence is None:
            self._recurrence = polynomial_operator(self.surface)
        return self._recurrence

    def totals(self) -> dict:
        """Run totals for ``EMDResult.info``: ``solves``, ``products`` (of the polynomial), ``factorizations``,
        ``backend``; no sifts, no envelope constraints."""
        return {
            "sifts": 0,
            "solves": self.n_solves,
            "products": self.n_products,
            "max_constraint_error": 0.0,
            "factorizations": self.n_factorizations,
            "backend": self.backend_name,
        }

    def _local_spacing(self, extrema: np.ndarray, distances: np.ndarray) -> np.ndarray:
        """``d(x)``: the extrema's :func:`opposite_distances` spread over the surface by a membrane
        resolvent of width :data:`LOCAL_SMOOTHING` spacings, within :data:`LOCAL_RANGE` of their median."""
        e = self.solver.energies
        spacing = float(np.median(distances))
        data = (LOCAL_SMOOTHING * spacing) ** 2 * e.laplacian
        data[e.diagonal] += self.surface.mass_diagonal
        factor = self.solver.factorize(e.matrix(data))
        weight, value = np.zeros(len(extrema)), np.zeros(len(extrema))
        weight[extrema], value[extrema] = 1.0, np.log(distances)
        smoothed = factor.solve(value) / np.maximum(factor.solve(weight), 1e-300)
        self.n_solves += 2
        return spacing * np.clip(np.exp(smoothed - np.log(spacing)), 1 / LOCAL_RANGE, LOCAL_RANGE)

    def _system(self, t: np.ndarray) -> sp.csr_matrix:
        """``M + K`` on the shared pattern, with ``t`` per vertex (constant for the global cut)."""
        e = self.solver.energies
        rows = np.repeat(np.arange(e.n), e.row_lengths)
        if self.options.filter == "membrane":
            data = e.laplacian * (0.5 * (t[rows] + t[e.indices]))
            off = np.ones(len(data), dtype=bool)
            off[e.diagonal] = False
            data[e.diagonal] = -np.bincount(rows[off], weights=data[off], minlength=e.n)
        elif np.ptp(t) == 0:
            data = t[0] ** 2 * e.smoothing
        else:
            data = e.local_smoothing(t)
        data[e.diagonal] += self.mass
        return e.matrix(data)
