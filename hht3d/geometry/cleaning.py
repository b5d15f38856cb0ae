"""Mesh and point-cloud cleaning with a report of what changed.

Cleaning welds vertices at identical positions, drops degenerate and
duplicated faces and removes unreferenced vertices.  It returns index maps so
per-vertex data (colours, stored scalars, user signals) can follow.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .operators import face_areas
from .rows import unique_rows

__all__ = ["CleanReport", "clean_mesh", "clean_points"]

#: A face whose area is below this fraction of the mean face area is degenerate.
DEGENERATE_AREA_FRACTION = 1e-12


@dataclass(frozen=True)
class CleanReport:
    """What cleaning changed.

    Attributes
    ----------
    kept_vertices : (n_new,) int array
        For each new vertex, the original vertex it was taken from.
    original_to_new : (n_old,) int array
        New index of each original vertex, ``-1`` where it was removed.
    """

    merged_duplicate_vertices: int = 0
    removed_unreferenced_vertices: int = 0
    removed_degenerate_faces: int = 0
    removed_duplicate_faces: int = 0
    kept_vertices: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64), repr=False)
    original_to_new: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64), repr=False)

    @property
    def changed(self) -> bool:
        return bool(
            self.merged_duplicate_vertices
            or self.removed_unreferenced_vertices
            or self.removed_degenerate_faces
            or self.removed_duplicate_faces
        )

    def summary(self) -> str:
        """One line for logs and the CLI."""
        if not self.changed:
            return "clean: nothing to change"
        return (
            f"clean: merged {self.merged_duplicate_vertices} duplicate vertices, "
            f"removed {self.removed_unreferenced_vertices} unreferenced vertices, "
            f"{self.removed_degenerate_faces} degenerate faces, "
            f"{self.removed_duplicate_faces} duplicate faces"
        )


def _weld(vertices: np.ndarray) -> tuple[np.ndarray, int]:
    """Map vertices with identical coordinates to their first occurrence."""
    _, first, inverse, _ = unique_rows(vertices)
    representative = first[inverse]  # original index of the kept twin
    return representative, len(vertices) - len(first)


def clean_mesh(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray, CleanReport]:
    """Weld duplicates, drop degenerate/duplicate faces and unreferenced vertices.

    Returns
    -------
    vertices, faces, report : (m, 3) array, (g, 3) array, CleanReport
    """
    n = len(vertices)
    representative, merged = _weld(vertices)
    faces = representative[faces]
    repeated = (faces[:, 0] == faces[:, 1]) | (faces[:, 1] == faces[:, 2]) | (faces[:, 0] == faces[:, 2])
    area = face_areas(vertices, faces)
    mean_area = area[~repeated].mean() if (~repeated).any() else 0.0
    degenerate = repeated | (area <= DEGENERATE_AREA_FRACTION * mean_area)
    faces = faces[~degenerate]
    _, first, _, _ = unique_rows(np.sort(faces, axis=1))
    duplicates = len(faces) - len(first)
    faces = faces[np.sort(first)]

    used = np.zeros(n, dtype=bool)
    used[faces.ravel()] = True
    kept = np.flatnonzero(used)
    old_to_kept = np.full(n, -1, dtype=np.int64)
    old_to_kept[kept] = np.arange(len(kept))
    original_to_new = old_to_kept[representative]
    report = CleanReport(
        merged_duplicate_vertices=int(merged),
        removed_unreferenced_vertices=int(n - merged - len(kept)),
        removed_degenerate_faces=int(degenerate.sum()),
        removed_duplicate_faces=int(duplicates),
        kept_vertices=kept,
        original_to_new=original_to_new,
    )
    return vertices[kept], old_to_kept[faces], report


def clean_points(points: np.ndarray) -> tuple[np.ndarray, CleanReport]:
    """Merge points at identical positions (they make the point-cloud Laplacian singular)."""
    representative, merged = _weld(points)
    kept = np.unique(representative)
    old_to_kept = np.full(len(points), -1, dtype=np.int64)
    old_to_kept[kept] = np.arange(len(kept))
    report = CleanReport(
        merged_duplicate_vertices=int(merged), kept_vertices=kept, original_to_new=old_to_kept[representative]
    )
    return points[kept], report
