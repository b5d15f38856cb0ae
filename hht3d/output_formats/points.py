"""The formats that write any result as its surface with every field: LAS and LAZ
(:func:`hht3d.io.las.write_las`, the ``lidar`` extra), VTU (through meshio, the ``meshio`` extra)
and VTP (:mod:`hht3d.io.mesh_files`)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ..geometry.surface import Surface
from ..io.las import write_las
from ..io.mesh_files import write_vtp, write_vtu
from .options import Format, Points

__all__ = ["emd_fields", "feature_fields", "point_formats"]


def emd_fields(decomposition: Any) -> dict[str, np.ndarray]:
    """``imf_K`` (from 1) and ``residue``."""
    fields = {f"imf_{k + 1}": imf for k, imf in enumerate(decomposition.imfs)}
    return {**fields, "residue": decomposition.residue}


def feature_fields(features: Any, surface: Surface) -> dict[str, np.ndarray]:
    """``feature_count`` and ``feature`` (1 at a feature vertex)."""
    is_feature = np.zeros(surface.n_vertices)
    is_feature[features.vertices] = 1.0
    return {"feature_count": features.vertex_counts.astype(np.float64), "feature": is_feature}


#: The surface a result of each kind is written on, and its fields.
_FIELDS: dict[str, Callable[[Any, Surface], tuple[Surface, dict]]] = {
    "hht": lambda result, _: (result.surface, result.vertex_attributes()),
    "emd": lambda decomposition, surface: (surface, emd_fields(decomposition)),
    "signal": lambda values, surface: (surface, {"signal": values}),
    "surface": lambda surface, _: (surface, {}),
    "features": lambda features, surface: (surface, feature_fields(features, surface)),
}


def _writer(kind: str, write: Callable) -> Callable:
    def written(value: Any, surface: Surface, path: Path | str, **options: Any) -> Path:
        on, fields = _FIELDS[kind](value, surface)
        return write(path, on, fields, **options)

    return written


def point_formats(kind: str) -> list[Format]:
    """The point formats of a result ``kind``."""
    las = _writer(kind, write_las)
    return [
        Format("las", ".las", "the points, a LAS input's dimensions, and every field as extra bytes", las, Points),
        Format("laz", ".laz", "as las, compressed", las, Points),
        Format("vtu", ".vtu", "VTK unstructured grid: the cells, every field as point data", _writer(kind, write_vtu)),
        Format("vtp", ".vtp", "VTK PolyData: the cells, every field as point data", _writer(kind, write_vtp)),
    ]
