"""Jacobi-preconditioned CG on many right-hand sides (hht3d.linalg.pcg) against a direct solve."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from hht3d.linalg.pcg import jacobi_cg
from hht3d.spectral.shifts import shifted_matrix


def test_each_column_reaches_its_residual(spot):
    # spot's L + σM at a shift near the top of its spectrum: CG's residual per column is within
    # rtol, and so its error against SuperLU's solve is within the condition number times it.
    a = shifted_matrix(spot, 1e3).tocsr()
    b = np.random.default_rng(1).standard_normal((a.shape[0], 3)) * [1.0, 1e-6, 1e6]
    x = jacobi_cg(a, b, 1e-10, 500)
    assert x is not None and x.shape == b.shape
    residual = np.linalg.norm(a @ x - b, axis=0) / np.linalg.norm(b, axis=0)
    assert np.all(residual <= 1e-10)
    exact = sla.spsolve(a.tocsc(), b)
    eigenvalues = np.linalg.eigvalsh(a.toarray())
    condition = eigenvalues[-1] / eigenvalues[0]
    assert np.all(np.linalg.norm(x - exact, axis=0) <= condition * 1e-10 * np.linalg.norm(exact, axis=0))


def test_a_vector_and_a_zero_column():
    a = sp.diags([-1.0, 4.0, -1.0], [-1, 0, 1], shape=(50, 50)).tocsr()
    b = np.arange(50.0)
    x = jacobi_cg(a, b, 1e-12, 100)
    assert x.shape == (50,) and np.allclose(a @ x, b, rtol=0, atol=1e-10)
    both = jacobi_cg(a, np.column_stack([b, np.zeros(50)]), 1e-12, 100)
    assert np.array_equal(both[:, 1], np.zeros(50)) and np.allclose(both[:, 0], x, atol=1e-12)


def test_too_few_iterations_give_none(spot):
    # At a small shift (condition ~1e4 after Jacobi) 5 iterations cannot reach 1e-10.
    a = shifted_matrix(spot, 1e-3).tocsr()
    b = np.ones((a.shape[0], 2))
    assert jacobi_cg(a, b, 1e-10, 5) is None


def test_tiny_and_huge_columns():
    # Squared norms of 1e-200 vanish and of 1e200 overflow in float64: each column is solved
    # as if scaled to 1, so both come out as 1e∓200 times the unit column's solution.
    a = sp.diags([-1.0, 4.0, -1.0], [-1, 0, 1], shape=(50, 50)).tocsr()
    b = np.linspace(1.0, 2.0, 50)
    unit = jacobi_cg(a, b, 1e-12, 100)
    both = jacobi_cg(a, np.column_stack([1e-200 * b, 1e200 * b]), 1e-12, 100)
    assert np.allclose(both[:, 0] / 1e-200, unit, rtol=1e-12) and np.allclose(both[:, 1] / 1e200, unit, rtol=1e-12)
