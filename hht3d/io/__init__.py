"""Reading and writing surfaces and result arrays, and where files may be read and written.

* :mod:`~hht3d.io.read` — meshes, point clouds, PLY and NPZ headers;
* :mod:`~hht3d.io.write` — PLY, NPZ and coloured PLY writers;
* :mod:`~hht3d.io.headers` — what PLY and PCD headers declare, checked before reading;
* :mod:`~hht3d.io.las` — LAS/LAZ point clouds through laspy (the ``lidar`` extra);
* :mod:`~hht3d.io.e57` — E57 scans through pye57 (the ``e57`` extra);
* :mod:`~hht3d.io.mesh_files` — VTU/VTP writers and the meshio formats (the ``meshio`` extra);
* :mod:`~hht3d.io.open3d` — conversion to and from Open3D geometries;
* :mod:`~hht3d.io.pyvista` — conversion to and from PyVista datasets, when PyVista is installed;
* :mod:`~hht3d.io.formats` — readable extensions, regular-file and property-name checks, name limits;
* :mod:`~hht3d.io.references` — files a glTF or OBJ refers to, confined to its folder;
* :mod:`~hht3d.io.paths` — output confinement, file-name checks, input expansion;
* :mod:`~hht3d.io.atomic` — atomic writes and their stale temporary files;
* :mod:`~hht3d.io.manifest` — what hht3d wrote in an output folder (overwrite and resume rules);
* :mod:`~hht3d.io.lock` — the lock an output folder's runs share;
* :mod:`~hht3d.io.url_lock` — the lock a URL output folder's run holds, where the store writes conditionally;
* :mod:`~hht3d.io.folder` — an output folder's rules, local (manifest, lock, confinement) or URL;
* :mod:`~hht3d.io.storage` — fsspec URLs (``s3://``, ``gs://``, ...): locations, back-ends, listing, reading;
* :mod:`~hht3d.io.uploads` — writing to them: atomic uploads, conditional updates, the check before a run.
"""

from ..geometry.normals import estimate_point_normals
from . import storage, uploads
from .atomic import atomic_path, check_output_paths, remove_stale_parts
from .formats import MESH_EXTENSIONS, POINT_CLOUD_EXTENSIONS, check_regular_file
from .las import write_las
from .manifest import check_overwrites, is_recorded, new_run_id, record
from .open3d import surface_from_open3d, surface_to_open3d
from .paths import check_name, check_output_location, confined, resolve_inputs
from .pyvista import surface_from_pyvista, surface_to_pyvista
from .read import LoadOptions, PlyHeader, data_path, load, read_npz, read_npz_shapes, read_ply_header
from .write import field_colors, write_colored_ply, write_npz, write_ply

__all__ = [
    "MESH_EXTENSIONS",
    "POINT_CLOUD_EXTENSIONS",
    "data_path",
    "load",
    "LoadOptions",
    "PlyHeader",
    "read_ply_header",
    "read_npz",
    "read_npz_shapes",
    "surface_from_open3d",
    "surface_to_open3d",
    "surface_from_pyvista",
    "surface_to_pyvista",
    "estimate_point_normals",
    "atomic_path",
    "check_output_paths",
    "remove_stale_parts",
    "check_regular_file",
    "check_overwrites",
    "is_recorded",
    "new_run_id",
    "record",
    "check_name",
    "check_output_location",
    "confined",
    "write_ply",
    "write_las",
    "write_npz",
    "field_colors",
    "write_colored_ply",
    "resolve_inputs",
]
