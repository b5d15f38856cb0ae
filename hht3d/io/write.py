"""Writing surfaces and per-vertex fields: binary PLY (every field a vertex property), NPZ, coloured PLY.

Every write is atomic (:func:`hht3d.io.atomic.atomic_path`).
"""

from __future__ import annotations

from pathlib import Path
from typing import cast

import numpy as np

from ..errors import InputError
from ..geometry.surface import Surface
from .atomic import atomic_path
from .formats import checked_name

__all__ = ["per_vertex", "write_ply", "write_npz", "field_colors", "write_colored_ply"]


def per_vertex(surface: Surface, key: str, values: np.ndarray) -> np.ndarray:
    a = np.asarray(values, dtype=np.float64)
    if a.shape != (surface.n_vertices,):
        raise InputError(f"attribute {key!r} has shape {a.shape}; expected ({surface.n_vertices},)")
    return a


def write_ply(
    path: Path | str, surface: Surface, attributes: dict | None = None, *, colors: np.ndarray | None = None
) -> Path:
    """Write the surface with named float64 per-vertex ``attributes`` to a binary PLY.

    Positions (in the file's frame: ``vertices + origin``) and normals are float64; ``colors``
    (n, 3) in [0, 1] (default: the surface's own) become uchar red/green/blue.  The file's stored scalars
    (``surface.attributes``) are written too unless overridden by name.

    Parameters
    ----------
    path : Path or str
        The PLY file to write.
    surface : Surface
        The surface.
    attributes : dict, optional
        Per-vertex fields, by name, written as float64 properties.
    colors : (n, 3) ndarray, optional
        Vertex colours in [0, 1] (default: the surface's own, if any).

    Returns
    -------
    Path
        The path written.

    Examples
    --------
    >>> from hht3d import data_path, load
    >>> spot = load(data_path("spot.ply"))
    >>> import tempfile
    >>> from pathlib import Path
    >>> from hht3d.io import read_ply_header, write_ply
    >>> path = write_ply(Path(tempfile.mkdtemp()) / "spot.ply", spot, {"height": spot.vertices[:, 1]})
    >>> header = read_ply_header(path)
    >>> header.counts, header.vertex_properties[-1]
    ({'vertex': 2930, 'face': 5856}, 'height')
    """
    from plyfile import PlyData, PlyElement

    fields = {**surface.attributes, **(attributes or {})}
    placed = surface.vertices + surface.origin  # the file's frame (a LAS scan's local origin added back)
    columns = {"x": placed[:, 0], "y": placed[:, 1], "z": placed[:, 2]}
    normals = surface.normals
    columns.update(nx=normals[:, 0], ny=normals[:, 1], nz=normals[:, 2])
    dtype = [(k, "f8") for k in columns]
    colors = surface.colors if colors is None else np.asarray(colors, dtype=np.float64)
    if colors is not None:
        rgb = np.clip(np.round(colors * 255.0), 0, 255).astype(np.uint8)
        columns.update(red=rgb[:, 0], green=rgb[:, 1], blue=rgb[:, 2])
        dtype += [("red", "u1"), ("green", "u1"), ("blue", "u1")]
    for key, values in fields.items():
        columns[checked_name(key)] = per_vertex(surface, key, values)
        dtype.append((key, "f8"))
    vertex = np.empty(surface.n_vertices, dtype=dtype)
    for key, values in columns.items():
        vertex[key] = values
    elements = [PlyElement.describe(vertex, "vertex")]
    if surface.is_mesh:
        face = np.empty(len(cast(np.ndarray, surface.faces)), dtype=[("vertex_indices", "i4", (3,))])
        face["vertex_indices"] = surface.faces
        elements.append(PlyElement.describe(face, "face"))
    with atomic_path(path) as tmp:
        PlyData(elements, text=False).write(str(tmp))
    return Path(path)


def write_npz(path: Path | str, arrays: dict) -> Path:
    """Write a compressed ``.npz`` of named arrays atomically.

    Parameters
    ----------
    path : Path or str
        The ``.npz`` file to write.
    arrays : dict
        The arrays, by name.

    Returns
    -------
    Path
        The path written.

    Examples
    --------
    >>> import tempfile
    >>> import numpy as np
    >>> from pathlib import Path
    >>> from hht3d.io import read_npz, write_npz
    >>> path = write_npz(Path(tempfile.mkdtemp()) / "fields.npz", {"height": np.arange(3.0)})
    >>> read_npz(path)["height"].tolist()
    [0.0, 1.0, 2.0]
    """
    with atomic_path(path) as tmp, open(tmp, "wb") as handle:
        np.savez_compressed(handle, **{k: np.asarray(v) for k, v in arrays.items()})  # type: ignore[arg-type]  # numpy's stub: **kwds could reach allow_pickle
    return Path(path)


def field_colors(values: np.ndarray, *, cmap: str = "viridis", limits: tuple[float, float] | None = None) -> np.ndarray:
    """Map a scalar field to RGB in [0, 1]; default limits: 1st and 99th percentile.

    Parameters
    ----------
    values : (n,) ndarray
        The scalar field; non-finite values take the colour of the low limit.
    cmap : str, optional
        A Matplotlib colormap name (default ``"viridis"``).
    limits : tuple of float, optional
        ``(low, high)`` of the colour scale (default: the 1st and 99th percentile).

    Returns
    -------
    (n, 3) ndarray
        RGB colours in [0, 1].

    Examples
    --------
    >>> import numpy as np
    >>> from hht3d.io import field_colors
    >>> colors = field_colors(np.array([0.0, 1.0, 2.0]), cmap="gray", limits=(0.0, 2.0))
    >>> colors.round(2).tolist()
    [[0.0, 0.0, 0.0], [0.5, 0.5, 0.5], [1.0, 1.0, 1.0]]
    """
    import matplotlib

    values = np.asarray(values, dtype=np.float64)
    finite = values[np.isfinite(values)]
    if finite.size == 0:
        raise InputError("the field has no finite values to colour")
    lo, hi = limits if limits is not None else np.percentile(finite, [1, 99])
    scale = (values - lo) / (hi - lo) if hi > lo else np.full_like(values, 0.5)
    rgba = matplotlib.colormaps[cmap](np.clip(np.nan_to_num(scale, nan=0.0), 0.0, 1.0))
    return rgba[:, :3]


def write_colored_ply(
    path: Path | str,
    surface: Surface,
    values: np.ndarray,
    *,
    cmap: str = "viridis",
    limits: tuple[float, float] | None = None,
    name: str = "field",
) -> Path:
    """Write a PLY whose vertex colours show one field (for any mesh viewer); the raw
    values are kept as attribute ``name``.

    Parameters
    ----------
    path : Path or str
        The PLY file to write.
    surface : Surface
        The surface.
    values : (n,) ndarray
        The field shown by the colours.
    cmap : str, optional
        A Matplotlib colormap name (default ``"viridis"``).
    limits : tuple of float, optional
        ``(low, high)`` of the colour scale (default: the 1st and 99th percentile).
    name : str, optional
        The attribute holding the raw values (default ``"field"``).

    Returns
    -------
    Path
        The path written.

    Examples
    --------
    >>> from hht3d import data_path, load
    >>> spot = load(data_path("spot.ply"))
    >>> import tempfile
    >>> from pathlib import Path
    >>> from hht3d.io import load, write_colored_ply
    >>> path = write_colored_ply(Path(tempfile.mkdtemp()) / "height.ply", spot, spot.vertices[:, 1], name="height")
    >>> again = load(path, clean=False)
    >>> again.colors.shape, sorted(again.attributes)
    ((2930, 3), ['height'])
    """
    values = per_vertex(surface, name, values)
    return write_ply(path, surface, {name: values}, colors=field_colors(values, cmap=cmap, limits=limits))
