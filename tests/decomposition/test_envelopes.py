"""Envelopes of EMD (hht3d.decomposition.envelopes): splines on a cylinder, the eliminated system, energies
shared while in use."""

from __future__ import annotations

import gc

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.interpolate import CubicSpline

from helpers.meshes import icosphere, open_cylinder
from helpers.systems import BACKENDS
from hht3d import InputError, Surface
from hht3d.decomposition import emd, envelope_interpolation, envelope_operator
from hht3d.decomposition.envelopes import EnvelopeSolver, envelope_energies

# -- envelopes -----------------------------------------------------------------------------


def cylinder_knots(n_axial: int):
    """Open cylinder of length 4 with constraints on 9 whole rings (both ends included)."""
    surface = Surface(*open_cylinder(n_axial, 8, length=4.0, radius=0.05), name="cylinder")
    z = np.linspace(0.0, 4.0, n_axial)
    rings = np.round(np.array([0, 0.3, 0.9, 1.4, 2.0, 2.2, 2.9, 3.5, 4.0]) / 4 * (n_axial - 1)).astype(int)
    values = np.array([0.3, -1.0, 0.8, -0.2, 0.5, 1.1, -0.7, 0.2, 0.4])
    on_ring = np.zeros(n_axial)
    on_ring[rings] = values
    mask = np.zeros(n_axial, dtype=bool)
    mask[rings] = True
    return surface, z, rings, values, np.repeat(on_ring, 8), np.repeat(mask, 8)


def test_biharmonic_envelope_is_clamped_cubic_spline():
    # Q = L M^-1 L with the Neumann Laplacian imposes dg/dn = 0 on the boundary, so on a
    # cylinder a ring-constant envelope is the clamped cubic spline through the ring values,
    # up to the O(dz^2) discretisation error (error ratio 4 when dz halves).
    errors = []
    for n_axial in (201, 401):
        surface, z, rings, values, f, mask = cylinder_knots(n_axial)
        g = envelope_interpolation(surface, f, mask, envelope="biharmonic").reshape(n_axial, 8)
        assert np.ptp(g, axis=1).max() < 1e-10  # constant around each ring
        spline = CubicSpline(z[rings], values, bc_type="clamped")(z)
        errors.append(np.max(np.abs(g[:, 0] - spline)))
    assert errors[1] < 1e-3
    assert 3.5 < errors[0] / errors[1] < 4.5


def tension_spline(knots: np.ndarray, values: np.ndarray, k: float, x: np.ndarray) -> np.ndarray:
    """The clamped 1-D spline in tension (Schweikert 1966) through ``values``, evaluated at ``x``.

    It minimises ∫ g''² + k² g'² with g' = 0 at both ends: on each interval g solves
    g'''' = k² g'', so g = a + b t + c e^(−k t) + e e^(−k (h − t)) (t from the interval's left
    knot), with g, g' and g'' continuous at the knots.  A dense solve of those 4m conditions.
    """
    h = np.diff(knots)
    m = len(h)
    rows, rhs = [], []

    def basis(i, t, order):  # the derivative of each of interval i's four functions at t
        p, q = np.exp(-k * t), np.exp(-k * (h[i] - t))
        row = np.zeros(4 * m)
        row[4 * i : 4 * i + 4] = [(1, t, p, q), (0, 1, -k * p, k * q), (0, 0, k * k * p, k * k * q)][order]
        return row

    for i in range(m):
        rows += [basis(i, 0.0, 0), basis(i, h[i], 0)]
        rhs += [values[i], values[i + 1]]
    for i in range(m - 1):
        rows += [basis(i, h[i], order) - basis(i + 1, 0.0, order) for order in (1, 2)]
        rhs += [0.0, 0.0]
    rows += [basis(0, 0.0, 1), basis(m - 1, h[-1], 1)]
    rhs += [0.0, 0.0]
    coef = np.linalg.solve(np.array(rows), np.array(rhs)).reshape(m, 4)
    i = np.clip(np.searchsorted(knots, x, side="right") - 1, 0, m - 1)
    t = x - knots[i]
    a, b, c, e = coef[i].T
    return a + b * t + c * np.exp(-k * t) + e * np.exp(-k * (h[i] - t))


def test_tension_envelope_is_the_spline_in_tension():
    # Q_τ = L M⁻¹ L + (τ/d)² L is the energy ∫ (Δg)² + (τ/d)² |∇g|², so on the cylinder a
    # ring-constant envelope is the clamped 1-D spline in tension with k = τ/d, d = √(A / |C|)
    # (envelopes.py), up to the O(dz²) discretisation error.  Here k ≈ 23, so k times the knot
    # gaps is 4.6–16: the envelope is far from the cubic spline (max difference printed).
    tension, errors = 3.0, []
    for n_axial in (201, 401):
        surface, z, rings, values, f, mask = cylinder_knots(n_axial)
        g = envelope_interpolation(surface, f, mask, envelope="tension", tension=tension).reshape(n_axial, 8)
        k = tension / np.sqrt(surface.mass_diagonal.sum() / mask.sum())
        exact = tension_spline(z[rings], values, k, z)
        errors.append(np.max(np.abs(g[:, 0] - exact)))
    cubic = CubicSpline(z[rings], values, bc_type="clamped")(z)
    print(
        f"tension envelope: errors {errors[0]:.2e}, {errors[1]:.2e}; from the cubic spline "
        f"{np.max(np.abs(exact - cubic)):.2f}"
    )
    assert errors[1] < 1e-2 * np.max(np.abs(exact - cubic))
    assert 3.5 < errors[0] / errors[1] < 4.5


def test_harmonic_envelope_is_linear_interpolation():
    surface, z, rings, values, f, mask = cylinder_knots(201)
    g = envelope_interpolation(surface, f, mask, envelope="harmonic").reshape(201, 8)
    np.testing.assert_allclose(g[:, 0], np.interp(z, z[rings], values), atol=1e-12)


@pytest.mark.parametrize("backend", BACKENDS)
def test_envelope_matches_eliminated_system(small_sphere, backend):
    s = small_sphere
    rng = np.random.default_rng(1)
    f = rng.standard_normal(s.n_vertices)
    mask = rng.random(s.n_vertices) < 0.1
    g = envelope_interpolation(s, f, mask, envelope="biharmonic", backend=backend)
    q = (s.stiffness @ sp.diags(1 / s.mass_diagonal) @ s.stiffness).tocsc()
    free = ~mask
    reference = spla.spsolve(q[free][:, free], -(q[free][:, mask] @ f[mask]))
    assert np.max(np.abs(g[mask] - f[mask])) <= 1e-8 * np.max(np.abs(f[mask]))
    assert np.max(np.abs(g[free] - reference)) <= 1e-8 * np.max(np.abs(reference))
    assert envelope_operator(s, envelope="biharmonic").nnz >= q.nnz  # diagonal kept as explicit entries
    mine = envelope_operator(s, envelope="biharmonic")  # the caller's own copy: changing it changes no later envelope
    mine.data[:] = 0
    mine.eliminate_zeros()
    np.testing.assert_array_equal(envelope_interpolation(s, f, mask, envelope="biharmonic", backend=backend), g)


def test_envelope_energies_are_shared_while_in_use_and_freed_after(small_sphere):
    """EMD runs of one surface alive together share its envelope energies, and none outlive them:
    the Riesz transform after an EMD must not carry them (666 MB at 1M vertices)."""
    solver = EnvelopeSolver(small_sphere, None)
    assert envelope_energies(small_sphere) is solver.energies
    emd(small_sphere, small_sphere.vertices[:, 2], max_imfs=1)
    held = small_sphere.cache["emd:energies"]
    assert held() is solver.energies
    del solver
    gc.collect()
    assert held() is None


def test_envelope_needs_a_constraint_per_component():
    v, f = icosphere(2)
    two = Surface(np.vstack([v, v + 3]), np.vstack([f, f + len(v)]), name="two spheres")
    mask = np.zeros(two.n_vertices, dtype=bool)
    mask[:5] = True
    with pytest.raises(InputError, match="no constrained vertex"):
        envelope_interpolation(two, np.zeros(two.n_vertices), mask, envelope="biharmonic")
