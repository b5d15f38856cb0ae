"""The dense and ARPACK eigenpairs of ``L φ = λ M φ`` and the spectral bounds (hht3d.spectral.eigenpairs) against
SciPy's generalized eigh and ARPACK.

Relative errors are measured in the M-norm ``‖x‖_M = √(xᵀMx)``.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse.linalg as spla

from helpers.spectral import eigen_reference, generalized_eigh, m_error, mixed_signals
from hht3d.geometry.signals import fluctuation
from hht3d.geometry.surface import Surface
from hht3d.spectral import fractional_laplacian, spectral_bounds

# -- exactness of the three methods -------------------------------------------------------------


def test_dense_method_matches_generalized_eigh(jittered_grid):
    # Two dense double-precision eigendecompositions of a 600-vertex problem agree to
    # round-off: measured 4e-14 in the M-norm, bound 5e-13 (10x headroom).  A dense method
    # with a wrong mass scaling, a dropped mode or a wrong power is off by O(1).
    s = jittered_grid
    f = mixed_signals(s)
    dense = fractional_laplacian(s, f, potential="dense")
    assert np.all(m_error(s, dense, eigen_reference(s, f)) < 5e-13)


def test_spectral_arpack_equals_truncated_generalized_eigh(jittered_grid):
    # 40 of 599 modes: the ARPACK path; reference = the generalized eigh of this file cut at the
    # same modes.  ARPACK runs with tol=0 (machine precision), so both sides agree to
    # round-off: measured 2e-14 in the M-norm, bound 2e-13 (10x headroom).
    s = jittered_grid
    f = mixed_signals(s)
    values, _ = generalized_eigh(s)
    p = 40
    assert values[p] - values[p - 1] > 1e-3 * values[p - 1]  # the cut does not split a cluster
    reference = eigen_reference(s, fluctuation(s, f), count=p)
    s.cache.pop("riesz:eigenpairs", None)
    approx = fractional_laplacian(s, f, potential="spectral", eigenpairs=p)
    assert "riesz:eigenpairs" in s.cache  # computed by ARPACK, not the dense fallback
    assert np.all(m_error(s, approx, reference) < 2e-13)


# -- spectral bounds ----------------------------------------------------------------------------
def extreme_eigenvalues(surface):
    """``(λ_1, λ_max)`` of ``L φ = λ M φ`` from SciPy's ARPACK, independent of the bounds code."""
    lowest = spla.eigsh(
        surface.stiffness, k=surface.n_components + 1, M=surface.mass, sigma=-1e-6, which="LM", tol=1e-12
    )[0]
    highest = spla.eigsh(surface.stiffness, k=1, M=surface.mass, which="LA", tol=1e-10)[0]
    return float(np.sort(lowest)[-1]), float(highest[0])


def test_spectral_bounds_enclose_spectrum(spot, cloud, jittered_grid):
    # m = 0.9·λ_1 from eigsh at relative accuracy 1e-6, so 0.9 λ_1 (1 ± 1e-6); M̄ must enclose
    # λ_max and is tight (Gershgorin was 1.27-1.57 λ_max on these three models).
    for s in (spot, cloud, jittered_grid):
        lam1, lam_max = extreme_eigenvalues(s)
        m, mbar = spectral_bounds(s)
        assert m == pytest.approx(0.9 * lam1, rel=1e-5)
        assert lam_max <= mbar <= 1.1 * lam_max  # Collatz–Wielandt bound: measured 1.001-1.056 λ_max


def test_spectral_bounds_fallback_without_arpack(monkeypatch, jittered_grid):
    def fail(*args, **kwargs):
        raise spla.ArpackNoConvergence("forced", np.array([]), np.array([]))

    s = Surface(jittered_grid.vertices, jittered_grid.faces)
    lam1 = extreme_eigenvalues(s)[0]
    monkeypatch.setattr(spla, "eigsh", fail)
    m, _ = spectral_bounds(s)
    assert 0.45 * lam1 <= m <= lam1
