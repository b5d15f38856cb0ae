"""Monogenic signal and Hilbert spectrum against analytic oracles."""

from __future__ import annotations

import numpy as np
import pytest

from helpers.meshes import fibonacci_sphere, grid
from helpers.spectral import LENGTH, RADIUS, WAVENUMBERS
from hht3d.errors import InputError
from hht3d.geometry.surface import Surface
from hht3d.spectral import fractional_laplacian, riesz
from hht3d.spectral.frequency import instantaneous_frequency
from hht3d.spectral.monogenic_signal import monogenic, monogenic_from_potential


@pytest.mark.parametrize("frequency", ["phase", "gradient"])
@pytest.mark.parametrize("kind", ["lsq", "fem"])
def test_cylinder_frequency_and_amplitude(cylinder, cylinder_waves, kind, frequency):
    # cos(kθ) is a Neumann eigenfunction with λ = (k/r)², so R f = −sin(kθ) e_θ,
    # a = 1 and φ = |kθ| folded into [0, π]: |∇φ| = k/r.  The gradient route's vertex
    # gradients of a sampled sinusoid lose ~(kh)²/6 (2.5% at k = 8), the phase route
    # reads plane waves exactly: both within the 5% bound.
    result = monogenic(cylinder, cylinder_waves, gradient=kind, frequency=frequency)
    z = cylinder.vertices[:, 2]
    inner = (z > 1.0) & (z < LENGTH - 1.0)
    for i, k in enumerate(WAVENUMBERS):
        assert np.median(result.frequency[i, inner]) == pytest.approx(k / RADIUS, rel=0.05)
        a = result.amplitude[i, inner]
        assert a.std() / a.mean() <= 0.05
        assert a.mean() == pytest.approx(1.0, rel=0.05)


def test_plane_wave_on_rectangle():
    # Flat Neumann strip, f = cos(kx): instantaneous frequency k everywhere.
    a = 2.0
    s = Surface(*grid(81, 21, a, 0.5))
    k = 4 * np.pi / a
    result = monogenic(s, np.cos(k * s.vertices[:, 0]))
    inner = (s.vertices[:, 0] > 0.3) & (s.vertices[:, 0] < a - 0.3)
    assert np.median(result.frequency[0, inner]) == pytest.approx(k, rel=0.05)


def test_definitions_and_identity(cylinder, cylinder_waves):
    # Eq. 21, Eq. 22 in [0, π], and Σ a_k cos φ_k + residue == signal to round-off.
    rng = np.random.default_rng(0)
    imfs = np.vstack([cylinder_waves, 0.1 * rng.standard_normal((1, cylinder.n_vertices))])
    residue = cylinder.vertices[:, 2] ** 2
    signal = imfs.sum(axis=0) + residue
    result = monogenic(cylinder, imfs)
    assert result.riesz.shape == (3, cylinder.n_vertices, 3)
    assert np.allclose(result.riesz, riesz(cylinder, imfs), atol=1e-12)
    q2 = np.sum(result.riesz**2, axis=-1)
    assert np.allclose(result.amplitude**2, imfs**2 + q2)
    assert result.phase.min() >= 0 and result.phase.max() <= np.pi
    assert np.allclose(result.reconstruct() + residue, signal, atol=1e-12 * np.abs(signal).max())


@pytest.mark.parametrize("frequency", ["phase", "gradient"])
def test_from_potential_matches(cylinder, cylinder_waves, frequency):
    potential = fractional_laplacian(cylinder, cylinder_waves)
    a = monogenic_from_potential(cylinder, cylinder_waves, potential, gradient="fem", frequency=frequency)
    b = monogenic(cylinder, cylinder_waves, gradient="fem", frequency=frequency)
    assert np.allclose(a.frequency, b.frequency, atol=1e-12) and np.allclose(a.riesz, b.riesz, atol=1e-12)
    expected = instantaneous_frequency(cylinder, cylinder_waves, a.riesz, frequency=frequency, gradient="fem")
    assert np.array_equal(a.frequency, expected)
    with pytest.raises(InputError, match="potential"):
        monogenic_from_potential(cylinder, cylinder_waves, potential[:1])


def test_riesz_is_tangent(cylinder, cylinder_waves):
    result = monogenic(cylinder, cylinder_waves)
    normal_part = np.einsum("knj,nj->kn", result.riesz, cylinder.normals)
    assert np.abs(normal_part).max() < 1e-10 * np.abs(result.riesz).max()


def test_zero_imf_has_zero_amplitude_and_frequency(cylinder, cylinder_waves):
    imfs = np.vstack([cylinder_waves[0], np.zeros(cylinder.n_vertices)])
    result = monogenic(cylinder, imfs)
    assert np.all(np.isfinite(result.frequency))
    assert np.all(result.amplitude[1] == 0) and np.all(result.frequency[1] == 0)


def test_point_cloud():
    # Unit sphere sampled by points, f = z = Y_1 (up to scale): |Rf| = |∇z|/√2 = sin(polar)/√2.
    s = Surface(fibonacci_sphere(3000), None)
    z = s.vertices[:, 2]
    result = monogenic(s, z)
    band = np.abs(z) < 0.8
    expected = np.sqrt(z**2 + (1 - z**2) / 2)
    assert np.median(np.abs(result.amplitude[0, band] / expected[band] - 1)) < 0.03


def test_bad_imfs(cylinder):
    with pytest.raises(InputError, match="imfs"):
        monogenic(cylinder, np.ones((2, cylinder.n_vertices - 1)))
    with pytest.raises(InputError, match="Surface"):
        monogenic(cylinder.vertices, np.ones(cylinder.n_vertices))


@pytest.mark.parametrize("frequency", ["phase", "gradient"])
def test_cylinder_mean_frequency_has_no_fold_bias(cylinder, cylinder_waves, frequency):
    # The phase folds at every extremum (q = |Rf| has a kink there).  The gradient route
    # takes ∇q by the chain rule, the phase route orients q by the ring's Riesz vectors
    # there; either keeps the mean over all vertices as accurate as the median
    # (differencing |Rf| gave 14.5% low at k = 8): within 5% of k/r, no vertex below 90%.
    result = monogenic(cylinder, cylinder_waves, frequency=frequency)
    z = cylinder.vertices[:, 2]
    inner = (z > 1.0) & (z < LENGTH - 1.0)
    expected = np.array(WAVENUMBERS)[:, None] / RADIUS
    ratio = result.frequency[:, inner] / expected
    assert np.allclose(ratio.mean(axis=1), 1.0, rtol=0.05)
    assert ratio.min() > 0.9


@pytest.mark.parametrize("scale", [2.0**-664, 2.0**664])
def test_monogenic_quantities_scale_with_the_signal(scale):
    """Amplitude is linear in the signal, phase and frequency do not change: at 2^±664 (1e±200) as at 1
    (squares of the signal would overflow or vanish in float64).  Powers of two scale every rounding
    alike, so no backend's round-off differs between the two runs."""
    from hht3d import data_path, load

    sphere = load(data_path("sphere_oct4098.ply"))
    x, y, z = sphere.vertices.T
    signals = np.stack([z, x * y])
    base, scaled = monogenic(sphere, signals), monogenic(sphere, scale * signals)
    # linear up to the round-off of the solves, 1e-12 of the largest amplitude
    np.testing.assert_allclose(scaled.amplitude / scale, base.amplitude, rtol=1e-10, atol=1e-12 * base.amplitude.max())
    np.testing.assert_allclose(scaled.phase, base.phase, rtol=0, atol=1e-10)
    # the frequency at a fold of the phase (an extremum of f, where Rf vanishes) depends on round-off: the
    # fold's orientation is chosen among near-equal directions; everywhere else it is the same number
    same = np.isclose(scaled.frequency, base.frequency, rtol=1e-8, atol=1e-8 * base.frequency.max())
    assert same.mean() > 0.999
    weight = base.amplitude**2 * sphere.mass_diagonal
    np.testing.assert_allclose((weight * scaled.frequency).sum(1), (weight * base.frequency).sum(1), rtol=1e-6)
    from hht3d.spectral import HilbertSpectrum  # its energy proportions stay finite too

    np.testing.assert_allclose(
        HilbertSpectrum.from_monogenic(sphere, scaled).mean_frequency(),
        HilbertSpectrum.from_monogenic(sphere, base).mean_frequency(),
        rtol=1e-6,
    )
