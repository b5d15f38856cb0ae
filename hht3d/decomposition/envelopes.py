"""Envelopes through extrema: thin plates, in tension or not, and membranes (Sec. 4.1, Eqs. 8-11).

Envelopes
---------
On a surface the cubic spline of 1-D EMD becomes the biharmonic field of
Eqs. (8)–(11) (Wang et al. 2012): ``g`` minimises the thin-plate energy
``gᵀ Q g``, ``Q = L M⁻¹ L``, subject to ``g = f`` at the extrema.  Between
sparse extrema a thin plate overshoots: through one sharp crease it bulges
over the whole neighbourhood, and the IMFs then cancel each other (see
:mod:`hht3d.decomposition.quality`; measured in ``benchmarks/results/quality.md``).  The default
envelope is therefore a thin plate *in tension* (Smith & Wessel 1990),

    Q_τ = L M⁻¹ L + (τ / d)² L,      d = √(A / |C|),

with ``A`` the surface area and ``|C|`` the number of extrema, so ``d`` is
their mean spacing, ``L`` in the tension term the membrane part of the
Laplacian (its non-negative edge weights, :func:`_membrane`; all of ``L`` on
a Delaunay mesh), and the tension ``τ`` is scale-free: the same ``τ``
behaves alike on every IMF and every model.  ``τ = 0`` is the paper's
biharmonic envelope and ``τ → ∞`` the membrane (harmonic) one, ``L g = 0``,
which obeys a discrete maximum principle but loses the scale separation of
the thin plate (on white noise the extrema thin out far less per IMF;
``benchmarks/results/quality.md``).

Solver design
-------------
Every envelope of a surface is solved with one matrix *pattern* (that of
``L M⁻¹ L`` and ``L`` together): the rows and columns of the constrained
vertices ``C`` are replaced by diagonal rows and columns (their off-diagonal
entries stored as explicit zeros),

    [Q_FF  0   ] [g_F]   [-Q_FC f_C]
    [0     D_CC] [g_C] = [ D_CC f_C ],      D_CC = diag(Q)_CC,

which is exactly the eliminated system ``Q_FF g_F = −Q_FC f_C`` plus
``g_C = f_C``, symmetric positive definite whenever every connected component
holds a constraint.  The sparsity pattern never changes, whatever the
tension, so the fill-reducing ordering and symbolic factorization are done
once per EMD run (:class:`hht3d.linalg.backends.SymbolicFactorization`) and each
envelope costs one numeric factorization and one solve.

Boundaries
----------
``L`` is the Neumann Laplacian, so on an open surface the envelopes have zero
normal derivative at the boundary: on a strip or cylinder a biharmonic
envelope is the *clamped* cubic spline through the extrema, the surface
analogue of the mirrored end extrema of 1-D EMD codes.
"""

from __future__ import annotations

import functools
import math
import weakref
from typing import Any

import numpy as np
import scipy.sparse as sp

from .. import linalg
from ..errors import InputError
from ..geometry.surface import Surface
from ..geometry.validation import check_signal, check_surface
from ..linalg.factor import entries_on_pattern
from .extrema import extrema_spacing
from .options import EMDOptions, start_tension

__all__ = [
    "envelope_operator",
    "envelope_interpolation",
    "EnvelopeSolver",
    "envelope_energies",
    "membrane_laplacian",
    "is_delaunay",
    "floored_mass",
    "MASS_FLOOR",
]

#: The local-mean correction's bilaplacian divides by vertex areas floored at this fraction of
#: their median, so tiny vertices of a scan do not make its system numerically indefinite.
MASS_FLOOR = 0.1


class _EnvelopeEnergies:
    """``L M⁻¹ L`` and the membrane ``L`` stored on one pattern (the 2-ring, diagonal included).

    Every envelope energy ``Q_τ`` is a combination of the two data arrays, so
    all tensions share one symbolic analysis.  The pattern's index arrays are
    read-only and shared by every matrix built on it (:meth:`matrix`).  The pattern is the structure
    of ``(|L| + I)²``, every product of two neighbours' entries, so no cancellation removes an entry.
    ``L M⁻¹ L`` (:attr:`bilaplacian`) is made on first use: iterative filtering never uses it
    (its filter is :attr:`smoothing`), which spares it 3 of 8 s at 1M vertices.
    """

    def __init__(self, surface: Surface):
        self.surface = surface
        structure = (abs(surface.stiffness) + sp.eye(surface.n_vertices)).tocsr()
        structure.data = np.ones_like(structure.data)
        pattern = (structure @ structure).tocsr()  # holds the structure too: its diagonal is 1
        del structure
        pattern.sort_indices()
        n = surface.n_vertices
        self.indptr, self.indices, self.n = pattern.indptr, pattern.indices, n
        for index in (self.indptr, self.indices):
            index.setflags(write=False)
        self.row_lengths = np.diff(self.indptr)
        self.diagonal = np.flatnonzero(self.indices == np.repeat(np.arange(n), self.row_lengths))
        membrane = membrane_laplacian(surface)
        self.laplacian = self._on_pattern(membrane)
        self.floored = floored_mass(surface)
        self.membrane = membrane
        self.smoothing = self._on_pattern(membrane @ sp.diags(1.0 / self.floored) @ membrane)

    @functools.cached_property
    def bilaplacian(self) -> np.ndarray:
        """Entries of ``L M⁻¹ L`` (symmetrized), the envelopes' thin-plate energy."""
        lap = self.surface.stiffness
        bilaplacian = lap @ sp.diags(1.0 / self.surface.mass_diagonal) @ lap
        return self._on_pattern(0.5 * (bilaplacian + bilaplacian.T))

    def _on_pattern(self, a: Any) -> np.ndarray:
        """The entries of ``a`` (sparse, within the pattern) on the shared pattern."""
        return entries_on_pattern(self.indptr, self.indices, a)

    def local_smoothing(self, scale: np.ndarray) -> np.ndarray:
        """Entries of ``L S M̃⁻¹ S L`` with ``S = diag(scale)``: :attr:`smoothing` with a scale per vertex."""
        return self._on_pattern(self.membrane @ sp.diags(scale**2 / self.floored) @ self.membrane)

    def data(self, tension: float, spacing: float) -> np.ndarray:
        """Entries of ``Q_τ = L M⁻¹ L + (τ/d)² L``; ``τ = inf`` gives ``L`` (the harmonic limit)."""
        if math.isinf(tension):
            return self.laplacian
        if tension == 0:
            return self.bilaplacian
        return self.bilaplacian + (tension / spacing) ** 2 * self.laplacian

    def free_entries(self, free: np.ndarray) -> np.ndarray:
        """Mask of the stored entries whose row and column are both ``free``."""
        return np.repeat(free, self.row_lengths) & free[self.indices]

    def matrix(self, data: np.ndarray) -> sp.csr_matrix:
        """``data`` on the pattern, sharing its (read-only, sorted) index arrays."""
        a = sp.csr_matrix((data, self.indices, self.indptr), shape=(self.n, self.n), copy=False)
        a.has_sorted_indices = True
        return a


def membrane_laplacian(surface: Surface) -> sp.csr_matrix:
    """:func:`_membrane` of the surface's stiffness matrix (the stiffness matrix itself when no cotangent
    weight is negative, :func:`is_delaunay`)."""
    return surface.stiffness if is_delaunay(surface) else _membrane(surface.stiffness)


def is_delaunay(surface: Surface) -> bool:
    """Whether no edge weight of the stiffness matrix is negative (no positive off-diagonal entry): then
    the membrane Laplacian is the stiffness matrix itself."""
    lap = surface.stiffness
    return not np.any(lap.data[lap.indices != np.repeat(np.arange(lap.shape[0]), np.diff(lap.indptr))] > 0)


def floored_mass(surface: Surface) -> np.ndarray:
    """``M̃``: the vertex areas floored at :data:`MASS_FLOOR` of their median."""
    return np.maximum(surface.mass_diagonal, MASS_FLOOR * np.median(surface.mass_diagonal))


def _membrane(lap: sp.csr_matrix) -> sp.csr_matrix:
    """``L`` without its positive off-diagonal entries (negative cotangent weights of
    non-Delaunay edges), the diagonal rebuilt so rows still sum to 0.

    An M-matrix: the membrane envelope then obeys a discrete maximum principle, and every
    constrained system stays numerically definite even with caps whose cotangents reach −500
    (dragon_vrip).  On a Delaunay mesh it is ``L`` itself.
    """
    off = sp.csr_matrix(lap - sp.diags(lap.diagonal()))
    off.data = np.minimum(off.data, 0.0)
    off.eliminate_zeros()
    return (off - sp.diags(np.asarray(off.sum(axis=1)).ravel())).tocsr()


def envelope_energies(surface: Surface) -> _EnvelopeEnergies:
    """The envelope energies of ``surface``, shared by the EMD runs of it alive at once.

    The surface's cache holds them weakly: EEMD members running together build
    them once, and they are freed with the last run, so the Riesz transform
    that follows does not carry them (666 MB at 1M vertices).
    """
    key = "emd:energies"
    held = surface.cache.get(key)
    energies = held() if held is not None else None
    if energies is None:
        energies = _EnvelopeEnergies(surface)
        surface.cache[key] = weakref.ref(energies)
    return energies


def envelope_operator(
    surface: Surface, options: EMDOptions | dict | None = None, *, spacing: float | None = None, **overrides: Any
) -> sp.csr_matrix:
    """The energy matrix ``Q`` of the envelope interpolation (Eqs. 8–11).

    ``Q = L M⁻¹ L`` for ``envelope="biharmonic"`` (thin-plate energy, the
    paper's choice; on a line it gives cubic splines), ``Q = L M⁻¹ L + (τ/d)² L``
    for ``"tension"`` and ``Q = L`` for ``"harmonic"`` (membrane energy,
    piecewise-linear on a line).  ``Q`` is symmetric PSD, stored on the
    pattern shared by all envelopes with every diagonal entry present.

    Parameters
    ----------
    surface : Surface
    options : EMDOptions or dict, optional
        Its ``envelope`` (default ``"tension"``, as EMD's) and ``tension`` ``τ``.
    spacing : float, optional
        ``d`` of ``"tension"`` (e.g. :func:`extrema_spacing`); required for it.
    **overrides
        Settings that replace those of ``options`` (``envelope="biharmonic"``).

    Returns
    -------
    scipy.sparse.csr_matrix
        ``Q`` (n, n), a copy the caller may change.
    """
    options = EMDOptions.of(options, **overrides)
    start = start_tension(options.envelope, options.tension)
    if options.envelope == "tension" and spacing is None:
        raise InputError("the tension envelope needs the extrema spacing d (see extrema_spacing)")
    energies = envelope_energies(check_surface(surface))
    return energies.matrix(energies.data(start, spacing or 1.0)).copy()  # the caller's own arrays


class EnvelopeSolver:
    """Constrained envelope solves sharing one symbolic factorization.

    The fill-reducing ordering and symbolic analysis of the shared pattern
    are done on the first solve; every envelope then costs one numeric
    factorization and one solve (module notes, "Solver design").
    """

    def __init__(self, surface: Surface, backend: str | None):
        self.backend = linalg.check_backend(backend)
        self.energies = envelope_energies(surface)
        self._points = surface.vertices  # for a backend that orders the pattern by them
        self._symbolic: linalg.SymbolicFactorization | None = None

    @property
    def n_factorizations(self) -> int:
        return 0 if self._symbolic is None else self._symbolic.n_factorizations

    def factorize(self, matrix: sp.csr_matrix) -> linalg.Factor:
        """Numeric factorization of an SPD matrix on the shared pattern (analysed on first use)."""
        if self._symbolic is None:
            self._symbolic = linalg.SymbolicFactorization(matrix, self.backend, points=self._points)
        return self._symbolic.factorize(matrix)

    def solve(self, f: np.ndarray, constrained: np.ndarray, tension: float, spacing: float) -> np.ndarray:
        """The envelope ``g`` with ``g_C = f_C`` minimising ``gᵀQ_τg`` (Eq. 11 for ``τ = 0``)."""
        e = self.energies
        q = e.data(tension, spacing)
        diag = q[e.diagonal]
        scale = np.where(diag > 0, diag, 1.0)
        data = q * e.free_entries(~constrained)
        data[e.diagonal[constrained]] = scale[constrained]
        factor = self.factorize(e.matrix(data))
        rhs = -(e.matrix(q) @ np.where(constrained, f, 0.0))
        rhs[constrained] = scale[constrained] * f[constrained]
        return factor.solve(rhs)


def envelope_interpolation(
    surface: Surface,
    values: np.ndarray,
    constrained: np.ndarray | None,
    options: EMDOptions | dict | None = None,
    *,
    backend: str | None = None,
    **overrides: Any,
) -> np.ndarray:
    """Interpolate ``values`` from the ``constrained`` vertices (Eq. 11).

    Solves ``min gᵀQg`` subject to ``g_C = values_C`` with ``Q`` from
    :func:`envelope_operator`; this is one EMD envelope.

    Parameters
    ----------
    surface : Surface
    values : (n,) array_like
        Only the entries at ``constrained`` are used.
    constrained : (n,) bool array_like or int indices
        The vertices ``C``; every connected component needs at least one.
    options : EMDOptions or dict, optional
        Its ``envelope`` (default ``"tension"``, as EMD's) and ``tension`` ``τ``; the
        spacing ``d`` of ``"tension"`` is :func:`extrema_spacing` of ``|C|``.
    backend : str, optional
        Sparse solver of :mod:`hht3d.linalg.backends`.
    **overrides
        Settings that replace those of ``options`` (``envelope="biharmonic"``).

    Returns
    -------
    (n,) ndarray
    """
    options = EMDOptions.of(options, **overrides)
    f = check_signal(check_surface(surface), values)
    start = start_tension(options.envelope, options.tension)
    c = np.asarray(constrained)
    if c.dtype == bool and c.shape != f.shape:
        raise InputError(f"constrained mask has shape {c.shape}; expected {f.shape}")
    if c.dtype != bool and (
        c.size and (not np.issubdtype(c.dtype, np.integer) or c.min() < -len(f) or c.max() >= len(f))
    ):
        raise InputError(f"constrained indices must be integers in [0, {len(f)})")
    mask = np.zeros(len(f), dtype=bool)
    mask[c] = True
    covered = np.bincount(surface.component_labels[mask], minlength=surface.n_components) > 0
    if not covered.all():
        raise InputError(
            f"{int((~covered).sum())} connected components of {surface.name} have no "
            "constrained vertex; their interpolant is undefined"
        )
    return EnvelopeSolver(surface, backend).solve(f, mask, start, extrema_spacing(surface, mask.sum()))
