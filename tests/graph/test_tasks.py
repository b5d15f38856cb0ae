"""The lazy graph's tasks (hht3d.graph.tasks): surfaces resident on a worker, one analysis shared by the shift
groups of a process."""

import numpy as np

from helpers.graphs import _surfaces
from hht3d import Surface, graph
from hht3d.geometry.signals import mean_curvature


def test_resident_surfaces_share_operators_across_copies():
    import pickle

    surface = _surfaces()[0]
    first = graph.resident(pickle.loads(pickle.dumps(surface)))
    lap = first.stiffness
    second = graph.resident(pickle.loads(pickle.dumps(surface)))  # a task's fresh copy
    assert second is not first and second.stiffness is lap
    other = graph.resident(Surface(surface.vertices * 2, surface.faces))
    assert other.stiffness is not lap
    moved = Surface(surface.vertices, surface.faces, laplacian="robust")
    assert graph.resident(moved).cache is not first.cache


def test_shift_groups_sharing_one_analysis_on_threads():
    # three shift-group tasks share one analysis (one live factor) in one process: they take turns
    surface = _surfaces()[0]
    s = graph.from_surface(surface)
    lazy = graph.riesz_potential(s, np.stack([mean_curvature(surface), surface.vertices[:, 0]]), riesz_tasks=3)
    (threads,) = graph.compute(lazy, scheduler="threads", workers=3, progress=False)
    (sync,) = graph.compute(lazy, scheduler="synchronous", progress=False)
    np.testing.assert_allclose(threads, sync, rtol=0, atol=1e-13 * np.abs(sync).max())
    assert [k for k in surface.cache if k.startswith("graph:shift_analysis")]
