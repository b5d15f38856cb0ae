"""Decomposition quality (hht3d.decomposition.quality) and the EMD defaults held to it on realistic input."""

from __future__ import annotations

import threading
import warnings

import numpy as np
import pytest
import scipy.sparse.linalg as spla

import hht3d
from helpers.meshes import grid, icosphere, random_bump_sphere
from helpers.models import shipped_model_path
from hht3d import InputError, Surface, emd, hht
from hht3d.dataset.summary import quality_fields
from hht3d.decomposition import (
    ALIASED_AREA_LIMIT,
    DOMINANT_SHARE_LIMIT,
    ENERGY_RATIO_LIMIT,
    GUARD_TENSIONS,
    LEAKAGE_LIMIT,
    ORTHOGONALITY_LIMIT,
    PAPER_OPTIONS,
    QualityWarning,
    local_extrema,
)
from hht3d.decomposition.quality import decomposition_quality, quality_warnings_muted, warn_quality
from hht3d.geometry.signals import fluctuation, mean_curvature


@pytest.fixture(scope="module")
def spot():
    surface = hht3d.load(shipped_model_path("spot.ply"))
    return surface, mean_curvature(surface)


# -- the figures themselves, from their definitions ---------------------------------------------------
def test_orthogonal_parts_have_ratio_one_and_cancelling_parts_do_not():
    s = Surface(*grid(9, 7), name="grid")  # uniform interior masses, smaller on the boundary
    mass, x, y = s.mass_diagonal, s.vertices[:, 0], s.vertices[:, 1]
    a = fluctuation(s, np.cos(np.pi * x))
    b = fluctuation(s, np.cos(np.pi * y))
    b = b - (a @ (mass * b)) / (a @ (mass * a)) * a  # M-orthogonal to a, by construction here
    signal = a + b + 3.0  # the constant goes to the residue's mean, which does not count
    q = decomposition_quality(s, signal, np.vstack([a]), b + 3.0)
    assert q.energy_ratio == pytest.approx(1.0, abs=1e-12)
    assert q.orthogonality_index == pytest.approx(0.0, abs=1e-12)
    np.testing.assert_allclose(q.energy_share.sum(), 1.0, atol=1e-15)
    assert q.ok
    # IMFs a + 2b and -2b: energies |a|² + 4|b|² + 4|b|², cross term -2·2|b|² - ... written out here
    na, nb = a @ (mass * a), b @ (mass * b)
    q = decomposition_quality(s, signal, np.vstack([a + 2 * b, -2 * b]), b + 3.0)
    reference = na + nb
    assert q.energy_ratio == pytest.approx((na + 4 * nb + 4 * nb + nb) / reference, rel=1e-12)
    assert q.orthogonality_index == pytest.approx(2 * (-4 * nb - 2 * nb + 2 * nb) / reference, rel=1e-12)
    assert not q.ok and "cancel" in q.warnings[0]


def test_spike_is_max_over_99th_percentile():
    s = Surface(*icosphere(3), name="sphere")
    signal = np.zeros(s.n_vertices)
    signal[: s.n_vertices // 2] = 1.0
    signal[-1] = 1e3  # one vertex: far beyond the 99th percentile of |s − s̄|
    q = decomposition_quality(s, signal, np.zeros((0, s.n_vertices)), signal)
    centred = np.abs(fluctuation(s, signal))
    assert q.signal_spike == pytest.approx(centred.max() / np.percentile(centred, 99), rel=1e-12)
    assert q.signal_spike > 20 and any("spikes" in w for w in q.warnings)


def test_bad_arguments():
    s = Surface(*icosphere(2))
    with pytest.raises(InputError, match="Surface"):
        decomposition_quality("mesh", np.zeros(3), np.zeros((0, 3)), np.zeros(3))
    with pytest.raises(InputError, match="shape"):
        decomposition_quality(s, np.zeros(3), np.zeros((0, s.n_vertices)), np.zeros(s.n_vertices))


def test_leaking_imfs_are_reported_with_both_parts():
    s = Surface(*grid(9, 7), name="grid")
    mass, x, y = s.mass_diagonal, s.vertices[:, 0], s.vertices[:, 1]
    a, b = fluctuation(s, np.cos(np.pi * x)), fluctuation(s, np.cos(np.pi * y))
    b = b - (a @ (mass * b)) / (a @ (mass * a)) * a
    na, nb = a @ (mass * a), b @ (mass * b)
    # parts a/2, a/2 + 1.5 b and residue -b/2 (a ⟂ b): a is split over two IMFs, ⟨x1, x2⟩ = na/4 > 0,
    # and 1.5 b cancels against -b/2, ⟨x2, r⟩ = -0.75 nb; each pair counts twice in IO
    q = decomposition_quality(s, a + b, np.vstack([a / 2, a / 2 + 1.5 * b]), -0.5 * b)
    reference = na + nb
    assert q.io_leaking == pytest.approx(0.5 * na / reference, rel=1e-12)
    assert q.io_cancelling == pytest.approx(-1.5 * nb / reference, rel=1e-12)
    assert q.orthogonality_index == pytest.approx(q.io_leaking + q.io_cancelling, rel=1e-12)
    leaking = decomposition_quality(s, a, np.vstack([a / 2, a / 2]), np.zeros_like(a))  # one component, halved
    assert leaking.orthogonality_index == pytest.approx(0.5, rel=1e-12) and 0.5 > LEAKAGE_LIMIT
    assert any("share content" in w for w in leaking.warnings)
    assert "leaking" in leaking.summary()


# -- the defaults on realistic input ----------------------------------------------------------------
def test_paper_envelopes_cancel_on_spot_and_the_defaults_do_not(spot):
    """Spot's mean curvature has a sharp crease at the tail (±180 against a median of 5): the
    paper's thin plate bulges through it and the IMFs cancel (energy ratio 18.9, IO -15.3, the
    issue's numbers).  The defaults measure 0.80 / +0.20."""
    surface, signal = spot
    with pytest.warns(QualityWarning, match="cancel"):
        paper = emd(surface, mean_curvature(surface, min_area=0), PAPER_OPTIONS)
    assert paper.quality.energy_ratio > 10 and paper.quality.orthogonality_index < -10
    with warnings.catch_warnings():
        warnings.simplefilter("error", QualityWarning)  # the defaults raise no quality warning
        result = emd(surface, signal)
    assert result.quality.energy_ratio <= ENERGY_RATIO_LIMIT
    assert result.quality.orthogonality_index >= ORTHOGONALITY_LIMIT
    # the guard did work: some IMF needed more tension, and every accepted extraction is within
    # its tolerance or the least cancelling of the ladder
    per_imf = result.info["imfs"]
    assert any(d["attempts"] > 1 for d in per_imf)
    assert {d["tension"] for d in per_imf} <= {3.0, *GUARD_TENSIONS, None}


def test_open_scan_meets_the_quality_targets(shared_model):
    surface = hht3d.load(shared_model("spacetime_face_neutral.ply"))  # open, two boundary loops
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", QualityWarning)  # it leaks: IO +0.30 > LEAKAGE_LIMIT, measured
        result = emd(surface, mean_curvature(surface))  # measured 0.70 / +0.30 (paper: 2.95 / -1.5)
    assert result.quality.energy_ratio <= ENERGY_RATIO_LIMIT
    assert result.quality.orthogonality_index >= ORTHOGONALITY_LIMIT


def test_white_noise_is_a_dyadic_filter_bank():
    """Extrema counts drop 2.5-5x from IMF to IMF (Flandrin et al.'s filter bank in 2-D, where a
    halved wavenumber means 4x fewer extrema).  Measured 3035, 1070, 327, 86, 28, 8: 2.8-3.8."""
    s = Surface(*icosphere(5))
    result = emd(s, np.random.default_rng(0).standard_normal(s.n_vertices))
    counts = [sum(map(len, local_extrema(s, imf))) for imf in result.imfs]
    ratios = [counts[i] / counts[i + 1] for i in range(len(counts) - 1) if counts[i + 1] >= 20]
    assert len(ratios) >= 3
    assert all(2.5 <= r <= 5 for r in ratios), counts


def test_two_eigenfunctions_on_a_real_mesh(spot):
    """Laplacian eigenfunctions φ_5 ± φ_100 of spot (eigenvalue ratio 19.5, from SciPy's eigsh):
    IMF 1 is φ_100.  Measured correlation 0.979 and 0.974 (paper options: 0.940).  The start
    vector is fixed, since eigsh's random one flips the eigenfunctions' signs from run to run."""
    surface, _ = spot
    values, vectors = spla.eigsh(surface.stiffness, k=101, M=surface.mass, sigma=-1e-8, v0=np.ones(surface.n_vertices))
    fine = vectors[:, 100] / np.abs(vectors[:, 100]).max()
    assert 10 <= values[100] / values[5] <= 30
    for sign in (1, -1):
        signal = vectors[:, 5] / np.abs(vectors[:, 5]).max() + sign * fine
        assert abs(np.corrcoef(emd(surface, signal).imfs[0], fine)[0, 1]) >= 0.97


def test_local_mean_correction_keeps_slow_content_out_of_the_imfs():
    """Random bumps of two widths on a sphere: the curvature has 4.2% of its norm in the ten
    lowest Laplacian eigenfunctions (SciPy's eigsh).  The IMFs together should carry no more than
    that; measured 4.2% with the correction and 58% without it (IMFs and residue cancel there)."""
    v, f, _, _ = random_bump_sphere(subdivisions=4)
    s = Surface(v, f)
    signal = mean_curvature(s)
    mass = s.mass_diagonal
    _, basis = spla.eigsh(s.stiffness, k=10, M=s.mass, sigma=-1e-8)

    def low(x):
        return np.linalg.norm(basis.T @ (mass * x))

    reference = np.sqrt(fluctuation(s, signal) @ (mass * fluctuation(s, signal)))
    corrected = emd(s, signal).imfs.sum(axis=0)
    assert low(corrected) <= 0.06 * reference
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", QualityWarning)
        uncorrected = emd(s, signal, mean_correction=None).imfs.sum(axis=0)
    assert low(uncorrected) >= 0.3 * reference


def test_hht_result_reports_the_same_quality(spot):
    surface, signal = spot
    result = hht(surface, signal, max_imfs=3)
    q = result.quality
    reference = decomposition_quality(surface, signal, result.imfs, result.residue)
    assert q.energy_ratio == reference.energy_ratio and q.warnings == reference.warnings
    assert set(q.as_dict()) == {
        "energy_ratio",
        "orthogonality_index",
        "io_leaking",
        "io_cancelling",
        "energy_share",
        "signal_spike",
        "warnings",
    }
    with pytest.raises(InputError, match="did you mean 'max_imfs'"):
        hht(surface, signal, max_imf=3)


# -- muting, thread by thread ---------------------------------------------------------------------------
# Under a threaded Dask scheduler two tasks are muted at once.  With warnings.catch_warnings (which swaps
# the process-wide filters) the first to leave its block restored the filters of before both, so the
# other task's warning was shown: that is how a QualityWarning reached the CLI's stderr
# (tests/test_stopping.py, threads scheduler, 1 run in ~6).  Here A leaves while B is still inside.
def test_quality_warnings_stay_muted_in_a_thread_when_another_thread_unmutes():
    a_inside, b_inside, a_left = threading.Event(), threading.Event(), threading.Event()

    def a():
        with quality_warnings_muted():
            a_inside.set()
            b_inside.wait(10)
        a_left.set()

    def b():
        a_inside.wait(10)
        with quality_warnings_muted():
            b_inside.set()
            a_left.wait(10)
            warn_quality("from B", stacklevel=1)

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        threads = [threading.Thread(target=a), threading.Thread(target=b)]
        for t in threads:
            t.start()
        for t in threads:
            t.join(20)
    assert a_left.is_set() and [str(w.message) for w in caught] == []
    with pytest.warns(QualityWarning, match="outside"):
        warn_quality("outside", stacklevel=1)


def _quality_warnings(surface, signal, max_imfs=2):
    with warnings.catch_warnings(record=True) as issued:
        warnings.simplefilter("always", QualityWarning)
        result = hht(surface, signal, max_imfs=max_imfs)
    return result, [str(w.message) for w in issued if issubclass(w.category, QualityWarning)]


def test_one_imf_holding_nearly_all_the_energy_is_reported():
    """A fine pattern of amplitude 1 beside a coarse one of 0.03: IMF 1 holds 99.5% of the energy
    (measured; white noise, the case the limit must let through, 91%), every frequency within the
    limit.  The quality line must say so, not stay clean."""
    v, f = icosphere(3)
    pattern = np.sin(9 * np.arctan2(v[:, 1], v[:, 0])) * np.sin(np.arccos(np.clip(v[:, 2], -1, 1))) ** 9
    result, issued = _quality_warnings(Surface(v, f), pattern + 0.03 * v[:, 2])
    assert result.quality.energy_share[0] > DOMINANT_SHARE_LIMIT
    assert [w for w in result.quality.warnings if "IMF 1 holds" in w] and not result.quality.ok
    assert not [w for w in result.quality.warnings if "resolution limit" in w], result.quality.warnings
    assert any("IMF 1 holds" in w for w in issued), issued  # issued too, so the CLI and summaries see it
    assert "WARNING: IMF 1 holds" in result.quality.summary()
    assert any("IMF 1 holds" in w for w in quality_fields(result, result.surface)["warnings"])


def test_frequencies_above_the_resolution_limit_are_reported():
    """cos(60x)·cos(60y) on a 16x16 grid of spacing 1/15, whose limit is π·15 = 47 rad/unit: the
    pattern is finer than the mesh, and 20% of IMF 1's area reads above the limit (measured)."""
    surface = Surface(*grid(16, 16))
    x = surface.vertices
    result, issued = _quality_warnings(surface, np.cos(60 * x[:, 0]) * np.cos(60 * x[:, 1]))
    share = result.spectrum.resolution.area_per_signal[0]
    assert share > ALIASED_AREA_LIMIT, share
    aliased = [w for w in result.quality.warnings if "above the resolution limit" in w]
    assert len(aliased) == 1 and aliased[0].startswith("IMF 1 has"), result.quality.warnings
    assert any("above the resolution limit" in w for w in issued), issued


def test_a_resolved_decomposition_has_neither_warning(spot):
    """Spot's mean curvature, two IMFs: 60% and 14% of the energy, 0.25% of IMF 1's area above the
    limit (measured): neither limit is near."""
    result, issued = _quality_warnings(*spot)
    assert max(result.quality.energy_share[:-1]) < DOMINANT_SHARE_LIMIT
    assert max(result.spectrum.resolution.area_per_signal) < ALIASED_AREA_LIMIT
    assert result.quality.ok and issued == [], (result.quality.warnings, issued)


def test_one_imf_is_not_reported_as_dominant():
    """With a single IMF there are no others to compare it with: no dominance warning."""
    signal = np.random.default_rng(0).standard_normal(162)
    quality = decomposition_quality(Surface(*icosphere(2)), signal, signal[None], np.zeros(162))
    assert quality.energy_share[0] == pytest.approx(1.0)
    assert not [w for w in quality.warnings if "holds" in w], quality.warnings
