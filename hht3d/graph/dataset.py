"""Datasets of many surfaces: one independent subgraph per file, failures isolated, outputs safe.

:func:`dataset_graph` builds, for every input file, the subgraph
load → signal → EMD → Riesz shift groups → spectra → export, every task
*guarded* (:mod:`hht3d.graph.guard`): one unreadable or degenerate file is
reported with its step and reason while the other files finish.  Outputs are
written atomically, one task each, and recorded in the output folder's
manifest (:mod:`hht3d.io.manifest`) once complete.

:func:`items_graph` and :func:`prepare_outputs` are shared with the
pipeline runner (:mod:`hht3d.pipeline.runner`): the one loop that skips
finished inputs on resume, and the checks made before anything is computed
(outputs writable, no file hht3d did not write replaced, stale temporary
files of earlier runs removed).

:func:`run_dataset` computes the graph on any scheduler of
:mod:`hht3d.graph.scheduling` and writes ``summary.json`` and ``summary.csv``
(:mod:`hht3d.graph.summary`).
"""
from __future__ import annotations

import os
from pathlib import Path

from dask import delayed
from dask.base import tokenize

from . import stages as graph
from ..errors import InputError, OutputError
from ..geometry.signals import SIGNALS
from ..io import (check_name, check_output_location, check_output_paths, check_overwrites, is_recorded, new_run_id,
                  remove_stale_parts, resolve_inputs)
from ..io.manifest import Recorded, entries
from ..transform import HHTResult
from .guard import MAX_ERROR, Failure, Guarded
from .scheduling import compute
from .summary import (SUMMARY_FILES, ItemSummary, item_summary, quality_fields, skipped_summary, summary_paths,
                      write_summary)

__all__ = ["Failure", "Guarded", "ItemSummary", "output_paths", "dataset_graph", "run_dataset", "write_summary",
           "summary_paths", "item_summary", "skipped_summary", "quality_fields", "SUMMARY_FILES", "MAX_ERROR",
           "FORMATS", "items_graph", "prepare_outputs", "check_outputs"]

#: Output formats of a dataset item, by file suffix.
FORMATS = (".ply", ".npz")


def output_paths(source: Path, out_dir: Path, formats=FORMATS, pattern: str = "{stem}_hht") -> list[Path]:
    """Where an item's results go: ``out_dir / pattern.format(stem=...) + suffix`` per format."""
    stem = pattern.format(stem=source.stem)
    return [Path(out_dir) / f"{stem}{suffix}" for suffix in formats]


def check_outputs(items: dict, folder, *, allow_outside: bool = False, where=lambda source, path: str(path)) -> None:
    """Refuse, before anything is computed, outputs that no file system takes, that resolve outside
    ``folder`` (unless ``allow_outside``), or that are one of the inputs.

    ``items`` maps each input file to its output paths; ``where(source, path)``
    names an output in messages.

    Raises
    ------
    OutputError
    """
    inputs = {os.path.realpath(source): source for source in items}
    for source, paths in items.items():
        for path in paths:
            check_name(path, where(source, path))
            if not allow_outside:
                check_output_location(path, folder, where(source, path))
            clash = inputs.get(os.path.realpath(path))
            if clash is not None:
                raise OutputError(f"{where(source, path)}: {path} is the input {clash}; an input is never an "
                                  "output: change the output path or folder")


def prepare_outputs(paths, folder, *, overwrite: bool = False) -> None:
    """Before a run: the outputs can be written, none replaces a file hht3d did not write (unless
    ``overwrite``), and temporary files that killed runs left in their folders are removed."""
    check_output_paths(paths)
    check_overwrites(paths, folder, overwrite)
    remove_stale_parts({Path(folder), *(Path(p).parent for p in paths)})


def items_graph(items: dict, folder, make_item, *, resume: bool = False):
    """One lazy :class:`ItemSummary` per input, in a delayed list: the one resume loop.

    ``items`` maps each input to its output paths; ``make_item(source, paths)``
    builds an input's lazy row.  With ``resume``, an input whose outputs the
    folder's manifest records as complete (same size and checksum) is a
    ``"skipped"`` row instead; a missing, empty or changed output is redone.
    """
    known = entries(folder) if resume else {}
    rows = []
    for source, paths in items.items():
        if resume and all(is_recorded(p, folder, known) for p in paths):
            rows.append(skipped_summary(source, paths))
        else:
            rows.append(make_item(source, paths))
    return delayed(list, pure=True)(rows)


def _check_options(signal: str, formats) -> None:
    """An invalid option is the caller's error, found before any task is made."""
    if signal not in SIGNALS:
        raise InputError(f"unknown signal {signal!r}; run_dataset takes one of {sorted(SIGNALS)}")
    for suffix in formats:
        if suffix not in FORMATS:
            raise InputError(f"unknown output format {suffix!r}; run_dataset writes {', '.join(FORMATS)}")


def dataset_graph(inputs, out_dir, *, signal: str = "mean_curvature", formats=FORMATS,
                  pattern: str = "{stem}_hht", resume: bool = False, overwrite: bool = False,
                  load_options: dict | None = None, run: str | None = None, **hht_options):
    """Lazy HHT of every input file; returns a delayed list of :class:`ItemSummary`.

    Parameters
    ----------
    inputs : path, glob, folder or list of them
        Resolved by :func:`hht3d.io.resolve_inputs` (files hht3d wrote are never inputs).
    out_dir : path
        Where the per-item outputs go (see :func:`output_paths`).
    signal : str
        One of :data:`hht3d.geometry.signals.SIGNALS`.
    formats : sequence of {".ply", ".npz"}
    resume : bool
        Skip items whose outputs the folder's manifest records as complete.
    overwrite : bool
        Replace existing files hht3d did not write (refused otherwise).
    load_options : dict, optional
        Passed to :func:`hht3d.io.load`.
    run : str, optional
        The run id recorded in the manifest (default: a new one).
    **hht_options
        Passed to :func:`hht3d.graph.stages.transform` (EMD and Riesz options).

    Raises
    ------
    InputError
        An unknown ``signal`` or format, or bad inputs.
    OutputError
        An output cannot be written there, is an input, or would replace a
        file hht3d did not write (checked before any task is made).
    """
    _check_options(signal, formats)
    sources = resolve_inputs(inputs)
    items = {source: output_paths(source, Path(out_dir), formats, pattern) for source in sources}
    check_outputs(items, out_dir)
    prepare_outputs([p for paths in items.values() for p in paths] + summary_paths(out_dir), out_dir,
                    overwrite=overwrite)
    save = Recorded(HHTResult.save, out_dir, run or new_run_id())

    def item(source, paths):
        tasks = graph.Builder(guard=lambda step, func, src=str(source): Guarded(step, func, src))
        stages = graph.transform_file(tasks, source, signal, load_options or {}, **hht_options)
        quality = tasks.task("quality", quality_fields)(stages["hht"], stages["load"])
        writes = [tasks.task(f"write {p.name}", save)(stages["hht"], str(p)) for p in paths]
        return delayed(item_summary, pure=True, name=f"summary-{tokenize(str(source), paths)}")(
            str(source), paths, stages["load"], stages["hht"], quality, [*stages.values(), quality], writes)

    return items_graph(items, out_dir, item, resume=resume)


def run_dataset(inputs, out_dir, *, scheduler: str = "processes", workers: int | None = None,
                address: str | None = None, progress: bool = True, **options) -> list[ItemSummary]:
    """Build :func:`dataset_graph`, compute it, write the summary, return its rows.

    Parameters
    ----------
    inputs, out_dir
        As for :func:`dataset_graph`.
    scheduler, workers, address, progress
        As for :func:`hht3d.graph.scheduling.compute`.
    **options
        Those of :func:`dataset_graph` (``signal``, ``formats``, ``resume``,
        ``overwrite``, ``load_options``) and the HHT options of
        :func:`hht3d.graph.stages.transform`.

    Returns
    -------
    list of ItemSummary
        One per input file; a failed file is a row with ``status="failed"``.

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> from hht3d import data_path
    >>> from hht3d.graph.dataset import run_dataset
    >>> out = Path(tempfile.mkdtemp())
    >>> rows = run_dataset([data_path("spot.ply")], out, scheduler="synchronous", progress=False,
    ...                    emd_options={"max_imfs": 2})
    >>> [(row.status, row.vertices, row.imfs) for row in rows]
    [('ok', 2930, 2)]
    >>> sorted(path.name for path in out.iterdir() if not path.name.startswith("."))
    ['spot_hht.npz', 'spot_hht.ply', 'summary.csv', 'summary.json']
    """
    run = options.pop("run", None) or new_run_id()
    (rows,) = compute(dataset_graph(inputs, out_dir, run=run, **options), scheduler=scheduler, workers=workers,
                      address=address, progress=progress)
    write_summary(rows, out_dir, run)
    return rows
