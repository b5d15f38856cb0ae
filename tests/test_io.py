"""Loading, cleaning, clear errors on bad input, and attribute round trips."""
import numpy as np
import open3d as o3d
import pytest
from scipy.spatial import cKDTree

from hht3d import InputError, Surface, load
from hht3d.errors import OutputError
from hht3d.io import (atomic_path, surface_from_open3d, surface_to_open3d, check_output_paths, read_npz_shapes, read_ply_header, write_colored_ply, write_npz,
                      write_ply)
from helpers.meshes import gltf_to_glb, icosphere


@pytest.fixture
def sphere():
    return Surface(*icosphere(2), name="sphere")


def test_ply_attributes_round_trip(tmp_path, sphere):
    values = {"imf_1": np.sin(sphere.vertices[:, 0]), "amplitude.2": np.arange(sphere.n_vertices) / 7}
    path = write_ply(tmp_path / "out.ply", sphere, values)
    back = load(path, clean=False)
    assert back.n_vertices == sphere.n_vertices and np.array_equal(back.faces, sphere.faces)
    assert set(back.attributes) == set(values)
    for key, v in values.items():
        np.testing.assert_array_equal(back.attributes[key], v)  # float64 on disk: bit-exact
    np.testing.assert_array_equal(back.vertices, sphere.vertices)


def test_point_cloud_ply_round_trip(tmp_path):
    cloud = Surface(icosphere(2)[0])
    back = load(write_ply(tmp_path / "pc.ply", cloud, {"f": cloud.vertices[:, 2]}), clean=False)
    assert not back.is_mesh
    np.testing.assert_array_equal(back.attributes["f"], cloud.vertices[:, 2])
    np.testing.assert_array_equal(back.vertices, cloud.vertices)
    # written, not re-estimated (estimates differ by ~1e-2); renormalised on load: a few ulps
    np.testing.assert_allclose(back.normals, cloud.normals, rtol=0, atol=1e-15)


def canonical_faces(faces) -> set:
    """Faces as a set of index triples rotated to start at their smallest index (orientation kept)."""
    faces = np.asarray(faces)
    start = np.argmin(faces, axis=1)
    return {tuple(np.roll(face, -k)) for face, k in zip(faces.tolist(), start)}


#: Largest position error each format allows for coordinates in [-1, 1]: text with 6 decimals
#: (half a unit of 1e-6 per coordinate, times √3), float32 (2^-24 relative per coordinate, times
#: √3), or Open3D's 10-decimal text.
POSITION_ATOL = {".obj": 8.7e-7, ".off": 8.7e-7, ".stl": 1.1e-7, ".gltf": 1.1e-7, ".glb": 1.1e-7,
                 ".pcd": 1.1e-7, ".xyz": 1e-9, ".xyzn": 1e-9, ".pts": 1e-9}


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


def test_open3d_geometries(sphere):
    legacy = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(sphere.vertices),
                                       o3d.utility.Vector3iVector(sphere.faces))
    from_legacy = surface_from_open3d(legacy)
    np.testing.assert_array_equal(from_legacy.vertices, sphere.vertices)  # float64 in memory: exact
    np.testing.assert_array_equal(from_legacy.faces, sphere.faces)
    tensor = surface_to_open3d(sphere, {"signal": sphere.vertices[:, 0]})
    back = surface_from_open3d(tensor, clean=False)
    np.testing.assert_array_equal(back.attributes["signal"], sphere.vertices[:, 0])
    np.testing.assert_array_equal(back.vertices, sphere.vertices)
    np.testing.assert_array_equal(back.faces, sphere.faces)
    cloud = surface_from_open3d(o3d.t.geometry.PointCloud(o3d.core.Tensor(sphere.vertices)))
    assert not cloud.is_mesh
    np.testing.assert_array_equal(cloud.vertices, sphere.vertices)


def test_cleaning_reports_and_maps_attributes():
    v, f = icosphere(1)
    n = len(v)
    # append: an unreferenced vertex, a duplicate of vertex 0 used by a copied face,
    # a degenerate face and a duplicated face
    v2 = np.vstack([v, [[9, 9, 9]], v[[0]]])
    f2 = np.vstack([f, [[n + 1, f[0, 1], f[0, 2]]], [[1, 1, 2]], f[[5]]])
    surface = Surface.cleaned(v2, f2, attributes={"id": np.arange(len(v2), dtype=float)})
    r = surface.clean_report
    assert (r.merged_duplicate_vertices, r.removed_degenerate_faces) == (1, 1)
    assert r.removed_duplicate_faces == 2  # the copied face (after welding) and f[5]
    assert r.removed_unreferenced_vertices == 1
    assert surface.n_vertices == n and len(surface.faces) == len(f)
    np.testing.assert_array_equal(surface.attributes["id"], np.arange(n))
    assert r.original_to_new[n + 1] == 0 and r.original_to_new[n] == -1


def test_real_scan_cleaning(shared_model):
    # MANIFEST: 1,113 unreferenced vertices in the Stanford bunny; 2,100
    # duplicate positions and 108 zero-area faces in the dragon
    bunny = load(shared_model("bunny_zipper.ply"))
    assert bunny.clean_report.removed_unreferenced_vertices == 1113
    assert bunny.n_vertices == 35947 - 1113


@pytest.mark.parametrize("make, message", [
    (lambda p: p / "missing.ply", "no such file"),
    (lambda p: (p / "m.dae").write_text("x") and p / "m.dae", "unknown extension"),
    (lambda p: (p / "bad.ply").write_bytes(b"ply\nformat nonsense\n") and p / "bad.ply", "not a readable PLY"),
    (lambda p: (p / "e.xyz").write_text("") or p / "e.xyz", "no vertices"),
])
def test_bad_files_give_one_clear_error(tmp_path, make, message):
    path = make(tmp_path)
    with pytest.raises(InputError, match=message) as info:
        load(path)
    assert str(path.name) in str(info.value)


def test_bad_arrays_give_clear_errors():
    v, f = icosphere(1)
    with pytest.raises(InputError, match="at least 4"):
        Surface(v[:3])
    bad = v.copy()
    bad[2, 1] = np.nan
    with pytest.raises(InputError, match="NaN"):
        Surface(bad, f)
    with pytest.raises(InputError, match="face indices"):
        Surface(v, f + 100)
    with pytest.raises(InputError, match="shape"):
        Surface(v[:, :2])


def _current_umask() -> int:
    import os

    mask = os.umask(0)
    os.umask(mask)
    return mask


def test_atomic_write_leaves_nothing_on_failure(tmp_path):
    target = tmp_path / "x.npz"
    with pytest.raises(RuntimeError):
        with atomic_path(target) as tmp:
            tmp.write_bytes(b"partial")
            raise RuntimeError("boom")
    assert list(tmp_path.iterdir()) == []
    write_npz(target, {"a": np.arange(3)})
    assert np.load(target)["a"].tolist() == [0, 1, 2]
    assert target.stat().st_mode & 0o777 == 0o666 & ~_current_umask()  # like an ordinary write


def test_colored_ply_uses_colormap(tmp_path, sphere):
    import matplotlib

    z = sphere.vertices[:, 2]
    path = write_colored_ply(tmp_path / "c.ply", sphere, z, name="height", limits=(-0.5, 0.5), cmap="magma")
    back = load(path, clean=False)
    np.testing.assert_array_equal(back.attributes["height"], z)
    # the colours are matplotlib's magma of the clipped, normalised values, stored as 8-bit
    # channels: within half a step (0.5/255) of the exact colour
    expected = matplotlib.colormaps["magma"](np.clip(z + 0.5, 0, 1))[:, :3]
    np.testing.assert_allclose(back.colors, expected, rtol=0, atol=0.5 / 255 + 1e-12)
    # default limits: the 1st and 99th percentile
    default = load(write_colored_ply(tmp_path / "d.ply", sphere, z), clean=False)
    lo, hi = np.percentile(z, [1, 99])
    expected = matplotlib.colormaps["viridis"](np.clip((z - lo) / (hi - lo), 0, 1))[:, :3]
    np.testing.assert_allclose(default.colors, expected, rtol=0, atol=0.5 / 255 + 1e-12)


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


def test_output_paths_are_probed_without_leaving_anything(tmp_path):
    (tmp_path / "file").write_text("x")
    (tmp_path / "dir.npz").mkdir()
    check_output_paths([tmp_path / "new" / "deeper" / "a.npz", tmp_path / "b.npz"])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dir.npz", "file"]
    for path, message in [(tmp_path / "file" / "a.npz", "file is not a folder"),
                          (tmp_path / "dir.npz", "a folder of that name is in the way"),
                          (tmp_path / ("x" * 300) / "a.npz", "File name too long")]:
        with pytest.raises(OutputError, match=message):
            check_output_paths([path])


def test_planar_point_clouds_get_the_plane_normal_and_no_qhull_output(capfd):
    rng = np.random.default_rng(0)
    rotation = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    plane = np.c_[rng.uniform(size=(300, 2)), np.zeros(300)] @ rotation.T
    normals = Surface(plane, name="plane").normals
    np.testing.assert_allclose(np.abs(normals @ rotation[:, 2]), 1.0, atol=1e-12)
    nearly = np.c_[rng.uniform(size=(300, 2)), 1e-12 * rng.normal(size=300)]
    assert np.abs(Surface(nearly, name="nearly").normals[:, 2]).min() > 0.999  # Qhull warns here
    assert capfd.readouterr() == ("", "")
    with pytest.raises(InputError, match="line: the 50 points lie on a line"):
        Surface(np.c_[np.arange(50.0), np.zeros(50), np.zeros(50)], name="line")


@pytest.mark.parametrize("build", [Surface, Surface.cleaned])
def test_point_clouds_built_from_arrays_are_checked_as_files_are(build):
    # before any operator: robust_laplacian would abort on these with a C++ assertion
    line = np.c_[np.linspace(0, 1, 50), np.zeros(50), np.zeros(50)]
    with pytest.raises(InputError, match="the 50 points lie on a line"):
        build(line, name="line")
    few = np.random.default_rng(2).normal(size=(10, 3))
    with pytest.raises(InputError, match="10 points cannot give each point n_neighbors=30 neighbours"):
        build(few, name="few")
    assert build(few, name="few", n_neighbors=5).n_vertices == 10


def test_load_result_gives_back_the_saved_result(tmp_path):
    """load_result is the partner of HHTResult.save: every array, the spectrum and the quality
    figures come back exactly (the surface is rebuilt with the saved normals and Laplacian)."""
    from hht3d import data_path, hht, load, load_result
    from hht3d.geometry.signals import mean_curvature

    spot = load(data_path("spot.ply"))
    result = hht(spot, mean_curvature(spot), emd={"max_imfs": 3})
    again = load_result(result.save(tmp_path / "spot_hht.npz"))
    for name in ("signal", "imfs", "residue"):
        np.testing.assert_array_equal(getattr(again, name), getattr(result, name))
    for name in ("riesz", "amplitude", "phase", "frequency"):
        np.testing.assert_array_equal(getattr(again.monogenic, name), getattr(result.monogenic, name))
    np.testing.assert_array_equal(again.surface.faces, spot.faces)
    np.testing.assert_allclose(again.surface.mass_diagonal, spot.mass_diagonal, rtol=1e-12)
    assert again.quality.energy_ratio == pytest.approx(result.quality.energy_ratio, rel=1e-12)
    np.testing.assert_allclose(again.spectrum.mean_frequency(), result.spectrum.mean_frequency(), rtol=1e-12)
    with pytest.raises(InputError, match="Riesz"):
        load_result(result.save(tmp_path / "spot_hht.ply"))
