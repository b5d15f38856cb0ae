"""Iterative filtering on levels (hht3d.decomposition.multiresolution) against the direct path.

Oracles: the signal itself (the IMFs and residue telescope back to it), the direct full-resolution
filtering (identical until the first residue moves to a coarser level; quality figures within the
issue's 0.01 after), and sifting (which never uses levels).
"""

import numpy as np
import pytest
from scipy.special import eval_legendre

from helpers.meshes import icosphere
from hht3d import Surface, data_path, emd, load
from hht3d.decomposition.envelopes import is_delaunay
from hht3d.decomposition.multiresolution import MULTIRESOLUTION_VERTICES, SPACING_LIMIT, uses_levels
from hht3d.decomposition.options import EMDOptions
from hht3d.geometry.signals import mean_curvature


@pytest.fixture(scope="module")
def sphere():
    return Surface(*icosphere(6), name="icosphere")


@pytest.fixture(scope="module")
def signal(sphere):
    """Zonal harmonics of degrees 60, 20 and 6 and a tilted one: cuts from fine to coarse."""
    x, y, z = sphere.vertices.T
    return eval_legendre(60, z) + 2 * eval_legendre(20, z) + 3 * eval_legendre(6, (x + z) / np.sqrt(2))


@pytest.fixture(scope="module")
def runs(sphere, signal):
    """Levels and the direct path with the defaults, and levels filtering by solves (as the direct path does)."""
    found = {mode: emd(sphere, signal, method="filtering", multiresolution=mode) for mode in ("always", "never")}
    found["solves"] = emd(sphere, signal, method="filtering", multiresolution="always", evaluation="solves")
    return found


def test_the_imfs_telescope_back_to_the_signal(runs, signal):
    levels = runs["always"]
    total = levels.imfs.sum(axis=0) + levels.residue
    np.testing.assert_allclose(total, signal, atol=1e-12 * np.abs(signal).max())
    used = [imf["level"] for imf in levels.info["imfs"]]
    assert used == sorted(used) and used[-1] >= 1, used  # the residues moved to coarser levels
    assert levels.info["levels"][0] == len(signal)
    assert len(levels.levels) == levels.n_imfs


def test_each_residue_moves_to_the_coarsest_level_resolving_its_cut(sphere, runs):
    from hht3d.geometry.hierarchy import hierarchy

    levels = hierarchy(sphere)
    for imf in runs["always"].info["imfs"]:
        target = imf["residue_level"]
        assert levels.levels[target].spacing * imf["cut_frequency"] <= SPACING_LIMIT or target == imf["level"]
        coarser = levels.level(target + 1)
        assert coarser is None or coarser.spacing * imf["cut_frequency"] > SPACING_LIMIT
        assert 0 <= imf["transfer_error"] < 0.05


def test_auto_filters_by_polynomial_where_it_gives_the_potential_and_by_solves_elsewhere(runs):
    """Coarse levels are well-shaped (their Laplacian is intrinsic Delaunay: tests/geometry/test_hierarchy.py), so
    ``evaluation="auto"`` takes the polynomial there; on an input below POLYNOMIAL_VERTICES only where its pass
    gives the Riesz potential too (the icosphere, Delaunay), and solves elsewhere (spot: negative cotangents)."""
    info = runs["always"].info["imfs"]
    assert any(imf["level"] > 0 for imf in info)
    assert all("degree" in imf and imf["factorizations"] == 0 for imf in info), info
    spot = load(data_path("spot.ply"))
    assert not is_delaunay(spot)
    info = emd(spot, mean_curvature(spot), method="filtering", multiresolution="always", max_imfs=3).info["imfs"]
    assert any(imf["level"] == 0 for imf in info)
    assert all(("degree" in imf) == (imf["level"] > 0) for imf in info), info


def test_the_direct_imfs_up_to_the_first_move_which_differs_by_its_transfer_error(runs, signal, sphere):
    """Until a residue moves, both paths compute the same filter (by solves) on the same residue; the IMF whose
    residue moves differs from the direct one by exactly ``r_k − P R r_k``, whose norm ``transfer_error`` reports."""
    on, off = runs["solves"], runs["never"]
    if any("degree" in imf for imf in off.info["imfs"]):  # SuperLU's "auto" filters 41k vertices by polynomial
        off = emd(sphere, signal, method="filtering", multiresolution="never", evaluation="solves")
    moved = next(k for k, imf in enumerate(on.info["imfs"]) if imf["residue_level"] > imf["level"])
    np.testing.assert_allclose(on.imfs[:moved], off.imfs[:moved], atol=1e-10 * np.abs(signal).max())
    mass = sphere.mass_diagonal
    residue = signal - off.imfs[: moved + 1].sum(axis=0)
    difference = on.imfs[moved] - off.imfs[moved]
    ratio = np.sqrt(mass @ difference**2 / (mass @ residue**2))
    np.testing.assert_allclose(ratio, on.info["imfs"][moved]["transfer_error"], rtol=1e-6)


def test_quality_within_a_hundredth_of_the_direct_path(runs):
    on, off = runs["always"].quality, runs["never"].quality
    assert abs(on.energy_ratio - off.energy_ratio) <= 0.01
    assert abs(on.orthogonality_index - off.orthogonality_index) <= 0.01


def test_auto_keeps_the_direct_path_below_the_crossover(sphere, signal):
    small = Surface(*icosphere(4))
    assert small.n_vertices < MULTIRESOLUTION_VERTICES <= sphere.n_vertices
    auto = emd(small, small.vertices[:, 2] ** 3, method="filtering", max_imfs=2)
    assert auto.levels == () and "levels" not in auto.info
    assert emd(sphere, signal, method="filtering", max_imfs=1).levels
    options = EMDOptions(method="filtering")
    assert not uses_levels(options, MULTIRESOLUTION_VERTICES - 1) and uses_levels(options, MULTIRESOLUTION_VERTICES)
    assert not uses_levels(EMDOptions(multiresolution="always"), 10**8)  # sifting never uses levels
