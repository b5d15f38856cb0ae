"""Conversion between :class:`~hht3d.geometry.surface.Surface` and Open3D geometries (legacy and tensor)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import InputError
from ..geometry.surface import Surface
from .formats import checked_name
from .write import per_vertex

__all__ = ["surface_from_open3d", "surface_to_open3d"]


def surface_from_open3d(geometry: Any, *, clean: bool = True, name: str | None = None, **options: Any) -> Surface:
    """Build a surface from an Open3D legacy or tensor ``TriangleMesh`` / ``PointCloud``.

    Colours and (tensor geometries) every other float vertex attribute are
    carried over; point-cloud normals are kept when present.

    Parameters
    ----------
    geometry : open3d geometry
        A legacy or tensor ``TriangleMesh`` or ``PointCloud``.
    clean : bool, optional
        Build with :meth:`Surface.cleaned` (default ``True``), else :class:`Surface` as given.
    name : str, optional
        The surface's name.
    **options
        Further keyword arguments of :class:`Surface` (e.g. ``laplacian``).

    Returns
    -------
    Surface
        The surface.

    Examples
    --------
    >>> import open3d as o3d
    >>> from hht3d.io import surface_from_open3d
    >>> ball = surface_from_open3d(o3d.geometry.TriangleMesh.create_sphere(radius=1.0, resolution=8))
    >>> ball.n_vertices, ball.is_mesh
    (114, True)
    """
    import open3d as o3d

    if isinstance(geometry, o3d.geometry.TriangleMesh):
        data: dict[str, Any] = {"vertices": np.asarray(geometry.vertices), "faces": np.asarray(geometry.triangles)}
        if geometry.has_vertex_colors():
            data["colors"] = np.asarray(geometry.vertex_colors)
    elif isinstance(geometry, o3d.geometry.PointCloud):
        data = {"vertices": np.asarray(geometry.points), "faces": None}
        if geometry.has_normals():
            data["normals"] = np.asarray(geometry.normals)
        if geometry.has_colors():
            data["colors"] = np.asarray(geometry.colors)
    elif isinstance(geometry, (o3d.t.geometry.TriangleMesh, o3d.t.geometry.PointCloud)):
        is_mesh = isinstance(geometry, o3d.t.geometry.TriangleMesh)
        tensors: Any = geometry  # the stubs' union has no common attributes
        attrs = tensors.vertex if is_mesh else tensors.point
        data = {
            "vertices": attrs["positions"].numpy(),
            "faces": tensors.triangle["indices"].numpy() if is_mesh and "indices" in tensors.triangle else None,
        }
        n = len(data["vertices"])
        for key in list(attrs):
            values = attrs[key].numpy()
            if key == "colors":
                data["colors"] = values.astype(np.float64) / (255.0 if values.dtype.kind in "iu" else 1.0)
            elif key == "normals" and not is_mesh:
                data["normals"] = values
            elif key not in ("positions", "normals") and values.size == n:
                data.setdefault("attributes", {})[key] = values.reshape(n).astype(np.float64)
    else:
        raise InputError(f"expected an Open3D TriangleMesh or PointCloud, got {type(geometry).__name__}")
    if len(data["vertices"]) == 0:
        raise InputError(f"{name or 'open3d geometry'}: the geometry is empty")
    build = Surface.cleaned if clean else Surface
    return build(**data, name=name, **options)


def surface_to_open3d(surface: Surface, attributes: dict | None = None) -> Any:
    """Tensor ``TriangleMesh``/``PointCloud`` carrying the surface's attributes and ``attributes``
    as (n, 1) float vertex attributes.

    Parameters
    ----------
    surface : Surface
        The surface to convert.
    attributes : dict, optional
        More per-vertex fields, by name (they override stored ones of the same name).

    Returns
    -------
    open3d.t.geometry.TriangleMesh or open3d.t.geometry.PointCloud
        The tensor geometry.

    Examples
    --------
    >>> from hht3d import data_path, load
    >>> spot = load(data_path("spot.ply"))
    >>> from hht3d.io import surface_to_open3d
    >>> mesh = surface_to_open3d(spot, {"height": spot.vertices[:, 1]})
    >>> tuple(mesh.vertex["height"].shape), tuple(mesh.triangle["indices"].shape)
    ((2930, 1), (5856, 3))
    """
    import open3d as o3d
    import open3d.core as o3c

    geometry: Any = o3d.t.geometry.TriangleMesh() if surface.is_mesh else o3d.t.geometry.PointCloud()
    store = geometry.vertex if surface.is_mesh else geometry.point
    tensor: Any = o3c.Tensor  # its stubs take no ndarray
    store["positions"] = tensor(surface.vertices)
    store["normals"] = tensor(surface.normals)
    if surface.colors is not None:
        store["colors"] = tensor(surface.colors)
    if surface.is_mesh:
        geometry.triangle["indices"] = tensor(surface.faces)
    for key, values in {**surface.attributes, **(attributes or {})}.items():
        store[checked_name(key)] = tensor(per_vertex(surface, key, values)[:, None])
    return geometry
