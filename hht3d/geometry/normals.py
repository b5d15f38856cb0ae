"""Normals and principal axes of point clouds (meshes get their normals from
:func:`hht3d.geometry.operators.vertex_normals`)."""

from __future__ import annotations

import numpy as np

from ..errors import InputError, one_line
from ..open3d_quiet import quiet_open3d

__all__ = ["FLAT", "principal_axes", "estimate_point_normals"]

#: A point cloud thinner than this fraction of its extent is treated as planar.
FLAT = 1e-9


def estimate_point_normals(points: np.ndarray, k: int = 30) -> np.ndarray:
    """Unit normals of a point cloud: PCA over ``k`` neighbours, consistently oriented.

    Open3D orients them along a minimum spanning tree over tangent planes;
    the whole set is then flipped, if needed, to point away from the centroid
    on average (outward for closed scans).  A planar cloud (thinner than
    :data:`FLAT` times its extent, where Open3D's
    Delaunay step fails) gets the plane's normal everywhere, its largest
    component positive.

    Parameters
    ----------
    points : (n, 3) ndarray
        The point positions.
    k : int, optional
        Neighbours of the PCA and of the orientation (default 30).

    Returns
    -------
    (n, 3) ndarray
        The unit normals.

    Raises
    ------
    InputError
        The points lie on a line, or Open3D cannot orient the normals.

    Examples
    --------
    >>> import numpy as np
    >>> from hht3d.geometry import estimate_point_normals
    >>> points = np.random.default_rng(0).normal(size=(400, 3))
    >>> points /= np.linalg.norm(points, axis=1, keepdims=True)  # on the unit sphere
    >>> normals = estimate_point_normals(points, k=15)
    >>> bool(np.einsum("ij,ij->i", normals, points).min() > 0.98)  # outward on the unit sphere
    True
    """
    points = np.asarray(points, dtype=np.float64)
    centered = points - points.mean(axis=0)
    spread, axes = principal_axes(centered)
    if spread[2] <= FLAT * spread[0]:
        normal = axes[2] * np.sign(axes[2][np.argmax(np.abs(axes[2]))])
        return np.tile(normal, (len(points), 1))
    with quiet_open3d() as o3d:
        try:
            pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
            pcd.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(knn=k))
            pcd.orient_normals_consistent_tangent_plane(k)
        except RuntimeError as exc:
            reason = one_line(str(exc).split("\n", 1)[0])
            raise InputError(
                f"cannot orient the point normals ({reason}); the cloud may be degenerate: "
                "check it with `hht3d info`, or store normals (nx, ny, nz) in the file"
            ) from None
        normals = np.asarray(pcd.normals, dtype=np.float64)
    if np.einsum("ij,ij->", normals, centered) < 0:
        normals = -normals
    return normals


def principal_axes(centered: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Singular values (descending) and principal axes of centred points; collinear points are an error.

    Parameters
    ----------
    centered : (n, 3) ndarray
        Points with their mean subtracted.

    Returns
    -------
    spread : (3,) ndarray
        The singular values, descending.
    axes : (3, 3) ndarray
        The principal axes, one per row, in the same order.

    Examples
    --------
    >>> import numpy as np
    >>> from hht3d.geometry import principal_axes
    >>> points = np.random.default_rng(0).normal(size=(500, 3)) * [3.0, 1.0, 0.1]
    >>> spread, axes = principal_axes(points - points.mean(axis=0))
    >>> int(np.abs(axes[0]).argmax()), int(np.abs(axes[2]).argmax())  # longest along x, thinnest along z
    (0, 2)
    """
    _, spread, axes = np.linalg.svd(centered, full_matrices=False)
    if spread[1] <= FLAT * spread[0]:
        raise InputError(f"the {len(centered)} points lie on a line; a surface needs points spread in two directions")
    return spread, axes
