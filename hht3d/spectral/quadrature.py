"""The elliptic quadrature of ``L^{-1/2}`` (Hale, Higham & Trefethen 2008) and its shift groups.

``L^{-1/2} f̃ ≈ Σ_j w_j (L + σ_j M)⁻¹ M f̃`` with shifts and weights from
:func:`quadrature_nodes` over the bounds of
:func:`~hht3d.spectral.eigenpairs.spectral_bounds`.  The shifts are
independent, so a scheduler can split them into groups
(:func:`quadrature_part`) and sum the parts (:func:`combine_quadrature_parts`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.special import ellipj, ellipk

from .. import linalg
from ..errors import InputError, NumericalError
from ..geometry.signals import fluctuation
from ..geometry.surface import Surface
from .eigenpairs import spectral_bounds
from .options import MIN_TOL, RIESZ_DEFAULTS
from .shifts import shift_analysis, solve_shifts

__all__ = [
    "quadrature_nodes",
    "QuadraturePlan",
    "quadrature_plan",
    "quadrature_part",
    "combine_quadrature_parts",
    "quadrature_sum",
]

#: λ sample points per quadrature check (log-spaced over ``[m, M̄]``).
CHECK_POINTS = 2000
#: Most shifts :func:`quadrature_nodes` tries before giving up.
MAX_SHIFTS = 200


def _nodes(m: float, mbar: float, count: int) -> tuple[np.ndarray, np.ndarray]:
    """Elliptic midpoint rule with ``count`` nodes (Hale, Higham & Trefethen 2008, method 3)."""
    p = 1.0 - m / mbar  # parameter (modulus squared) of the Jacobi functions
    kp = ellipk(p)
    u = (np.arange(1, count + 1) - 0.5) * kp / count
    sn, cn, dn, _ = ellipj(u, p)
    sigmas = m * (sn / cn) ** 2
    weights = 2.0 * kp * np.sqrt(m) / (np.pi * count) * dn / cn**2
    return sigmas, weights


def _scalar_error(m: float, mbar: float, sigmas: np.ndarray, weights: np.ndarray) -> float:
    """``max |Σ_j w_j/(λ+σ_j) · √λ − 1|`` over log-spaced ``λ ∈ [m, M̄]``."""
    lam = np.geomspace(m, mbar, CHECK_POINTS)
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
    for count in range(1, MAX_SHIFTS + 1):
        sigmas, weights = _nodes(m, mbar, count)
        if _scalar_error(m, mbar, sigmas, weights) <= tol:
            return sigmas, weights
    raise NumericalError(
        f"no quadrature with at most {MAX_SHIFTS} shifts reaches tol={tol:g} on "
        f"[{m:g}, {mbar:g}] (condition {mbar / m:.3g}); loosen tol"
    )


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


def quadrature_plan(
    surface: Surface,
    tol: float = RIESZ_DEFAULTS.tol,
    backend: str | None = None,
    *,
    symbolic: linalg.SymbolicFactorization | None = None,
) -> QuadraturePlan:
    """Bounds and nodes of the ``L^{-1/2}`` quadrature for ``surface`` at ``tol``.

    Parameters
    ----------
    surface : Surface
        The surface.
    tol : float, optional
        The quadrature's relative tolerance (default 1e-8).
    backend : str, optional
        The sparse solver backend of the bounds (default :func:`hht3d.linalg.default_backend`).
    symbolic : SymbolicFactorization, optional
        A symbolic factorization of the operator's pattern to reuse.

    Returns
    -------
    QuadraturePlan
        The spectral bounds, ``tol`` and the nodes.

    Examples
    --------
    >>> import open3d as o3d
    >>> from hht3d.io import surface_from_open3d
    >>> ball = surface_from_open3d(o3d.geometry.TriangleMesh.create_sphere(radius=1.0, resolution=8))
    >>> from hht3d.spectral import quadrature_plan
    >>> loose, tight = quadrature_plan(ball, tol=1e-4), quadrature_plan(ball, tol=1e-10)
    >>> len(loose.sigmas) < len(tight.sigmas)  # a tighter tolerance takes more shifts
    True
    """
    bounds = spectral_bounds(surface, backend=backend, symbolic=symbolic)
    return QuadraturePlan(bounds, tol, *quadrature_nodes(*bounds, tol))


def quadrature_part(
    surface: Surface,
    f: np.ndarray,
    plan: QuadraturePlan,
    group: int = 0,
    groups: int = 1,
    backend: str | None = None,
    *,
    symbolic: linalg.SymbolicFactorization | None = None,
) -> np.ndarray:
    """Partial sum ``Σ_j w_j (L + σ_j M)⁻¹ M f̃`` over the shifts ``j ≡ group (mod groups)``.

    From the largest shift down, each is solved by Jacobi-preconditioned CG
    (:func:`~hht3d.linalg.pcg.jacobi_cg`, relative residual
    :func:`~hht3d.linalg.cg.rtol_for` ``(tol)``) while it converges within the backend's
    ``factorization_iterations``; the first that does not, and every smaller one, are factorized,
    by a second thread from the smallest up meanwhile where the backend allows
    (:func:`~hht3d.spectral.shifts.solve_shifts`).

    Parameters
    ----------
    surface : Surface
    f : (n,) or (k, n) array_like
        Signals; the kernel is removed here (:func:`fluctuation`).
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
    g = fluctuation(surface, f)
    rhs = (surface.mass_diagonal * np.atleast_2d(g)).T  # (n, k): M f̃, one column per signal
    total = np.zeros_like(rhs)
    mine = slice(int(group), None, int(groups))
    shifts = sorted(zip(plan.sigmas[mine], plan.weights[mine]), reverse=True) if rhs.size else []
    sigmas = np.array([sigma for sigma, _ in shifts])
    solutions = solve_shifts(surface, rhs, sigmas, plan.tol, backend, symbolic) if shifts else []
    for (_, weight), x in zip(shifts, solutions):
        total += weight * x
    return total.T.reshape(g.shape)


def combine_quadrature_parts(surface: Surface, parts: Sequence[np.ndarray]) -> np.ndarray:
    """``L^{-1/2} f̃`` from all :func:`quadrature_part` results (kernel removed again).

    Parameters
    ----------
    surface : Surface
        The surface the parts were computed on.
    parts : sequence of ndarray
        Every :func:`quadrature_part` result, each ``(k, n)``.

    Returns
    -------
    (k, n) ndarray
        The potential ``L^{-1/2} f̃``.
    """
    return fluctuation(surface, np.sum(parts, axis=0))


def quadrature_sum(surface: Surface, g: np.ndarray, tol: float, backend: str | None) -> np.ndarray:
    symbolic = shift_analysis(surface, backend, tol)
    plan = quadrature_plan(surface, tol, symbolic=symbolic)
    return combine_quadrature_parts(surface, [quadrature_part(surface, g, plan, symbolic=symbolic)])
