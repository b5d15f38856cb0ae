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
Every potential therefore projects the kernel out: the M-weighted mean of each
component is removed from the input, ``f̃ = f − (1_cᵀ M f)/(1_cᵀ M 1_c)``
(:func:`fluctuation`), and the result is M-orthogonal to the kernel too.
So ``L^{-1/2}`` of a constant is zero and ``L^{-1/2} f == L^{-1/2} f̃``.

Potentials (``RieszOptions.potential``)
---------------------------------------
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

Each part solves each of its shifts once for all signals, as one multi-column
right-hand side: the largest by Jacobi-preconditioned CG, the rest factorized
(:func:`shifted_solve`); factorizations never leave the task.
:func:`fractional_laplacian` does the same with one group.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp

from ..errors import InputError
from ..geometry.signals import fluctuation
from ..geometry.surface import Surface
from ..geometry.validation import as_signals, check_surface
from .eigenpairs import apply_eigenpairs, dense_eigenpairs, smallest_eigenpairs
from .options import RIESZ_DEFAULTS, RieszOptions
from .quadrature import quadrature_sum

__all__ = ["fractional_laplacian", "riesz", "vertex_gradient"]


def fractional_laplacian(
    surface: Surface,
    f: np.ndarray,
    power: float = -0.5,
    options: RieszOptions | dict | None = None,
    *,
    backend: str | None = None,
    **overrides: Any,
) -> np.ndarray:
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
    options : RieszOptions or dict, optional
        ``potential`` (module notes): ``"quadrature"`` is exact to ``tol``
        (relative, in the M-norm; about 17 shifted solves for a condition
        number of 1e6 at 1e-8), ``"spectral"`` the paper's truncation to
        ``eigenpairs`` non-zero modes (the paper uses 300), ``"dense"`` the
        exact reference (at most :data:`DENSE_MAX_VERTICES` vertices).
        The other settings are not used here.
    backend : str, optional
        Sparse solver of :mod:`hht3d.linalg`.
    **overrides
        Settings that replace those of ``options``.

    Returns
    -------
    ndarray, shape of ``f``
        ``L^{power} f̃``, M-orthogonal to the kernel: the per-component
        constants are removed from ``f`` first (see :func:`fluctuation`).

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
    options = RieszOptions.of(options, **overrides)
    surface = check_surface(surface)
    a, single = as_signals(surface, f)
    if not np.isfinite(power) or power == 0:
        raise InputError(f"power must be a finite non-zero number, got {power!r}")
    g = fluctuation(surface, a)
    if len(g) == 0:  # no signals (e.g. an EMD that found no IMF)
        return g
    if options.potential == "quadrature":
        if power != -0.5:
            raise InputError(
                f"potential='quadrature' computes power=-0.5 only, got power={power}; "
                "use potential='spectral' or 'dense' for other powers"
            )
        out = quadrature_sum(surface, g, options.tol, backend)
    else:
        values, vectors = (
            dense_eigenpairs(surface)
            if options.potential == "dense"
            else smallest_eigenpairs(surface, options.eigenpairs, backend=backend)
        )
        out = apply_eigenpairs(surface, g, values, vectors, power)
    return out[0] if single else out


def riesz(
    surface: Surface,
    f: np.ndarray,
    options: RieszOptions | dict | None = None,
    *,
    backend: str | None = None,
    **overrides: Any,
) -> np.ndarray:
    """Riesz transform ``R f = ∇ L^{-1/2} f`` (Eqs. 14, 16; Eq. 18 with ``potential="spectral"``).

    Parameters
    ----------
    surface : Surface
    f : (n,) or (k, n) array_like
    options : RieszOptions or dict, optional
        ``gradient`` (tangent-plane least squares of Eq. 17, meshes and point
        clouds, or area-averaged per-face FEM gradients, meshes) and
        ``potential``, ``tol``, ``eigenpairs`` as in :func:`fractional_laplacian`;
        default :data:`~hht3d.spectral.options.RIESZ_DEFAULTS`.
    backend : str, optional
        Sparse solver of :mod:`hht3d.linalg`.
    **overrides
        Settings that replace those of ``options``.

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
    >>> from hht3d.geometry.signals import fluctuation
    >>> sphere = load(data_path("sphere_oct4098.ply"))
    >>> f = sphere.vertices[:, 0] * sphere.vertices[:, 1] + sphere.vertices[:, 2]
    >>> rf = riesz(sphere, f, gradient="fem")
    >>> area, f_tilde = sphere.mass_diagonal, fluctuation(sphere, f)
    >>> round(float(area @ (rf ** 2).sum(axis=1) / (area @ f_tilde ** 2)), 2)
    1.0
    """
    options = RieszOptions.of(options, **overrides)
    u = fractional_laplacian(surface, f, -0.5, options, backend=backend)
    return vertex_gradient(surface, u, options.gradient)


def vertex_gradient(
    surface: Surface, u: np.ndarray, kind: str = RIESZ_DEFAULTS.gradient, operator: sp.spmatrix | None = None
) -> np.ndarray:
    """Tangent gradients of (n,) or (k, n) per-vertex fields: (n, 3) or (k, n, 3).

    Parameters
    ----------
    surface : Surface
        The surface.
    u : ndarray
        One field ``(n,)`` or a stack ``(k, n)``.
    kind : str, optional
        The gradient operator, as in :class:`~hht3d.spectral.options.RieszOptions` (default ``"lsq"``).
    operator : sparse (3n, n), optional
        A gradient operator to apply instead of ``surface.gradient(kind)`` (a coarse level's,
        :meth:`hht3d.geometry.hierarchy.Level.gradient`).

    Returns
    -------
    ndarray
        ``(n, 3)`` for one field, ``(k, n, 3)`` for a stack.

    Examples
    --------
    >>> from hht3d import data_path, load
    >>> spot = load(data_path("spot.ply"))
    >>> import numpy as np
    >>> from hht3d.spectral import vertex_gradient
    >>> vertex_gradient(spot, spot.vertices[:, 0]).shape, vertex_gradient(spot, spot.vertices.T).shape
    ((2930, 3), (3, 2930, 3))
    """
    grad = surface.gradient(kind) if operator is None else operator
    n = surface.n_vertices
    u2 = np.atleast_2d(u)
    out = np.asarray(grad @ u2.T).reshape(n, 3, len(u2)).transpose(2, 0, 1)
    return out[0] if np.ndim(u) == 1 else out
