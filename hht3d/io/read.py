"""Reading meshes, point clouds and the headers of saved results.

* PLY is read with ``plyfile`` so that every per-vertex property survives; a
  PLY with faces is a mesh, without faces a point cloud.  A property name
  hht3d could not write back (PLY allows ``0bad``) is made writable at load
  (:func:`~hht3d.io.formats.usable_name`: ``_0bad``).
* OBJ, OFF, STL, GLB/GLTF meshes and PCD, XYZ, XYZN, PTS point clouds are read
  with Open3D, after the files they refer to are checked
  (:mod:`hht3d.io.references`).
* VTU, VTK, Gmsh, Medit, Abaqus, Nastran, SU2, ... (:data:`~hht3d.io.formats.MESHIO_EXTENSIONS`)
  are read with meshio (:mod:`hht3d.io.mesh_files`); quads and polygons are split into triangles.
* LAS and LAZ point clouds are read with laspy (:mod:`hht3d.io.las`), in chunks, at the file's
  scale and relative to a local origin (``surface.origin``); E57 scans with pye57
  (:mod:`hht3d.io.e57`), one or all merged with their poses.
* Only regular files are read (:func:`~hht3d.io.formats.check_regular_file`).
"""

from __future__ import annotations

from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError, one_line
from ..geometry.surface import Surface, SurfaceOptions
from ..open3d_quiet import quiet_open3d
from ..records import option
from .e57 import read_e57
from .formats import (
    MESH_EXTENSIONS,
    MESHIO_EXTENSIONS,
    PLY_RESERVED,
    POINT_CLOUD_EXTENSIONS,
    check_extension,
    check_regular_file,
    short,
    usable_name,
)
from .headers import PlyHeader, check_declared, read_ply_header
from .las import LAS_EXTENSIONS, read_las
from .mesh_files import read_meshio
from .references import check_references
from .sealed import Sealed, unsealed

__all__ = [
    "data_path",
    "MESH_EXTENSIONS",
    "POINT_CLOUD_EXTENSIONS",
    "load",
    "LoadOptions",
    "PlyHeader",
    "read_ply_header",
    "read_npz_shapes",
]


def data_path(name: str) -> Path:
    """Path of a file shipped in the package's ``data`` folder.

    Parameters
    ----------
    name : str
        ``spot.ply`` (Keenan Crane's cow, 2,930 vertices, CC0), ``sphere_oct4098.ply``
        (the paper's octahedral sphere) or ``demo.yaml`` (the demo pipeline).

    Examples
    --------
    >>> from hht3d import data_path
    >>> data_path("spot.ply").name
    'spot.ply'
    >>> data_path("spot.ply").is_file()
    True
    """
    return Path(str(resources.files("hht3d") / "data" / name))


@dataclass(frozen=True)
class LoadOptions(SurfaceOptions):
    """The settings of :func:`load`: cleaning, and the :class:`~hht3d.geometry.surface.SurfaceOptions`."""

    label = "load"

    clean: bool = option(True, "weld duplicate vertices, drop degenerate faces and unused vertices")
    classes: tuple[int, ...] | None = option(
        None,
        "LAS/LAZ: keep only points of these classification codes (2 ground, 6 building)",
        kind="ints",
        minimum=0,
        maximum=255,
    )
    dimensions: tuple[str, ...] | None = option(
        None,
        "LAS/LAZ: keep only these dimensions as attributes (default all; luminance keeps the colours)",
        kind="strs",
    )
    scan: int | None = option(
        None,
        "E57: read this scan (0-based); default all, merged with their poses",
        kind="int",
        minimum=0,
        maximum=10**6,
    )


def load(
    path: Path | str,
    options: LoadOptions | dict | None = None,
    *,
    name: str | None = None,
    storage_options: dict | Sealed | None = None,
    **overrides: Any,
) -> Surface:
    """Load a triangle mesh or point cloud as a :class:`~hht3d.geometry.surface.Surface`.

    Parameters
    ----------
    path : str or Path
        PLY, OBJ, OFF, STL, GLB, GLTF, VTU, VTK and the meshio formats (meshes); PLY, PCD, XYZ, XYZN,
        PTS, LAS, LAZ, E57 (points);
        a local path or an fsspec URL (``s3://bucket/scan.ply``, :mod:`hht3d.io.storage`).
    options : LoadOptions or dict, optional
        ``clean``: weld duplicate vertices and drop degenerate/duplicate faces and
        unreferenced vertices (:mod:`hht3d.geometry.cleaning`; the report is in
        ``surface.clean_report``); ``laplacian`` and ``n_neighbors``: passed to
        :class:`~hht3d.geometry.surface.Surface`; ``classes``: the classification codes of the
        LAS/LAZ points kept; ``dimensions``: the LAS/LAZ dimensions kept as attributes (default all);
        ``scan``: the E57 scan read (default all).
    name : str, optional
        Defaults to the file stem.
    storage_options : dict, optional
        For a URL: options of its fsspec back-end (endpoint, region, ...), or their
        :class:`~hht3d.io.sealed.Sealed` token (a task of a graph, :mod:`hht3d.io.sealed`).
    **overrides
        Settings that replace those of ``options`` (``clean=False``).

    Raises
    ------
    InputError
        Missing or unreadable file, unknown extension, empty or invalid geometry.

    Examples
    --------
    >>> from hht3d import data_path, load
    >>> surface = load(data_path("spot.ply"))
    >>> surface.n_vertices, len(surface.faces), surface.is_mesh
    (2930, 5856, True)
    """
    options = LoadOptions.of(options, **overrides)
    from .storage import is_url, load_url, local_path

    path = local_path(path)
    if is_url(path):  # object storage: through a temporary local copy
        return load_url(load, path, unsealed(storage_options), options=options, name=name)
    path = Path(path)
    check_regular_file(path)
    check_extension(path)
    check_declared(path)
    ext = path.suffix.lower()
    for setting, suffixes in (("classes", LAS_EXTENSIONS), ("dimensions", LAS_EXTENSIONS), ("scan", (".e57",))):
        if getattr(options, setting) is not None and ext not in suffixes:
            raise InputError(f"{short(path)}: load option {setting} is for {', '.join(suffixes)} files; this is {ext}")
    if ext in LAS_EXTENSIONS:
        data = read_las(path, options.classes, options.dimensions)
    elif ext == ".e57":
        data = read_e57(path, options.scan)
    elif ext == ".ply":
        data = _read_ply(path)
    elif ext in MESHIO_EXTENSIONS:
        data = read_meshio(path)
    elif ext in MESH_EXTENSIONS:
        check_references(path)
        data = _read_open3d_mesh(path)
    else:
        data = _read_open3d_points(path)
    if len(data["vertices"]) == 0:
        raise InputError(f"{path}: the file holds no vertices (empty or unreadable geometry)")
    settings: dict[str, Any] = dict(
        laplacian=options.laplacian, n_neighbors=options.n_neighbors, name=name or path.stem
    )
    try:
        surface = Surface.cleaned(**data, **settings) if options.clean else Surface(**data, **settings)
    except InputError as exc:
        raise InputError(f"{path}: {exc}") from None
    return surface


#: Faces read as one fixed-size array when every face is a triangle: plyfile then maps the element
#: instead of parsing it face by face (igea subdivided to 1M vertices: 1.6 s against 8.5 s).
_TRIANGLES = {"face": {"vertex_indices": 3, "vertex_index": 3}}


def _read_ply(path: Path) -> dict:
    from plyfile import PlyData

    try:
        try:
            ply = PlyData.read(str(path), known_list_len=_TRIANGLES)
        except Exception:  # not all triangles, or not readable: the general reader says which
            ply = PlyData.read(str(path), mmap=False)
        vertex = ply["vertex"].data
    except Exception as exc:  # plyfile raises many types on corrupt input
        raise InputError(f"{path}: not a readable PLY file ({exc})") from None
    names = vertex.dtype.names or ()
    if not {"x", "y", "z"} <= set(names):
        raise InputError(f"{path}: PLY vertices lack x, y, z properties (found {names})")
    data: dict[str, Any] = {
        "vertices": np.column_stack([vertex["x"], vertex["y"], vertex["z"]]).astype(np.float64),
        "faces": _ply_faces(ply, path),
    }
    if {"red", "green", "blue"} <= set(names):
        rgb = np.column_stack([vertex["red"], vertex["green"], vertex["blue"]]).astype(np.float64)
        data["colors"] = rgb / 255.0 if np.issubdtype(vertex["red"].dtype, np.integer) else rgb
    if data["faces"] is None and {"nx", "ny", "nz"} <= set(names):
        data["normals"] = np.column_stack([vertex["nx"], vertex["ny"], vertex["nz"]])
    attributes: dict[str, np.ndarray] = {}
    for key in names:
        if key not in PLY_RESERVED and vertex[key].dtype.kind in "biuf":
            attributes.setdefault(usable_name(key), np.array(vertex[key], dtype=np.float64))  # not a map of the file
    data["attributes"] = attributes
    return data


def read_npz(path: Path | str) -> dict[str, np.ndarray]:
    """Every array of a ``.npz`` file (no pickled objects).

    Parameters
    ----------
    path : Path or str
        The ``.npz`` file.

    Raises
    ------
    InputError
        Not a regular file, or not a readable ``.npz``.
    """
    import zipfile

    path = Path(path)
    check_regular_file(path, "an .npz file")
    try:
        with np.load(path, allow_pickle=False) as stored:
            return {name: stored[name] for name in stored.files}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as exc:
        raise InputError(f"{path}: not a readable .npz file ({one_line(exc)})") from None


def read_npz_shapes(path: Path | str) -> dict[str, tuple[int, ...]]:
    """The shape of every array in a ``.npz`` file, from the array headers alone (no data is read).

    Parameters
    ----------
    path : Path or str
        The ``.npz`` file.

    Raises
    ------
    InputError
        Not a readable ``.npz`` file.
    """
    import zipfile

    path = Path(path)
    check_regular_file(path, "an .npz file")
    shapes = {}
    try:
        with zipfile.ZipFile(path) as archive:
            for name in archive.namelist():
                with archive.open(name) as member:
                    version = np.lib.format.read_magic(member)
                    read = (
                        np.lib.format.read_array_header_1_0
                        if version == (1, 0)
                        else np.lib.format.read_array_header_2_0
                    )
                    shapes[name.removesuffix(".npy")] = read(member)[0]
    except (OSError, ValueError, zipfile.BadZipFile) as exc:
        raise InputError(f"{path}: not a readable .npz file ({one_line(exc)})") from None
    return shapes


def _ply_faces(ply: Any, path: Path) -> np.ndarray | None:
    if "face" not in ply or ply["face"].count == 0:
        return None
    face = ply["face"].data
    key = next((k for k in ("vertex_indices", "vertex_index") if k in face.dtype.names), None)
    if key is None:
        raise InputError(f"{path}: PLY faces lack a vertex_indices property")
    polygons = face[key]
    if polygons.ndim == 2:  # read as triangles (_TRIANGLES)
        return polygons.astype(np.int64)
    sizes = np.fromiter((len(p) for p in polygons), dtype=np.int64, count=len(polygons))
    if np.all(sizes == 3):
        return np.vstack(polygons).astype(np.int64)
    if sizes.min() < 3:
        raise InputError(f"{path}: PLY has faces with fewer than 3 vertices")
    # fan-triangulate polygons
    return np.array([(p[0], p[i], p[i + 1]) for p in polygons for i in range(1, len(p) - 1)], dtype=np.int64)


def _read_open3d_mesh(path: Path) -> dict:
    with quiet_open3d() as o3d:
        mesh = o3d.io.read_triangle_mesh(str(path))
    data = {
        "vertices": np.asarray(mesh.vertices, dtype=np.float64),
        "faces": np.asarray(mesh.triangles, dtype=np.int64),
    }
    if len(data["vertices"]) and len(data["faces"]) == 0:
        raise InputError(f"{path}: the mesh file holds no triangles")
    if mesh.has_vertex_colors():
        data["colors"] = np.asarray(mesh.vertex_colors, dtype=np.float64)
    return data


def _read_open3d_points(path: Path) -> dict:
    with quiet_open3d() as o3d:
        pcd = o3d.io.read_point_cloud(str(path))
    data = {"vertices": np.asarray(pcd.points, dtype=np.float64), "faces": None}
    if pcd.has_normals():
        data["normals"] = np.asarray(pcd.normals, dtype=np.float64)
    if pcd.has_colors():
        data["colors"] = np.asarray(pcd.colors, dtype=np.float64)
    return data
