"""Sparse symmetric positive-definite factorization backends.

* :mod:`~hht3d.linalg.backends` — the registry: which backends exist, which one runs and why;
* :mod:`~hht3d.linalg.symbolic` — :class:`SymbolicFactorization` (one analysis, many factorizations);
* :mod:`~hht3d.linalg.estimate` — time and memory known before factorizing, and the advice that follows;
* :mod:`~hht3d.linalg.pardiso`, :mod:`~hht3d.linalg.cholmod`, :mod:`~hht3d.linalg.superlu` — the direct backends;
* :mod:`~hht3d.linalg.cg` — the iterative one (CG with a multigrid preconditioner).
"""

from typing import Any

from . import backends
from .backends import (
    BACKEND_VARIABLE,
    SOLVER_BACKENDS,
    Backend,
    BackendStatus,
    available_backends,
    backend_report,
    check_backend,
    default_backend,
    register_backend,
)
from .estimate import (
    SLOW_FALLBACK_VERTICES,
    Estimate,
    SlowSolverWarning,
    available_memory,
    backend_estimates,
    check_memory,
    estimate_hht,
    estimate_lines,
    slow_fallback,
    warn_slow_fallback,
)
from .factor import Factor
from .symbolic import SymbolicFactorization, factorize

__all__ = [
    "BACKEND_VARIABLE",
    "SOLVER_BACKENDS",
    "Backend",
    "BackendStatus",
    "available_backends",
    "backend_report",
    "check_backend",
    "default_backend",
    "register_backend",
    "SLOW_FALLBACK_VERTICES",
    "Estimate",
    "SlowSolverWarning",
    "available_memory",
    "backend_estimates",
    "check_memory",
    "estimate_hht",
    "estimate_lines",
    "slow_fallback",
    "warn_slow_fallback",
    "Factor",
    "SymbolicFactorization",
    "factorize",
]


def __getattr__(name: str) -> Any:
    if name == "BACKENDS":  # deprecated in 0.2.0
        return backends._deprecated_backends()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
