"""The shifted systems ``L + σM`` (hht3d.spectral.shifts): one pattern for every shift."""

from __future__ import annotations

import numpy as np

from helpers.meshes import fibonacci_sphere
from hht3d.geometry.surface import Surface
from hht3d.spectral.shifts import shifted_matrix


def test_pattern_has_explicit_diagonal():
    # A point cloud vertex whose Laplacian row is empty still gets a pattern entry for σM.
    s = Surface(fibonacci_sphere(50), None)
    a = shifted_matrix(s, 1.0)
    b = shifted_matrix(s, 2.0)
    assert np.array_equal(a.indices, b.indices) and np.array_equal(a.indptr, b.indptr)
    assert np.allclose((b - a).diagonal(), s.mass_diagonal)
    assert np.allclose((a - s.mass).toarray(), s.stiffness.toarray())
