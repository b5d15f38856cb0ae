"""References of the spectral tests (tests/spectral/): the M-norm error, test signals, the generalized
eigendecomposition written with SciPy, and the cylinder of the monogenic-signal tests."""

from __future__ import annotations

import numpy as np
import scipy.linalg

RADIUS = 1.5
LENGTH = 6.0
WAVENUMBERS = (4, 8)


def m_error(surface, approx, exact):
    """Relative M-norm error, per row."""
    mass = surface.mass_diagonal
    return np.sqrt(((approx - exact) ** 2 * mass).sum(-1) / (exact**2 * mass).sum(-1))


def mixed_signals(surface, count=3, seed=0):
    """A smooth, a rough (white noise) and an off-centre distance signal."""
    v = surface.vertices
    rng = np.random.default_rng(seed)
    rows = [
        np.sin(3 * v[:, 0]) + v[:, 1] * v[:, 2],
        rng.standard_normal(len(v)),
        np.linalg.norm(v - v.mean(axis=0) - 0.1 * np.ptp(v, axis=0), axis=1),
    ]
    return np.stack(rows[:count])


def generalized_eigh(surface):
    """Non-zero eigenpairs of ``L φ = λ M φ`` by ``scipy.linalg.eigh(L, M)``, written here.

    Independent of ``hht3d.spectral.eigenpairs.dense_eigenpairs`` (which symmetrises with
    ``M^{-1/2}`` and calls the standard problem): LAPACK's generalized
    solver returns M-orthonormal eigenvectors directly.
    """
    key = "test:generalized_eigh"
    if key not in surface.cache:
        values, vectors = scipy.linalg.eigh(surface.stiffness.toarray(), np.diag(surface.mass_diagonal))
        k = surface.n_components  # the per-component constants have λ = 0
        surface.cache[key] = values[k:], vectors[:, k:]
    return surface.cache[key]


def eigen_reference(surface, f, count=None, power=-0.5):
    """``Σ_k λ_k^power φ_k φ_kᵀ M f`` over the ``count`` smallest non-zero modes (all by default)."""
    values, vectors = generalized_eigh(surface)
    values, vectors = values[:count], vectors[:, :count]
    return ((f * surface.mass_diagonal) @ vectors * values**power) @ vectors.T
