"""The schedulers (hht3d.execution): identical numbers on the synchronous scheduler and a local cluster, and
as many Riesz tasks as the cluster has workers."""

import numpy as np
import pytest

from helpers.graphs import OPTIONS, _prefix, _surfaces
from hht3d import graph


@pytest.fixture(scope="module")
def cluster_client():
    from distributed import Client, LocalCluster

    with (
        LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster,
        Client(cluster) as client,
    ):
        yield client


def test_same_numbers_on_synchronous_scheduler_and_local_cluster(cluster_client):
    for surface in _surfaces():
        s = graph.from_surface(surface)
        lazy = graph.hht(s, graph.signal(s, "mean_curvature"), **OPTIONS)
        (sync,) = graph.compute(lazy, scheduler="synchronous", progress=False)
        (dist,) = graph.compute(lazy, client=cluster_client, progress=False)
        assert sync.n_imfs == dist.n_imfs > 0
        for name in ("riesz", "amplitude", "phase"):
            a, b = getattr(sync.monogenic, name), getattr(dist.monogenic, name)
            np.testing.assert_allclose(a, b, rtol=0, atol=1e-12 * np.abs(a).max())
        # ω divides by f² + q² (Eq. 23), which amplifies round-off where the amplitude
        # nearly vanishes: compare where a > 1e-3 max a, and the energy-weighted ω everywhere
        amp = sync.monogenic.amplitude
        strong = amp > 1e-3 * amp.max(axis=1, keepdims=True)
        np.testing.assert_allclose(sync.monogenic.frequency[strong], dist.monogenic.frequency[strong], rtol=1e-12)
        np.testing.assert_allclose(sync.spectrum.mean_frequency(), dist.spectrum.mean_frequency(), rtol=1e-12)
        np.testing.assert_allclose(sync.imfs, dist.imfs, rtol=0, atol=1e-12 * np.abs(sync.imfs).max())


def test_riesz_tasks_default_to_the_worker_count(cluster_client):
    surface = graph.from_surface(_surfaces()[0])
    tasks = dict(graph.riesz_potential(surface, np.ones((2, 642))).__dask_graph__())
    assert sum(_prefix(k) == "_quadrature_part" for k in tasks) == 2  # the 2-worker cluster
