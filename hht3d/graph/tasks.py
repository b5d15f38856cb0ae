"""How the lazy graph makes its tasks: one key per surface, operators resident on each worker.

A :class:`Builder` turns core functions into ``dask.delayed`` tasks.  In-memory
surfaces and arrays enter a graph once, as one key each (:func:`as_key`), and
are shared by reference between the tasks that use them.

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
import threading
from collections import OrderedDict
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from dask import delayed
from dask.base import tokenize

from ..execution.workers import worker_count
from ..geometry.surface import Surface
from ..linalg.backends import default_backend
from ..records import Record, option
from ..spectral.multilevel import combine_riesz_parts, riesz_part
from ..spectral.options import RieszOptions
from ..spectral.quadrature import combine_quadrature_parts, quadrature_part, quadrature_plan
from ..spectral.riesz_transform import fractional_laplacian
from ..spectral.shifts import shift_analysis

if TYPE_CHECKING:
    from hht3d.spectral.quadrature import QuadraturePlan


__all__ = [
    "Builder",
    "GraphOptions",
    "resident",
    "as_key",
    "from_surface",
    "riesz_potential",
    "RESIDENT_SURFACES",
    "ARRAY_KEY_SIZE",
    "MAX_RIESZ_TASKS",
]

#: Arrays with more entries than this enter a graph as a key of their own (shared by reference);
#: smaller ones are copied into each task, where a key would cost more than the copy.
ARRAY_KEY_SIZE = 64


#: Shift-group tasks of the Riesz quadrature, which has about 60 shifts even at the finest tol.
MAX_RIESZ_TASKS = 64


@dataclass(frozen=True)
class GraphOptions(Record):
    """How a graph splits its work beyond the method's settings."""

    label = "graph"

    riesz_tasks: int | None = option(
        None,
        "parallel shift-group tasks of the quadrature (default: one per worker)",
        kind="int",
        minimum=1,
        maximum=MAX_RIESZ_TASKS,
    )


class Builder:
    """Makes the tasks of a graph.

    Parameters
    ----------
    guard : callable, optional
        ``guard(step, func) -> callable`` wrapping every task's function; the
        dataset runner uses it to isolate failures per file
        (:class:`hht3d.dataset.guard.Failure`).  Default: tasks raise normally.
    riesz_tasks : int, optional
        Shift-group tasks of the Riesz quadrature (:func:`riesz_potential`).
    """

    def __init__(
        self,
        guard: Callable[..., Callable[..., Any]] | None = None,
        riesz_tasks: int | None = None,
    ) -> None:
        self.guard = guard
        self.riesz_tasks = GraphOptions.check("riesz_tasks", riesz_tasks)

    def task(self, step: str, func: Callable[..., Any]) -> Callable[..., Any]:
        """A ``dask.delayed`` of ``func`` named after ``step``.

        In-memory surfaces and arrays among its arguments enter the graph once,
        as their own keys (:func:`as_key`), instead of being copied into every task.
        """
        func = _OnWorker(func)
        wrapped = delayed(func if self.guard is None else self.guard(step, func), pure=True)

        def call(*args: Any, **kwargs: Any) -> Any:
            return wrapped(*map(as_key, args), **{k: as_key(v) for k, v in kwargs.items()})

        return call

    def potential(self, surface: Surface, imfs: np.ndarray, riesz: RieszOptions, backend: str | None) -> Any:
        """``L^{-1/2}`` of the IMFs as :func:`riesz_potential`'s tasks (the ``Stages`` of
        :func:`hht3d.transform.hht_stages`)."""
        return riesz_potential(surface, imfs, riesz, backend=backend, riesz_tasks=self.riesz_tasks, builder=self)

    def riesz_vectors(self, surface: Surface, decomposition: Any, riesz: RieszOptions, backend: str | None) -> Any:
        """The Riesz vectors of the IMFs on their levels: one task per group of IMFs (``riesz_tasks``,
        default one per worker), then a combining task."""
        groups = self.riesz_tasks or worker_count()
        part = self.task("riesz_imfs", riesz_part)
        parts = [part(surface, decomposition, riesz, backend, group, groups) for group in range(groups)]
        return self.task("riesz_sum", combine_riesz_parts)(surface, parts)


#: Geometries whose caches a process keeps across tasks (the least recently used is dropped).
RESIDENT_SURFACES = 2
_RESIDENT: OrderedDict = OrderedDict()
_RESIDENT_LOCK = threading.Lock()


def resident(surface: Surface) -> Surface:
    """``surface``, sharing this process's cache for its geometry (operators, bounds, analyses).

    The cache is keyed by the vertices, faces, Laplacian options and given
    normals; the :data:`RESIDENT_SURFACES` most recently used ones are kept.
    Returns the same object, whose ``cache`` is now the shared one.

    Parameters
    ----------
    surface : Surface
        The surface whose cache is shared.

    Returns
    -------
    Surface
        ``surface`` itself.
    """
    key = tokenize(
        surface.vertices, surface.faces, surface.laplacian, surface.n_neighbors, surface.cache.get("normals")
    )
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

    def __init__(self, func: Callable[..., Any]):
        self.func = func
        functools.update_wrapper(self, func)

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        def local(value: Any) -> Any:
            return resident(value) if isinstance(value, Surface) else value

        return self.func(*map(local, args), **{k: local(v) for k, v in kwargs.items()})

    def __dask_tokenize__(self) -> tuple:
        return "hht3d.graph.tasks._OnWorker", tokenize(self.func)


class _SharedAnalysis:
    """A surface's shift analysis (:func:`hht3d.spectral.shifts.shift_analysis`), one task at a time.

    PARDISO and CHOLMOD keep one numeric factor per analysis, so tasks sharing
    it in one process (threads) take turns.  One per backend and ``tol`` (the
    accuracy an iterative backend's solves keep).
    """

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._symbolic = None

    @classmethod
    @contextlib.contextmanager
    def of(cls, surface: Surface, backend: str | None, tol: float) -> Iterator[Any]:
        backend = default_backend() if backend is None else backend
        with _RESIDENT_LOCK:
            shared = surface.cache.setdefault(f"graph:shift_analysis:{backend}:{tol!r}", cls())
        with shared._lock:
            if shared._symbolic is None:
                shared._symbolic = shift_analysis(surface, backend, tol)
            yield shared._symbolic


def _quadrature_plan(surface: Surface, tol: float, backend: str | None) -> QuadraturePlan:
    """:func:`hht3d.spectral.quadrature_plan` with this process's shared shift analysis."""
    with _SharedAnalysis.of(surface, backend, tol) as symbolic:
        return quadrature_plan(surface, tol, symbolic=symbolic)


def _quadrature_part(
    surface: Surface, f: np.ndarray, plan: QuadraturePlan, group: int, groups: int, backend: str | None
) -> np.ndarray:
    """:func:`hht3d.spectral.quadrature_part` with this process's shared shift analysis."""
    with _SharedAnalysis.of(surface, backend, plan.tol) as symbolic:
        return quadrature_part(surface, f, plan, group, groups, symbolic=symbolic)


def from_surface(surface: Surface) -> Any:
    """Put an in-memory surface into the graph once, as a single key.

    Parameters
    ----------
    surface : Surface
        The surface to put in the graph.

    Returns
    -------
    Delayed
        The surface's key.

    Examples
    --------
    >>> from hht3d import data_path, load
    >>> spot = load(data_path("spot.ply"))
    >>> from hht3d import graph
    >>> key = graph.from_surface(spot)
    >>> (again,) = graph.compute(key, scheduler="synchronous", progress=False)
    >>> again is spot
    True
    """
    return delayed(surface, name=f"surface-{surface.name}-{id(surface):x}")


def as_key(value: Any) -> Any:
    """A surface or array as one graph key (Delayed objects and small values pass through).

    Parameters
    ----------
    value : object
        A :class:`Surface`, an array, a ``Delayed`` or any small value.

    Returns
    -------
    object
        A ``Delayed`` for a surface or a large array (:data:`ARRAY_KEY_SIZE`), else ``value``.

    Examples
    --------
    >>> import numpy as np
    >>> from dask.delayed import Delayed
    >>> from hht3d import graph
    >>> graph.as_key(3), isinstance(graph.as_key(np.zeros(10_000)), Delayed)  # a large array becomes a key
    (3, True)
    """
    if isinstance(value, Surface):
        return from_surface(value)
    if isinstance(value, np.ndarray) and value.size > ARRAY_KEY_SIZE:
        return delayed(value, name=f"array-{tokenize(value)}")
    return value


def riesz_potential(
    surface: Surface,
    imfs: np.ndarray,
    options: RieszOptions | dict | None = None,
    *,
    backend: str | None = None,
    riesz_tasks: int | None = None,
    builder: Builder | None = None,
    **overrides: Any,
) -> Any:
    """Lazy ``L^{-1/2}`` of all IMFs, ``(k, n)``, with the ``potential``, ``tol`` and ``eigenpairs`` of
    ``options`` (:class:`~hht3d.spectral.options.RieszOptions`, with ``overrides``).

    ``potential="quadrature"``: a bounds task, ``riesz_tasks`` shift-group tasks
    (:func:`hht3d.spectral.quadrature_part`; default one per worker of the
    scheduler, :func:`hht3d.execution.workers.worker_count`) and a summing task.
    Other potentials: one task (:func:`hht3d.spectral.riesz_transform.fractional_laplacian`).

    Parameters
    ----------
    surface : Surface or Delayed
        The surface the IMFs live on.
    imfs : ndarray or Delayed
        The IMFs, ``(k, n)``.
    options : RieszOptions or dict, optional
        The Riesz settings.
    backend : str, optional
        The sparse solver backend (default :func:`hht3d.linalg.default_backend`).
    riesz_tasks : int, optional
        Shift-group tasks of the quadrature (default: one per worker).
    builder : Builder, optional
        The builder making the tasks (default: a plain one).
    **overrides
        Flat settings over ``options``.

    Returns
    -------
    Delayed
        Computes to the ``(k, n)`` potential ``L^{-1/2}`` of the IMFs.
    """
    options = RieszOptions.of(options, **overrides)
    builder = Builder() if builder is None else builder
    if options.potential != "quadrature":
        return builder.task("riesz", fractional_laplacian)(surface, imfs, -0.5, options, backend=backend)
    riesz_tasks = GraphOptions.check("riesz_tasks", riesz_tasks) or worker_count()
    plan = builder.task("riesz_bounds", _quadrature_plan)(surface, options.tol, backend)
    part = builder.task("riesz_shifts", _quadrature_part)
    parts = [part(surface, imfs, plan, group, riesz_tasks, backend) for group in range(riesz_tasks)]
    return builder.task("riesz_sum", combine_quadrature_parts)(surface, parts)
