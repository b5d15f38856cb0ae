"""The robust Laplacian of a large surface, built block by block in bounded memory (issue 39).

``robust_laplacian`` builds its intrinsic Delaunay Laplacian (meshes, and the tufted
triangulation of a point cloud's local Delaunay neighbourhoods) in one data structure
whose transient memory far exceeds the mesh's: about 2.9 KB per vertex on a coarse mesh
level (3 GB for igea's 1M-vertex level 1), 12 KB per point on a point cloud (12.2 GB for
1M points).  So a surface above :data:`MESH_BLOCK` vertices (:data:`CLOUD_BLOCK` points)
is cut into blocks: boxes of a recursive coordinate bisection with at most that many
vertices.  Each block is built together with a halo around it, and keeps the rows of its
own vertices:

* meshes: the halo is the :data:`MESH_HALO_RINGS` rings of vertices around the block,
  and the sub-mesh the faces with all three corners in block or halo;
* point clouds: the halo is every point within :data:`CLOUD_HALO_SPANS` of the block's
  largest ``k``-nearest-neighbour distance of its box: a row depends on the local
  triangulations of its neighbours, which depend on their neighbours.

A row far enough from the halo's edge is the row of the whole surface: the intrinsic
Delaunay flips that set it are local.  What differs is the intrinsic mollification, whose
length shift ``ε`` is the largest one any triangle of the block needs (at most
``mollify_factor`` times the mean edge length, 1e-5): entries move by ``O(ε / ℓ)``.  The
rows are assembled into ``(L + Lᵀ) / 2`` with the diagonal set to minus the off-diagonal
row sums, so ``L`` stays symmetric with ``L 1 = 0``; each vertex's mass is its block's.
The blocks are built in :func:`~.block_processes.process_count` child processes
(:mod:`.block_processes`), so transient memory is that of one block per process.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Iterator

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from .block_processes import mapped, process_count

__all__ = [
    "MESH_BLOCK",
    "CLOUD_BLOCK",
    "MESH_HALO_RINGS",
    "CLOUD_HALO_SPANS",
    "bisection_blocks",
    "built_by_blocks",
    "own_rows",
]

#: Meshes of more vertices are built by blocks of at most this many (about 0.6 GB transient each).
MESH_BLOCK = 200_000
#: Point clouds of more points are built by blocks of at most this many (about 0.6 GB transient each).
CLOUD_BLOCK = 50_000
#: Rings of vertices around a mesh block that are built with it (2 left rows 2% off on nefertiti, 4 none).
MESH_HALO_RINGS = 4
#: The halo of a point-cloud block reaches this many times its largest ``k``-nearest-neighbour distance (3 gave
#: the same rows on nefertiti's vertices, 1 rows 7% off).
CLOUD_HALO_SPANS = 2.0

#: ``build(points, faces) -> (L, mass_diagonal)`` of a whole (sub-)surface; it must pickle (child processes).
Builder = Callable[[np.ndarray, "np.ndarray | None"], "tuple[sp.spmatrix, np.ndarray]"]


def bisection_blocks(points: np.ndarray, size: int) -> list[np.ndarray]:
    """Vertex indices of boxes of at most ``size`` points: each box over ``size`` is halved at the median
    of its longest side, so the blocks are compact and balanced (deterministic: introselect, no random pivot)."""
    pending, blocks = [np.arange(len(points))], []
    while pending:
        index = pending.pop()
        if len(index) <= size:
            blocks.append(index)
            continue
        p = points[index]
        axis = int(np.argmax(p.max(axis=0) - p.min(axis=0)))
        half = len(index) // 2
        order = np.argpartition(p[:, axis], half)  # the median's side, no whole sort (17 s at 10M points)
        pending += [index[order[half:]], index[order[:half]]]
    return blocks


def built_by_blocks(
    build: Builder, points: np.ndarray, faces: np.ndarray | None, size: int, n_neighbors: int = 30
) -> tuple[sp.csr_matrix, np.ndarray]:
    """``(L, mass_diagonal)`` of the whole surface from ``build`` on blocks of at most ``size`` vertices
    and their halos (module notes); ``build`` on the whole when it has ``size`` vertices or fewer.
    ``n_neighbors`` sets a point cloud's halo (its Laplacian's ``k``)."""
    n = len(points)
    if n <= size:
        lap, mass = build(points, faces)
        return sp.csr_matrix(lap), np.asarray(mass, dtype=np.float64)
    halo = _mesh_halo(n, faces) if faces is not None else _cloud_halo(points, n_neighbors)
    found, prepared = bisection_blocks(points, size), deque[tuple[np.ndarray, np.ndarray]]()

    def arguments() -> Iterator[tuple]:
        for block in found:
            kept, sub_faces = halo(block)
            prepared.append((block, kept))
            yield build, points[kept], sub_faces, np.searchsorted(kept, block)  # kept is sorted, holds the block

    rows, cols, vals, mass = [], [], [], np.zeros(n)
    for row, col, val, own_mass in mapped(own_rows, arguments(), min(process_count(), len(found))):
        block, kept = prepared.popleft()
        rows.append(block[row])
        cols.append(kept[col])
        vals.append(val)
        mass[block] = own_mass
    return _symmetric(n, np.concatenate(rows), np.concatenate(cols), np.concatenate(vals)), mass


def own_rows(
    build: Builder, points: np.ndarray, faces: np.ndarray | None, own: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(row, col, value, mass)`` of the rows ``own`` of ``build(points, faces)``: one block's share
    (``row`` indexes ``own``, ``col`` the points)."""
    lap, mass = build(points, faces)
    part = sp.csr_matrix(lap)[own].tocoo()
    return part.row, part.col, part.data, np.asarray(mass)[own]


def _mesh_halo(n: int, faces: np.ndarray) -> Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]:
    """``halo(block)``: the sorted vertices of the block and of the :data:`MESH_HALO_RINGS` rings around it,
    and the faces with all three corners among them, renumbered to them."""
    i, j = faces.ravel(), faces[:, [1, 2, 0]].ravel()
    graph = sp.csr_matrix((np.ones(2 * len(i), dtype=bool), (np.concatenate([i, j]), np.concatenate([j, i]))), (n, n))

    def halo(block: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        reached = np.zeros(n, dtype=bool)
        reached[block] = True
        frontier = block
        for _ in range(MESH_HALO_RINGS):
            around = np.unique(graph[frontier].indices)
            frontier = around[~reached[around]]
            reached[frontier] = True
        kept = np.flatnonzero(reached)
        renumber = np.full(n, -1, dtype=np.int64)
        renumber[kept] = np.arange(len(kept))
        return kept, renumber[faces[reached[faces].all(axis=1)]]

    return halo


def _cloud_halo(points: np.ndarray, k: int) -> Callable[[np.ndarray], tuple[np.ndarray, None]]:
    """``halo(block)``: the sorted points of the block and those within :data:`CLOUD_HALO_SPANS` times the
    block's largest ``k``-nearest-neighbour distance of its bounding box."""
    tree = cKDTree(points)

    def halo(block: np.ndarray) -> tuple[np.ndarray, None]:
        reach = CLOUD_HALO_SPANS * float(tree.query(points[block], k=min(k + 1, len(points)))[0].max())
        low, high = points[block].min(axis=0) - reach, points[block].max(axis=0) + reach
        # the cube around the box from the tree, then the box (at 10M points 0.013 s a block; a scan, 0.27 s)
        half = (high - low).max() / 2 * (1 + 1e-9)
        near = np.asarray(tree.query_ball_point((low + high) / 2, half, p=np.inf, return_sorted=True), dtype=np.int64)
        return near[np.all((points[near] >= low) & (points[near] <= high), axis=1)], None

    return halo


def _symmetric(n: int, rows: np.ndarray, cols: np.ndarray, vals: np.ndarray) -> sp.csr_matrix:
    """``(A + Aᵀ) / 2`` of the assembled rows' off-diagonal part, with minus its row sums on the diagonal."""
    off = rows != cols
    a = sp.csr_matrix((vals[off], (rows[off], cols[off])), shape=(n, n))
    a = ((a + a.T) * 0.5).tocsr()
    lap = (a - sp.diags(np.asarray(a.sum(axis=1)).ravel())).tocsr()
    lap.sort_indices()
    return lap
