"""Datasets of many surfaces: one independent subgraph per file, failures isolated.

:func:`dataset_graph` builds, for every input file, the subgraph
load → signal → EMD → Riesz shift groups → spectra → export, with every task
*guarded*: an exception inside a task becomes a :class:`Failure` record that
the item's later tasks pass along, so one unreadable or degenerate file is
reported with its step and reason while the other files finish.  Outputs are
written atomically, so a failed item leaves nothing half-written.

:func:`run_dataset` computes that graph on any scheduler of
:mod:`hht3d.scheduling` and writes ``summary.json`` and ``summary.csv``.
"""
from __future__ import annotations

import csv
import io as _stdio
import json
import time
from dataclasses import asdict, dataclass
from pathlib import Path

from dask import delayed
from dask.base import tokenize

from . import graph
from .io import atomic_path, resolve_inputs
from .scheduling import compute

__all__ = ["Failure", "Guarded", "ItemSummary", "output_paths", "dataset_graph", "run_dataset", "write_summary"]

#: Output formats of a dataset item, by file suffix.
FORMATS = (".ply", ".npz")


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
            value = self.func(*args, **kwargs)
        except Exception as exc:  # a dataset item must never take the others down
            return Failure(self.step, self.source, f"{type(exc).__name__}: {exc}")
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
    """One row of the dataset summary table."""

    source: str
    status: str  # "ok", "failed" or "skipped"
    vertices: int | None = None
    imfs: int | None = None
    seconds: float | None = None
    outputs: tuple[str, ...] = ()
    step: str | None = None
    error: str | None = None


def output_paths(source: Path, out_dir: Path, formats=FORMATS, pattern: str = "{stem}_hht") -> list[Path]:
    """Where an item's results go: ``out_dir / pattern.format(stem=...) + suffix`` per format."""
    stem = pattern.format(stem=source.stem)
    return [Path(out_dir) / f"{stem}{suffix}" for suffix in formats]


def _summarize(source: str, outputs, stages: dict) -> ItemSummary:
    failure = next((v for v in stages.values() if isinstance(v, Failure)), None)
    if failure is not None:
        return ItemSummary(source, "failed", step=failure.step, error=failure.error)
    result = stages["hht"].value
    seconds = sum(v.seconds for v in stages.values())
    return ItemSummary(source, "ok", vertices=result.surface.n_vertices, imfs=result.n_imfs,
                       seconds=round(seconds, 3), outputs=tuple(str(p) for p in outputs))


def _save_all(result, paths):
    return [result.save(p) for p in paths]


def dataset_graph(inputs, out_dir, *, signal: str = "mean_curvature", formats=FORMATS,
                  pattern: str = "{stem}_hht", resume: bool = False, load_options: dict | None = None,
                  **hht_options):
    """Lazy HHT of every input file; returns a delayed list of :class:`ItemSummary`.

    Parameters
    ----------
    inputs : path, glob, folder or list of them
        Resolved by :func:`hht3d.io.resolve_inputs`.
    out_dir : path
        Where the per-item outputs go (see :func:`output_paths`).
    signal : str
        Signal name of :func:`hht3d.signals.signal`.
    formats : sequence of {".ply", ".npz"}
    resume : bool
        Skip items whose outputs all exist (writes are atomic, so an existing
        file is complete).
    load_options : dict, optional
        Passed to :func:`hht3d.io.load`.
    **hht_options
        Passed to :func:`hht3d.graph.transform` (EMD and Riesz options).
    """
    rows = []
    for source in resolve_inputs(inputs):
        paths = output_paths(source, Path(out_dir), formats, pattern)
        if resume and all(p.is_file() for p in paths):
            rows.append(ItemSummary(str(source), "skipped", outputs=tuple(map(str, paths))))
            continue
        tasks = graph.Builder(guard=lambda step, func, src=str(source): Guarded(step, func, src))
        stages = graph.transform_file(tasks, source, signal, load_options or {}, **hht_options)
        stages["export"] = tasks.task("export", _save_all)(stages["hht"], paths)
        rows.append(delayed(_summarize, pure=True, name=f"summary-{tokenize(str(source), paths)}")(
            str(source), paths, stages))
    return delayed(list, pure=True)(rows)


def write_summary(rows: list[ItemSummary], out_dir) -> list[Path]:
    """Write the summary table as ``summary.json`` and ``summary.csv`` (atomically)."""
    out_dir = Path(out_dir)
    records = [asdict(r) | {"outputs": list(r.outputs)} for r in rows]
    json_path, csv_path = out_dir / "summary.json", out_dir / "summary.csv"
    with atomic_path(json_path) as tmp:
        tmp.write_text(json.dumps(records, indent=2))
    buffer = _stdio.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=list(records[0]) if records else ["source"])
    writer.writeheader()
    for r in records:
        writer.writerow(r | {"outputs": ";".join(r["outputs"])})
    with atomic_path(csv_path) as tmp:
        tmp.write_text(buffer.getvalue())
    return [json_path, csv_path]


def run_dataset(inputs, out_dir, *, scheduler: str = "processes", workers: int | None = None,
                address: str | None = None, progress: bool = True, **options) -> list[ItemSummary]:
    """Build :func:`dataset_graph`, compute it, write the summary, return its rows."""
    (rows,) = compute(dataset_graph(inputs, out_dir, **options), scheduler=scheduler, workers=workers,
                      address=address, progress=progress)
    write_summary(rows, out_dir)
    return rows
