"""Loading files (hht3d.io.read): every format Open3D writes, one clear error per bad file, headers read
without the data."""

import numpy as np
import open3d as o3d
import pytest
from scipy.spatial import cKDTree

from helpers.meshes import gltf_to_glb, icosphere
from hht3d import InputError, load
from hht3d.io import read_npz_shapes, read_ply_header, write_npz, write_ply


def canonical_faces(faces) -> set:
    """Faces as a set of index triples rotated to start at their smallest index (orientation kept)."""
    faces = np.asarray(faces)
    start = np.argmin(faces, axis=1)
    return {tuple(np.roll(face, -k)) for face, k in zip(faces.tolist(), start)}


#: Largest position error each format allows for coordinates in [-1, 1]: text with 6 decimals
#: (half a unit of 1e-6 per coordinate, times √3), float32 (2^-24 relative per coordinate, times
#: √3), or Open3D's 10-decimal text.
POSITION_ATOL = {
    ".obj": 8.7e-7,
    ".off": 8.7e-7,
    ".stl": 1.1e-7,
    ".gltf": 1.1e-7,
    ".glb": 1.1e-7,
    ".pcd": 1.1e-7,
    ".xyz": 1e-9,
    ".xyzn": 1e-9,
    ".pts": 1e-9,
}


@pytest.mark.parametrize("ext", [".obj", ".off", ".stl", ".gltf", ".glb"])
def test_open3d_mesh_formats(tmp_path, ext):
    v, f = icosphere(2)
    mesh = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(v), o3d.utility.Vector3iVector(f))
    mesh.compute_vertex_normals()
    path = tmp_path / f"m{ext}"
    assert o3d.io.write_triangle_mesh(str(path.with_suffix(".gltf" if ext == ".glb" else ext)), mesh)
    if ext == ".glb":
        gltf_to_glb(path.with_suffix(".gltf"), path)
    surface = load(path)
    # STL stores one vertex per corner: cleaning welds them back to the original count.  The order
    # may change: match every vertex to its nearest loaded one, then compare the faces through
    # that map, orientation included.
    assert surface.n_vertices == len(v) and len(surface.faces) == len(f)
    distance, index = cKDTree(surface.vertices).query(v)
    assert distance.max() <= POSITION_ATOL[ext]
    assert len(set(index)) == len(v)
    assert canonical_faces(index[f]) == canonical_faces(surface.faces)


@pytest.mark.parametrize("ext", [".pcd", ".xyz", ".xyzn", ".pts"])
def test_open3d_point_formats(tmp_path, ext):
    pts = icosphere(2)[0]
    pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(pts))
    pcd.normals = o3d.utility.Vector3dVector(pts)
    path = str(tmp_path / f"p{ext}")
    assert o3d.io.write_point_cloud(path, pcd)
    surface = load(path)
    assert not surface.is_mesh and surface.n_vertices == len(pts)
    np.testing.assert_allclose(surface.vertices, pts, rtol=0, atol=POSITION_ATOL[ext])
    if ext in (".pcd", ".xyzn"):  # formats that store normals: they are read, not re-estimated
        np.testing.assert_allclose(surface.normals, pts, rtol=0, atol=POSITION_ATOL[ext])


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda p: p / "missing.ply", "no such file"),
        (lambda p: (p / "m.dae").write_text("x") and p / "m.dae", "unknown extension"),
        (lambda p: (p / "bad.ply").write_bytes(b"ply\nformat nonsense\n") and p / "bad.ply", "not a readable PLY"),
        (lambda p: (p / "e.xyz").write_text("") or p / "e.xyz", "no vertices"),
    ],
)
def test_bad_files_give_one_clear_error(tmp_path, make, message):
    path = make(tmp_path)
    with pytest.raises(InputError, match=message) as info:
        load(path)
    assert str(path.name) in str(info.value)


def test_headers_give_sizes_without_the_data(tmp_path, sphere):
    write_ply(tmp_path / "s.ply", sphere, {"height": sphere.vertices[:, 2]})
    header = read_ply_header(tmp_path / "s.ply")
    assert header.counts == {"vertex": 162, "face": 320} and header.vertex_properties[-1] == "height"
    write_npz(tmp_path / "s.npz", {"imfs": np.zeros((3, 162)), "faces": sphere.faces})
    assert read_npz_shapes(tmp_path / "s.npz") == {"imfs": (3, 162), "faces": (320, 3)}
    with pytest.raises(InputError, match="not a PLY file"):
        read_ply_header(tmp_path / "s.npz")
    with pytest.raises(InputError, match="not a readable .npz file"):
        read_npz_shapes(tmp_path / "s.ply")


# -- headers that declare more than the file holds (resource bombs) ----------------------------------
def _ply(path, header_lines, body=b""):
    path.write_bytes(("\n".join(["ply", *header_lines, "end_header"]) + "\n").encode() + body)
    return path


@pytest.mark.parametrize(
    "name, header, message",
    [
        (
            "many properties",
            ["format ascii 1.0", "element vertex 1", *(f"property float p{i}" for i in range(20_000))],
            "declares 20,000 properties; at most 10,000",
        ),
        (
            "a billion vertices",
            [
                "format binary_little_endian 1.0",
                "element vertex 1000000000",
                "property float x",
                "property float y",
                "property float z",
            ],
            "more than its",
        ),
        (
            "a header over 1 MiB",
            ["format ascii 1.0", "element vertex 1", *(f"property float p{i}" for i in range(100_000))],
            "no end_header",
        ),
    ],
)
def test_a_ply_header_is_bounded_before_the_data_is_read(tmp_path, name, header, message):
    """Refused in one line from the header alone (the reader would build a dtype of every property,
    or allocate every declared vertex); a header longer than 1 MiB is not read to its end."""
    with pytest.raises(InputError, match=message):
        load(_ply(tmp_path / "bomb.ply", header))


def test_a_pcd_declaring_a_trillion_points_is_refused(tmp_path):
    path = tmp_path / "bomb.pcd"
    path.write_text(
        "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
        "WIDTH 1000000000000\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1000000000000\nDATA ascii\n0 0 0\n"
    )
    with pytest.raises(InputError, match="declares 1,000,000,000,000 vertices"):
        load(path)


def test_a_path_with_a_nul_is_an_input_error():
    with pytest.raises(InputError, match="NUL character"):
        load("scan\0.ply")


@pytest.mark.parametrize("byte_order", ["<", ">"])
def test_a_triangle_ply_read_at_once_matches_plyfiles_face_by_face_reader(tmp_path, byte_order):
    """All-triangle faces are read as one (f, 3) array (plyfile maps them); the oracle is plyfile's
    general reader, which parses each face's list.  Nothing returned maps the file."""
    from plyfile import PlyData

    from helpers.bad_files import _ply

    v, f = icosphere(3)
    path = tmp_path / "sphere.ply"
    _ply(path, v, f, index="u4", byte_order=byte_order)
    surface = load(path, clean=False)
    reference = PlyData.read(str(path), mmap=False)["face"].data["vertex_indices"]
    np.testing.assert_array_equal(surface.faces, np.vstack(reference))
    np.testing.assert_array_equal(surface.vertices, v)
    assert surface.faces.flags.owndata and surface.vertices.flags.owndata
