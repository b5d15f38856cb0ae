"""Sparse symmetric positive definite (SPD) direct solvers with pattern reuse.

EMD (Sec. 4.1) and the quadrature for ``L^{-1/2}`` (Sec. 4.2) factorize many
matrices that share one sparsity pattern.  A :class:`SymbolicFactorization`
analyses that pattern once (fill-reducing ordering, symbolic factorization)
and then only refactorizes numerically.

Backends, in order of preference
--------------------------------
``"pardiso"``
    Intel MKL PARDISO through the ``pypardiso`` package (extra ``fast``,
    x86-64 only): real SPD mode (``mtype=2``) on the upper triangle, METIS
    nested-dissection ordering and symbolic phase 11 once, numeric phase 22
    per matrix, solve phase 33.
``"cholmod"``
    CHOLMOD's supernodal Cholesky ``P A Pᵀ = L Lᵀ`` through ``cvxopt``
    (wheels with their own BLAS for Linux, macOS and Windows; no MKL):
    AMD ordering and supernodal symbolic analysis once
    (``cholmod.symbolic``), numeric factorization per matrix
    (``cholmod.numeric``).
``"superlu"``
    SciPy's SuperLU, always available.  SciPy exposes no symbolic reuse, so
    each factorization orders and factorizes from scratch.

The default is the first installed backend of :data:`SOLVER_BACKENDS`,
unless the environment variable :data:`BACKEND_VARIABLE` names another; a
``backend=`` argument overrides both.  :func:`backend_report` says which one
runs and why.  Every backend gives the same results to solver round-off.

Adding a backend
----------------
One :func:`register_backend` call with a :class:`Backend`: its package, the
modules to import (only when a backend is first needed, so a missing or slow
package costs nothing until then), a line for ``hht3d info --backends``, an
install hint, and a class that analyses a pattern and factorizes matrices on
it (see :class:`Backend`).  Pipelines (``backend:``), EMD, the Riesz
transform and ``hht3d info`` read the registry.
"""
from __future__ import annotations

import functools
import importlib
import importlib.metadata
import os
import threading
import weakref
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from ..errors import InputError, NumericalError

__all__ = [
    "Backend",
    "SOLVER_BACKENDS",
    "register_backend",
    "check_backend",
    "BACKENDS",
    "BACKEND_VARIABLE",
    "available_backends",
    "default_backend",
    "backend_report",
    "BackendStatus",
    "factorize",
    "Factor",
    "SymbolicFactorization",
]

#: Environment variable naming the default backend (e.g. ``HHT3D_BACKEND=superlu``).
BACKEND_VARIABLE = "HHT3D_BACKEND"


@dataclass(frozen=True)
class Backend:
    """A sparse SPD solver backend: where it comes from and how it factorizes.

    Parameters
    ----------
    name : str
        The ``backend=`` value that selects it.
    distribution : str
        The package providing it (its version is reported by :func:`backend_report`).
    modules : tuple of str
        Modules imported, in order, the first time the backend is needed; the
        backend is available when they all import.
    algorithm : str
        One line on what it does, for ``hht3d info --backends``.
    missing : str
        What to do when it is not installed.
    pattern : callable
        ``pattern(csr_matrix)`` analyses a sparsity pattern and returns an
        object whose ``factorize(a)`` gives a :class:`Factor` of any matrix
        with that pattern; it is called as ``pattern(csr, module)`` with
        :meth:`module`.
    """

    name: str
    distribution: str
    modules: tuple[str, ...]
    algorithm: str
    missing: str
    pattern: Callable = field(repr=False)

    def module(self):
        """The first of :attr:`modules`, all imported on first use; ``None`` if one is absent."""
        if self.name not in _MODULES:
            try:
                _MODULES[self.name] = [importlib.import_module(m) for m in self.modules][0]
            except ImportError:  # depends on the environment
                _MODULES[self.name] = None
        return _MODULES[self.name]

    @property
    def available(self) -> bool:
        return self.module() is not None


#: The registered backends by name, fastest first (:func:`register_backend` adds one).
SOLVER_BACKENDS: dict[str, Backend] = {}
#: Imported backend modules by backend name (``None``: not installed); filled on first use.
_MODULES: dict[str, object] = {}


def register_backend(backend: Backend, *, before: str | None = None) -> Backend:
    """Add a solver backend, after the others or ahead of ``before`` in order of preference."""
    entries = [b for b in SOLVER_BACKENDS.values() if b.name != backend.name]
    at = next((i for i, b in enumerate(entries) if b.name == before), len(entries))
    entries.insert(at, backend)
    SOLVER_BACKENDS.clear()
    SOLVER_BACKENDS.update((b.name, b) for b in entries)
    return backend


def available_backends() -> list[str]:
    """Names of the installed backends, fastest first."""
    return [name for name, backend in SOLVER_BACKENDS.items() if backend.available]


def default_backend() -> str:
    """The backend used when none is requested.

    The one named by the environment variable :data:`BACKEND_VARIABLE` if set,
    else the fastest installed one.
    """
    chosen = os.environ.get(BACKEND_VARIABLE, "").strip()
    if chosen:
        return check_backend(chosen, f"{BACKEND_VARIABLE}={chosen!r}")
    return available_backends()[0]


@dataclass(frozen=True)
class BackendStatus:
    """One backend as seen by this process (:func:`backend_report`)."""

    name: str
    available: bool
    default: bool
    detail: str


def backend_report() -> tuple[list[BackendStatus], str]:
    """Every backend's availability and the reason the default was chosen.

    Returns
    -------
    statuses : list of BackendStatus
        In order of preference (:data:`SOLVER_BACKENDS`).
    reason : str
        Why :func:`default_backend` is what it is.
    """
    chosen = os.environ.get(BACKEND_VARIABLE, "").strip()
    default = default_backend()
    installed = available_backends()
    if chosen:
        reason = f"set by the environment variable {BACKEND_VARIABLE}={chosen}"
    else:
        names = list(SOLVER_BACKENDS)
        faster = names[:names.index(default)]
        reason = ("the fastest backend" if not faster else
                  f"the fastest installed backend ({', '.join(faster)} not installed)")
        reason += f"; override with {BACKEND_VARIABLE}=NAME or backend=NAME"
    statuses = []
    for name, backend in SOLVER_BACKENDS.items():
        if name in installed:
            version = importlib.metadata.version(backend.distribution)
            detail = f"{backend.distribution} {version}: {backend.algorithm}"
        else:
            detail = backend.missing
        statuses.append(BackendStatus(name, name in installed, name == default, detail))
    return statuses, reason


def check_backend(backend: str | None, where: str = "backend") -> str:
    """The backend to use: ``backend`` if it is registered and installed, :func:`default_backend` for ``None``."""
    if backend is None:
        return default_backend()
    if backend not in SOLVER_BACKENDS:
        raise InputError(f"unknown sparse solver backend {backend!r} ({where}); "
                         f"choose one of {tuple(SOLVER_BACKENDS)}")
    if not SOLVER_BACKENDS[backend].available:
        raise InputError(f"sparse solver backend {backend!r} ({where}) is not available: "
                         f"{SOLVER_BACKENDS[backend].missing}; installed: {available_backends()}")
    return backend


class Factor:
    """A numeric factorization of one SPD matrix; ``solve`` takes (n,) or (n, k)."""

    def __init__(self, solve, n: int):
        self._solve = solve
        self.n = n

    def solve(self, b: np.ndarray) -> np.ndarray:
        b = np.asarray(b, dtype=np.float64)
        if b.shape[0] != self.n:
            raise InputError(f"right-hand side has {b.shape[0]} rows, the matrix has {self.n}")
        x = self._solve(b)
        if not np.all(np.isfinite(x)):
            raise NumericalError("sparse solve produced non-finite values (singular matrix?)")
        return x


class _Pattern:
    """The analysed sparsity pattern: every matrix factorized must have exactly it."""

    def __init__(self, pattern: sp.csr_matrix):
        self.n = pattern.shape[0]
        self._indptr, self._indices = pattern.indptr.copy(), pattern.indices.copy()

    def check(self, a: sp.csr_matrix) -> sp.csr_matrix:
        if not (np.array_equal(a.indptr, self._indptr) and np.array_equal(a.indices, self._indices)):
            raise InputError("matrix sparsity pattern differs from the analysed one")
        return a


class _UpperTriangle(_Pattern):
    """The upper triangle of matrices on one analysed pattern, by a fixed index map.

    For a symmetric matrix the CSR upper triangle is also the CSC lower
    triangle: the same three arrays.
    """

    def __init__(self, pattern: sp.csr_matrix):
        super().__init__(pattern)
        rows = np.repeat(np.arange(self.n), np.diff(pattern.indptr))
        self._mask = pattern.indices >= rows
        self.rows = rows[self._mask]
        self.indices = pattern.indices[self._mask]
        self.indptr = np.concatenate([[0], np.cumsum(np.bincount(self.rows, minlength=self.n))])

    def data(self, a: sp.csr_matrix) -> np.ndarray:
        """The upper-triangle values of ``a``."""
        return self.check(a).data[self._mask]

    def csr(self, a: sp.csr_matrix) -> sp.csr_matrix:
        return sp.csr_matrix((self.data(a), self.indices, self.indptr), shape=(self.n, self.n))


class _SuperLUPattern:
    """SuperLU: no symbolic reuse, a fresh ``splu`` per matrix."""

    def __init__(self, pattern: sp.csr_matrix, module):
        self._pattern = _Pattern(pattern)
        self._splu = module.splu

    def factorize(self, a: sp.csr_matrix) -> Factor:
        try:
            lu = self._splu(self._pattern.check(a).tocsc(), permc_spec="MMD_AT_PLUS_A",
                           options={"SymmetricMode": True})
        except RuntimeError as exc:  # "Factor is exactly singular"
            raise NumericalError(f"SuperLU factorization failed: {exc}") from exc
        return Factor(lu.solve, self._pattern.n)


class _Latest:
    """Backends that keep one factor per analysis: only the latest may solve."""

    def __init__(self, backend: str):
        self._backend = backend
        self._current = None

    def claim(self):
        self._current = token = object()
        return token

    def check(self, token) -> None:
        if self._current is not token:
            raise NumericalError(f"this {self._backend} factor was replaced by a later factorization")


@functools.lru_cache(maxsize=1)
def _locate_mkl(pypardiso) -> None:
    """Find MKL's runtime once per process and tell pypardiso where it is.

    pypardiso otherwise searches the whole installation tree for ``mkl_rt``
    every time a solver is created (0.3-0.7 s each).
    """
    if "PYPARDISO_MKL_RT" not in os.environ:
        os.environ["PYPARDISO_MKL_RT"] = pypardiso.PyPardisoSolver().libmkl._name


class _PardisoPattern:
    """MKL PARDISO in SPD mode with the symbolic phase run once.

    ``solver`` is the ``pypardiso.PyPardisoSolver`` (its ``iparm`` reports
    memory and fill); every phase goes through :meth:`run`.
    """

    def __init__(self, pattern: sp.csr_matrix, module):
        self.n = pattern.shape[0]
        self._upper = _UpperTriangle(pattern)
        self._error = module.pardiso_wrapper.PyPardisoError
        _locate_mkl(module)
        self.solver = module.PyPardisoSolver(mtype=2)  # MKL's SPD defaults
        weakref.finalize(self, self.solver.free_memory, True)
        self._latest = _Latest("PARDISO")
        self.run(11, self._upper.csr(pattern), np.zeros((self.n, 1)))
        # keep the defaults MKL filled in, minus iterative refinement: SPD
        # solves are accurate to ~1e-13 without it and 5x faster on many columns
        self.solver.iparm[0] = 1
        self.solver.iparm[7] = 0

    def run(self, phase: int, upper: sp.csr_matrix, b: np.ndarray) -> np.ndarray:
        """PARDISO ``phase`` (11 analysis, 22 numeric factorization, 33 solve) on ``upper``."""
        self.solver.set_phase(phase)
        try:
            return self.solver._call_pardiso(upper, b)
        except self._error as exc:
            raise NumericalError(f"PARDISO phase {phase} failed: {exc}") from exc

    def factorize(self, a: sp.csr_matrix) -> Factor:
        upper = self._upper.csr(a)
        self.run(22, upper, np.zeros((self.n, 1)))
        token = self._latest.claim()

        def solve(b: np.ndarray) -> np.ndarray:
            self._latest.check(token)
            return self.run(33, upper, np.asfortranarray(b))

        return Factor(solve, self.n)


#: cvxopt keeps CHOLMOD's workspace in one process-wide ``cholmod_common``.
_CHOLMOD_LOCK = threading.Lock()


class _CholmodPattern:
    """CHOLMOD (cvxopt) supernodal Cholesky with the ordering and symbolic analysis done once.

    One cvxopt sparse matrix holds the lower triangle in CSC order; each
    factorization overwrites its values and refactorizes numerically in
    place, so (as with PARDISO) only the latest factor is valid.
    """

    def __init__(self, pattern: sp.csr_matrix, module):
        self.n = pattern.shape[0]
        self._cvxopt, self._cholmod = module, module.cholmod
        self._lower = _UpperTriangle(pattern)  # CSR upper == CSC lower
        # CSC lower: column = CSR row, row = CSR column; values 1 so that none is dropped
        self._matrix = module.spmatrix(1.0, self._lower.indices.astype(np.int64),
                                        self._lower.rows.astype(np.int64), (self.n, self.n))
        if len(self._matrix.V) != len(self._lower.rows):  # pragma: no cover - cvxopt invariant
            raise NumericalError("cvxopt changed the sparsity pattern of the matrix")
        with _CHOLMOD_LOCK:
            try:
                self._factor = self._cholmod.symbolic(self._matrix, uplo="L")
            except (ValueError, MemoryError) as exc:
                raise NumericalError(f"CHOLMOD symbolic analysis failed: {exc}") from exc
        self._latest = _Latest("CHOLMOD")

    def factorize(self, a: sp.csr_matrix) -> Factor:
        values = self._cvxopt.matrix(self._lower.data(a))
        with _CHOLMOD_LOCK:
            self._matrix.V = values
            try:
                self._cholmod.numeric(self._matrix, self._factor)
            except ArithmeticError as exc:
                raise NumericalError(f"CHOLMOD: the matrix is not positive definite (pivot {exc.args[0]} "
                                     "of the permuted matrix)") from exc
            except (ValueError, MemoryError) as exc:
                raise NumericalError(f"CHOLMOD factorization failed: {exc}") from exc
        token = self._latest.claim()

        def solve(b: np.ndarray) -> np.ndarray:
            self._latest.check(token)
            x = self._cvxopt.matrix(b)
            with _CHOLMOD_LOCK:
                self._cholmod.solve(self._factor, x)
            return np.array(x).reshape(b.shape)

        return Factor(solve, self.n)


register_backend(Backend(
    "pardiso", "pypardiso", ("pypardiso",),
    "MKL PARDISO, supernodal, METIS ordering, symbolic analysis reused",
    "pypardiso is not installed (MKL, x86-64 only): pip install 'hht3d[fast]'", _PardisoPattern))
register_backend(Backend(
    "cholmod", "cvxopt", ("cvxopt", "cvxopt.cholmod"),
    "CHOLMOD supernodal Cholesky, AMD ordering, symbolic analysis reused",
    "cvxopt is not installed (no wheel for this platform?): pip install cvxopt", _CholmodPattern))
register_backend(Backend(
    "superlu", "scipy", ("scipy.sparse.linalg",),
    "SciPy SuperLU, ordered and factorized from scratch per matrix",
    "scipy is always installed", _SuperLUPattern))

#: Every backend's name, fastest first (the registry's order when this module was imported).
BACKENDS = tuple(SOLVER_BACKENDS)


class SymbolicFactorization:
    """Analyse a sparsity pattern once, then factorize matrices sharing it.

    Parameters
    ----------
    pattern : sparse matrix
        Symmetric matrix whose stored entries (explicit zeros included)
        define the pattern.
    backend : {"pardiso", "cholmod", "superlu"}, optional
        Defaults to :func:`default_backend`.

    Notes
    -----
    With the ``pardiso`` and ``cholmod`` backends only the most recent
    :class:`Factor` of one ``SymbolicFactorization`` is valid (both keep one
    factor per analysis); create one ``SymbolicFactorization`` per factor
    that must stay alive.
    """

    def __init__(self, pattern, backend: str | None = None):
        pattern = _as_square_csr(pattern)
        self.backend = check_backend(backend)
        entry = SOLVER_BACKENDS[self.backend]
        self._impl = entry.pattern(pattern, entry.module())
        self.n_factorizations = 0

    def factorize(self, a) -> Factor:
        """Numerically factorize ``a`` (same pattern as analysed)."""
        factor = self._impl.factorize(_as_square_csr(a))
        self.n_factorizations += 1
        return factor


def factorize(a, backend: str | None = None) -> Factor:
    """Factorize one SPD sparse matrix (analysis and numeric phase)."""
    return SymbolicFactorization(a, backend).factorize(a)


def _as_square_csr(a) -> sp.csr_matrix:
    a = sp.csr_matrix(a, dtype=np.float64)
    if a.shape[0] != a.shape[1]:
        raise InputError(f"matrix must be square, got shape {a.shape}")
    a.sort_indices()
    return a
