"""Conversion between :class:`~hht3d.geometry.surface.Surface` and PyVista datasets, when PyVista is
installed (it is not a dependency).

A surface becomes a ``pyvista.PolyData`` as the VTU/VTP writers lay it out
(:mod:`hht3d.io.mesh_files`): points at the file's coordinates (``vertices + origin``), triangles as
faces or one vertex cell per point of a cloud, and every stored attribute and given field as point
data (colours as ``colors``, 3 components).
"""

from __future__ import annotations

from types import ModuleType
from typing import Any

import numpy as np

from ..errors import InputError
from ..geometry.surface import Surface
from .formats import usable_name
from .mesh_files import _point_data
from .write import per_vertex

__all__ = ["surface_to_pyvista", "surface_from_pyvista"]


def _pyvista() -> ModuleType:
    try:
        import pyvista
    except ImportError:
        raise InputError("PyVista conversion needs pyvista: pip install pyvista") from None
    return pyvista


def surface_to_pyvista(surface: Surface, fields: dict | None = None) -> Any:
    """The surface as a ``pyvista.PolyData`` with its attributes and ``fields`` as point data.

    Parameters
    ----------
    surface : Surface
    fields : dict of str to (n,) array, optional
        More per-vertex values, e.g. :meth:`~hht3d.transform.HHTResult.vertex_attributes`.

    Returns
    -------
    pyvista.PolyData
        Triangles as faces for a mesh, one vertex cell per point for a point cloud.

    Raises
    ------
    InputError
        PyVista is not installed, or a field has not one value per vertex.
    """
    pyvista = _pyvista()
    points = surface.vertices + surface.origin
    if surface.is_mesh:
        faces = np.asarray(surface.faces, dtype=np.int64)
        poly = pyvista.PolyData(points, np.column_stack([np.full(len(faces), 3), faces]).ravel())
    else:
        poly = pyvista.PolyData(points)  # with a vertex cell per point
    for name, values in _point_data(surface, fields).items():
        poly.point_data[name] = values if name == "colors" else per_vertex(surface, name, values)
    return poly


def surface_from_pyvista(mesh: Any, *, clean: bool = True, name: str | None = None, **options: Any) -> Surface:
    """A surface from a PyVista dataset, its polygons triangulated.

    Parameters
    ----------
    mesh : pyvista.DataSet
        A ``PolyData``, or any dataset whose outer surface is taken (an ``UnstructuredGrid``
        read from a VTU, ...).  Without polygons it is a point cloud.
    clean : bool
        Build with :meth:`Surface.cleaned` (merge duplicates, drop degenerate faces).
    name : str, optional
        The surface's name.
    **options
        Further :class:`Surface` settings (``laplacian``, ``n_neighbors``).

    Returns
    -------
    Surface
        With each scalar numeric point-data array as a stored attribute, and ``colors``
        (3 components; 0-255 integers scaled to 0-1) as its colours.

    Raises
    ------
    InputError
        PyVista is not installed, ``mesh`` is not a PyVista dataset, or it has no points.
    """
    pyvista = _pyvista()
    if not isinstance(mesh, pyvista.DataSet):
        raise InputError(f"expected a PyVista dataset, got {type(mesh).__name__}")
    if mesh.n_points == 0:
        raise InputError(f"{name or 'pyvista dataset'}: the dataset has no points")
    poly = mesh if isinstance(mesh, pyvista.PolyData) else _outer_surface(pyvista, mesh)
    triangles = poly.triangulate() if poly.GetNumberOfPolys() else None
    source = poly if triangles is None else triangles
    data: dict[str, Any] = {
        "vertices": np.asarray(source.points, dtype=np.float64),
        "faces": None if triangles is None else np.asarray(triangles.regular_faces, dtype=np.int64),
    }
    n = source.n_points
    for key in source.point_data.keys():
        values = np.asarray(source.point_data[key])
        if key == "colors" and values.shape == (n, 3):
            data["colors"] = values.astype(np.float64) / (255.0 if values.dtype.kind in "iu" else 1.0)
        elif values.shape == (n,) and values.dtype.kind in "biuf":
            data.setdefault("attributes", {})[usable_name(key)] = values.astype(np.float64)
    build = Surface.cleaned if clean else Surface
    return build(**data, name=name, **options)


def _outer_surface(pyvista: ModuleType, mesh: Any) -> Any:
    """The dataset's outer faces, vertices and lines as ``PolyData`` (VTK's geometry filter: an
    unstructured grid's points stay in their order)."""
    from vtkmodules.vtkFiltersGeometry import vtkGeometryFilter

    geometry = vtkGeometryFilter()
    geometry.SetInputData(mesh)
    geometry.Update()
    return pyvista.wrap(geometry.GetOutput())
