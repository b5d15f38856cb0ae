"""Saved results read back (hht3d.results.load_result)."""

import numpy as np
import pytest

from hht3d import InputError


def test_load_result_gives_back_the_saved_result(tmp_path):
    """load_result is the partner of HHTResult.save: every array, the spectrum and the quality
    figures come back exactly (the surface is rebuilt with the saved normals and Laplacian)."""
    from hht3d import data_path, hht, load, load_result
    from hht3d.geometry.signals import mean_curvature

    spot = load(data_path("spot.ply"))
    result = hht(spot, mean_curvature(spot), max_imfs=3)
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


def test_load_result_names_the_arrays_a_file_lacks(tmp_path):
    from hht3d import load_result

    np.savez(tmp_path / "x.npz", vertices=np.zeros((3, 3)), signal=np.zeros(3))
    with pytest.raises(InputError, match="no normals, laplacian, n_neighbors, imfs, .*, area; expected a file"):
        load_result(tmp_path / "x.npz")


def test_a_result_saved_without_its_origin_reads_back_at_the_origin(tmp_path):
    """Files of HHTResult.save from before the origin was stored read back with the origin 0."""
    from hht3d import data_path, hht, load, load_result
    from hht3d.geometry.signals import mean_curvature

    spot = load(data_path("spot.ply"))
    spot.origin = np.array([5e5, 5.4e6, 0.0])
    arrays = dict(np.load(hht(spot, mean_curvature(spot), max_imfs=1).save(tmp_path / "new.npz")))
    np.testing.assert_array_equal(load_result(tmp_path / "new.npz").surface.origin, spot.origin)
    del arrays["origin"]
    np.savez(tmp_path / "old.npz", **arrays)
    np.testing.assert_array_equal(load_result(tmp_path / "old.npz").surface.origin, np.zeros(3))
