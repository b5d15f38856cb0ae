"""Fractional Laplacian ``L^{-1/2}`` and the Riesz transform on surfaces (Sec. 4.2).

The Riesz transform of a signal ``h`` on a surface is (Eqs. 12, 14, 16)

    R h = ∇ Δ^{-1/2} h,

with ``Δ^{-1/2}`` defined spectrally (Eq. 13).  Discretely, ``Δ`` is the
generalized eigenproblem of the stiffness matrix ``L`` and the lumped mass
``M`` of :class:`~hht3d.geometry.surface.Surface`,

    L φ_k = λ_k M φ_k,   φ_kᵀ M φ_l = δ_kl,

so ``L^{-α} f = Σ_k λ_k^{-α} φ_k (φ_kᵀ M f)`` (Eq. 15 written for the
strong Laplacian ``M⁻¹L``).

Kernel
------
``λ = 0`` belongs to the functions that are constant on each connected
component (``surface.component_labels``); ``λ^{-α}`` is undefined there.
Every method therefore projects the kernel out: the M-weighted mean of each
component is removed from the input, ``f̃ = f − (1_cᵀ M f)/(1_cᵀ M 1_c)``
(:func:`remove_kernel`), and the result is M-orthogonal to the kernel too.
So ``L^{-1/2}`` of a constant is zero and ``L^{-1/2} f == L^{-1/2} f̃``.

Methods
-------
``"quadrature"`` (default)
    The whole spectrum without eigenvectors: the elliptic midpoint rule of
    Hale, Higham & Trefethen (2008) for ``A^{-1/2}``, ``A = M⁻¹L``,

        L^{-1/2} f̃ ≈ Σ_j w_j (L + σ_j M)⁻¹ M f̃,

    with shifts ``σ_j > 0`` and weights ``w_j > 0`` from
    :func:`quadrature_nodes`, over spectral bounds ``m ≤ λ_1`` and
    ``M̄ ≥ λ_max`` from :func:`spectral_bounds`.  Every ``L + σ_j M`` is SPD
    and has one sparsity pattern, analysed once
    (:class:`hht3d.linalg.backends.SymbolicFactorization`); each shift is factorized
    once and solves all signals as one multi-column right-hand side.
``"spectral"``
    The paper's Algorithm 1 (Eq. 18): the ``p`` smallest non-zero eigenpairs
    only, a low-pass approximation.  Eigenpairs are cached on the surface.
``"dense"``
    Full dense eigendecomposition (Eq. 15), exact to round-off; the
    reference for small surfaces (at most :data:`DENSE_MAX_VERTICES`).

Running the shifts elsewhere
----------------------------
The quadrature is a sum of independent shifted solves, so a scheduler can
split the shifts into groups and run one task per group:

    plan = quadrature_plan(surface, tol)                       # bounds, shifts, weights
    parts = [quadrature_part(surface, f, plan, group, groups)  # independent tasks
             for group in range(groups)]
    result = combine_quadrature_parts(surface, parts)

Each part factorizes its shifts once (:func:`shifted_solve`) and solves all
signals as one multi-column right-hand side; factorizations never leave the
task.  :func:`fractional_laplacian` does the same with one group.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.special import ellipj, ellipk

from .. import linalg
from ..errors import InputError, NumericalError
from .options import GRADIENTS, METHODS, MIN_TOL, RIESZ_DEFAULTS
from ..geometry.surface import Surface
from ..geometry.validation import as_signals, check_choice, check_surface

__all__ = [
    "METHODS",
    "GRADIENTS",
    "DENSE_MAX_VERTICES",
    "fractional_laplacian",
    "riesz",
    "remove_kernel",
    "spectral_bounds",
    "quadrature_nodes",
    "QuadraturePlan",
    "quadrature_plan",
    "quadrature_part",
    "combine_quadrature_parts",
    "shifted_matrix",
    "shift_analysis",
    "shifted_solve",
    "smallest_eigenpairs",
    "vertex_gradient",
]

#: Largest surface the ``"dense"`` method accepts (an n×n float64 eigendecomposition).
DENSE_MAX_VERTICES = 6000
#: ``m = SAFETY · λ_1`` so that the lower bound stays below ``λ_1`` despite
#: eigensolver error.
SAFETY = 0.9
#: λ sample points per quadrature check (log-spaced over ``[m, M̄]``).
_CHECK_POINTS = 2000
#: Power iterations tightening the upper spectral bound (:func:`_upper_bound`).
_POWER_ITERATIONS = 10
#: Most shifts :func:`quadrature_nodes` tries before giving up.
_MAX_SHIFTS = 200


# -- kernel --------------------------------------------------------------------------------

def remove_kernel(surface: Surface, f) -> np.ndarray:
    """Remove the M-weighted mean of every connected component.

    Parameters
    ----------
    surface : Surface
    f : (n,) or (k, n) array_like

    Returns
    -------
    ndarray, shape of ``f``
        ``f − Σ_c 1_c (1_cᵀ M f)/(1_cᵀ M 1_c)``: M-orthogonal to the kernel
        of ``L`` (the per-component constants).
    """
    surface = check_surface(surface)
    a, single = as_signals(surface, f)
    labels = surface.component_labels
    mass = surface.mass_diagonal
    n = surface.n_vertices
    indicator = sp.csr_matrix((mass, (np.arange(n), labels)), shape=(n, surface.n_components))
    means = np.asarray(indicator.T @ a.T).T / np.asarray(indicator.sum(axis=0))  # (k, components)
    out = a - means[:, labels]
    return out[0] if single else out


# -- spectral bounds and quadrature nodes --------------------------------------------------

def _upper_bound(surface: Surface) -> float:
    """``M̄ ≥ λ_max``: the Collatz–Wielandt bound for ``M⁻¹|L|`` (cached on the surface).

    ``λ_max(M⁻¹L) ≤ ρ(M⁻¹|L|)`` because ``|xᵀLx| ≤ |x|ᵀ|L||x|``, and for the
    non-negative ``M⁻¹|L|`` and any positive ``w``,
    ``ρ ≤ max_i (M⁻¹|L|w)_i / w_i`` (Collatz–Wielandt).  With ``w = 1`` this
    is Gershgorin's bound ``max_i Σ_j |L_ij| / M_ii``; power iterations
    ``w ← M⁻¹|L|w`` tighten it towards ``ρ``.  Every iterate gives a valid
    bound and the smallest is kept.  On meshes ``ρ`` is within a few per
    cent of ``λ_max`` (the top eigenvector sits at the worst-shaped
    vertices), where Gershgorin is 1.3–2× above it.
    """
    key = "riesz:upper_bound"
    if key not in surface.cache:
        lap = abs(surface.stiffness)
        inv_mass = 1.0 / surface.mass_diagonal
        w = np.ones(surface.n_vertices)
        best = np.inf
        for _ in range(_POWER_ITERATIONS):
            y = inv_mass * (lap @ w)
            top = float(np.max(y))
            best = min(best, float(np.max(y / w)))
            if top == 0:
                break
            # rows of |L| that are zero give 0 whatever w is: keep w positive there
            w = np.where(y > 0, y / top, 1.0)
        surface.cache[key] = best
    return surface.cache[key]


class _ShiftedSystems:
    """``L + σM`` for many ``σ`` on one fixed sparsity pattern (``L``'s plus the diagonal)."""

    def __init__(self, surface: Surface):
        lap = surface.stiffness
        n = lap.shape[0]
        pattern = (abs(lap) + sp.eye(n, format="csr")).tocsr()
        pattern.sum_duplicates()
        pattern.sort_indices()
        rows = np.repeat(np.arange(n), np.diff(pattern.indptr))
        keys = rows * n + pattern.indices
        coo = lap.tocoo()
        stored = coo.data != 0  # explicit zeros of L may be missing from the pattern
        self.l_data = np.zeros(len(keys))
        np.add.at(self.l_data, np.searchsorted(keys, coo.row[stored].astype(np.int64) * n + coo.col[stored]),
                  coo.data[stored])
        self.m_data = np.zeros(len(keys))
        self.m_data[np.searchsorted(keys, np.arange(n, dtype=np.int64) * (n + 1))] = surface.mass_diagonal
        self.indptr, self.indices, self.n = pattern.indptr, pattern.indices, n

    def matrix(self, sigma: float) -> sp.csr_matrix:
        return sp.csr_matrix((self.l_data + sigma * self.m_data, self.indices.copy(), self.indptr.copy()),
                             shape=(self.n, self.n))


def _systems(surface: Surface) -> _ShiftedSystems:
    key = "riesz:shifted_systems"
    if key not in surface.cache:
        surface.cache[key] = _ShiftedSystems(surface)
    return surface.cache[key]


def shifted_matrix(surface: Surface, sigma: float) -> sp.csr_matrix:
    """``L + σ M`` on the pattern shared by every shift (explicit zeros kept).

    Parameters
    ----------
    surface : Surface
    sigma : float
        Shift; ``L + σM`` is SPD for ``σ > 0``.
    """
    return _systems(check_surface(surface)).matrix(float(sigma))


def shifted_solve(surface: Surface, sigma: float, rhs, *, backend: str | None = None,
                  symbolic: linalg.SymbolicFactorization | None = None) -> np.ndarray:
    """Solve ``(L + σM) x = rhs`` with one factorization for all columns.

    One term of the quadrature of :func:`fractional_laplacian`; independent
    of the other shifts, so a scheduler may run each shift as its own task.

    Parameters
    ----------
    surface : Surface
    sigma : float
        Shift ``> 0``.
    rhs : (n,) or (n, k) array_like
        Right-hand sides (for the quadrature: ``M f̃``, one column per signal).
    backend : str, optional
        Sparse solver (:func:`hht3d.linalg.backends.available_backends`).
    symbolic : SymbolicFactorization, optional
        From :func:`shift_analysis`, to analyse the pattern only once.

    Returns
    -------
    ndarray, shape of ``rhs``
    """
    if not sigma > 0:
        raise InputError(f"the shift must be positive (L + σM is then SPD), got {sigma}")
    symbolic = symbolic or shift_analysis(surface, backend)
    return symbolic.factorize(shifted_matrix(surface, sigma)).solve(rhs)


def shift_analysis(surface: Surface, backend: str | None = None) -> linalg.SymbolicFactorization:
    """Symbolic analysis of the pattern of every ``L + σM`` (:func:`shifted_matrix`).

    Pass it as ``symbolic=`` to :func:`shifted_solve` and
    :func:`spectral_bounds` to order and analyse the pattern only once.
    """
    return linalg.SymbolicFactorization(shifted_matrix(surface, 1.0), backend)


def _deflated_shift_invert(surface: Surface, shift: float,
                           symbolic: linalg.SymbolicFactorization) -> spla.LinearOperator:
    """``y ↦ P (L + shift·M)⁻¹ y`` with ``P`` the M-orthogonal projector off the kernel.

    In ARPACK's generalized shift-invert mode (``sigma = −shift``) the
    operator is applied to ``M x``; the projection confines the iteration to
    the complement of the kernel, so the first Ritz values are ``λ_1, λ_2…``.
    """
    factor = symbolic.factorize(shifted_matrix(surface, shift))
    n = surface.n_vertices
    return spla.LinearOperator((n, n), matvec=lambda y: remove_kernel(surface, factor.solve(np.ravel(y))),
                               dtype=np.float64)


def _start_vector(surface: Surface) -> np.ndarray:
    """A fixed (seeded) starting vector M-orthogonal to the kernel."""
    return remove_kernel(surface, np.random.default_rng(0).standard_normal(surface.n_vertices))


def _tiny_shift(mbar: float) -> float:
    """Keeps ``L + shift·M`` non-singular; below ``λ_1`` whenever ``M̄/λ_1 < 1e9``.

    Shift-invert finds the eigenvalues nearest the shift first, so ``λ_1`` is
    found even on a worse-conditioned surface, only more slowly.
    """
    return 1e-9 * mbar


def _arpack_smallest(surface: Surface, k: int, symbolic: linalg.SymbolicFactorization, mbar: float,
                     return_vectors: bool, tol: float = 0.0):
    """The ``k`` smallest non-zero generalized eigenpairs by shift-invert Lanczos.

    Lanczos Ritz values of ``(L + s M)⁻¹M`` never exceed its largest
    eigenvalue, so each returned ``λ`` is at least the true one.
    """
    shift = _tiny_shift(mbar)
    op = _deflated_shift_invert(surface, shift, symbolic)
    return spla.eigsh(surface.stiffness, k=k, M=surface.mass, sigma=-shift, OPinv=op, which="LM",
                      v0=_start_vector(surface), return_eigenvectors=return_vectors, tol=tol)


def _lobpcg_lambda1(surface: Surface, symbolic: linalg.SymbolicFactorization, mbar: float) -> float:
    """Fallback estimate of ``λ_1``: LOBPCG preconditioned by the near-exact shifted solve."""
    op = _deflated_shift_invert(surface, _tiny_shift(mbar), symbolic)
    kernel = np.zeros((surface.n_vertices, surface.n_components))
    kernel[np.arange(surface.n_vertices), surface.component_labels] = 1.0
    x = _start_vector(surface)[:, None]
    values, vectors = spla.lobpcg(surface.stiffness, x, B=surface.mass, M=op, Y=kernel, tol=1e-8,
                                  maxiter=200, largest=False)
    lam, v = float(values[0]), vectors[:, 0]
    mass = surface.mass_diagonal
    residual = surface.stiffness @ v - lam * mass * v
    # ‖M^{-1/2} r‖ / ‖v‖_M bounds the distance from lam to the nearest eigenvalue
    if not np.isfinite(lam) or (np.sqrt(np.sum(residual ** 2 / mass))
                                > 1e-2 * lam * np.sqrt(np.sum(v * v * mass))):
        raise NumericalError(f"{surface.name}: could not estimate the smallest non-zero eigenvalue "
                             "(ARPACK and LOBPCG failed); use method='dense' or 'spectral'")
    return lam


def spectral_bounds(surface: Surface, *, backend: str | None = None,
                    symbolic: linalg.SymbolicFactorization | None = None) -> tuple[float, float]:
    """Bounds ``0 < m ≤ λ_1`` and ``M̄ ≥ λ_max`` of the non-zero spectrum of ``L φ = λ M φ``.

    ``λ_1`` (the smallest non-zero eigenvalue) comes from shift-invert
    Lanczos (``scipy.sparse.linalg.eigsh``, relative accuracy 1e-6) on the
    complement of the kernel, with the sparse factorization of
    :mod:`hht3d.linalg.backends`; ``m = 0.9·λ_1``.  If ARPACK does not converge,
    LOBPCG preconditioned with the same factorization is used, and ``m`` is
    then half its estimate.  ``M̄`` is a Collatz–Wielandt bound, Gershgorin's
    ``max_i Σ_j |L_ij| / M_ii`` tightened by a few power iterations.  Cached
    on the surface.

    Parameters
    ----------
    surface : Surface
    backend : str, optional
        Sparse solver of :mod:`hht3d.linalg.backends`.
    symbolic : SymbolicFactorization, optional
        From :func:`shift_analysis`, to share the ordering with the solves.

    Returns
    -------
    (m, M̄) : tuple of float
    """
    surface = check_surface(surface)
    key = "riesz:bounds"
    if key not in surface.cache:
        if surface.n_vertices - surface.n_components < 1:
            raise InputError(f"{surface.name}: every connected component is a single vertex; "
                             "the Laplacian has no non-zero eigenvalue")
        symbolic = symbolic or shift_analysis(surface, backend)
        mbar = _upper_bound(surface)
        try:
            m = SAFETY * float(np.min(_arpack_smallest(surface, 1, symbolic, mbar, False, tol=1e-6)))
        except (spla.ArpackNoConvergence, spla.ArpackError):
            m = 0.5 * _lobpcg_lambda1(surface, symbolic, mbar)
        if not 0 < m < mbar:
            raise NumericalError(f"{surface.name}: invalid spectral bounds m={m:g}, M̄={mbar:g}")
        surface.cache[key] = (m, mbar)
    return surface.cache[key]


def _nodes(m: float, mbar: float, count: int) -> tuple[np.ndarray, np.ndarray]:
    """Elliptic midpoint rule with ``count`` nodes (Hale, Higham & Trefethen 2008, method 3)."""
    p = 1.0 - m / mbar  # parameter (modulus squared) of the Jacobi functions
    kp = ellipk(p)
    u = (np.arange(1, count + 1) - 0.5) * kp / count
    sn, cn, dn, _ = ellipj(u, p)
    sigmas = m * (sn / cn) ** 2
    weights = 2.0 * kp * np.sqrt(m) / (np.pi * count) * dn / cn ** 2
    return sigmas, weights


def _scalar_error(m: float, mbar: float, sigmas: np.ndarray, weights: np.ndarray) -> float:
    """``max |Σ_j w_j/(λ+σ_j) · √λ − 1|`` over log-spaced ``λ ∈ [m, M̄]``."""
    lam = np.geomspace(m, mbar, _CHECK_POINTS)
    approx = (weights / (lam[:, None] + sigmas)).sum(axis=1)
    return float(np.max(np.abs(approx * np.sqrt(lam) - 1.0)))


def quadrature_nodes(m: float, mbar: float, tol: float = RIESZ_DEFAULTS.tol) -> tuple[np.ndarray, np.ndarray]:
    """Shifts and weights of ``λ^{-1/2} ≈ Σ_j w_j / (λ + σ_j)`` on ``[m, M̄]``.

    With ``t = √m · sn(u)/cn(u)`` (Jacobi functions of parameter
    ``1 − m/M̄``) the integral ``λ^{-1/2} = (2/π) ∫_0^∞ dt / (t² + λ)`` becomes
    an integral over ``[0, K]`` that the midpoint rule with ``N`` points
    resolves geometrically fast, error ``≈ exp(−2π²N / (ln(M̄/m) + c))``.

    ``N`` is the fewest nodes whose relative error
    ``max_λ |Σ_j w_j √λ/(λ + σ_j) − 1|``, checked on a fine log grid of
    ``[m, M̄]``, is at most ``tol``.  This bounds the result too: for any
    ``f``, ``‖approx − L^{-1/2} f̃‖_M ≤ tol · ‖L^{-1/2} f̃‖_M``.

    Parameters
    ----------
    m, mbar : float
        ``0 < m ≤ λ_min`` and ``M̄ ≥ λ_max``.
    tol : float
        Relative accuracy, ``1e-13 ≤ tol < 1``.

    Returns
    -------
    sigmas, weights : (N,) ndarrays, positive
    """
    if not 0 < m < mbar or not np.isfinite(mbar):
        raise InputError(f"spectral bounds must satisfy 0 < m < M̄ < inf, got m={m!r}, M̄={mbar!r}")
    if not MIN_TOL <= tol < 1:
        raise InputError(f"quadrature tolerance must lie in [{MIN_TOL:g}, 1), got {tol!r}")
    for count in range(1, _MAX_SHIFTS + 1):
        sigmas, weights = _nodes(m, mbar, count)
        if _scalar_error(m, mbar, sigmas, weights) <= tol:
            return sigmas, weights
    raise NumericalError(f"no quadrature with at most {_MAX_SHIFTS} shifts reaches tol={tol:g} on "
                         f"[{m:g}, {mbar:g}] (condition {mbar / m:.3g}); loosen tol")


# -- the three methods ------------------------------------------------------------------------

@dataclass(frozen=True)
class QuadraturePlan:
    """Spectral bounds and quadrature nodes of one surface (:func:`quadrature_plan`).

    Attributes
    ----------
    bounds : (m, M̄)
        ``m ≤ λ_1`` and ``M̄ ≥ λ_max`` (:func:`spectral_bounds`).
    tol : float
    sigmas, weights : (N,) ndarrays
        Shifts and weights (:func:`quadrature_nodes`).
    """

    bounds: tuple[float, float]
    tol: float
    sigmas: np.ndarray
    weights: np.ndarray


def quadrature_plan(surface: Surface, tol: float = RIESZ_DEFAULTS.tol, backend: str | None = None, *,
                    symbolic: linalg.SymbolicFactorization | None = None) -> QuadraturePlan:
    """Bounds and nodes of the ``L^{-1/2}`` quadrature for ``surface`` at ``tol``."""
    bounds = spectral_bounds(surface, backend=backend, symbolic=symbolic)
    return QuadraturePlan(bounds, tol, *quadrature_nodes(*bounds, tol))


def quadrature_part(surface: Surface, f, plan: QuadraturePlan, group: int = 0, groups: int = 1,
                    backend: str | None = None, *,
                    symbolic: linalg.SymbolicFactorization | None = None) -> np.ndarray:
    """Partial sum ``Σ_j w_j (L + σ_j M)⁻¹ M f̃`` over the shifts ``j ≡ group (mod groups)``.

    Parameters
    ----------
    surface : Surface
    f : (n,) or (k, n) array_like
        Signals; the kernel is removed here (:func:`remove_kernel`).
    plan : QuadraturePlan
    group, groups : int
        This part's shifts: every ``groups``-th, from ``group``.
    backend, symbolic
        As in :func:`shifted_solve`.

    Returns
    -------
    ndarray, shape of ``f``
        Add all parts with :func:`combine_quadrature_parts`.
    """
    if not (int(groups) == groups >= 1 and int(group) == group and 0 <= group < groups):
        raise InputError(f"need 0 <= group < groups with integers, got group={group!r}, groups={groups!r}")
    g = remove_kernel(surface, f)
    rhs = (surface.mass_diagonal * np.atleast_2d(g)).T  # (n, k): M f̃, one column per signal
    total = np.zeros_like(rhs)
    mine = slice(int(group), None, int(groups))
    if rhs.size and len(plan.sigmas[mine]):
        symbolic = symbolic or shift_analysis(surface, backend)
        for sigma, weight in zip(plan.sigmas[mine], plan.weights[mine]):
            total += weight * shifted_solve(surface, sigma, rhs, symbolic=symbolic)
    return total.T.reshape(g.shape)


def combine_quadrature_parts(surface: Surface, parts) -> np.ndarray:
    """``L^{-1/2} f̃`` from all :func:`quadrature_part` results (kernel removed again)."""
    return remove_kernel(surface, np.sum(parts, axis=0))


def _quadrature(surface: Surface, g: np.ndarray, tol: float, backend: str | None) -> np.ndarray:
    symbolic = shift_analysis(surface, backend)
    plan = quadrature_plan(surface, tol, symbolic=symbolic)
    return combine_quadrature_parts(surface, [quadrature_part(surface, g, plan, symbolic=symbolic)])


def _dense_eigenpairs(surface: Surface) -> tuple[np.ndarray, np.ndarray]:
    """All non-zero generalized eigenpairs (ascending), eigenvectors M-orthonormal; cached."""
    n = surface.n_vertices
    if n > DENSE_MAX_VERTICES:
        raise InputError(f"{surface.name} has {n} vertices; the dense eigendecomposition is limited "
                         f"to {DENSE_MAX_VERTICES} (it needs n² memory and n³ time): use "
                         "method='quadrature'")
    key = "riesz:dense_eigenpairs"
    if key not in surface.cache:
        scale = 1.0 / np.sqrt(surface.mass_diagonal)
        a = surface.stiffness.toarray() * scale[:, None] * scale[None, :]  # M^{-1/2} L M^{-1/2}
        values, vectors = scipy.linalg.eigh(a, overwrite_a=True)
        kernel = surface.n_components  # the per-component constants come first
        surface.cache[key] = (values[kernel:], vectors[:, kernel:] * scale[:, None])
    return surface.cache[key]


def smallest_eigenpairs(surface: Surface, count: int, *,
                        backend: str | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The ``count`` smallest non-zero eigenpairs of ``L φ = λ M φ`` (cached on the surface).

    The kernel (per-component constants) is not counted.  ARPACK in
    shift-invert mode on the complement of the kernel computes them, except
    when they are a large part of the spectrum (at least a tenth on surfaces
    within :data:`DENSE_MAX_VERTICES`, or half): then the dense
    eigendecomposition, cheaper there, is truncated.

    Returns
    -------
    values : (count,) ndarray, ascending
    vectors : (n, count) ndarray, M-orthonormal columns
    """
    surface = check_surface(surface)
    available = surface.n_vertices - surface.n_components
    if int(count) != count or not 1 <= count <= available:
        raise InputError(f"eigenpairs must be an integer in [1, {available}] for {surface.name} "
                         f"({available} non-zero eigenvalues), got {count!r}")
    count = int(count)
    if 2 * count >= available or (surface.n_vertices <= DENSE_MAX_VERTICES and 10 * count >= available):
        values, vectors = _dense_eigenpairs(surface)
        return values[:count], vectors[:, :count]
    key = "riesz:eigenpairs"
    cached = surface.cache.get(key)
    if cached is None or len(cached[0]) < count:
        mbar = _upper_bound(surface)
        values, vectors = _arpack_smallest(surface, count, shift_analysis(surface, backend), mbar, True)
        order = np.argsort(values)
        cached = surface.cache[key] = (values[order], vectors[:, order])
    return cached[0][:count], cached[1][:, :count]


def _apply_eigenpairs(surface: Surface, g: np.ndarray, values, vectors, power: float) -> np.ndarray:
    coefficients = (g * surface.mass_diagonal) @ vectors  # (k, p) = gᵀ M Φ
    return (coefficients * values ** power) @ vectors.T


# -- public API ------------------------------------------------------------------------------

def fractional_laplacian(surface: Surface, f, power: float = -0.5, method: str = RIESZ_DEFAULTS.method,
                         tol: float = RIESZ_DEFAULTS.tol, eigenpairs: int = RIESZ_DEFAULTS.eigenpairs,
                         backend: str | None = RIESZ_DEFAULTS.backend) -> np.ndarray:
    """Apply ``L^{power}`` of the generalized problem ``L φ = λ M φ`` (Eqs. 13, 15, 18).

    Parameters
    ----------
    surface : Surface
    f : (n,) or (k, n) array_like
        One signal or ``k`` signals (e.g. all IMFs); all are processed at once.
    power : float
        Exponent; ``-0.5`` gives ``L^{-1/2}`` of the Riesz transform.
        ``"quadrature"`` supports only ``-0.5``; the eigen-methods any
        non-zero power.
    method : {"quadrature", "spectral", "dense"}
        See the module notes.  ``"quadrature"`` is exact to ``tol``;
        ``"spectral"`` is the paper's truncation to ``eigenpairs`` modes;
        ``"dense"`` is the exact reference (at most
        :data:`DENSE_MAX_VERTICES` vertices).
    tol : float
        Relative accuracy of ``"quadrature"`` in the M-norm; sets the number
        of shifted solves (about 17 for a condition number of 1e6 at 1e-8).
    eigenpairs : int
        Non-zero eigenpairs used by ``"spectral"`` (the paper uses 300).
    backend : str, optional
        Sparse solver of :mod:`hht3d.linalg.backends`.

    Returns
    -------
    ndarray, shape of ``f``
        ``L^{power} f̃``, M-orthogonal to the kernel: the per-component
        constants are removed from ``f`` first (see :func:`remove_kernel`).

    Examples
    --------
    On the unit sphere ``z`` is a spherical harmonic of degree 1, an
    eigenfunction with ``λ = l(l + 1) = 2``, so ``L^{-1/2} z = z / √2``:

    >>> import numpy as np
    >>> from hht3d import data_path, fractional_laplacian, load
    >>> sphere = load(data_path("sphere_oct4098.ply"))
    >>> z = sphere.vertices[:, 2]
    >>> u = fractional_laplacian(sphere, z)
    >>> bool(np.abs(np.sqrt(2) * u - z).max() < 1e-3)
    True
    """
    surface = check_surface(surface)
    a, single = as_signals(surface, f)
    check_choice(method, METHODS, "method")
    if not np.isfinite(power) or power == 0:
        raise InputError(f"power must be a finite non-zero number, got {power!r}")
    g = remove_kernel(surface, a)
    if len(g) == 0:  # no signals (e.g. an EMD that found no IMF)
        return g
    if method == "quadrature":
        if power != -0.5:
            raise InputError(f"method='quadrature' computes power=-0.5 only, got power={power}; "
                             "use method='spectral' or 'dense' for other powers")
        out = _quadrature(surface, g, tol, backend)
    else:
        values, vectors = (_dense_eigenpairs(surface) if method == "dense"
                           else smallest_eigenpairs(surface, eigenpairs, backend=backend))
        out = _apply_eigenpairs(surface, g, values, vectors, power)
    return out[0] if single else out


def riesz(surface: Surface, f, *, gradient: str = RIESZ_DEFAULTS.gradient, method: str = RIESZ_DEFAULTS.method,
          tol: float = RIESZ_DEFAULTS.tol, eigenpairs: int = RIESZ_DEFAULTS.eigenpairs,
          backend: str | None = RIESZ_DEFAULTS.backend) -> np.ndarray:
    """Riesz transform ``R f = ∇ L^{-1/2} f`` (Eqs. 14, 16; Eq. 18 with ``method="spectral"``).

    Parameters
    ----------
    surface : Surface
    f : (n,) or (k, n) array_like
    gradient : {"lsq", "fem"}
        Vertex gradient: tangent-plane least squares of Eq. (17) (meshes and
        point clouds) or area-averaged per-face FEM gradients (meshes).
    method, tol, eigenpairs, backend
        As in :func:`fractional_laplacian`.

    Returns
    -------
    (n, 3) or (k, n, 3) ndarray
        Tangent vectors, one per vertex (and signal).

    Examples
    --------
    The Riesz transform is an isometry: ``∫|Rf|² dA = ∫f̃² dA`` for the signal
    without its mean, ``f̃`` (with FEM gradients up to their vertex averaging):

    >>> import numpy as np
    >>> from hht3d import data_path, load, riesz
    >>> from hht3d.spectral.riesz_transform import remove_kernel
    >>> sphere = load(data_path("sphere_oct4098.ply"))
    >>> f = sphere.vertices[:, 0] * sphere.vertices[:, 1] + sphere.vertices[:, 2]
    >>> rf = riesz(sphere, f, gradient="fem")
    >>> area, f_tilde = sphere.mass_diagonal, remove_kernel(sphere, f)
    >>> round(float(area @ (rf ** 2).sum(axis=1) / (area @ f_tilde ** 2)), 2)
    1.0
    """
    surface = check_surface(surface)
    check_choice(gradient, GRADIENTS, "gradient")
    u = fractional_laplacian(surface, f, -0.5, method, tol, eigenpairs, backend)
    return vertex_gradient(surface, u, gradient)


def vertex_gradient(surface: Surface, u: np.ndarray, kind: str = RIESZ_DEFAULTS.gradient) -> np.ndarray:
    """Tangent gradients of (n,) or (k, n) per-vertex fields: (n, 3) or (k, n, 3)."""
    grad = surface.gradient(kind)
    n = surface.n_vertices
    u2 = np.atleast_2d(u)
    out = np.asarray(grad @ u2.T).reshape(n, 3, len(u2)).transpose(2, 0, 1)
    return out[0] if np.ndim(u) == 1 else out
