"""The coarsening hierarchy (hht3d.geometry.hierarchy) against geometry it must reproduce.

Oracles: linear functions (barycentric interpolation reproduces them on the coarse mesh), the
nearest coarse vertex (a closest point on the coarse mesh is never farther), the interpolation
bound of a zonal spherical harmonic, the sphere's Laplace spectrum ``l(l + 1)``, and a second build
from a copy of the surface.
"""

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as sla
from scipy.spatial import cKDTree
from scipy.special import eval_legendre

from helpers.meshes import fibonacci_sphere, icosphere
from hht3d import Surface
from hht3d.decomposition.envelopes import floored_mass, membrane_laplacian
from hht3d.geometry.hierarchy import COARSENING, MIN_LEVEL_VERTICES, hierarchy
from hht3d.linalg.chebyshev import spectral_radius_bound


@pytest.fixture(scope="module")
def sphere():
    return Surface(*icosphere(6), name="icosphere")


def test_each_level_has_about_a_quarter_of_the_vertices(sphere):
    levels = hierarchy(sphere)
    sizes = [levels.level(i).surface.n_vertices for i in range(4)]
    ratios = np.array(sizes[:-1]) / np.array(sizes[1:])
    assert np.all((ratios > 0.6 * COARSENING) & (ratios < 1.4 * COARSENING)), sizes
    spacings = np.array([levels.levels[i].spacing for i in range(4)])
    np.testing.assert_allclose(spacings[1:] / spacings[:-1], np.sqrt(ratios), rtol=0.1)  # same area, fewer vertices
    assert all(levels.levels[i].surface.is_mesh for i in range(4))


def test_prolongation_is_barycentric_on_the_coarse_mesh(sphere):
    level = hierarchy(sphere).level(1)
    p, coarse = level.prolongation, level.surface
    assert p.shape == (sphere.n_vertices, coarse.n_vertices)
    np.testing.assert_allclose(np.asarray(p.sum(axis=1)).ravel(), 1.0, atol=1e-6)
    assert p.data.min() >= 0
    # a linear function is reproduced at the interpolated points
    a = np.array([0.3, -1.2, 0.7])
    located = p @ coarse.vertices
    np.testing.assert_allclose(level.prolong(coarse.vertices @ a), located @ a, atol=1e-12)
    # the closest point on the coarse mesh is no farther than the nearest coarse vertex (float32 slack)
    nearest = cKDTree(coarse.vertices).query(sphere.vertices)[0]
    assert np.all(np.linalg.norm(located - sphere.vertices, axis=1) <= nearest + 1e-6)


def test_restriction_samples_the_finer_vertices(sphere):
    levels = hierarchy(sphere)
    level = levels.level(2)
    np.testing.assert_array_equal(levels.restrict(sphere.vertices[:, 0], 0, 2), level.surface.vertices[:, 0])


@pytest.mark.parametrize("degree", [3, 8])
def test_round_trip_of_a_resolved_harmonic_is_within_the_interpolation_bound(sphere, degree):
    """``P R Y_l`` for the zonal harmonic ``Y_l = P_l(z)``: piecewise-linear interpolation errs by at most
    ``h² max|∇²Y| / 8`` with ``h`` the longest coarse edge; ``|∇²Y| ≤ l(l+1) max|Y|`` in the M-norm sense,
    and the coarse mesh's chords add ``O(h²)`` more, so the bound is taken twice."""
    levels = hierarchy(sphere)
    f = eval_legendre(degree, sphere.vertices[:, 2])
    mass = sphere.mass_diagonal
    for index in (1, 2):
        coarse = levels.level(index).surface
        edges = coarse.vertices[coarse.faces] - coarse.vertices[np.roll(coarse.faces, 1, axis=1)]
        h = np.linalg.norm(edges, axis=2).max()
        back = levels.to_finest(levels.restrict(f, 0, index), index)
        error = np.sqrt(mass @ (back - f) ** 2 / (mass @ f**2))
        assert error <= 2 * h**2 * degree * (degree + 1) / 8, (index, error)


@pytest.mark.parametrize("index", [1, 2, 3])
def test_a_coarse_level_has_the_spheres_spectrum_and_no_needle_eigenvalues(sphere, index):
    """The unit sphere's eigenvalues ``l(l + 1)`` (0; 2 three times; 6 five times) within 3%, as the
    input's Laplacian gives them (0.02%) up to the coarse level's ``O(h²)`` error (1.2% on level 3).

    The top of the spectrum sets the polynomial filters' degree (``√λ_max``): a mesh of well-shaped
    triangles has ``λ_max h²`` of order 10 (the bound is 7.7 on the input).  Vertex clustering leaves
    needles and caps whose cotangent weights gave 1,102, 598 and 179 on levels 1-3; the bound of 100
    allows at most 3.6 times the input's degree (the intrinsic Delaunay Laplacian: 34, 31, 23)."""
    level = hierarchy(sphere).level(index)
    coarse = level.surface
    values = sla.eigsh(coarse.stiffness.tocsc(), k=9, M=sp.diags(coarse.mass_diagonal).tocsc(), sigma=-1e-3)[0]
    np.testing.assert_allclose(np.sort(values)[1:], [2] * 3 + [6] * 5, rtol=0.03)
    assert abs(np.sort(values)[0]) < 1e-8
    top = spectral_radius_bound(membrane_laplacian(coarse), floored_mass(coarse))
    assert top * level.spacing**2 <= 100


def test_point_cloud_levels_interpolate_from_nearest_points():
    cloud = Surface(fibonacci_sphere(8000), name="cloud")
    level = hierarchy(cloud).level(1)
    assert not level.surface.is_mesh and 1000 < level.surface.n_vertices < 4000
    np.testing.assert_allclose(level.prolong(np.ones(level.surface.n_vertices)), 1.0, atol=1e-12)
    np.testing.assert_allclose(np.asarray(level.prolongation.sum(axis=1)).ravel(), 1.0, atol=1e-12)


def test_a_rebuilt_hierarchy_is_identical(sphere):
    """Workers rebuild the levels from their copy of the surface; both builds must agree exactly."""
    copy = Surface(sphere.vertices.copy(), sphere.faces.copy(), name="copy")
    a, b = hierarchy(sphere).level(2), hierarchy(copy).level(2)
    np.testing.assert_array_equal(a.samples, b.samples)
    np.testing.assert_array_equal(a.surface.faces, b.surface.faces)
    assert (a.prolongation != b.prolongation).nnz == 0


def test_a_small_surface_has_no_coarser_level():
    small = Surface(*icosphere(3))
    assert small.n_vertices < COARSENING * MIN_LEVEL_VERTICES
    levels = hierarchy(small)
    assert levels.level(1) is None
    assert levels.coarsest_resolving(1.0, 10.0) == 0
