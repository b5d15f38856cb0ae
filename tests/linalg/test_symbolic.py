"""Symbolic analyses (hht3d.linalg.symbolic): refactorization on one pattern, a replaced factor, bad input."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from helpers.systems import BACKENDS, SINGLE_FACTOR, relative_error, singular, systems
from hht3d import linalg
from hht3d.decomposition import envelope_operator
from hht3d.errors import InputError, NumericalError


@pytest.mark.parametrize("backend", BACKENDS)
def test_refactorization_gives_the_new_answer(spot, backend):
    (_, first), (_, second), *_ = systems(spot)
    rhs = np.random.default_rng(2).standard_normal(spot.n_vertices)
    symbolic = linalg.SymbolicFactorization(envelope_operator(spot, envelope="biharmonic"), backend)
    x1 = symbolic.factorize(first).solve(rhs)
    x2 = symbolic.factorize(second).solve(rhs)
    exact1, exact2 = spla.spsolve(first.tocsc(), rhs), spla.spsolve(second.tocsc(), rhs)
    assert relative_error(exact1, exact2) > 0.1  # the two systems really differ
    assert relative_error(x1, exact1) < 1e-9
    assert relative_error(x2, exact2) < 1e-9
    assert symbolic.n_factorizations == 2 and symbolic.backend == backend


@pytest.mark.parametrize("backend", SINGLE_FACTOR)
def test_replaced_factor_refuses_to_solve(spot, backend):
    (_, first), (_, second), *_ = systems(spot)
    symbolic = linalg.SymbolicFactorization(first, backend)
    old = symbolic.factorize(first)
    symbolic.factorize(second)
    with pytest.raises(NumericalError, match="replaced"):
        old.solve(np.ones(spot.n_vertices))


@pytest.mark.parametrize("backend", BACKENDS)
def test_input_errors(backend):
    a = singular() + sp.eye(6)
    symbolic = linalg.SymbolicFactorization(a, backend)
    with pytest.raises(InputError, match="pattern differs"):
        symbolic.factorize(sp.eye(6))
    with pytest.raises(InputError, match="rows"):
        symbolic.factorize(a).solve(np.ones(5))
    with pytest.raises(InputError, match="square"):
        linalg.factorize(sp.eye(6, 5), backend)
