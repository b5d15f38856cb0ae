"""Distinct rows (hht3d.geometry.rows) against NumPy's ``np.unique(axis=0)``, the oracle they replace."""

import numpy as np
import pytest

from hht3d.geometry.rows import unique_rows


@pytest.mark.parametrize("dtype", [np.float64, np.int64, np.int32])
@pytest.mark.parametrize("shape", [(2000, 3), (500, 2), (0, 3), (1, 3)])
def test_unique_rows_are_numpys(dtype, shape):
    """The same distinct rows in the same order, first occurrences, groups and counts; ``-0.0`` equals ``0.0``."""
    rows = np.random.default_rng(2).integers(-2, 3, shape).astype(dtype)
    if dtype == np.float64 and len(rows):
        rows[::7] *= -1.0  # -0.0 wherever a 0 was
    unique, first, inverse, counts = np.unique(rows, axis=0, return_index=True, return_inverse=True, return_counts=True)
    mine = unique_rows(rows)
    assert np.array_equal(mine[0], unique)
    assert np.array_equal(mine[1], first)
    assert np.array_equal(mine[2], inverse.ravel())
    assert np.array_equal(mine[3], counts)
