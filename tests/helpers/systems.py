"""The sparse SPD systems hht3d factorizes, for the solver-backend tests (tests/linalg/).

Built on a surface: the constrained biharmonic envelope system of EMD and
the shifted systems ``L + σM`` of the ``L^{-1/2}`` quadrature at its smallest
and largest shift; and a small singular matrix.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from hht3d import linalg
from hht3d.decomposition import envelope_operator
from hht3d.spectral import quadrature_plan
from hht3d.spectral.shifts import shifted_matrix

#: The installed direct backends (exact to round-off); the iterative ``cg`` is tested in tests/linalg/test_cg.py.
BACKENDS = [b for b in linalg.available_backends() if not linalg.SOLVER_BACKENDS[b].iterative]
#: Backends keeping one numeric factor per symbolic analysis.
SINGLE_FACTOR = [b for b in BACKENDS if b in ("pardiso", "cholmod")]


def envelope_system(surface, constrained: np.ndarray) -> sp.csr_matrix:
    """``[Q_FF 0; 0 diag(Q)_CC]`` on Q's full pattern, as EMD builds it (hht3d.decomposition.decompose notes)."""
    q = envelope_operator(surface, envelope="biharmonic")
    rows = np.repeat(np.arange(surface.n_vertices), np.diff(q.indptr))
    free = ~constrained
    data = q.data * (free[rows] & free[q.indices])
    diagonal = np.flatnonzero(q.indices == rows)
    data[diagonal[constrained]] = q.data[diagonal[constrained]]
    return sp.csr_matrix((data, q.indices.copy(), q.indptr.copy()), shape=q.shape)


def systems(surface):
    """(name, SPD matrix) pairs: two envelope systems and the extreme quadrature shifts."""
    rng = np.random.default_rng(0)
    plan = quadrature_plan(surface, 1e-8, "superlu")
    return [
        ("envelope 5%", envelope_system(surface, rng.random(surface.n_vertices) < 0.05)),
        ("envelope 30%", envelope_system(surface, rng.random(surface.n_vertices) < 0.3)),
        ("smallest shift", shifted_matrix(surface, plan.sigmas[0])),
        ("largest shift", shifted_matrix(surface, plan.sigmas[-1])),
    ]


def relative_error(x, reference):
    return np.linalg.norm(x - reference) / np.linalg.norm(reference)


def singular(n: int = 6) -> sp.csr_matrix:
    """A path-graph Laplacian plus identity with one row and column zeroed (explicit zeros kept)."""
    a = sp.diags([-np.ones(n - 1), 3 * np.ones(n), -np.ones(n - 1)], [-1, 0, 1], format="csr")
    a.data[(np.repeat(np.arange(n), np.diff(a.indptr)) == 2) | (a.indices == 2)] = 0.0
    return a
