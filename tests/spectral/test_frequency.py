"""Instantaneous frequency (Eq. 23) against references independent of the estimator.

References: sampled plane waves ``cos(kx)`` that are Neumann eigenfunctions of
a strip (the continuum Eq. 23 reads ``k`` at every point); amplitude-modulated
waves whose Riesz transform is known in closed form; spherical harmonics,
with the continuum Eq. 23 evaluated from ``scipy.special.lpmv`` and finite
differences; and the closed-form discrete response of the paper's gradient
route on a regular grid.
"""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest
from scipy.special import lpmv

from helpers.meshes import grid, icosphere
from hht3d.errors import InputError
from hht3d.geometry.surface import Surface
from hht3d.spectral import (
    FREQUENCY_METHODS,
    edge_stencil,
    fractional_laplacian,
    instantaneous_frequency,
    resolvable_frequency,
    riesz,
)
from hht3d.spectral.monogenic_signal import monogenic, monogenic_from_potential
from hht3d.spectral.riesz_transform import vertex_gradient

# A strip [0, 1] x [0, 16h], h = 1/128.  cos(mπx) is a Neumann eigenfunction of the
# continuum strip and, sampled, of the cotangent Laplacian of the regular grid
# (tensor-product 5-point stencil with lumped mass), so the discrete Riesz transform
# of the regular strip is exact up to the gradient's own response.
N = 128
H = 1.0 / N
MODES = np.array([4, 16, 32, 48, 64, 80, 85, 98, 116])
WAVENUMBERS = MODES * np.pi
POINTS_PER_WAVELENGTH = 2 * N / MODES  # 64, 16, 8, 5.3, 4, 3.2, 3.0, 2.6, 2.2
RESOLVED = POINTS_PER_WAVELENGTH >= 3.0


def strip(jitter: float = 0.0, faces: bool = True) -> Surface:
    v, f = grid(N + 1, 17, 1.0, 16 * H, jitter=jitter, seed=0)
    if faces:
        return Surface(v, f)
    return Surface(v, None, normals=np.tile([0.0, 0.0, 1.0], (len(v), 1)))


def away_from_edges(s: Surface) -> np.ndarray:
    """Vertices at least two spacings from the strip's edges: the one-sided gradients at
    the boundary make the discrete Riesz transform inexact there (an effect of the
    transform, not of the frequency estimate)."""
    x, y = s.vertices[:, 0], s.vertices[:, 1]
    return (x > 1.5 * H) & (x < 1 - 1.5 * H) & (y > 1.5 * H) & (y < 16 * H - 1.5 * H)


def both_estimates(s: Surface, signals):
    """(phase, gradient) monogenic signals from one L^{-1/2}."""
    potential = fractional_laplacian(s, signals)
    return [monogenic_from_potential(s, signals, potential, frequency=m) for m in FREQUENCY_METHODS]


@pytest.fixture(scope="module")
def regular():
    s = strip()
    return s, both_estimates(s, np.cos(WAVENUMBERS[:, None] * s.vertices[:, 0]))


def test_plane_waves_on_a_regular_grid_read_their_wavenumber(regular):
    s, (phase, _) = regular
    ratio = phase.frequency[:, away_from_edges(s)] / WAVENUMBERS[:, None]
    # Exact for a plane wave whose Riesz magnitude is corrected at the true wavenumber;
    # the correction uses a ring mean of a first estimate instead, which leaves at most
    # 1.4% at any vertex from 64 to 4 points per wavelength (measured 1.36%), 3.1% at
    # 3-3.2, and grows towards the Nyquist limit (10.4% at 2.2).
    bound = np.select([POINTS_PER_WAVELENGTH >= 4, POINTS_PER_WAVELENGTH >= 3], [0.02, 0.04], 0.16)
    assert np.all(np.abs(ratio - 1).max(axis=1) <= bound)
    assert np.allclose(np.median(ratio, axis=1), 1.0, atol=0.01)
    assert np.all(np.diff(np.median(phase.frequency[:, away_from_edges(s)], axis=1)) > 0)


def test_gradient_route_matches_its_discrete_response(regular):
    # The paper's route on the regular grid, closed form: with θ = kx, the LSQ gradient
    # of a sampled sinusoid scales it by σ = sin(kh)/h, the Riesz magnitude by
    # c = cos(kh/2) (σ over the 5-point symbol (2/h) sin(kh/2)), so f = cos θ,
    # q = c|sin θ|, and Eq. 23 gives ω = σc / (cos²θ + c² sin²θ).  Agreement to the
    # quadrature tolerance (1e-8) shows the estimate follows the stencil, peaking near
    # 4 points per wavelength and falling towards 0 at the Nyquist limit.
    s, (_, gradient) = regular
    theta = WAVENUMBERS[:, None] * s.vertices[:, 0]
    sigma, c = np.sin(WAVENUMBERS * H) / H, np.cos(WAVENUMBERS * H / 2)
    expected = (sigma * c)[:, None] / (np.cos(theta) ** 2 + (c**2)[:, None] * np.sin(theta) ** 2)
    inner = away_from_edges(s)
    assert np.allclose(gradient.frequency[:, inner], expected[:, inner], rtol=1e-6)
    medians = np.median(gradient.frequency[:, inner], axis=1) / WAVENUMBERS
    assert medians[-1] < 0.1 and not np.all(np.diff(medians * WAVENUMBERS) > 0)


@pytest.mark.parametrize("faces", [True, False], ids=["jittered mesh", "point cloud"])
def test_plane_waves_on_irregular_samplings(faces):
    # Interior vertices moved by up to ±0.2 spacings in x and y (edges 0.6h-1.4h along
    # the wave); as a point cloud the Laplacian and gradients come from the points alone.
    # Irregular stencils make the Riesz transform itself noisy (single vertices read
    # 0.4-1.2 k), so the median over the strip is what is checked: within 5% of k from
    # 64 to 3 points per wavelength (measured within 1.3%) and strictly increasing in k
    # up to 2.2, where the longest edges already sample the wave below their own Nyquist.
    s = strip(jitter=0.2, faces=faces)
    phase = monogenic(s, np.cos(WAVENUMBERS[:, None] * s.vertices[:, 0]))
    median = np.median(phase.frequency[:, away_from_edges(s)], axis=1)
    assert np.allclose(median[RESOLVED] / WAVENUMBERS[RESOLVED], 1.0, atol=0.05)
    assert np.all(np.diff(median) > 0)


def test_amplitude_modulated_waves(regular):
    # f = 3 a(x) cos(kx), a = 1 + cos(πx)/2, is a sum of three Neumann modes
    # (k and k ± π), so R f = -3 a(x) sin(kx) x̂ exactly and Eq. 23 reads k at every
    # point although the amplitude 3a varies from 1.5 to 4.5.  Dividing Eq. 23's
    # numerator by the amplitude instead of its square would read 3a·k.
    s, _ = regular
    x = s.vertices[:, 0]
    k = np.array([16, 32]) * np.pi  # 16 and 8 points per wavelength
    f = 3 * (1 + 0.5 * np.cos(np.pi * x)) * np.cos(k[:, None] * x)
    phase, gradient = both_estimates(s, f)
    inner = away_from_edges(s)
    # phase route: each mode is exact; the mixture of responses at k ± π leaves 1.2%
    assert np.allclose(phase.frequency[:, inner] / k[:, None], 1.0, atol=0.02)
    # gradient route at 16 points per wavelength: the stencil's 1 - (kh)²/6 = 0.974 at
    # the median, within 5% at every vertex
    assert np.allclose(gradient.frequency[0, inner] / k[0], 1.0, atol=0.05)


# -- spherical harmonics against the continuum Eq. 23 ------------------------------------------


def harmonic(l: int, m: int, polar, azimuth):
    return lpmv(m, l, np.cos(polar)) * np.cos(m * azimuth)


def surface_gradient(func, polar, azimuth, step=1e-4):
    """(∂_θ, ∂_φ / sin θ) by fourth-order central differences (error ~ step⁴ f⁽⁵⁾)."""

    def diff(shift):
        return (-func(*shift(2)) + 8 * func(*shift(1)) - 8 * func(*shift(-1)) + func(*shift(-2))) / (12 * step)

    d_polar = diff(lambda j: (polar + j * step, azimuth))
    d_azimuth = diff(lambda j: (polar, azimuth + j * step))
    return np.stack([d_polar, d_azimuth / np.sin(polar)], axis=-1)


def continuum_frequency(l: int, m: int, polar, azimuth):
    """Eq. 23 of Y_l^m on the unit sphere, |f ∇q − q ∇f| / (f² + q²), where R f = ∇f/√(l(l+1))
    (f is an eigenfunction) and q = |R f| in the orthonormal frame (e_θ, e_φ).

    ∇q = Jᵀ r̂ with J the derivative of the components of R f along the frame,
    taken with the frame of the evaluation point: the components of a field in a
    moving frame differ from those in a fixed one by O(R f · dist), and the
    rotation term of the frame is orthogonal to r̂ to first order, so Jᵀ r̂ is
    exact; at zeros of R f the slope is J's largest singular value."""
    scale = 1 / np.sqrt(l * (l + 1))

    def riesz(p, a):
        return surface_gradient(lambda pp, aa: harmonic(l, m, pp, aa), p, a, 1e-5) * scale

    f = harmonic(l, m, polar, azimuth)
    r = riesz(polar, azimuth)
    q = np.linalg.norm(r, axis=-1)
    jac = np.stack(
        [surface_gradient(lambda p, a, c=c: riesz(p, a)[..., c], polar, azimuth, 1e-3) for c in range(2)], axis=-2
    )  # [vertex, component, direction]
    direction = np.divide(r, q[:, None], out=np.zeros_like(r), where=q[:, None] > 1e-9 * q.max())
    grad_q = np.einsum("vcg,vc->vg", jac, direction)
    zero = ~(q > 1e-9 * q.max())
    grad_q[zero] = np.linalg.svd(jac[zero], compute_uv=False)[:, :1] * [1.0, 0.0]
    grad_f = r / scale
    numerator = np.linalg.norm(f[:, None] * grad_q - q[:, None] * grad_f, axis=-1)
    return numerator / (f**2 + q**2)


@pytest.fixture(scope="module")
def sphere():
    return Surface(*icosphere(5))  # 10,242 vertices, mean edge 0.0378


# (l, m, tolerance): 8.1 points per wavelength at l = 20 (wavelength 2π/√(l(l+1)) over the
# mean edge length), 10.1 at l = 16, 13.3 at l = 12.  Zonal and sectoral harmonics vary
# mostly in one direction: within 2%.  A tesseral harmonic varies in two: its phase field
# curves on the scale of the wavelength and the 1-ring fit of the increments is off by
# O((kh)²) of it, +2.4% at 8.1 points per wavelength (+1.7% at 10.1, +1.0% at 13.3).
HARMONICS = [(20, 0, 0.02), (20, 20, 0.02), (16, 9, 0.02), (12, 5, 0.02), (20, 7, 0.03)]


def test_spherical_harmonics_match_the_continuum_eq23(sphere):
    x, y, z = sphere.vertices.T
    polar, azimuth = np.arccos(np.clip(z, -1, 1)), np.arctan2(y, x)
    signals = np.stack([harmonic(l, m, polar, azimuth) for l, m, _ in HARMONICS])
    signals /= np.abs(signals).max(axis=1, keepdims=True)
    result = monogenic(sphere, signals)
    inside = (polar > 0.05) & (polar < np.pi - 0.05)  # the finite differences in φ need sin θ > 0
    for i, (l, m, tol) in enumerate(HARMONICS):
        reference = continuum_frequency(l, m, polar[inside], azimuth[inside])
        weight = (result.amplitude[i] ** 2 * sphere.mass_diagonal)[inside]
        estimate = result.frequency[i, inside]
        mean_ratio = (weight * estimate).sum() / (weight * reference).sum()
        assert mean_ratio == pytest.approx(1.0, abs=tol), (l, m)


# -- shapes, stacking, the resolution limit -------------------------------------------------


def test_signals_at_once_equal_one_at_a_time(monkeypatch):
    rng = np.random.default_rng(1)
    small = Surface(*icosphere(3))
    f = rng.standard_normal((3, small.n_vertices))
    r = rng.standard_normal((3, small.n_vertices, 3))
    r -= np.einsum("kvc,vc->kv", r, small.normals)[..., None] * small.normals
    monkeypatch.setenv("OMP_NUM_THREADS", "3")  # three threads share each signal's blocks, whatever the cores
    together = instantaneous_frequency(small, f, r)
    alone = np.stack([instantaneous_frequency(small, f[i : i + 1], r[i : i + 1])[0] for i in range(3)])
    assert np.array_equal(together, alone)
    monkeypatch.setenv("OMP_NUM_THREADS", "1")  # one block, one thread: the same bits
    assert np.array_equal(instantaneous_frequency(small, f, r), together)
    assert np.all(np.isfinite(together)) and together.min() >= 0


def test_blocks_of_a_few_vertices_read_the_plane_waves_unchanged(monkeypatch):
    # The phase route works a block of vertices at a time; blocks of ~8 vertices put a block
    # boundary inside almost every ring, so every read across blocks (the orientation's ring,
    # the response's ring mean, the corrected fit's neighbours) is exercised.  The per-vertex
    # sums run in edge order whatever the blocks, so the numbers are the same to the bit, and
    # the jittered strip's plane waves still read their wavenumber (bound of the test above).
    s = strip(jitter=0.2)
    signals = np.cos(WAVENUMBERS[RESOLVED, None] * s.vertices[:, 0])
    rf = riesz(s, signals)
    whole = instantaneous_frequency(s, signals, rf)
    monkeypatch.setattr(edge_stencil, "BLOCK_EDGES", 50)
    s.cache.pop("frequency:stencil:lsq")
    blocked = instantaneous_frequency(s, signals, rf)
    assert np.array_equal(blocked, whole)
    median = np.median(blocked[:, away_from_edges(s)], axis=1)
    assert np.allclose(median / WAVENUMBERS[RESOLVED], 1.0, atol=0.05)


def test_the_phase_route_needs_no_per_edge_array_of_the_whole_surface(monkeypatch):
    # Memory, counted by tracemalloc (NumPy reports its buffers to it), per vertex of a 41k-vertex
    # icosphere (6 edges a vertex) with blocks of 4,096 edges and one thread:
    # - the cached stencil: its ends (4 bytes) and coefficients (24) of the gradient's edges and
    #   the Laplacian's (4 + 8), 40 bytes an edge, plus the points and row pointers (40 a vertex):
    #   280 bytes; bound 320.  Built a block at a time: bound 400 while building.
    # - a signal's work: about 25 whole-surface floats (its orientation, first fit, response, ...):
    #   200 bytes; bound 260.
    # The former stencil of sparse matrices held 964 bytes a vertex, peaked at 2,154 while built,
    # and a signal's per-edge arrays took 649: each bound fails by more than 2x there.
    monkeypatch.setenv("OMP_NUM_THREADS", "1")
    monkeypatch.setattr(edge_stencil, "BLOCK_EDGES", 4096)
    s = Surface(*icosphere(6))
    n = s.n_vertices
    rng = np.random.default_rng(0)
    f = rng.standard_normal((1, n))
    r = rng.standard_normal((1, n, 3))
    s.gradient("lsq"), s.stiffness  # the surface's own operators are not the estimator's
    tracemalloc.start()
    try:
        edge_stencil.edge_stencil(s, "lsq")
        stencil, building = tracemalloc.get_traced_memory()
        tracemalloc.reset_peak()
        instantaneous_frequency(s, f, r)
        work = tracemalloc.get_traced_memory()[1] - stencil
    finally:
        tracemalloc.stop()
    assert stencil / n < 320 and building / n < 400
    assert work / n < 260
    assert "frequency:stencil:lsq" in s.cache
    monkeypatch.setattr(edge_stencil, "CACHED_VERTICES", n)  # a large surface keeps no stencil
    monkeypatch.setattr("hht3d.geometry.surface.CACHED_GRADIENT_VERTICES", n)  # nor gradient operator
    big = Surface(*icosphere(6))
    instantaneous_frequency(big, f, r)
    np.testing.assert_array_equal(vertex_gradient(big, f[0]), vertex_gradient(s, f[0]))
    assert not any(key.startswith(("frequency:stencil", "gradient")) for key in big.cache)


def test_the_lsq_stencil_applies_the_gradient_operator_without_building_it(monkeypatch):
    # The stencil's gradient edges come from the least-squares coefficients over the adjacency, so no
    # (3n, n) operator (250 bytes a vertex) sits beside it: applied to a field they give the operator's
    # gradient to rounding (it adds c_ij f_j and the diagonal's −Σ c_ij f_i, the stencil c_ij (f_j − f_i)).
    s = strip(jitter=0.2)
    f = np.random.default_rng(2).standard_normal(s.n_vertices)
    expected = (s.gradient("lsq") @ f).reshape(-1, 3)

    def refuse(*_):
        raise AssertionError("the stencil built a gradient operator")

    monkeypatch.setattr(Surface, "gradient", refuse)
    stencil = edge_stencil.build_edge_stencil(s, "lsq")
    got = np.concatenate([block.fit(f[block.cols] - block.at_start(f)) for block in stencil.blocks()])
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12 * np.abs(expected).max())


def test_zero_signal_reads_zero(regular):
    s, _ = regular
    zero = np.zeros((1, s.n_vertices))
    for method in FREQUENCY_METHODS:
        assert np.all(instantaneous_frequency(s, zero, np.zeros((1, s.n_vertices, 3)), frequency=method) == 0)


def test_bad_arguments(regular):
    s, _ = regular
    f = np.zeros((2, s.n_vertices))
    with pytest.raises(InputError, match="frequency method"):
        instantaneous_frequency(s, f, np.zeros((2, s.n_vertices, 3)), frequency="hilbert")
    with pytest.raises(InputError, match="shape"):
        instantaneous_frequency(s, f, np.zeros((2, s.n_vertices, 2)))
    with pytest.raises(InputError, match="frequency"):
        monogenic(s, f, frequency="wavelet")
    with pytest.raises(InputError, match="Surface"):
        resolvable_frequency(s.vertices)


def test_resolvable_frequency_is_the_grid_nyquist_limit(regular):
    # A vertex of a regular grid carries area h² (h²/2 on edges, h²/4 at corners):
    # π/√A = π/h, the wavenumber of a wave with 2 points per wavelength.
    s, (phase, _) = regular
    limit = resolvable_frequency(s)
    inner = ~s.boundary_vertices
    assert np.allclose(limit[inner], np.pi / H)
    assert np.allclose(phase.resolvable, limit)
    # 2.2 points per wavelength is 0.91 of the limit: the regular strip resolves every wave
    assert np.all(WAVENUMBERS < np.pi / H)


def test_option_reaches_hht_the_graph_and_the_pipeline():
    from hht3d import graph
    from hht3d.pipeline.registry import OPERATIONS
    from hht3d.transform import hht

    s = Surface(*icosphere(3))
    f = np.cos(6 * np.arctan2(s.vertices[:, 1], s.vertices[:, 0])) + s.vertices[:, 2]
    eager = hht(s, f, frequency="gradient", max_imfs=1)
    (lazy,) = graph.compute(graph.hht(s, f, frequency="gradient", max_imfs=1), scheduler="synchronous", progress=False)
    assert eager.info["riesz"]["frequency"] == lazy.info["riesz"]["frequency"] == "gradient"
    expected = instantaneous_frequency(s, eager.imfs, eager.monogenic.riesz, frequency="gradient")
    assert np.allclose(eager.monogenic.frequency, expected) and np.allclose(lazy.monogenic.frequency, expected)
    (param,) = [p for p in OPERATIONS["hht"].params if p.name == "frequency"]
    assert param.default == "phase" and tuple(param.choices) == FREQUENCY_METHODS


def test_frequency_is_the_riesz_setting_and_method_its_former_name():
    s = Surface(*icosphere(2))
    f = np.stack([s.vertices[:, 0]])
    r = riesz(s, f)
    with pytest.warns(DeprecationWarning, match="write frequency='gradient'"):
        former = instantaneous_frequency(s, f, r, method="gradient")
    np.testing.assert_array_equal(former, instantaneous_frequency(s, f, r, frequency="gradient"))
