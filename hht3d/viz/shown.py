"""What a page draws of a surface: the surface itself, or a decimated copy carrying its fields."""

from __future__ import annotations

from dataclasses import dataclass
from typing import cast

import numpy as np

from ..errors import InputError
from ..geometry.surface import Surface
from .render import PERCENTILES, color_scale
from .render.colors import SYMMETRIC_CMAP

__all__ = ["Shown", "shown_copy", "color_limits", "VERTEX_BUDGET", "CLUSTER_ABOVE"]

#: Surfaces with more vertices are drawn as a decimated copy carrying the fields.
VERTEX_BUDGET = 150_000
#: Meshes with more than this many times the budget are clustered (O(n)) before the quadric
#: decimation, which alone is several times slower on millions of vertices
#: (``benchmarks/results/viewer.md``).
CLUSTER_ABOVE = 4
#: A point cloud's random subset is drawn with this seed, so a page is reproducible.
SUBSET_SEED = 0


@dataclass(frozen=True)
class Shown:
    """The geometry a page draws of one surface: the surface itself or a decimated copy.

    Attributes
    ----------
    vertices : (m, 3) ndarray
    faces : (g, 3) ndarray or None
        ``None`` for a point cloud.
    source : (m,) ndarray of int
        The original vertex whose field values each drawn vertex shows.
    n_original : int
        Vertices of the surface.
    """

    vertices: np.ndarray
    faces: np.ndarray | None
    source: np.ndarray
    n_original: int

    @property
    def decimated(self) -> bool:
        return len(self.source) < self.n_original

    def carry(self, values: np.ndarray) -> np.ndarray:
        """``values`` (n,) of the original vertices at the drawn vertices (m,)."""
        return np.asarray(values)[self.source]


def shown_copy(surface: Surface, max_vertices: int = VERTEX_BUDGET) -> Shown:
    """What a page draws of ``surface``: itself, or a copy with at most ``max_vertices`` vertices.

    A mesh is simplified by Open3D's quadric decimation (about twice as
    many triangles as vertices), after a vertex clustering to about twice
    ``max_vertices`` when it has more than :data:`CLUSTER_ABOVE` times as
    many, and each kept vertex takes its fields from the nearest original
    vertex (``scipy.spatial.cKDTree``).  A point cloud
    keeps a random subset of its points (:data:`SUBSET_SEED`), which carry their own
    values.

    Parameters
    ----------
    surface : Surface
        The surface to draw.
    max_vertices : int, optional
        The vertex budget, at least 4 (default :data:`VERTEX_BUDGET`, 150 000).

    Returns
    -------
    Shown
        The drawn geometry and, per drawn vertex, its source vertex.

    Raises
    ------
    InputError
        ``max_vertices`` below 4.

    Examples
    --------
    >>> from hht3d import data_path, load
    >>> spot = load(data_path("spot.ply"))
    >>> from hht3d.viz import shown_copy
    >>> shown = shown_copy(spot, max_vertices=1000)
    >>> len(shown.vertices) <= 1000, bool(shown.source.max() < 2930)
    (True, True)
    """
    if int(max_vertices) != max_vertices or max_vertices < 4:
        raise InputError(f"max_vertices must be an integer >= 4, got {max_vertices!r}")
    n = surface.n_vertices
    if n <= max_vertices:
        return Shown(surface.vertices, surface.faces, np.arange(n), n)
    if not surface.is_mesh:
        keep = np.sort(np.random.default_rng(SUBSET_SEED).choice(n, int(max_vertices), replace=False))
        return Shown(surface.vertices[keep], None, keep, n)
    import open3d as o3d
    from scipy.spatial import cKDTree

    mesh = o3d.geometry.TriangleMesh(
        o3d.utility.Vector3dVector(surface.vertices), o3d.utility.Vector3iVector(cast(np.ndarray, surface.faces))
    )
    if n > CLUSTER_ABOVE * max_vertices:  # a voxel per two kept vertices' worth of area
        mesh = mesh.simplify_vertex_clustering(voxel_size=float(np.sqrt(surface.face_areas.sum() / (2 * max_vertices))))
    target, small = int(len(mesh.triangles) * max_vertices / len(mesh.vertices)), mesh
    while len(small.vertices) > max_vertices and target >= 4:  # triangles set the vertex count only roughly
        small = small.simplify_quadric_decimation(target_number_of_triangles=target)
        small.remove_unreferenced_vertices()
        target = min(target - 1, int(target * max_vertices / len(small.vertices)))
    vertices = np.asarray(small.vertices)
    _, nearest = cKDTree(surface.vertices).query(vertices)
    return Shown(vertices, np.asarray(small.triangles), nearest, n)


def color_limits(values: np.ndarray, percentiles: tuple[float, float] = PERCENTILES) -> dict:
    """Colour limits of a field in both scales and the one chosen by default.

    Parameters
    ----------
    values : ndarray
        The field.
    percentiles : tuple of float, optional
        The robust range's low and high percentiles (default ``(1, 99)``).

    Returns
    -------
    dict
        ``"symmetric"``: ``[-b, b]`` with ``b = max(|p_low|, |p_high|)``;
        ``"sequential"``: ``[p_low, p_high]``; ``"auto"``: the name of the
        default (symmetric when the robust range holds both signs in earnest,
        :func:`hht3d.viz.render.color_scale`).  Degenerate ranges are widened.

    Examples
    --------
    >>> import numpy as np
    >>> from hht3d.viz import color_limits
    >>> limits = color_limits(np.linspace(0.5, 3.0, 101), percentiles=(0, 100))
    >>> limits["auto"], limits["sequential"], limits["symmetric"]
    ('sequential', [0.5, 3.0], [-3.0, 3.0])
    """
    auto = color_scale(values, percentiles=percentiles)
    symmetric = auto.cmap == SYMMETRIC_CMAP
    other = color_scale(values, percentiles=percentiles, symmetric=not symmetric)
    chosen, alternative = ("symmetric", "sequential") if symmetric else ("sequential", "symmetric")
    return {chosen: [auto.vmin, auto.vmax], alternative: [other.vmin, other.vmax], "auto": chosen}
