"""The resolution limit of a surface: the highest frequency each vertex can resolve (Sec. 4.3).

A vertex of area ``A_v`` resolves frequencies up to ``π/√A_v``; instantaneous
frequencies above it alias.  :func:`resolution_report` says how many
vertex–IMF pairs, and what share of the energy ``a² A_v``, lie above.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..geometry.surface import Surface
from ..geometry.validation import check_surface

__all__ = ["resolvable_frequency", "resolvable_from_area", "ResolutionReport", "resolution_report"]


def resolvable_frequency(surface: Surface) -> np.ndarray:
    """Highest frequency each vertex can resolve, ``π/√A_v`` (n,), radians per unit length.

    ``A_v`` is the vertex area (lumped mass, :attr:`Surface.mass_diagonal`):
    the Nyquist wavenumber of a square lattice with one sample per ``A_v``
    (``π/h`` on a grid of spacing ``h``).  A pattern whose wavelength is
    shorter than about two sample spacings aliases: its frequency cannot be
    read from the samples.

    Parameters
    ----------
    surface : Surface
        The surface.

    Returns
    -------
    (n,) ndarray
        The highest resolvable frequency at each vertex.

    Examples
    --------
    >>> import numpy as np
    >>> from hht3d import data_path, load
    >>> from hht3d.spectral import resolvable_frequency
    >>> sphere = load(data_path("sphere_oct4098.ply"))
    >>> nyquist = resolvable_frequency(sphere)
    >>> bool(np.allclose(nyquist, np.pi / np.sqrt(sphere.mass_diagonal)))
    True
    """
    check_surface(surface)
    return resolvable_from_area(surface.mass_diagonal)


def resolvable_from_area(area: np.ndarray) -> np.ndarray:
    """``π/√A_v`` for vertex areas ``A_v`` (:func:`resolvable_frequency` without the surface)."""
    return np.pi / np.sqrt(np.asarray(area, dtype=np.float64))


@dataclass(frozen=True)
class ResolutionReport:
    """Instantaneous frequencies above the resolution limit (:func:`resolution_report`).

    Attributes
    ----------
    limit : float
        Median per-vertex resolvable frequency ``π/√A_v`` of the surface.
    pairs : int
        Vertex–signal pairs whose frequency exceeds their vertex's limit.
    fraction : float
        ``pairs`` over all vertex–signal pairs.
    per_signal : (k,) ndarray
        That fraction per signal (IMF).
    energy_share : float
        Share of the weighted energy (``a² A_v``) carried by those pairs;
        ``nan`` without weights or energy.
    area_per_signal : (k,) ndarray
        Per signal, the share of the area (``A_v``) where it is above the limit; with no areas
        given, every vertex counts alike (``per_signal``).  The figure of
        :func:`hht3d.decomposition.quality.aliasing_warnings`.
    """

    limit: float
    pairs: int
    fraction: float
    per_signal: np.ndarray
    energy_share: float
    area_per_signal: np.ndarray

    @property
    def ok(self) -> bool:
        """True when every frequency is within its vertex's limit."""
        return self.pairs == 0

    def summary(self) -> str:
        """One line, e.g. for a log or a figure."""
        if self.ok:
            return f"all frequencies within the resolution limit (median π/√A = {self.limit:.4g})"
        share = "" if np.isnan(self.energy_share) else f", {100 * self.energy_share:.2g}% of the energy"
        return (
            f"{self.pairs} vertex–IMF pairs ({100 * self.fraction:.2g}%{share}) above the resolution "
            f"limit (median π/√A = {self.limit:.4g}): their frequencies are aliased"
        )


def resolution_report(
    frequency: np.ndarray,
    resolvable: np.ndarray,
    weights: np.ndarray | None = None,
    area: np.ndarray | None = None,
) -> ResolutionReport:
    """Which instantaneous frequencies exceed the resolution limit of their vertex.

    Parameters
    ----------
    frequency : (k, n) array_like
        Instantaneous frequencies.
    resolvable : (n,) array_like
        Per-vertex limits (:func:`resolvable_frequency`).
    weights : (k, n) array_like, optional
        E.g. ``a² A_v``, for :attr:`ResolutionReport.energy_share`.
    area : (n,) array_like, optional
        Vertex areas ``A_v``, for :attr:`ResolutionReport.area_per_signal`.

    Returns
    -------
    ResolutionReport
    """
    frequency = np.atleast_2d(np.asarray(frequency, dtype=np.float64))
    resolvable = np.asarray(resolvable, dtype=np.float64)
    if resolvable.shape != frequency.shape[1:]:
        raise InputError(f"resolvable has shape {resolvable.shape}; expected ({frequency.shape[1]},)")
    above = frequency > resolvable
    share = np.nan
    if weights is not None:
        weights = np.broadcast_to(np.asarray(weights, dtype=np.float64), frequency.shape)
        total = weights.sum()
        share = float(weights[above].sum() / total) if total > 0 else np.nan
    per_signal = above.mean(axis=1) if above.shape[1] else np.zeros(len(above))
    area_per_signal = per_signal
    if area is not None:
        area = np.asarray(area, dtype=np.float64)
        total_area = float(area.sum())
        area_per_signal = above @ area / total_area if total_area > 0 else np.zeros(len(above))
    return ResolutionReport(
        limit=float(np.median(resolvable)) if resolvable.size else np.nan,
        pairs=int(above.sum()),
        fraction=float(above.mean()) if above.size else 0.0,
        per_signal=per_signal,
        energy_share=share,
        area_per_signal=area_per_signal,
    )
