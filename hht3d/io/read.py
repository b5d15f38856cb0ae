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
from importlib import resources
import re
import sys
import tempfile
import threading
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import MAX_SHOWN, InputError, OutputError, one_line
from ..geometry.surface import FLAT, Surface, principal_axes

__all__ = [
    "data_path",
    "MESH_EXTENSIONS",
    "POINT_CLOUD_EXTENSIONS",
    "load",
    "surface_from_open3d",
    "surface_to_open3d",
    "estimate_point_normals",
    "atomic_path",
    "check_output_paths",
    "read_ply_header",
    "read_npz_shapes",
    "PlyHeader",
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
def data_path(name: str) -> Path:
    """Path of a file shipped in the package's ``data`` folder.

    ``spot.ply`` (Keenan Crane's cow, 2,930 vertices, CC0), ``sphere_oct4098.ply``
    (the paper's octahedral sphere) and ``demo.yaml`` (the demo pipeline).

    Examples
    --------
    >>> from hht3d import data_path
    >>> data_path("spot.ply").name
    'spot.ply'
    >>> data_path("spot.ply").is_file()
    True
    """
    return Path(str(resources.files("hht3d") / "data" / name))


def load(path, *, clean: bool = True, laplacian: str = "cotan", n_neighbors: int = 30,
         name: str | None = None, storage_options: dict | None = None) -> Surface:
    """Load a triangle mesh or point cloud as a :class:`~hht3d.geometry.surface.Surface`.

    Parameters
    ----------
    path : str or Path
        PLY, OBJ, OFF, STL, GLB, GLTF (meshes); PLY, PCD, XYZ, XYZN, PTS (points);
        a local path or an fsspec URL (``s3://bucket/scan.ply``, :mod:`hht3d.io.storage`).
    clean : bool
        Weld duplicate vertices and drop degenerate/duplicate faces and
        unreferenced vertices (:mod:`hht3d.geometry.cleaning`); the report is in
        ``surface.clean_report``.
    laplacian, n_neighbors
        Passed to :class:`~hht3d.geometry.surface.Surface`.
    name : str, optional
        Defaults to the file stem.
    storage_options : dict, optional
        For a URL: options of its fsspec back-end (endpoint, region, ...).

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
    from .storage import is_url, load_url
    if is_url(path):  # object storage: through a temporary local copy
        return load_url(load, path, storage_options, clean=clean, laplacian=laplacian, n_neighbors=n_neighbors,
                        name=name)
    path = Path(path)
    try:
        is_dir, is_file = path.is_dir(), path.is_file()
    except OSError as exc:
        raise InputError(f"{_short(path)}: cannot read ({exc.strerror or one_line(exc)})") from None
    if is_dir:
        raise InputError(f"{path}: is a folder, not a mesh or point-cloud file; give one file "
                         "(pipeline inputs take folders)")
    if not is_file:
        raise InputError(f"{path}: no such file; check the path")
    _check_extension(path)
    ext = path.suffix.lower()
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
        surface = Surface.cleaned(**data, **options) if clean else Surface(**data, **options)
    except InputError as exc:
        raise InputError(f"{path}: {exc}") from None
    return surface


def _check_extension(path: Path) -> None:
    """Raise :class:`InputError` unless ``path`` has a mesh or point-cloud extension."""
    if path.suffix.lower() not in MESH_EXTENSIONS + POINT_CLOUD_EXTENSIONS:
        raise InputError(f"{path}: unknown extension {path.suffix.lower() or '(none)'!r}; meshes: "
                         f"{', '.join(MESH_EXTENSIONS)}; point clouds: {', '.join(POINT_CLOUD_EXTENSIONS)}")


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


@dataclass(frozen=True)
class PlyHeader:
    """What the header of a PLY file declares: element counts and vertex property names."""

    counts: dict
    vertex_properties: tuple[str, ...]


#: The longest PLY header :func:`read_ply_header` reads.
_MAX_HEADER = 1 << 20


def read_ply_header(path) -> PlyHeader:
    """The header of a PLY file, without reading its data (cheap for any file size).

    Raises
    ------
    InputError
        Not a PLY header (no ``ply`` line or no ``end_header`` in the first megabyte).
    """
    path = Path(path)
    counts, properties, element = {}, [], None
    try:
        with open(path, "rb") as handle:
            lines = handle.read(_MAX_HEADER).split(b"\n")
    except OSError as exc:
        raise InputError(f"{path}: cannot read ({exc.strerror or one_line(exc)})") from None
    if lines[0].strip() != b"ply":
        raise InputError(f"{path}: not a PLY file (it does not start with 'ply')")
    for line in lines[1:]:
        words = line.decode("ascii", "replace").split()
        if words[:1] == ["end_header"]:
            return PlyHeader(counts, tuple(properties))
        if words[:1] == ["element"] and len(words) == 3 and words[2].isdigit():
            element = words[1]
            counts[element] = int(words[2])
        elif words[:1] == ["property"] and element == "vertex" and len(words) >= 3:
            properties.append(words[-1])
    raise InputError(f"{path}: not a readable PLY file (no end_header)")


def read_npz_shapes(path) -> dict[str, tuple[int, ...]]:
    """The shape of every array in a ``.npz`` file, from the array headers alone (no data is read).

    Raises
    ------
    InputError
        Not a readable ``.npz`` file.
    """
    import zipfile

    path = Path(path)
    shapes = {}
    try:
        with zipfile.ZipFile(path) as archive:
            for name in archive.namelist():
                with archive.open(name) as member:
                    version = np.lib.format.read_magic(member)
                    read = (np.lib.format.read_array_header_1_0 if version == (1, 0)
                            else np.lib.format.read_array_header_2_0)
                    shapes[name.removesuffix(".npy")] = read(member)[0]
    except (OSError, ValueError, zipfile.BadZipFile) as exc:
        raise InputError(f"{path}: not a readable .npz file ({one_line(exc)})") from None
    return shapes


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


#: Serialises the redirection of the process's stdout/stderr (see :func:`_captured_native_output`).
_NATIVE_OUTPUT = threading.Lock()


@contextlib.contextmanager
def _captured_native_output():
    """Send what C and C++ code writes to file descriptors 1 and 2 to a temporary file, then drop it.

    Qhull (inside Open3D) prints warnings and 25-line error reports there,
    below Python's ``sys.stdout``/``sys.stderr``; its errors also reach
    Python as exceptions, which are reported instead.  The redirection is
    process-wide, so it is serialised by a lock and kept to the native call
    it wraps.
    """
    with _NATIVE_OUTPUT, tempfile.TemporaryFile() as sink:
        for stream in (sys.stdout, sys.stderr):
            with contextlib.suppress(Exception):
                stream.flush()
        try:
            saved = [os.dup(1), os.dup(2)]
        except OSError:  # no standard descriptors (a daemon): nothing can leak
            yield
            return
        try:
            os.dup2(sink.fileno(), 1)
            os.dup2(sink.fileno(), 2)
            yield
        finally:
            _flush_c_streams()
            for fd, copy in zip((1, 2), saved):
                os.dup2(copy, fd)
                os.close(copy)


def _flush_c_streams() -> None:
    """``fflush(NULL)``: write out C stdio buffers before the descriptors are restored."""
    import ctypes

    with contextlib.suppress(Exception):
        ctypes.CDLL(None).fflush(None)


@contextlib.contextmanager
def _quiet_open3d():
    """Open3D with its log at error level and its native output (Qhull's too) captured."""
    import open3d as o3d

    with o3d.utility.VerbosityContextManager(o3d.utility.VerbosityLevel.Error), _captured_native_output():
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
    on average (outward for closed scans).  A planar cloud (thinner than
    :data:`FLAT` times its extent, where Open3D's Delaunay step fails) gets
    the plane's normal everywhere, its largest component positive.

    Raises
    ------
    InputError
        The points lie on a line, or Open3D cannot orient the normals.
    """
    points = np.asarray(points, dtype=np.float64)
    centered = points - points.mean(axis=0)
    spread, axes = principal_axes(centered)
    if spread[2] <= FLAT * spread[0]:
        normal = axes[2] * np.sign(axes[2][np.argmax(np.abs(axes[2]))])
        return np.tile(normal, (len(points), 1))
    with _quiet_open3d() as o3d:
        try:
            pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
            pcd.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(knn=k))
            pcd.orient_normals_consistent_tangent_plane(k)
        except RuntimeError as exc:
            reason = one_line(str(exc).split("\n", 1)[0])
            raise InputError(f"cannot orient the point normals ({reason}); the cloud may be degenerate: "
                             "check it with `hht3d info`, or store normals (nx, ny, nz) in the file") from None
        normals = np.asarray(pcd.normals, dtype=np.float64)
    if np.einsum("ij,ij->", normals, centered) < 0:
        normals = -normals
    return normals


# -- writing -------------------------------------------------------------------------------
@contextlib.contextmanager
def atomic_path(path):
    """Yield a temporary path beside ``path``; rename it to ``path`` on success.

    On any exception the temporary file is removed and ``path`` is untouched.

    Raises
    ------
    OutputError
        The folder cannot be made, or writing failed (no permission, full
        disk, a folder in the way); names ``path`` and the reason.
    """
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".part", dir=path.parent)
    except OSError as exc:
        raise _cannot_write(path, exc) from None
    os.close(fd)
    try:
        yield Path(tmp)
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp creates 0600; match an ordinary write
        os.replace(tmp, path)
    except BaseException as exc:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        if isinstance(exc, OSError):
            raise _cannot_write(path, exc) from None
        raise


def _cannot_write(path: Path, exc: OSError) -> OutputError:
    return OutputError(f"{path}: cannot write ({exc.strerror or one_line(exc)}); free space, fix the "
                       "permissions or choose another output folder")


def check_output_paths(paths) -> None:
    """Check, creating nothing, that files can be written at ``paths`` (their folders may not exist yet).

    For each path: it must not be a folder; the nearest existing folder
    above it must be a folder (not a file such as ``/dev/full``) in which a
    probe (a temporary folder, made and removed at once) succeeds, which
    catches read-only and pseudo file systems (``/proc``) and missing
    permissions before anything is computed.

    Raises
    ------
    OutputError
        Naming the path, the folder at fault and the reason.
    """
    probed: set[Path] = set()
    for path in map(Path, paths):
        try:
            _check_output_path(path, probed)
        except OSError as exc:
            raise OutputError(f"{_short(path)}: cannot write ({exc.strerror or one_line(exc)}); choose another "
                              "output path") from None


def _check_output_path(path: Path, probed: set) -> None:
    """:func:`check_output_paths` of one path; ``probed`` holds the folders already found writable."""
    if path.is_dir():
        raise OutputError(f"{path}: cannot write: a folder of that name is in the way; remove it or change "
                          "the output path")
    existing = path.parent
    while not os.path.lexists(existing) and existing != existing.parent:
        existing = existing.parent
    if existing in probed:
        return
    if not existing.is_dir():
        raise OutputError(f"{path}: cannot write: {existing} is not a folder; choose another output folder")
    try:
        os.rmdir(tempfile.mkdtemp(prefix=".hht3d-probe-", dir=existing))
    except OSError as exc:
        raise OutputError(f"{path}: cannot write: creating anything in {existing} fails "
                          f"({exc.strerror or one_line(exc)}); choose another output folder") from None
    probed.add(existing)


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

    Folders and globs yield only the files with a mesh or point-cloud
    extension; a file named explicitly must have one.

    Raises
    ------
    InputError
        A named file is missing or has an unknown extension, or a folder/glob
        matches no usable file.
    """
    specs = [spec] if isinstance(spec, (str, Path)) else list(spec)
    found: list[Path] = []
    usable = set(MESH_EXTENSIONS + POINT_CLOUD_EXTENSIONS)
    for item in specs:
        text = str(item)
        try:
            matches = _input_files(text, usable)
        except OSError as exc:
            raise InputError(f"{_short(text)}: cannot read ({exc.strerror or one_line(exc)})") from None
        if not matches:
            raise InputError(f"{text}: matches no mesh or point-cloud file "
                             f"({', '.join(sorted(usable))})")
        found.extend(matches)
    return list(dict.fromkeys(found))


def _input_files(text: str, usable) -> list[Path]:
    """The usable files of one input spec: a folder's, a glob's, or the named file."""
    import glob

    path = Path(text)
    if path.is_dir():
        return sorted(p for p in path.iterdir() if p.suffix.lower() in usable and p.is_file())
    if any(ch in text for ch in "*?["):
        return sorted(p for p in map(Path, glob.glob(text, recursive=True)) if p.suffix.lower() in usable
                      and p.is_file())
    if path.is_file():
        _check_extension(path)
        return [path]
    raise InputError(f"{text}: no such file or folder")


def _short(path) -> str:
    """A path for a message, cut if absurdly long."""
    return one_line(path, MAX_SHOWN)
