"""A coarsening hierarchy of a surface and the transfers between its levels (issue 39).

Level 0 is the surface itself; level ``ℓ + 1`` has about :data:`COARSENING` times fewer
vertices than level ``ℓ``.  A coarser level clusters the vertices of the finer one in a
voxel grid of side :data:`VOXEL_SPACINGS` times the finer level's spacing (``√`` of its
mean vertex area):

* a cluster's vertex is the one of its vertices nearest their area-weighted mean,
  taken among its boundary vertices if it has any (so the coarse boundary runs along the
  fine one); coarse vertices are finer vertices, with their normals;
* meshes keep the triangles whose three corners fall in three clusters (vertex
  clustering), once, and the clusters such triangles reference; the coarse mesh's
  operator is the intrinsic Delaunay Laplacian (``laplacian="robust"``).  Its cotangent
  Laplacian would not do: clustering leaves needles and caps with angles near 0 and π,
  whose weights reached 6.7e5, so ``λ_max h²`` was 6.7e6 on igea's level 1 (151 on the
  input), where the intrinsic Delaunay one gives 51 (48-65 on igea's levels 1-3, 40-76 on
  nefertiti's), and the polynomial filters' degree grows like ``√λ_max``;
* point clouds keep every cluster, with the robust point-cloud Laplacian.

Transfers (``P`` from level ``ℓ + 1`` to level ``ℓ``, ``n_ℓ × n_{ℓ+1}``, rows summing to 1):

* meshes: each finer vertex takes the barycentric weights of its closest point on the
  coarse mesh, so ``P`` reproduces functions linear on the coarse triangles (error
  ``O(h²|∇²f|)`` for a smooth ``f``);
* point clouds: inverse-square-distance weights of the :data:`CLOUD_NEIGHBOURS` nearest
  coarse points (Shepard; reproduces constants, error ``O(h |∇f|)``).

Restriction is sampling: a coarse vertex takes the value of the finer vertex it is.  It is
meant for fields that the coarse level resolves (the band-limited residues of
:mod:`hht3d.decomposition.multiresolution`), where it adds no error of its own, so a
round trip ``P R f`` errs only by ``P``'s interpolation.

Everything here is deterministic (sorted distinct rows, :mod:`.rows`; Open3D's closest points), so a
worker that rebuilds the hierarchy from the same surface gets the same levels.  The
hierarchy is built one level at a time, when asked, and kept in ``surface.cache``.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from ..errors import InputError
from ..linalg.heap import release_free_heap
from ..linalg.threads import usable_cores
from .operators import adjacency
from .rows import unique_rows
from .surface import MIN_VERTICES, Surface
from .tangent_gradient import tangent_gradient

__all__ = [
    "Level",
    "Hierarchy",
    "hierarchy",
    "release_hierarchy",
    "KEPT_VERTICES",
    "COARSENING",
    "VOXEL_SPACINGS",
    "CLOUD_NEIGHBOURS",
    "MIN_LEVEL_VERTICES",
]

#: The voxel side of a coarser level, in spacings of the finer one (3-4× fewer vertices on meshes).
VOXEL_SPACINGS = 2.0
#: About this many finer vertices per coarser one (:data:`VOXEL_SPACINGS` gave 3.4-3.7 on nefertiti,
#: 3.4-4 on igea subdivided to 1M); a level is made only from ``COARSENING * MIN_LEVEL_VERTICES`` up.
COARSENING = 4.0
#: From this many vertices :func:`release_hierarchy` drops a surface's hierarchy: at 10M vertices its
#: levels and transfers hold about 1.5 GB, which the HHT's monogenic stage would otherwise carry.
KEPT_VERTICES = 1_000_000
#: Coarse points a point-cloud vertex interpolates from.
CLOUD_NEIGHBOURS = 3
#: No level is made with fewer vertices than this (its Laplacian would not resolve an oscillation).
MIN_LEVEL_VERTICES = 500


@dataclass(frozen=True)
class Level:
    """One level: its surface, its spacing and its transfers to and from the next finer level.

    Attributes
    ----------
    surface : Surface
        The level's vertices, triangles (meshes) and operators.
    spacing : float
        ``√(area / n)``: the side of a vertex's mean area.
    prolongation : (n_finer, n) csr_matrix or None
        ``P``, rows summing to 1; ``None`` on level 0.
    samples : (n,) ndarray of int or None
        The finer vertex each vertex is (:meth:`restrict`); ``None`` on level 0.
    """

    surface: Surface
    spacing: float
    prolongation: sp.csr_matrix | None = None
    samples: np.ndarray | None = None

    def gradient(self, kind: str) -> sp.csr_matrix:
        """The level's tangent gradient ``(3n, n)`` (:meth:`Surface.gradient`).  On a coarse mesh the least
        squares of ``kind="lsq"`` run over the neighbours of its intrinsic Delaunay Laplacian, not its faces'
        1-rings, which hold the needles and caps: of a potential ``u = L^{-1/2} f``, for which
        ``‖∇u‖ = ‖f‖``, the faces' 1-rings gave ``‖∇u‖ = 1.54 ‖f‖`` on igea's level 1, the Laplacian's 0.995."""
        coarse = self.surface
        if kind != "lsq" or self.samples is None or not coarse.is_mesh:
            return coarse.gradient(kind)
        if "gradient:lsq:laplacian" not in coarse.cache:
            neighbours = adjacency(coarse.n_vertices, laplacian=coarse.stiffness)
            coarse.cache["gradient:lsq:laplacian"] = tangent_gradient(coarse.vertices, coarse.normals, neighbours)
        return coarse.cache["gradient:lsq:laplacian"]

    def prolong(self, values: np.ndarray) -> np.ndarray:
        """``P v``: values (``(n,)`` or ``(k, n)``) on the next finer level."""
        return np.asarray((self._p @ np.atleast_2d(values).T).T).reshape(*np.shape(values)[:-1], -1)

    def restrict(self, values: np.ndarray) -> np.ndarray:
        """Finer values (``(n_finer,)`` or ``(k, n_finer)``) sampled at this level's vertices."""
        if self.samples is None:
            raise InputError("level 0 has no finer level")
        return np.asarray(values)[..., self.samples]

    @property
    def _p(self) -> sp.csr_matrix:
        if self.prolongation is None:
            raise InputError("level 0 has no finer level")
        return self.prolongation


class Hierarchy:
    """The levels of one surface, built when first asked for (thread-safe)."""

    def __init__(self, surface: Surface) -> None:
        self.levels = [Level(surface, _spacing(surface))]
        self._lock = threading.Lock()

    def level(self, index: int) -> Level | None:
        """Level ``index``, built with those before it; ``None`` when it would be too small."""
        with self._lock:
            while len(self.levels) <= index:
                finer = self.levels[-1]
                if finer.surface.n_vertices < COARSENING * MIN_LEVEL_VERTICES:
                    return None
                self.levels.append(_coarser(finer, len(self.levels)))
            return self.levels[index]

    def coarsest_resolving(self, frequency: float, spacing_limit: float, start: int = 0) -> int:
        """The coarsest level from ``start`` on whose ``spacing · frequency ≤ spacing_limit``
        (``start`` itself when no coarser level qualifies)."""
        index = start
        while (level := self.level(index + 1)) is not None and level.spacing * frequency <= spacing_limit:
            index += 1
        return index

    def to_finest(self, values: np.ndarray, index: int) -> np.ndarray:
        """Values on level ``index`` prolonged to level 0."""
        return self.prolong(values, index, 0)

    def prolong(self, values: np.ndarray, source: int, target: int) -> np.ndarray:
        """Values on level ``source`` prolonged to the finer level ``target``."""
        for level in reversed(self.levels[target + 1 : source + 1]):
            values = level.prolong(values)
        return values

    def restrict(self, values: np.ndarray, source: int, target: int) -> np.ndarray:
        """Values on level ``source`` restricted to the coarser level ``target``."""
        for index in range(source + 1, target + 1):
            values = self.levels[index].restrict(values)
        return values


def hierarchy(surface: Surface) -> Hierarchy:
    """The :class:`Hierarchy` of ``surface``, kept in its cache (not pickled: workers rebuild it)."""
    return surface.cache.setdefault("hierarchy", Hierarchy(surface))


def release_hierarchy(surface: Surface) -> None:
    """Drop the cached hierarchy of a surface of :data:`KEPT_VERTICES` vertices or more, once no later
    stage needs it (the next :func:`hierarchy` rebuilds it, identically), and hand the memory its smaller
    arrays held back to the operating system (:func:`~hht3d.linalg.heap.release_free_heap`)."""
    if surface.n_vertices >= KEPT_VERTICES and surface.cache.pop("hierarchy", None) is not None:
        release_free_heap()


def _spacing(surface: Surface) -> float:
    return float(np.sqrt(surface.mass_diagonal.sum() / surface.n_vertices))


def _coarser(finer: Level, index: int) -> Level:
    """The next level of ``finer`` (module notes)."""
    fine = finer.surface
    key = np.floor((fine.vertices - fine.vertices.min(axis=0)) / (VOXEL_SPACINGS * finer.spacing)).astype(np.int64)
    cluster = unique_rows(key)[2]
    samples = _representatives(fine, cluster)
    name = f"{fine.name} level {index}"
    if fine.is_mesh:
        samples, faces = _cluster_triangles(fine.vertices, cluster[fine.faces], samples)
        if len(samples) < MIN_VERTICES:
            raise InputError(f"{name}: vertex clustering left {len(samples)} vertices")
        coarse = Surface(fine.vertices[samples], faces, normals=fine.normals[samples], laplacian="robust", name=name)
        prolongation = _barycentric(fine.vertices, coarse)
    else:
        coarse = Surface(fine.vertices[samples], normals=fine.normals[samples], n_neighbors=fine.n_neighbors, name=name)
        prolongation = _shepard(fine.vertices, coarse.vertices)
    return Level(coarse, _spacing(coarse), prolongation, samples)


def _representatives(fine: Surface, cluster: np.ndarray) -> np.ndarray:
    """Per cluster, in cluster order, the vertex nearest the cluster's area-weighted mean (a boundary
    vertex if the cluster has one)."""
    mass, count = fine.mass_diagonal, int(cluster.max()) + 1
    area = np.bincount(cluster, weights=mass, minlength=count)
    mean = np.column_stack([np.bincount(cluster, weights=mass * x, minlength=count) for x in fine.vertices.T])
    distance = np.linalg.norm(fine.vertices - mean[cluster] / area[cluster, None], axis=1)
    if fine.is_mesh:
        boundary = fine.boundary_vertices
        has_boundary = np.bincount(cluster, weights=boundary, minlength=count) > 0
        distance = distance + np.where(has_boundary[cluster] & ~boundary, np.inf, 0.0)
    order = np.lexsort((distance, cluster))
    first = np.ones(len(order), dtype=bool)
    first[1:] = cluster[order][1:] != cluster[order][:-1]
    return order[first]


def _cluster_triangles(points: np.ndarray, corners: np.ndarray, samples: np.ndarray) -> tuple:
    """The triangles of three distinct clusters (``corners``: cluster numbers), each once and with area;
    the sampled vertices they reference, and the triangles renumbered to them."""
    distinct = (corners[:, 0] != corners[:, 1]) & (corners[:, 1] != corners[:, 2]) & (corners[:, 0] != corners[:, 2])
    corners = corners[distinct]
    first = unique_rows(np.sort(corners, axis=1))[1]
    corners = corners[np.sort(first)]
    p = points[samples[corners]]
    doubled = np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    corners = corners[doubled > 1e-12 * np.median(doubled)]
    used, faces = np.unique(corners, return_inverse=True)
    return samples[used], faces.reshape(-1, 3)


def _barycentric(points: np.ndarray, coarse: Surface) -> sp.csr_matrix:
    """Rows of barycentric weights of each point's closest point on the coarse mesh."""
    import open3d as o3d

    faces = np.asarray(coarse.faces)
    centre = coarse.vertices.mean(axis=0)  # Open3D's scene is float32: keep the coordinates small
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(
        o3d.core.Tensor.from_numpy(np.ascontiguousarray(coarse.vertices - centre, dtype=np.float32)),
        o3d.core.Tensor.from_numpy(np.ascontiguousarray(faces, dtype=np.uint32)),
    )
    closest = scene.compute_closest_points(
        o3d.core.Tensor.from_numpy(np.ascontiguousarray(points - centre, dtype=np.float32))
    )
    triangle = closest["primitive_ids"].numpy().astype(np.int64)
    uv = closest["primitive_uvs"].numpy().astype(np.float64)
    uv = np.clip(uv, 0.0, 1.0)
    uv /= np.maximum(1.0, uv.sum(axis=1))[:, None]
    return _rows(np.column_stack([1.0 - uv.sum(axis=1), uv]), faces[triangle], coarse.n_vertices)


def _shepard(points: np.ndarray, coarse: np.ndarray) -> sp.csr_matrix:
    """Rows of inverse-square-distance weights of the :data:`CLOUD_NEIGHBOURS` nearest coarse points."""
    k = min(CLOUD_NEIGHBOURS, len(coarse))
    distance, index = cKDTree(coarse).query(points, k=k, workers=usable_cores())
    distance, index = distance.reshape(len(points), k), index.reshape(len(points), k)
    weights = 1.0 / np.maximum(distance, 1e-9 * max(float(distance.max()), 1e-300)) ** 2
    return _rows(weights / weights.sum(axis=1, keepdims=True), index, len(coarse))


def _rows(weights: np.ndarray, columns: np.ndarray, n_columns: int) -> sp.csr_matrix:
    """The sparse matrix whose row ``i`` holds ``weights[i]`` at ``columns[i]`` (same width per row)."""
    n, k = weights.shape
    return sp.csr_matrix((weights.ravel(), columns.ravel(), np.arange(0, k * n + 1, k)), shape=(n, n_columns))
