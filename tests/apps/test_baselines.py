"""The baselines (hht3d.apps.baselines): IMF enhancement and manifold-harmonics filtering on bump spheres, the
heat kernel signature against its definitions."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

from helpers.bumps import AMPLITUDE, bump_amplitude, sphere_distance
from helpers.meshes import bump_band_sphere, icosphere
from hht3d import Surface
from hht3d.apps import (
    BandStop,
    Constant,
    heat_kernel_signature,
    hks_features,
    imf_enhancement,
    manifold_harmonics_filter,
)

# -- baselines -------------------------------------------------------------------------------


def test_imf_enhancement(bumps):
    surface, _, pattern, result = bumps
    assert np.array_equal(imf_enhancement(surface, result, factor=1.0).vertices, surface.vertices)
    ratio = bump_amplitude(surface, imf_enhancement(surface, result, factor=2.0).vertices, pattern) / AMPLITUDE
    assert 1.5 <= ratio <= 2.2, ratio  # measured 1.96: IMF1 holds the bumps here


def test_manifold_harmonics_filter():
    v, f, _, pattern = bump_band_sphere(3, 8, 0.01)  # 642 vertices; bumps are Y_8^8, ω = √72
    surface = Surface(v, f)
    omega = np.sqrt(72)
    # all eigenpairs and gain 1 synthesise the coordinates exactly (M-orthonormal basis + centroid)
    full = manifold_harmonics_filter(surface, Constant(1.0), eigenpairs=surface.n_vertices - 1, keep_remainder=False)
    assert np.abs(full.vertices - v).max() <= 1e-10
    assert np.array_equal(manifold_harmonics_filter(surface, Constant(1.0), eigenpairs=50).vertices, v)
    out = manifold_harmonics_filter(surface, BandStop(low=omega / 1.5, high=1.5 * omega), eigenpairs=150)
    factor = sphere_distance(surface, v) / sphere_distance(surface, out.vertices)
    assert factor >= 10, factor  # measured 17: the bumps are one eigenspace
    truncated = manifold_harmonics_filter(surface, Constant(1.0), eigenpairs=40, keep_remainder=False)
    assert abs(bump_amplitude(surface, truncated.vertices, pattern)) <= 0.1 * 0.01  # low-pass at √λ_40


# -- heat kernel signature -----------------------------------------------------------------------


def test_hks_equals_heat_kernel_diagonal():
    """With every eigenpair, k_t(x, x) is the diagonal of expm(−t M⁻¹L) M⁻¹."""
    surface = Surface(*icosphere(2))
    n = surface.n_vertices
    times = np.array([0.01, 0.1, 1.0])
    hks = heat_kernel_signature(surface, times, eigenpairs=n - 1)
    operator = surface.stiffness.toarray() / surface.mass_diagonal[:, None]
    for t, row in zip(times, hks):
        kernel = scipy.linalg.expm(-t * operator) / surface.mass_diagonal[None, :]
        assert np.allclose(row, np.diag(kernel), rtol=1e-8)
    # large t: heat spreads evenly, k_t -> 1 / area
    assert np.allclose(
        heat_kernel_signature(surface, 100.0, eigenpairs=n - 1), 1 / surface.mass_diagonal.sum(), rtol=1e-8
    )


def sphere_hks_series(t: float) -> float:
    """HKS of the unit sphere, the same at every point: Σ_l (2l+1)/(4π) e^{−l(l+1)t}.

    (Addition theorem: Σ_m Y_lm(x)² = (2l+1)/(4π) for the l(l+1)-eigenspace.)
    """
    degrees = np.arange(60)
    return float(np.sum((2 * degrees + 1) / (4 * np.pi) * np.exp(-degrees * (degrees + 1) * t)))


def test_hks_on_the_sphere_is_constant_and_matches_the_series():
    # 48 eigenpairs = every mode of degree 1..6 (ARPACK path on 642 vertices); at t = 0.5 the
    # degree-7 terms weigh e^{-28} and are negligible.  By symmetry the HKS is the same at every
    # point: the icosphere breaks the symmetry slightly, measured spread 3.6e-4 of the value
    # (bound 2e-3).  Its value is the series up to the mesh's O(h²) area and eigenvalue errors:
    # measured +0.73%, bound 2%.
    surface = Surface(*icosphere(3))
    hks = heat_kernel_signature(surface, [0.5, 1.0], eigenpairs=48)
    for row, t in zip(hks, (0.5, 1.0)):
        assert np.ptp(row) <= 2e-3 * row.mean()
        assert row.mean() == pytest.approx(sphere_hks_series(t), rel=0.02)


def test_hks_matches_a_truncated_generalized_eigh():
    # The HKS sum over p modes, written here from scipy.linalg.eigh(L, M) and the kernel
    # term 1/area; the library takes its 29 modes from ARPACK (tol 0), so the two agree to
    # round-off: measured 3e-14 relative, bound 3e-13.  The cut must not split an
    # eigenspace (Σ φ² over part of one depends on the basis).
    v, f = icosphere(3)
    surface = Surface(v * [1.6, 1.0, 0.8], f)
    values, vectors = scipy.linalg.eigh(surface.stiffness.toarray(), np.diag(surface.mass_diagonal))
    times = np.array([0.05, 0.3])
    p = 29
    assert values[p + 1] - values[p] > 0.05 * values[p]  # values[0] is the kernel
    expected = (
        np.exp(-np.outer(times, values[1 : p + 1])) @ (vectors[:, 1 : p + 1] ** 2).T + 1 / surface.mass_diagonal.sum()
    )
    hks = heat_kernel_signature(surface, times, eigenpairs=p)
    assert np.max(np.abs(hks / expected - 1)) <= 3e-13


def test_hks_features_of_an_ellipsoid_are_the_long_axis_tips():
    # Ellipsoid with semi-axes 2 > 1.3 > 1.  The HKS at small t is 1/(4πt) + K/(12π) + O(t)
    # (Minakshisundaram–Pleijel), and K = a²/(b²c²) peaks at the tips of the long axis; the
    # short-axis tips are minima and the middle-axis tips saddles.  The mesh keeps the three
    # mirror symmetries of the icosahedron, whose subdivision has vertices on the axes; the
    # strict 2-ring rule must find exactly the two tips, and only maxima.
    v, f = icosphere(3)
    surface = Surface(v * [2.0, 1.3, 1.0], f)
    tips = [int(np.argmax(v[:, 0])), int(np.argmin(v[:, 0]))]
    assert np.allclose(np.abs(surface.vertices[tips, 0]), 2.0)
    result = hks_features(surface, eigenpairs=60)
    assert sorted(result.vertices.tolist()) == sorted(tips)
    assert result.n_scales == 1 and len(result.minima[0]) == 0 and result.counts.tolist() == [1, 1]
