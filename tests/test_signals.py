"""Signals against differential geometry: mean and Gaussian curvature on spheres."""
import numpy as np
import pytest

from hht3d import InputError, Surface, load, signals
from meshes import fibonacci_sphere, grid, icosphere


def test_mean_curvature_on_unit_sphere_is_two():
    # s = n · M⁻¹LV = 2H = 2 on the unit sphere with outward normals (sign documented)
    s = signals.mean_curvature(Surface(*icosphere(5)))
    np.testing.assert_allclose(s, 2.0, rtol=0.02)


def test_mean_curvature_scales_inversely_with_radius():
    s = signals.mean_curvature(Surface(*icosphere(4, radius=3.0)))
    np.testing.assert_allclose(s, 2.0 / 3.0, rtol=0.02)


def test_mean_curvature_on_point_cloud_sphere():
    s = signals.mean_curvature(Surface(fibonacci_sphere(8000)))
    assert np.median(s) == pytest.approx(2.0, rel=0.02)


@pytest.mark.parametrize("model", ["sphere_oct4098.ply", "spot.ply", "nefertiti.ply"])
def test_gauss_bonnet_on_closed_genus0_models(shared_model, model):
    surface = load(shared_model(model))
    k = signals.gaussian_curvature(surface)
    assert np.sum(k * surface.mass_diagonal) == pytest.approx(4 * np.pi, abs=1e-8)


def test_gauss_bonnet_genus1(shared_model):
    surface = load(shared_model("rocker_arm.ply"))
    k = signals.gaussian_curvature(surface)
    assert abs(np.sum(k * surface.mass_diagonal)) < 1e-8  # χ = 0


def test_gauss_bonnet_disk_with_boundary():
    # flat disk-like grid: χ = 1, all curvature is at the boundary (turning angles)
    surface = Surface(*grid(8, 5))
    k = signals.gaussian_curvature(surface)
    assert np.sum(k * surface.mass_diagonal) == pytest.approx(2 * np.pi, abs=1e-10)
    np.testing.assert_allclose(k[~surface.boundary_vertices], 0, atol=1e-12)


def test_centroid_distance_and_coordinates():
    surface = Surface(*icosphere(3, radius=2.0))
    np.testing.assert_allclose(signals.centroid_distance(surface), 2.0, rtol=1e-12)
    np.testing.assert_array_equal(signals.signal(surface, "z"), surface.vertices[:, 2])


def test_luminance_uses_rec709_weights():
    v, f = icosphere(1)
    colors = np.tile([1.0, 0.0, 0.0], (len(v), 1))
    assert signals.luminance(Surface(v, f, colors=colors))[0] == pytest.approx(0.2126)


def test_bad_user_signals_are_refused(tmp_path):
    surface = Surface(*icosphere(1))
    with pytest.raises(InputError, match="shape"):
        signals.check_signal(surface, np.zeros(5))
    bad = np.zeros(surface.n_vertices)
    bad[3] = np.nan
    with pytest.raises(InputError, match="NaN.*vertex 3"):
        signals.check_signal(surface, bad)
    path = tmp_path / "s.npy"
    np.save(path, np.arange(surface.n_vertices, dtype=float))
    assert signals.signal(surface, "file", path=path)[7] == 7.0
    with pytest.raises(InputError, match="unknown signal"):
        signals.signal(surface, "curvy")
    with pytest.raises(InputError, match="colours"):
        signals.luminance(surface)
    with pytest.raises(InputError, match="needs a triangle mesh"):
        signals.gaussian_curvature(Surface(fibonacci_sphere(100)))
