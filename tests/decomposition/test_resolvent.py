"""The filter applied by solves on SuperLU (hht3d.decomposition.resolvent): the bilaplacian's global cut as one
complex second-order system, ``(M̃ + t² L M̃⁻¹ L)⁻¹ y = Re (M̃ + i t L)⁻¹ y``.

Oracles: NumPy's dense solve of the real fourth-order system, and the dense generalized eigendecomposition of
``(L, M̃)`` for the whole IMF.  A needle-strewn sphere (:func:`helpers.meshes.sliver_sphere`) has negative
cotangent weights, so the membrane ``L`` is not the stiffness matrix, and with the area floor raised to 0.9 of the
median 15% of its vertices are floored, so ``M̃ ≠ M``: a system built from either of those instead fails.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import scipy.linalg as sl

from helpers.meshes import sliver_sphere
from hht3d import Surface, linalg
from hht3d.decomposition import emd, envelopes
from hht3d.decomposition.envelopes import floored_mass, is_delaunay, membrane_laplacian
from hht3d.decomposition.filtering import Filterer
from hht3d.decomposition.options import EMDOptions
from hht3d.decomposition.resolvent import passband, resolvent


@pytest.fixture
def needles(monkeypatch):
    monkeypatch.setattr(envelopes, "MASS_FLOOR", 0.9)
    s = Surface(*sliver_sphere(3, count=60, eps=1e-3, kind="corner"), name="needles")
    assert not is_delaunay(s) and np.mean(floored_mass(s) > s.mass_diagonal) > 0.1
    return s


def _dense(s):
    return membrane_laplacian(s).toarray(), floored_mass(s)


def test_the_complex_system_solves_the_bilaplacian_resolvent(needles):
    # Re (M̃ + itL)⁻¹ y against the dense solve of M̃ + t² L M̃⁻¹ L: both are exact up to rounding.  With
    # t λ̄ = 100 the real system's condition is 1 + t² λ̄² ≈ 1e4, so its rounding, 1e-16 times that, leaves 1e-10
    # a wide margin; a cut 100 times below the resolution is the filter's working range.
    lap, mass = _dense(needles)
    t = 100 / np.linalg.eigvalsh(lap / np.sqrt(np.outer(mass, mass))).max()
    y = np.random.default_rng(0).standard_normal(needles.n_vertices)
    solve, complex_system = resolvent(needles, mass, t, "superlu", lambda: pytest.fail("real system factorized"))
    expected = np.linalg.solve(np.diag(mass) + t**2 * lap @ np.diag(1 / mass) @ lap, y)
    assert complex_system
    np.testing.assert_allclose(solve(y), expected, rtol=0, atol=1e-10 * np.abs(expected).max())


def test_superlu_filters_a_global_bilaplacian_cut_by_one_complex_factorization(needles):
    # IMF 1 = Σ_j P(1/(1 + (λ_j/ω_c²)²)) ⟨φ_j, s⟩_M̃ φ_j over the generalized eigenpairs of (L, M̃), as the
    # module notes of filtering; 31 complex solves in the Clenshaw recurrence keep it to 1e-8 of the signal.
    signal = np.random.default_rng(1).standard_normal(needles.n_vertices)
    result = emd(needles, signal, method="filtering", max_imfs=1, evaluation="solves", backend="superlu")
    cut = result.info["imfs"][0]["cut_frequency"]
    lap, mass = _dense(needles)
    lam, phi = sl.eigh(lap, np.diag(mass))
    share = passband(1 / (1 + (lam / cut**2) ** 2), result.info["options"]["order"])
    expected = phi @ (share * (phi.T @ (mass * signal)))
    np.testing.assert_allclose(result.imfs[0], expected, atol=1e-8 * np.abs(signal).max())
    assert result.info["factorizations"] == 1 and result.info["backend"] == "superlu"


@pytest.mark.parametrize(
    "settings, backend",
    [({"filter": "membrane"}, "superlu"), ({"cut": "local"}, "superlu"), ({}, "no complex solver")],
)
def test_other_filters_and_backends_take_the_real_system(needles, settings, backend, monkeypatch):
    # The factorization splits only K = t² L M̃⁻¹ L with one t: a membrane filter (second order already), a local
    # cut (t per vertex) and a backend without complex_solver factorize M̃ + K itself on the envelopes' pattern.
    if backend != "superlu":
        entry = dataclasses.replace(linalg.SOLVER_BACKENDS["superlu"], complex_solver=None)
        monkeypatch.setitem(linalg.SOLVER_BACKENDS, "superlu", entry)
    options = EMDOptions(method="filtering", evaluation="solves", **settings)
    filterer = Filterer(needles, options, "superlu")
    signal = np.random.default_rng(2).standard_normal(needles.n_vertices)
    assert filterer.imf(signal) is not None
    assert filterer.n_complex == 0 and filterer.solver.n_factorizations >= 1
