"""VTK files and the meshio formats: reading any meshio mesh whose cells triangulate, writing VTU
(through meshio, the ``meshio`` extra) and VTP (VTK's XML PolyData, written here with numpy).

Both writers put every field and stored attribute as point data (colours as ``colors``, 3
components) beside the mesh's triangles, or one vertex cell per point of a point cloud, at the
file's coordinates (``vertices + origin``).  ParaView and PyVista read them.
"""

from __future__ import annotations

import base64
from pathlib import Path
from types import ModuleType
from typing import Any
from xml.sax.saxutils import quoteattr

import numpy as np

from ..errors import InputError, one_line
from ..geometry.surface import Surface
from .atomic import atomic_path
from .formats import short, usable_name

__all__ = ["read_meshio", "write_vtu", "write_vtp"]

#: Cell types whose corners triangulate (a fan from the first corner): their corner count (the
#: quadratic ones list their corners first; a polygon uses them all).
_CORNERS = {"triangle": 3, "triangle6": 3, "triangle7": 3, "quad": 4, "quad8": 4, "quad9": 4, "polygon": None}


def _meshio() -> ModuleType:
    try:
        import meshio
    except ImportError:
        raise InputError("VTU files and the meshio formats need meshio: pip install 'hht3d[meshio]'") from None
    return meshio


def read_meshio(path: Path) -> dict:
    """The arrays of a :class:`~hht3d.geometry.surface.Surface` from a file meshio reads: triangles,
    quads and polygons split into triangles (quadratic ones by their corners; other cells are left
    out; vertex cells alone make a point cloud), and each scalar point-data array as an attribute.

    Raises
    ------
    InputError
        meshio missing, or a file it cannot read.
    """
    meshio = _meshio()
    try:
        mesh = meshio.read(str(path))
    except (Exception, SystemExit) as exc:  # meshio raises many types, and exits on an unknown format
        raise InputError(f"{short(path)}: not a readable mesh file ({one_line(exc)})") from None
    points = np.asarray(mesh.points, dtype=np.float64)
    if points.ndim == 2 and points.shape[1] == 2:  # planar formats: z = 0
        points = np.column_stack([points, np.zeros(len(points))])
    triangles = [_fan(np.asarray(b.data)[:, : _CORNERS[b.type]]) for b in mesh.cells if b.type in _CORNERS]
    other = sorted({block.type for block in mesh.cells} - {"vertex", *_CORNERS})
    if not triangles and other:
        raise InputError(
            f"{short(path)}: the file holds {', '.join(other)} cells and no triangles, quads or polygons; "
            "hht3d reads surfaces"
        )
    attributes = {
        usable_name(name): np.asarray(values, dtype=np.float64).reshape(len(points))
        for name, values in mesh.point_data.items()
        if np.asarray(values).size == len(points) and np.asarray(values).dtype.kind in "biuf"
    }
    return {"vertices": points, "faces": np.vstack(triangles) if triangles else None, "attributes": attributes}


def _fan(corners: Any) -> np.ndarray:
    corners = np.asarray(corners, dtype=np.int64)
    return np.vstack([corners[:, [0, k, k + 1]] for k in range(1, corners.shape[1] - 1)])


def _point_data(surface: Surface, fields: dict | None) -> dict[str, np.ndarray]:
    data = {k: np.asarray(v, dtype=np.float64) for k, v in {**surface.attributes, **(fields or {})}.items()}
    if surface.colors is not None:
        data["colors"] = surface.colors
    return data


def _cells(surface: Surface) -> tuple[str, np.ndarray]:
    if surface.is_mesh:
        return "triangle", np.asarray(surface.faces, dtype=np.int64)
    return "vertex", np.arange(surface.n_vertices, dtype=np.int64)[:, None]


def write_vtu(path: Path | str, surface: Surface, fields: dict | None = None) -> Path:
    """Write the surface as a VTU unstructured grid through meshio, atomically (see the module)."""
    meshio = _meshio()
    with atomic_path(path) as tmp:
        meshio.write_points_cells(
            str(tmp),
            surface.vertices + surface.origin,
            [_cells(surface)],
            point_data=_point_data(surface, fields),
            file_format="vtu",
        )
    return Path(path)


_VTK_TYPES = {"f8": "Float64", "i8": "Int64"}


def _array(values: np.ndarray, name: str | None = None) -> str:
    """A DataArray, inline binary: base64 of a UInt64 byte count and the little-endian values."""
    values = np.ascontiguousarray(values, dtype=values.dtype.newbyteorder("<"))
    components = 1 if values.ndim == 1 else values.shape[1]
    payload = base64.b64encode(np.uint64(values.nbytes).tobytes() + values.tobytes()).decode("ascii")
    named = f" Name={quoteattr(name)}" if name is not None else ""
    kind = _VTK_TYPES[values.dtype.str[1:]]
    return f'<DataArray type="{kind}"{named} NumberOfComponents="{components}" format="binary">{payload}</DataArray>'


def write_vtp(path: Path | str, surface: Surface, fields: dict | None = None) -> Path:
    """Write the surface as VTK XML PolyData (triangles as ``Polys``, a cloud's points as ``Verts``),
    atomically; needs no package beyond numpy."""
    kind, cells = _cells(surface)
    element = "Polys" if kind == "triangle" else "Verts"
    offsets = np.arange(1, len(cells) + 1, dtype=np.int64) * cells.shape[1]
    point_data = "".join(_array(v, k) for k, v in _point_data(surface, fields).items())
    counts = {"Verts": 0, "Polys": 0, element: len(cells)}
    text = (
        '<?xml version="1.0"?>\n<VTKFile type="PolyData" version="1.0" byte_order="LittleEndian" '
        'header_type="UInt64"><PolyData>'
        f'<Piece NumberOfPoints="{surface.n_vertices}" NumberOfVerts="{counts["Verts"]}" NumberOfLines="0" '
        f'NumberOfStrips="0" NumberOfPolys="{counts["Polys"]}">'
        f"<PointData>{point_data}</PointData>"
        f"<Points>{_array(surface.vertices + surface.origin)}</Points>"
        f"<{element}>{_array(cells.ravel(), 'connectivity')}{_array(offsets, 'offsets')}</{element}>"
        "</Piece></PolyData></VTKFile>\n"
    )
    with atomic_path(path) as tmp:
        Path(tmp).write_text(text, encoding="ascii")
    return Path(path)
