"""The tangent-plane least-squares vertex gradient of Eq. (17), as a sparse operator.

At vertex ``i`` with unit normal ``n_i``, the offsets ``v_j − v_i`` to its neighbours are
projected on the tangent plane and written in a basis ``(t1, t2)`` of it
(:func:`tangent_bases`); the gradient solves the 2×2 normal equations there.  Their
pseudo-inverse is in closed form (:func:`_pseudo_inverse`), vectorized over the vertices.
On a 1M-point cloud the coefficients took 3.2 s with LAPACK's pseudo-inverse of each 3×3
normal matrix in space, 1.2 s so, the same to 2.4e-14 of the largest.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["GRADIENT_BLOCK", "RESOLVED_SHARE", "tangent_gradient", "tangent_gradient_coefficients", "tangent_bases"]

#: Vertices per block when assembling the least-squares gradient (bounds its transient memory).
GRADIENT_BLOCK = 1 << 16
#: A tangent direction holding less than this share ``Σ_j (p_ij · u)²`` of the largest gets no gradient component
#: (minimum norm) rather than the neighbours' noise divided by it: cloud points with neighbours nearly in line (558
#: on igea's 1M-point cloud; one gave a Riesz vector 7,000× the median); none on igea or nefertiti.
RESOLVED_SHARE = 1e-2


def tangent_gradient(
    vertices: np.ndarray, normals: np.ndarray, adj: sp.csr_matrix, block: int = GRADIENT_BLOCK
) -> sp.csr_matrix:
    """Tangent-plane least-squares gradient of Eq. (17) as a sparse ``(3n, n)`` operator.

    At vertex ``i`` with unit normal ``n_i`` and neighbours ``j``, ``P_ij`` is
    the unit projection of ``v_j - v_i`` on the tangent plane and the gradient
    ``g`` minimises ``sum_j ((g, P_ij) - (f_j - f_i)/|v_j - v_i|)^2`` over
    tangent vectors (the paper writes ``f_i - f_j``; that is the negative
    gradient).  Exact for linear functions on planar neighbourhoods.  Vertices whose neighbours
    do not span the plane (to :data:`RESOLVED_SHARE`) get the minimum-norm solution.

    The CSR arrays are written ``block`` vertices at a time, so the transient
    memory is that of one block, not of all edges (about 2.7 GB at a million
    vertices otherwise).
    """
    n = len(vertices)
    adj = sp.csr_matrix(adj)
    degree = np.diff(adj.indptr)
    # row 3i+k holds vertex i's neighbours and, if it has any, i itself: sorted columns
    length = degree + (degree > 0)
    start = np.concatenate([[0], np.cumsum(length)])
    nnz = 3 * int(start[-1])
    index = np.int32 if max(nnz, n) < np.iinfo(np.int32).max else np.int64
    data, indices = np.empty(nnz), np.empty(nnz, dtype=index)
    for first in range(0, n, block):
        last = min(first + block, n)
        edges = slice(adj.indptr[first], adj.indptr[last])
        coef = tangent_gradient_coefficients(vertices, normals, adj, first, last)  # (edges, 3)
        rows = np.repeat(np.arange(first, last), degree[first:last])
        cols = adj.indices[edges]
        # each vertex's entries: its neighbours, then itself with minus their sum
        diagonal = np.flatnonzero(degree[first:last]) + first
        sums = np.stack([np.bincount(rows - first, coef[:, k], last - first) for k in range(3)], axis=1)
        entry_vertex = np.concatenate([rows, diagonal])
        entry_col = np.concatenate([cols, diagonal])
        entry_val = np.concatenate([coef, -sums[diagonal - first]])
        order = np.lexsort((entry_col, entry_vertex))
        entry_vertex, entry_col, entry_val = entry_vertex[order], entry_col[order], entry_val[order]
        offset = np.arange(len(order)) - (start[entry_vertex] - start[first])
        for k in range(3):
            position = 3 * start[entry_vertex] + k * length[entry_vertex] + offset
            data[position] = entry_val[:, k]
            indices[position] = entry_col
    indptr = np.concatenate([[0], np.cumsum(np.repeat(length, 3))]).astype(index)
    return sp.csr_matrix((data, indices, indptr), shape=(3 * n, n))


def tangent_gradient_coefficients(
    vertices: np.ndarray, normals: np.ndarray, adj: sp.csr_matrix, first: int, last: int
) -> np.ndarray:
    """``(P^T P)^+ P_ij / |v_j - v_i|`` (edges, 3) for the edges ``adj`` holds for vertices ``first..last-1``, in
    its order: the entries ``c_ij`` of :func:`tangent_gradient` (``∇f_i = Σ_j c_ij (f_j − f_i)``).

    The normal equations are solved in coordinates of the tangent plane (module notes), their 2×2
    pseudo-inverse in closed form."""
    rows = np.repeat(np.arange(first, last), np.diff(adj.indptr[first : last + 1]))
    owner = rows - first
    d = vertices[adj.indices[adj.indptr[first] : adj.indptr[last]]] - vertices[rows]
    length = np.linalg.norm(d, axis=1)
    t1, t2 = tangent_bases(normals[first:last])
    x, y = np.einsum("ei,ei->e", d, t1[owner]), np.einsum("ei,ei->e", d, t2[owner])
    p_len = np.hypot(x, y)
    ok = (p_len > 0) & (length > 0)
    x = np.divide(x, p_len, out=np.zeros_like(x), where=ok)
    y = np.divide(y, p_len, out=np.zeros_like(y), where=ok)
    inv_len = np.divide(1.0, length, out=np.zeros_like(length), where=ok)
    size = last - first
    pa, pb, pc = _pseudo_inverse(*(np.bincount(owner, weights=w, minlength=size) for w in (x * x, x * y, y * y)))
    gx, gy = (pa[owner] * x + pb[owner] * y) * inv_len, (pb[owner] * x + pc[owner] * y) * inv_len
    coef = gx[:, None] * t1[owner] + gy[:, None] * t2[owner]
    unset = ~np.any(normals[first:last] != 0, axis=1)  # no normal (isolated, or its faces cancel): fit in space
    if unset.any():
        edges = unset[owner]
        coef[edges] = _spatial_coefficients(d[edges], owner[edges], length[edges])
    return coef


def tangent_bases(normals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit tangents ``t1, t2`` (n, 3) with ``(t1, t2, n)`` right-handed, for unit ``normals`` (n, 3):
    ``t1`` across the coordinate axis least aligned with the normal."""
    axis = np.zeros_like(normals)
    axis[np.arange(len(normals)), np.argmin(np.abs(normals), axis=1)] = 1.0
    t1 = np.cross(normals, axis)
    norm = np.linalg.norm(t1, axis=1, keepdims=True)
    t1 = np.divide(t1, norm, out=np.zeros_like(t1), where=norm > 0)  # a zero normal gets zero tangents
    return t1, np.cross(normals, t1)


def _spatial_coefficients(d: np.ndarray, owner: np.ndarray, length: np.ndarray) -> np.ndarray:
    """``(Pᵀ P)⁺ P_ij / |v_j − v_i|`` (edges, 3) with ``P_ij`` the unit offsets ``d`` themselves (no tangent
    plane), ``owner`` the vertex of each edge."""
    vertex, owner = np.unique(owner, return_inverse=True)
    ok = length > 0
    p = np.divide(d, length[:, None], out=np.zeros_like(d), where=ok[:, None])
    outer = (p[:, :, None] * p[:, None, :]).reshape(len(p), 9)
    ptp = np.stack([np.bincount(owner, weights=outer[:, c], minlength=len(vertex)) for c in range(9)], axis=1)
    pinv = np.linalg.pinv(ptp.reshape(-1, 3, 3), rcond=RESOLVED_SHARE, hermitian=True)
    inv_len = np.divide(1.0, length, out=np.zeros_like(length), where=ok)
    return np.einsum("eij,ej->ei", pinv[owner], p) * inv_len[:, None]


def _pseudo_inverse(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Entries ``(a', b', c')`` of the pseudo-inverse of each symmetric ``[[a, b], [b, c]]`` (positive
    semidefinite), its eigenvalues below :data:`RESOLVED_SHARE` of the largest dropped: the inverse when
    both stay; ``u uᵀ / λ₁`` with ``u uᵀ = (S − λ₂ I) / (λ₁ − λ₂)`` when only the largest ``λ₁`` does; 0
    for 0."""
    mean, radius = 0.5 * (a + c), np.hypot(0.5 * (a - c), b)
    top, low = mean + radius, mean - radius
    full = low > RESOLVED_SHARE * top
    single = ~full & (top > 0)
    det = np.where(full, a * c - b * b, 1.0)
    gap = np.where(single, (top - low) * top, 1.0)
    return (
        np.where(full, c / det, np.where(single, (a - low) / gap, 0.0)),
        np.where(full, -b / det, np.where(single, b / gap, 0.0)),
        np.where(full, a / det, np.where(single, (c - low) / gap, 0.0)),
    )
