"""The summary table of a dataset or pipeline run: one row per input file, merged across runs.

``summary.json`` and ``summary.csv`` in the output folder: each input's
status, size, run time and decomposition quality
(:mod:`hht3d.decomposition.quality`: energy ratio, index of orthogonality,
warnings).  Concurrent runs into one local folder merge their rows under
the folder's lock (:func:`write_summary`); a URL folder has no lock, and
its summary holds the rows of the last run.  Secrets are redacted
(:func:`hht3d.redaction.redact`).
"""
from __future__ import annotations

import csv
import io as _stdio
import json
from dataclasses import asdict, dataclass, fields
from pathlib import Path

from ..decomposition.quality import decomposition_quality
from ..errors import InputError
from ..io import is_recorded, new_run_id, read_npz_shapes, read_ply_header
from ..io.manifest import folder_lock, recording
from ..io.read import _MAX_HEADER
from ..io.storage import atomic_location, file_name, is_url, join, local_copy
from ..linalg.estimate import slow_fallback
from ..redaction import redact
from ..transform import HHTResult
from .guard import Failure, Timed

__all__ = ["SUMMARY_FILES", "ItemSummary", "summary_paths", "quality_fields", "item_summary", "skipped_summary",
           "write_summary"]

#: The summary table, in the output folder.
SUMMARY_FILES = ("summary.json", "summary.csv")


@dataclass(frozen=True)
class ItemSummary:
    """One row of the dataset summary table.

    ``status`` is ``"ok"``, ``"failed"`` (``step`` and ``error`` say where
    and why; ``outputs`` lists what was written before) or ``"skipped"``
    (``--resume``: ``vertices`` and ``imfs`` are read from the existing
    outputs; ``seconds`` and the quality are empty, since nothing ran).
    ``energy_ratio``, ``orthogonality_index`` (with its ``io_leaking`` and
    ``io_cancelling`` parts) and ``warnings`` are the
    quality of the item's last decomposition (:mod:`hht3d.decomposition.quality`).
    ``solver_advice`` says which extra to install when a slow sparse solver ran on a
    large mesh (:func:`hht3d.linalg.estimate.slow_fallback`).
    """

    source: str
    status: str  # "ok", "failed" or "skipped"
    vertices: int | None = None
    imfs: int | None = None
    seconds: float | None = None
    energy_ratio: float | None = None
    orthogonality_index: float | None = None
    io_leaking: float | None = None
    io_cancelling: float | None = None
    warnings: tuple[str, ...] = ()
    outputs: tuple[str, ...] = ()
    step: str | None = None
    error: str | None = None
    solver_advice: str | None = None


def summary_paths(out_dir) -> list:
    """``summary.json`` and ``summary.csv`` in ``out_dir`` (paths, or URLs for a URL folder)."""
    return [join(out_dir, summary) for summary in SUMMARY_FILES]


def quality_fields(decomposition, surface) -> dict:
    """``energy_ratio``, ``orthogonality_index``, its two parts and ``warnings`` of an EMD or HHT result."""
    if isinstance(decomposition, HHTResult):
        quality = decomposition.quality
    else:
        imfs, residue = decomposition.imfs, decomposition.residue
        quality = decomposition_quality(surface, imfs.sum(axis=0) + residue, imfs, residue)
    return {"energy_ratio": quality.energy_ratio, "orthogonality_index": quality.orthogonality_index,
            "io_leaking": quality.io_leaking, "io_cancelling": quality.io_cancelling,
            "warnings": tuple(quality.warnings)}


def item_summary(source: str, paths, surface, decomposition, quality, parts, writes) -> ItemSummary:
    """The summary row of one item from the values of its guarded tasks.

    ``surface`` is the load task's value, ``decomposition`` that of the last
    step making IMFs (or None) and ``quality`` its :func:`quality_fields`
    task's; ``parts`` are every task of the item, ``writes`` the write task
    of each of ``paths``.
    """
    written = tuple(str(p) for p, w in zip(paths, writes) if isinstance(w, Timed))
    failure = next((v for v in [*parts, *writes] if isinstance(v, Failure)), None)
    if failure is not None:
        return ItemSummary(source, "failed", outputs=written, step=failure.step, error=failure.error)
    seconds = round(sum(v.seconds for v in [*parts, *writes]), 3)
    imfs = None if decomposition is None else decomposition.value.n_imfs
    fields = {} if quality is None else quality.value
    vertices = surface.value.n_vertices
    advice = None if decomposition is None else slow_fallback(vertices, _backend_of(decomposition.value))
    return ItemSummary(source, "ok", vertices=vertices, imfs=imfs, seconds=seconds,
                       outputs=written, solver_advice=advice, **fields)


def _backend_of(decomposition) -> str | None:
    """The sparse solver an EMD or HHT result was computed with."""
    info = decomposition.info
    return info.get("emd", info).get("backend")


def skipped_summary(source, paths, storage_options: dict | None = None) -> ItemSummary:
    """The row of an item whose outputs are done (``resume``): its size read from those outputs."""
    vertices = imfs = None
    for path in paths:
        head = _MAX_HEADER if file_name(path).lower().endswith(".ply") else None
        try:
            with local_copy(path, storage_options, head=head) as local:  # a URL: its header, or the npz
                found = _stored_size(local)
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


def write_summary(rows: list[ItemSummary], out_dir, run: str | None = None,
                  storage_options: dict | None = None) -> list:
    """Write the summary table as ``summary.json`` and ``summary.csv`` (atomically, secrets redacted).

    In a local folder, the rows already there are merged in, under the
    folder's lock: runs into one folder, even at once, keep each other's
    rows (a row of an input that ``rows`` do not cover is kept, one that
    they do is replaced), and both files are recorded in the folder's
    manifest (:mod:`hht3d.io.manifest`) under the run id ``run``.  A URL
    folder (``storage_options`` for its back-end) is written with ``rows`` only.
    In the CSV, ``outputs`` are joined with ``;`` and ``warnings`` with `` | ``.

    Raises
    ------
    OutputError
        A summary file cannot be written (names it and the reason).
    """
    records = [asdict(r) | {"outputs": list(r.outputs), "warnings": list(r.warnings)} for r in rows]
    if is_url(out_dir):
        return _write_tables(records, out_dir, storage_options)
    with folder_lock(out_dir), recording(out_dir, run or new_run_id()):
        ours = {r["source"] for r in records}
        earlier = [r for r in _earlier_rows(summary_paths(out_dir)[0], out_dir) if r.get("source") not in ours]
        return _write_tables(earlier + records, out_dir)


def _write_tables(records: list[dict], out_dir, storage_options: dict | None = None) -> list:
    """``summary.json`` and ``summary.csv`` of ``records``, each written atomically."""
    json_path, csv_path = summary_paths(out_dir)
    with atomic_location(json_path, storage_options) as tmp:
        tmp.write_text(redact(json.dumps(records, indent=2)), encoding="utf-8")
    buffer = _stdio.StringIO()
    names = [f.name for f in fields(ItemSummary)]
    writer = csv.DictWriter(buffer, fieldnames=names, extrasaction="ignore")
    writer.writeheader()
    for r in records:
        writer.writerow({k: r.get(k) for k in names} | {"outputs": ";".join(r.get("outputs") or []),
                                                        "warnings": " | ".join(r.get("warnings") or [])})
    with atomic_location(csv_path, storage_options) as tmp:
        tmp.write_text(redact(buffer.getvalue()), encoding="utf-8")
    return [json_path, csv_path]


def _earlier_rows(path: Path, folder) -> list[dict]:
    """The rows of a summary hht3d wrote earlier (none if it is missing, changed or unreadable)."""
    if not is_recorded(path, folder):
        return []
    try:
        rows = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return []
    return [r for r in rows if isinstance(r, dict)] if isinstance(rows, list) else []
