"""Discrete differential operators on triangle meshes and point clouds.

Pure functions, arrays in and arrays or sparse matrices out; :class:`~hht3d.geometry.surface.Surface` caches them.

Conventions
-----------
* ``L`` is the *stiffness* (weak) Laplacian: symmetric positive semidefinite,
  positive diagonal, ``L @ 1 == 0`` (the sign used by ``robust_laplacian``).
  For meshes ``L_ij = -(cot a_ij + cot b_ij)/2`` (Eq. 10 without the area
  factor).
* ``M`` is the diagonal lumped mass.  The strong Laplacian of Eq. (9)-(10)
  (with the paper's area-normalised weights) is ``M^{-1} L``.
* Gradient operators map a per-vertex scalar ``f`` (n,) to ``(G @ f)`` of
  length ``3 n``; ``(G @ f).reshape(n, 3)`` holds one tangent vector per
  vertex.
"""

from __future__ import annotations

import functools
from concurrent.futures import ThreadPoolExecutor
from typing import Callable, cast

import numpy as np
import scipy.sparse as sp

from ..errors import InputError
from .block_processes import process_count
from .blocks import CLOUD_BLOCK, MESH_BLOCK, built_by_blocks
from .normals import estimate_point_normals

__all__ = [
    "face_areas",
    "face_normals",
    "vertex_normals",
    "cotan_laplacian",
    "mixed_voronoi_mass",
    "robust_mesh_operators",
    "point_cloud_operators",
    "cloud_operators_and_normals",
    "adjacency",
    "k_ring",
    "face_gradient",
    "vertex_fem_gradient",
    "connected_components",
    "boundary_vertices",
    "corner_angles",
    "grown_regions",
]


#: Faces per block of the per-face geometry (:func:`_by_face_blocks`): its (faces, 3, 3)
#: temporaries stay near 19 MB each, whatever the mesh's size.
FACE_BLOCK = 1 << 18


def _by_face_blocks(per_face: Callable[[np.ndarray, np.ndarray], np.ndarray]) -> Callable:
    """``per_face(vertices, faces)``, whose rows are one per face, computed a block of
    :data:`FACE_BLOCK` faces at a time: its temporaries grow with the block, not the mesh, and
    its rows are those of one call (each face's row depends on that face alone)."""

    @functools.wraps(per_face)
    def blocks(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
        if len(faces) <= FACE_BLOCK:
            return per_face(vertices, faces)
        return np.concatenate([per_face(vertices, faces[i : i + FACE_BLOCK]) for i in range(0, len(faces), FACE_BLOCK)])

    return blocks


def _edges(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Edge vectors opposite each corner: e[:, k] = v[k+2] - v[k+1]."""
    v = vertices[faces]  # (f, 3 corners, 3 coords)
    return np.stack([v[:, 2] - v[:, 1], v[:, 0] - v[:, 2], v[:, 1] - v[:, 0]], axis=1)


@_by_face_blocks
def face_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Non-normalised face normals, of length twice the face area (f, 3)."""
    v = vertices[faces]
    return np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])


def face_areas(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Triangle areas (f,)."""
    return 0.5 * np.linalg.norm(face_normals(vertices, faces), axis=1)


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area-weighted unit vertex normals (n, 3); isolated vertices get (0, 0, 0)."""
    fn = face_normals(vertices, faces)
    n = np.zeros_like(vertices)
    for k in range(3):
        np.add.at(n, faces[:, k], fn)
    length = np.linalg.norm(n, axis=1, keepdims=True)
    return np.divide(n, length, out=np.zeros_like(n), where=length > 0)


@_by_face_blocks
def _corner_cotangents(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """cot of the angle at each corner (f, 3); degenerate corners give 0."""
    e = _edges(vertices, faces)
    # angle at corner k is between the edges leaving it: -e[k+2] and e[k+1]
    a = -e[:, [2, 0, 1]]
    b = e[:, [1, 2, 0]]
    dot = np.einsum("fki,fki->fk", a, b)
    cross = np.linalg.norm(np.cross(a, b), axis=2)
    return np.divide(dot, cross, out=np.zeros_like(dot), where=cross > 0)


def cotan_laplacian(vertices: np.ndarray, faces: np.ndarray) -> sp.csr_matrix:
    """Cotangent stiffness matrix, Eq. (10) with ``w_ij = (cot a + cot b)/2``.

    Returns a symmetric PSD ``(n, n)`` CSR matrix with rows summing to 0.
    """
    n = len(vertices)
    cot = _corner_cotangents(vertices, faces)
    # the corner k is opposite the edge (k+1, k+2)
    i = faces[:, [1, 2, 0]].ravel()
    j = faces[:, [2, 0, 1]].ravel()
    w = 0.5 * cot.ravel()
    off = sp.coo_matrix(
        (np.concatenate([-w, -w]), (np.concatenate([i, j]), np.concatenate([j, i]))), shape=(n, n)
    ).tocsr()
    diag = -np.asarray(off.sum(axis=1)).ravel()
    lap = (off + sp.diags(diag)).tocsr()
    lap.sum_duplicates()
    lap.sort_indices()
    return lap


def mixed_voronoi_mass(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Mixed Voronoi vertex areas of Meyer et al. (2002), the ``A_i`` of Eq. (10).

    Non-obtuse triangles give each corner its Voronoi share
    ``(|e_b|^2 cot b + |e_c|^2 cot c)/8``; an obtuse triangle gives half its
    area to the obtuse corner and a quarter to the others.  The areas sum to
    the surface area.
    """
    share = _voronoi_shares(vertices, faces)
    mass = np.zeros(len(vertices))
    for k in range(3):
        np.add.at(mass, faces[:, k], share[:, k])
    return mass


@_by_face_blocks
def _voronoi_shares(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Each corner's share (f, 3) of its face's area in :func:`mixed_voronoi_mass`."""
    e = _edges(vertices, faces)
    sq = np.einsum("fki,fki->fk", e, e)  # squared length of the edge opposite corner k
    cot = _corner_cotangents(vertices, faces)
    area = face_areas(vertices, faces)
    # Voronoi share of corner k: edges adjacent to k are opposite k+1 and k+2
    voronoi = (sq[:, [1, 2, 0]] * cot[:, [1, 2, 0]] + sq[:, [2, 0, 1]] * cot[:, [2, 0, 1]]) / 8.0
    obtuse_corner = cot < 0
    obtuse_face = cast(np.ndarray, obtuse_corner.any(axis=1))
    return np.where(obtuse_face[:, None], np.where(obtuse_corner, area[:, None] / 2, area[:, None] / 4), voronoi)


def robust_mesh_operators(
    vertices: np.ndarray, faces: np.ndarray, mollify_factor: float = 1e-5
) -> tuple[sp.csr_matrix, np.ndarray]:
    """``(L, mass_diagonal)`` from ``robust_laplacian.mesh_laplacian`` (intrinsic Delaunay); by blocks of
    :data:`~.blocks.MESH_BLOCK` vertices on larger meshes (:mod:`.blocks`)."""
    return built_by_blocks(functools.partial(_robust_mesh, mollify_factor=mollify_factor), vertices, faces, MESH_BLOCK)


def point_cloud_operators(
    points: np.ndarray, n_neighbors: int = 30, mollify_factor: float = 1e-5
) -> tuple[sp.csr_matrix, np.ndarray]:
    """``(L, mass_diagonal)`` from ``robust_laplacian.point_cloud_laplacian``; by blocks of
    :data:`~.blocks.CLOUD_BLOCK` points on larger clouds (:mod:`.blocks`)."""
    build = functools.partial(_robust_cloud, mollify_factor=mollify_factor, n_neighbors=n_neighbors)
    return built_by_blocks(build, points, None, CLOUD_BLOCK, n_neighbors)


def cloud_operators_and_normals(
    points: np.ndarray, n_neighbors: int = 30
) -> tuple[sp.csr_matrix, np.ndarray, np.ndarray | None]:
    """:func:`point_cloud_operators` and the points' normals (:func:`~.normals.estimate_point_normals`),
    estimated in a thread meanwhile when child processes build the Laplacian's blocks: this process only
    waits on them then, and the normals' single-threaded orientation fills the cores' idle time.

    The normals are ``None`` when the Laplacian is built in this process (nothing to overlap) or when they
    cannot be estimated: asked for later, they raise their error then.
    """
    if len(points) <= CLOUD_BLOCK or process_count() <= 1:
        return (*point_cloud_operators(points, n_neighbors), None)
    with ThreadPoolExecutor(1, thread_name_prefix="hht3d-normals") as pool:
        normals = pool.submit(estimate_point_normals, points)
        lap, mass = point_cloud_operators(points, n_neighbors)
        try:
            return lap, mass, normals.result()
        except InputError:  # a degenerate cloud: its normals' error waits for a request of them
            return lap, mass, None


def _robust_mesh(
    points: np.ndarray, triangles: np.ndarray | None, mollify_factor: float
) -> tuple[sp.spmatrix, np.ndarray]:
    """``robust_laplacian.mesh_laplacian`` of one (sub-)mesh: ``(L, mass_diagonal)``."""
    import robust_laplacian

    lap, mass = robust_laplacian.mesh_laplacian(
        np.ascontiguousarray(points), np.ascontiguousarray(triangles), mollify_factor
    )
    return lap, mass.diagonal()


def _robust_cloud(
    points: np.ndarray, _: np.ndarray | None, mollify_factor: float, n_neighbors: int
) -> tuple[sp.spmatrix, np.ndarray]:
    """``robust_laplacian.point_cloud_laplacian`` of one (sub-)cloud: ``(L, mass_diagonal)``."""
    import robust_laplacian

    lap, mass = robust_laplacian.point_cloud_laplacian(np.ascontiguousarray(points), mollify_factor, n_neighbors)
    return lap, mass.diagonal()


def adjacency(n: int, faces: np.ndarray | None = None, laplacian: sp.spmatrix | None = None) -> sp.csr_matrix:
    """Boolean vertex adjacency (n, n), no self loops.

    From the mesh edges when ``faces`` is given, otherwise from the
    off-diagonal pattern of ``laplacian`` (point clouds).  A fresh matrix is
    built, never a view sharing index arrays with ``laplacian``.
    """
    if faces is not None:
        i = faces[:, [0, 1, 2]].ravel()
        j = faces[:, [1, 2, 0]].ravel()
        rows, cols = np.concatenate([i, j]), np.concatenate([j, i])
    else:
        coo = sp.coo_matrix(laplacian)
        keep = (coo.row != coo.col) & (coo.data != 0)
        rows, cols = coo.row[keep].copy(), coo.col[keep].copy()
    adj = sp.coo_matrix((np.ones(len(rows), dtype=bool), (rows, cols)), shape=(n, n)).tocsr()
    adj.setdiag(False)
    adj.eliminate_zeros()
    adj.sort_indices()
    return adj


def k_ring(adj: sp.csr_matrix, k: int) -> sp.csr_matrix:
    """Vertices within ``k`` edges of each vertex (boolean, self excluded)."""
    if k < 1:
        raise ValueError(f"ring size must be >= 1, got {k}")
    step = adj.astype(np.int32)
    reach = step.copy()
    for _ in range(k - 1):
        reach = reach + reach @ step
        reach.data[:] = 1
    reach = reach.astype(bool).tocsr()
    reach.setdiag(False)
    reach.eliminate_zeros()
    reach.sort_indices()
    return reach


def face_gradient(vertices: np.ndarray, faces: np.ndarray) -> sp.csr_matrix:
    """Per-face gradient of the piecewise-linear interpolant, ``(3f, n)``.

    ``grad f|_t = sum_k f_k (n_t x e_k) / (2 A_t)`` with ``e_k`` the edge
    opposite corner ``k``.  Then ``sum_t A_t |grad u|_t|^2 = u^T L u`` for the
    cotangent ``L`` (the FEM identity behind the Riesz isometry test).
    Degenerate faces get a zero gradient.
    """
    n, f = len(vertices), len(faces)
    fn = face_normals(vertices, faces)
    dbl_area = np.linalg.norm(fn, axis=1)
    unit = np.divide(fn, dbl_area[:, None], out=np.zeros_like(fn), where=dbl_area[:, None] > 0)
    e = _edges(vertices, faces)
    coef = np.cross(unit[:, None, :], e) / np.where(dbl_area > 0, dbl_area, 1.0)[:, None, None]
    rows = 3 * np.arange(f)[:, None, None] + np.arange(3)[None, None, :]  # (f,1,3)
    rows = np.broadcast_to(rows, (f, 3, 3))
    cols = np.broadcast_to(faces[:, :, None], (f, 3, 3))
    grad = sp.coo_matrix((coef.ravel(), (rows.ravel(), cols.ravel())), shape=(3 * f, n)).tocsr()
    grad.sum_duplicates()
    return grad


def vertex_fem_gradient(vertices: np.ndarray, faces: np.ndarray) -> sp.csr_matrix:
    """Per-face gradients averaged to vertices with face-area weights, ``(3n, n)``."""
    n, f = len(vertices), len(faces)
    area = face_areas(vertices, faces)
    rows = faces.ravel()
    cols = np.repeat(np.arange(f), 3)
    w = np.repeat(area, 3)
    total = np.bincount(rows, weights=w, minlength=n)
    w = w / np.where(total[rows] > 0, total[rows], 1.0)
    avg = sp.coo_matrix((w, (rows, cols)), shape=(n, f)).tocsr()
    return (sp.kron(avg, sp.eye(3), format="csr") @ face_gradient(vertices, faces)).tocsr()


def connected_components(adj: sp.csr_matrix) -> tuple[int, np.ndarray]:
    """``(count, labels)`` of the vertex graph."""
    from scipy.sparse.csgraph import connected_components as cc

    count, labels = cc(adj, directed=False)
    return int(count), labels.astype(np.int64)


def boundary_vertices(n: int, faces: np.ndarray) -> np.ndarray:
    """Boolean mask of vertices on an edge used by exactly one face.

    Each edge is one integer, ``lo · n + hi``: ``np.unique`` of rows (``axis=0``) took 27 s on 4M vertices."""
    corners = np.asarray(faces, dtype=np.int64)
    first, second = corners.ravel(), corners[:, [1, 2, 0]].ravel()
    keys, counts = np.unique(np.minimum(first, second) * n + np.maximum(first, second), return_counts=True)
    single = keys[counts == 1]
    mask = np.zeros(n, dtype=bool)
    mask[single // n] = True
    mask[single % n] = True
    return mask


@_by_face_blocks
def corner_angles(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Interior angle at each corner (f, 3), radians; 0 at the corners of a zero-area face."""
    e = _edges(vertices, faces)
    a, b = -e[:, [2, 0, 1]], e[:, [1, 2, 0]]  # the edges leaving each corner
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=2), np.einsum("fki,fki->fk", a, b))


def grown_regions(
    adj: sp.csr_matrix, mass: np.ndarray, seeds: np.ndarray, min_area: np.ndarray, max_rings: int = 8
) -> sp.csr_matrix:
    """Vertex regions around ``seeds``, grown ring by ring until they hold ``min_area``.

    Each region starts as the closed 1-ring of its seed and gains one ring
    per step while its area (sum of ``mass``) is below ``min_area`` (a number,
    or one per seed), for at most ``max_rings`` rings.  Returns a 0/1 matrix ``(len(seeds), n)``: row
    ``k`` marks the region of ``seeds[k]``.
    """
    n = len(mass)
    step = (adj + sp.eye(n, dtype=bool, format="csr")).astype(np.float64)
    region = sp.csr_matrix((np.ones(len(seeds)), (np.arange(len(seeds)), seeds)), shape=(len(seeds), n)) @ step
    for _ in range(max_rings - 1):
        small = np.asarray(region @ mass).ravel() < min_area
        if not small.any():
            break
        region = region + sp.diags(small.astype(np.float64)) @ region @ step
        region.data[:] = 1.0
    region.data[:] = 1.0
    return region.tocsr()
