"""The registry of sparse symmetric positive definite (SPD) direct solvers.

EMD (Sec. 4.1) and the quadrature for ``L^{-1/2}`` (Sec. 4.2) factorize many
matrices that share one sparsity pattern.  A
:class:`~hht3d.linalg.symbolic.SymbolicFactorization` analyses that pattern once
(fill-reducing ordering, symbolic factorization)
and then only refactorizes numerically.

Backends, in order of preference
--------------------------------
``"pardiso"``
    Intel MKL PARDISO through the ``pypardiso`` package (extra ``fast``,
    x86-64 only): real SPD mode (``mtype=2``) on the upper triangle, METIS
    nested-dissection ordering and symbolic phase 11 once, numeric phase 22
    per matrix, solve phase 33.  One thread at a time: two threads in PARDISO
    at once (on separate handles: EMD's envelopes beside the Riesz bounds'
    shift-invert Lanczos) crashed or hung a threads-scheduler run inside MKL.
``"cholmod"``
    CHOLMOD's supernodal Cholesky ``P A Pᵀ = L Lᵀ`` through ``cvxopt``
    (wheels with their own BLAS for Linux, macOS and Windows; no MKL):
    AMD ordering and supernodal symbolic analysis once
    (``cholmod.symbolic``), numeric factorization per matrix
    (``cholmod.numeric``).  One thread at a time: cvxopt keeps CHOLMOD's
    workspace in one process-wide ``cholmod_common``.
``"superlu"``
    SciPy's SuperLU, always available (a plain ``pip install hht3d``): used
    as a Cholesky, without pivoting, ordered once per pattern and the ordering
    reused: by nested dissection of the surface's vertices
    (:mod:`hht3d.linalg.ordering`), or by its minimum degree when no positions
    are given (:mod:`hht3d.linalg.superlu`).
    Thread-safe: SuperLU 5 keeps no global state, and SciPy releases the GIL
    around it.
``"cg"``
    Iterative, never the default: conjugate gradients preconditioned by
    pyamg's smoothed aggregation (:mod:`hht3d.linalg.cg`), for the
    second-order systems only (``M + tL`` of membrane filtering, the Riesz
    quadrature's ``L + σM``), to the caller's ``tol``.  Thread-safe: the
    solves only read the multigrid hierarchy.

The default is the first installed backend of :data:`SOLVER_BACKENDS`,
unless the environment variable :data:`BACKEND_VARIABLE` names another; a
``backend=`` argument overrides both.  :func:`backend_report` says which one
runs and why.  Every backend gives the same results to solver round-off.

Adding a backend
----------------
One :func:`register_backend` call with a :class:`Backend`: its package, the
modules to import (only when a backend is first needed, so a missing or slow
package costs nothing until then), a line for ``hht3d info --backends``, an
install hint, a class that analyses a pattern and factorizes matrices on
it, and a lock unless the library may be entered by several threads at once
(see :class:`Backend`); a fitted cost in
:data:`hht3d.linalg.estimate.COSTS` adds its time and memory estimates.  Pipelines (``backend:``), EMD, the Riesz
transform and ``hht3d info`` read the registry.
"""

from __future__ import annotations

import importlib
import importlib.metadata
import os
import threading
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from ..errors import HHT3DDeprecationWarning, InputError
from .cg import CGPattern
from .cholmod import CHOLMOD_LOCK, CholmodPattern
from .pardiso import PARDISO_LOCK, PardisoPattern
from .superlu import SuperLUPattern, complex_symmetric_solver

__all__ = [
    "Backend",
    "SOLVER_BACKENDS",
    "register_backend",
    "check_backend",
    "BACKEND_VARIABLE",
    "available_backends",
    "default_backend",
    "backend_report",
    "BackendStatus",
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
        object whose ``factorize(a)`` gives a :class:`~hht3d.linalg.factor.Factor` of any matrix
        with that pattern; it is called as ``pattern(csr, module)`` with
        :meth:`module`.
    lock : threading.RLock or None
        For a library that must not be entered by two threads at once (all its
        handles included): :class:`~hht3d.linalg.symbolic.SymbolicFactorization`
        holds it over every analysis, factorization and solve, so the threads
        scheduler's tasks take turns in it.  ``None`` declares the backend
        thread-safe.
    iterative : bool
        Solves to a relative residual instead of round-off: ``pattern`` then also takes
        the caller's accuracy as ``pattern(csr, module, tol)``.
    orders_by_points : bool
        Has no fill-reducing ordering of its own that suits a surface's systems: ``pattern`` then
        also takes the rows' positions, when the caller has them, as ``pattern(csr, module, points=)``
        (:func:`~hht3d.linalg.ordering.nested_dissection`).
    factorization_iterations : int
        Iterations of :func:`~hht3d.linalg.pcg.jacobi_cg` on a surface's ``L + σM`` (4-5
        right-hand sides) that take about as long as one factorization and solve on this backend:
        the Riesz quadrature solves a shift by them when they suffice
        (:func:`~hht3d.spectral.quadrature.quadrature_part`).  0: always factorize.
    complex_solver : callable or None
        ``complex_solver(matrix, points)`` factorizes a complex symmetric matrix whose real part is SPD and
        gives its solve (``b ↦ A⁻¹ b``), ordered by the rows' positions ``points``: the bilaplacian filter
        as one second-order system (:mod:`hht3d.decomposition.resolvent`).  ``None``: real systems only.
    """

    name: str
    distribution: str
    modules: tuple[str, ...]
    algorithm: str
    missing: str
    pattern: Callable = field(repr=False)
    lock: threading.RLock | None = field(default=None, repr=False, compare=False)
    iterative: bool = False
    orders_by_points: bool = False
    factorization_iterations: int = 0
    complex_solver: Callable | None = field(default=None, repr=False, compare=False)

    def module(self) -> Any:
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
    """Add a solver backend, after the others or ahead of ``before`` in order of preference.

    Parameters
    ----------
    backend : Backend
        The backend; one of the same name is replaced.
    before : str, optional
        The backend it goes ahead of (default: after all others).

    Returns
    -------
    Backend
        ``backend`` itself.
    """
    entries = [b for b in SOLVER_BACKENDS.values() if b.name != backend.name]
    at = next((i for i, b in enumerate(entries) if b.name == before), len(entries))
    entries.insert(at, backend)
    SOLVER_BACKENDS.clear()
    SOLVER_BACKENDS.update((b.name, b) for b in entries)
    return backend


def available_backends() -> list[str]:
    """Names of the installed backends, fastest first.

    Returns
    -------
    list of str
        The backend names.

    Examples
    --------
    >>> from hht3d.linalg import available_backends
    >>> "superlu" in available_backends()  # SciPy's, always installed
    True
    """
    return [name for name, backend in SOLVER_BACKENDS.items() if backend.available]


def default_backend() -> str:
    """The backend used when none is requested.

    The one named by the environment variable :data:`BACKEND_VARIABLE` if set,
    else the fastest installed one.

    Returns
    -------
    str
        The backend's name.

    Examples
    --------
    >>> from hht3d.linalg import available_backends, default_backend
    >>> default_backend() in available_backends()
    True
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
        faster = names[: names.index(default)]
        reason = (
            "the fastest backend"
            if not faster
            else f"the fastest installed backend ({', '.join(faster)} not installed)"
        )
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
    """The backend to use: ``backend`` if it is registered and installed, :func:`default_backend` for ``None``.

    Parameters
    ----------
    backend : str or None
        A backend name, or ``None`` for the default.
    where : str, optional
        The setting the error names (default ``"backend"``).

    Returns
    -------
    str
        The backend's name.

    Examples
    --------
    >>> from hht3d.linalg import check_backend
    >>> check_backend("superlu")
    'superlu'
    >>> check_backend("magic")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    hht3d.errors.InputError: unknown sparse solver backend 'magic' (backend); choose one of (...)
    """
    if backend is None:
        return default_backend()
    if backend not in SOLVER_BACKENDS:
        raise InputError(f"unknown sparse solver backend {backend!r} ({where}); choose one of {tuple(SOLVER_BACKENDS)}")
    if not SOLVER_BACKENDS[backend].available:
        raise InputError(
            f"sparse solver backend {backend!r} ({where}) is not available: "
            f"{SOLVER_BACKENDS[backend].missing}; installed: {available_backends()}"
        )
    return backend


register_backend(
    Backend(
        "pardiso",
        "pypardiso",
        ("pypardiso",),
        "MKL PARDISO, supernodal, METIS ordering, symbolic analysis reused",
        "pypardiso is not installed (MKL, x86-64 only): pip install 'hht3d[fast]'",
        PardisoPattern,
        PARDISO_LOCK,
        factorization_iterations=15,  # 13-25 measured on nefertiti, igea and igea at 250k
    )
)
register_backend(
    Backend(
        "cholmod",
        "cvxopt",
        ("cvxopt", "cvxopt.cholmod"),
        "CHOLMOD supernodal Cholesky, AMD ordering, symbolic analysis reused",
        "cvxopt is not installed (no wheel for this platform?): pip install 'hht3d[fast]'",
        CholmodPattern,
        CHOLMOD_LOCK,
        factorization_iterations=15,  # as PARDISO's
    )
)
register_backend(
    Backend(
        "superlu",
        "scipy",
        ("scipy.sparse.linalg",),
        "SciPy SuperLU without pivoting, nested dissection (or MMD) once per pattern, then reused",
        "scipy is always installed",
        SuperLUPattern,
        orders_by_points=True,
        factorization_iterations=60,  # 53-160 measured on nefertiti, igea and igea at 250k
        complex_solver=complex_symmetric_solver,
    )
)
register_backend(
    Backend(
        "cg",
        "pyamg",
        ("pyamg",),
        "iterative: CG preconditioned by smoothed-aggregation AMG, second-order systems only",
        'pyamg is not installed: pip install "hht3d[iterative]"',
        CGPattern,
        iterative=True,
    )
)


def _deprecated_backends() -> tuple[str, ...]:
    """What ``BACKENDS`` gave, the backends' names fastest first, with a warning to the code that asked."""
    warnings.warn(
        "hht3d.linalg.BACKENDS is deprecated and goes in 0.3.0; use tuple(hht3d.linalg.SOLVER_BACKENDS), "
        "which also holds the backends registered later",
        HHT3DDeprecationWarning,
        stacklevel=3,
    )
    return tuple(SOLVER_BACKENDS)


def __getattr__(name: str) -> Any:
    if name == "BACKENDS":  # deprecated in 0.2.0
        return _deprecated_backends()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
