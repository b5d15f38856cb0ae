"""Writing surfaces and their fields (hht3d.io.write): PLY round trips, colour-mapped PLYs."""

import numpy as np

from helpers.meshes import icosphere
from hht3d import Surface, load
from hht3d.io import write_colored_ply, write_ply


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
