"""How trustworthy a decomposition is: IMFs that add up without cancelling.

EMD writes a signal as IMFs plus a residue (Eq. 1).  That sum holds for any
IMFs, so it says nothing about their quality.  What does is how the energy
splits: with ``M`` the lumped mass, ``x̄`` the area-weighted mean of ``x`` on
each connected component, ``f_k`` the IMFs and ``r`` the residue,

* **energy ratio** ``(Σ_k f_kᵀ M f_k + r̃ᵀ M r̃) / s̃ᵀ M s̃`` with ``r̃ = r − r̄``
  and ``s̃ = s − s̄``: 1 when the IMFs and the residue are mutually
  M-orthogonal, large when they overshoot and cancel each other;
* **index of orthogonality** (Huang et al. 1998) ``IO = Σ_{j≠k} x_jᵀ M x_k /
  s̃ᵀ M s̃`` over the IMFs and ``r̃``: 0 when orthogonal, negative when they
  cancel, positive when they *leak* (one component split over neighbouring
  IMFs).  A total near 0 can hide both, so the positive and the negative
  cross terms are also summed apart (``io_leaking >= 0``, ``io_cancelling <=
  0``; their sum is ``IO``);
* **energy share** of each IMF and of the residue, ``x_kᵀ M x_k`` over their
  sum;
* **signal spike** ``max|s̃| / p99|s̃|``: large where the signal itself is
  broken, typically curvature at vertices with tiny areas or needle
  triangles;
* **a dominant IMF**: with two IMFs or more, one holding more than
  :data:`DOMINANT_SHARE_LIMIT` of the energy, so the others say little;
* **aliased area** (of an HHT, :func:`aliasing_warnings`): the share of the
  surface's area where an IMF's instantaneous frequency is above the
  resolution limit ``π/√A_v`` (:mod:`hht3d.spectral.resolution`).

A clean line must not hide a bad result: a bunny scan's IMF 1 once held 97% of
the energy with 24% of its frequencies aliased, and no figure above flagged it;
the last two do.

:func:`decomposition_quality` computes them and turns the ones past a
documented limit into warnings that name the likely cause and the option to
try.  :class:`QualityWarning` is the warning category the core emits.
"""

from __future__ import annotations

import contextlib
import contextvars
import warnings
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np

from ..errors import InputError
from ..geometry.signals import fluctuation
from ..geometry.surface import Surface
from ..geometry.validation import check_surface
from .display import Facts, share_text, summary_html

__all__ = [
    "Quality",
    "QualityWarning",
    "quality_warnings_muted",
    "warn_quality",
    "decomposition_quality",
    "quality_facts",
    "decomposition_html",
    "decomposition_repr",
    "ENERGY_RATIO_LIMIT",
    "ORTHOGONALITY_LIMIT",
    "LEAKAGE_LIMIT",
    "SPIKE_LIMIT",
    "DOMINANT_SHARE_LIMIT",
    "ALIASED_AREA_LIMIT",
    "aliasing_warnings",
]

#: Energy ratio above which a decomposition is reported as cancelling.
ENERGY_RATIO_LIMIT = 1.5
#: Index of orthogonality below which a decomposition is reported as cancelling.
ORTHOGONALITY_LIMIT = -0.25
#: Index of orthogonality above which a decomposition is reported as leaking, the mirror of
#: :data:`ORTHOGONALITY_LIMIT`.  Huang et al. (1998) call ``|IO| < 0.05-0.1`` good in 1-D; on
#: surfaces the defaults measure +0.04 to +0.30 (``benchmarks/results/quality.md``), so a limit of
#: 0.1 would flag 9 of the 11 models and say nothing.
LEAKAGE_LIMIT = 0.25
#: ``max|s̃| / p99|s̃|`` above which the signal is reported as spiking.
SPIKE_LIMIT = 20.0
#: Energy share above which one IMF of two or more is reported as dominant.  On the shipped spot
#: model (mean curvature) IMF 1 holds 60% with two or three IMFs.  White noise, the flattest
#: spectrum, gives IMF 1 the top octave of wavenumbers, 3/4 of a surface's modes: measured 90-92%
#: on icospheres of 162 to 10242 vertices, so a limit of 90% would flag every noisy scan for being
#: noisy.  Past 95% less than 5% is left to every other IMF and the residue together, and asking
#: for more than one IMF bought nothing (the review's bunny scan: 97%).
DOMINANT_SHARE_LIMIT = 0.95
#: Share of the surface's area where an IMF's frequency is above the resolution limit, past which
#: the IMF is reported as aliased.  An IMF resolved by its mesh stays well below it (spot: 0.25% for
#: IMF 1, 0 for the others); white noise, whose finest IMF sits at the limit, reaches 3-5% on
#: icospheres of 162 and 642 vertices; a pattern of 60 rad/unit on a grid whose limit is 47 puts 20%
#: of IMF 1 above.  Past 5% the frequencies above are no longer the scatter of noise at the limit
#: but a pattern finer than the mesh (the review's bunny: 24%).
ALIASED_AREA_LIMIT = 0.05


class QualityWarning(UserWarning):
    """A result was computed but should not be trusted as it is (see its message)."""


_MUTED = contextvars.ContextVar("hht3d_quality_warnings_muted", default=False)


@contextlib.contextmanager
def quality_warnings_muted() -> Iterator[None]:
    """Issue no :class:`QualityWarning` inside the block, in this thread only.

    ``warnings.catch_warnings`` swaps the process-wide filter list, so under a
    threaded scheduler one task leaving the block unmuted another task's
    warnings; a context variable is private to its thread.
    """
    token = _MUTED.set(True)
    try:
        yield
    finally:
        _MUTED.reset(token)


def warn_quality(message: str, stacklevel: int) -> None:
    """Issue ``message`` as a :class:`QualityWarning` unless muted (:func:`quality_warnings_muted`)."""
    if not _MUTED.get():
        warnings.warn(message, QualityWarning, stacklevel=stacklevel + 1)


@dataclass(frozen=True)
class Quality:
    """Quality figures of one decomposition (module notes).

    Attributes
    ----------
    energy_ratio : float
    orthogonality_index : float
        ``io_leaking + io_cancelling``.
    io_leaking, io_cancelling : float
        Sums of the positive and of the negative cross terms of ``IO``.
    energy_share : (k + 1,) ndarray
        Share of each IMF, then of the residue; sums to 1.
    signal_spike : float
        ``max|s̃| / p99|s̃|`` of the decomposed signal.
    warnings : tuple of str
        One sentence per figure past its limit; empty when all are fine.
    """

    energy_ratio: float
    orthogonality_index: float
    io_leaking: float
    io_cancelling: float
    energy_share: np.ndarray
    signal_spike: float
    warnings: tuple[str, ...] = ()

    @property
    def ok(self) -> bool:
        """True when no figure is past its limit."""
        return not self.warnings

    def summary(self) -> str:
        """One line: ``energy ratio 1.12, IO -0.06 (+0.03 leaking, -0.09 cancelling), spike 3.1``
        plus ``; WARNING: ...``."""
        text = (
            f"energy ratio {self.energy_ratio:.3g}, IO {self.orthogonality_index:.3g} "
            f"({self.io_leaking:+.2g} leaking, {self.io_cancelling:+.2g} cancelling), "
            f"spike {self.signal_spike:.3g}"
        )
        return text + "".join(f"; WARNING: {w}" for w in self.warnings)

    def with_warnings(self, extra: tuple[str, ...]) -> Quality:
        """These figures with the warnings ``extra`` added (an HHT's :func:`aliasing_warnings`)."""
        return replace(self, warnings=self.warnings + tuple(extra))

    def __repr__(self) -> str:
        return (
            f"Quality(energy ratio {self.energy_ratio:.3g}, IO {self.orthogonality_index:.3g}, "
            f"{'ok' if self.ok else f'{len(self.warnings)} warning(s)'})"
        )

    def _repr_html_(self) -> str:
        return decomposition_html("Quality", [], len(self.energy_share) - 1, {}, self)

    def as_dict(self) -> dict:
        """Plain numbers and strings, for JSON summaries."""
        return {
            "energy_ratio": self.energy_ratio,
            "orthogonality_index": self.orthogonality_index,
            "io_leaking": self.io_leaking,
            "io_cancelling": self.io_cancelling,
            "energy_share": [float(x) for x in self.energy_share],
            "signal_spike": self.signal_spike,
            "warnings": list(self.warnings),
        }


def _spike(s: np.ndarray) -> float:
    magnitude = np.abs(s)
    p99 = float(np.percentile(magnitude, 99))
    top = float(magnitude.max())
    return top / p99 if p99 > 0 else (1.0 if top == 0 else float("inf"))


def decomposition_quality(surface: Surface, signal: np.ndarray, imfs: np.ndarray, residue: np.ndarray) -> Quality:
    """Energy ratio, IO, energy shares and signal spike of ``signal = Σ imfs + residue``.

    Parameters
    ----------
    surface : Surface
        Supplies the lumped mass ``M`` and the connected components.
    signal : (n,) array_like
    imfs : (k, n) array_like
        ``k`` may be 0.
    residue : (n,) array_like

    Returns
    -------
    Quality
        A constant signal has ratio 1 and IO 0 (nothing to split).
    """
    check_surface(surface)
    s = np.asarray(signal, dtype=np.float64)
    f = np.asarray(imfs, dtype=np.float64).reshape(-1, surface.n_vertices)
    r = np.asarray(residue, dtype=np.float64)
    if s.shape != (surface.n_vertices,) or r.shape != s.shape:
        raise InputError(f"signal and residue must have shape ({surface.n_vertices},), got {s.shape} and {r.shape}")
    scale = max(float(np.abs(s).max(initial=0.0)), float(np.abs(f).max(initial=0.0)), float(np.abs(r).max()))
    if scale > 0:  # every figure is scale-free; this keeps signals near 1e±200 from overflowing
        s, f, r = s / scale, f / scale, r / scale
    s_tilde = fluctuation(surface, s)
    parts = np.vstack([f, fluctuation(surface, r)[None]])
    mass = surface.mass_diagonal
    gram = (parts * mass) @ parts.T
    reference = float(s_tilde @ (mass * s_tilde))
    energies = np.diag(gram)
    total = float(energies.sum())
    if reference <= 0:
        return Quality(1.0, 0.0, 0.0, 0.0, np.r_[np.zeros(len(f)), 1.0], 1.0)
    ratio = total / reference
    cross = gram - np.diag(energies)
    leaking, cancelling = float(cross[cross > 0].sum() / reference), float(cross[cross < 0].sum() / reference)
    io = leaking + cancelling
    share = energies / total if total > 0 else np.r_[np.zeros(len(f)), 1.0]
    spike = _spike(s_tilde)
    return Quality(ratio, io, leaking, cancelling, share, spike, _warnings(ratio, io, spike, share[:-1]))


def _warnings(ratio: float, io: float, spike: float, imf_shares: np.ndarray) -> tuple[str, ...]:
    found = []
    if len(imf_shares) > 1 and float(imf_shares.max()) > DOMINANT_SHARE_LIMIT:
        k = int(imf_shares.argmax())
        found.append(
            f"IMF {k + 1} holds {100 * imf_shares[k]:.3g}% of the energy (> {100 * DOMINANT_SHARE_LIMIT:.3g}%), "
            "so the other IMFs say little: the signal is dominated by its finest scale (noise, or a "
            "pattern near the mesh's resolution) or the sifting stopped early; smooth the signal, "
            "or try EEMD (ensemble_size)"
        )
    if ratio > ENERGY_RATIO_LIMIT or io < ORTHOGONALITY_LIMIT:
        found.append(
            f"the IMFs cancel each other (energy ratio {ratio:.3g} > {ENERGY_RATIO_LIMIT}, "
            f"or IO {io:.3g} < {ORTHOGONALITY_LIMIT}): envelopes overshoot between sparse "
            "extrema; keep the default envelope and cancellation guard, or try EEMD "
            "(ensemble_size) or a higher emd option tension"
        )
    if io > LEAKAGE_LIMIT:
        found.append(
            f"neighbouring IMFs share content (IO {io:.3g} > {LEAKAGE_LIMIT}): a component is split "
            "over several IMFs; read adjacent IMFs together, or try EEMD (ensemble_size)"
        )
    if spike > SPIKE_LIMIT:
        found.append(
            f"the signal spikes to {spike:.3g}x its 99th percentile: likely tiny-area, needle "
            "or cap triangles; use the curvature signals with their default min_area, or "
            "clean or remesh the surface"
        )
    return tuple(found)


def aliasing_warnings(area_above: np.ndarray | Sequence[float], limit: float) -> tuple[str, ...]:
    """One warning per IMF whose share of the surface's area with frequencies above the resolution
    limit (``area_above[k]``, :attr:`hht3d.spectral.resolution.ResolutionReport.area_per_signal`)
    exceeds :data:`ALIASED_AREA_LIMIT`; ``limit`` is the median ``π/√A_v``, for the message."""
    return tuple(
        f"IMF {k + 1} has {100 * share:.3g}% of the area above the resolution limit "
        f"(> {100 * ALIASED_AREA_LIMIT:.3g}%, median π/√A = {limit:.4g}): its frequencies there are "
        "finer than the mesh and aliased; remesh finer, smooth the signal, or read that IMF's "
        "frequencies as a lower bound"
        for k, share in enumerate(area_above)
        if share > ALIASED_AREA_LIMIT
    )


def quality_facts(quality: Quality) -> list[tuple[str, str]]:
    """The quality figures of :class:`~hht3d.decomposition.quality.Quality`, as labelled text."""
    return [
        ("energy ratio", f"{quality.energy_ratio:.3g}"),
        (
            "index of orthogonality",
            f"{quality.orthogonality_index:.3g} ({quality.io_leaking:+.2g} leaking, "
            f"{quality.io_cancelling:+.2g} cancelling)",
        ),
        ("signal spike", f"{quality.signal_spike:.3g}"),
        ("quality", "ok" if quality.ok else f"{len(quality.warnings)} warning(s)"),
    ]


def decomposition_html(
    title: str, facts: Facts, n_imfs: int, columns: Mapping[str, Sequence[str]], quality: Quality | None
) -> str:
    """:func:`summary_html` of a decomposition: the ``facts``, then with ``quality`` its figures, and a
    table of one row per IMF (its ``columns``, then its energy share), then the residue's share."""
    header = ["IMF", *columns]
    rows = [[str(k + 1), *(column[k] for column in columns.values())] for k in range(n_imfs)]
    if quality is None:
        return summary_html(title, facts, [(header, rows)])
    shares = [f"{x:.1%}" for x in quality.energy_share]
    rows = [[*r, share] for r, share in zip(rows, shares)] + [["residue", *[""] * len(columns), shares[-1]]]
    tables = [([*header, "energy share"], rows)]
    return summary_html(title, [*facts, *quality_facts(quality)], tables, quality.warnings)


def decomposition_repr(name: str, text: str, quality: Quality | None) -> str:
    """``name(text, shares 61.2% 30.1% + residue 8.7%, quality ok)``; without ``quality``, ``name(text)``."""
    if quality is None:
        return f"{name}({text})"
    state = "quality ok" if quality.ok else f"{len(quality.warnings)} quality warning(s)"
    return f"{name}({text}, shares {share_text(quality.energy_share)}, {state})"
