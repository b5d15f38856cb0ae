"""Normals of point clouds (hht3d.geometry.normals): planar clouds get the plane's normal, without Qhull output."""

import numpy as np
import pytest

from hht3d import InputError, Surface


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
