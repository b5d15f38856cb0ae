"""The lazy graph's stages (hht3d.graph.stages): the shape of the graph, the same numbers as the eager functions,
the eager signatures, settings checked while the graph is built."""

import numpy as np
import pytest
from dask.core import get_dependencies

from helpers.graphs import OPTIONS, _prefix, _surfaces
from hht3d import InputError, graph
from hht3d.geometry.signals import mean_curvature
from hht3d.io import load
from hht3d.transform import hht as eager_hht


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
    (lazy,) = graph.compute(
        graph.hht(s, graph.signal(s, "mean_curvature"), **OPTIONS), scheduler="synchronous", progress=False
    )
    eager = eager_hht(surface, mean_curvature(surface), max_imfs=OPTIONS["max_imfs"])
    np.testing.assert_array_equal(lazy.imfs, eager.imfs)
    # shifts summed in groups instead of one loop: only the summation order differs
    np.testing.assert_allclose(
        lazy.monogenic.riesz, eager.monogenic.riesz, rtol=0, atol=1e-12 * np.abs(eager.monogenic.riesz).max()
    )


def test_eemd_members_are_tasks():
    s = graph.from_surface(_surfaces()[0])
    lazy = graph.eemd(s, graph.signal(s, "mean_curvature"), ensemble_size=4, seed=3, max_imfs=2)
    members = [k for k in dict(lazy.__dask_graph__()) if _prefix(k) == "eemd_member"]
    assert len(members) == 4
    (a,) = graph.compute(lazy, scheduler="synchronous", progress=False)
    (b,) = graph.compute(lazy, scheduler="threads", progress=False)
    np.testing.assert_array_equal(a.imfs, b.imfs)


def test_lazy_twins_have_the_eager_signatures_and_docstrings():
    import inspect

    from hht3d import apps
    from hht3d.decomposition import eemd, emd
    from hht3d.geometry.signals import signal
    from hht3d.io import load
    from hht3d.spectral.monogenic_signal import monogenic, monogenic_from_potential

    mirrored = [
        load,
        signal,
        emd,
        eemd,
        monogenic_from_potential,
        apps.filter_signal,
        apps.filter_geometry,
        apps.reconstruct,
        apps.prominent_features,
        apps.hks_features,
        apps.imf_enhancement,
        apps.manifold_harmonics_filter,
    ]
    for func in mirrored:
        twin = getattr(graph, func.__name__)
        assert inspect.signature(twin).parameters == inspect.signature(func).parameters, func.__name__
        assert twin.__doc__.startswith(f"Lazy :func:`{func.__module__}.{func.__name__}`")
        eager = inspect.cleandoc(func.__doc__).split("\nExamples\n")[0]
        assert eager.partition("\nReturns\n-------\n")[0].rstrip() in twin.__doc__  # the eager Returns...
        assert twin.__doc__.count("\nReturns\n") == 1 and "\nReturns\n-------\nDelayed\n" in twin.__doc__  # ...is lazy
    for func in (monogenic, eager_hht):  # plus the scheduling parameter riesz_tasks, keyword-only
        lazy, core = inspect.signature(getattr(graph, func.__name__)).parameters, inspect.signature(func).parameters
        assert {k: v for k, v in lazy.items() if k != "riesz_tasks"} == dict(core), func.__name__
        assert lazy["riesz_tasks"].kind is inspect.Parameter.KEYWORD_ONLY


@pytest.mark.parametrize(
    "build",
    [
        lambda s, f: graph.emd(s, f, max_imf=2),
        lambda s, f: graph.eemd(s, f, ensemble_sise=3),
        lambda s, f: graph.hht(s, f, max_imf=2),
        lambda s, f: graph.hht(s, f, potential="quadratur"),
        lambda s, f: graph.monogenic(s, f, tol=0),
    ],
)
def test_wrong_settings_raise_while_the_graph_is_built(build):
    """A misspelled or out-of-range setting is the caller's error before any task exists, with a hint."""
    surface = _surfaces()[0]
    with pytest.raises(InputError, match="max_imfs|ensemble_size|quadrature|tol"):
        build(graph.from_surface(surface), np.zeros(surface.n_vertices))


def test_lazy_monogenic_takes_the_eager_arguments():
    from hht3d.spectral.monogenic_signal import monogenic

    surface = _surfaces()[0]
    imfs = np.stack([mean_curvature(surface), surface.vertices[:, 0]])
    (lazy,) = graph.compute(
        graph.monogenic(graph.from_surface(surface), imfs, gradient="fem", riesz_tasks=2),
        scheduler="synchronous",
        progress=False,
    )
    eager = monogenic(surface, imfs, gradient="fem")
    np.testing.assert_allclose(lazy.riesz, eager.riesz, rtol=0, atol=1e-12 * np.abs(eager.riesz).max())


def test_riesz_tasks_zero_is_named(inputs):
    from hht3d import graph
    from hht3d.errors import InputError

    surface = load(inputs / "good.ply")
    with pytest.raises(InputError, match=r"riesz_tasks must be an integer in \[1, 64\] or None, got 0"):
        graph.hht(surface, surface.vertices[:, 0], riesz_tasks=0)


def test_filtering_on_levels_takes_each_imf_group_riesz_as_a_task():
    """With levels, the Riesz stage is one task per group of IMFs (each IMF on its level), which
    needs only the surface and the decomposition; the graph computes the eager numbers, with threads too."""
    from scipy.special import eval_legendre

    from helpers.meshes import icosphere
    from hht3d import Surface

    sphere = Surface(*icosphere(5), name="icosphere")
    x, _, z = sphere.vertices.T
    signal = eval_legendre(40, z) + 3 * eval_legendre(6, (x + z) / 2**0.5)
    settings = {"method": "filtering", "multiresolution": "always", "max_imfs": 3}
    s = graph.from_surface(sphere)
    lazy = graph.hht(s, signal, riesz_tasks=2, **settings)
    tasks = dict(lazy.__dask_graph__())
    parts = [k for k in tasks if _prefix(k) == "riesz_part"]
    (emd_key,) = [k for k in tasks if _prefix(k) == "emd"]
    assert len(parts) == 2 and all(emd_key in get_dependencies(tasks, k) for k in parts)
    eager = eager_hht(sphere, signal, **settings)
    assert eager.info["emd"]["imfs"][-1]["level"] >= 1  # some IMF lies on a coarser level
    for scheduler in ("synchronous", "threads"):
        (result,) = graph.compute(lazy, scheduler=scheduler, progress=False)
        np.testing.assert_array_equal(result.imfs, eager.imfs)
        # a group's IMFs of one level share the shifts of their lowest cut, so two groups may take other
        # shifts than one: both are within the quadrature's tol (1e-8), well within 1e-7 pointwise
        np.testing.assert_allclose(result.monogenic.amplitude, eager.monogenic.amplitude, rtol=1e-7, atol=1e-12)
