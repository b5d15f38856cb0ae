"""The Hilbert spectrum's resolution limit and its report of unresolved frequencies."""

from __future__ import annotations

import numpy as np
import pytest

from helpers.meshes import grid
from hht3d.errors import InputError
from hht3d.geometry.surface import Surface
from hht3d.spectral import resolution_report, resolvable_frequency
from hht3d.spectral.monogenic_signal import MonogenicSignal, monogenic
from hht3d.spectral.spectrum import HilbertSpectrum


def test_default_limit_comes_from_the_vertex_areas():
    area = np.array([0.01, 0.04, 0.25, 1.0])
    spectrum = HilbertSpectrum(np.ones((1, 4)), np.ones((1, 4)), area)
    assert np.allclose(spectrum.resolvable, np.pi / np.array([0.1, 0.2, 0.5, 1.0]))
    assert spectrum.resolvable_frequency == pytest.approx(np.median(np.pi / np.sqrt(area)))
    with pytest.raises(InputError, match="resolvable"):
        HilbertSpectrum(np.ones((1, 4)), np.ones((1, 4)), area, np.ones(3))


def test_resolution_report_weights_pairs_by_energy_and_area():
    # two IMFs on three vertices with limits π/√A = (π, π/2, π/3)
    area = np.array([1.0, 4.0, 9.0])
    frequency = np.array([[1.0, 1.5, 1.5], [4.0, 1.0, 0.1]])  # above: (0,2) 1.5 > π/3 and (1,0) 4 > π
    amplitude = np.array([[1.0, 1.0, 2.0], [3.0, 1.0, 1.0]])
    report = HilbertSpectrum(frequency, amplitude, area).resolution
    energy = amplitude**2 * area  # [[1, 4, 36], [9, 4, 9]]
    assert report.pairs == 2 and report.fraction == pytest.approx(2 / 6)
    assert np.allclose(report.per_signal, [1 / 3, 1 / 3])
    assert report.energy_share == pytest.approx((36 + 9) / energy.sum())


def test_monogenic_result_carries_the_limit():
    s = Surface(*grid(33, 9, 1.0, 0.25))
    k = 8 * np.pi  # 8 points per wavelength at h = 1/32
    result = monogenic(s, np.cos(k * s.vertices[:, 0]))
    assert np.array_equal(result.resolvable, resolvable_frequency(s))
    assert result.resolution.ok  # k is a quarter of π/h
    spectrum = HilbertSpectrum.from_monogenic(s, result)
    assert np.array_equal(spectrum.resolvable, result.resolvable)
    assert spectrum.resolution.ok and spectrum.resolvable_frequency == pytest.approx(32 * np.pi)
    bare = MonogenicSignal(result.imfs, result.riesz, result.amplitude, result.phase, result.frequency)
    with pytest.raises(InputError, match="vertex areas"):
        bare.resolution


def test_one_energy_share_above_the_limit_on_spot():
    """The monogenic signal and the spectrum report one energy share above the resolution limit:
    the a²·A_v-weighted one, whose value the test recomputes from the per-vertex arrays."""
    from hht3d import data_path, hht, load
    from hht3d.geometry.signals import mean_curvature

    spot = load(data_path("spot.ply"))
    result = hht(spot, mean_curvature(spot), max_imfs=3)
    mono = result.monogenic
    energy = mono.amplitude**2 * spot.mass_diagonal
    expected = energy[mono.frequency > np.pi / np.sqrt(spot.mass_diagonal)].sum() / energy.sum()
    assert expected > 0  # spot's finest IMF has unresolved vertices, so the share is not trivially 0
    assert mono.resolution.energy_share == pytest.approx(expected, rel=1e-12)
    assert result.spectrum.resolution.energy_share == pytest.approx(expected, rel=1e-12)


def test_resolution_report_counts_pairs_above_the_limit():
    frequency = np.array([[1.0, 5.0, 2.0, 9.0], [0.5, 0.5, 3.5, 0.5]])
    limit = np.array([2.0, 4.0, 3.0, 8.0])
    weights = np.array([[1.0, 2.0, 3.0, 4.0], [1.0, 1.0, 6.0, 2.0]])
    report = resolution_report(frequency, limit, weights)
    assert report.pairs == 3  # 5 > 4, 9 > 8, 3.5 > 3
    assert report.fraction == pytest.approx(3 / 8)
    assert np.allclose(report.per_signal, [0.5, 0.25])
    assert report.energy_share == pytest.approx((2 + 4 + 6) / 20)
    assert report.limit == pytest.approx(3.5) and not report.ok
    assert "3 vertex–IMF pairs" in report.summary()
    assert resolution_report(frequency, limit * 10).ok
    with pytest.raises(InputError, match="resolvable"):
        resolution_report(frequency, limit[:3])
