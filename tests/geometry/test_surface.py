"""Surfaces built from arrays (hht3d.geometry.surface): clear errors, the checks that files get too, and
pickling without the cached operators."""

import numpy as np
import pytest

from helpers.meshes import icosphere
from hht3d import InputError, Surface


def test_bad_arrays_give_clear_errors():
    v, f = icosphere(1)
    with pytest.raises(InputError, match="at least 4"):
        Surface(v[:3])
    bad = v.copy()
    bad[2, 1] = np.nan
    with pytest.raises(InputError, match="NaN"):
        Surface(bad, f)
    with pytest.raises(InputError, match="face indices"):
        Surface(v, f + 100)
    with pytest.raises(InputError, match="shape"):
        Surface(v[:, :2])


@pytest.mark.parametrize("build", [Surface, Surface.cleaned])
def test_point_clouds_built_from_arrays_are_checked_as_files_are(build):
    # before any operator: robust_laplacian would abort on these with a C++ assertion
    line = np.c_[np.linspace(0, 1, 50), np.zeros(50), np.zeros(50)]
    with pytest.raises(InputError, match="the 50 points lie on a line"):
        build(line, name="line")
    few = np.random.default_rng(2).normal(size=(10, 3))
    with pytest.raises(InputError, match="10 points cannot give each point n_neighbors=30 neighbours"):
        build(few, name="few")
    assert build(few, name="few", n_neighbors=5).n_vertices == 10


def test_pickling_drops_cached_operators(sphere):
    import pickle

    _ = sphere.stiffness
    clone = pickle.loads(pickle.dumps(sphere))
    assert "operators" not in clone.cache
    assert abs(clone.stiffness - sphere.stiffness).max() == 0
