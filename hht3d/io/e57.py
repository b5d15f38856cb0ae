"""E57 scans of terrestrial scanners through pye57 (``pip install 'hht3d[e57]'``).

A file holds several scans, each with its pose (a rotation and a translation to the file's
frame).  :func:`read_e57` reads one scan or all of them, each placed by its pose and merged, as
one point cloud relative to a local origin (the whole metres below the smallest coordinates:
``surface.vertices + surface.origin`` are the file's coordinates).  Intensity, ``luminance`` of
the colours, and (all scans merged) ``scan``, the index of each point's scan, are stored
attributes.
"""

from __future__ import annotations

from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

from ..errors import InputError, one_line
from .formats import short

__all__ = ["read_e57"]

_LUMA = np.array([0.2126, 0.7152, 0.0722])
_XYZ = ("cartesianX", "cartesianY", "cartesianZ")
_RGB = ("colorRed", "colorGreen", "colorBlue")


def _pye57() -> ModuleType:
    try:
        import pye57
    except ImportError:
        raise InputError("E57 files need pye57: pip install 'hht3d[e57]'") from None
    return pye57


def read_e57(path: Path, scan: int | None = None) -> dict:
    """The arrays of a point-cloud :class:`~hht3d.geometry.surface.Surface` from scan ``scan`` of an
    E57 file (0-based), or from all its scans merged.

    Memory: 8 bytes × (3 + 1 with intensity + 4 with colours + 1 for ``scan``) per point, plus
    pye57's buffers of one scan; the counts the headers declare are checked against the memory
    available before any scan is read.

    Raises
    ------
    InputError
        pye57 missing, not an E57 file, no such scan, a scan without Cartesian coordinates, more
        points declared than memory can take, or no points.
    """
    from ..linalg.estimate import available_memory

    pye57 = _pye57()
    try:
        e57 = pye57.E57(str(path))
    except Exception as exc:  # libE57Format raises its own types on a corrupt file
        raise InputError(f"{short(path)}: not a readable E57 file ({one_line(exc)})") from None
    try:
        count = e57.scan_count
        if scan is not None and scan >= count:
            raise InputError(f"{short(path)}: load option scan is {scan}, but the file holds {count} scans (0-based)")
        chosen = range(count) if scan is None else [scan]
        headers = [e57.get_header(i) for i in chosen]
        fields = [set(h.point_fields) for h in headers]
        for i, present in zip(chosen, fields):
            if not set(_XYZ) <= present:
                raise InputError(f"{short(path)}: scan {i} has no Cartesian coordinates ({', '.join(sorted(present))})")
        points = sum(int(h.point_count) for h in headers)
        need, memory = 8 * 9 * points, available_memory()
        if memory is not None and need > memory:
            raise InputError(
                f"{short(path)}: its scans declare {points:,} points, which need {need / 2**30:.1f} GiB to read; "
                f"{memory / 2**30:.1f} GiB are available"
            )
        if points == 0:
            raise InputError(f"{short(path)}: the file holds no points")
        scans = [_scan(e57, i, present) for i, present in zip(chosen, fields)]
    except InputError:
        raise
    except Exception as exc:  # corrupt point data
        raise InputError(f"{short(path)}: the points cannot be read ({one_line(exc)})") from None
    finally:
        e57.close()
    return _merged(scans, merged=scan is None and count > 1)


def _scan(e57: Any, index: int, present: set) -> dict:
    has_rgb = set(_RGB) <= present
    data = e57.read_scan(index, intensity="intensity" in present, colors=has_rgb, ignore_missing_fields=True)
    return {"index": index, **{k: np.asarray(v) for k, v in data.items()}}


def _merged(scans: list[dict], *, merged: bool) -> dict:
    xyz = np.vstack([np.column_stack([s[k] for k in _XYZ]) for s in scans]).astype(np.float64)
    origin = np.floor(xyz.min(axis=0))
    attributes: dict[str, np.ndarray] = {}
    if all("intensity" in s for s in scans):
        attributes["intensity"] = np.concatenate([s["intensity"] for s in scans]).astype(np.float64)
    if merged:
        attributes["scan"] = np.concatenate([np.full(len(s[_XYZ[0]]), s["index"], dtype=np.float64) for s in scans])
    data: dict[str, Any] = {"vertices": xyz - origin, "faces": None, "origin": origin, "attributes": attributes}
    if all(_RGB[0] in s for s in scans):
        rgb = np.vstack([np.column_stack([s[k] for k in _RGB]) for s in scans]).astype(np.float64)
        data["colors"] = rgb / (255.0 if rgb.max() <= 255 else 65535.0)
        attributes["luminance"] = data["colors"] @ _LUMA
    return data
