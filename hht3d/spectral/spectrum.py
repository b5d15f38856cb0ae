"""Hilbert spectra on surfaces: the space–frequency–energy distribution (Sec. 4.3, Alg. 2).

Each vertex ``v`` and IMF ``k`` carry one pair ``(ω_k(v), a_k(v))`` of
instantaneous frequency and local amplitude (:mod:`hht3d.spectral.monogenic_signal`).  The
Hilbert spectrum places the energy ``a_k(v)²`` at frequency ``ω_k(v)``:

    H(ω, v) = Σ_k a_k(v)² [ω_k(v) ∈ bin(ω)],

and the marginal spectrum integrates it over the surface with the vertex
areas ``A_v`` (lumped mass): ``h(ω) = Σ_v A_v H(ω, v)``.

Frequencies are Eq. 23 as :mod:`hht3d.spectral.frequency` estimates it (the
wavenumber for waves varying in one direction, less for patterns varying in
two: 0.77 of it for an isotropic random wave, energy-weighted).  A
vertex resolves frequencies up to ``π/√A_v``
(:func:`hht3d.spectral.resolution.resolvable_frequency`); the spectrum keeps these
limits, and :attr:`HilbertSpectrum.resolution` counts the vertex–IMF pairs
above them (their frequencies are aliased).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import cast

import numpy as np

from ..errors import InputError
from ..geometry.surface import Surface
from .monogenic_signal import MonogenicSignal
from .resolution import ResolutionReport, resolution_report, resolvable_from_area

__all__ = ["HilbertSpectrum", "SCALES"]

#: Frequency bin spacings.
SCALES = ("linear", "log")


@dataclass(frozen=True)
class HilbertSpectrum:
    """Instantaneous frequency and amplitude of ``k`` IMFs at ``n`` vertices.

    Attributes
    ----------
    frequency : (k, n) ndarray
        ``ω_k(v)``, radians per model unit of length (Eq. 23).
    amplitude : (k, n) ndarray
        ``a_k(v)`` (Eq. 21).
    area : (n,) ndarray
        Vertex areas (the lumped mass) used to integrate over the surface.
    resolvable : (n,) ndarray, optional
        Per-vertex resolution limit; default ``π/√A_v`` from ``area``
        (:func:`hht3d.spectral.resolution.resolvable_from_area`).
    """

    frequency: np.ndarray
    amplitude: np.ndarray
    area: np.ndarray
    resolvable: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.frequency.shape != self.amplitude.shape or self.frequency.ndim != 2:
            raise InputError(
                f"frequency {self.frequency.shape} and amplitude {self.amplitude.shape} must both have shape (k, n)"
            )
        if self.area.shape != self.frequency.shape[1:]:
            raise InputError(f"area has shape {self.area.shape}; expected ({self.frequency.shape[1]},)")
        if self.resolvable is None:
            object.__setattr__(self, "resolvable", resolvable_from_area(self.area))
        elif self.resolvable.shape != self.area.shape:
            raise InputError(f"resolvable has shape {self.resolvable.shape}; expected {self.area.shape}")

    @classmethod
    def from_monogenic(cls, surface: Surface, signal: MonogenicSignal) -> "HilbertSpectrum":
        """The spectrum of :func:`hht3d.spectral.monogenic_signal.monogenic`'s result on ``surface``."""
        return cls(signal.frequency, signal.amplitude, surface.mass_diagonal)

    @property
    def resolvable_frequency(self) -> float:
        """The surface's resolution limit: the median over vertices of ``π/√A_v``."""
        return float(np.median(cast(np.ndarray, self.resolvable)))

    @property
    def resolution(self) -> ResolutionReport:
        """Vertex–IMF pairs whose frequency exceeds their vertex's limit, and their share of
        the energy ``a² A_v``: frequencies the surface cannot resolve, reported, not dropped."""
        resolvable = cast(np.ndarray, self.resolvable)
        return resolution_report(self.frequency, resolvable, self._relative_energy() * self.area, self.area)

    @property
    def energy(self) -> np.ndarray:
        """``a_k(v)²`` (k, n)."""
        return self.amplitude**2

    def _relative_energy(self) -> np.ndarray:
        """``(a / max a)²``: the energy's proportions, finite for amplitudes of any magnitude."""
        top = float(np.max(self.amplitude, initial=0.0))
        return (self.amplitude / top) ** 2 if top > 0 else self.energy

    def imf_energy(self) -> np.ndarray:
        """``∫ a_k² dA`` per IMF (k,)."""
        return self.energy @ self.area

    def mean_frequency(self) -> np.ndarray:
        """Energy-weighted mean frequency per IMF, ``∫ a_k² ω_k dA / ∫ a_k² dA`` (k,).

        ``nan`` for an IMF without energy.
        """
        relative = self._relative_energy()
        total = relative @ self.area
        weighted = (relative * self.frequency) @ self.area
        return np.divide(weighted, total, out=np.full_like(total, np.nan), where=total > 0)

    def frequency_limits(self, scale: str = "linear", tail: float = 1e-3) -> tuple[float, float]:
        """Frequencies between which all but ``tail`` of the energy lies at each end.

        With ``scale="log"`` only positive frequencies count.  The limits of
        the figures and the viewer's marginal spectrum.
        """
        frequency = self.frequency.ravel()
        weight = (self._relative_energy() * self.area).ravel()
        keep = (frequency > 0) if scale == "log" else np.isfinite(frequency)
        frequency, weight = frequency[keep], weight[keep]
        order = np.argsort(frequency)
        cumulative = np.cumsum(weight[order])
        if cumulative.size == 0 or cumulative[-1] <= 0:
            raise InputError("no positive instantaneous frequency carries energy; give explicit limits")
        low, high = np.searchsorted(cumulative, [tail * cumulative[-1], (1 - tail) * cumulative[-1]])
        low_f, high_f = frequency[order[low]], frequency[order[min(high, len(order) - 1)]]
        return (float(low_f), float(high_f)) if high_f > low_f else (float(frequency.min()), float(frequency.max()))

    def bin_edges(self, bins: int = 64, scale: str = "linear", limits: tuple[float, float] | None = None) -> np.ndarray:
        """Frequency bin edges (bins + 1,).

        Parameters
        ----------
        bins : int
            Number of bins.
        scale : {"linear", "log"}
            Equal widths or equal ratios.
        limits : (low, high), optional
            Default: ``[0, max ω]`` (linear) or ``[min ω > 0, max ω]`` (log).
        """
        if int(bins) != bins or bins < 1:
            raise InputError(f"bins must be a positive integer, got {bins!r}")
        if scale not in SCALES:
            raise InputError(f"unknown frequency scale {scale!r}; choose one of {SCALES}")
        if limits is None:
            positive = self.frequency[self.frequency > 0]
            if positive.size == 0:
                raise InputError("every instantaneous frequency is 0; give explicit limits")
            limits = (0.0 if scale == "linear" else positive.min(), positive.max())
        low, high = (float(x) for x in limits)
        if not (np.isfinite(low) and np.isfinite(high) and high > low >= 0) or (scale == "log" and low <= 0):
            raise InputError(
                f"frequency limits must satisfy 0 {'<' if scale == 'log' else '<='} low < high, got {limits!r}"
            )
        if scale == "log":
            return np.geomspace(low, high, int(bins) + 1)
        return np.linspace(low, high, int(bins) + 1)

    def distribution(
        self, bins: int = 64, scale: str = "linear", limits: tuple[float, float] | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Space–frequency–energy distribution ``H(ω, v)``.

        Frequencies outside the limits are left out (as in ``numpy.histogram``;
        the last bin includes its right edge).

        Returns
        -------
        edges : (bins + 1,) ndarray
        H : (bins, n) ndarray
            Energy ``a²`` per frequency bin and vertex.
        """
        edges = self.bin_edges(bins, scale, limits)
        index = np.searchsorted(edges, self.frequency, side="right") - 1
        index[self.frequency == edges[-1]] = len(edges) - 2
        inside = (index >= 0) & (index < len(edges) - 1)
        vertex = np.broadcast_to(np.arange(self.frequency.shape[1]), self.frequency.shape)
        h = np.zeros((len(edges) - 1, self.frequency.shape[1]))
        np.add.at(h, (index[inside], vertex[inside]), self.energy[inside])
        return edges, h

    def marginal(
        self, bins: int = 64, scale: str = "linear", limits: tuple[float, float] | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Area-weighted marginal spectrum ``h(ω) = Σ_v A_v H(ω, v)``.

        Returns
        -------
        edges : (bins + 1,) ndarray
        h : (bins,) ndarray
            Energy times area per frequency bin; sums to the total
            :meth:`imf_energy` of the frequencies within the limits.
        """
        edges, h = self.distribution(bins, scale, limits)
        return edges, h @ self.area
