"""L^{-1/2} and the Riesz transform against analytic and independent references.

Relative errors are measured in the M-norm ``‖x‖_M = √(xᵀMx)``, the norm
in which the quadrature tolerance is a proven bound.
"""

from __future__ import annotations

import sys

import numpy as np
import pytest
import scipy.sparse.linalg as spla
from scipy.special import sph_harm_y

from helpers.meshes import grid, icosphere
from helpers.spectral import m_error, mixed_signals
from helpers.systems import BACKENDS
from hht3d.errors import InputError
from hht3d.geometry.signals import fluctuation
from hht3d.geometry.surface import Surface
from hht3d.spectral import fractional_laplacian, riesz


def test_dense_and_spectral_other_powers(jittered_grid):
    # L^{-1} via powers equals a direct solve of L u = M f̃ on the kernel complement.
    s = jittered_grid
    f = fluctuation(s, mixed_signals(s, 1)[0])
    inverse = fractional_laplacian(s, f, power=-1.0, potential="dense")
    reg = (s.stiffness + 1e-12 * s.mass).tocsc()
    direct = fluctuation(s, spla.spsolve(reg, s.mass_diagonal * f))
    assert m_error(s, inverse, direct) < 1e-6
    half = fractional_laplacian(s, f, potential="dense")
    twice = fractional_laplacian(s, half, potential="dense")
    assert m_error(s, twice, inverse) < 1e-9


# -- analytic oracles -----------------------------------------------------------------------------


def real_harmonic_mix(l, polar, azimuth, rng):
    """Random combination of the 2l+1 real spherical harmonics of degree l."""
    modes = []
    for m in range(-l, l + 1):
        y = sph_harm_y(l, abs(m), polar, azimuth)
        modes.append(y.real if m >= 0 else y.imag)
    return rng.standard_normal(2 * l + 1) @ np.array(modes)


def test_sphere_harmonics():
    # Y_l is an eigenfunction with λ = l(l+1); the cotan discretisation on a 2562-vertex
    # icosphere is accurate to O(h² l²): measured 0.7% at l = 6, the bound is 2%.
    s = Surface(*icosphere(4))
    v = s.vertices
    polar, azimuth = np.arccos(np.clip(v[:, 2], -1, 1)), np.arctan2(v[:, 1], v[:, 0])
    rng = np.random.default_rng(0)
    degrees = np.arange(1, 7)
    y = np.stack([real_harmonic_mix(l, polar, azimuth, rng) for l in degrees])
    exact = y / np.sqrt(degrees * (degrees + 1))[:, None]
    assert np.all(m_error(s, fractional_laplacian(s, y), exact) < 0.02)


def test_neumann_rectangle():
    # cos(πkx/a)cos(πly/b) has λ = (πk/a)² + (πl/b)² with natural (Neumann) boundary.
    a, b = 2.0, 1.0
    s = Surface(*grid(61, 31, a, b, jitter=0.2))
    x, y = s.vertices[:, 0], s.vertices[:, 1]
    modes = [(1, 0), (0, 1), (2, 1), (3, 2), (4, 3)]
    f = np.stack([np.cos(np.pi * k * x / a) * np.cos(np.pi * l * y / b) for k, l in modes])
    lam = np.array([(np.pi * k / a) ** 2 + (np.pi * l / b) ** 2 for k, l in modes])
    exact = f / np.sqrt(lam)[:, None]
    assert np.all(m_error(s, fractional_laplacian(s, f), exact) < 0.02)


def test_riesz_of_sphere_harmonic_is_its_scaled_gradient():
    # R Y_1 = ∇Y_1/√2; for Y = z the tangent gradient is e_z − z n.
    s = Surface(*icosphere(4))
    z = s.vertices[:, 2]
    exact = (np.array([0, 0, 1.0]) - z[:, None] * s.vertices) / np.sqrt(2)
    for kind in ("lsq", "fem"):
        r = riesz(s, z, gradient=kind)
        assert r.shape == (s.n_vertices, 3)
        assert np.sqrt(np.sum((r - exact) ** 2) / np.sum(exact**2)) < 0.01


# -- Riesz isometry --------------------------------------------------------------------------------


def test_isometry_face_gradient_is_exact():
    # Σ_t A_t |∇u|² = uᵀLu (cotan L) and uᵀLu = f̃ᵀMf̃ for u = L^{-1/2}f̃; the quadrature
    # error tol per eigen-component gives a relative energy error ≤ 2 tol + tol².
    s = Surface(*grid(41, 21, 2.0, 1.0, jitter=0.3))
    f = mixed_signals(s)
    u = fractional_laplacian(s, f)
    grads = (s.face_gradient() @ u.T).reshape(len(s.faces), 3, -1)
    energy = np.einsum("fik,f->k", grads**2, s.face_areas)
    expected = (fluctuation(s, f) ** 2 * s.mass_diagonal).sum(-1)
    assert np.allclose(energy, expected, rtol=3e-8, atol=0)


@pytest.mark.parametrize("kind", ["lsq", "fem"])
def test_isometry_vertex_gradients_on_smooth_signals(kind):
    # Vertex gradients average over the 1-ring: an O(h²) loss for smooth signals (measured
    # 0.3–0.7% here), hence 2%.  White noise is not resolved by any vertex gradient.
    s = Surface(*icosphere(4))
    v = s.vertices
    f = np.stack([np.sin(3 * v[:, 0]) * np.cos(2 * v[:, 1]) + v[:, 2] ** 2, v[:, 0] * v[:, 1]])
    r = riesz(s, f, gradient=kind)
    energy = (np.sum(r**2, axis=-1) * s.mass_diagonal).sum(-1)
    expected = (fluctuation(s, f) ** 2 * s.mass_diagonal).sum(-1)
    assert np.allclose(energy, expected, rtol=0.02)


# -- kernel ------------------------------------------------------------------------------------------


def test_kernel_is_projected_per_component():
    v, f = icosphere(2)
    two = Surface(np.vstack([v, 0.5 * v + 3.0]), np.vstack([f, f + len(v)]))
    assert two.n_components == 2
    rng = np.random.default_rng(3)
    signal = rng.standard_normal(two.n_vertices)
    shifted = signal + np.where(two.component_labels == 0, 5.0, -2.0)
    for method in ("quadrature", "dense"):
        a = fractional_laplacian(two, signal, potential=method)
        b = fractional_laplacian(two, shifted, potential=method)
        assert np.allclose(a, b, atol=1e-8 * np.abs(a).max())
        for c in range(2):  # M-orthogonal to each component's constant
            part = two.component_labels == c
            assert abs(np.sum(a[part] * two.mass_diagonal[part])) < 1e-8 * np.sum(np.abs(a[part]))
    # each component on its own gives the same values
    alone = Surface(v, f)
    first = fractional_laplacian(alone, signal[: len(v)], potential="dense")
    both = fractional_laplacian(two, signal, potential="dense")
    assert np.allclose(both[: len(v)], first, atol=1e-10)


def test_constant_maps_to_zero(jittered_grid):
    assert np.allclose(fractional_laplacian(jittered_grid, np.full(jittered_grid.n_vertices, 7.0)), 0)


def test_many_signals_equal_one_at_a_time(jittered_grid):
    f = mixed_signals(jittered_grid)
    together = riesz(jittered_grid, f)
    assert together.shape == (3, jittered_grid.n_vertices, 3)
    for row, r in zip(f, together):
        assert np.allclose(riesz(jittered_grid, row), r, atol=1e-12)


@pytest.mark.parametrize("backend", [b for b in BACKENDS if b != "superlu"])
def test_backends_agree(jittered_grid, backend):
    f = mixed_signals(jittered_grid)
    a = fractional_laplacian(jittered_grid, f, backend=backend)
    b = fractional_laplacian(jittered_grid, f, backend="superlu")
    assert np.all(m_error(jittered_grid, a, b) < 1e-10)


# -- errors ---------------------------------------------------------------------------------------


def test_bad_inputs(jittered_grid, monkeypatch):
    s = jittered_grid
    n = s.n_vertices
    bad = np.ones(n)
    bad[5] = np.nan
    with pytest.raises(InputError, match="NaN"):
        fractional_laplacian(s, bad)
    with pytest.raises(InputError, match="shape"):
        fractional_laplacian(s, np.ones(n + 1))
    with pytest.raises(InputError, match="shape"):
        riesz(s, np.ones((2, 3, n)))
    with pytest.raises(InputError, match="potential must be one of"):
        fractional_laplacian(s, np.ones(n), potential="eig")
    with pytest.raises(InputError, match="power=-0.5 only"):
        fractional_laplacian(s, np.ones(n), power=-0.25)
    with pytest.raises(InputError, match="tolerance"):
        fractional_laplacian(s, np.ones(n), tol=1e-16)
    with pytest.raises(InputError, match="eigenpairs"):
        fractional_laplacian(s, np.ones(n), potential="spectral", eigenpairs=n)
    with pytest.raises(InputError, match="gradient"):
        riesz(s, np.ones(n), gradient="green")
    with pytest.raises(InputError, match="Surface"):
        riesz(s.vertices, np.ones(n))
    monkeypatch.setattr(sys.modules["hht3d.spectral.eigenpairs"], "DENSE_MAX_VERTICES", 100)
    big = Surface(s.vertices, s.faces)
    with pytest.raises(InputError, match="dense eigendecomposition is limited"):
        fractional_laplacian(big, np.ones(n), potential="dense")
