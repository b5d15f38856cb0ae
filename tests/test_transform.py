"""hht(): EMD + Hilbert spectra in one call, saving and Open3D export."""

from __future__ import annotations

import numpy as np
import pytest

import hht3d
from helpers.meshes import fibonacci_sphere, icosphere
from hht3d.errors import InputError
from hht3d.geometry.surface import Surface
from hht3d.transform import FIELDS, IMF_FIELDS, RESULT_ARRAYS, HHTResult, field_imf, hht


def two_scale_signal(vertices):
    x, y, z = vertices.T
    return np.cos(12 * np.arctan2(y, x)) * (1 - z**2) + 0.5 * z + 0.2 * x * y


@pytest.fixture(scope="module")
def result() -> HHTResult:
    s = Surface(*icosphere(4))
    return hht(s, two_scale_signal(s.vertices), max_imfs=3)


def test_decomposition_and_spectra(result):
    n = result.surface.n_vertices
    assert 1 <= result.n_imfs <= 3
    assert result.imfs.shape == (result.n_imfs, n) and result.residue.shape == (n,)
    scale = np.abs(result.signal).max()
    assert np.allclose(result.imfs.sum(0) + result.residue, result.signal, atol=1e-12 * scale)
    assert np.allclose(result.monogenic.reconstruct() + result.residue, result.signal, atol=1e-12 * scale)
    assert result.monogenic.frequency.shape == (result.n_imfs, n)
    # the first IMF carries the 12-fold azimuthal wave: frequency 12/sin(polar) ∈ [12, 12.6] near
    # the equator; at ~7 vertices per period the vertex gradients read ≈ (kh)²/6 ≈ 10% low
    equator = np.abs(result.surface.vertices[:, 2]) < 0.3
    median = np.median(result.monogenic.frequency[0, equator])
    assert 10 < median < 14
    spectrum = result.spectrum
    assert spectrum.mean_frequency().shape == (result.n_imfs,)
    assert result.info["riesz"]["potential"] == "quadrature"
    assert set(result.info["seconds"]) == {"emd", "spectra"}


def test_save_ply_round_trip(result, tmp_path):
    path = result.save(tmp_path / "out.ply")
    back = hht3d.load(path, clean=False)
    expected = result.vertex_attributes()
    assert {"signal", "residue", "imf_1", "amplitude_1", "phase_1", "frequency_1"} <= set(back.attributes)
    for key, values in expected.items():
        assert np.array_equal(back.attributes[key], values)
    assert np.array_equal(back.faces, result.surface.faces)


def test_save_npz(result, tmp_path):
    path = result.save(tmp_path / "out.npz")
    with np.load(path) as data:
        assert np.array_equal(data["imfs"], result.imfs)
        assert np.array_equal(data["riesz"], result.monogenic.riesz)
        assert np.array_equal(data["faces"], result.surface.faces)
        assert data["area"].sum() == pytest.approx(4 * np.pi, rel=0.01)


def test_fields_and_arrays_are_declared_once(result, tmp_path):
    """The fields are FIELDS, then one per kind of IMF_FIELDS for every IMF, which field_imf reads back;
    the .npz holds arrays(): RESULT_ARRAYS, then the faces."""
    imfs = range(1, result.n_imfs + 1)
    names = list(result.vertex_attributes())
    assert names == [*FIELDS, *(f"{kind}_{k}" for k in imfs for kind in IMF_FIELDS)]
    assert [field_imf(name) for name in names] == [None] * len(FIELDS) + [k for k in imfs for _ in IMF_FIELDS]
    with np.load(result.save(tmp_path / "out.npz")) as data:
        assert data.files == list(result.arrays()) == [*RESULT_ARRAYS, "faces"]


def test_save_rejects_unknown_format(result, tmp_path):
    with pytest.raises(InputError, match=".ply or .npz"):
        result.save(tmp_path / "out.vtk")
    assert not list(tmp_path.iterdir())


def test_to_open3d_mesh(result):
    mesh = result.to_open3d()
    assert "imf_1" in mesh.vertex and "frequency_1" in mesh.vertex
    assert np.array_equal(mesh.vertex["amplitude_1"].numpy()[:, 0], result.monogenic.amplitude[0])
    assert mesh.triangle["indices"].shape[0] == len(result.surface.faces)


def test_point_cloud_to_open3d():
    s = Surface(fibonacci_sphere(800), None)
    r = hht(s, two_scale_signal(s.vertices), max_imfs=1)
    cloud = r.to_open3d()
    assert "phase_1" in cloud.point
    assert np.array_equal(cloud.point["imf_1"].numpy()[:, 0], r.imfs[0])


def test_constant_signal_has_no_imfs():
    s = Surface(*icosphere(2))
    r = hht(s, np.full(s.n_vertices, 2.0))
    assert r.n_imfs == 0 and np.allclose(r.residue, 2.0)
    assert r.monogenic.amplitude.shape == (0, s.n_vertices)
    assert set(r.vertex_attributes()) == {"signal", "residue"}


@pytest.mark.parametrize("frequency", ["phase", "gradient"])
def test_hht_settings_reach_every_stage(frequency):
    """hht's Riesz record is the one the monogenic stage uses: its frequencies equal
    monogenic() of the same IMFs with the same settings, and the two estimators differ."""
    from hht3d import data_path, load, monogenic
    from hht3d.geometry.signals import mean_curvature

    spot = load(data_path("spot.ply"))
    result = hht(spot, mean_curvature(spot), max_imfs=2, frequency=frequency, gradient="fem")
    direct = monogenic(spot, result.imfs, frequency=frequency, gradient="fem")
    np.testing.assert_allclose(result.monogenic.frequency, direct.frequency, rtol=0, atol=1e-9 * direct.frequency.max())
    other = monogenic(spot, result.imfs, frequency="gradient" if frequency == "phase" else "phase", gradient="fem")
    assert np.abs(other.frequency - direct.frequency).max() > 0.1 * direct.frequency.max()
    assert result.info["riesz"]["frequency"] == frequency


def test_record_field_names_are_disjoint():
    """hht's flat settings are routed by name: no two records of an HHT declare the same one."""
    from hht3d.decomposition import EMDOptions, EnsembleOptions
    from hht3d.hht_options import PARTS
    from hht3d.spectral import RieszOptions

    names = [name for record in (EMDOptions, RieszOptions, EnsembleOptions) for name in record.specs()]
    assert len(names) == len(set(names))
    assert set(PARTS.values()) == {EMDOptions, RieszOptions, EnsembleOptions}


def test_one_call_shape_and_the_former_keywords():
    """Flat settings, HHTOptions and a dict of parts give one result; emd=/riesz=/ensemble= warn."""
    from hht3d.decomposition import EMDOptions
    from hht3d.spectral import RieszOptions
    from hht3d.transform import HHTOptions

    surface = Surface(*icosphere(2))
    f = surface.vertices[:, 0] + 0.3 * surface.vertices[:, 1] ** 3
    flat = hht(surface, f, max_imfs=1, tol=1e-6)
    record = hht(surface, f, HHTOptions(emd=EMDOptions(max_imfs=1), riesz=RieszOptions(tol=1e-6)))
    parts = hht(surface, f, {"emd": {"max_imfs": 1}, "riesz": {"tol": 1e-6}})
    with pytest.warns(DeprecationWarning, match="hht\\(emd=, riesz=\\) is deprecated"):
        former = hht(surface, f, emd={"max_imfs": 1}, riesz={"tol": 1e-6})
    for other in (record, parts, former):
        np.testing.assert_array_equal(other.imfs, flat.imfs)
        np.testing.assert_array_equal(other.monogenic.frequency, flat.monogenic.frequency)
    assert HHTOptions.of(ensemble_size=3).ensemble.ensemble_size == 3
    assert HHTOptions.of(max_imfs=2).ensemble is None
    with pytest.raises(InputError, match="EMD option method must be one of sifting, filtering"):
        hht(surface, f, method="spectral")  # the flat name method is the decomposition's (Riesz: potential)
    with pytest.raises(InputError, match="did you mean 'max_imfs'"):
        hht(surface, f, max_imf=2)
