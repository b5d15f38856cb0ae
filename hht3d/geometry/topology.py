"""Topological facts about a surface, for ``hht3d info`` and input checks."""

from __future__ import annotations

from typing import cast

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from .rows import unique_rows
from .surface import Surface

__all__ = ["edge_face_counts", "boundary_loops", "describe"]


def edge_face_counts(faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unique undirected edges ``(e, 2)`` and how many faces use each."""
    e = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    unique, _, _, counts = unique_rows(e)
    return unique, counts


def boundary_loops(n: int, edges: np.ndarray, counts: np.ndarray) -> int:
    """Connected chains of boundary edges (edges of one face) among the ``edges`` of :func:`edge_face_counts`
    of a mesh of ``n`` vertices: 0 for a closed mesh, 1 for a disc, 2 for an open cylinder."""
    boundary = edges[counts == 1]
    if not len(boundary):
        return 0
    graph = sp.coo_matrix((np.ones(len(boundary)), (boundary[:, 0], boundary[:, 1])), shape=(n, n))
    labels = connected_components(graph, directed=False)[1]
    return len(np.unique(labels[np.unique(boundary)]))


def _non_manifold_vertices(surface: Surface) -> int:
    """Vertices whose incident faces do not form one fan (Open3D's test)."""
    import open3d as o3d

    mesh = o3d.geometry.TriangleMesh(
        o3d.utility.Vector3dVector(surface.vertices), o3d.utility.Vector3iVector(cast(np.ndarray, surface.faces))
    )
    return len(mesh.get_non_manifold_vertices())


def describe(surface: Surface) -> dict:
    """Vertices, faces, components, boundary, manifoldness, Euler characteristic, bounding box (in the
    file's frame: ``vertices + origin``), the stored attributes and, with a ``classification``
    attribute (LAS), the number of points of each class."""
    lo, hi = surface.vertices.min(axis=0), surface.vertices.max(axis=0)
    info: dict = {
        "name": surface.name,
        "kind": "mesh" if surface.is_mesh else "point cloud",
        "vertices": surface.n_vertices,
        "components": surface.n_components,
        "bounding_box_min": (lo + surface.origin).tolist(),
        "bounding_box_max": (hi + surface.origin).tolist(),
        "bounding_box_diagonal": float(np.linalg.norm(hi - lo)),
        "attributes": sorted(surface.attributes),
    }
    if "classification" in surface.attributes:
        codes, counts = np.unique(surface.attributes["classification"], return_counts=True)
        info["classes"] = {str(int(c)): int(k) for c, k in zip(codes, counts)}
    if surface.clean_report is not None:
        info["cleaning"] = surface.clean_report.summary()
    if not surface.is_mesh:
        return info
    edges, counts = edge_face_counts(cast(np.ndarray, surface.faces))
    n = surface.n_vertices
    info.update(
        {
            "faces": len(cast(np.ndarray, surface.faces)),
            "edges": len(edges),
            "euler_characteristic": n - len(edges) + len(cast(np.ndarray, surface.faces)),
            "boundary_loops": boundary_loops(n, edges, counts),
            "boundary_vertices": int(surface.boundary_vertices.sum()),
            "non_manifold_edges": int(np.sum(counts > 2)),
            "non_manifold_vertices": _non_manifold_vertices(surface),
            "closed": bool(np.all(counts != 1)),
            "surface_area": float(surface.face_areas.sum()),
        }
    )
    return info
