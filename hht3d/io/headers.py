"""What the headers of PLY and PCD files declare, read without their data, and the check that refuses a
header declaring more than its file can hold or memory can take (before any reader allocates)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..errors import InputError, one_line
from .formats import check_regular_file

__all__ = ["PlyHeader", "read_ply_header", "check_declared", "MAX_PLY_PROPERTIES"]


@dataclass(frozen=True)
class PlyHeader:
    """What the header of a PLY file declares: element counts, vertex property names, properties per element."""

    counts: dict
    vertex_properties: tuple[str, ...]
    property_counts: dict


#: The longest PLY header :func:`read_ply_header` reads.
_MAX_HEADER = 1 << 20


def read_ply_header(path: Path | str) -> PlyHeader:
    """The header of a PLY file, without reading its data (cheap for any file size).

    Parameters
    ----------
    path : Path or str
        The PLY file.

    Returns
    -------
    PlyHeader
        Element counts, vertex property names and properties per element.

    Raises
    ------
    InputError
        Not a PLY header (no ``ply`` line or no ``end_header`` in the first megabyte).
    """
    path = Path(path)
    check_regular_file(path, "a PLY file")
    counts: dict[str, int] = {}
    properties: list[Any] = []
    per_element: dict[str, Any] = {}
    element = None
    try:
        with open(path, "rb") as handle:
            lines = handle.read(_MAX_HEADER).split(b"\n")
    except OSError as exc:
        raise InputError(f"{path}: cannot read ({exc.strerror or one_line(exc)})") from None
    if lines[0].strip() != b"ply":
        raise InputError(f"{path}: not a PLY file (it does not start with 'ply')")
    for line in lines[1:]:
        words = line.decode("ascii", "replace").split()
        if words[:1] == ["end_header"]:
            return PlyHeader(counts, tuple(properties), per_element)
        if words[:1] == ["element"] and len(words) == 3 and words[2].isdigit():
            element = words[1]
            counts[element] = int(words[2])
        elif words[:1] == ["property"] and element is not None and len(words) >= 3:
            per_element[element] = per_element.get(element, 0) + 1
            if element == "vertex":
                properties.append(words[-1])
    raise InputError(f"{path}: not a readable PLY file (no end_header)")


#: Properties one PLY element may declare (scans carry a few dozen; plyfile builds a dtype of all).
MAX_PLY_PROPERTIES = 10_000
#: Bytes of a PCD header :func:`check_declared` reads.
_MAX_PCD_HEADER = 1 << 16


def check_declared(path: Path) -> None:
    """Refuse a PLY or PCD file whose header declares more than the file can hold or the reader may
    build (10⁷ properties, 10¹² points), before any reader allocates for it.

    Every declared item takes at least one byte per property in the file; a point takes 24 bytes
    of memory once read.

    Raises
    ------
    InputError
    """
    from ..linalg.estimate import available_memory

    ext = path.suffix.lower()
    if ext == ".ply":
        with open(path, "rb") as handle:
            if handle.read(3) != b"ply":  # not a PLY at all: the reader says what is wrong
                return
        header = read_ply_header(path)
        crowded = {e: n for e, n in header.property_counts.items() if n > MAX_PLY_PROPERTIES}
        if crowded:
            element, count = next(iter(crowded.items()))
            raise InputError(
                f"{path}: the PLY element {element!r} declares {count:,} properties; at most "
                f"{MAX_PLY_PROPERTIES:,} are read"
            )
        needed = sum(n * max(1, header.property_counts.get(e, 1)) for e, n in header.counts.items())
        points = header.counts.get("vertex", 0)
    elif ext == ".pcd":
        needed = points = _pcd_points(path)
    else:
        return
    size = path.stat().st_size
    if needed > size:
        raise InputError(
            f"{path}: the header declares {points:,} vertices ({needed:,} values), more than its "
            f"{size:,} bytes can hold: the file is truncated or its header is wrong"
        )
    memory = available_memory()
    if memory is not None and 24 * points > memory:
        raise InputError(
            f"{path}: {points:,} vertices need {24 * points / 2**30:.1f} GiB to read; "
            f"{memory / 2**30:.1f} GiB are available"
        )


def _pcd_points(path: Path) -> int:
    """The ``POINTS`` a PCD header declares (0 if it declares none)."""
    try:
        with open(path, "rb") as handle:
            head = handle.read(_MAX_PCD_HEADER)
    except OSError as exc:
        raise InputError(f"{path}: cannot read ({exc.strerror or one_line(exc)})") from None
    for line in head.split(b"\n"):
        words = line.decode("ascii", "replace").split()
        if words[:1] == ["POINTS"] and len(words) == 2 and words[1].isdigit():
            return int(words[1])
        if words[:1] == ["DATA"]:
            break
    return 0
