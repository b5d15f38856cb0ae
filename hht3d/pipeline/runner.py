"""Compiling a validated :class:`~.plan.Pipeline` to a Dask graph and running it.

Every input file becomes an independent subgraph of its steps' tasks
(:mod:`hht3d.graph.stages`) and output writes.  Every task is guarded as in
:mod:`hht3d.graph.guard`: an exception becomes a record of the step and the
input file that the item's later tasks pass along, so one bad file is
reported while the others finish.  An output is written once the step it
comes from is done, atomically, and recorded in the output folder's manifest
(:mod:`hht3d.io.manifest`): a failed item may have the outputs of its earlier
steps, which its summary row lists, never a half-written file.  Before
anything is computed (:func:`hht3d.graph.dataset.prepare_outputs`) the
outputs are checked writable, a file hht3d did not write is refused unless
``overwrite``, and temporary files of killed runs are removed.
"""
from __future__ import annotations

import dataclasses
from pathlib import Path

from dask import delayed
from dask.base import tokenize

from ..graph.dataset import Guarded, ItemSummary, item_summary, items_graph, prepare_outputs, quality_fields, write_summary
from ..graph.scheduling import compute
from ..graph.stages import Builder
from ..io import new_run_id
from ..io.manifest import Recorded
from .plan import FILE, Pipeline
from .schema import EXECUTION

__all__ = ["pipeline_graph", "run_pipeline", "failures"]


def _guarded(source: Path, label):
    """A task builder whose tasks are guarded with the input file; ``label(task)`` names the step."""
    return Builder(guard=lambda task, func: Guarded(label(task), func, str(source)))


def _item(plan: Pipeline, run: str, source: Path, paths: list[Path]):
    """The lazy :class:`~hht3d.graph.summary.ItemSummary` of one input file."""
    results, parts = {}, {}
    for step in plan.steps:
        builder = _guarded(source, lambda task, s=step: s.id if task in (s.op.name, s.id) else f"{s.id} ({task})")
        inputs = {slot: str(source) if ref == FILE else results[ref] for slot, ref in step.refs.items()}
        tasks = step.op.tasks(builder, inputs, dict(step.params))
        results[step.id] = tasks["result"]
        parts.update({t.key: t for t in tasks.values()})
    writes = []
    for output, path in zip(plan.outputs, paths):
        write = _guarded(source, lambda task, label=f"write {path.name}": label)
        writes.append(write.task("write", Recorded(output.format.write, plan.folder, run))(
            results[output.step], results[plan.origin_of(output.step)], str(path), **output.options))
    surface = results[next(s.id for s in plan.steps if s.op.name == "load")]
    last = next((s.id for s in reversed(plan.steps) if s.kind in ("emd", "hht")), None)
    decomposition = quality = None
    if last is not None:
        decomposition = results[last]
        quality = _guarded(source, lambda task: f"{last} (quality)").task("quality", quality_fields)(
            decomposition, results[plan.surface_of(last)])
        parts[quality.key] = quality
    name = f"pipeline-item-{tokenize(plan.name, str(source), [str(p) for p in paths])}"
    return delayed(item_summary, pure=True, name=name)(str(source), [str(p) for p in paths], surface,
                                                       decomposition, quality, list(parts.values()), writes)


def pipeline_graph(plan: Pipeline, *, resume: bool = False, run: str | None = None):
    """The pipeline as one lazy list of :class:`~hht3d.graph.summary.ItemSummary`, one per input file.

    Parameters
    ----------
    plan : Pipeline
    resume : bool
        Skip inputs whose outputs the output folder's manifest records as
        complete (status ``"skipped"``, sizes read from those outputs).
    run : str, optional
        The run id recorded in the manifest (default: a new one).
    """
    run = run or new_run_id()
    items = {source: plan.output_paths(source) for source in plan.inputs}
    return items_graph(items, plan.folder, lambda source, paths: _item(plan, run, source, paths), resume=resume)


def run_pipeline(plan: Pipeline, *, scheduler: str | None = None, workers: int | None = None,
                 address: str | None = None, progress: bool | None = None,
                 resume: bool = False, overwrite: bool = False, summary: bool = True,
                 run: str | None = None) -> list[ItemSummary]:
    """Run a pipeline; return one :class:`~hht3d.graph.summary.ItemSummary` per input file.

    Arguments left as ``None`` take the pipeline's ``execution`` block and
    are checked like it.  The output locations are checked first, so a run
    that could not write its results computes nothing; an existing file that
    hht3d did not write is refused unless ``overwrite``.  Failed items are
    reported in the rows (see :func:`failures`), not raised.  With
    ``summary`` and the pipeline's ``outputs.summary``, the rows are also
    written to ``summary.json`` and ``summary.csv`` in the output folder (the
    CLI passes ``summary=False`` and writes them after printing the rows).

    Raises
    ------
    OutputError
        An output or the summary cannot be written, or would replace a file hht3d did not write.
    PipelineError
        A bad ``scheduler`` or ``workers``.

    Examples
    --------
    The shipped demo pipeline, with two IMFs and one output in a temporary folder:

    >>> import tempfile
    >>> from pathlib import Path
    >>> from hht3d import data_path
    >>> from hht3d.pipeline import load_pipeline, run_pipeline
    >>> out = Path(tempfile.mkdtemp())
    >>> plan = load_pipeline(data_path("demo.yaml"), overrides=[
    ...     "steps.hht.params.max_imfs=2", f"outputs.folder={out}", "outputs.files=[{path: '{stem}_hht.npz'}]"])
    >>> rows = run_pipeline(plan, scheduler="synchronous", progress=False)
    >>> [(row.status, row.imfs) for row in rows], sorted(p.name for p in out.iterdir() if not p.name.startswith("."))
    ([('ok', 2)], ['spot_hht.npz'])
    """
    given = {"scheduler": scheduler, "workers": workers, "address": address, "progress": progress}
    checked = {p.name: p.check(given[p.name], f"{p.name}={given[p.name]}") for p in EXECUTION
               if given.get(p.name) is not None}
    execution = dataclasses.replace(plan.execution, **checked)
    prepare_outputs(plan.written_paths(), plan.folder, overwrite=overwrite)
    run = run or new_run_id()
    (rows,) = compute(pipeline_graph(plan, resume=resume, run=run), scheduler=execution.scheduler,
                      workers=execution.workers, address=execution.address, progress=execution.progress)
    if summary and plan.summary:
        write_summary(rows, plan.folder, run)
    return rows


def failures(rows: list[ItemSummary]) -> list[str]:
    """One line per failed item: ``"step S failed on FILE: ERROR"``."""
    return [f"step {r.step} failed on {r.source}: {r.error}" for r in rows if r.status == "failed"]
