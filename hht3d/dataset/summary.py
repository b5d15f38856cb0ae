"""The summary table of a dataset or pipeline run: one row per input file, merged across runs.

``summary.json`` and ``summary.csv`` in the output folder: each input's
status, size, run time and decomposition quality
(:mod:`hht3d.decomposition.quality`: energy ratio, index of orthogonality,
warnings).  Runs into one folder, even at once, merge their rows
(:func:`write_summary`): a local folder under its lock, a URL folder by a
conditional write of ``summary.json`` on S3 (``If-Match`` its ETag, redone
from the new rows when another run came first;
:func:`hht3d.io.uploads.update_object`).  Other stores have no conditional
write here: there the last of two runs finishing at once wins.  Secrets are
redacted (:func:`hht3d.redaction.redact`).
"""

from __future__ import annotations

import csv
import io as _stdio
import json
from collections.abc import Sequence
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..decomposition.quality import decomposition_quality
from ..errors import InputError
from ..io import is_recorded, new_run_id, read_npz_shapes, read_ply_header
from ..io.folder import OutputFolder
from ..io.headers import _MAX_HEADER
from ..io.lock import folder_lock
from ..io.manifest import recording
from ..io.storage import file_name, is_url, join, local_copy, local_path
from ..io.uploads import atomic_location, update_object
from ..linalg.backends import SOLVER_BACKENDS
from ..linalg.estimate import slow_fallback
from ..redaction import redact
from ..transform import HHTResult
from .guard import Failure, Timed

if TYPE_CHECKING:
    from hht3d.geometry.surface import Surface


__all__ = [
    "SUMMARY_FILES",
    "ItemSummary",
    "summary_paths",
    "quality_fields",
    "item_summary",
    "skipped_summary",
    "written_outputs",
    "write_summary",
]

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
    ``method`` is the decomposition's (``sifting`` or ``filtering``, :data:`~hht3d.decomposition.options.METHODS`).
    ``solver_advice`` says which extra to install when a slow sparse solver ran on a
    large mesh (:func:`hht3d.linalg.estimate.slow_fallback`).
    """

    source: str
    status: str  # "ok", "failed" or "skipped"
    vertices: int | None = None
    imfs: int | None = None
    seconds: float | None = None
    method: str | None = None
    energy_ratio: float | None = None
    orthogonality_index: float | None = None
    io_leaking: float | None = None
    io_cancelling: float | None = None
    warnings: tuple[str, ...] = ()
    outputs: tuple[str, ...] = ()
    step: str | None = None
    error: str | None = None
    solver_advice: str | None = None


def summary_paths(out_dir: Path | str) -> list:
    """``summary.json`` and ``summary.csv`` in ``out_dir`` (paths, or URLs for a URL folder)."""
    return [join(out_dir, summary) for summary in SUMMARY_FILES]


def quality_fields(decomposition: Any, surface: Surface) -> dict:
    """``method``, ``energy_ratio``, ``orthogonality_index``, its two parts and ``warnings`` of an EMD or HHT
    result."""
    if isinstance(decomposition, HHTResult):
        quality = decomposition.quality
    else:
        imfs, residue = decomposition.imfs, decomposition.residue
        quality = decomposition_quality(surface, imfs.sum(axis=0) + residue, imfs, residue)
    info = decomposition.info
    return {
        "method": info.get("emd", info).get("method"),
        "energy_ratio": quality.energy_ratio,
        "orthogonality_index": quality.orthogonality_index,
        "io_leaking": quality.io_leaking,
        "io_cancelling": quality.io_cancelling,
        "warnings": tuple(quality.warnings),
    }


def item_summary(
    source: str, paths: Sequence[str], surface: Any, decomposition: Any, quality: Any, parts: Any, writes: Any
) -> ItemSummary:
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
    return ItemSummary(
        source, "ok", vertices=vertices, imfs=imfs, seconds=seconds, outputs=written, solver_advice=advice, **fields
    )


def _backend_of(decomposition: Any) -> str | None:
    """The sparse solver an EMD or HHT result was computed with: iterative filtering records what applied
    its filters, ``"chebyshev"`` and the solver joined by ``+`` (``None`` when it made no solves)."""
    info = decomposition.info
    used = str(info.get("emd", info).get("backend") or "").split("+")
    return next((name for name in used if name in SOLVER_BACKENDS), None)


def skipped_summary(source: Path | str, paths: Sequence[str], storage_options: dict | None = None) -> ItemSummary:
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


def written_outputs(rows: list[ItemSummary]) -> list[str]:
    """The outputs that the rows' inputs wrote in this run (not those of skipped inputs)."""
    return [path for row in rows if row.status != "skipped" for path in row.outputs]


def write_summary(
    rows: list[ItemSummary], out_dir: Path | str, run: str | None = None, storage_options: dict | None = None
) -> list:
    """Write the summary table as ``summary.json`` and ``summary.csv`` (atomically, secrets redacted).

    The rows already there are merged in: runs into one folder, even at
    once, keep each other's rows (a row of an input that ``rows`` do not
    cover is kept, one that they do is replaced).  In a local folder this
    happens under the folder's lock, with the earlier rows of a summary the
    manifest records, and both files are recorded in the folder's manifest
    (:mod:`hht3d.io.manifest`) under the run id ``run``.  In a URL folder
    (``storage_options`` for its back-end) ``summary.json`` is updated
    conditionally where the store can (see the module), ``summary.csv``
    written from it, and both recorded in the folder's manifest object.
    In the CSV, ``outputs`` are joined with ``;`` and ``warnings`` with ``" | "``.

    Parameters
    ----------
    rows : list of ItemSummary
        The rows of this run, one per input.
    out_dir : Path or str
        The output folder (a path or a URL).
    run : str, optional
        The run id of the manifest (default: a new one).
    storage_options : dict, optional
        Options of the fsspec back-end of a URL ``out_dir``.

    Returns
    -------
    list
        The paths (or URLs) written: ``summary.json`` and ``summary.csv``.

    Raises
    ------
    OutputError
        A summary file cannot be written (names it and the reason).
    """
    out_dir = local_path(out_dir)
    records = [asdict(r) | {"outputs": list(r.outputs), "warnings": list(r.warnings)} for r in rows]
    ours = {r["source"] for r in records}
    if is_url(out_dir):
        return _write_remote(records, ours, OutputFolder(out_dir, storage_options=storage_options, run=run))
    with folder_lock(out_dir, run), recording(out_dir, run or new_run_id()):
        earlier = _earlier_rows(summary_paths(out_dir)[0], out_dir)
        return _write_tables([r for r in earlier if r.get("source") not in ours] + records, out_dir)


def _write_remote(records: list[dict], ours: set, folder: OutputFolder) -> list:
    """The summary of a URL folder: ``summary.json`` merged with the rows there, ``summary.csv`` from it,
    then both recorded in the manifest object."""
    json_url, csv_url = summary_paths(folder.location)
    merged: list[dict] = []

    def update(old: bytes | None) -> bytes:
        merged[:] = [r for r in _rows(old) if r.get("source") not in ours] + records
        return redact(json.dumps(merged, indent=2)).encode()

    update_object(json_url, update, folder.storage_options)
    with atomic_location(csv_url, folder.storage_options) as tmp:
        tmp.write_text(_csv_text(merged), encoding="utf-8")
    folder.record([json_url, csv_url])
    return [json_url, csv_url]


def _write_tables(records: list[dict], out_dir: Path | str) -> list:
    """``summary.json`` and ``summary.csv`` of ``records`` in a local folder, each written atomically."""
    json_path, csv_path = summary_paths(out_dir)
    with atomic_location(json_path) as tmp:
        tmp.write_text(redact(json.dumps(records, indent=2)), encoding="utf-8")
    with atomic_location(csv_path) as tmp:
        tmp.write_text(_csv_text(records), encoding="utf-8")
    return [json_path, csv_path]


def _csv_text(records: list[dict]) -> str:
    buffer = _stdio.StringIO()
    names = [f.name for f in fields(ItemSummary)]
    writer = csv.DictWriter(buffer, fieldnames=names, extrasaction="ignore")
    writer.writeheader()
    for r in records:
        writer.writerow(
            {k: r.get(k) for k in names}
            | {"outputs": ";".join(r.get("outputs") or []), "warnings": " | ".join(r.get("warnings") or [])}
        )
    return redact(buffer.getvalue())


def _earlier_rows(path: Path, folder: Path | str) -> list[dict]:
    """The rows of a summary hht3d wrote earlier (none if it is missing, changed or unreadable)."""
    if not is_recorded(path, folder):
        return []
    try:
        return _rows(path.read_bytes())
    except OSError:
        return []


def _rows(data: bytes | None) -> list[dict]:
    """The rows of a summary's bytes (none if missing or not a JSON list of rows)."""
    try:
        rows = json.loads(data) if data else []
    except ValueError:
        return []
    return [r for r in rows if isinstance(r, dict)] if isinstance(rows, list) else []
