"""Conjugate gradients preconditioned by smoothed-aggregation multigrid: the iterative backend ``"cg"``.

For the second-order SPD systems of hht3d, the membrane resolvent ``M + tL``
of iterative filtering (``filter="membrane"``) and the Riesz quadrature's
``L + σM``, a "factorization" is building the preconditioner
(``pyamg.smoothed_aggregation_solver(A).aspreconditioner()``, one V-cycle)
and every solve runs PCG from zero until the relative residual
``‖b − Ax‖₂ / ‖b‖₂`` is at most ``rtol``.

The preconditioner was chosen by measurement on nefertiti (50k vertices) at
the ``t`` of a real membrane filtering run and the shifts of the Riesz
quadrature at ``tol=1e-8`` (docs/performance.md, "The iterative backend"):
Jacobi needs 51-849 iterations on ``M + tL`` (growing like ``√t``) and up to
1,739 on ``L + σM``; smoothed aggregation 10-28 and at most 36.

Fourth-order systems (EMD's bilaplacian envelopes and filter) are refused
by :func:`~hht3d.decomposition.emd` before they are built; any system CG
cannot solve within :data:`MAX_ITERATIONS` raises :class:`NumericalError`
(on nefertiti's bilaplacian filter ``M + t²LM̃⁻¹L`` SA-PCG needs 71 to
1,943 iterations, 30-50x a direct solve).

Thread-safe: the multigrid hierarchy, its coarse-grid factor included (built
by one preconditioner application in :meth:`CGPattern.factorize`), is only
read by the solves, and every solve has its own vectors.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp

from ..errors import NumericalError
from .factor import Factor, Pattern
from .pcg import pcg

__all__ = ["CGPattern", "DEFAULT_RTOL", "MAX_ITERATIONS", "rtol_for"]

#: Relative residual when the caller states no accuracy: on nefertiti the solutions then differ
#: from SuperLU's by at most 7e-11 relative (2-norm), the IMFs of membrane filtering by < 1e-9.
DEFAULT_RTOL = 1e-10
#: The tightest residual asked for: below it round-off in the updates dominates.
MIN_RTOL = 1e-14
#: PCG iterations before giving up (SA-PCG needs at most 36 on the second-order systems measured).
MAX_ITERATIONS = 500


def rtol_for(tol: float | None) -> float:
    """The relative residual that keeps a solution within ``tol`` of the exact one (a hundredth of it).

    Parameters
    ----------
    tol : float or None
        The caller's relative accuracy; ``None`` gives :data:`DEFAULT_RTOL`.
    """
    return DEFAULT_RTOL if tol is None else float(np.clip(tol / 100.0, MIN_RTOL, 1e-2))


class CGPattern:
    """SA-preconditioned CG on one sparsity pattern; ``factorize`` builds the preconditioner."""

    def __init__(self, pattern: sp.csr_matrix, module: Any, tol: float | None = None) -> None:
        self._pattern = Pattern(pattern)
        self._pyamg = module
        self.rtol = rtol_for(tol)

    def factorize(self, a: sp.csr_matrix) -> Factor:
        a = self._pattern.check(a).copy()
        a.eliminate_zeros()  # the envelopes' shared pattern stores the bilaplacian's zeros
        if np.any(a.diagonal() <= 0):
            raise NumericalError("CG needs a positive diagonal (SPD matrix); the matrix has a non-positive one")
        preconditioner = self._pyamg.smoothed_aggregation_solver(a).aspreconditioner()
        preconditioner @ np.zeros(a.shape[0])  # builds the coarse-grid factor now: later solves only read
        rtol = self.rtol

        def solve(b: np.ndarray) -> np.ndarray:
            x, reached = pcg(a, b, lambda r: _columns(preconditioner, r), rtol, MAX_ITERATIONS)
            if reached > rtol:
                raise NumericalError(
                    f"CG did not converge on the {a.shape[0]:,}-row SPD system ({a.nnz:,} entries) in "
                    f"{MAX_ITERATIONS} iterations: relative residual {reached:.2e}, asked {rtol:.1e}; the cg backend "
                    "is for second-order systems (M + tL, L + σM): use a direct backend (pardiso, cholmod, superlu)"
                )
            return x

        return Factor(solve, a.shape[0])


def _columns(preconditioner: Any, r: np.ndarray) -> np.ndarray:
    """The V-cycle applied to each column of ``r`` (n, k)."""
    return np.column_stack([preconditioner @ column for column in r.T])
