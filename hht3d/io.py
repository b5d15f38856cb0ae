"""Reading and writing meshes, point clouds and per-vertex fields.

* PLY is read and written with ``plyfile`` so that every per-vertex property
  survives (Open3D's tensor mesh writer drops custom attributes).  A PLY with
  faces is a mesh, without faces a point cloud.
* OBJ, OFF, STL, GLB/GLTF meshes and PCD, XYZ, XYZN, PTS point clouds are read
  with Open3D.
* Every write is atomic: a temporary file in the target folder, renamed over
  the target only once complete.
"""
from __future__ import annotations

import contextlib
import os
import re
import tempfile
from pathlib import Path

import numpy as np

from .errors import InputError
from .surface import Surface

__all__ = [
    "MESH_EXTENSIONS",
    "POINT_CLOUD_EXTENSIONS",
    "load",
    "surface_from_open3d",
    "surface_to_open3d",
    "estimate_point_normals",
    "atomic_path",
    "write_ply",
    "write_npz",
    "write_colored_ply",
    "field_colors",
    "resolve_inputs",
]

MESH_EXTENSIONS = (".ply", ".obj", ".off", ".stl", ".glb", ".gltf")
POINT_CLOUD_EXTENSIONS = (".ply", ".pcd", ".xyz", ".xyzn", ".pts")
_PLY_RESERVED = {"x", "y", "z", "nx", "ny", "nz", "red", "green", "blue", "alpha"}
_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_.\-]*$")


# -- reading -------------------------------------------------------------------------------
def load(path, *, clean: bool = True, laplacian: str = "cotan", n_neighbors: int = 30,
         name: str | None = None) -> Surface:
    """Load a triangle mesh or point cloud as a :class:`~hht3d.surface.Surface`.

    Parameters
    ----------
    path : str or Path
        PLY, OBJ, OFF, STL, GLB, GLTF (meshes); PLY, PCD, XYZ, XYZN, PTS (points).
    clean : bool
        Weld duplicate vertices and drop degenerate/duplicate faces and
        unreferenced vertices (:mod:`hht3d.cleaning`); the report is in
        ``surface.clean_report``.
    laplacian, n_neighbors
        Passed to :class:`~hht3d.surface.Surface`.
    name : str, optional
        Defaults to the file stem.

    Raises
    ------
    InputError
        Missing or unreadable file, unknown extension, empty or invalid geometry.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: no such file; check the path")
    ext = path.suffix.lower()
    if ext not in MESH_EXTENSIONS + POINT_CLOUD_EXTENSIONS:
        raise InputError(f"{path}: unknown extension {ext!r}; meshes: {', '.join(MESH_EXTENSIONS)}; "
                         f"point clouds: {', '.join(POINT_CLOUD_EXTENSIONS)}")
    if ext == ".ply":
        data = _read_ply(path)
    elif ext in MESH_EXTENSIONS:
        data = _read_open3d_mesh(path)
    else:
        data = _read_open3d_points(path)
    if len(data["vertices"]) == 0:
        raise InputError(f"{path}: the file holds no vertices (empty or unreadable geometry)")
    options = dict(laplacian=laplacian, n_neighbors=n_neighbors, name=name or path.stem)
    try:
        if clean:
            return Surface.cleaned(**data, **options)
        return Surface(**data, **options)
    except InputError as exc:
        raise InputError(f"{path}: {exc}") from None


def _read_ply(path: Path) -> dict:
    from plyfile import PlyData

    try:
        ply = PlyData.read(str(path))
        vertex = ply["vertex"].data
    except Exception as exc:  # plyfile raises many types on corrupt input
        raise InputError(f"{path}: not a readable PLY file ({exc})") from None
    names = vertex.dtype.names or ()
    if not {"x", "y", "z"} <= set(names):
        raise InputError(f"{path}: PLY vertices lack x, y, z properties (found {names})")
    data = {"vertices": np.column_stack([vertex["x"], vertex["y"], vertex["z"]]).astype(np.float64),
            "faces": _ply_faces(ply, path)}
    if {"red", "green", "blue"} <= set(names):
        rgb = np.column_stack([vertex["red"], vertex["green"], vertex["blue"]]).astype(np.float64)
        data["colors"] = rgb / 255.0 if np.issubdtype(vertex["red"].dtype, np.integer) else rgb
    if data["faces"] is None and {"nx", "ny", "nz"} <= set(names):
        data["normals"] = np.column_stack([vertex["nx"], vertex["ny"], vertex["nz"]])
    data["attributes"] = {k: np.asarray(vertex[k], dtype=np.float64) for k in names
                          if k not in _PLY_RESERVED and vertex[k].dtype.kind in "biuf"}
    return data


def _ply_faces(ply, path: Path):
    if "face" not in ply or ply["face"].count == 0:
        return None
    face = ply["face"].data
    key = next((k for k in ("vertex_indices", "vertex_index") if k in face.dtype.names), None)
    if key is None:
        raise InputError(f"{path}: PLY faces lack a vertex_indices property")
    polygons = face[key]
    sizes = np.fromiter((len(p) for p in polygons), dtype=np.int64, count=len(polygons))
    if np.all(sizes == 3):
        return np.vstack(polygons).astype(np.int64)
    if sizes.min() < 3:
        raise InputError(f"{path}: PLY has faces with fewer than 3 vertices")
    # fan-triangulate polygons
    return np.array([(p[0], p[i], p[i + 1]) for p in polygons for i in range(1, len(p) - 1)],
                    dtype=np.int64)


@contextlib.contextmanager
def _quiet_open3d():
    import open3d as o3d

    with o3d.utility.VerbosityContextManager(o3d.utility.VerbosityLevel.Error):
        yield o3d


def _read_open3d_mesh(path: Path) -> dict:
    with _quiet_open3d() as o3d:
        mesh = o3d.io.read_triangle_mesh(str(path))
    data = {"vertices": np.asarray(mesh.vertices, dtype=np.float64),
            "faces": np.asarray(mesh.triangles, dtype=np.int64)}
    if len(data["vertices"]) and len(data["faces"]) == 0:
        raise InputError(f"{path}: the mesh file holds no triangles")
    if mesh.has_vertex_colors():
        data["colors"] = np.asarray(mesh.vertex_colors, dtype=np.float64)
    return data


def _read_open3d_points(path: Path) -> dict:
    with _quiet_open3d() as o3d:
        pcd = o3d.io.read_point_cloud(str(path))
    data = {"vertices": np.asarray(pcd.points, dtype=np.float64), "faces": None}
    if pcd.has_normals():
        data["normals"] = np.asarray(pcd.normals, dtype=np.float64)
    if pcd.has_colors():
        data["colors"] = np.asarray(pcd.colors, dtype=np.float64)
    return data


def surface_from_open3d(geometry, *, clean: bool = True, name: str | None = None, **options) -> Surface:
    """Build a surface from an Open3D legacy or tensor ``TriangleMesh`` / ``PointCloud``.

    Colours and (tensor geometries) every other float vertex attribute are
    carried over; point-cloud normals are kept when present.
    """
    import open3d as o3d

    if isinstance(geometry, o3d.geometry.TriangleMesh):
        data = {"vertices": np.asarray(geometry.vertices), "faces": np.asarray(geometry.triangles)}
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
        attrs = geometry.vertex if is_mesh else geometry.point
        data = {"vertices": attrs["positions"].numpy(),
                "faces": geometry.triangle["indices"].numpy() if is_mesh and "indices" in geometry.triangle
                else None}
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


def surface_to_open3d(surface: Surface, attributes: dict):
    """Tensor ``TriangleMesh``/``PointCloud`` carrying ``attributes`` as (n, 1) float vertex attributes."""
    import open3d as o3d
    import open3d.core as o3c

    geometry = (o3d.t.geometry.TriangleMesh() if surface.is_mesh else o3d.t.geometry.PointCloud())
    store = geometry.vertex if surface.is_mesh else geometry.point
    store["positions"] = o3c.Tensor(surface.vertices)
    store["normals"] = o3c.Tensor(surface.normals)
    if surface.colors is not None:
        store["colors"] = o3c.Tensor(surface.colors)
    if surface.is_mesh:
        geometry.triangle["indices"] = o3c.Tensor(surface.faces)
    for key, values in {**surface.attributes, **attributes}.items():
        store[_checked_name(key)] = o3c.Tensor(_per_vertex(surface, key, values)[:, None])
    return geometry


def estimate_point_normals(points: np.ndarray, k: int = 30) -> np.ndarray:
    """Unit normals of a point cloud: PCA over ``k`` neighbours, consistently oriented.

    Open3D orients them along a minimum spanning tree over tangent planes;
    the whole set is then flipped, if needed, to point away from the centroid
    on average (outward for closed scans).
    """
    with _quiet_open3d() as o3d:
        pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
        pcd.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(knn=k))
        pcd.orient_normals_consistent_tangent_plane(k)
        normals = np.asarray(pcd.normals, dtype=np.float64)
    if np.einsum("ij,ij->", normals, points - points.mean(axis=0)) < 0:
        normals = -normals
    return normals


# -- writing -------------------------------------------------------------------------------
@contextlib.contextmanager
def atomic_path(path):
    """Yield a temporary path beside ``path``; rename it to ``path`` on success.

    On any exception the temporary file is removed and ``path`` is untouched.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".part", dir=path.parent)
    os.close(fd)
    try:
        yield Path(tmp)
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp creates 0600; match an ordinary write
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _checked_name(key: str) -> str:
    if not _NAME.match(str(key)) or key in _PLY_RESERVED:
        raise InputError(f"attribute name {key!r} is not usable as a PLY property "
                         "(letters, digits, '_', '.', '-'; not x/y/z/nx/ny/nz/red/green/blue/alpha)")
    return str(key)


def _per_vertex(surface: Surface, key: str, values) -> np.ndarray:
    a = np.asarray(values, dtype=np.float64)
    if a.shape != (surface.n_vertices,):
        raise InputError(f"attribute {key!r} has shape {a.shape}; expected ({surface.n_vertices},)")
    return a


def write_ply(path, surface: Surface, attributes: dict | None = None, *, colors=None) -> Path:
    """Write the surface with named float64 per-vertex ``attributes`` to a binary PLY.

    Positions and normals are float64; ``colors`` (n, 3) in [0, 1] (default:
    the surface's own) become uchar red/green/blue.  The file's stored scalars
    (``surface.attributes``) are written too unless overridden by name.
    """
    from plyfile import PlyData, PlyElement

    fields = {**surface.attributes, **(attributes or {})}
    columns = {"x": surface.vertices[:, 0], "y": surface.vertices[:, 1], "z": surface.vertices[:, 2]}
    normals = surface.normals
    columns.update(nx=normals[:, 0], ny=normals[:, 1], nz=normals[:, 2])
    dtype = [(k, "f8") for k in columns]
    colors = surface.colors if colors is None else np.asarray(colors, dtype=np.float64)
    if colors is not None:
        rgb = np.clip(np.round(colors * 255.0), 0, 255).astype(np.uint8)
        columns.update(red=rgb[:, 0], green=rgb[:, 1], blue=rgb[:, 2])
        dtype += [("red", "u1"), ("green", "u1"), ("blue", "u1")]
    for key, values in fields.items():
        columns[_checked_name(key)] = _per_vertex(surface, key, values)
        dtype.append((key, "f8"))
    vertex = np.empty(surface.n_vertices, dtype=dtype)
    for key, values in columns.items():
        vertex[key] = values
    elements = [PlyElement.describe(vertex, "vertex")]
    if surface.is_mesh:
        face = np.empty(len(surface.faces), dtype=[("vertex_indices", "i4", (3,))])
        face["vertex_indices"] = surface.faces
        elements.append(PlyElement.describe(face, "face"))
    with atomic_path(path) as tmp:
        PlyData(elements, text=False).write(str(tmp))
    return Path(path)


def write_npz(path, arrays: dict) -> Path:
    """Write a compressed ``.npz`` of named arrays atomically."""
    with atomic_path(path) as tmp, open(tmp, "wb") as handle:
        np.savez_compressed(handle, **{k: np.asarray(v) for k, v in arrays.items()})
    return Path(path)


def field_colors(values, *, cmap: str = "viridis", limits=None) -> np.ndarray:
    """Map a scalar field to RGB in [0, 1]; default limits: 1st and 99th percentile."""
    import matplotlib

    values = np.asarray(values, dtype=np.float64)
    finite = values[np.isfinite(values)]
    if finite.size == 0:
        raise InputError("the field has no finite values to colour")
    lo, hi = limits if limits is not None else np.percentile(finite, [1, 99])
    scale = (values - lo) / (hi - lo) if hi > lo else np.full_like(values, 0.5)
    rgba = matplotlib.colormaps[cmap](np.clip(np.nan_to_num(scale, nan=0.0), 0.0, 1.0))
    return rgba[:, :3]


def write_colored_ply(path, surface: Surface, values, *, cmap: str = "viridis", limits=None,
                      name: str = "field") -> Path:
    """Write a PLY whose vertex colours show one field (for any mesh viewer); the raw
    values are kept as attribute ``name``."""
    values = _per_vertex(surface, name, values)
    return write_ply(path, surface, {name: values}, colors=field_colors(values, cmap=cmap, limits=limits))


def resolve_inputs(spec) -> list[Path]:
    """Expand an input spec into files: a file, a folder (its mesh/point files),
    a glob pattern, or a list of these.  Order is sorted and duplicates dropped.

    Raises
    ------
    InputError
        A named file is missing, or a folder/glob matches no usable file.
    """
    import glob

    specs = [spec] if isinstance(spec, (str, Path)) else list(spec)
    found: list[Path] = []
    usable = set(MESH_EXTENSIONS + POINT_CLOUD_EXTENSIONS)
    for item in specs:
        text = str(item)
        path = Path(text)
        if path.is_dir():
            matches = sorted(p for p in path.iterdir() if p.suffix.lower() in usable and p.is_file())
        elif any(ch in text for ch in "*?["):
            matches = sorted(Path(p) for p in glob.glob(text, recursive=True))
        elif path.is_file():
            matches = [path]
        else:
            raise InputError(f"{text}: no such file or folder")
        if not matches:
            raise InputError(f"{text}: matches no mesh or point-cloud file "
                             f"({', '.join(sorted(usable))})")
        found.extend(matches)
    return list(dict.fromkeys(found))
