"""Datasets of many surfaces: one independent subgraph per file, failures isolated, outputs safe.

:func:`dataset_graph` builds, for every input file, the subgraph
load → signal → EMD → Riesz shift groups → spectra → export, every task
*guarded* (:mod:`hht3d.dataset.guard`): one unreadable or degenerate file is
reported with its step and reason while the other files finish.  Outputs are
written atomically, one task each, and recorded in the output folder's
manifest (:mod:`hht3d.io.manifest`) once complete.

:func:`items_graph` is shared with the pipeline runner
(:mod:`hht3d.pipeline.runner`): the one loop that skips finished inputs on
resume.  What "finished", "writable" and "written" mean for a local folder
or an fsspec URL is decided in one place, :class:`hht3d.io.folder.OutputFolder`.

:func:`run_dataset` computes the graph on any scheduler of
:mod:`hht3d.execution` and writes ``summary.json`` and ``summary.csv``
(:mod:`hht3d.dataset.summary`).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import Any

import dask
from dask import delayed
from dask.base import tokenize

from ..errors import InputError, shown
from ..execution import compute
from ..geometry.signals import SIGNALS
from ..graph import stages as graph
from ..io import read_ply_header
from ..io.folder import OutputFolder, check_locations
from ..io.manifest import new_run_id
from ..io.sealed import seal
from ..io.storage import file_name, input_size, is_url, join, local_path, resolve_locations, stem
from ..output_formats import plain_formats
from ..transform import HHTResult
from .guard import MAX_ERROR, Failure, Guarded
from .summary import (
    SUMMARY_FILES,
    ItemSummary,
    item_summary,
    quality_fields,
    skipped_summary,
    summary_paths,
    write_summary,
    written_outputs,
)

__all__ = [
    "Failure",
    "Guarded",
    "ItemSummary",
    "output_paths",
    "dataset_graph",
    "run_dataset",
    "write_summary",
    "summary_paths",
    "item_summary",
    "skipped_summary",
    "quality_fields",
    "SUMMARY_FILES",
    "MAX_ERROR",
    "RESULT_SUFFIXES",
    "items_graph",
]

#: The files a dataset item's result is saved as by default: PLY and NPZ.  ``formats=`` may name any
#: format of an HHT result that takes no options (:func:`hht3d.output_formats.plain_formats`, written
#: by :meth:`HHTResult.save`: also ``.vtu``, ``.vtp``).
RESULT_SUFFIXES = (".ply", ".npz")


def output_paths(
    source: Path | str, out_dir: Path | str, formats: Iterable[str] = RESULT_SUFFIXES, pattern: str = "{stem}_hht"
) -> list:
    """Where an item's results go: ``out_dir / pattern.format(stem=...) + suffix`` per format (paths or URLs).

    Parameters
    ----------
    source : Path or str
        The input file (or URL) whose stem names the outputs.
    out_dir : Path or str
        The output folder (a path or a URL).
    formats : iterable of str, optional
        The suffixes to write (default ``(".ply", ".npz")``).
    pattern : str, optional
        The file name without suffix; ``{stem}`` is its only field (default ``"{stem}_hht"``).

    Returns
    -------
    list
        One path (or URL string) per format, in order.

    Examples
    --------
    >>> from hht3d.dataset import output_paths
    >>> [str(p) for p in output_paths("scans/bunny.ply", "out")]
    ['out/bunny_hht.ply', 'out/bunny_hht.npz']
    >>> output_paths("s3://lab/scans/bunny.ply", "s3://lab/out", formats=[".npz"], pattern="{stem}_v2")
    ['s3://lab/out/bunny_v2.npz']
    """
    try:
        base = str(pattern).format(stem=stem(source))
    except (IndexError, KeyError, ValueError, AttributeError):  # "{0}", "{name}", "{", "{stem.x}"
        raise InputError(
            f"output pattern {shown(pattern)}: the only field is {{stem}}, the input's file name "
            "without its suffix (write {{ and }} for literal braces)"
        ) from None
    return [join(out_dir, f"{base}{suffix}") for suffix in formats]


def items_graph(items: dict, folder: OutputFolder, make_item: Callable[..., Any], *, resume: bool = False) -> Any:
    """One lazy :class:`ItemSummary` per input, in a delayed list: the one resume loop.

    ``items`` maps each input to its output paths; ``make_item(source, paths)``
    builds an input's lazy row.  With ``resume``, an input that ``folder``
    finds done (:meth:`~hht3d.io.folder.OutputFolder.done`: locally, outputs the
    manifest records as complete with the same size and checksum; for a URL,
    likewise in its manifest object) is a ``"skipped"`` row instead.

    The more work an input holds (:func:`_expected_work`), the higher its tasks' ``priority``
    (honoured by ``dask.distributed``): the longest chain starts first, and the small items fill
    the other workers meanwhile, instead of the largest starting last while the others idle.
    """
    work = _expected_work(items, folder.storage_options)
    rank = {source: index for index, source in enumerate(sorted(items, key=work.__getitem__))}
    rows = []
    for source, paths in items.items():
        if resume and folder.done(paths):
            rows.append(skipped_summary(source, paths, folder.storage_options))
        else:
            with dask.annotate(priority=rank[source]):
                rows.append(make_item(source, paths))
    return delayed(list, pure=True)(rows)


def _expected_work(sources: Iterable[Any], storage_options: dict | None = None) -> dict:
    """Each input's expected work, in one unit for all: the vertices its header declares when every input
    is a local PLY file with a readable header, else its bytes.

    Bytes per vertex differ threefold between a bare point cloud and a coloured one, so bytes alone ranked
    the 40,256-point bunny scan (0.48 MB, 14.8 s) below a 34,834-vertex mesh (1.3 MB, 7.3 s), and it ran
    last on 2 workers (``bench_graph``)."""
    vertices = {}
    for source in sources:
        path = local_path(source)
        if is_url(path) or Path(path).suffix.lower() != ".ply":
            break
        try:
            vertices[source] = read_ply_header(path).counts.get("vertex", 0)
        except InputError:  # unreadable: its load reports it
            break
    else:
        return vertices
    return {source: input_size(source, storage_options) for source in sources}


def _check_options(signal: str, formats: Iterable[str]) -> None:
    """An invalid option is the caller's error, found before any task is made."""
    if signal not in SIGNALS:
        raise InputError(f"unknown signal {signal!r}; run_dataset takes one of {sorted(SIGNALS)}")
    written = plain_formats("hht")
    for suffix in formats:
        if suffix not in written:
            raise InputError(f"unknown output format {suffix!r}; run_dataset writes {', '.join(written)}")


def dataset_graph(
    inputs: Any,
    out_dir: Path | str,
    *,
    signal: str = "mean_curvature",
    formats: Iterable[str] = RESULT_SUFFIXES,
    pattern: str = "{stem}_hht",
    resume: bool = False,
    overwrite: bool = False,
    load_options: dict | None = None,
    run: str | None = None,
    storage_options: dict | None = None,
    **hht_options: Any,
) -> Any:
    """Lazy HHT of every input file; returns a delayed list of :class:`ItemSummary`.

    Parameters
    ----------
    inputs : path, glob, folder or list of them
        Local or fsspec URLs (``s3://bucket/scans/*.ply``), resolved by
        :func:`hht3d.io.storage.resolve_locations` (local files hht3d wrote are never inputs).
    out_dir : path or URL
        Where the per-item outputs go (see :func:`output_paths`); a local
        folder or a ``file://`` URL with every local rule, another URL with
        those its store allows (:mod:`hht3d.io.folder`).
    signal : str
        One of :data:`hht3d.geometry.signals.SIGNALS`.
    formats : sequence of {".ply", ".npz"}
    resume : bool
        Skip items whose outputs are done: recorded complete, with the same size
        and checksum, in the folder's manifest (a URL folder's manifest object).
    overwrite : bool
        Replace existing files hht3d did not write (refused otherwise; local folders).
    load_options : dict, optional
        Passed to :func:`hht3d.io.load`.
    run : str, optional
        The run id recorded in the manifest (default: a new one).
    storage_options : dict, optional
        Options of the fsspec back-end of URL inputs and outputs; the workers
        receive them with the URLs and read and write the files themselves.
    **hht_options
        Passed to :func:`hht3d.graph.stages.transform`: the HHT's settings by name
        (``max_imfs=4``, ``potential="spectral"``, ...) and ``riesz_tasks``
        (:class:`hht3d.graph.tasks.GraphOptions`).

    Returns
    -------
    Delayed
        Computes to the list of :class:`ItemSummary`, one per input file.

    Raises
    ------
    InputError
        An unknown ``signal`` or format, or bad inputs.
    OutputError
        An output cannot be written there, is an input, or would replace a
        file hht3d did not write (checked before any task is made).
    """
    _check_options(signal, formats)
    out_dir = local_path(out_dir)
    sources = resolve_locations(inputs, storage_options)
    items = {source: output_paths(source, out_dir, formats, pattern) for source in sources}
    check_locations(items, out_dir)
    folder = OutputFolder(out_dir, storage_options=storage_options, run=run)
    folder.prepare([p for paths in items.values() for p in paths] + summary_paths(out_dir), overwrite=overwrite)
    save = folder.writer(HHTResult.save)
    load_options = {**(load_options or {}), **({"storage_options": seal(storage_options)} if storage_options else {})}

    def item(source: Path | str, paths: Sequence[Path | str]) -> Any:
        tasks = graph.Builder(guard=lambda step, func, src=str(source): Guarded(step, func, src))
        stages = graph.transform_file(tasks, source, signal, load_options, **hht_options)
        quality = tasks.task("quality", quality_fields)(stages["hht"], stages["load"])
        writes = [tasks.task(f"write {file_name(p)}", save)(stages["hht"], str(p)) for p in paths]
        return delayed(item_summary, pure=True, name=f"summary-{tokenize(str(source), paths)}")(
            str(source), paths, stages["load"], stages["hht"], quality, [*stages.values(), quality], writes
        )

    return items_graph(items, folder, item, resume=resume)


def run_dataset(
    inputs: Any,
    out_dir: Path | str,
    *,
    scheduler: str = "processes",
    workers: int | None = None,
    address: str | None = None,
    progress: bool = True,
    **options: Any,
) -> list[ItemSummary]:
    """Build :func:`dataset_graph`, compute it, write the summary, return its rows; a URL folder's lock
    is held meanwhile (:meth:`hht3d.io.folder.OutputFolder.lock`).

    Parameters
    ----------
    inputs, out_dir
        As for :func:`dataset_graph`: paths or fsspec URLs.
    scheduler, workers, address, progress
        As for :func:`hht3d.execution.schedulers.compute`.
    **options
        Those of :func:`dataset_graph` (``signal``, ``formats``, ``resume``,
        ``overwrite``, ``load_options``, ``storage_options``) and the HHT options of
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
    >>> from hht3d.dataset import run_dataset
    >>> out = Path(tempfile.mkdtemp())
    >>> rows = run_dataset([data_path("spot.ply")], out, scheduler="synchronous", progress=False,
    ...                    max_imfs=2)
    >>> [(row.status, row.vertices, row.imfs) for row in rows]
    [('ok', 2930, 2)]
    >>> sorted(path.name for path in out.iterdir() if not path.name.startswith("."))
    ['spot_hht.npz', 'spot_hht.ply', 'summary.csv', 'summary.json']
    """
    run, out_dir = options.pop("run", None) or new_run_id(), local_path(out_dir)
    folder = OutputFolder(out_dir, storage_options=options.get("storage_options"), run=run)
    with folder.lock():
        (rows,) = compute(
            dataset_graph(inputs, out_dir, run=run, **options),
            scheduler=scheduler,
            workers=workers,
            address=address,
            progress=progress,
        )
        folder.finish([], written_outputs(rows))
        write_summary(rows, out_dir, run, options.get("storage_options"))
    return rows
