"""Reading and writing surfaces and results (PLY, NPZ and Open3D's formats)."""
from .read import (MESH_EXTENSIONS, POINT_CLOUD_EXTENSIONS, data_path, load, PlyHeader, read_ply_header,
                   read_npz_shapes, surface_from_open3d, surface_to_open3d, estimate_point_normals,
                   atomic_path, check_output_paths, write_ply, write_npz, field_colors, write_colored_ply,
                   resolve_inputs)
