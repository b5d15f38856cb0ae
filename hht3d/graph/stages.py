"""Lazy task-graph API: every HHT stage as a ``dask.delayed`` task.

This layer adds laziness only.  Each public core function has a lazy twin here with the same name,
signature and docstring (as dask-image mirrors SciPy's ndimage): ``graph.emd(surface, signal, max_imfs=3)``
takes what :func:`hht3d.decomposition.decompose.emd` takes, Delayed values included, and returns a
``Delayed``.  :func:`mirror` makes such a twin from any core function.  Stages compose freely and run on
any scheduler of :mod:`hht3d.execution`.

Examples
--------
>>> from hht3d import data_path, graph
>>> s = graph.load(data_path("spot.ply"))
>>> f = graph.signal(s, "mean_curvature")
>>> lazy = graph.hht(s, f, max_imfs=2)    # EMD -> Riesz shift groups -> spectra
>>> (result,) = graph.compute(lazy, scheduler="synchronous", progress=False)
>>> result.n_imfs
2

Parallelism follows the method:

* independent signals give independent :func:`emd` tasks; EEMD members are
  tasks of their own (:func:`eemd`);
* the Riesz transform of all IMFs is a sum over quadrature shifts (:mod:`hht3d.spectral.riesz_transform`):
  one task finds the spectral bounds and shifts, then ``riesz_tasks`` independent *shift-group* tasks
  (default: one per worker, :func:`hht3d.execution.workers.worker_count`) each factorize their shifts once
  and solve all IMFs as one multi-column right-hand side; they depend only on the EMD task and the
  surface, and factorizations never leave a task.  (One task per IMF would repeat every factorization
  once per IMF.)  :func:`monogenic` and :func:`hht` take ``riesz_tasks`` beyond the eager signature;
* the files of a dataset are independent subgraphs (:mod:`hht3d.dataset.run`).

How the tasks are made, and how workers keep each surface's operators, is
:mod:`hht3d.graph.tasks`.  Settings are checked when the graph is built:
``graph.emd(s, f, max_imf=2)`` raises before anything runs.
"""

from __future__ import annotations

import functools
import inspect
import re
from pathlib import Path
from typing import Any, Callable, ParamSpec

import numpy as np
from dask.delayed import Delayed

from .. import apps
from ..decomposition.decompose import emd as _emd
from ..decomposition.ensemble import eemd as _eemd
from ..decomposition.ensemble import ensemble_settings
from ..decomposition.options import EMDOptions, EnsembleOptions
from ..execution import compute
from ..geometry.signals import signal as _signal
from ..geometry.surface import Surface
from ..io.read import load as _load
from ..io.sealed import seal
from ..spectral.monogenic_signal import monogenic_from_potential as _monogenic_from_potential
from ..spectral.options import RieszOptions
from ..transform import HHTOptions, HHTResult, decomposition_stage, hht_settings, hht_stages
from .tasks import Builder, as_key, from_surface, resident, riesz_potential

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

P = ParamSpec("P")
_PLAIN = Builder()


def mirror(
    func: Callable[P, Any],
    build: Callable | None = None,
    *,
    settle: Callable | None = None,
    tasks: str = "one task",
    examples: str = "",
) -> Callable[P, Delayed]:
    """The lazy twin of the core function ``func``: its name, signature and docstring; a ``Delayed`` result.

    The twin's type is ``func``'s parameters returning ``Delayed``, so a type
    checker reads the same signature as the eager function's.

    Parameters
    ----------
    func : callable
        The eager core function.
    build : callable, optional
        ``build(builder, *args, **kwargs)`` making the tasks from the
        arguments bound to the signature, defaults applied; returns the
        result's ``Delayed``.  Default: one task calling ``func``.
    settle : callable, optional
        ``settle(arguments)`` turns the bound arguments' settings into checked
        records in place, so that a wrong setting raises while the graph is built.
    tasks : str
        How the twin's docstring describes its tasks.
    examples : str
        The twin's Examples section (``func``'s own is left out: it is eager).
    """
    signature = inspect.signature(func).replace(return_annotation="Delayed")

    def lazy(*args: Any, **kwargs: Any) -> Any:
        bound = signature.bind(*args, **kwargs)
        bound.apply_defaults()
        if settle is not None:
            settle(bound.arguments)
        if build is None:
            return _PLAIN.task(func.__name__, func)(*bound.args, **bound.kwargs)
        return build(_PLAIN, *bound.args, **bound.kwargs)

    functools.update_wrapper(lazy, func)
    delattr(lazy, "__wrapped__")  # the twin's signature is its own
    setattr(lazy, "__signature__", signature)
    lazy.__module__ = __name__
    eager = inspect.cleandoc(func.__doc__ or "").split("\nExamples\n--------")[0].rstrip()
    eager = re.sub(r"\nReturns\n-------\n.*?(?=\n\n\S[^\n]*\n-{3,}\n|\Z)", "", eager, flags=re.S).rstrip()
    returns = f"Returns\n-------\nDelayed\n    Computes to what :func:`{func.__module__}.{func.__name__}` returns."
    lazy.__doc__ = f"Lazy :func:`{func.__module__}.{func.__name__}`: {tasks}.\n\n{eager}\n\n{returns}\n"
    if examples:
        lazy.__doc__ += f"\nExamples\n--------\n{inspect.cleandoc(examples)}\n"
    return lazy


def _load_tasks(builder: Builder, path: Path | str, options: Any = None, **keywords: Any) -> Any:
    """The ``load`` task; its ``storage_options`` go into the graph sealed, as a token (:mod:`hht3d.io.sealed`)."""
    if keywords.get("storage_options"):
        keywords["storage_options"] = seal(keywords["storage_options"])
    return builder.task("load", _load)(str(path), options, **keywords)


load = mirror(_load, _load_tasks)


def _with_operators(surface: Surface) -> Surface:
    """Build the cached Laplacian, mass and normals (shared under the threads scheduler)."""
    _ = surface.stiffness, surface.mass, surface.normals
    return surface


def operators(surface: Surface) -> Any:
    """Lazy operator build; later tasks in the same process reuse them (:func:`resident`).

    Parameters
    ----------
    surface : Surface or Delayed
        The surface whose Laplacian, mass and normals are built.

    Returns
    -------
    Delayed
        Computes to ``surface`` with its operators cached.
    """
    return _PLAIN.task("operators", _with_operators)(surface)


def _settle_emd(arguments: dict) -> None:
    arguments["options"] = EMDOptions.of(arguments["options"], **arguments["overrides"])
    arguments["overrides"] = {}


def _settle_eemd(arguments: dict) -> None:
    arguments["options"], arguments["ensemble"] = ensemble_settings(
        arguments["options"], arguments["ensemble"], arguments["overrides"]
    )
    arguments["overrides"] = {}


def _eemd_tasks(
    builder: Builder,
    surface: Surface,
    signal: np.ndarray,
    options: EMDOptions,
    *,
    ensemble: EnsembleOptions,
    backend: str | None = None,
) -> Any:
    return decomposition_stage(builder, surface, signal, options, ensemble, backend)


signal = mirror(_signal)
emd = mirror(_emd, settle=_settle_emd)
eemd = mirror(_eemd, _eemd_tasks, settle=_settle_eemd, tasks="one task per member, then one averaging task")


def monogenic(
    surface: Surface,
    imfs: np.ndarray,
    options: RieszOptions | dict | None = None,
    *,
    backend: str | None = None,
    riesz_tasks: int | None = None,
    **overrides: Any,
) -> Delayed:
    """Lazy :func:`hht3d.spectral.monogenic`: the shift-group tasks of :func:`riesz_potential`
    (``riesz_tasks`` of them, default one per worker), then one task of
    :func:`hht3d.spectral.monogenic_from_potential`.  Arguments as the eager function's.

    Parameters
    ----------
    surface : Surface or Delayed
        The surface the IMFs live on.
    imfs : ndarray or Delayed
        The IMFs, ``(k, n)``.
    options : RieszOptions or dict, optional
        The Riesz settings, as for :func:`hht3d.spectral.monogenic`.
    backend : str, optional
        The sparse solver backend (default :func:`hht3d.linalg.default_backend`).
    riesz_tasks : int, optional
        Shift-group tasks of the quadrature (default: one per worker).
    **overrides
        Flat settings over ``options``.

    Returns
    -------
    Delayed
        Computes to the monogenic signal, as :func:`hht3d.spectral.monogenic` returns it.
    """
    options = RieszOptions.of(options, **overrides)
    builder = Builder(riesz_tasks=riesz_tasks)
    potential = builder.potential(surface, imfs, options, backend)
    return builder.task("monogenic", _monogenic_from_potential)(surface, imfs, potential, options)


monogenic_from_potential = mirror(_monogenic_from_potential)


def transform(
    builder: Builder,
    surface: Surface,
    signal: np.ndarray,
    options: HHTOptions | dict | None = None,
    *,
    backend: str | None = None,
    riesz_tasks: int | None = None,
    **overrides: Any,
) -> dict:
    """The tasks of one HHT by stage name (:func:`hht3d.transform.hht_stages`): ``emd``, ``imfs``,
    ``riesz``, ``monogenic``, ``hht``.  Settings (as for :func:`hht3d.hht`) are checked now, before
    any task runs.

    Parameters
    ----------
    builder : Builder
        The builder making the tasks (its guard wraps each one).
    surface : Surface or Delayed
        The surface.
    signal : ndarray or Delayed
        One value per vertex.
    options : HHTOptions or dict, optional
        The settings, as for :func:`hht3d.hht`.
    backend : str, optional
        The sparse solver backend (default :func:`hht3d.linalg.default_backend`).
    riesz_tasks : int, optional
        Shift-group tasks of the Riesz quadrature (default: one per worker).
    **overrides
        Flat settings over ``options``.

    Returns
    -------
    dict
        The ``Delayed`` of each stage, by name.
    """
    options = hht_settings(options, overrides, "transform")
    return hht_stages(Builder(builder.guard, riesz_tasks), surface, signal, options, backend=backend)


def transform_file(
    builder: Builder, path: Path | str, signal: str = "mean_curvature", load_options: dict | None = None, **options: Any
) -> dict:
    """:func:`transform` of one file's signal, with its ``load`` and ``signal`` tasks.

    Parameters
    ----------
    builder : Builder
        The builder making the tasks.
    path : Path or str
        The surface file (or URL) to load.
    signal : str, optional
        The signal's name, as for :func:`hht3d.geometry.signals.signal` (default ``"mean_curvature"``).
    load_options : dict, optional
        Keyword arguments of :func:`hht3d.load`.
    **options
        The arguments of :func:`transform` after ``signal``.

    Returns
    -------
    dict
        The ``Delayed`` of each stage, by name, with ``load`` and ``signal``.
    """
    surface = _load_tasks(builder, path, **(load_options or {}))
    values = builder.task("signal", _signal)(surface, signal)
    return {"load": surface, "signal": values, **transform(builder, surface, values, **options)}


def hht(
    surface: Surface,
    signal: np.ndarray,
    options: HHTOptions | dict | None = None,
    *,
    backend: str | None = None,
    riesz_tasks: int | None = None,
    **overrides: Any,
) -> Delayed:
    """Lazy :func:`hht3d.hht`: the tasks of :func:`transform` (``riesz_tasks`` shift groups of the
    Riesz quadrature, default one per worker).  Arguments as the eager function's.

    The lazy result equals the eager one up to the order in which the shift groups' parts of ``L^{-1/2}`` are summed.

    Parameters
    ----------
    surface : Surface or Delayed
        The surface (e.g. :func:`from_surface` or :func:`load`).
    signal : ndarray or Delayed
        One value per vertex.
    options : HHTOptions or dict, optional
        The settings, as for :func:`hht3d.hht`.
    backend : str, optional
        The sparse solver backend (default :func:`hht3d.linalg.default_backend`).
    riesz_tasks : int, optional
        Shift-group tasks of the Riesz quadrature (default: one per worker).
    **overrides
        Flat settings (e.g. ``max_imfs=2``) over ``options``.

    Returns
    -------
    Delayed
        Computes to the :class:`~hht3d.transform.HHTResult`.

    Examples
    --------
    >>> import numpy as np
    >>> import hht3d
    >>> from hht3d import data_path, graph
    >>> from hht3d.geometry.signals import mean_curvature
    >>> surface = hht3d.load(data_path("spot.ply"))
    >>> lazy = graph.hht(graph.from_surface(surface), mean_curvature(surface), max_imfs=2, riesz_tasks=2)
    >>> (result,) = graph.compute(lazy, scheduler="synchronous", progress=False)
    >>> eager = hht3d.hht(surface, mean_curvature(surface), max_imfs=2)
    >>> np.array_equal(result.imfs, eager.imfs)
    True
    >>> np.allclose(result.monogenic.riesz, eager.monogenic.riesz, rtol=0, atol=1e-10)
    True
    """
    options = hht_settings(options, overrides, "hht")
    return transform(_PLAIN, surface, signal, options, backend=backend, riesz_tasks=riesz_tasks)["hht"]


def save(result: HHTResult, path: Path | str, *, storage_options: dict | None = None) -> Any:
    """Lazy :meth:`HHTResult.save <hht3d.transform.HHTResult.save>` (atomic PLY or npz write; ``path`` may be an
    fsspec URL, written by the worker with ``storage_options``, which the task carries sealed, as a token:
    :mod:`hht3d.io.sealed`); returns the path.

    Parameters
    ----------
    result : HHTResult or Delayed
        The result to write.
    path : Path or str
        A ``.ply`` or ``.npz`` path, or an fsspec URL.
    storage_options : dict, optional
        Options of the fsspec back-end of a URL ``path``.

    Returns
    -------
    Delayed
        Computes to the path written.
    """
    return _PLAIN.task("save", HHTResult.save)(result, str(path), storage_options=seal(storage_options))


# -- applications (Sec. 5, hht3d.apps): one task each ----------------------------------------
filter_signal = mirror(apps.filter_signal)
filter_geometry = mirror(apps.filter_geometry)
reconstruct = mirror(apps.reconstruct)
prominent_features = mirror(apps.prominent_features)
hks_features = mirror(apps.hks_features)
imf_enhancement = mirror(apps.imf_enhancement)
manifold_harmonics_filter = mirror(apps.manifold_harmonics_filter)
