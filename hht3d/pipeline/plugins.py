"""Operations other packages add, through the entry-point group ``hht3d.operations``.

A distribution declares, in its ``pyproject.toml``::

    [project.entry-points."hht3d.operations"]
    smooth = "hht3d_smooth:OPERATIONS"     # an Operation, or a list of them

and each :class:`~hht3d.pipeline.registry.Operation` it names (the same record as the built-in
ones: slots, output kind, :class:`~hht3d.pipeline.params.Param` parameters, ``func`` or
``build``) becomes a pipeline operation: validation, ``hht3d ops`` (with the distribution it
comes from), the JSON Schema and the task graph read :func:`operations`.  Entry points are
loaded once, on the first call, not when hht3d is imported.  A plugin that fails to import, names
something that is not an ``Operation``, uses an unknown kind or takes the name of a built-in or an
earlier plugin's operation is left out and reported in one line (:func:`plugin_problems`, logged as
a warning); the others still load.  Pipelines are shared files and a plugin's operation runs its
package's code, so a run refuses one, and a ``python`` step, unless the user allows it (:func:`check_allowed`:
``hht3d run --allow-plugins``, or ``HHT3D_ALLOW_PLUGINS=1`` in the user's environment).
"""

from __future__ import annotations

import functools
import importlib.metadata
import os
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

from ..errors import PipelineError, one_line, shown
from ..logs import get_logger
from . import python_step
from .params import did_you_mean
from .registry import OPERATIONS, Operation

__all__ = ["GROUP", "KINDS", "ALLOW", "operations", "operation", "plugin_sources", "plugin_problems", "check_allowed"]

#: The entry-point group plugins register in.
GROUP = "hht3d.operations"
#: The user's environment variable that lets every run use plugin operations (``1``); never the pipeline's.
ALLOW = "HHT3D_ALLOW_PLUGINS"
#: The kinds a slot takes and an operation makes (:mod:`hht3d.pipeline.registry`).
KINDS = ("file", "surface", "signal", "emd", "hht", "features")


@dataclass(frozen=True)
class _Plugins:
    operations: dict[str, Operation]
    sources: dict[str, str]
    problems: tuple[str, ...]


def _distribution(entry: Any) -> str:
    dist = getattr(entry, "dist", None)
    return f"{dist.name} {dist.version}" if dist is not None else entry.value


def _declared(value: Any) -> list[Any]:
    return list(value) if isinstance(value, Iterable) and not isinstance(value, (str, bytes)) else [value]


def _fault(op: Any, taken: dict[str, str]) -> str | None:
    """Why ``op`` cannot be registered, or ``None``."""
    if not isinstance(op, Operation):
        return f"names {shown(op)}, not an hht3d.pipeline.Operation"
    if op.name in OPERATIONS:
        return f"declares operation {op.name!r}, the name of a built-in operation; rename it"
    if op.name in taken:
        return f"declares operation {op.name!r}, already declared by {taken[op.name]}"
    kinds = {op.output, *(kind for slot in op.slots for kind in slot.kinds)} - set(KINDS)
    if kinds:
        return f"operation {op.name!r} uses unknown kinds {', '.join(sorted(kinds))}; use {', '.join(KINDS)}"
    return None


@functools.cache
def _plugins() -> _Plugins:
    found: dict[str, Operation] = {}
    sources: dict[str, str] = {}
    problems: list[str] = []
    for entry in importlib.metadata.entry_points(group=GROUP):
        source = _distribution(entry)
        try:
            declared = _declared(entry.load())
        except Exception as exc:  # any error of a third-party import
            problems.append(f"plugin {entry.name!r} ({source}) failed to load: {one_line(exc)}")
            continue
        for op in declared:
            fault = _fault(op, sources)
            if fault is not None:
                problems.append(f"plugin {entry.name!r} ({source}) {fault}")
                continue
            found[op.name], sources[op.name] = op, source
    for problem in problems:
        get_logger().warning("%s", problem)
    return _Plugins(found, sources, tuple(problems))


def operations() -> dict[str, Operation]:
    """The built-in operations, then those of the installed plugins.

    Returns
    -------
    dict of str to Operation
        Operations by name (a plugin's never replaces a built-in one).

    Examples
    --------
    >>> from hht3d.pipeline import operations
    >>> "hht" in operations()
    True
    """
    return {**OPERATIONS, **_plugins().operations}


def plugin_sources() -> dict[str, str]:
    """The distribution (``name version``) of each plugin operation, by operation name."""
    return dict(_plugins().sources)


def plugin_problems() -> tuple[str, ...]:
    """One line per plugin left out, and why."""
    return _plugins().problems


def operation(name: str, where: str) -> Operation:
    """The operation called ``name``; a :class:`PipelineError` with "did you mean" (and the plugins
    that failed to load) otherwise."""
    known = operations()
    if not isinstance(name, str) or name not in known:
        failed = "".join(f"; {problem}" for problem in plugin_problems())
        raise PipelineError(
            f"{where}: unknown op {shown(name)}{did_you_mean(name, known)} (`hht3d ops` lists them){failed}"
        )
    return known[name]


def check_allowed(steps: Iterable[Any], allow: bool | None = None) -> None:
    """Refuse a step whose operation comes from a plugin, or a ``python`` step
    (:mod:`hht3d.pipeline.python_step`), unless ``allow`` (``None``: whether the user's environment
    sets :data:`ALLOW` to ``1``).

    Raises
    ------
    PipelineError
        Naming the step, the operation, its distribution and how to allow it.
    """
    if allow if allow is not None else os.environ.get(ALLOW) == "1":
        return
    sources = plugin_sources()
    for step in steps:
        if step.op.name in sources:
            raise PipelineError(
                f"step {step.id!r} runs op {step.op.name!r} of the plugin {sources[step.op.name]}, which runs that "
                f"package's code; pass --allow-plugins (or set {ALLOW}=1) to run it"
            )
        if step.op.name == python_step.NAME:
            raise PipelineError(
                f"step {step.id!r} is a python step calling {step.params['function']}, which runs that code; "
                f"pass --allow-plugins (or set {ALLOW}=1) to run it"
            )
