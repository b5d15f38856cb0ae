"""The lazy graph: its shape, and identical numbers on every scheduler."""
import numpy as np
import pytest
from dask.core import get_dependencies

from hht3d import Surface, graph
from hht3d.transform import hht as eager_hht
from hht3d.geometry.signals import mean_curvature
from meshes import fibonacci_sphere, icosphere

OPTIONS = dict(emd_options={"max_imfs": 3}, riesz_tasks=3)


def _surfaces():
    v, f = icosphere(3)
    bumpy = v * (1 + 0.05 * np.sin(5 * v[:, [0]]) * np.cos(4 * v[:, [1]]))
    return [Surface(bumpy, f, name="mesh"), Surface(fibonacci_sphere(1500) * 1.3, name="cloud")]


def _prefix(key) -> str:
    name = key[0] if isinstance(key, tuple) else key
    return name.rsplit("-", 1)[0]


def test_riesz_stage_is_independent_shift_group_tasks():
    surface = graph.from_surface(_surfaces()[0])
    result = graph.hht(surface, graph.signal(surface, "mean_curvature"), **OPTIONS)
    tasks = dict(result.__dask_graph__())
    by_prefix = {}
    for key in tasks:
        by_prefix.setdefault(_prefix(key), []).append(key)
    groups = by_prefix["_quadrature_part"]
    assert len(groups) == OPTIONS["riesz_tasks"]
    (emd_key,) = by_prefix["emd"]
    (imfs_key,) = by_prefix["_imfs"]
    (plan_key,) = by_prefix["_quadrature_plan"]
    (surface_key,) = [k for k in tasks if _prefix(k).startswith("surface")]
    for key in groups:
        deps = get_dependencies(tasks, key)
        # a group needs only the surface (its operators), the IMFs and the shifts
        assert deps == {surface_key, imfs_key, plan_key}
        assert not deps & set(groups)
    assert get_dependencies(tasks, imfs_key) == {emd_key}
    assert get_dependencies(tasks, plan_key) == {surface_key}  # bounds do not wait for EMD


def test_graph_equals_eager_hht():
    surface = _surfaces()[0]
    s = graph.from_surface(surface)
    (lazy,) = graph.compute(graph.hht(s, graph.signal(s, "mean_curvature"), **OPTIONS),
                            scheduler="synchronous", progress=False)
    eager = eager_hht(surface, mean_curvature(surface), emd_options=OPTIONS["emd_options"])
    np.testing.assert_array_equal(lazy.imfs, eager.imfs)
    # shifts summed in groups instead of one loop: only the summation order differs
    np.testing.assert_allclose(lazy.monogenic.riesz, eager.monogenic.riesz, rtol=0,
                               atol=1e-12 * np.abs(eager.monogenic.riesz).max())


@pytest.fixture(scope="module")
def cluster_client():
    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster, \
            Client(cluster) as client:
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


def test_eemd_members_are_tasks():
    s = graph.from_surface(_surfaces()[0])
    lazy = graph.eemd(s, graph.signal(s, "mean_curvature"), ensemble_size=4, seed=3, max_imfs=2)
    members = [k for k in dict(lazy.__dask_graph__()) if _prefix(k) == "eemd_member"]
    assert len(members) == 4
    (a,) = graph.compute(lazy, scheduler="synchronous", progress=False)
    (b,) = graph.compute(lazy, scheduler="threads", progress=False)
    np.testing.assert_array_equal(a.imfs, b.imfs)


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


def test_riesz_tasks_default_to_the_worker_count(cluster_client):
    surface = graph.from_surface(_surfaces()[0])
    tasks = dict(graph.riesz_potential(surface, np.ones((2, 642))).__dask_graph__())
    assert sum(_prefix(k) == "_quadrature_part" for k in tasks) == 2  # the 2-worker cluster


def test_shift_groups_sharing_one_analysis_on_threads():
    # three shift-group tasks share one analysis (one live factor) in one process: they take turns
    surface = _surfaces()[0]
    s = graph.from_surface(surface)
    lazy = graph.riesz_potential(s, np.stack([mean_curvature(surface), surface.vertices[:, 0]]), riesz_tasks=3)
    (threads,) = graph.compute(lazy, scheduler="threads", workers=3, progress=False)
    (sync,) = graph.compute(lazy, scheduler="synchronous", progress=False)
    np.testing.assert_allclose(threads, sync, rtol=0, atol=1e-13 * np.abs(sync).max())
    assert [k for k in surface.cache if k.startswith("graph:shift_analysis")]


def test_lazy_twins_have_the_eager_signatures_and_docstrings():
    import inspect

    from hht3d import apps
    from hht3d.decomposition.decompose import eemd, emd
    from hht3d.io import load
    from hht3d.spectral.monogenic_signal import monogenic, monogenic_from_potential
    from hht3d.geometry.signals import signal

    extras = {"monogenic": ["riesz_tasks"], "hht": ["ensemble", "riesz_tasks"]}
    eager = [load, signal, emd, eemd, monogenic, monogenic_from_potential, eager_hht, apps.filter_signal,
             apps.filter_geometry, apps.reconstruct, apps.prominent_features, apps.hks_features,
             apps.imf_enhancement, apps.manifold_harmonics_filter]
    for func in eager:
        twin = getattr(graph, func.__name__)
        lazy, core = inspect.signature(twin).parameters, inspect.signature(func).parameters
        assert list(lazy) == list(core) + extras.get(func.__name__, []), func.__name__
        assert all(lazy[name] == core[name] for name in core), func.__name__
        assert twin.__doc__.startswith(f"Lazy :func:`{func.__module__}.{func.__name__}`")
        assert inspect.cleandoc(func.__doc__).split("\nExamples\n")[0].rstrip() in twin.__doc__


def test_lazy_monogenic_takes_the_eager_arguments():
    from hht3d.spectral.monogenic_signal import monogenic

    surface = _surfaces()[0]
    imfs = np.stack([mean_curvature(surface), surface.vertices[:, 0]])
    (lazy,) = graph.compute(graph.monogenic(graph.from_surface(surface), imfs, gradient="fem", riesz_tasks=2),
                            scheduler="synchronous", progress=False)
    eager = monogenic(surface, imfs, gradient="fem")
    np.testing.assert_allclose(lazy.riesz, eager.riesz, rtol=0, atol=1e-12 * np.abs(eager.riesz).max())
