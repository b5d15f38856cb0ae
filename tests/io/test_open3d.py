"""Open3D geometries to and from surfaces (hht3d.io.open3d)."""

import numpy as np
import open3d as o3d

from hht3d.io import surface_from_open3d, surface_to_open3d


def test_open3d_geometries(sphere):
    legacy = o3d.geometry.TriangleMesh(
        o3d.utility.Vector3dVector(sphere.vertices), o3d.utility.Vector3iVector(sphere.faces)
    )
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
