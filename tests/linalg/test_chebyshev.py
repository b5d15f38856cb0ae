"""Chebyshev series of a Laplacian (hht3d.linalg.chebyshev) against a dense eigendecomposition.

Oracles: the dense generalized eigendecomposition of ``(L, M)`` on a small icosphere (``φ(A) v =
Σ φ(λ_j) ⟨φ_j, v⟩_M φ_j``, ``λ_max``), and the function itself on a fine grid for the series' bound.
"""

import numpy as np
import pytest
import scipy.linalg as sl
import scipy.sparse as sp

from helpers.meshes import icosphere
from hht3d import Surface
from hht3d.decomposition.filtering import passband
from hht3d.errors import NumericalError
from hht3d.linalg.chebyshev import (
    MAX_DEGREE,
    apply_series,
    chebyshev_series,
    recurrence_matrix,
    spectral_radius_bound,
)


@pytest.fixture(scope="module")
def pencil():
    surface = Surface(*icosphere(3))
    lap, mass = surface.stiffness, surface.mass_diagonal
    values, vectors = sl.eigh(lap.toarray(), np.diag(mass))
    return lap, mass, np.maximum(values, 0.0), vectors


def test_the_bound_is_above_the_top_eigenvalue_and_close_to_it(pencil):
    """Collatz–Wielandt: an upper bound by construction, 1.23× ``λ_max`` on this regular icosphere (``ρ(|L|)``
    exceeds ``λ_max(L)`` most where no vertex stands out), below Gershgorin's 1.36×."""
    lap, mass, values, _ = pencil
    bound = spectral_radius_bound(lap, mass)
    assert values[-1] <= bound <= 1.25 * values[-1], (bound, values[-1])
    assert bound <= spectral_radius_bound(lap, mass, iterations=1)  # the first is Gershgorin's


@pytest.mark.parametrize("cut", [3.0, 30.0, 300.0])
def test_the_series_error_is_within_its_tolerance(cut):
    """The bilaplacian pass band of iterative filtering at cut ``λ_c`` on ``[0, 1000]``: the uniform error on
    10⁵ points stays below the tolerance asked for, and the degree grows like ``√(λ̄/λ_c)``."""
    top = 1000.0

    def band(lam):
        return passband(1 / (1 + (lam / cut) ** 2), 16)

    series = chebyshev_series(band, top, 1e-8, scale=cut)
    grid = np.linspace(0, top, 100_001)
    error = np.abs(np.polynomial.chebyshev.chebval(2 * grid / top - 1, series) - band(grid))
    assert error.max() <= 1e-8
    degree = len(series) - 1
    assert 10 * np.sqrt(top / cut) < degree < 60 * np.sqrt(top / cut), degree


def test_without_its_scale_a_narrow_change_is_missed_and_with_it_found():
    """A pass band cut at 1e-6 of the interval is 1 at all of the first 64 points (the lowest is at 1.5e-4):
    without ``scale`` the series is the constant 1 (wrong by 1 at 0); with it, it is resolved."""

    def band(lam):
        return passband(1 / (1 + (lam / 1e-6) ** 2), 16)

    assert len(chebyshev_series(band, 1.0, 1e-6)) == 1
    series = chebyshev_series(band, 1.0, 1e-6, scale=1e-6)
    assert abs(np.polynomial.chebyshev.chebval(-1.0, series) - band(0.0)) < 1e-6


def test_too_sharp_a_function_is_refused():
    with pytest.raises(NumericalError, match="more than"):
        chebyshev_series(lambda lam: np.tanh(lam / 1e-12), 1.0, 1e-8, scale=1e-12 / MAX_DEGREE)


def test_applied_series_equal_the_eigenbasis(pencil):
    """``p(A) v`` from the recurrence equals ``Σ φ(λ_j) ⟨φ_j, v⟩_M φ_j`` within the series' tolerance (in the
    M-norm, relative to ``v``), for one series on two columns and for two series on them at once."""
    lap, mass, values, vectors = pencil
    top = spectral_radius_bound(lap, mass)
    y2 = recurrence_matrix(lap, mass, top)
    v = np.random.default_rng(0).standard_normal((len(mass), 2))
    functions = [lambda lam: np.exp(-lam / 20), lambda lam: passband(1 / (1 + (lam / 50) ** 2), 16)]
    series = [chebyshev_series(f, top, 1e-10, scale=20) for f in functions]
    coefficients = np.zeros((2, max(map(len, series))))
    for row, found in zip(coefficients, series):
        row[: len(found)] = found
    both = apply_series(coefficients, y2, v)
    assert both.shape == (2, *v.shape)
    for f, got in zip(functions, both):
        exact = vectors @ (f(values)[:, None] * (vectors.T @ (mass[:, None] * v)))
        error = np.sqrt((mass[:, None] * (got - exact) ** 2).sum(0) / (mass[:, None] * v**2).sum(0))
        assert np.all(error < 1e-9), error
    np.testing.assert_allclose(apply_series(series[0], y2, v), both[0], atol=1e-12)
    np.testing.assert_allclose(apply_series(series[0], y2, v[:, 1]), both[0][:, 1], atol=1e-12)


@pytest.mark.parametrize("threads", [2, 3])
def test_threads_share_the_rows_and_change_nothing(pencil, monkeypatch, threads):
    """Rows cut over threads (blocks of 200 rows here) give the one-thread result to the bit: each row's
    arithmetic is the same whichever thread does it; and still the eigenbasis's."""
    lap, mass, values, vectors = pencil
    top = spectral_radius_bound(lap, mass)
    y2 = recurrence_matrix(lap, mass, top)
    v = np.random.default_rng(1).standard_normal(len(mass))
    series = chebyshev_series(lambda lam: np.exp(-lam / 20), top, 1e-10, scale=20)
    one = apply_series(series, y2, v, threads=1)
    monkeypatch.setattr("hht3d.linalg.chebyshev.THREAD_ROWS", 200)
    shared = apply_series(series, y2, v, threads=threads)
    np.testing.assert_array_equal(shared, one)
    exact = vectors @ (np.exp(-values / 20) * (vectors.T @ (mass * v)))
    assert np.sqrt(mass @ (shared - exact) ** 2 / (mass @ v**2)) < 1e-9


def test_the_rows_are_renumbered_into_a_narrow_band_and_the_result_back():
    """A 40×60 grid numbered at random: its bandwidth is 40 at best (the grid's, min(m, n)), about 2,400 as
    numbered; the recurrence's rows have at most twice the best, and ``exp(−A/20) v`` comes back in the
    vertices' order (the dense ``expm``)."""
    side, other = 40, 60
    grid = sp.kronsum(_path(other), _path(side)).tocsr()  # vertex (a, b) is row a * side + b
    shuffle = np.random.default_rng(2).permutation(side * other)
    lap = grid[shuffle][:, shuffle].tocsr()
    mass = np.random.default_rng(3).uniform(0.5, 2.0, side * other)
    top = spectral_radius_bound(lap, mass)
    y2 = recurrence_matrix(lap, mass, top)
    rows, cols = y2.matrix.nonzero()
    assert np.abs(rows - cols).max() <= 2 * side
    assert np.abs(np.subtract(*lap.nonzero())).max() > 20 * side  # the numbering it started from
    v = np.random.default_rng(4).standard_normal(side * other)
    series = chebyshev_series(lambda lam: np.exp(-lam / 20), top, 1e-12)
    exact = sl.expm(-(lap.toarray() / mass[:, None]) / 20) @ v
    np.testing.assert_allclose(apply_series(series, y2, v), exact, atol=1e-10 * np.abs(v).max())


def _path(n: int) -> sp.csr_matrix:
    """The Laplacian of a path of ``n`` vertices."""
    main = np.full(n, 2.0)
    main[[0, -1]] = 1.0
    return sp.diags([-np.ones(n - 1), main, -np.ones(n - 1)], [-1, 0, 1]).tocsr()
