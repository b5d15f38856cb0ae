"""Sparse symmetric positive-definite factorization backends."""
from .backends import (BACKEND_VARIABLE, SOLVER_BACKENDS, Backend, register_backend, available_backends, default_backend,
                       BackendStatus, backend_report, check_backend, Factor, BACKENDS, SymbolicFactorization,
                       factorize)
