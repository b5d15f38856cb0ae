"""Sparse SPD solver backends (hht3d.linalg) against SciPy's dense and sparse solvers.

The systems are the two kinds hht3d factorizes, built on the shipped model
spot (2,930 vertices): the constrained biharmonic envelope system of EMD and
the shifted systems ``L + σM`` of the ``L^{-1/2}`` quadrature at its smallest
and largest shift.

Tolerance: Cholesky is backward stable without pivoting growth, so each
solver's relative forward error is at most about ``κ₂(A)·ε`` (Higham,
*Accuracy and Stability of Numerical Algorithms*, Thm. 10.4 with Sec. 7.1);
two solvers then differ by at most the sum of their errors.  ``κ₂`` is
computed from the extreme eigenvalues (ARPACK), and the bound used is
``20·κ₂·ε`` (a factor 10 per solver for the dimension-dependent constant,
which is small in practice for sparse factors).
"""

from __future__ import annotations

import threading
import time
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from helpers.systems import BACKENDS, SINGLE_FACTOR, relative_error, singular, systems
from hht3d import linalg
from hht3d.errors import InputError, NumericalError
from hht3d.linalg import backends
from hht3d.spectral import spectral_bounds
from hht3d.spectral.shifts import shifted_matrix


@pytest.fixture(scope="module")
def references(spot):
    """Per system: name, matrix, right-hand sides, LAPACK and SuperLU solutions, error bound."""
    rhs = np.random.default_rng(1).standard_normal((spot.n_vertices, 3))
    out = []
    for name, a in systems(spot):
        largest = spla.eigsh(a, 1, which="LA", return_eigenvectors=False, tol=1e-6)[0]
        smallest = spla.eigsh(a.tocsc(), 1, sigma=0, which="LM", return_eigenvectors=False, tol=1e-6)[0]
        assert smallest > 0, name
        bound = 20 * largest / smallest * np.finfo(float).eps
        out.append((name, a, rhs, np.linalg.solve(a.toarray(), rhs), spla.spsolve(a.tocsc(), rhs), bound))
    return out


@pytest.mark.parametrize("backend", BACKENDS)
def test_agrees_with_dense_and_spsolve(references, backend):
    for name, a, rhs, dense, sparse, bound in references:
        x = linalg.factorize(a, backend).solve(rhs)
        assert relative_error(x, dense) <= bound, name
        assert relative_error(x, sparse) <= bound, name
        single = linalg.factorize(a, backend).solve(rhs[:, 0])
        assert single.shape == (a.shape[0],)
        assert relative_error(single, x[:, 0]) <= bound, name


@pytest.mark.parametrize("backend", BACKENDS)
def test_singular_matrix_raises_numerical_error(backend):
    a = singular()
    assert a.nnz == 16  # the zeros stay in the pattern
    with pytest.raises(NumericalError):
        linalg.factorize(a, backend).solve(np.ones(6))


@pytest.mark.parametrize("backend", SINGLE_FACTOR)
def test_indefinite_matrix_raises_numerical_error(spot, backend):
    # L - σM with σ above the smallest non-zero eigenvalue is indefinite: no Cholesky factor
    m, _ = spectral_bounds(spot, backend="superlu")
    a = shifted_matrix(spot, -10 * m)
    with pytest.raises(NumericalError):
        linalg.factorize(a, backend).solve(np.ones(spot.n_vertices))


def test_default_backend_and_override(monkeypatch):
    monkeypatch.delenv(linalg.BACKEND_VARIABLE, raising=False)
    assert linalg.default_backend() == BACKENDS[0]
    assert BACKENDS[-1] == "superlu" and set(BACKENDS) <= set(linalg.SOLVER_BACKENDS)
    statuses, reason = linalg.backend_report()
    assert [s.name for s in statuses] == list(linalg.SOLVER_BACKENDS)
    assert [s.name for s in statuses if s.default] == [BACKENDS[0]]
    assert linalg.BACKEND_VARIABLE in reason

    monkeypatch.setenv(linalg.BACKEND_VARIABLE, "superlu")
    assert linalg.default_backend() == "superlu"
    assert linalg.SymbolicFactorization(sp.eye(3)).backend == "superlu"
    statuses, reason = linalg.backend_report()
    assert [s.name for s in statuses if s.default] == ["superlu"] and "environment" in reason

    monkeypatch.setenv(linalg.BACKEND_VARIABLE, "mumps")
    with pytest.raises(InputError, match="HHT3D_BACKEND='mumps'"):
        linalg.default_backend()
    with pytest.raises(InputError, match="unknown sparse solver backend"):
        linalg.factorize(sp.eye(3), "mumps")


def test_missing_backend_is_explained(monkeypatch):
    monkeypatch.setitem(backends._MODULES, "cholmod", None)
    monkeypatch.delenv(linalg.BACKEND_VARIABLE, raising=False)
    assert "cholmod" not in linalg.available_backends()
    with pytest.raises(InputError, match="cvxopt is not installed"):
        linalg.factorize(sp.eye(3), "cholmod")
    statuses, _ = linalg.backend_report()
    assert not next(s for s in statuses if s.name == "cholmod").available


def test_info_backends_names_the_solver_and_why(capsys, monkeypatch):
    from hht3d.cli import main

    monkeypatch.setenv(linalg.BACKEND_VARIABLE, "superlu")
    assert main(["info", "--backends"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("sparse solver: superlu (set by the environment variable HHT3D_BACKEND=superlu)")
    assert all(name in out for name in linalg.SOLVER_BACKENDS)


class _DenseCholesky:
    """A test backend: dense Cholesky of scipy.linalg on any pattern."""

    def __init__(self, pattern, module):
        self.n, self.module = pattern.shape[0], module

    def factorize(self, a):
        factor = self.module.cho_factor(a.toarray())
        return linalg.Factor(lambda b: self.module.cho_solve(factor, b), self.n)


def test_a_new_backend_is_one_registry_entry(monkeypatch):
    monkeypatch.setattr(backends, "SOLVER_BACKENDS", dict(backends.SOLVER_BACKENDS))
    monkeypatch.delenv(linalg.BACKEND_VARIABLE, raising=False)
    linalg.register_backend(
        linalg.Backend("dense", "scipy", ("scipy.linalg",), "dense Cholesky", "never missing", _DenseCholesky),
        before="superlu",
    )
    linalg.register_backend(
        linalg.Backend("absent", "absent", ("hht3d_no_such_module",), "nothing", "pip install absent", _DenseCholesky)
    )
    assert list(backends.SOLVER_BACKENDS)[-3:] == ["superlu", "cg", "absent"]
    assert "dense" in linalg.available_backends() and "absent" not in linalg.available_backends()
    a = sp.csr_matrix(np.array([[4.0, 1.0], [1.0, 3.0]]))
    np.testing.assert_allclose(a @ linalg.factorize(a, "dense").solve(np.ones(2)), np.ones(2))
    assert linalg.SymbolicFactorization(a, "dense").factorize(a).solve(np.ones(2)).shape == (2,)
    with pytest.raises(InputError, match="pip install absent"):
        linalg.factorize(a, "absent")
    statuses = {s.name: s for s in linalg.backend_report()[0]}
    assert statuses["dense"].available and "dense Cholesky" in statuses["dense"].detail
    assert statuses["absent"].detail == "pip install absent"
    # the pipeline's backend: choices and the JSON Schema read the registry
    from hht3d.pipeline import OPERATIONS
    from hht3d.pipeline.json_schema import pipeline_schema

    param = OPERATIONS["emd"].param("backend")
    assert param.check("dense", "steps.emd") == "dense" and "dense" in param.describe()
    emd = next(
        rule["then"]
        for rule in pipeline_schema()["$defs"]["step"]["allOf"]
        if rule["if"]["properties"]["op"]["const"] == "emd"
    )
    choices = emd["properties"]["params"]["properties"]["backend"]["enum"]
    assert choices[-5:] == ["dense", "superlu", "cg", "absent", None]


def test_the_backends_tuple_is_deprecated_for_the_registry():
    for module in (linalg, backends):
        with pytest.warns(DeprecationWarning, match="SOLVER_BACKENDS"):
            assert module.BACKENDS == tuple(backends.SOLVER_BACKENDS)


class _Occupancy:
    """A backend library that records how many threads are inside it at once."""

    def __init__(self):
        self.inside = self.most = 0
        self._count = threading.Lock()

    def enter(self):
        with self._count:
            self.inside += 1
            self.most = max(self.most, self.inside)
        time.sleep(0.005)  # long enough for the other thread to arrive if nothing stops it
        with self._count:
            self.inside -= 1


class _Watched(_DenseCholesky):
    library = _Occupancy()

    def __init__(self, pattern, module):
        super().__init__(pattern, module)
        self.library.enter()

    def factorize(self, a):
        self.library.enter()
        factor = super().factorize(a)
        return linalg.Factor(lambda b: (self.library.enter(), factor.solve(b))[1], self.n)


@pytest.mark.parametrize("lock", [None, threading.RLock()], ids=["thread-safe", "locked"])
def test_a_locked_backend_is_entered_by_one_thread_at_a_time(monkeypatch, lock):
    """Two threads, each with its own analysis (separate handles), factorize and solve
    30 times: a backend registered with a lock never has both inside it; one registered
    without may (the first case shows the check sees overlap when nothing prevents it)."""
    monkeypatch.setattr(backends, "SOLVER_BACKENDS", dict(backends.SOLVER_BACKENDS))
    monkeypatch.setattr(_Watched, "library", _Occupancy())
    linalg.register_backend(
        linalg.Backend("watched", "scipy", ("scipy.linalg",), "dense Cholesky", "never missing", _Watched, lock)
    )
    a = sp.csr_matrix(np.array([[4.0, 1.0], [1.0, 3.0]]))

    def work():
        symbolic = linalg.SymbolicFactorization(a, "watched")
        for _ in range(30):
            symbolic.factorize(a).solve(np.ones(2))

    threads = [threading.Thread(target=work) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert _Watched.library.most == (1 if lock else 2)


def test_backends_not_declared_thread_safe_have_a_lock():
    """PARDISO (two threads in MKL at once crashed a threads-scheduler run) and CHOLMOD
    (cvxopt's one process-wide workspace) are locked; SciPy's SuperLU keeps no global state."""
    locked = {name for name, b in backends.SOLVER_BACKENDS.items() if b.lock is not None}
    assert locked == {"pardiso", "cholmod"}


def test_mkl_runtime_comes_from_the_wheel_file_list_without_a_tree_search(monkeypatch):
    """The mkl wheel's file list names a loadable mkl_rt; pypardiso's search globs the whole tree (1.6 s)."""
    pytest.importorskip("pypardiso")
    import ctypes
    import glob

    from hht3d.linalg import pardiso

    def no_search(*args, **kwargs):
        raise AssertionError("searched the installation tree")

    monkeypatch.setattr(glob, "glob", no_search)
    path = pardiso.listed_mkl_runtime()
    assert path is not None and "mkl_rt" in Path(path).name and Path(path).is_file()
    assert ctypes.CDLL(path).pardiso  # the library pypardiso calls
