"""The directed edges of a vertex gradient operator and of the Laplacian, read a block of vertices at a time.

The phase route of :func:`hht3d.spectral.frequency.instantaneous_frequency` (Eq. 23) fits each
vertex's phase gradient to increments along its edges.  :class:`EdgeStencil` keeps those edges as
plain arrays (about 280 bytes a vertex, 230 where the gradient and the Laplacian have the same
edges), built a block of rows at a time, and :class:`Block` gives the maps the estimator applies
over a range of vertices, so no per-edge work array spans the surface.  Per-vertex sums run in
edge order, as the sparse products they replace add them.
"""

from __future__ import annotations

import functools
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..geometry.surface import Surface
from ..geometry.tangent_gradient import tangent_gradient_coefficients

__all__ = ["BLOCK_EDGES", "CACHED_VERTICES", "Block", "EdgeStencil", "edge_stencil", "build_edge_stencil"]

#: Surfaces of this many vertices or more build the edge stencil at each call (0.7 s a million
#: vertices) rather than keep its 280 bytes a vertex for the rest of the run.
CACHED_VERTICES = 1_000_000
#: Edges a block of the phase route spans: its per-edge work arrays (about a dozen, with the edge
#: offsets) stay near 100 MB a thread whatever the surface's size.
BLOCK_EDGES = 1 << 20


@dataclass(frozen=True)
class EdgeStencil:
    """Directed edges ``i → j`` of a vertex gradient operator and of the Laplacian, cached per surface.

    ``points`` are the vertices (3, n).  The gradient ``G`` (3n, n) has rows
    ``∇f_i = Σ_j c_ij (f_j − f_i)``: its edges, sorted by ``i`` (``starts`` is the row pointer),
    keep their ends ``j`` (``cols``) and the coefficients ``c_ij`` (``coef``, (3, E)); the
    Laplacian's edges, likewise, keep ``−L_ij`` (``lap_weight``).  About 40 bytes an edge; the
    phase route reads them a block of vertices at a time (:class:`Block`), so no per-edge work
    array spans the whole surface.
    """

    points: np.ndarray
    starts: np.ndarray
    cols: np.ndarray
    coef: np.ndarray
    lap_starts: np.ndarray
    lap_cols: np.ndarray
    lap_weight: np.ndarray

    @property
    def n(self) -> int:
        return self.points.shape[1]

    def blocks(self, at_least: int = 1) -> Iterator["Block"]:
        """The vertices in consecutive ranges of about :data:`BLOCK_EDGES` edges, one block at a time; at least
        ``at_least`` of them (as many as threads that share them) where there are that many vertices."""
        step = max(1, min(BLOCK_EDGES * self.n // max(len(self.cols), 1), -(-self.n // at_least)))
        for a in range(0, self.n, step):
            yield Block(self, a, min(a + step, self.n))


class Block:
    """The edges of the vertices ``[a, b)`` of a stencil, with the maps the phase route applies.

    Per-vertex inputs are whole-surface arrays read at each edge's start ``i`` (:meth:`at_start`)
    or end ``j`` (``cols``); per-vertex outputs cover ``[a, b)``.  The offsets ``x_j − x_i`` are gathered on first use,
    so a block's memory is its own.  Edges are sorted by ``i``: a value per vertex reaches its
    edges by :func:`numpy.repeat`, the fastest gather.
    """

    def __init__(self, st: EdgeStencil, a: int, b: int) -> None:
        self.st, self.a, self.b = st, a, b
        self.edges = slice(st.starts[a], st.starts[b])
        self.lap = slice(st.lap_starts[a], st.lap_starts[b])
        self.cols = st.cols[self.edges]
        self.counts = np.diff(st.starts[a : b + 1])
        self.lap_counts = np.diff(st.lap_starts[a : b + 1])

    @property
    def size(self) -> int:
        return self.b - self.a

    @property
    def starts(self) -> np.ndarray:
        """Where each vertex's edges start within the block (size,)."""
        return self.st.starts[self.a : self.b] - self.st.starts[self.a]

    def at_start(self, y: np.ndarray) -> np.ndarray:
        """``y_i`` per edge, for a whole-surface ``y`` (n,)."""
        return np.repeat(y[self.a : self.b], self.counts)

    @functools.cached_property
    def offset(self) -> np.ndarray:
        """``x_j − x_i`` (3, E) of the gradient's edges."""
        return self._offset(self.cols, self.counts)

    @functools.cached_property
    def lap_offset(self) -> np.ndarray:
        """``x_j − x_i`` (3, E) of the Laplacian's edges."""
        return self._offset(self.st.lap_cols[self.lap], self.lap_counts)

    def _offset(self, cols: np.ndarray, counts: np.ndarray) -> np.ndarray:
        points = self.st.points
        return np.stack([points[c][cols] - np.repeat(points[c][self.a : self.b], counts) for c in range(3)])

    def fit(self, x: np.ndarray) -> np.ndarray:
        """``Σ_j c_ij x_ij`` (size, 3): the gradient's coefficients applied to per-edge differences."""
        coef = self.st.coef[:, self.edges]
        return np.column_stack([self._sum(self.owner, coef[c] * x) for c in range(3)])

    def along(self, g: np.ndarray) -> np.ndarray:
        """``g_i · (x_j − x_i)`` per edge for block vectors ``g`` (size, 3)."""
        return self._along(g, self.offset, self.counts)

    def ring(self, y: np.ndarray) -> np.ndarray:
        """``Σ_j y_j`` over each vertex's edges, for a whole-surface ``y`` (n,)."""
        return self._sum(self.owner, y[self.cols])

    def lap_along(self, g: np.ndarray) -> np.ndarray:
        """``g_i · (x_j − x_i)`` per Laplacian edge."""
        return self._along(g, self.lap_offset, self.lap_counts)

    def lap_sum(self, y: np.ndarray) -> np.ndarray:
        """``Σ_j −L_ij y_ij`` over each vertex's Laplacian edges."""
        return self._sum(self.lap_owner, self.st.lap_weight[self.lap] * y)

    def _along(self, g: np.ndarray, offset: np.ndarray, counts: np.ndarray) -> np.ndarray:
        at = [np.repeat(g[:, c], counts) for c in range(3)]
        return at[0] * offset[0] + at[1] * offset[1] + at[2] * offset[2]

    @functools.cached_property
    def owner(self) -> np.ndarray:
        """``i − a`` per edge."""
        return np.repeat(np.arange(self.size), self.counts)

    @functools.cached_property
    def lap_owner(self) -> np.ndarray:
        """``i − a`` per Laplacian edge."""
        return np.repeat(np.arange(self.size), self.lap_counts)

    def _sum(self, owner: np.ndarray, values: np.ndarray) -> np.ndarray:
        """Per-vertex sums of per-edge ``values`` (in edge order, as a sparse product adds them)."""
        return np.bincount(owner, weights=values, minlength=self.size)


def edge_stencil(surface: Surface, kind: str) -> EdgeStencil:
    """The surface's stencil, kept in its cache below :data:`CACHED_VERTICES` vertices."""
    if surface.n_vertices >= CACHED_VERTICES:
        return build_edge_stencil(surface, kind)
    key = f"frequency:stencil:{kind}"
    if key not in surface.cache:
        surface.cache[key] = build_edge_stencil(surface, kind)
    return surface.cache[key]


def build_edge_stencil(surface: Surface, kind: str) -> EdgeStencil:
    """The edges of ``G`` and of ``L``, gathered a block of rows at a time (no whole-surface sort)."""
    n = surface.n_vertices
    step = max(1, BLOCK_EDGES // 8)
    ranges = [(a, min(a + step, n)) for a in range(0, n, step)]
    stiffness = surface.stiffness.tocsr()
    if kind == "lsq":  # from the coefficients: no (3n, n) operator beside the stencil
        edges = functools.partial(_lsq_edges, surface)
    else:
        edges = functools.partial(_gradient_edges, surface.gradient(kind))
    counts, cols, coef = (np.concatenate(part, axis=-1) for part in zip(*(edges(a, b) for a, b in ranges)))
    lap_counts, lap_cols, lap_weight = (
        np.concatenate(part) for part in zip(*(_laplacian_edges(stiffness, a, b) for a, b in ranges))
    )
    starts, lap_starts = np.r_[0, np.cumsum(counts)], np.r_[0, np.cumsum(lap_counts)]
    if np.array_equal(lap_starts, starts) and np.array_equal(lap_cols, cols):  # a mesh's 1-ring, most often
        lap_starts, lap_cols = starts, cols
    return EdgeStencil(np.ascontiguousarray(surface.vertices.T), starts, cols, coef, lap_starts, lap_cols, lap_weight)


def _gradient_edges(gradient: sp.csr_matrix, a: int, b: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Edges per vertex, ends ``j`` sorted and ``c_ij`` (3, E) of the vertices ``[a, b)``: the
    off-diagonal entries of the rows ``3i .. 3i + 2`` of ``G``, an edge wherever one component is
    nonzero."""
    block = gradient[3 * a : 3 * b].tocoo()
    block.sum_duplicates()
    vertex, component = np.divmod(block.row, 3)
    n = gradient.shape[1]
    off = (block.col != vertex + a) & (block.data != 0)
    keys = vertex[off].astype(np.int64) * n + block.col[off]
    order = np.argsort(keys, kind="stable")
    ordered = keys[order]
    first = np.r_[True, ordered[1:] != ordered[:-1]]
    index = np.empty_like(order)
    index[order] = np.cumsum(first) - 1
    coef = np.zeros((3, int(first.sum())))
    coef[component[off], index] = block.data[off]  # one entry per (row, column): no sums
    rows, cols = np.divmod(ordered[first], n)
    return np.bincount(rows, minlength=b - a), cols.astype(_index_type(n)), coef


def _lsq_edges(surface: Surface, a: int, b: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`_gradient_edges` of ``surface.gradient("lsq")``, from its coefficients over the adjacency (whose
    columns are sorted), without the operator: the same edges and values."""
    adj = surface.adjacency
    coef = tangent_gradient_coefficients(surface.vertices, surface.normals, adj, a, b)
    keep = np.any(coef != 0, axis=1)
    owner = np.repeat(np.arange(b - a), np.diff(adj.indptr[a : b + 1]))[keep]
    cols = adj.indices[adj.indptr[a] : adj.indptr[b]][keep]
    return np.bincount(owner, minlength=b - a), cols.astype(_index_type(surface.n_vertices)), coef[keep].T


def _laplacian_edges(stiffness: sp.csr_matrix, a: int, b: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Edges per vertex, ends ``j`` and ``−L_ij`` of the off-diagonal nonzeros of the rows ``[a, b)`` of ``L``."""
    block = stiffness[a:b].tocoo()
    keep = (block.row + a != block.col) & (block.data != 0)
    rows = block.row[keep]
    return (
        np.bincount(rows, minlength=b - a),
        block.col[keep].astype(_index_type(stiffness.shape[0])),
        -block.data[keep],
    )


def _index_type(n: int) -> type:
    return np.int32 if n < 2**31 else np.int64
