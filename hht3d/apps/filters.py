"""Filtering a surface signal through its Hilbert spectrum (Sec. 5.1, Eqs. 25–26).

The Hilbert–Huang transform writes a signal as (Eq. 25)

    s = Re Σ_k a_k e^{i ∫ω_k} + r_N = Σ_k a_k cos φ_k + r_N,

with local amplitude ``a_k``, phase ``φ_k`` and instantaneous frequency
``ω_k`` of IMF ``k`` at every vertex (:mod:`hht3d.spectral.monogenic_signal`).  A filter is
a gain ``μ(ω)`` applied per vertex and IMF (Eq. 26):

    s' = Σ_k μ(ω_k) a_k cos φ_k + r_N.

Since ``a_k cos φ_k`` equals the IMF ``f_k`` exactly (Eqs. 21–22),
:func:`filter_signal` computes ``s' = Σ_k μ(ω_k) f_k + r_N``; a gain of 1
everywhere returns the signal to round-off.  The residue is never filtered.

Gains
-----
Each gain is a small frozen dataclass, picklable and callable on an array of
frequencies (radians per model unit of length, as :mod:`hht3d.spectral.monogenic_signal`
reports them; a wavelength ``ℓ`` is the frequency ``2π/ℓ``):

=================  ==========================================================
:class:`Constant`      ``μ ≡ value`` (1: identity)
:class:`LowPass`       1 below ``cutoff``, ``stop`` above
:class:`HighBoost`     1 below ``cutoff``, ``factor`` above (high-frequency
                       enhancement)
:class:`BandStop`      ``stop`` inside ``[low, high]``, 1 outside
:class:`BandBoost`     ``factor`` inside ``[low, high]``, 1 outside
                       (band enhancement)
:class:`PiecewiseLinear`  linear through user points ``(ω, μ)``, constant
                       beyond the first and last point
=================  ==========================================================

Edges are sharp by default (``width=0``; a frequency exactly on an edge
counts as below it).  With ``width > 0`` an edge at ``e`` becomes a
raised-cosine transition over ``[e − width/2, e + width/2]``, so that
vertices whose frequency estimate sits near an edge are not switched on and
off by its noise.  :func:`make_gain` builds a gain from a name and
parameters (as a pipeline description would give them).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import InputError
from ..records import Record, Spec, option

__all__ = [
    "Gain",
    "Constant",
    "LowPass",
    "HighBoost",
    "BandStop",
    "BandBoost",
    "PiecewiseLinear",
    "GAINS",
    "make_gain",
    "gains_of",
    "filter_signal",
    "decomposition_parts",
    "evaluate_gain",
]


def _rise(omega: np.ndarray, edge: float, width: float) -> np.ndarray:
    """0 below an edge, 1 above it; a raised cosine over ``edge ± width/2`` when ``width > 0``."""
    if width == 0:
        return (omega > edge).astype(np.float64)
    t = np.clip((omega - edge) / width + 0.5, 0.0, 1.0)
    return 0.5 - 0.5 * np.cos(np.pi * t)


class Gain:
    """Base class of the gains: ``gain(omega)`` returns ``μ(ω)`` with the shape of ``omega``."""

    label = "gain"

    def __call__(self, omega: np.ndarray) -> np.ndarray:
        return self._evaluate(np.asarray(omega, dtype=np.float64))

    def _evaluate(self, omega: np.ndarray) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError


@dataclass(frozen=True)
class Constant(Gain, Record):
    """``μ(ω) = value`` everywhere; ``Constant(1.0)`` leaves the signal unchanged."""

    value: float = option(1.0, "the gain at every frequency")

    def _evaluate(self, omega: np.ndarray) -> np.ndarray:
        return np.full(omega.shape, self.value)


#: Edge frequencies and transition widths, radians per unit length, are non-negative.
_FREQUENCY = Spec("a frequency, radians per unit length", "float", minimum=0)


def _width() -> Any:
    return option(0.0, "width of the raised-cosine transition (0: sharp)", like=_FREQUENCY)


def _edge(doc: str) -> Any:
    """A required edge frequency."""
    return option(dataclasses.MISSING, doc, like=_FREQUENCY)


@dataclass(frozen=True, kw_only=True)
class LowPass(Gain, Record):
    """Keep frequencies up to ``cutoff``, multiply higher ones by ``stop`` (default 0).

    Parameters
    ----------
    cutoff : float
        Edge frequency, radians per unit length (``>= 0``).
    width : float
        Width of the raised-cosine transition centred on ``cutoff`` (0: sharp).
    stop : float
        Gain above the cutoff.
    """

    cutoff: float = _edge("edge frequency, radians per unit length")
    width: float = _width()
    stop: float = option(0.0, "gain above the cutoff")

    def _evaluate(self, omega: np.ndarray) -> np.ndarray:
        return 1.0 + (self.stop - 1.0) * _rise(omega, self.cutoff, self.width)


@dataclass(frozen=True, kw_only=True)
class HighBoost(Gain, Record):
    """High-frequency enhancement: multiply frequencies above ``cutoff`` by ``factor``.

    Parameters
    ----------
    cutoff : float
        Edge frequency, radians per unit length (``>= 0``).
    factor : float
        Gain above the cutoff (e.g. 2.5 as in the paper's Fig. 6); 1 below.
    width : float
        Width of the raised-cosine transition (0: sharp).
    """

    cutoff: float = _edge("edge frequency, radians per unit length")
    factor: float = option(2.0, "gain above the cutoff")
    width: float = _width()

    def _evaluate(self, omega: np.ndarray) -> np.ndarray:
        return 1.0 + (self.factor - 1.0) * _rise(omega, self.cutoff, self.width)


class _Band(Record):
    """A band ``(low, high]``: checked like every record, then ``low < high``."""

    if TYPE_CHECKING:  # the fields of the dataclasses that derive from it
        low: float
        high: float

    def __post_init__(self) -> None:
        super().__post_init__()
        if not self.low < self.high:
            raise InputError(f"a band needs low < high, got low={self.low!r}, high={self.high!r}")


def _band(omega: np.ndarray, low: float, high: float, width: float) -> np.ndarray:
    """1 inside ``(low, high]``, 0 outside, with raised-cosine edges of ``width``."""
    return _rise(omega, low, width) * (1.0 - _rise(omega, high, width))


@dataclass(frozen=True, kw_only=True)
class BandStop(Gain, _Band):
    """Multiply frequencies in the band ``(low, high]`` by ``stop`` (default 0), keep the rest.

    Parameters
    ----------
    low, high : float
        Band edges, radians per unit length, ``0 <= low < high``.
    width : float
        Width of each raised-cosine edge (0: sharp).
    stop : float
        Gain inside the band.
    """

    low: float = _edge("lower band edge, radians per unit length")
    high: float = _edge("upper band edge, radians per unit length")
    width: float = _width()
    stop: float = option(0.0, "gain inside the band")

    def _evaluate(self, omega: np.ndarray) -> np.ndarray:
        return 1.0 + (self.stop - 1.0) * _band(omega, self.low, self.high, self.width)


@dataclass(frozen=True, kw_only=True)
class BandBoost(Gain, _Band):
    """Band enhancement: multiply frequencies in ``(low, high]`` by ``factor``, keep the rest.

    Parameters
    ----------
    low, high : float
        Band edges, radians per unit length, ``0 <= low < high``.
    factor : float
        Gain inside the band.
    width : float
        Width of each raised-cosine edge (0: sharp).
    """

    low: float = _edge("lower band edge, radians per unit length")
    high: float = _edge("upper band edge, radians per unit length")
    factor: float = option(2.0, "gain inside the band")
    width: float = _width()

    def _evaluate(self, omega: np.ndarray) -> np.ndarray:
        return 1.0 + (self.factor - 1.0) * _band(omega, self.low, self.high, self.width)


@dataclass(frozen=True)
class PiecewiseLinear(Gain):
    """A user gain: linear between points ``(ω_j, μ_j)``, constant beyond the ends.

    Parameters
    ----------
    points : sequence of (float, float)
        At least one point; frequencies ``>= 0`` and strictly increasing.
    """

    points: tuple

    def __post_init__(self) -> None:
        try:
            pts = np.asarray(self.points, dtype=np.float64)
        except (TypeError, ValueError):
            raise InputError(f"PiecewiseLinear points must be (frequency, gain) pairs, got {self.points!r}") from None
        if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) == 0:
            raise InputError(
                f"PiecewiseLinear points must be a non-empty list of (frequency, gain) pairs, got shape {pts.shape}"
            )
        if not np.all(np.isfinite(pts)):
            raise InputError("PiecewiseLinear points must be finite")
        if pts[0, 0] < 0 or np.any(np.diff(pts[:, 0]) <= 0):
            raise InputError(
                f"PiecewiseLinear frequencies must be >= 0 and strictly increasing, got {pts[:, 0].tolist()}"
            )
        object.__setattr__(self, "points", tuple(map(tuple, pts.tolist())))

    def _evaluate(self, omega: np.ndarray) -> np.ndarray:
        pts = np.asarray(self.points)
        return np.interp(omega, pts[:, 0], pts[:, 1])


#: Gain classes by name, for configuration files.
GAINS = {
    "constant": Constant,
    "low_pass": LowPass,
    "high_boost": HighBoost,
    "band_stop": BandStop,
    "band_boost": BandBoost,
    "piecewise_linear": PiecewiseLinear,
}


def make_gain(kind: str, **parameters: Any) -> Gain:
    """Build a gain by name (one of :data:`GAINS`) from keyword parameters.

    Parameters
    ----------
    kind : str
        The gain's name, a key of :data:`GAINS` (e.g. ``"low_pass"``, ``"band_stop"``).
    **parameters
        The gain's fields (its class's parameters); a missing required or unknown one is an :class:`InputError`.

    Returns
    -------
    Gain
        The gain, an instance of ``GAINS[kind]``.

    Examples
    --------
    >>> make_gain("band_stop", low=8.0, high=20.0, width=2.0)
    BandStop(low=8.0, high=20.0, width=2.0, stop=0.0)
    """
    if kind not in GAINS:
        raise InputError(f"unknown gain {kind!r}; choose one of {sorted(GAINS)}")
    fields = dataclasses.fields(GAINS[kind])
    unknown = sorted(set(parameters) - {f.name for f in fields})
    if unknown:
        raise InputError(f"gain {kind} has no parameter {unknown[0]!r}; it takes {', '.join(f.name for f in fields)}")
    required = [f.name for f in fields if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING]
    missing = [name for name in required if name not in parameters]
    if missing:
        example = ", ".join(f"{name}: ..." for name in required)
        raise InputError(
            f"gain {kind} needs {' and '.join(missing)}: {{kind: {kind}, {example}}} "
            f"(see help(hht3d.apps.{GAINS[kind].__name__}))"
        )
    return GAINS[kind](**parameters)


def decomposition_parts(decomposition: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(imfs (k, n), residue (n,), frequency (k, n))`` from an HHT result or a tuple."""
    if isinstance(decomposition, tuple):
        if len(decomposition) != 3:
            raise InputError("pass an HHTResult or a tuple (imfs, residue, monogenic)")
        imfs, residue, mono = decomposition
    else:
        try:
            imfs, residue, mono = decomposition.imfs, decomposition.residue, decomposition.monogenic
        except AttributeError:
            raise InputError(
                f"expected an HHTResult or a tuple (imfs, residue, monogenic), got {type(decomposition).__name__}"
            ) from None
    imfs = np.asarray(imfs, dtype=np.float64)
    residue = np.asarray(residue, dtype=np.float64)
    frequency = np.asarray(getattr(mono, "frequency", None), dtype=np.float64)
    if residue.ndim != 1 or imfs.ndim != 2 or imfs.shape[1] != residue.shape[0]:
        raise InputError(f"imfs must have shape (k, n) and the residue (n,), got {imfs.shape} and {residue.shape}")
    if frequency.shape != imfs.shape:
        raise InputError(f"the monogenic frequency has shape {frequency.shape}; the imfs have {imfs.shape}")
    return imfs, residue, frequency


def gains_of(decomposition: Any, gain: Callable[[np.ndarray], Any]) -> np.ndarray:
    """The gains ``μ(ω_k(v))`` (k, n) of a decomposition's instantaneous frequencies.

    Parameters
    ----------
    decomposition : HHTResult or tuple
        An HHT result, or a tuple ``(imfs, residue, monogenic)``.
    gain : callable
        ``gain(frequency)`` the gain ``μ(ω)``, e.g. a :class:`LowPass`.

    Returns
    -------
    (k, n) ndarray
        The gain of each IMF at each vertex.
    """
    _, _, frequency = decomposition_parts(decomposition)
    return evaluate_gain(gain, frequency)


def evaluate_gain(gain: Callable[[np.ndarray], Any], frequency: np.ndarray) -> np.ndarray:
    """``gain(frequency)`` checked: callable, finite, and of the frequencies' shape (a scalar spreads)."""
    if not callable(gain):
        raise InputError(f"gain must be callable on frequencies (e.g. hht3d.apps.LowPass), got {gain!r}")
    mu = np.asarray(gain(frequency), dtype=np.float64)
    if mu.ndim == 0:
        mu = np.full(frequency.shape, float(mu))
    if mu.shape != frequency.shape:
        raise InputError(f"gain returned shape {mu.shape} for frequencies of shape {frequency.shape}")
    if not np.all(np.isfinite(mu)):
        raise InputError("gain returned NaN or infinite values")
    return mu


def filter_signal(decomposition: Any, gain: Callable[[np.ndarray], Any]) -> np.ndarray:
    """Filter a signal through its Hilbert spectrum (Eq. 26).

    Parameters
    ----------
    decomposition : HHTResult or tuple (imfs, residue, monogenic)
        IMFs ``(k, n)``, residue ``(n,)`` and their
        :class:`~hht3d.spectral.monogenic_signal.MonogenicSignal` (its ``frequency`` is used).
    gain : callable
        ``μ(ω)`` evaluated elementwise on the ``(k, n)`` instantaneous
        frequencies: a :class:`Gain` or any function returning an array of
        the same shape (or a scalar).

    Returns
    -------
    (n,) ndarray
        ``s' = Σ_k μ(ω_k) a_k cos φ_k + r_N = Σ_k μ(ω_k) f_k + r_N``.
    """
    imfs, residue, frequency = decomposition_parts(decomposition)
    mu = evaluate_gain(gain, frequency)
    return np.sum(mu * imfs, axis=0) + residue
