"""The robust Laplacian built by blocks (hht3d.geometry.blocks) against ``robust_laplacian`` on the whole surface.

Oracle: ``robust_laplacian`` itself, called once on the whole mesh or cloud.  Where no triangle needs
intrinsic mollification (nefertiti's faces) the blocks reproduce it to rounding: the flips that set a row
stay within the halo.  Elsewhere (a clustered coarse level's needles, a point cloud's tufted triangles)
each block shifts its edge lengths by its own ``ε ≤ δ = 1e-5`` mean edge lengths, so eigenvalues and
areas move by ``O(δ)``: the tolerance is 1e-4 (measured 1.6e-5 on nefertiti's cloud and igea's level 1).
"""

import numpy as np
import pytest
import robust_laplacian
import scipy.sparse as sp
import scipy.sparse.linalg as sla

import hht3d
from helpers.models import shared_model_path
from hht3d.geometry import blocks
from hht3d.geometry.hierarchy import hierarchy
from hht3d.geometry.operators import point_cloud_operators, robust_mesh_operators


@pytest.fixture(scope="module")
def nefertiti():
    return hht3d.load(shared_model_path("nefertiti.ply"))


def _eigenvalues(lap, mass, k=20):
    return np.sort(sla.eigsh(lap, k=k, M=sp.diags(mass), sigma=-1e-8, which="LM")[0])[1:]


def test_bisection_cuts_every_vertex_into_exactly_one_block_of_at_most_the_size(nefertiti):
    found = blocks.bisection_blocks(nefertiti.vertices, 7_000)
    assert max(map(len, found)) <= 7_000 and min(map(len, found)) >= 7_000 // 2
    np.testing.assert_array_equal(np.sort(np.concatenate(found)), np.arange(nefertiti.n_vertices))


def test_blocks_of_a_well_shaped_mesh_are_its_whole_laplacian_to_rounding(nefertiti, monkeypatch):
    v, f = nefertiti.vertices, np.asarray(nefertiti.faces)
    lap, mass = robust_laplacian.mesh_laplacian(v, f)
    monkeypatch.setattr("hht3d.geometry.operators.MESH_BLOCK", 10_000)
    by_blocks, block_mass = robust_mesh_operators(v, f)
    assert abs(by_blocks - lap).max() <= 1e-12 * abs(lap).max()
    np.testing.assert_allclose(block_mass, mass.diagonal(), rtol=1e-12)


def test_blocks_of_a_coarse_level_keep_its_spectrum(nefertiti, monkeypatch):
    level = hierarchy(nefertiti).level(1).surface
    v, f = level.vertices, np.asarray(level.faces)
    lap, mass = robust_laplacian.mesh_laplacian(v, f)
    monkeypatch.setattr("hht3d.geometry.operators.MESH_BLOCK", 3_000)
    by_blocks, block_mass = robust_mesh_operators(v, f)
    np.testing.assert_allclose(_eigenvalues(by_blocks, block_mass), _eigenvalues(lap, mass.diagonal()), rtol=1e-4)
    np.testing.assert_allclose(block_mass.sum(), mass.diagonal().sum(), rtol=1e-4)


def test_blocks_of_a_point_cloud_keep_its_spectrum_symmetry_and_constants(monkeypatch):
    points = hht3d.load(shared_model_path("rocker_arm.ply")).vertices
    lap, mass = robust_laplacian.point_cloud_laplacian(points, 1e-5, 30)
    monkeypatch.setattr("hht3d.geometry.operators.CLOUD_BLOCK", 2_500)
    by_blocks, block_mass = point_cloud_operators(points)
    assert abs(by_blocks - by_blocks.T).max() == 0.0
    assert np.abs(by_blocks @ np.ones(len(points))).max() <= 1e-12 * abs(by_blocks).max()
    np.testing.assert_allclose(_eigenvalues(by_blocks, block_mass), _eigenvalues(lap, mass.diagonal()), rtol=1e-4)
    np.testing.assert_allclose(block_mass.sum(), mass.diagonal().sum(), rtol=1e-4)


def test_a_halo_of_one_ring_is_not_enough(nefertiti, monkeypatch):
    """The halo is what makes the rows right: with one ring the blocks' rows differ by percents."""
    v, f = nefertiti.vertices, np.asarray(nefertiti.faces)
    lap, _ = robust_laplacian.mesh_laplacian(v, f)
    monkeypatch.setattr(blocks, "MESH_HALO_RINGS", 1)
    monkeypatch.setattr("hht3d.geometry.operators.MESH_BLOCK", 10_000)
    assert abs(robust_mesh_operators(v, f)[0] - lap).max() > 1e-2 * abs(lap).max()
