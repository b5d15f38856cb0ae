"""Declarative YAML pipelines: load → process → export, validated before anything runs.

A pipeline file (schema in :mod:`hht3d.pipeline.schema`) names its inputs,
a list of steps (operations of :data:`~hht3d.pipeline.registry.OPERATIONS`
with parameters and references to earlier steps) and the files to write.
:func:`load_pipeline` validates it into a typed :class:`Pipeline`;
:func:`run_pipeline` compiles that to the lazy graph of :mod:`hht3d.graph`
and runs it on any scheduler of :mod:`hht3d.scheduling`.

>>> from hht3d.pipeline import load_pipeline, run_pipeline
>>> plan = load_pipeline("pipelines/demo.yaml", overrides=["inputs=model.ply"])
>>> print(plan.describe())
>>> rows = run_pipeline(plan, scheduler="processes")   # one ItemSummary per input file

This layer adds configuration only: nothing in the core knows YAML exists.
"""
from .outputs import FORMATS, Format
from .params import Param
from .plan import Execution, Output, Pipeline, Step
from .registry import OPERATIONS, Operation, Slot
from .runner import failures, pipeline_graph, run_pipeline
from .document import apply_overrides
from .schema import VERSION, builtin_models, load_pipeline, parse_pipeline

__all__ = [
    "VERSION", "load_pipeline", "parse_pipeline", "apply_overrides", "builtin_models",
    "Pipeline", "Execution", "Step", "Output",
    "OPERATIONS", "Operation", "Slot", "Param", "FORMATS", "Format",
    "pipeline_graph", "run_pipeline", "failures",
]
