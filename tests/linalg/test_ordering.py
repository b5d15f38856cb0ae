"""The nested-dissection ordering (hht3d.linalg.ordering) against the fill that theory gives a grid, and the
SuperLU backend ordered by it against a direct solve."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from hht3d.errors import InputError
from hht3d.linalg import SymbolicFactorization
from hht3d.linalg.ordering import nested_dissection
from hht3d.linalg.superlu import SUPERLU_OPTIONS


def grid_laplacian(k: int) -> tuple[sp.csr_matrix, np.ndarray]:
    """The 5-point Laplacian of a k × k grid plus the identity, and its points."""
    path = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(k, k))
    eye = sp.eye(k)
    a = (sp.kron(path, eye) + sp.kron(eye, path) + sp.eye(k * k)).tocsr()
    x, y = np.meshgrid(np.arange(k), np.arange(k), indexing="ij")
    return a, np.column_stack([x.ravel(), y.ravel(), np.zeros(k * k)])


def factor_entries(a: sp.csr_matrix, order: np.ndarray) -> int:
    """Entries of the Cholesky factor of ``a`` in ``order`` (SuperLU's L, no pivoting)."""
    return sla.splu(sp.csc_matrix(a[order][:, order]), permc_spec="NATURAL", **SUPERLU_OPTIONS).L.nnz


def test_a_grid_fills_as_nested_dissection_does():
    # George (1973): nested dissection of a k × k grid (n = k²) gives a Cholesky factor of
    # O(n log n) entries, (31/4) n log₂ n with optimal separators, against n·k for the natural
    # (banded) order.  At k = 128 that is 1.78M against 2.10M; this ordering gives 0.51M.  Separators
    # ordered before their halves give 2.1M+, parts left whole below 4,000 rows more than 0.75 of
    # the banded factor: both fail.
    k = 128
    a, points = grid_laplacian(k)
    n = k * k
    order = nested_dissection(a, points)
    assert np.array_equal(np.sort(order), np.arange(n))
    entries = factor_entries(a, order)
    assert entries <= 31 / 4 * n * np.log2(n)
    assert entries < 0.75 * factor_entries(a, np.arange(n))


def test_separators_come_after_their_halves():
    # The first cut of a 64 × 64 grid is one of its middle lines: the last 64 rows of the order
    # are that line, and no entry joins the two halves ordered before it.
    k = 64
    a, points = grid_laplacian(k)
    order = nested_dissection(a, points)
    line = order[-k:]
    assert len(np.unique(points[line, 0])) == 1 or len(np.unique(points[line, 1])) == 1
    rest = np.setdiff1d(np.arange(k * k), line)
    graph = a[rest][:, rest]
    count, _ = sp.csgraph.connected_components(graph, directed=False)
    assert count == 2


def test_superlu_by_points_solves_as_by_minimum_degree():
    # The ordering changes the factor, not the solution: both solve to round-off (relative 1e-12
    # against the minimum-degree factor; the matrix's condition number is ~1e4).
    a, points = grid_laplacian(40)
    b = np.random.default_rng(0).standard_normal((len(points), 3))
    by_points = SymbolicFactorization(a, "superlu", points=points).factorize(a).solve(b)
    by_degree = SymbolicFactorization(a, "superlu").factorize(a).solve(b)
    assert np.linalg.norm(by_points - by_degree) <= 1e-12 * np.linalg.norm(by_degree)
    assert np.linalg.norm(a @ by_points - b) <= 1e-12 * np.linalg.norm(b)


def test_points_must_match_the_rows():
    a, points = grid_laplacian(8)
    with pytest.raises(InputError, match="one point per row"):
        nested_dissection(a, points[:-1])
