"""The Hilbert spectrum (hht3d.spectral.spectrum) of a cylinder's waves against analytic oracles."""

from __future__ import annotations

import numpy as np
import pytest

from helpers.spectral import RADIUS, WAVENUMBERS
from hht3d.errors import InputError
from hht3d.spectral.monogenic_signal import monogenic
from hht3d.spectral.spectrum import HilbertSpectrum

# -- Hilbert spectrum -----------------------------------------------------------------------------


@pytest.fixture(scope="module")
def cylinder_spectrum(cylinder, cylinder_waves):
    return HilbertSpectrum.from_monogenic(cylinder, monogenic(cylinder, cylinder_waves))


def test_spectrum_per_imf(cylinder, cylinder_waves, cylinder_spectrum):
    spectrum = cylinder_spectrum
    area = cylinder.mass_diagonal.sum()  # 2πrL = surface area, a = 1
    assert np.allclose(spectrum.imf_energy(), area, rtol=0.02)
    assert np.allclose(spectrum.mean_frequency(), np.array(WAVENUMBERS) / RADIUS, rtol=0.05)


@pytest.mark.parametrize("scale", ["linear", "log"])
def test_distribution_and_marginal(cylinder, cylinder_spectrum, scale):
    spectrum = cylinder_spectrum
    edges, h = spectrum.distribution(bins=40, scale=scale)
    assert h.shape == (40, cylinder.n_vertices)
    # every frequency lies within the default limits: all energy is binned
    assert np.allclose(h.sum(axis=0), spectrum.energy.sum(axis=0))
    edges2, marginal = spectrum.marginal(bins=40, scale=scale)
    assert np.array_equal(edges, edges2)
    assert marginal.sum() == pytest.approx(spectrum.imf_energy().sum())
    # the two largest peaks sit at k/r, within the 5% discretisation bound plus one bin
    centres = np.sqrt(edges[1:] * edges[:-1]) if scale == "log" else (edges[1:] + edges[:-1]) / 2
    top = np.sort(np.argsort(marginal)[-2:])
    expected = np.array(WAVENUMBERS) / RADIUS
    assert np.all(np.abs(centres[top] - expected) <= 0.05 * expected + np.diff(edges)[top])


def test_explicit_limits_drop_outside(cylinder_spectrum):
    edges, h = cylinder_spectrum.distribution(bins=10, limits=(0.0, 4.0))  # only k = 4 (ω ≈ 2.67)
    assert edges[-1] == 4.0
    inside = cylinder_spectrum.frequency <= 4.0
    assert h.sum() == pytest.approx(cylinder_spectrum.energy[inside].sum())


def test_spectrum_errors(cylinder_spectrum):
    with pytest.raises(InputError, match="scale"):
        cylinder_spectrum.distribution(scale="mel")
    with pytest.raises(InputError, match="limits"):
        cylinder_spectrum.distribution(scale="log", limits=(0.0, 1.0))
    with pytest.raises(InputError, match="bins"):
        cylinder_spectrum.marginal(bins=0)
    with pytest.raises(InputError, match="shape"):
        HilbertSpectrum(np.ones((2, 5)), np.ones((2, 4)), np.ones(5))
