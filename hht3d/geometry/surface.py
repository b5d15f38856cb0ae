"""The :class:`Surface` value: a triangle mesh or a point cloud with operators.

A ``Surface`` holds vertex positions, faces (``None`` for a point cloud),
per-vertex colours and stored scalars, and computes its discrete operators
lazily (:mod:`hht3d.geometry.operators`), caching them in :attr:`Surface.cache`.  The
cache is dropped on pickling, so a surface is cheap to send to another
process, which rebuilds what it needs.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, cast

import numpy as np
import scipy.sparse as sp

from ..errors import InputError
from ..records import Record, option
from . import operators as ops
from .cleaning import CleanReport, clean_mesh, clean_points
from .normals import estimate_point_normals, principal_axes
from .tangent_gradient import tangent_gradient

__all__ = ["Surface", "SurfaceOptions", "MIN_VERTICES", "LAPLACIANS", "MAX_NEIGHBORS"]

#: The fewest vertices a surface may have (a tetrahedron).
MIN_VERTICES = 4
#: Mesh Laplacians; point clouds always use ``robust_laplacian.point_cloud_laplacian``.
LAPLACIANS = ("cotan", "robust")
#: Neighbours of the point-cloud Laplacian and normals (far above useful values; stops a typo).
MAX_NEIGHBORS = 256
#: Surfaces of this many vertices or more build a vertex gradient operator at each call (an lsq one
#: takes about 250 bytes a vertex, 2.5 GB at 10M vertices) rather than keep it for the rest of the run.
CACHED_GRADIENT_VERTICES = 1_000_000


@dataclass(frozen=True)
class SurfaceOptions(Record):
    """The operator settings of a :class:`Surface` (and of :func:`hht3d.io.load`)."""

    label = "surface"

    laplacian: str = option("cotan", "mesh Laplacian (point clouds always use the robust one)", choices=LAPLACIANS)
    n_neighbors: int = option(
        30, "neighbours of the point-cloud Laplacian and normals", minimum=3, maximum=MAX_NEIGHBORS
    )


@dataclass(frozen=True)
class _Operators:
    stiffness: sp.csr_matrix
    mass_diagonal: np.ndarray


class Surface:
    """A triangle mesh or point cloud carrying the operators HHT needs.

    Parameters
    ----------
    vertices : (n, 3) array_like
        Positions; must be finite, ``n >= 4``.
    faces : (f, 3) array_like of int, optional
        Triangles; ``None`` or empty for a point cloud.
    normals : (n, 3) array_like, optional
        Unit vertex normals.  Default: area-weighted face normals (meshes) or
        normals estimated by Open3D and consistently oriented
        (:func:`~hht3d.geometry.normals.estimate_point_normals`; point clouds).
    colors : (n, 3) array_like, optional
        RGB in [0, 1].
    attributes : dict of str to (n,) arrays, optional
        Per-vertex scalars (e.g. read from a PLY file).
    laplacian : {"cotan", "robust"}
        Mesh Laplacian: cotangent weights with mixed Voronoi areas (Eq. 10,
        Meyer et al. 2002) or ``robust_laplacian.mesh_laplacian``.
    n_neighbors : int
        Neighbours of the point-cloud Laplacian.
    name : str, optional
        Shown in messages and used for output names.
    clean_report : CleanReport, optional
        Set by the loaders when cleaning changed the input.
    origin : (3,) array_like, optional
        Where the local frame of ``vertices`` lies in the file's frame: the file's coordinates are
        ``vertices + origin`` (a LAS scan 10⁶ m from its datum is read near 0; writers add it back).
    header : object, optional
        What a reader kept to write the file's format back (a LAS file's ``laspy`` header).
    """

    def __init__(
        self,
        vertices: np.ndarray,
        faces: np.ndarray | None = None,
        *,
        normals: np.ndarray | None = None,
        colors: np.ndarray | None = None,
        attributes: dict | None = None,
        laplacian: str = "cotan",
        n_neighbors: int = 30,
        name: str | None = None,
        clean_report: CleanReport | None = None,
        origin: np.ndarray | None = None,
        header: Any = None,
    ) -> None:
        self.name = name or "surface"
        self.vertices = _as_vertices(vertices, self.name)
        n = len(self.vertices)
        self.faces = _as_faces(faces, n, self.name)
        try:
            SurfaceOptions(laplacian, n_neighbors)
        except InputError as exc:
            raise InputError(f"{self.name}: {exc}") from None
        if self.faces is None:
            _check_cloud(self.vertices, int(n_neighbors), self.name)
        self.laplacian = laplacian
        self.n_neighbors = int(n_neighbors)
        self.colors = None if colors is None else _as_per_vertex(colors, n, 3, "colors", self.name)
        self.attributes = {
            str(k): _as_per_vertex(v, n, None, f"attribute {k!r}", self.name) for k, v in (attributes or {}).items()
        }
        self.clean_report = clean_report
        self.origin = np.zeros(3) if origin is None else _as_per_vertex(origin, 3, None, "origin", self.name)
        self.header = header
        self.cache: dict = {}
        if normals is not None:
            normals = _as_per_vertex(normals, n, 3, "normals", self.name)
            length = np.linalg.norm(normals, axis=1, keepdims=True)
            self.cache["normals"] = np.divide(normals, length, out=np.zeros_like(normals), where=length > 0)

    # -- construction -----------------------------------------------------------------
    @classmethod
    def cleaned(
        cls,
        vertices: np.ndarray,
        faces: np.ndarray | None = None,
        *,
        colors: np.ndarray | None = None,
        attributes: dict | None = None,
        **options: Any,
    ) -> "Surface":
        """Clean the arrays (see :mod:`hht3d.geometry.cleaning`) and build a surface.

        Per-vertex colours and attributes follow the kept vertices; the
        :class:`~hht3d.geometry.cleaning.CleanReport` is in ``surface.clean_report``.
        """
        name = options.get("name") or "surface"
        vertices = _as_vertices(vertices, name)
        faces = _as_faces(faces, len(vertices), name)
        if faces is None:
            vertices, report = clean_points(vertices)
        else:
            vertices, faces, report = clean_mesh(vertices, faces)
        kept = report.kept_vertices
        if colors is not None:
            colors = np.asarray(colors, dtype=np.float64)[kept]
        if attributes:
            attributes = {k: np.asarray(v, dtype=np.float64)[kept] for k, v in attributes.items()}
        normals = options.pop("normals", None)
        if normals is not None:
            normals = np.asarray(normals, dtype=np.float64)[kept]
        return cls(
            vertices, faces, colors=colors, attributes=attributes, normals=normals, clean_report=report, **options
        )

    # -- pickling: operators and factorizations are rebuilt where needed ----------------
    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        normals = self.cache.get("normals")
        state["cache"] = {} if normals is None else {"normals": normals}
        return state

    def __repr__(self) -> str:
        kind = f"mesh, {len(self._triangles)} faces" if self.is_mesh else "point cloud"
        return f"Surface({self.name!r}: {self.n_vertices} vertices, {kind})"

    def _repr_html_(self) -> str:
        """The summary table a notebook shows (:func:`hht3d.viz.notebook.surface_html`)."""
        from ..viz.notebook import surface_html

        return surface_html(self)

    def show(self, field: str | np.ndarray | None = None, **options: Any) -> Any:
        """The viewer inline in a notebook, showing ``field`` (an attribute's name or per-vertex values)
        first (:func:`hht3d.viz.notebook.surface_view`: ``height``, ``max_vertices``, ...)."""
        from ..viz.notebook import surface_view

        return surface_view(self, field, **options)

    # -- basic properties -------------------------------------------------------------
    @property
    def is_mesh(self) -> bool:
        return self.faces is not None

    @property
    def _triangles(self) -> np.ndarray:
        """:attr:`faces` where :attr:`is_mesh` was checked (for the type checker)."""
        return cast(np.ndarray, self.faces)

    @property
    def n_vertices(self) -> int:
        return len(self.vertices)

    def _cached(self, key: str, build: Callable[[], Any]) -> Any:
        if key not in self.cache:
            self.cache[key] = build()
        return self.cache[key]

    @property
    def bounding_box_diagonal(self) -> float:
        return float(np.linalg.norm(self.vertices.max(axis=0) - self.vertices.min(axis=0)))

    @property
    def normals(self) -> np.ndarray:
        """Unit vertex normals (n, 3)."""
        return self._cached("normals", self._build_normals)

    def _build_normals(self) -> np.ndarray:
        if self.is_mesh:
            return ops.vertex_normals(self.vertices, self._triangles)
        return estimate_point_normals(self.vertices)

    @property
    def face_areas(self) -> np.ndarray:
        self._require_mesh("face areas")
        return self._cached("face_areas", lambda: ops.face_areas(self.vertices, self._triangles))

    # -- operators --------------------------------------------------------------------
    def _operators(self) -> _Operators:
        def build() -> _Operators:
            if not self.is_mesh and "normals" in self.cache:
                lap, mass = ops.point_cloud_operators(self.vertices, self.n_neighbors)
            elif not self.is_mesh:  # large clouds estimate their normals meanwhile
                lap, mass, normals = ops.cloud_operators_and_normals(self.vertices, self.n_neighbors)
                if normals is not None:
                    self.cache["normals"] = normals
            elif self.laplacian == "robust":
                lap, mass = ops.robust_mesh_operators(self.vertices, self._triangles)
            else:
                lap = ops.cotan_laplacian(self.vertices, self._triangles)
                mass = ops.mixed_voronoi_mass(self.vertices, self._triangles)
            if not np.all(mass > 0):
                hint = (
                    "load with clean=True to remove unreferenced vertices"
                    if self.clean_report is None
                    else "they are isolated or on zero-area faces only"
                )
                raise InputError(f"{self.name}: {int(np.sum(mass <= 0))} vertices have zero area; {hint}")
            return _Operators(sp.csr_matrix(lap, dtype=np.float64), mass)

        return self._cached("operators", build)

    @property
    def stiffness(self) -> sp.csr_matrix:
        """Stiffness Laplacian ``L`` (n, n): symmetric PSD, ``L @ 1 = 0``."""
        return self._operators().stiffness

    @property
    def mass_diagonal(self) -> np.ndarray:
        """Lumped vertex areas (n,), all positive; they sum to the surface area."""
        return self._operators().mass_diagonal

    @property
    def mass(self) -> sp.csr_matrix:
        """Diagonal lumped mass matrix ``M`` (n, n)."""
        return self._cached("mass", lambda: sp.diags(self.mass_diagonal, format="csr"))

    @property
    def adjacency(self) -> sp.csr_matrix:
        """Boolean 1-ring adjacency (mesh edges; for point clouds, the Laplacian's graph)."""
        return self._cached(
            "adjacency", lambda: ops.adjacency(self.n_vertices, self.faces, None if self.is_mesh else self.stiffness)
        )

    def ring(self, k: int = 1) -> sp.csr_matrix:
        """Boolean ``(n, n)`` matrix of the vertices within ``k`` edges, self excluded."""
        if int(k) != k or k < 1:
            raise InputError(f"ring size must be a positive integer, got {k!r}")
        k = int(k)
        return self.adjacency if k == 1 else self._cached(f"ring:{k}", lambda: ops.k_ring(self.adjacency, k))

    def _components(self) -> Any:
        return self._cached("components", lambda: ops.connected_components(self.adjacency))

    @property
    def n_components(self) -> int:
        return self._components()[0]

    @property
    def component_labels(self) -> np.ndarray:
        """Connected component of each vertex, 0 to ``n_components - 1``."""
        return self._components()[1]

    @property
    def boundary_vertices(self) -> np.ndarray:
        """Mask of boundary vertices (always all-False for point clouds)."""
        if not self.is_mesh:
            return np.zeros(self.n_vertices, dtype=bool)
        return self._cached("boundary", lambda: ops.boundary_vertices(self.n_vertices, self._triangles))

    def gradient(self, kind: str = "lsq") -> sp.csr_matrix:
        """Per-vertex tangent gradient operator ``(3n, n)``.

        ``kind="lsq"``: tangent-plane least squares of Eq. (17) over the
        1-ring (meshes and point clouds).  ``kind="fem"``: per-face gradients
        averaged to vertices with area weights (meshes only).  Kept in the cache below
        :data:`CACHED_GRADIENT_VERTICES` vertices, built at each call from there on.
        """
        if kind not in ("lsq", "fem"):
            raise InputError(f"unknown gradient kind {kind!r}; choose 'lsq' or 'fem'")
        if kind == "fem":
            self._require_mesh("the FEM gradient")

        def build() -> sp.csr_matrix:
            if kind == "lsq":
                return tangent_gradient(self.vertices, self.normals, self.adjacency)
            return ops.vertex_fem_gradient(self.vertices, self._triangles)

        return build() if self.n_vertices >= CACHED_GRADIENT_VERTICES else self._cached(f"gradient:{kind}", build)

    def face_gradient(self) -> sp.csr_matrix:
        """Per-face P1 gradient operator ``(3f, n)`` (meshes only)."""
        self._require_mesh("the per-face gradient")
        return self._cached("gradient:face", lambda: ops.face_gradient(self.vertices, self._triangles))

    def _require_mesh(self, what: str) -> None:
        if not self.is_mesh:
            raise InputError(f"{self.name}: {what} needs a triangle mesh, this is a point cloud")


def _check_cloud(points: np.ndarray, n_neighbors: int, name: str) -> None:
    """What the point-cloud Laplacian needs: more points than neighbours, not all on a line."""
    if len(points) <= n_neighbors:
        raise InputError(
            f"{name}: a point cloud of {len(points)} points cannot give each point "
            f"n_neighbors={n_neighbors} neighbours; lower n_neighbors below {len(points)}"
        )
    try:
        principal_axes(points - points.mean(axis=0))
    except InputError as exc:
        raise InputError(f"{name}: {exc}") from None


#: The largest coordinate a surface may have: areas, their squares (cleaning) and products stay inside float64.
MAX_COORDINATE = 1e75


def _as_vertices(vertices: np.ndarray, name: str) -> np.ndarray:
    try:
        v = np.array(vertices, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name}: vertices are not numeric: {exc}") from None
    if v.ndim != 2 or v.shape[1] != 3:
        raise InputError(f"{name}: vertices must have shape (n, 3), got {v.shape}")
    if len(v) < MIN_VERTICES:
        raise InputError(f"{name}: {len(v)} vertices; a surface needs at least {MIN_VERTICES}")
    bad = ~np.isfinite(v).all(axis=1)
    if bad.any():
        raise InputError(
            f"{name}: {int(bad.sum())} vertices have NaN or infinite coordinates "
            f"(first: vertex {int(np.flatnonzero(bad)[0])}); remove or repair them"
        )
    largest = np.abs(v).max()
    if largest > MAX_COORDINATE:
        raise InputError(
            f"{name}: coordinates reach {largest:.3g}; beyond {MAX_COORDINATE:.0e} areas and curvatures "
            "overflow float64: scale the surface down"
        )
    return v


def _as_faces(faces: np.ndarray | None, n: int, name: str) -> np.ndarray | None:
    if faces is None:
        return None
    f = np.asarray(faces)
    if f.size == 0:
        return None
    if f.ndim != 2 or f.shape[1] != 3:
        raise InputError(f"{name}: faces must be triangles of shape (f, 3), got {f.shape}")
    if not np.issubdtype(f.dtype, np.integer):
        if not np.all(np.mod(f, 1) == 0):
            raise InputError(f"{name}: face indices must be integers")
    f = f.astype(np.int64)
    if f.min() < 0 or f.max() >= n:
        raise InputError(f"{name}: face indices must lie in [0, {n}), got [{f.min()}, {f.max()}]")
    return f


def _as_per_vertex(values: np.ndarray, n: int, width: int | None, what: str, name: str) -> np.ndarray:
    a = np.asarray(values, dtype=np.float64)
    expected = (n,) if width is None else (n, width)
    if a.shape != expected:
        raise InputError(f"{name}: {what} must have shape {expected}, got {a.shape}")
    return a
