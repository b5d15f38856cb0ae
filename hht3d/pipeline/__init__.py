"""Declarative YAML pipelines: load → process → export, validated before anything runs.

A pipeline file (schema in :mod:`hht3d.pipeline.validation`) names its inputs,
a list of steps (operations of :data:`~hht3d.pipeline.registry.OPERATIONS`, or of installed
plugins: :mod:`hht3d.pipeline.plugins`, with parameters and references to earlier steps) and the files to write.
:func:`load_pipeline` validates it into a typed :class:`Pipeline`;
:func:`run_pipeline` compiles that to the lazy graph of :mod:`hht3d.graph.stages`
and runs it on any scheduler of :mod:`hht3d.execution`.

>>> from hht3d import data_path
>>> from hht3d.pipeline import load_pipeline
>>> plan = load_pipeline(data_path("demo.yaml"), overrides=["steps.hht.params.max_imfs=2"])
>>> [step.id for step in plan.steps], plan.inputs[0].name
(['load', 'curvature', 'hht'], 'spot.ply')
>>> plan.step("hht").params["max_imfs"]
2

``run_pipeline(plan)`` then returns one ItemSummary per input file (see its example).

This layer adds configuration only: nothing in the core knows YAML exists.
"""

from typing import Any

from ..errors import HHT3DDeprecationWarning
from ..output_formats import FORMATS, Format
from .document import apply_overrides
from .params import Param
from .plan import ExecutionOptions, Output, Pipeline, Step
from .plugins import operations
from .registry import OPERATIONS, Operation, Slot
from .runner import failures, pipeline_graph, run_pipeline
from .validation import VERSION, builtin_models, load_pipeline, parse_pipeline

__all__ = [
    "VERSION",
    "load_pipeline",
    "parse_pipeline",
    "apply_overrides",
    "builtin_models",
    "Pipeline",
    "ExecutionOptions",
    "Step",
    "Output",
    "OPERATIONS",
    "operations",
    "Operation",
    "Slot",
    "Param",
    "FORMATS",
    "Format",
    "pipeline_graph",
    "run_pipeline",
    "failures",
]


def __getattr__(name: str) -> Any:
    """``Execution``, the former name of :class:`ExecutionOptions`, for one release."""
    if name == "Execution":
        import warnings

        warnings.warn("hht3d.pipeline.Execution is now ExecutionOptions", HHT3DDeprecationWarning, stacklevel=2)
        return ExecutionOptions
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
