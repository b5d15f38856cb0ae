"""Spectral bounds and eigenpairs of ``L φ = λ M φ`` (Sec. 4.2; Eq. 15, Alg. 1).

:func:`spectral_bounds` gives ``m ≤ λ_1`` and ``M̄ ≥ λ_max`` for the
quadrature; :func:`smallest_eigenpairs` the paper's truncated basis
(Eq. 18); :func:`dense_eigenpairs` the exact reference on small surfaces.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.linalg
import scipy.sparse.linalg as spla

from .. import linalg
from ..errors import InputError, NumericalError
from ..geometry.signals import fluctuation
from ..geometry.surface import Surface
from ..geometry.validation import check_surface
from ..linalg.chebyshev import spectral_radius_bound
from .shifts import shift_analysis, shifted_matrix

__all__ = [
    "spectral_bounds",
    "smallest_eigenpairs",
    "dense_eigenpairs",
    "apply_eigenpairs",
    "upper_bound",
    "DENSE_MAX_VERTICES",
    "SAFETY",
]

#: Largest surface the ``"dense"`` method accepts (an n×n float64 eigendecomposition).
DENSE_MAX_VERTICES = 6000
#: ``m = SAFETY · λ_1`` so that the lower bound stays below ``λ_1`` despite
#: eigensolver error.
SAFETY = 0.9
#: ARPACK gives way to the dense eigendecomposition when the eigenpairs asked for are at least
#: this fraction of the spectrum (dense is then cheaper: ARPACK's work grows with the count) ...
DENSE_SHARE = 0.5
#: ... or this fraction on surfaces small enough for the dense method (its n³ cost is small there).
DENSE_SHARE_SMALL = 0.1


def upper_bound(surface: Surface) -> float:
    """``M̄ ≥ λ_max``: :func:`~hht3d.linalg.chebyshev.spectral_radius_bound` of ``L`` and ``M`` (cached on the
    surface); on meshes within a few per cent of ``λ_max``, where Gershgorin is 1.3–2× above it."""
    key = "riesz:upper_bound"
    if key not in surface.cache:
        surface.cache[key] = spectral_radius_bound(surface.stiffness, surface.mass_diagonal)
    return surface.cache[key]


def _deflated_shift_invert(
    surface: Surface, shift: float, symbolic: linalg.SymbolicFactorization
) -> spla.LinearOperator:
    """``y ↦ P (L + shift·M)⁻¹ y`` with ``P`` the M-orthogonal projector off the kernel.

    In ARPACK's generalized shift-invert mode (``sigma = −shift``) the
    operator is applied to ``M x``; the projection confines the iteration to
    the complement of the kernel, so the first Ritz values are ``λ_1, λ_2…``.
    """
    factor = symbolic.factorize(shifted_matrix(surface, shift))
    n = surface.n_vertices
    return spla.LinearOperator(
        (n, n), matvec=lambda y: fluctuation(surface, factor.solve(np.ravel(y))), dtype=np.float64
    )


def _start_vector(surface: Surface) -> np.ndarray:
    """A fixed (seeded) starting vector M-orthogonal to the kernel."""
    return fluctuation(surface, np.random.default_rng(0).standard_normal(surface.n_vertices))


def _tiny_shift(mbar: float) -> float:
    """Keeps ``L + shift·M`` non-singular; below ``λ_1`` whenever ``M̄/λ_1 < 1e9``.

    Shift-invert finds the eigenvalues nearest the shift first, so ``λ_1`` is
    found even on a worse-conditioned surface, only more slowly.
    """
    return 1e-9 * mbar


def _arpack_smallest(
    surface: Surface,
    k: int,
    symbolic: linalg.SymbolicFactorization,
    mbar: float,
    return_vectors: bool,
    tol: float = 0.0,
) -> Any:
    """The ``k`` smallest non-zero generalized eigenpairs by shift-invert Lanczos.

    Lanczos Ritz values of ``(L + s M)⁻¹M`` never exceed its largest
    eigenvalue, so each returned ``λ`` is at least the true one.
    """
    shift = _tiny_shift(mbar)
    op = _deflated_shift_invert(surface, shift, symbolic)
    return spla.eigsh(
        surface.stiffness,
        k=k,
        M=surface.mass,
        sigma=-shift,
        OPinv=op,
        which="LM",
        v0=_start_vector(surface),
        return_eigenvectors=return_vectors,
        tol=tol,
    )


def _lobpcg_lambda1(surface: Surface, symbolic: linalg.SymbolicFactorization, mbar: float) -> float:
    """Fallback estimate of ``λ_1``: LOBPCG preconditioned by the near-exact shifted solve."""
    op = _deflated_shift_invert(surface, _tiny_shift(mbar), symbolic)
    kernel = np.zeros((surface.n_vertices, surface.n_components))
    kernel[np.arange(surface.n_vertices), surface.component_labels] = 1.0
    x = _start_vector(surface)[:, None]
    values, vectors = spla.lobpcg(
        surface.stiffness, x, B=surface.mass, M=op, Y=kernel, tol=1e-8, maxiter=200, largest=False
    )
    lam, v = float(values[0]), vectors[:, 0]
    mass = surface.mass_diagonal
    residual = surface.stiffness @ v - lam * mass * v
    # ‖M^{-1/2} r‖ / ‖v‖_M bounds the distance from lam to the nearest eigenvalue
    if not np.isfinite(lam) or (np.sqrt(np.sum(residual**2 / mass)) > 1e-2 * lam * np.sqrt(np.sum(v * v * mass))):
        raise NumericalError(
            f"{surface.name}: could not estimate the smallest non-zero eigenvalue "
            "(ARPACK and LOBPCG failed); use method='dense' or 'spectral'"
        )
    return lam


def spectral_bounds(
    surface: Surface, *, backend: str | None = None, symbolic: linalg.SymbolicFactorization | None = None
) -> tuple[float, float]:
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

    Examples
    --------
    >>> import open3d as o3d
    >>> from hht3d.io import surface_from_open3d
    >>> ball = surface_from_open3d(o3d.geometry.TriangleMesh.create_sphere(radius=1.0, resolution=8))
    >>> from hht3d.spectral import dense_eigenpairs, spectral_bounds
    >>> low, high = spectral_bounds(ball)
    >>> values, _ = dense_eigenpairs(ball)
    >>> bool(0 < low <= values[0] and values[-1] <= high)
    True
    """
    surface = check_surface(surface)
    key = "riesz:bounds"
    if key not in surface.cache:
        if surface.n_vertices - surface.n_components < 1:
            raise InputError(
                f"{surface.name}: every connected component is a single vertex; "
                "the Laplacian has no non-zero eigenvalue"
            )
        symbolic = symbolic or shift_analysis(surface, backend)
        mbar = upper_bound(surface)
        try:
            m = SAFETY * float(np.min(_arpack_smallest(surface, 1, symbolic, mbar, False, tol=1e-6)))
        except (spla.ArpackNoConvergence, spla.ArpackError):
            m = 0.5 * _lobpcg_lambda1(surface, symbolic, mbar)
        if not 0 < m < mbar:
            raise NumericalError(f"{surface.name}: invalid spectral bounds m={m:g}, M̄={mbar:g}")
        surface.cache[key] = (m, mbar)
    return surface.cache[key]


def dense_eigenpairs(surface: Surface) -> tuple[np.ndarray, np.ndarray]:
    """All non-zero generalized eigenpairs (ascending), eigenvectors M-orthonormal; cached.

    Parameters
    ----------
    surface : Surface
        A surface of at most :data:`DENSE_MAX_VERTICES` vertices.

    Returns
    -------
    values : (m,) ndarray
        The non-zero eigenvalues, ascending.
    vectors : (n, m) ndarray
        The eigenvectors, M-orthonormal columns.

    Examples
    --------
    >>> import open3d as o3d
    >>> from hht3d.io import surface_from_open3d
    >>> ball = surface_from_open3d(o3d.geometry.TriangleMesh.create_sphere(radius=1.0, resolution=8))
    >>> import numpy as np
    >>> from hht3d.spectral import dense_eigenpairs
    >>> values, vectors = dense_eigenpairs(ball)
    >>> values.shape, vectors.shape  # all but the constant
    ((113,), (114, 113))
    >>> bool(np.allclose(vectors.T @ (ball.mass_diagonal[:, None] * vectors), np.eye(113)))
    True
    """
    n = surface.n_vertices
    if n > DENSE_MAX_VERTICES:
        raise InputError(
            f"{surface.name} has {n} vertices; the dense eigendecomposition is limited "
            f"to {DENSE_MAX_VERTICES} (it needs n² memory and n³ time): use "
            "method='quadrature'"
        )
    key = "riesz:dense_eigenpairs"
    if key not in surface.cache:
        scale = 1.0 / np.sqrt(surface.mass_diagonal)
        a = surface.stiffness.toarray() * scale[:, None] * scale[None, :]  # M^{-1/2} L M^{-1/2}
        values, vectors = scipy.linalg.eigh(a, overwrite_a=True)
        kernel = surface.n_components  # the per-component constants come first
        surface.cache[key] = (values[kernel:], vectors[:, kernel:] * scale[:, None])
    return surface.cache[key]


def smallest_eigenpairs(surface: Surface, count: int, *, backend: str | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The ``count`` smallest non-zero eigenpairs of ``L φ = λ M φ`` (cached on the surface).

    The kernel (per-component constants) is not counted.  ARPACK in
    shift-invert mode on the complement of the kernel computes them, except
    when they are a large part of the spectrum (at least a tenth on surfaces
    within :data:`DENSE_MAX_VERTICES`, or half): then the dense
    eigendecomposition, cheaper there, is truncated.

    Parameters
    ----------
    surface : Surface
        The surface.
    count : int
        How many eigenpairs, in ``[1, n - components]``.
    backend : str, optional
        The sparse solver backend of the shift-invert (default :func:`hht3d.linalg.default_backend`).

    Returns
    -------
    values : (count,) ndarray, ascending
    vectors : (n, count) ndarray, M-orthonormal columns

    Examples
    --------
    >>> import numpy as np
    >>> from hht3d import data_path, load
    >>> from hht3d.spectral import smallest_eigenpairs
    >>> sphere = load(data_path("sphere_oct4098.ply"))
    >>> values, vectors = smallest_eigenpairs(sphere, 3)
    >>> np.round(values, 2).tolist()  # l(l + 1) = 2, three times, on the unit sphere
    [2.0, 2.0, 2.0]
    """
    surface = check_surface(surface)
    available = surface.n_vertices - surface.n_components
    if int(count) != count or not 1 <= count <= available:
        raise InputError(
            f"eigenpairs must be an integer in [1, {available}] for {surface.name} "
            f"({available} non-zero eigenvalues), got {count!r}"
        )
    count = int(count)
    if count >= DENSE_SHARE * available or (
        surface.n_vertices <= DENSE_MAX_VERTICES and count >= DENSE_SHARE_SMALL * available
    ):
        values, vectors = dense_eigenpairs(surface)
        return values[:count], vectors[:, :count]
    key = "riesz:eigenpairs"
    cached = surface.cache.get(key)
    if cached is None or len(cached[0]) < count:
        mbar = upper_bound(surface)
        values, vectors = _arpack_smallest(surface, count, shift_analysis(surface, backend), mbar, True)
        order = np.argsort(values)
        cached = surface.cache[key] = (values[order], vectors[:, order])
    return cached[0][:count], cached[1][:, :count]


def apply_eigenpairs(
    surface: Surface, g: np.ndarray, values: np.ndarray, vectors: np.ndarray, power: float
) -> np.ndarray:
    coefficients = (g * surface.mass_diagonal) @ vectors  # (k, p) = gᵀ M Φ
    return (coefficients * values**power) @ vectors.T
