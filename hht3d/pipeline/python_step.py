"""The ``python`` step: an importable function ``module:function`` called on an earlier step's result.

::

    - {id: rescaled, op: python, from: hht, params: {function: "mylab.tools:rescale", output: signal}}

calls ``mylab.tools.rescale(result)`` with the ``hht`` step's result and takes what it returns
as a result of kind ``output`` (a signal: an ``(n,)`` array; a surface, an EMD or HHT result,
features), which later steps and outputs use like any other.  The string is checked when the
pipeline is validated; the module is imported only when a run is allowed to run code, as for a
plugin's operation (:func:`~hht3d.pipeline.plugins.check_allowed`): first once before anything
is computed, so a module that does not import or lacks the function is one line, then by each
task.  A function that raises fails that input's step, reported in its summary row.
"""

from __future__ import annotations

import importlib
import re
from collections.abc import Callable, Iterable
from operator import attrgetter
from typing import Any

import numpy as np

from ..apps.features import FeatureResult
from ..decomposition.decompose import EMDResult
from ..errors import PipelineError, one_line, shown
from ..geometry.surface import Surface
from ..transform import HHTResult
from .params import REQUIRED, Param

__all__ = ["NAME", "PARAMS", "RESULTS", "check_function", "resolve", "call", "resolve_steps"]

#: The op name of the step.
NAME = "python"
#: The kinds a ``python`` step takes and can make, with the type of each result.
RESULTS: dict[str, type] = {
    "surface": Surface,
    "signal": np.ndarray,
    "emd": EMDResult,
    "hht": HHTResult,
    "features": FeatureResult,
}
PARAMS = (
    Param("function", "str", "the function to call, module:function (e.g. mylab.tools:rescale)", default=REQUIRED),
    Param("output", "choice", "the kind of result the function returns", default="signal", choices=tuple(RESULTS)),
)
_DOTTED = r"[A-Za-z_]\w*(?:\.[A-Za-z_]\w*)*"
_SPEC = re.compile(f"({_DOTTED}):({_DOTTED})")


def check_function(params: dict, where: str) -> None:
    """Refuse a ``function`` that is not ``module:function`` (without importing anything).

    Parameters
    ----------
    params : dict
        The step's checked parameters.
    where : str
        The step's place in the pipeline, for the message.

    Raises
    ------
    PipelineError
        ``function`` is not two dotted names joined by ``:``.
    """
    if _SPEC.fullmatch(params["function"]) is None:
        raise PipelineError(
            f"{where}: parameter function must be module:function, e.g. mylab.tools:rescale; "
            f"got {shown(params['function'])}"
        )


def resolve(spec: str) -> Callable[..., Any]:
    """The function ``module:function`` names, its module imported.

    Parameters
    ----------
    spec : str
        ``module:function``; the function may be a dotted attribute path (``module:Class.method``).

    Returns
    -------
    callable

    Raises
    ------
    PipelineError
        The module does not import, lacks the attribute, or it is not callable.
    """
    module_name, attribute = spec.split(":")
    try:
        module = importlib.import_module(module_name)
    except Exception as exc:  # any error of the user's import
        reason = one_line(f"{type(exc).__name__}: {exc}")
        raise PipelineError(f"python function {spec}: module {module_name!r} does not import: {reason}") from None
    try:
        function = attrgetter(attribute)(module)
    except AttributeError:
        raise PipelineError(f"python function {spec}: module {module_name!r} has no attribute {attribute!r}") from None
    if not callable(function):
        raise PipelineError(f"python function {spec}: {attribute!r} is {shown(function)}, not a function")
    return function


def call(value: Any, *, function: str, output: str) -> Any:
    """``function(value)``, checked to be a result of kind ``output``.

    Parameters
    ----------
    value : object
        The result of the step the ``python`` step takes.
    function : str
        ``module:function``.
    output : str
        The kind of result it must return (:data:`RESULTS`).

    Returns
    -------
    object
        What the function returned; a signal as a float64 array.

    Raises
    ------
    PipelineError
        The function cannot be resolved or returns something of another kind; what the
        function itself raises passes through (the runner reports it for the input).
    """
    result = resolve(function)(value)
    if output == "signal" and isinstance(result, (np.ndarray, list, tuple)):
        array = np.asarray(result)
        if array.ndim == 1 and array.dtype.kind in "biuf":
            return array.astype(np.float64)
    elif isinstance(result, RESULTS[output]):
        return result
    wanted = "a 1-D array of numbers" if output == "signal" else RESULTS[output].__name__
    raise PipelineError(
        f"python function {function} returned {type(result).__name__} {shown(result, 60)}, not {wanted} "
        f"(its step has output: {output})"
    )


def resolve_steps(steps: Iterable[Any]) -> None:
    """Import the function of every ``python`` step once, before a run computes anything.

    Parameters
    ----------
    steps : iterable of Step

    Raises
    ------
    PipelineError
        Naming the step whose function cannot be resolved.
    """
    for step in steps:
        if step.op.name == NAME:
            try:
                resolve(step.params["function"])
            except PipelineError as exc:
                raise PipelineError(f"step {step.id!r}: {exc}") from None
