"""The bump-band sphere of the filtering tests (tests/apps/): its scale, and how much of it a surface keeps."""

from __future__ import annotations

import numpy as np

from hht3d import Surface

#: Bump sphere: 20 bumps around the equator, peak 0.005 of the radius; ω = √(20·21) ≈ 20.5.
WAVES, AMPLITUDE = 20, 0.005
OMEGA = np.sqrt(WAVES * (WAVES + 1))


def sphere_distance(surface: Surface, vertices: np.ndarray) -> float:
    """Area-weighted RMS distance of ``vertices`` to the unit sphere (areas of ``surface``)."""
    area = surface.mass_diagonal
    return float(np.sqrt(np.sum(area * (np.linalg.norm(vertices, axis=1) - 1) ** 2) / area.sum()))


def bump_amplitude(surface: Surface, vertices: np.ndarray, pattern: np.ndarray) -> float:
    """Least-squares amplitude of the bump pattern in the radial deviation."""
    area = surface.mass_diagonal
    deviation = np.linalg.norm(vertices, axis=1) - 1
    return float(np.sum(area * deviation * pattern) / np.sum(area * pattern**2))
