"""The least-squares gradient's coefficients (hht3d.geometry.tangent_gradient) against LAPACK's pseudo-inverse.

Oracle: Eq. (17)'s normal equations written in space, ``(Pᵀ P)⁺ Pᵀ`` with ``P`` the unit tangent projections of
the offsets, by :func:`numpy.linalg.pinv` (``hermitian=True``, the same relative cut).  The closed form works in a
basis of the tangent plane, so the two agree to round-off (1e-12 relative to the largest coefficient) wherever a
normal is given, whether the neighbours span the plane, lie on a line (rank one) or coincide with the vertex.
"""

import numpy as np
import scipy.sparse as sp

from hht3d.geometry.tangent_gradient import RESOLVED_SHARE, tangent_gradient_coefficients


def _pinv_coefficients(vertices, normals, adj):
    rows = np.repeat(np.arange(adj.shape[0]), np.diff(adj.indptr))
    d = vertices[adj.indices] - vertices[rows]
    length = np.linalg.norm(d, axis=1)
    n = normals[rows]
    p = d - np.einsum("ei,ei->e", d, n)[:, None] * n
    p_len = np.linalg.norm(p, axis=1)
    ok = (p_len > 0) & (length > 0)
    p = np.divide(p, p_len[:, None], out=np.zeros_like(p), where=ok[:, None])
    ptp = np.zeros((adj.shape[0], 3, 3))
    np.add.at(ptp, rows, p[:, :, None] * p[:, None, :])
    pinv = np.linalg.pinv(ptp, rcond=RESOLVED_SHARE, hermitian=True)
    return np.einsum("eij,ej->ei", pinv[rows], p) * np.divide(1.0, length, out=np.zeros_like(length), where=ok)[:, None]


def test_the_closed_form_is_lapacks_pseudo_inverse():
    """300 vertices with 1–12 random neighbours and random unit normals, among them: a vertex whose neighbours lie
    on a line through it (rank one), one with a single neighbour, one with a neighbour on top of it, one whose
    neighbours' tangent spread is 1/200 of the other direction's (below the 1/100 cut: rank one), one with no
    normal (a fit in space), and one without neighbours."""
    rng = np.random.default_rng(5)
    n = 300
    vertices = rng.normal(size=(n, 3))
    normals = rng.normal(size=(n, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    lists = [rng.choice(np.delete(np.arange(n), i), rng.integers(1, 13), replace=False) for i in range(n)]
    u = np.cross(normals[0], [1.0, 0.0, 0.0])
    vertices[1:4] = vertices[0] + np.outer([1.0, -2.0, 0.5], u)  # vertex 0's neighbours on a line in its plane
    lists[0] = np.array([1, 2, 3])
    lists[5] = np.array([7])
    vertices[9] = vertices[8]  # a neighbour on top of vertex 8
    lists[8] = np.array([9, 10, 11])
    a, b = np.cross(normals[12], [0.0, 1.0, 0.0]), np.cross(normals[12], [0.0, 0.0, 1.0])
    vertices[13:16] = vertices[12] + np.array([a + 0.005 * b, -a, a - 0.005 * b]) * 0.9
    lists[12] = np.array([13, 14, 15])
    normals[20] = 0.0
    lists[30] = np.array([], dtype=int)
    adj = sp.csr_matrix(
        (np.ones(sum(map(len, lists))), np.concatenate(lists), np.r_[0, np.cumsum(list(map(len, lists)))]), (n, n)
    )
    adj.sort_indices()
    expected = _pinv_coefficients(vertices, normals, adj)
    unit = np.where(np.any(normals != 0, axis=1))[0]
    blocks = [(a, min(a + 64, n)) for a in range(0, n, 64)]
    got = np.concatenate([tangent_gradient_coefficients(vertices, normals, adj, a, b) for a, b in blocks])
    scale = np.abs(expected).max()
    np.testing.assert_allclose(got, expected, atol=1e-12 * scale)
    assert len(unit) == n - 1
    ranks = [
        np.linalg.matrix_rank(_pinv_coefficients(vertices, normals, adj)[adj.indptr[i] : adj.indptr[i + 1]], 1e-9)
        for i in (0, 5, 12)
    ]
    assert ranks == [1, 1, 1]  # the rank-one cases are what the test says they are
