"""Datasets of many surfaces: one independent subgraph per file, failures isolated.

:func:`dataset_graph` builds, for every input file, the subgraph
load → signal → EMD → Riesz shift groups → spectra → export, with every task
*guarded*: an exception inside a task becomes a :class:`Failure` record that
the item's later tasks pass along, so one unreadable or degenerate file is
reported with its step and reason while the other files finish.  Outputs are
written atomically, one task each, so a failed item leaves nothing
half-written, and its summary row lists the outputs it did write.  Output
locations are checked before anything is computed.

:func:`run_dataset` computes that graph on any scheduler of
:mod:`hht3d.graph.scheduling` and writes ``summary.json`` and ``summary.csv``: one
row per file with its status, size, run time and decomposition quality
(:mod:`hht3d.decomposition.quality`: energy ratio, index of orthogonality, warnings).
"""
from __future__ import annotations

import csv
import io as _stdio
import json
import time
import warnings
from dataclasses import asdict, dataclass, fields
from pathlib import Path

from dask import delayed
from dask.base import tokenize

from . import stages as graph
from ..errors import InputError, one_line
from ..transform import HHTResult
from ..io.read import atomic_path, check_output_paths, read_npz_shapes, read_ply_header, resolve_inputs
from ..decomposition.quality import QualityWarning, decomposition_quality
from .scheduling import compute

__all__ = ["Failure", "Guarded", "ItemSummary", "output_paths", "dataset_graph", "run_dataset", "write_summary",
           "summary_paths", "item_summary", "skipped_summary", "quality_fields", "SUMMARY_FILES"]

#: Output formats of a dataset item, by file suffix.
FORMATS = (".ply", ".npz")
#: The summary table, in the output folder.
SUMMARY_FILES = ("summary.json", "summary.csv")
#: Characters of an exception's message kept in a summary row.
MAX_ERROR = 500


@dataclass(frozen=True)
class Failure:
    """Why a dataset item failed: the step, the input file and the error."""

    step: str
    source: str
    error: str


@dataclass(frozen=True)
class _Timed:
    """A guarded task's value and its own run time."""

    value: object
    seconds: float


class Guarded:
    """Run ``func`` unless an input already failed; turn an exception into a :class:`Failure`."""

    def __init__(self, step: str, func, source: str):
        self.step, self.func, self.source = step, func, source
        self.__name__ = f"{step}"

    def __dask_tokenize__(self):
        return (self.step, self.func.__module__, self.func.__qualname__, self.source)

    def __call__(self, *args, **kwargs):
        args = [_unwrap(a) for a in args]
        kwargs = {k: _unwrap(v) for k, v in kwargs.items()}
        failed = next((a for a in _flat(args, kwargs) if isinstance(a, Failure)), None)
        if failed is not None:
            return failed
        start = time.perf_counter()
        try:
            with warnings.catch_warnings():  # the summary row reports the quality figures instead
                warnings.simplefilter("ignore", QualityWarning)
                value = self.func(*args, **kwargs)
        except Exception as exc:  # a dataset item must never take the others down
            return Failure(self.step, self.source, one_line(f"{type(exc).__name__}: {exc}", MAX_ERROR))
        return _Timed(value, time.perf_counter() - start)


def _unwrap(value):
    if isinstance(value, _Timed):
        return value.value
    if isinstance(value, (list, tuple)):
        return type(value)(_unwrap(v) for v in value)
    return value


def _flat(args, kwargs):
    for value in [*args, *kwargs.values()]:
        yield from (value if isinstance(value, (list, tuple)) else [value])


@dataclass(frozen=True)
class ItemSummary:
    """One row of the dataset summary table.

    ``status`` is ``"ok"``, ``"failed"`` (``step`` and ``error`` say where
    and why; ``outputs`` lists what was written before) or ``"skipped"``
    (``--resume``: ``vertices`` and ``imfs`` are read from the existing
    outputs; ``seconds`` and the quality are empty, since nothing ran).
    ``energy_ratio``, ``orthogonality_index`` and ``warnings`` are the
    quality of the item's last decomposition (:mod:`hht3d.decomposition.quality`).
    """

    source: str
    status: str  # "ok", "failed" or "skipped"
    vertices: int | None = None
    imfs: int | None = None
    seconds: float | None = None
    energy_ratio: float | None = None
    orthogonality_index: float | None = None
    warnings: tuple[str, ...] = ()
    outputs: tuple[str, ...] = ()
    step: str | None = None
    error: str | None = None


def output_paths(source: Path, out_dir: Path, formats=FORMATS, pattern: str = "{stem}_hht") -> list[Path]:
    """Where an item's results go: ``out_dir / pattern.format(stem=...) + suffix`` per format."""
    stem = pattern.format(stem=source.stem)
    return [Path(out_dir) / f"{stem}{suffix}" for suffix in formats]


def summary_paths(out_dir) -> list[Path]:
    """``summary.json`` and ``summary.csv`` in ``out_dir``."""
    return [Path(out_dir) / name for name in SUMMARY_FILES]


def quality_fields(decomposition, surface) -> dict:
    """``energy_ratio``, ``orthogonality_index`` and ``warnings`` of an EMD or HHT result on ``surface``."""
    if isinstance(decomposition, HHTResult):
        quality = decomposition.quality
    else:
        imfs, residue = decomposition.imfs, decomposition.residue
        quality = decomposition_quality(surface, imfs.sum(axis=0) + residue, imfs, residue)
    return {"energy_ratio": quality.energy_ratio, "orthogonality_index": quality.orthogonality_index,
            "warnings": tuple(quality.warnings)}


def item_summary(source: str, paths, surface, decomposition, quality, parts, writes) -> ItemSummary:
    """The summary row of one item from the values of its guarded tasks.

    ``surface`` is the load task's value, ``decomposition`` that of the last
    step making IMFs (or None) and ``quality`` its :func:`quality_fields`
    task's; ``parts`` are every task of the item, ``writes`` the write task
    of each of ``paths``.
    """
    written = tuple(str(p) for p, w in zip(paths, writes) if isinstance(w, _Timed))
    failure = next((v for v in [*parts, *writes] if isinstance(v, Failure)), None)
    if failure is not None:
        return ItemSummary(source, "failed", outputs=written, step=failure.step, error=failure.error)
    seconds = round(sum(v.seconds for v in [*parts, *writes]), 3)
    imfs = None if decomposition is None else decomposition.value.n_imfs
    fields = {} if quality is None else quality.value
    return ItemSummary(source, "ok", vertices=surface.value.n_vertices, imfs=imfs, seconds=seconds,
                       outputs=written, **fields)


def skipped_summary(source, paths) -> ItemSummary:
    """The row of an item whose outputs all exist (``resume``): its size read from those outputs."""
    vertices = imfs = None
    for path in map(Path, paths):
        try:
            found = _stored_size(path)
        except InputError:
            continue
        vertices = vertices if vertices is not None else found[0]
        imfs = imfs if imfs is not None else found[1]
    return ItemSummary(str(source), "skipped", vertices=vertices, imfs=imfs, outputs=tuple(map(str, paths)))


def _stored_size(path: Path) -> tuple[int | None, int | None]:
    """Vertices and IMFs of a written result, from its PLY or npz headers (None where it does not say)."""
    suffix = path.suffix.lower()
    if suffix == ".npz":
        shapes = read_npz_shapes(path)
        if "imfs" in shapes:
            return shapes["imfs"][1], shapes["imfs"][0]
        return next((shape[0] for shape in shapes.values() if len(shape) == 1), None), None
    if suffix == ".ply":
        header = read_ply_header(path)
        names = set(header.vertex_properties)
        decomposed = "residue" in names and ("signal" in names or "imf_1" in names)
        imfs = sum(1 for name in names if name.startswith("imf_")) if decomposed else None
        return header.counts.get("vertex"), imfs
    return None, None


def _save(result, path):
    return result.save(path)


def dataset_graph(inputs, out_dir, *, signal: str = "mean_curvature", formats=FORMATS,
                  pattern: str = "{stem}_hht", resume: bool = False, load_options: dict | None = None,
                  **hht_options):
    """Lazy HHT of every input file; returns a delayed list of :class:`ItemSummary`.

    Parameters
    ----------
    inputs : path, glob, folder or list of them
        Resolved by :func:`hht3d.io.read.read.resolve_inputs`.
    out_dir : path
        Where the per-item outputs go (see :func:`output_paths`).
    signal : str
        Signal name of :func:`hht3d.geometry.signals.signal`.
    formats : sequence of {".ply", ".npz"}
    resume : bool
        Skip items whose outputs all exist (writes are atomic, so an existing
        file is complete).
    load_options : dict, optional
        Passed to :func:`hht3d.io.read.read.load`.
    **hht_options
        Passed to :func:`hht3d.graph.stages.transform` (EMD and Riesz options).

    Raises
    ------
    OutputError
        An output cannot be written there (checked before any task is made).
    """
    sources = resolve_inputs(inputs)
    items = {source: output_paths(source, Path(out_dir), formats, pattern) for source in sources}
    check_output_paths([p for paths in items.values() for p in paths] + summary_paths(out_dir))
    rows = []
    for source, paths in items.items():
        if resume and all(p.is_file() for p in paths):
            rows.append(skipped_summary(source, paths))
            continue
        tasks = graph.Builder(guard=lambda step, func, src=str(source): Guarded(step, func, src))
        stages = graph.transform_file(tasks, source, signal, load_options or {}, **hht_options)
        quality = tasks.task("quality", quality_fields)(stages["hht"], stages["load"])
        writes = [tasks.task(f"write {p.name}", _save)(stages["hht"], str(p)) for p in paths]
        rows.append(delayed(item_summary, pure=True, name=f"summary-{tokenize(str(source), paths)}")(
            str(source), paths, stages["load"], stages["hht"], quality, [*stages.values(), quality], writes))
    return delayed(list, pure=True)(rows)


def write_summary(rows: list[ItemSummary], out_dir) -> list[Path]:
    """Write the summary table as ``summary.json`` and ``summary.csv`` (atomically).

    In the CSV, ``outputs`` are joined with ``;`` and ``warnings`` with `` | ``.

    Raises
    ------
    OutputError
        A summary file cannot be written (names it and the reason).
    """
    json_path, csv_path = summary_paths(out_dir)
    records = [asdict(r) | {"outputs": list(r.outputs), "warnings": list(r.warnings)} for r in rows]
    with atomic_path(json_path) as tmp:
        tmp.write_text(json.dumps(records, indent=2), encoding="utf-8")
    buffer = _stdio.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=[f.name for f in fields(ItemSummary)])
    writer.writeheader()
    for r in records:
        writer.writerow(r | {"outputs": ";".join(r["outputs"]), "warnings": " | ".join(r["warnings"])})
    with atomic_path(csv_path) as tmp:
        tmp.write_text(buffer.getvalue(), encoding="utf-8")
    return [json_path, csv_path]


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
        ``load_options``) and the HHT options of :func:`hht3d.graph.stages.transform`.

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
    >>> sorted(path.name for path in out.iterdir())
    ['spot_hht.npz', 'spot_hht.ply', 'summary.csv', 'summary.json']
    """
    (rows,) = compute(dataset_graph(inputs, out_dir, **options), scheduler=scheduler, workers=workers,
                      address=address, progress=progress)
    write_summary(rows, out_dir)
    return rows
