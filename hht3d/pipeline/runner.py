"""Compiling a validated :class:`~.plan.Pipeline` to a Dask graph and running it.

Every input file becomes an independent subgraph of its steps' tasks
(:mod:`hht3d.graph.stages`) and output writes.  Every task is guarded as in
:mod:`hht3d.dataset.guard`: an exception becomes a record of the step and the
input file that the item's later tasks pass along, so one bad file is
reported while the others finish.  An output is written once the step it
comes from is done, atomically: a failed item may have the outputs of its
earlier steps, which its summary row lists, never a half-written file.
Inputs are skipped on resume by the loop shared with
:func:`hht3d.dataset.run_dataset`, and outputs checked, written and
recorded through :class:`hht3d.io.folder.OutputFolder`: in a local folder,
before anything is computed, a file hht3d did not write is refused unless
``overwrite`` and temporary files of killed runs are removed, and every
output is recorded in the folder's manifest; a URL folder is probed and
written by upload.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from pathlib import Path
from typing import Any

from dask import delayed
from dask.base import tokenize

from ..dataset.guard import Guarded
from ..dataset.run import items_graph
from ..dataset.summary import ItemSummary, item_summary, quality_fields, write_summary, written_outputs
from ..execution import compute
from ..graph.stages import Builder
from ..io.folder import OutputFolder
from ..io.sealed import seal
from ..io.storage import file_name
from .plan import FILE, Pipeline
from .plugins import check_allowed
from .python_step import resolve_steps
from .validation import EXECUTION

__all__ = ["output_folder", "pipeline_graph", "run_pipeline", "failures"]


def _guarded(source: Path, label: Callable[..., str]) -> Builder:
    """A task builder whose tasks are guarded with the input file; ``label(task)`` names the step."""
    return Builder(guard=lambda task, func: Guarded(label(task), func, str(source)))


def _item(plan: Pipeline, folder: OutputFolder, source: Path, paths: list[Path]) -> Any:
    """The lazy :class:`~hht3d.dataset.summary.ItemSummary` of one input file."""
    results: dict[str, Any] = {}
    parts: dict[str, Any] = {}
    for step in plan.steps:
        builder = _guarded(source, lambda task, s=step: s.id if task in (s.op.name, s.id) else f"{s.id} ({task})")
        inputs = {slot: str(source) if ref == FILE else results[ref] for slot, ref in step.refs.items()}
        params = dict(step.params)
        if step.op.name == "load" and plan.storage_options:  # the worker reads the URL itself
            params["storage_options"] = seal(plan.storage_options)
        tasks = step.op.tasks(builder, inputs, params)
        results[step.id] = tasks["result"]
        parts.update({t.key: t for t in tasks.values()})
    writes = []
    for output, path in zip(plan.outputs, paths):
        write = _guarded(source, lambda task, label=f"write {file_name(path)}": label)
        writes.append(
            write.task("write", folder.writer(output.format.write))(
                results[output.step], results[plan.origin_of(output.step)], str(path), **output.options
            )
        )
    surface = results[next(s.id for s in plan.steps if s.op.name == "load")]
    last = next((s.id for s in reversed(plan.steps) if s.kind in ("emd", "hht")), None)
    decomposition = quality = None
    if last is not None:
        decomposition = results[last]
        quality = _guarded(source, lambda task: f"{last} (quality)").task("quality", quality_fields)(
            decomposition, results[plan.surface_of(last)]
        )
        parts[quality.key] = quality
    name = f"pipeline-item-{tokenize(plan.name, str(source), [str(p) for p in paths])}"
    return delayed(item_summary, pure=True, name=name)(
        str(source), [str(p) for p in paths], surface, decomposition, quality, list(parts.values()), writes
    )


def output_folder(plan: Pipeline, run: str | None = None) -> OutputFolder:
    """The pipeline's output folder (local or URL), writing under the run id ``run`` (default: a new one)."""
    return OutputFolder(plan.folder, storage_options=plan.storage_options, run=run, allow_outside=plan.allow_outside)


def pipeline_graph(plan: Pipeline, *, resume: bool = False, folder: OutputFolder | None = None) -> Any:
    """The pipeline as one lazy list of :class:`~hht3d.dataset.summary.ItemSummary`, one per input file.

    Parameters
    ----------
    plan : Pipeline
    resume : bool
        Skip inputs whose outputs are done (status ``"skipped"``, sizes read
        from those outputs): recorded complete, with the same size and
        checksum, in the folder's manifest (a URL folder's manifest object).
    folder : OutputFolder, optional
        Where the outputs go (default: :func:`output_folder` with a new run id).

    Returns
    -------
    Delayed
        Computes to the list of :class:`~hht3d.dataset.summary.ItemSummary`.
    """
    folder = folder or output_folder(plan)
    items = {source: plan.output_paths(source) for source in plan.inputs}
    return items_graph(items, folder, lambda source, paths: _item(plan, folder, source, paths), resume=resume)


def run_pipeline(
    plan: Pipeline,
    *,
    scheduler: str | None = None,
    workers: int | None = None,
    address: str | None = None,
    progress: bool | None = None,
    resume: bool = False,
    overwrite: bool = False,
    summary: bool = True,
    run: str | None = None,
    allow_plugins: bool | None = None,
) -> list[ItemSummary]:
    """Run a pipeline; return one :class:`~hht3d.dataset.summary.ItemSummary` per input file.

    Arguments left as ``None`` take the pipeline's ``execution`` block and
    are checked like it.  The output locations are checked first, so a run
    that could not write its results computes nothing; in a local folder,
    an existing file that hht3d did not write is refused unless
    ``overwrite``.  ``run`` is the run id of the manifest (default: a new one).  A step whose
    operation comes from a plugin, and a ``python`` step, run only with ``allow_plugins`` (default: the
    user's ``HHT3D_ALLOW_PLUGINS=1``; :func:`~hht3d.pipeline.plugins.check_allowed`); a ``python``
    step's function is imported then, before anything is computed.  Failed items are
    reported in the rows (see :func:`failures`), not raised.  With
    ``summary`` and the pipeline's ``outputs.summary``, the rows are also
    written to ``summary.json`` and ``summary.csv`` in the output folder (the
    CLI passes ``summary=False`` and writes them after printing the rows).

    Parameters
    ----------
    plan : Pipeline
        The validated pipeline (:func:`load_pipeline`).
    scheduler : str, optional
        A name of :data:`hht3d.execution.SCHEDULERS`.
    workers : int, optional
        Worker count of the scheduler.
    address : str, optional
        The address of a running Dask scheduler.
    progress : bool, optional
        Show a progress bar.
    resume : bool, optional
        Skip the items whose outputs are complete (default ``False``).
    overwrite : bool, optional
        Replace existing files hht3d did not write (default ``False``).
    summary : bool, optional
        Write the summary files, if the pipeline asks for them (default ``True``).
    run : str, optional
        The run id of the manifest (default: a new one).

    Returns
    -------
    list of ItemSummary
        One row per input file.

    Raises
    ------
    OutputError
        An output or the summary cannot be written, would replace a file hht3d did not write, or
        another run held a URL folder's lock for the whole timeout.
    PipelineError
        A bad ``scheduler`` or ``workers``, a plugin's operation or a ``python`` step not allowed,
        or a ``python`` step's function that does not import.

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
    check_allowed(plan.steps, allow_plugins)
    resolve_steps(plan.steps)
    given = {"scheduler": scheduler, "workers": workers, "address": address, "progress": progress}
    checked = {
        p.name: p.check(given[p.name], f"{p.name}={given[p.name]}") for p in EXECUTION if given.get(p.name) is not None
    }
    execution = dataclasses.replace(plan.execution, **checked)
    folder = output_folder(plan, run)
    with folder.lock():
        folder.prepare(plan.written_paths(), overwrite=overwrite)
        (rows,) = compute(
            pipeline_graph(plan, resume=resume, folder=folder),
            scheduler=execution.scheduler,
            workers=execution.workers,
            address=execution.address,
            progress=execution.progress,
        )
        folder.finish(plan.written_paths(), written_outputs(rows))
        if summary and plan.summary:
            write_summary(rows, plan.folder, folder.run, plan.storage_options)
    return rows


def failures(rows: list[ItemSummary]) -> list[str]:
    """One line per failed item: ``"step S failed on FILE: ERROR"``.

    Parameters
    ----------
    rows : list of ItemSummary
        The rows of a run.

    Returns
    -------
    list of str
        One line per failed row, in order.
    """
    return [f"step {r.step} failed on {r.source}: {r.error}" for r in rows if r.status == "failed"]
