"""Lazy task-graph API: every HHT stage as a ``dask.delayed`` task.

This layer adds laziness only.  Each public core function has a lazy twin
here with the same name, signature and docstring (as dask-image mirrors
SciPy's ndimage): ``graph.emd(surface, signal, max_imfs=3)`` takes what
:func:`hht3d.decomposition.decompose.emd` takes, Delayed values included, and returns a
``Delayed``.  :func:`mirror` makes such a twin from any core function.
Stages compose freely and run on any scheduler of :mod:`hht3d.graph.stages.scheduling`.

Examples
--------
>>> from hht3d import data_path, graph
>>> s = graph.load(data_path("spot.ply"))
>>> f = graph.signal(s, "mean_curvature")
>>> lazy = graph.hht(s, f, emd_options={"max_imfs": 2})    # EMD -> Riesz shift groups -> spectra
>>> (result,) = graph.compute(lazy, scheduler="synchronous", progress=False)
>>> result.n_imfs
2

Parallelism follows the method:

* independent signals give independent :func:`emd` tasks; EEMD members are
  tasks of their own (:func:`eemd`);
* the Riesz transform of all IMFs is a sum over quadrature shifts
  (:mod:`hht3d.spectral.riesz_transform`): one task finds the spectral bounds and shifts, then
  ``riesz_tasks`` independent *shift-group* tasks (default: one per worker,
  :func:`hht3d.graph.stages.scheduling.worker_count`) each factorize their shifts once and
  solve all IMFs as one multi-column right-hand side; they depend only on the
  EMD task and the surface, and factorizations never leave a task.  (One task
  per IMF would repeat every factorization once per IMF.)  :func:`monogenic`
  and :func:`hht` take ``riesz_tasks`` beyond the eager signature;
* the files of a dataset are independent subgraphs (:mod:`hht3d.graph.stages.dataset`).

A surface or array enters a graph once, as one key, and is shared by
reference between the tasks that use it.

Worker-side caching
-------------------
A task receives a fresh copy of a surface whenever the scheduler pickles it
(process pools, transfers between workers), and pickling drops the cached
operators.  Every task therefore passes its surfaces through
:func:`resident`: tasks on the same geometry in one process share one cache,
so a worker builds ``L``, ``M``, the gradient, the spectral bounds and the
symbolic analysis of the shifted systems once for all the tasks it runs on
that surface.
"""
from __future__ import annotations

import contextlib
import functools
import inspect
import threading
from collections import OrderedDict

import numpy as np
from dask import delayed
from dask.base import tokenize

from .. import apps
from ..errors import InputError
from ..decomposition.decompose import combine_eemd, eemd_member
from ..decomposition.decompose import eemd as _eemd
from ..decomposition.decompose import emd as _emd
from ..transform import HHTResult
from ..transform import hht as _hht
from ..io.read import load as _load
from ..linalg.backends import default_backend
from ..spectral.monogenic_signal import monogenic as _monogenic
from ..spectral.monogenic_signal import monogenic_from_potential as _monogenic_from_potential
from ..spectral.options import RIESZ_DEFAULTS, RieszOptions
from ..spectral.riesz_transform import (combine_quadrature_parts, fractional_laplacian, quadrature_part, quadrature_plan,
                    shift_analysis)
from .scheduling import compute, worker_count
from ..geometry.signals import signal as _signal
from ..geometry.surface import Surface

__all__ = [
    "Builder",
    "mirror",
    "compute",
    "load",
    "from_surface",
    "as_key",
    "resident",
    "operators",
    "signal",
    "emd",
    "eemd",
    "eemd_tasks",
    "riesz_potential",
    "monogenic",
    "monogenic_from_potential",
    "hht",
    "save",
    "transform",
    "transform_file",
    "filter_signal",
    "filter_geometry",
    "reconstruct",
    "prominent_features",
    "hks_features",
    "imf_enhancement",
    "manifold_harmonics_filter",
]


class Builder:
    """Makes the tasks of a graph.

    Parameters
    ----------
    guard : callable, optional
        ``guard(step, func) -> callable`` wrapping every task's function; the
        dataset runner uses it to isolate failures per file
        (:class:`hht3d.graph.stages.dataset.Failure`).  Default: tasks raise normally.
    """

    def __init__(self, guard=None):
        self.guard = guard

    def task(self, step: str, func):
        """A ``dask.delayed`` of ``func`` named after ``step``.

        In-memory surfaces and arrays among its arguments enter the graph once,
        as their own keys (:func:`as_key`), instead of being copied into every task.
        """
        func = _OnWorker(func)
        wrapped = delayed(func if self.guard is None else self.guard(step, func), pure=True)

        def call(*args, **kwargs):
            return wrapped(*map(as_key, args), **{k: as_key(v) for k, v in kwargs.items()})

        return call


#: Geometries whose caches a process keeps across tasks (the least recently used is dropped).
RESIDENT_SURFACES = 2
_RESIDENT: OrderedDict = OrderedDict()
_RESIDENT_LOCK = threading.Lock()


def resident(surface: Surface) -> Surface:
    """``surface``, sharing this process's cache for its geometry (operators, bounds, analyses).

    The cache is keyed by the vertices, faces, Laplacian options and given
    normals; the :data:`RESIDENT_SURFACES` most recently used ones are kept.
    Returns the same object, whose ``cache`` is now the shared one.
    """
    key = tokenize(surface.vertices, surface.faces, surface.laplacian, surface.n_neighbors,
                   surface.cache.get("normals"))
    with _RESIDENT_LOCK:
        cache = _RESIDENT.pop(key, surface.cache)
        for name, value in surface.cache.items():
            cache.setdefault(name, value)
        _RESIDENT[key] = cache
        while len(_RESIDENT) > RESIDENT_SURFACES:
            _RESIDENT.popitem(last=False)
    surface.cache = cache
    return surface


class _OnWorker:
    """A task function that receives its surfaces through :func:`resident`."""

    def __init__(self, func):
        self.func = func
        functools.update_wrapper(self, func)

    def __call__(self, *args, **kwargs):
        def local(value):
            return resident(value) if isinstance(value, Surface) else value

        return self.func(*map(local, args), **{k: local(v) for k, v in kwargs.items()})

    def __dask_tokenize__(self):
        return "hht3d.graph.stages.stages._OnWorker", tokenize(self.func)


class _SharedAnalysis:
    """A surface's shift analysis (:func:`hht3d.spectral.riesz_transform.shift_analysis`), one task at a time.

    PARDISO and CHOLMOD keep one numeric factor per analysis, so tasks sharing
    it in one process (threads) take turns.
    """

    def __init__(self):
        self._lock = threading.Lock()
        self._symbolic = None

    @classmethod
    @contextlib.contextmanager
    def of(cls, surface: Surface, backend: str | None):
        backend = default_backend() if backend is None else backend
        with _RESIDENT_LOCK:
            shared = surface.cache.setdefault(f"graph:shift_analysis:{backend}", cls())
        with shared._lock:
            if shared._symbolic is None:
                shared._symbolic = shift_analysis(surface, backend)
            yield shared._symbolic


def _quadrature_plan(surface: Surface, tol: float, backend: str | None):
    """:func:`hht3d.spectral.riesz_transform.quadrature_plan` with this process's shared shift analysis."""
    with _SharedAnalysis.of(surface, backend) as symbolic:
        return quadrature_plan(surface, tol, symbolic=symbolic)


def _quadrature_part(surface: Surface, f, plan, group: int, groups: int, backend: str | None):
    """:func:`hht3d.spectral.riesz_transform.quadrature_part` with this process's shared shift analysis."""
    with _SharedAnalysis.of(surface, backend) as symbolic:
        return quadrature_part(surface, f, plan, group, groups, symbolic=symbolic)


_PLAIN = Builder()


def mirror(func, build=None, *, tasks: str = "one task", extras: tuple[inspect.Parameter, ...] = (),
           examples: str = ""):
    """The lazy twin of the core function ``func``: its name, signature and docstring; a ``Delayed`` result.

    Parameters
    ----------
    func : callable
        The eager core function.
    build : callable, optional
        ``build(builder, *args, **kwargs)`` making the tasks from the
        arguments bound to the signature, defaults applied; returns the
        result's ``Delayed``.  Default: one task calling ``func``.
    tasks : str
        How the twin's docstring describes its tasks.
    extras : tuple of inspect.Parameter
        Keyword-only parameters of the twin beyond ``func``'s (scheduling
        options such as ``riesz_tasks``), passed on to ``build``.
    examples : str
        The twin's Examples section (``func``'s own is left out: it is eager).

    Returns
    -------
    callable
    """
    signature = inspect.signature(func)
    signature = signature.replace(parameters=[*signature.parameters.values(), *extras],
                                  return_annotation="Delayed")

    def lazy(*args, **kwargs):
        bound = signature.bind(*args, **kwargs)
        bound.apply_defaults()
        if build is None:
            return _PLAIN.task(func.__name__, func)(*bound.args, **bound.kwargs)
        return build(_PLAIN, *bound.args, **bound.kwargs)

    functools.update_wrapper(lazy, func)
    del lazy.__wrapped__  # the twin's signature is its own (extras included)
    lazy.__signature__ = signature
    lazy.__module__ = __name__
    eager = inspect.cleandoc(func.__doc__ or "").split("\nExamples\n--------")[0].rstrip()
    lazy.__doc__ = f"Lazy :func:`{func.__module__}.{func.__name__}`: {tasks}.\n\n{eager}\n"
    if examples:
        lazy.__doc__ += f"\nExamples\n--------\n{inspect.cleandoc(examples)}\n"
    return lazy


def _load_tasks(builder: Builder, path, **options):
    return builder.task("load", _load)(str(path), **options)


load = mirror(_load, _load_tasks)


def from_surface(surface: Surface):
    """Put an in-memory surface into the graph once, as a single key."""
    return delayed(surface, name=f"surface-{surface.name}-{id(surface):x}")


def as_key(value):
    """A surface or array as one graph key (Delayed objects and small values pass through)."""
    if isinstance(value, Surface):
        return from_surface(value)
    if isinstance(value, np.ndarray) and value.size > 64:
        return delayed(value, name=f"array-{tokenize(value)}")
    return value


def _with_operators(surface: Surface) -> Surface:
    """Build the cached Laplacian, mass and normals (shared under the threads scheduler)."""
    _ = surface.stiffness, surface.mass, surface.normals
    return surface


def operators(surface):
    """Lazy operator build; later tasks in the same process reuse them (:func:`resident`)."""
    return _PLAIN.task("operators", _with_operators)(surface)


signal = mirror(_signal)
emd = mirror(_emd)


def eemd_tasks(builder: Builder, surface, signal, *, ensemble_size: int, noise_std: float, seed: int,
               **emd_options):
    """The tasks of ensemble EMD: one per member (:func:`hht3d.decomposition.decompose.eemd_member`), one averaging task."""
    member = builder.task("eemd_member", eemd_member)
    members = [member(surface, signal, i, seed, noise_std, **emd_options) for i in range(ensemble_size)]
    return builder.task("eemd_combine", combine_eemd)(surface, signal, members)


eemd = mirror(_eemd, eemd_tasks, tasks="one task per member, then one averaging task")


def _imfs(decomposition) -> object:
    return decomposition.imfs


def riesz_potential(surface, imfs, *, method: str = RIESZ_DEFAULTS.method, tol: float = RIESZ_DEFAULTS.tol,
                    eigenpairs: int = RIESZ_DEFAULTS.eigenpairs, backend: str | None = RIESZ_DEFAULTS.backend,
                    riesz_tasks: int | None = None, builder: Builder = _PLAIN):
    """Lazy ``L^{-1/2}`` of all IMFs, ``(k, n)``.

    ``method="quadrature"``: a bounds task, ``riesz_tasks`` shift-group tasks
    (:func:`hht3d.spectral.riesz_transform.quadrature_part`; default one per worker of the
    scheduler, :func:`hht3d.graph.stages.scheduling.worker_count`) and a summing task.
    Other methods: one task (:func:`hht3d.spectral.riesz_transform.fractional_laplacian`).
    """
    if method != "quadrature":
        return builder.task("riesz", fractional_laplacian)(
            surface, imfs, -0.5, method, tol, eigenpairs, backend)
    riesz_tasks = worker_count() if riesz_tasks is None else riesz_tasks
    if isinstance(riesz_tasks, bool) or not isinstance(riesz_tasks, int) or riesz_tasks < 1:
        raise InputError(f"riesz_tasks must be a whole number >= 1, got {riesz_tasks!r}")
    plan = builder.task("riesz_bounds", _quadrature_plan)(surface, tol, backend)
    part = builder.task("riesz_shifts", _quadrature_part)
    parts = [part(surface, imfs, plan, group, riesz_tasks, backend) for group in range(riesz_tasks)]
    return builder.task("riesz_sum", combine_quadrature_parts)(surface, parts)


#: The lazy-only parameter of :func:`monogenic` and :func:`hht`.
_RIESZ_TASKS = inspect.Parameter("riesz_tasks", inspect.Parameter.KEYWORD_ONLY, default=None,
                                 annotation="int | None")


def _monogenic_tasks(builder: Builder, surface, imfs, *, gradient: str, frequency: str, method: str, tol: float,
                     eigenpairs: int, backend: str | None, riesz_tasks: int | None):
    potential = riesz_potential(surface, imfs, method=method, tol=tol, eigenpairs=eigenpairs, backend=backend,
                                riesz_tasks=riesz_tasks, builder=builder)
    return builder.task("monogenic", _monogenic_from_potential)(surface, imfs, potential, gradient, frequency)


monogenic = mirror(_monogenic, _monogenic_tasks, extras=(_RIESZ_TASKS,),
                   tasks="the shift-group tasks of :func:`riesz_potential` (``riesz_tasks`` of them), then one "
                         "task of :func:`hht3d.spectral.monogenic_signal.monogenic_from_potential`")
monogenic_from_potential = mirror(_monogenic_from_potential)


def transform(builder: Builder, surface, signal, *, emd_options: dict | None = None,
              ensemble: dict | None = None,
              gradient: str = RIESZ_DEFAULTS.gradient, frequency: str = RIESZ_DEFAULTS.frequency,
              method: str = RIESZ_DEFAULTS.method, tol: float = RIESZ_DEFAULTS.tol,
              eigenpairs: int = RIESZ_DEFAULTS.eigenpairs, backend: str | None = RIESZ_DEFAULTS.backend,
              riesz_tasks: int | None = None) -> dict:
    """The tasks of one HHT, by stage name: ``emd``, ``imfs``, ``riesz``, ``monogenic``, ``hht``.

    ``ensemble``: EEMD options (``ensemble_size``, ``noise_std``, ``seed``)
    to decompose with ensemble EMD instead of EMD.
    """
    emd_options = {"backend": backend, **(emd_options or {})}
    if ensemble is not None:
        decomposition = eemd_tasks(builder, surface, signal, **ensemble, **emd_options)
    else:
        decomposition = builder.task("emd", _emd)(surface, signal, **emd_options)
    imfs = builder.task("imfs", _imfs)(decomposition)
    potential = riesz_potential(surface, imfs, method=method, tol=tol, eigenpairs=eigenpairs,
                                backend=backend, riesz_tasks=riesz_tasks, builder=builder)
    mono = builder.task("monogenic", _monogenic_from_potential)(surface, imfs, potential, gradient, frequency)
    riesz_options = RieszOptions(gradient, frequency, method, tol, eigenpairs, backend).recorded()
    result = builder.task("hht", HHTResult.from_parts)(surface, signal, decomposition, mono, riesz_options)
    return {"emd": decomposition, "imfs": imfs, "riesz": potential, "monogenic": mono, "hht": result}


def transform_file(builder: Builder, path, signal: str = "mean_curvature", load_options: dict | None = None,
                   **options) -> dict:
    """:func:`transform` of one file's signal, with its ``load`` and ``signal`` tasks."""
    surface = _load_tasks(builder, path, **(load_options or {}))
    values = builder.task("signal", _signal)(surface, signal)
    return {"load": surface, "signal": values, **transform(builder, surface, values, **options)}


#: The lazy-only parameter of :func:`hht`: EEMD options instead of EMD.
_ENSEMBLE = inspect.Parameter("ensemble", inspect.Parameter.KEYWORD_ONLY, default=None,
                              annotation="dict | None")


def _hht_tasks(builder: Builder, surface, signal, **options):
    return transform(builder, surface, signal, **options)["hht"]


hht = mirror(_hht, _hht_tasks, extras=(_ENSEMBLE, _RIESZ_TASKS),
             tasks="the tasks of :func:`transform` (``ensemble``: EEMD options, e.g. "
                   "``{'ensemble_size': 20, 'noise_std': 0.2, 'seed': 0}``, to decompose by EEMD)",
             examples="""
    The lazy result equals the eager one; only the order in which the shift
    groups' parts of ``L^{-1/2}`` are summed differs:

    >>> import numpy as np
    >>> import hht3d
    >>> from hht3d import data_path, graph
    >>> from hht3d.geometry.signals import mean_curvature
    >>> surface = hht3d.load(data_path("spot.ply"))
    >>> lazy = graph.hht(graph.from_surface(surface), mean_curvature(surface), emd_options={"max_imfs": 2},
    ...                  riesz_tasks=2)
    >>> (result,) = graph.compute(lazy, scheduler="synchronous", progress=False)
    >>> eager = hht3d.hht(surface, mean_curvature(surface), emd_options={"max_imfs": 2})
    >>> np.array_equal(result.imfs, eager.imfs)
    True
    >>> np.allclose(result.monogenic.riesz, eager.monogenic.riesz, rtol=0, atol=1e-10)
    True
    """)


def save(result, path):
    """Lazy :meth:`HHTResult.save <hht3d.transform.HHTResult.save>` (atomic PLY or npz write); returns the path."""
    return _PLAIN.task("save", HHTResult.save)(result, str(path))


# -- applications (Sec. 5, hht3d.apps): one task each ----------------------------------------
filter_signal = mirror(apps.filter_signal)
filter_geometry = mirror(apps.filter_geometry)
reconstruct = mirror(apps.reconstruct)
prominent_features = mirror(apps.prominent_features)
hks_features = mirror(apps.hks_features)
imf_enhancement = mirror(apps.imf_enhancement)
manifold_harmonics_filter = mirror(apps.manifold_harmonics_filter)
