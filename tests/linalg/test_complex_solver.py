"""SuperLU's complex symmetric solve (hht3d.linalg.superlu.complex_symmetric_solver) against NumPy's dense solve."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from helpers.meshes import grid
from hht3d import Surface
from hht3d.linalg.superlu import complex_symmetric_solver


def test_a_complex_symmetric_system_with_spd_real_part_is_solved_to_rounding():
    # M + i t L on a jittered grid, t large enough that the imaginary part dominates (|t λ_max| ≈ 1e4): elimination
    # without pivoting is stable for an SPD real part, so the residual is rounding, 1e-12 of the solution with the
    # condition ≈ 1e4 and the nested-dissection order, rows and columns, undone.
    s = Surface(*grid(25, 18, 1.5, 1.0, jitter=0.3))
    a = (sp.diags(s.mass_diagonal) + 1j * 30.0 * s.stiffness).tocsr()
    rng = np.random.default_rng(3)
    b = rng.standard_normal((s.n_vertices, 2)) + 1j * rng.standard_normal((s.n_vertices, 2))
    x = complex_symmetric_solver(a, s.vertices)(b)
    expected = np.linalg.solve(a.toarray(), b)
    np.testing.assert_allclose(x, expected, rtol=0, atol=1e-12 * np.abs(expected).max())
