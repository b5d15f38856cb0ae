"""Local extrema on surfaces (hht3d.decomposition.extrema): a hand-made grid, and the paper's ring rule by
brute force."""

from __future__ import annotations

import numpy as np
import pytest

from helpers.meshes import grid
from hht3d import Surface
from hht3d.decomposition import local_extrema

# -- extrema -------------------------------------------------------------------------------


def square_3x3():
    """Hand-made 3x3 grid: vertex 4 is the centre, neighbours of every vertex known."""
    v = np.array([[x, y, 0.0] for y in range(3) for x in range(3)])
    f = np.array([[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4], [3, 4, 7], [3, 7, 6], [4, 5, 8], [4, 8, 7]])
    return Surface(v, f, name="square")


def test_strict_extrema_hand_made():
    s = square_3x3()
    # 1-rings: 0:{1,3,4} 2:{1,5} 6:{3,7} 8:{5,7} 4: all but 2, 6.
    f = np.array([0.0, 1.0, 5.0, 1.0, 3.0, 1.0, -2.0, 1.0, 0.0])
    maxima, minima = local_extrema(s, f)
    assert maxima.tolist() == [2, 4]  # 2 > {1, 5}; 4 > {0,1,3,5,7,8}
    assert minima.tolist() == [0, 6, 8]  # 0 < {1,3,4}; 6 < {3,7}; 8 < {4,5,7}


def test_extrema_ties_and_plateaus():
    s = square_3x3()
    assert all(len(e) == 0 for e in local_extrema(s, np.full(9, 2.5)))
    # a plateau of two equal top values: both are maxima (>= all, > some)
    f = np.array([0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0])
    maxima, minima = local_extrema(s, f)
    assert maxima.tolist() == [4, 5]
    # the zero vertices touching the bump are minima (<= all, < some); vertex 6 only sees
    # zeros (interior of the low plateau) and is not
    assert minima.tolist() == [0, 1, 2, 3, 7, 8]


def test_ring_rule_relaxes_strict_rule():
    s = Surface(*grid(12, 12, jitter=0.2, seed=3), name="grid")
    f = np.random.default_rng(0).standard_normal(s.n_vertices)
    strict_max, strict_min = local_extrema(s, f)
    ring_max, ring_min = local_extrema(s, f, extrema="relaxed", ring=1, ratio=0.8)
    assert set(strict_max) <= set(ring_max) and set(strict_min) <= set(ring_min)
    # ratio 1 on the 1-ring is the strict rule
    one = local_extrema(s, f, extrema="relaxed", ring=1, ratio=1.0)
    assert one[0].tolist() == strict_max.tolist() and one[1].tolist() == strict_min.tolist()
    # the paper's rule (Sec. 5.2) by brute force on the 2-ring
    ring2 = s.ring(2).toarray()
    expected = [
        i
        for i in range(s.n_vertices)
        if np.sum(f[i] >= f[ring2[i]]) >= 0.8 * ring2[i].sum() and np.any(f[i] > f[ring2[i]])
    ]
    assert local_extrema(s, f, extrema="relaxed")[0].tolist() == expected


def test_extrema_is_the_emd_setting_and_rule_its_former_name():
    s = Surface(*grid(8, 8, jitter=0.2, seed=1), name="grid")
    f = np.random.default_rng(2).standard_normal(s.n_vertices)
    relaxed = local_extrema(s, f, extrema="relaxed", ring=2, ratio=0.8)
    with pytest.warns(DeprecationWarning, match="write extrema='relaxed'"):
        former = local_extrema(s, f, rule="relaxed", ring=2, ratio=0.8)
    assert [e.tolist() for e in former] == [e.tolist() for e in relaxed]
