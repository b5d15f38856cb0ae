"""Compiling a validated :class:`~.plan.Pipeline` to a Dask graph and running it.

Every input file becomes an independent subgraph of its steps' tasks
(:mod:`hht3d.graph`) and output writes.  Every task is guarded as in
:mod:`hht3d.dataset`: an exception becomes a record of the step and the
input file that the item's later tasks pass along, so one bad file is
reported while the others finish.  An output is written once the step it
comes from is done, atomically: a failed item may have the outputs of its
earlier steps, never a half-written file.
"""
from __future__ import annotations

import dataclasses
from pathlib import Path

from dask import delayed
from dask.base import tokenize

from ..dataset import Failure, ItemSummary, Guarded, write_summary
from ..graph import Builder
from ..scheduling import compute
from .plan import FILE, Pipeline

__all__ = ["pipeline_graph", "run_pipeline", "failures"]


def _step_builder(step_id: str, op_name: str, source: str) -> Builder:
    """Tasks guarded with the input file; a step's inner tasks are labelled ``"id (task)"``."""

    def guard(task: str, func):
        label = step_id if task in (op_name, step_id) else f"{step_id} ({task})"
        return Guarded(label, func, source)

    return Builder(guard=guard)


def _summarize(source: str, paths: list[str], surface, sizes: list, parts: list, writes: list) -> ItemSummary:
    failure = next((v for v in [*parts, *writes] if isinstance(v, Failure)), None)
    if failure is not None:
        return ItemSummary(source, "failed", step=failure.step, error=failure.error)
    imfs = next((v.value.imfs.shape[0] for v in reversed(sizes)), None)
    seconds = sum(v.seconds for v in [*parts, *writes])
    return ItemSummary(source, "ok", vertices=surface.value.n_vertices, imfs=imfs, seconds=round(seconds, 3),
                       outputs=tuple(paths))


def _item(plan: Pipeline, source: Path, paths: list[Path]):
    """The lazy :class:`~hht3d.dataset.ItemSummary` of one input file."""
    results, parts = {}, {}
    for step in plan.steps:
        builder = _step_builder(step.id, step.op.name, str(source))
        inputs = {slot: source if ref == FILE else results[ref] for slot, ref in step.refs.items()}
        tasks = step.op.build(builder, inputs, dict(step.params))
        results[step.id] = tasks["result"]
        parts.update({t.key: t for t in tasks.values()})
    writes = []
    for output, path in zip(plan.outputs, paths):
        write = Builder(guard=lambda task, func, label=f"write {path.name}": Guarded(label, func, str(source)))
        writes.append(write.task("write", output.format.write)(
            results[output.step], results[plan.origin_of(output.step)], str(path), **output.options))
    first_load = next(s.id for s in plan.steps if s.op.name == "load")
    sizes = [results[s.id] for s in plan.steps if s.kind in ("emd", "hht")]
    name = f"pipeline-item-{tokenize(plan.name, str(source), [str(p) for p in paths])}"
    return delayed(_summarize, pure=True, name=name)(str(source), [str(p) for p in paths], results[first_load],
                                                     sizes, list(parts.values()), writes)


def pipeline_graph(plan: Pipeline, *, resume: bool = False):
    """The pipeline as one lazy list of :class:`~hht3d.dataset.ItemSummary`, one per input file.

    Parameters
    ----------
    plan : Pipeline
    resume : bool
        Skip inputs whose outputs all exist (status ``"skipped"``).
    """
    rows = []
    for source in plan.inputs:
        paths = plan.output_paths(source)
        if resume and all(p.is_file() for p in paths):
            rows.append(ItemSummary(str(source), "skipped", outputs=tuple(map(str, paths))))
        else:
            rows.append(_item(plan, source, paths))
    return delayed(list, pure=True)(rows)


def run_pipeline(plan: Pipeline, *, scheduler: str | None = None, workers: int | None = None,
                 address: str | None = None, progress: bool | None = None,
                 resume: bool = False) -> list[ItemSummary]:
    """Run a pipeline; return one :class:`~hht3d.dataset.ItemSummary` per input file.

    Arguments left as ``None`` take the pipeline's ``execution`` block.
    Failed items are reported in the rows (see :func:`failures`), not
    raised; with ``outputs.summary`` the rows are also written to
    ``summary.json`` and ``summary.csv`` in the output folder.
    """
    given = {"scheduler": scheduler, "workers": workers, "address": address, "progress": progress}
    execution = dataclasses.replace(plan.execution, **{k: v for k, v in given.items() if v is not None})
    (rows,) = compute(pipeline_graph(plan, resume=resume), scheduler=execution.scheduler,
                      workers=execution.workers, address=execution.address, progress=execution.progress)
    if plan.summary:
        write_summary(rows, plan.folder)
    return rows


def failures(rows: list[ItemSummary]) -> list[str]:
    """One line per failed item: ``"step S failed on FILE: ERROR"``."""
    return [f"step {r.step} failed on {r.source}: {r.error}" for r in rows if r.status == "failed"]
