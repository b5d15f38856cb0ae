"""LAS and LAZ point clouds through laspy (``pip install 'hht3d[lidar]'``; lazrs decompresses LAZ).

Coordinates are read as the file stores them, integers ``X`` scaled and offset, in float64 and
relative to a local origin (the file's offset plus its first chunk's smallest integer coordinate):
``surface.vertices + surface.origin`` are the file's coordinates, and a scan 10⁶ m from its datum
keeps every digit of its scale.  Writing turns them back into the same integers.

Every scalar per-point dimension becomes a stored attribute (:func:`~hht3d.io.formats.usable_name`
of its name): ``intensity``, ``classification``, ``return_number``, ``gps_time``, ..., every
extra-bytes dimension, and ``luminance`` (Rec. 709) beside the colours of RGB formats; the load option
``dimensions`` keeps only those it names (``luminance`` for the colours), for less memory per point
(:func:`bytes_per_point`) and, in a LAZ of point format 6-10, only their layers decoded.  Array-valued
extra-bytes dimensions are not read.

Speed: LAZ is decoded by lazrs's parallel decompressor, and each decoded chunk converted to the columns
by one thread per CPU.  No reader outruns its decoder: on the shared 2-core machine laspy and lazrs
decoding alone reach 3.7-3.9 M points/s, the ceiling of this reader there and below the 5 M points/s
the issue asked for; a 10⁷-point format-3 LAZ reads at 1.9-2.7 M points/s in full and 3.2-3.3 M points/s
with two dimensions (``benchmarks/results/las.md``).
"""

from __future__ import annotations

import copy
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
from numpy.lib.recfunctions import structured_to_unstructured

from ..errors import InputError, one_line
from ..geometry.surface import MIN_VERTICES, Surface
from ..linalg.threads import usable_cores
from .atomic import atomic_path
from .formats import short, usable_name

__all__ = ["LAS_EXTENSIONS", "CHUNK_POINTS", "LasSource", "read_las", "write_las", "bytes_per_point"]

LAS_EXTENSIONS = (".las", ".laz")
#: Points decoded at a time.
CHUNK_POINTS = 1_000_000
#: Dimensions read as positions and colours, not as attributes.
_RGB = ["red", "green", "blue"]
_GEOMETRY = ("X", "Y", "Z", *_RGB)
_LUMA = np.array([0.2126, 0.7152, 0.0722])
#: The layer of each dimension of a LAZ of point format 6-10, which lazrs can leave undecoded (laspy's
#: ``DecompressionSelection``); x, y, the returns and the scanner channel are always decoded.
_LAYERS = {
    "Z": "Z",
    "intensity": "INTENSITY",
    "classification": "CLASSIFICATION",
    **dict.fromkeys(
        ("synthetic", "key_point", "withheld", "overlap", "scan_direction_flag", "edge_of_flight_line"), "FLAGS"
    ),
    "user_data": "USER_DATA",
    "scan_angle": "SCAN_ANGLE",
    "point_source_id": "POINT_SOURCE_ID",
    "gps_time": "GPS_TIME",
    "red": "RGB",
    "nir": "NIR",
    **dict.fromkeys(
        ("wavepacket_index", "wavepacket_offset", "wavepacket_size", "return_point_wave_location", "x_t", "y_t", "z_t"),
        "WAVEPACKET",
    ),
}
_ALWAYS_DECODED = ("X", "Y", "return_number", "number_of_returns", "scanner_channel")
#: Extra-bytes names hold at most 32 bytes.
_MAX_EXTRA_NAME = 32


@dataclass(frozen=True)
class LasSource:
    """What :func:`read_las` keeps to write the file back: its laspy header (point format, scales,
    offsets, VLRs such as the CRS) and the full-scale value of its colours (255 or 65535)."""

    header: Any
    color_scale: float = 65535.0


def _laspy(compressed: bool = False) -> ModuleType:
    try:
        import laspy
    except ImportError:
        raise InputError("LAS/LAZ files need laspy: pip install 'hht3d[lidar]'") from None
    if compressed and not laspy.LazBackend.detect_available():
        raise InputError("LAZ files need lazrs: pip install 'hht3d[lidar]'")
    return laspy


def _laz_backends(laspy: ModuleType) -> tuple:
    """The LAZ decompressors available, fastest first: lazrs's parallel one decoded 1.9-2.0x as fast as
    its single-threaded one on 2 cores and 1.2x on one (``benchmarks/bench_las.py``)."""
    order = (laspy.LazBackend.LazrsParallel, laspy.LazBackend.Lazrs, laspy.LazBackend.Laszip)
    return tuple(backend for backend in order if backend.is_available())


def _attribute_dimensions(point_format: Any) -> list[str]:
    """The scalar dimensions read as attributes."""
    return [d.name for d in point_format.dimensions if d.name not in _GEOMETRY and d.num_elements == 1]


@dataclass(frozen=True)
class _Kept:
    """What a read keeps: the LAS dimensions read as attributes, and whether the colours are."""

    dimensions: list[str]
    colours: bool

    @property
    def bytes_per_point(self) -> int:
        """8 bytes for each coordinate and dimension, 32 for the colours and their luminance."""
        return 8 * (3 + len(self.dimensions) + (4 if self.colours else 0))


def _kept(point_format: Any, dimensions: Sequence[str] | None) -> _Kept:
    """The dimensions ``dimensions`` names (LAS or attribute names; ``luminance`` for the colours), all
    by default.

    Raises
    ------
    InputError
        A name the point format does not have, in one line listing those it has.
    """
    names = _attribute_dimensions(point_format)
    has_rgb = "red" in point_format.dimension_names
    if dimensions is None:
        return _Kept(names, has_rgb)
    known = {usable_name(name): name for name in names} | {name: name for name in names}
    colours = "luminance" in dimensions and has_rgb
    unknown = [name for name in dimensions if name not in known and not (name == "luminance" and has_rgb)]
    if unknown:
        offered = [usable_name(name) for name in names] + (["luminance"] if has_rgb else [])
        raise InputError(
            f"no dimension {', '.join(map(repr, unknown))} in point format {point_format.id}; "
            f"its dimensions: {', '.join(offered)}"
        )
    wanted = {known[name] for name in dimensions if name in known}
    return _Kept([name for name in names if name in wanted], colours)


def _layers(laspy: ModuleType, point_format: Any, decoded: Sequence[str]) -> Any:
    """The LAZ layers that hold the dimensions ``decoded`` (laspy ignores them below point format 6)."""
    selection = laspy.DecompressionSelection.base()
    extra = set(point_format.extra_dimension_names)
    for name in decoded:
        if name in extra:
            selection |= laspy.DecompressionSelection.ALL_EXTRA_BYTES
        elif name in _LAYERS:
            selection |= laspy.DecompressionSelection[_LAYERS[name]]
        elif name not in _ALWAYS_DECODED:  # a dimension of a later LAS version: decode everything
            return laspy.DecompressionSelection.all()
    return selection


def bytes_per_point(point_format: Any, dimensions: Sequence[str] | None = None) -> int:
    """Memory one kept point takes once read: float64 coordinates, the kept dimensions, and the colours
    and luminance when kept (``dimensions`` as for :func:`read_las`).

    Parameters
    ----------
    point_format : laspy.PointFormat
    dimensions : sequence of str, optional
        The dimensions kept; default all.

    Returns
    -------
    int
        Bytes per point.
    """
    return _kept(point_format, dimensions).bytes_per_point


def read_las(path: Path, classes: Sequence[int] | None = None, dimensions: Sequence[str] | None = None) -> dict:
    """The arrays of a :class:`~hht3d.geometry.surface.Surface` from a LAS or LAZ file, read in chunks
    of :data:`CHUNK_POINTS`.

    Memory: :func:`bytes_per_point` per point, 8 bytes for each coordinate and kept dimension and 32
    for the colours with their luminance: 160 bytes for point format 3 in full, 40 with
    ``dimensions=["intensity", "classification"]``; plus one chunk's records and temporaries (about 60
    bytes per point of a chunk of 10⁶ points).  The arrays are allocated for the points the header
    declares; those ``classes`` leaves out are never touched and are given back.

    Parameters
    ----------
    path : Path
        A ``.las`` or ``.laz`` file.
    classes : sequence of int, optional
        Keep only the points of these classification codes.
    dimensions : sequence of str, optional
        Keep only these dimensions as attributes, by their LAS or attribute names (``echo width`` or
        ``echo_width``); ``luminance`` keeps the colours.  Default: every scalar dimension and the colours.

    Returns
    -------
    dict
        ``vertices``, ``faces`` (None), ``attributes``, ``origin``, ``header`` (a :class:`LasSource`) and
        ``colors`` when kept: the keyword arguments of a point-cloud surface.

    Raises
    ------
    InputError
        laspy (or lazrs for LAZ) missing, not a LAS file, a dimension the file does not have, a header
        declaring more points than the file holds or memory can take, no points, or fewer than 4 left
        by ``classes``.
    """
    from ..linalg.estimate import available_memory

    laspy = _laspy(path.suffix.lower() == ".laz")
    try:
        reader = laspy.open(str(path), laz_backend=_laz_backends(laspy))
    except Exception as exc:  # laspy raises many types on a corrupt header
        raise InputError(f"{short(path)}: not a readable LAS/LAZ file ({one_line(exc)})") from None
    with reader:
        header = reader.header
        count, point_format = int(header.point_count), header.point_format
        try:
            wanted = _kept(point_format, dimensions)
        except InputError as exc:
            raise InputError(f"{short(path)}: {exc}") from None
        if count == 0:
            raise InputError(f"{short(path)}: the file holds no points")
        size = path.stat().st_size
        if not header.are_points_compressed and header.offset_to_point_data + count * point_format.size > size:
            raise InputError(
                f"{short(path)}: the header declares {count:,} points of {point_format.size} bytes, more than "
                f"its {size:,} bytes hold: the file is truncated or its header is wrong"
            )
        need, memory = count * wanted.bytes_per_point, available_memory()
        if memory is not None and need > memory:
            raise InputError(
                f"{short(path)}: {count:,} points need {need / 2**30:.1f} GiB to read; "
                f"{memory / 2**30:.1f} GiB are available"
            )
        decoded = [
            "Z",
            *wanted.dimensions,
            *(["red"] if wanted.colours else []),
            *([] if classes is None else ["classification"]),
        ]
        # the layers to decode, set before the first read makes the decompressor
        reader.decompression_selection = _layers(laspy, point_format, decoded)
        try:
            data = _read_points(reader, count, classes, wanted)
        except InputError:
            raise
        except Exception as exc:  # lazrs and laspy raise their own types on corrupt point data
            raise InputError(f"{short(path)}: the points cannot be read ({one_line(exc)})") from None
    kept, seen = len(data["vertices"]), data.pop("classes_seen")
    if classes is not None and kept < MIN_VERTICES:
        raise InputError(
            f"{short(path)}: classes {list(classes)} keep {kept:,} of {count:,} points; a surface needs at "
            f"least {MIN_VERTICES} (the file's classes: {', '.join(map(str, seen)) or 'none'})"
        )
    return data


def _read_points(reader: Any, count: int, classes: Sequence[int] | None, kept: _Kept) -> dict:
    """Decode the points chunk by chunk straight into the kept arrays, a chunk's columns filled in parallel."""
    header = reader.header
    xyz = np.empty((count, 3))
    columns = {name: np.empty(count) for name in kept.dimensions}
    rgb = np.empty((count, 3)) if kept.colours else None
    reference: np.ndarray | None = None
    seen = np.zeros(256, dtype=bool)
    filled = read = 0
    with ThreadPoolExecutor(usable_cores()) as pool:
        for chunk in reader.chunk_iterator(CHUNK_POINTS):
            read += len(chunk)
            keep: Any = slice(None)
            if classes is not None:
                code = np.asarray(chunk.classification)
                seen |= np.bincount(code, minlength=256)[:256] > 0
                keep = np.isin(code, classes)
            ints = structured_to_unstructured(chunk.array[["X", "Y", "Z"]])  # a view of the records
            if reference is None:
                reference = ints.min(axis=0).astype(np.int64)
            end = filled + (len(chunk) if classes is None else int(np.count_nonzero(keep)))
            part = slice(filled, end)
            jobs = [partial(_coordinates, xyz[part], ints[keep], reference, header.scales)]
            jobs += [partial(_copy, columns[name][part], chunk[name], keep) for name in columns]
            if rgb is not None:
                jobs.append(partial(_copy, rgb[part], structured_to_unstructured(chunk.array[_RGB]), keep))
            for _ in pool.map(lambda job: job(), jobs):  # numpy releases the GIL: the columns fill in parallel
                pass
            filled = end
    if read < count:
        raise InputError(f"the file holds {read:,} of the {count:,} points its header declares")
    if filled < count:  # the classes filter left points out: give the unused tails back, without a copy
        for array in (xyz, rgb, *columns.values()):
            if array is not None:
                array.resize((filled, *array.shape[1:]), refcheck=False)
    data: dict[str, Any] = {
        "vertices": xyz,
        "faces": None,
        "attributes": {usable_name(name): values for name, values in columns.items()},
        "origin": np.asarray(header.offsets) + np.asarray(header.scales) * (0 if reference is None else reference),
        "classes_seen": np.flatnonzero(seen).tolist(),
    }
    scale = 65535.0
    if rgb is not None:
        scale = 255.0 if filled and rgb.max() <= 255 else 65535.0
        rgb /= scale
        data["colors"] = rgb
        data["attributes"]["luminance"] = rgb @ _LUMA
    data["header"] = LasSource(copy.deepcopy(header), scale)
    return data


def _coordinates(out: np.ndarray, ints: np.ndarray, reference: np.ndarray, scales: np.ndarray) -> None:
    """``(ints - reference) * scales`` into ``out``: integers below 2**53 subtract exactly in float64."""
    np.subtract(ints, reference, out=out, dtype=np.float64)
    out *= scales


def _copy(out: np.ndarray, values: Any, keep: Any) -> None:
    """A chunk's ``values`` at ``keep`` into ``out`` (converted to its type)."""
    out[...] = np.asarray(values)[keep]


def write_las(path: Path | str, surface: Surface, fields: dict | None = None, *, precision: str = "float64") -> Path:
    """Write the surface's points as LAS (LAZ for a ``.laz`` suffix) atomically.

    A surface read from LAS keeps its point format, scales, offsets, VLRs and every dimension (from
    its attributes and colours); other attributes and ``fields`` (IMFs, amplitude, frequency, ...) are
    added as extra-bytes dimensions of type ``precision``.  Another surface becomes point format 0
    (7 with colours) with a scale of 10⁻⁷ of its bounding box.

    Parameters
    ----------
    path : str or Path
        A ``.las`` or ``.laz`` file.
    surface : Surface
    fields : dict of str to (n,) array, optional
        Per-point values added as extra-bytes dimensions.
    precision : {"float64", "float32"}
        The type of the added dimensions.

    Returns
    -------
    Path
    """
    path = Path(path)
    compress = path.suffix.lower() == ".laz"
    laspy = _laspy(compress)
    source = surface.header if isinstance(surface.header, LasSource) else _new_source(laspy, surface)
    header = copy.deepcopy(source.header)
    standard = {usable_name(d): d for d in header.point_format.dimension_names}
    values = {**surface.attributes, **(fields or {})}
    added = [name for name in values if name not in standard and name != "luminance"]
    for name in added:
        if len(name) > _MAX_EXTRA_NAME:
            raise InputError(f"{name!r}: a LAS extra-bytes name holds at most {_MAX_EXTRA_NAME} characters")
    header.add_extra_dims([laspy.ExtraBytesParams(name, type=np.dtype(precision)) for name in added])
    las = laspy.LasData(header, points=laspy.ScaleAwarePointRecord.zeros(surface.n_vertices, header=header))
    scales, offsets = np.asarray(header.scales), np.asarray(header.offsets)
    reference = np.round((surface.origin - offsets) / scales).astype(np.int64)
    integers = reference + np.round(surface.vertices / scales).astype(np.int64)
    las.X, las.Y, las.Z = integers[:, 0], integers[:, 1], integers[:, 2]
    for name, values_of in values.items():
        dimension = standard.get(name, name)
        if dimension in _GEOMETRY or name == "luminance":
            continue
        kind = las.points[dimension].dtype if dimension not in added else np.dtype(precision)
        column = np.asarray(values_of, dtype=np.float64)
        las[dimension] = column.astype(kind) if kind.kind == "f" else np.rint(column).astype(kind)
    if surface.colors is not None and "red" in header.point_format.dimension_names:
        rgb = np.round(np.clip(surface.colors, 0, 1) * source.color_scale).astype(np.uint16)
        las.red, las.green, las.blue = rgb[:, 0], rgb[:, 1], rgb[:, 2]
    with atomic_path(path) as tmp, open(tmp, "wb") as handle:  # a stream: laspy compresses a path by its suffix
        las.write(handle, do_compress=compress)
    return path


def _new_source(laspy: ModuleType, surface: Surface) -> LasSource:
    header = laspy.LasHeader(point_format=7 if surface.colors is not None else 0, version="1.4")
    lowest = surface.vertices.min(axis=0)
    extent = max(surface.bounding_box_diagonal, 1e-300)
    header.scales = np.full(3, 10.0 ** np.floor(np.log10(extent * 1e-7)))
    header.offsets = surface.origin + lowest
    return LasSource(header)
