"""Signals of the EMD tests (tests/decomposition/): real spherical harmonics, and the sum of the parts."""

from __future__ import annotations

import numpy as np
from scipy.special import sph_harm_y

# Σ imfs + residue reproduces the signal up to a few ulps of its magnitude.
SUM_RTOL = 1e-10


def real_sph_harm(degree: int, coefficients: np.ndarray, vertices: np.ndarray) -> np.ndarray:
    """``Σ_m c_m Y_lm`` over the 2l+1 real spherical harmonics of one degree, unit RMS."""
    polar = np.arccos(np.clip(vertices[:, 2] / np.linalg.norm(vertices, axis=1), -1, 1))
    azimuth = np.arctan2(vertices[:, 1], vertices[:, 0])
    total = coefficients[degree] * sph_harm_y(degree, 0, polar, azimuth).real
    for m in range(1, degree + 1):
        y = sph_harm_y(degree, m, polar, azimuth)
        total = total + coefficients[degree + m] * y.real + coefficients[degree - m] * y.imag
    return total / np.sqrt(np.mean(total**2))


def assert_sums_to_signal(result, signal):
    total = result.imfs.sum(axis=0) + result.residue
    assert np.max(np.abs(total - signal)) <= SUM_RTOL * np.max(np.abs(signal))
