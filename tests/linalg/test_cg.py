"""The iterative backend ``cg`` (hht3d.linalg.cg) against SuperLU, the direct path, as oracle.

On spot (2,930 vertices) and the point cloud of its vertices: the two second-order systems CG is
for (the membrane resolvent ``M + tL`` at the ``t`` of a real filtering run, ``L + σM`` at the
Riesz quadrature's extreme shifts), membrane filtering EMD and the Riesz transform end to end,
and the ways CG must fail loudly instead of returning a wrong answer.
"""

import numpy as np
import pytest
import scipy.sparse as sp

from helpers.spectral import m_error, mixed_signals
from helpers.systems import relative_error
from hht3d import InputError, Surface, emd, linalg
from hht3d.cli import main
from hht3d.errors import NumericalError
from hht3d.geometry.signals import mean_curvature
from hht3d.linalg import cg
from hht3d.spectral import fractional_laplacian, quadrature_plan, spectral_bounds
from hht3d.spectral.shifts import shifted_matrix

pytestmark = pytest.mark.skipif("cg" not in linalg.available_backends(), reason="pyamg is not installed")


@pytest.fixture(scope="module", params=["mesh", "cloud"])
def surface(request, spot):
    return spot if request.param == "mesh" else Surface(spot.vertices.copy(), name="spot points")


@pytest.fixture(scope="module")
def signal(spot):
    return mean_curvature(spot)


def membrane(surface, t):
    return (sp.diags(surface.mass_diagonal) + t * surface.stiffness).tocsr()


def test_cg_is_registered_thread_safe_after_the_direct_backends(capsys):
    entry = linalg.SOLVER_BACKENDS["cg"]
    assert entry.iterative and entry.lock is None
    assert list(linalg.SOLVER_BACKENDS)[-1] == "cg" and linalg.default_backend() != "cg"
    assert main(["info", "--backends"]) == 0
    assert "smoothed-aggregation" in capsys.readouterr().out


def test_cg_solves_equal_superlus(surface, signal):
    """Within 1e-8 relative (100x the residual asked for; measured <= 7e-11 on nefertiti), for one
    column and several, at the first and last IMF's ``t`` of spot's filtering and the extreme shifts."""
    plan = quadrature_plan(surface, 1e-8, "superlu")
    cut = [imf["cut_frequency"] for imf in emd(surface, signal, method="filtering", filter="membrane").info["imfs"]]
    matrices = [membrane(surface, 1 / c**2) for c in (cut[0], cut[-1])]
    matrices += [shifted_matrix(surface, s) for s in (plan.sigmas[0], plan.sigmas[-1])]
    b = np.column_stack([surface.mass_diagonal * signal, np.random.default_rng(0).standard_normal(len(signal))])
    for a in matrices:
        exact = linalg.factorize(a, "superlu").solve(b)
        factor = linalg.factorize(a, "cg")
        assert relative_error(factor.solve(b[:, 0]), exact[:, 0]) <= 1e-8
        found = factor.solve(b)
        assert found.shape == b.shape
        assert all(relative_error(found[:, k], exact[:, k]) <= 1e-8 for k in range(2))


def test_membrane_filtering_imfs_equal_the_direct_backends(surface, signal):
    """31 solves per IMF, each within 1e-10 residual: IMFs and residue within 1e-8 of the signal's
    magnitude (measured 2e-11), the same count and the same cuts (no extremum flips)."""
    options = {"method": "filtering", "filter": "membrane"}
    direct, iterative = (emd(surface, signal, backend=b, **options) for b in ("superlu", "cg"))
    scale = np.abs(signal).max()
    assert iterative.imfs.shape == direct.imfs.shape and iterative.info["backend"] == "cg"
    assert np.abs(iterative.imfs - direct.imfs).max() <= 1e-8 * scale
    assert np.abs(iterative.residue - direct.residue).max() <= 1e-8 * scale
    assert [i["cut_frequency"] for i in iterative.info["imfs"]] == [i["cut_frequency"] for i in direct.info["imfs"]]


@pytest.mark.parametrize("tol", [1e-8, 1e-4])
def test_riesz_potential_equals_the_direct_one_within_its_tol(surface, tol):
    """``L^{-1/2}`` by the quadrature with CG solves (residual ``tol/100``) is within ``tol/10`` of
    the direct one in the M-norm (measured 3e-11 at 1e-8, 4e-7 at 1e-4)."""
    f = mixed_signals(surface)
    direct = fractional_laplacian(surface, f, backend="superlu", tol=tol)
    assert np.all(m_error(surface, fractional_laplacian(surface, f, backend="cg", tol=tol), direct) <= tol / 10)


def test_the_caller_tolerance_sets_the_residual():
    assert cg.rtol_for(None) == cg.DEFAULT_RTOL
    assert cg.rtol_for(1e-8) == 1e-10 and cg.rtol_for(1e-13) == cg.MIN_RTOL
    a = sp.identity(3, format="csr")
    assert linalg.SymbolicFactorization(a, "cg", tol=1e-6)._impl.rtol == 1e-8


def test_no_convergence_in_the_cap_is_a_clear_error(spot, signal, monkeypatch):
    monkeypatch.setattr(cg, "MAX_ITERATIONS", 2)
    factor = linalg.factorize(membrane(spot, 1e3), "cg")
    expected = r"CG did not converge on the 2,930-row .* 2 iterations: relative residual"
    with pytest.raises(NumericalError, match=expected):
        factor.solve(spot.mass_diagonal * signal)


def test_an_indefinite_system_is_refused(spot):
    m, _ = spectral_bounds(spot, backend="superlu")
    with pytest.raises(NumericalError, match="not SPD"):
        linalg.factorize(shifted_matrix(spot, -10 * m), "cg").solve(np.ones(spot.n_vertices))


@pytest.mark.parametrize("options", [{}, {"method": "filtering"}, {"method": "sifting", "envelope": "harmonic"}])
def test_emd_refuses_cg_for_fourth_order_systems(spot, signal, options):
    """Sifting's envelopes and the bilaplacian filter: SA-PCG needs up to 1,943 iterations there."""
    with pytest.raises(InputError, match="second-order systems only"):
        emd(spot, signal, backend="cg", **options)
