"""Iterative filtering (hht3d.decomposition.filtering) against its mathematics.

Oracles: the regularized incomplete beta function (scipy.special.betainc), a dense generalized
eigendecomposition of the filter's pencil, and the sine whose extrema spacing is known.
"""

import numpy as np
import pytest
import scipy.linalg as sl
import scipy.sparse.linalg as spla

from helpers.meshes import grid, icosphere
from hht3d import Surface, emd, hht
from hht3d.decomposition.filtering import (
    POLYNOMIAL_TOLERANCE,
    apply_passband,
    opposite_distances,
    passband,
    uses_polynomial,
)
from hht3d.geometry.signals import fluctuation


@pytest.fixture(scope="module")
def sphere():
    return Surface(*icosphere(3), name="icosphere")


def test_passband_is_the_symmetric_bernstein_high_pass():
    g = np.linspace(0, 1, 101)
    for m in (1, 2, 8, 16):
        p = passband(g, m)
        assert p[0] == 1 and p[-1] == 0 and np.all(np.diff(p) <= 0)
        np.testing.assert_allclose(p + passband(1 - g, m), 1, atol=1e-14)  # symmetric about g = 1/2
    np.testing.assert_allclose(passband(g, 1), 1 - g, atol=1e-15)  # classic IF's I - W
    np.testing.assert_allclose(passband(g, 2), 1 - 3 * g**2 + 2 * g**3, atol=1e-15)  # the smoothstep


@pytest.mark.parametrize("order", [1, 2, 8, 16, 40])
def test_clenshaw_matches_the_eigenbasis_and_never_cancels(order):
    """A random SPD pencil: ``P(W) r`` from the recurrence equals ``Σ P(1/(1+μ)) c φ`` of the dense
    generalized eigendecomposition of ``(K, M)`` to 1e-12, and ``⟨f, r − f⟩_M = Σ P(1−P) c² ≥ 0``."""
    rng = np.random.default_rng(order)
    n = 60
    a = rng.standard_normal((n, n))
    k, mass = a @ a.T, rng.uniform(0.2, 3.0, n)
    system = k + np.diag(mass)
    for _ in range(5):
        r = rng.standard_normal(n)
        f = apply_passband(lambda b: np.linalg.solve(system, b), mass, r, order)
        mu, phi = sl.eigh(k, np.diag(mass))
        c = phi.T @ (mass * r)
        share = passband(1 / (1 + mu), order)
        np.testing.assert_allclose(f, phi @ (share * c), atol=1e-12 * np.abs(r).max())
        inner = (mass * f) @ (r - f)
        assert inner >= -1e-12 * (mass * r) @ r
        np.testing.assert_allclose(inner, np.sum(share * (1 - share) * c**2), rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("evaluation", ["solves", "polynomial"])
def test_first_imf_is_the_filter_of_the_module_notes(sphere, evaluation):
    """On an icosphere (Delaunay, no area below the floor, so ``K = t² L M⁻¹ L`` and ``M̃ = M``) IMF 1 is
    ``Σ_j P(1/(1 + (λ_j/ω_c²)²)) ⟨φ_j, s⟩_M φ_j`` over the generalized eigenpairs of ``(L, M)``: to 1e-8
    pointwise by solves, and within the polynomial's ``POLYNOMIAL_TOLERANCE`` (M-norm, relative) by it."""
    s = sphere
    signal = np.random.default_rng(1).standard_normal(s.n_vertices)
    result = emd(s, signal, method="filtering", cut="global", max_imfs=1, evaluation=evaluation)
    cut = result.info["imfs"][0]["cut_frequency"]
    lam, phi = sl.eigh(s.stiffness.toarray(), np.diag(s.mass_diagonal))
    share = passband(1 / (1 + (lam / cut**2) ** 2), result.info["options"]["order"])
    expected = phi @ (share * (phi.T @ (s.mass_diagonal * signal)))
    if evaluation == "solves":
        np.testing.assert_allclose(result.imfs[0], expected, atol=1e-8 * np.abs(signal).max())
    else:
        m = s.mass_diagonal
        error = np.sqrt(m @ (result.imfs[0] - expected) ** 2 / (m @ signal**2))
        assert error <= POLYNOMIAL_TOLERANCE and result.info["imfs"][0]["degree"] > 0, error
        assert result.info["backend"] == "chebyshev" and result.info["factorizations"] == 0


def test_auto_takes_the_polynomial_on_large_surfaces_and_global_cuts_only():
    from hht3d import linalg
    from hht3d.decomposition import filtering
    from hht3d.decomposition.options import EMDOptions
    from hht3d.linalg.estimate import COSTS, SLOW_FALLBACK_VERTICES

    # from POLYNOMIAL_VERTICES on a fast default backend, from SLOW_FALLBACK_VERTICES on SuperLU (HHT3D_BACKEND)
    slow = COSTS[linalg.default_backend()].slow
    start = SLOW_FALLBACK_VERTICES if slow else filtering.POLYNOMIAL_VERTICES
    assert not uses_polynomial(EMDOptions(method="filtering"), start - 1)
    assert uses_polynomial(EMDOptions(method="filtering"), start)
    assert uses_polynomial(EMDOptions(method="filtering"), SLOW_FALLBACK_VERTICES, "superlu")
    assert uses_polynomial(EMDOptions(method="filtering"), 500, coarse=True)  # a coarse level of the hierarchy
    assert not uses_polynomial(EMDOptions(method="filtering", evaluation="solves"), 500, coarse=True)
    assert not uses_polynomial(EMDOptions(method="filtering", cut="local", evaluation="polynomial"), 10**9)
    assert not uses_polynomial(EMDOptions(method="filtering", evaluation="solves"), 10**9)


def test_a_polynomial_with_a_local_cut_is_refused_in_one_line(sphere):
    from hht3d.errors import InputError

    with pytest.raises(InputError, match="evaluation='polynomial' needs cut='global'"):
        emd(sphere, sphere.vertices[:, 2], method="filtering", evaluation="polynomial", cut="local")


def test_an_imf_beyond_the_largest_degree_is_filtered_by_solves(sphere, monkeypatch):
    """With the largest degree lowered below IMF 2's, IMF 1 is a polynomial and IMF 2 comes from solves, and
    both equal the solves' run (the polynomial to its tolerance)."""
    from hht3d.decomposition import filtering

    signal = np.random.default_rng(4).standard_normal(sphere.n_vertices)
    polynomial = emd(sphere, signal, method="filtering", evaluation="polynomial", max_imfs=2)
    first, second = (imf["degree"] for imf in polynomial.info["imfs"])
    monkeypatch.setattr(filtering, "MAX_POLYNOMIAL_DEGREE", (first + second) // 2)
    mixed = emd(sphere, signal, method="filtering", evaluation="polynomial", max_imfs=2)
    assert "degree" in mixed.info["imfs"][0] and "degree" not in mixed.info["imfs"][1]
    assert mixed.info["factorizations"] == 1 and mixed.info["backend"].startswith("chebyshev+")
    solves = emd(sphere, signal, method="filtering", evaluation="solves", max_imfs=2)
    m = sphere.mass_diagonal
    for got in (polynomial, mixed):
        error = np.sqrt((m * (got.imfs - solves.imfs) ** 2).sum() / (m @ signal**2))
        assert error < 2 * POLYNOMIAL_TOLERANCE, error


@pytest.mark.parametrize("options", [{"cut": "global"}, {"cut": "local"}, {"filter": "membrane"}, {"order": 2}])
def test_no_imf_cancels_what_is_left(sphere, options):
    """Every step's ``⟨f_k, r_k⟩_M ≥ 0``, so the energy ratio is at most 1 (the steps telescope).  A
    pair of IMFs that are not adjacent may still have a small negative cross term: only each IMF
    against all that follows it is bounded."""
    s = sphere
    signal = np.random.default_rng(2).standard_normal(s.n_vertices)
    result = emd(s, signal, method="filtering", **options)
    assert result.n_imfs >= 2
    residue = signal.copy()
    for imf in result.imfs:
        residue = residue - imf
        assert (s.mass_diagonal * imf) @ fluctuation(s, residue) >= -1e-10 * (s.mass_diagonal * signal) @ signal
    assert result.quality.energy_ratio <= 1 + 1e-10


def test_two_eigenfunctions_are_separated(sphere):
    """The sum of eigenfunctions 9 and 144 (eigenvalue ratio 12): IMF 1 is the finer one (corr > 0.99)
    and the residue plus later IMFs the coarser one."""
    s = Surface(*icosphere(4))
    values, vectors = spla.eigsh(s.stiffness, k=145, M=s.mass, sigma=-1e-8, v0=np.ones(s.n_vertices))
    fine, coarse = vectors[:, 144] / np.abs(vectors[:, 144]).max(), vectors[:, 9] / np.abs(vectors[:, 9]).max()
    result = emd(s, fine + coarse, method="filtering")
    assert abs(np.corrcoef(result.imfs[0], fine)[0, 1]) > 0.99
    rest = result.residue + result.imfs[1:].sum(axis=0)
    assert abs(np.corrcoef(rest, coarse)[0, 1]) > 0.99


def test_opposite_distance_of_a_sine_is_its_half_wavelength():
    """On a strip, ``sin(ωx)`` has its extrema ``π/ω`` from the nearest opposite ones."""
    from hht3d.decomposition.extrema import active_extrema
    from hht3d.decomposition.options import EMD_DEFAULTS

    vertices, faces = grid(400, 3, 1.0, 0.01)
    s = Surface(vertices, faces)
    omega = 2 * np.pi * 10
    is_max, is_min, _ = active_extrema(s, np.sin(omega * vertices[:, 0]), EMD_DEFAULTS)
    np.testing.assert_allclose(np.median(opposite_distances(vertices, is_max, is_min)), np.pi / omega, rtol=0.02)


def test_stopping_rules(sphere):
    s = sphere
    noise = np.random.default_rng(3).standard_normal(s.n_vertices)
    assert emd(s, noise, method="filtering", max_imfs=2).n_imfs == 2
    assert emd(s, noise, method="filtering", max_imfs=2).info["stop_reason"] == "max_imfs"
    constant = emd(s, np.full(s.n_vertices, 2.0), method="filtering")
    assert constant.n_imfs == 0 and constant.info["stop_reason"] == "constant"
    trend = emd(s, s.vertices[:, 2], method="filtering")  # one maximum and one minimum: nothing to filter
    assert trend.n_imfs == 0 and trend.info["stop_reason"] == "extrema"
    full = emd(s, noise, method="filtering", max_imfs=64)
    assert full.info["stop_reason"] in ("extrema", "energy") and full.n_imfs < 64
    counts = [d["n_maxima"] + d["n_minima"] for d in full.info["imfs"]]
    assert counts == sorted(counts, reverse=True)  # every IMF starts from fewer extrema


def test_method_reaches_hht_and_records_itself(sphere):
    s = sphere
    signal = s.vertices[:, 0] * s.vertices[:, 1] + 0.1 * np.sin(12 * s.vertices[:, 2])
    direct = emd(s, signal, method="filtering", max_imfs=2)
    result = hht(s, signal, method="filtering", max_imfs=2)
    np.testing.assert_array_equal(result.imfs, direct.imfs)
    assert result.info["emd"]["method"] == "filtering" and direct.info["options"]["method"] == "filtering"
    assert direct.info["sifts"] == 0 and direct.info["solves"] > 0
    assert direct.info["factorizations"] == direct.n_imfs  # one numeric factorization per IMF (global cut)


def test_a_low_mode_is_not_cut_into_many_imfs():
    """Spot's third eigenfunction: its extrema lie closer than its frequency says (1.9/d, not π/d), so
    the cut falls inside it and IMF 1 takes about half.  What is left has the same extrema, so the
    next IMF would take half again, and so on to ``max_imfs``: the trend stop ends after one."""
    from hht3d import data_path, load

    spot = load(data_path("spot.ply"))
    _, vectors = spla.eigsh(spot.stiffness, k=3, M=spot.mass, sigma=-1e-8, v0=np.ones(spot.n_vertices))
    result = emd(spot, vectors[:, 2], method="filtering")
    assert result.n_imfs == 1 and result.info["stop_reason"] == "extrema"
    assert 0.2 < result.quality.energy_share[0] < 0.8
