"""Sifting: one IMF at a time, with the cancellation guard and the local-mean correction (Sec. 4.1).

Sifting (Huang et al. 1998) finds the local maxima and minima of the current
signal ``h``, interpolates each set by an envelope (:mod:`.envelopes`),
subtracts the envelopes' mean, and repeats until ``h`` is an IMF.

Cancellation guard
------------------
Each extraction of an IMF ``f_k`` from the residue ``r_{k−1}`` is checked by
its *step energy ratio* ``(‖f̃_k‖² + ‖r̃_k‖²) / ‖r̃_{k−1}‖²`` (M-norms of
the fluctuations about the per-component mean), which exceeds 1 exactly when
the new IMF and what is left cancel.  With ``cancellation_tolerance = δ``:
sifting stops before a sift that would push the ratio above ``1 + δ``, and
when already the first sift does, the IMF is extracted again with 4× the
tension (:data:`~hht3d.decomposition.options.GUARD_TENSIONS`, then the harmonic envelope).  Signals whose
extrema are dense and regular (noise, eigenfunctions) never trigger it, so
they keep the thin plate's dyadic scale separation; intermittent signals
(sharp creases on smooth patches) get the tension they need.  The IMFs then
add up without cancelling (per-step ratios multiply up to the total of
:func:`hht3d.decomposition.quality.decomposition_quality`).

Local-mean correction
---------------------
Envelopes through sparse extrema leave a slow part in every IMF: a bump
spanning several of its oscillations that the next IMFs and the residue
then carry with the opposite sign (``benchmarks/results/quality.md``).  An IMF has zero local mean by
definition, so after sifting, the part of ``f_k`` slower than its own
oscillation is found,

    G = (M + t² L M̃⁻¹ L)⁻¹ M,   t = (c d_k)²,   m_k = (3G² − 2G³) f_k,

with ``d_k`` the IMF's scale (its extrema spacing or ``π`` over its RMS
wavenumber, the larger) and ``c = mean_correction``.  ``L`` is the membrane
part of the Laplacian and ``M̃`` the vertex areas floored at
:data:`~hht3d.decomposition.envelopes.MASS_FLOOR` of their median, so the system stays definite on scans
with caps and tiny areas.  ``G`` passes a fraction ``g = 1 / (1 + (c d_k
ω)⁴)`` of frequency ``ω`` and its smoothstep a fraction ``3g² − 2g³``, sharper
around ``g = ½``: at the IMF's own
``ω ≈ π/d_k`` (``c = 0.6``) 1.5% (``G`` alone: 7%), at a third of it 95%
(86%).  One more numeric factorization per IMF, on the envelopes' pattern,
and three solves.

The IMF's mean on each connected component moves to the residue too, so
every IMF has zero mean and the energy ratio and the index of orthogonality
add up to 1 (:mod:`hht3d.decomposition.quality`):

    f_k ← f̃_k − m̃_k      (tildes: fluctuations about the per-component mean).

IMFs still *leak* (IO +0.04 to +0.30 on the models, as before this filter):
a share of each IMF's own-scale content stays in the residue and returns in
the next IMF.  Moving only the share of ``m_k`` that leaves the IMF
orthogonal to the rest brought IO within ±0.12, but by adding cancelling
cross terms, and it recovered known components worse
(``benchmarks/results/design_notes.md``, "Leakage").
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any, cast

import numpy as np

from ..errors import NumericalError
from ..geometry.signals import fluctuation, fluctuation_energy
from ..geometry.surface import Surface
from .envelopes import EnvelopeSolver
from .extrema import active_extrema, extrema_spacing
from .options import EMDOptions

__all__ = ["Sifter", "RFG_THRESHOLDS"]

#: Rilling, Flandrin & Gonçalvès (2003) thresholds ``(θ₁, θ₂, α)`` of the ``"rfg"`` stopping rule.
RFG_THRESHOLDS = (0.05, 0.5, 0.05)


@dataclass
class _Sifted:
    """One extraction attempt: the IMF candidate and how it was sifted."""

    imf: np.ndarray
    sifts: int
    counts: tuple[int, int]
    value: float
    stop: str
    step_energy_ratio: float


class Sifter:
    """Extracts IMFs one at a time from a residue (Sec. 4.1, module notes)."""

    def __init__(self, surface: Surface, options: EMDOptions, backend: str | None):
        self.surface = surface
        self.options = options
        self.solver = EnvelopeSolver(surface, backend)
        self.mass = surface.mass_diagonal
        self.max_constraint_error = 0.0
        self.n_sifts = 0

    def extrema(self, h: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Maximum and minimum masks plus the mask of components lacking either."""
        return active_extrema(self.surface, h, self.options)

    def envelopes(
        self, h: np.ndarray, is_max: np.ndarray, is_min: np.ndarray, passive: np.ndarray, tension: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """Upper and lower envelopes (Eq. 11 for ``τ = 0``) through the extrema."""
        return (self._envelope(h, is_max, passive, tension), self._envelope(h, is_min, passive, tension))

    def _envelope(self, h: np.ndarray, extrema: np.ndarray, passive: np.ndarray, tension: float) -> np.ndarray:
        constrained = extrema | passive
        g = self.solver.solve(h, constrained, tension, extrema_spacing(self.surface, extrema.sum()))
        scale = np.max(np.abs(h[constrained]))
        if scale > 0:
            error = np.max(np.abs(g[constrained] - h[constrained])) / scale
            self.max_constraint_error = max(self.max_constraint_error, float(error))
        g[constrained] = h[constrained]  # exact, so passive components give exactly zero IMFs
        return g

    def corrected(self, imf: np.ndarray, info: dict) -> np.ndarray:
        """``f_k − f̄_k − m̃_k``: the IMF without its mean and its local mean (module notes).

        ``info`` records ``mean_share`` (``‖removed‖ / ‖f_k‖``).  ``d_k`` is the larger of the
        extrema spacing and ``π / ω_k`` with ``ω_k² = f_kᵀ L f_k / f_kᵀ M f_k`` (the RMS
        wavenumber): extrema crowding in one region overstate the scale, spikes at bad triangles
        understate it, and only an understated scale is harmful (the filter then takes the IMF
        itself).
        """
        c = self.options.mean_correction
        stiffness = float(imf @ (self.surface.stiffness @ imf))
        if c is None or not stiffness > 0:
            return imf
        e = self.solver.energies
        spacing = max(
            extrema_spacing(self.surface, info["n_maxima"] + info["n_minima"]),
            np.pi * np.sqrt(float(np.dot(self.mass * imf, imf)) / stiffness),
        )
        data = (c * spacing) ** 4 * e.smoothing
        data[e.diagonal] += self.mass
        try:
            factor = self.solver.factorize(e.matrix(data))
            g1 = factor.solve(self.mass * imf)
            g2 = factor.solve(self.mass * g1)
            slow = 3 * g2 - 2 * factor.solve(self.mass * g2)  # smoothstep 3G² − 2G³ of the filter G
        except NumericalError:  # not definite in floating point: leave the IMF as sifted
            return imf
        info["factorizations"] += 1
        removed = imf - fluctuation(self.surface, imf) + fluctuation(self.surface, slow)
        info["mean_share"] = float(np.sqrt(self.energy(removed) / max(self.energy(imf), 1e-300)))
        return imf - removed

    def energy(self, f: np.ndarray) -> float:
        """``‖f̃‖²_M`` of the fluctuation about the per-component mean."""
        return fluctuation_energy(self.surface, f)

    def imf(self, residue: np.ndarray) -> tuple[np.ndarray, dict] | None:
        """The next IMF, sifted and :meth:`corrected`, and its diagnostics; ``None`` when the residue
        has < 2 maxima or minima."""
        sifted = self.sifted(residue)
        if sifted is None:
            return None
        self.n_sifts += sifted[1]["sifts"]
        return self.corrected(*sifted), sifted[1]

    def totals(self) -> dict:
        """Run totals for ``EMDResult.info``: ``sifts``, ``max_constraint_error``, ``factorizations``,
        ``backend``."""
        return {
            "sifts": self.n_sifts,
            "max_constraint_error": self.max_constraint_error,
            "factorizations": self.solver.n_factorizations,
            "backend": self.solver.backend,
        }

    def sifted(self, residue: np.ndarray) -> tuple[np.ndarray, dict] | None:
        """Sift one IMF out of ``residue``; ``None`` when it has < 2 maxima or minima.

        Tries the tensions of the cancellation guard in turn and keeps the
        first extraction within the tolerance, else the one that cancels least.
        A retry whose envelope system is not numerically definite (the
        membrane ``L`` of caps with angles near 180° can be so) is skipped.
        """
        o = self.options
        start, factorizations = time.perf_counter(), self.solver.n_factorizations
        reference = self.energy(residue)
        best, attempts, skipped = None, 0, []
        for tension in o.tensions:
            try:
                sifted = self._sift(residue, tension, reference)
            except NumericalError:
                if best is None:
                    raise
                skipped.append(None if math.isinf(tension) else tension)
                continue
            if sifted is None:
                return None
            attempts += 1
            if best is None or sifted.step_energy_ratio < best[0].step_energy_ratio:
                best = (sifted, tension)
            if o.cancellation_tolerance is None or sifted.step_energy_ratio <= 1 + o.cancellation_tolerance:
                break
        sifted, tension = cast(tuple[Any, float], best)
        return sifted.imf, {
            "sifts": sifted.sifts,
            "n_maxima": sifted.counts[0],
            "n_minima": sifted.counts[1],
            "stopping_value": float(sifted.value),
            "stop": sifted.stop,
            "envelope": "harmonic" if math.isinf(tension) else ("biharmonic" if tension == 0 else "tension"),
            "tension": None if math.isinf(tension) else tension,
            "attempts": attempts,
            "skipped_tensions": skipped,
            "step_energy_ratio": sifted.step_energy_ratio,
            "factorizations": self.solver.n_factorizations - factorizations,
            "seconds": time.perf_counter() - start,
        }

    def _sift(self, residue: np.ndarray, tension: float, reference: float) -> _Sifted | None:
        """Sift with one tension until the stopping rule, the guard or the sift cap ends it."""
        o = self.options
        h, sifts, stable, previous, step = residue, 0, 0, None, 1.0
        value = float(np.inf) if o.stopping == "sd" else 0.0
        while True:
            is_max, is_min, passive = self.extrema(h)
            counts = (int(is_max.sum()), int(is_min.sum()))
            if min(counts) < 2:
                if sifts == 0:
                    return None
                stop = "extrema"
                break
            if o.stopping == "s_number":
                stable = stable + 1 if counts == previous else 0
                previous, value = counts, stable
            stop = self._stopped(sifts, stable, value)
            if stop:
                break
            upper, lower = self.envelopes(h, is_max, is_min, passive, tension)
            mean = 0.5 * (upper + lower)
            if o.stopping == "rfg":
                value = _rfg_excess(mean, 0.5 * np.abs(upper - lower), self.mass)
                if value <= 0:
                    stop = "rfg"
                    break
            candidate = h - mean
            candidate_step = (self.energy(candidate) + self.energy(residue - candidate)) / reference
            if o.cancellation_tolerance is not None and sifts > 0 and candidate_step > 1 + o.cancellation_tolerance:
                stop = "guard"
                break
            if o.stopping == "sd":  # Cauchy criterion: |h_k-1 - h_k|² / |h_k-1|²
                value = float(np.dot(self.mass * mean, mean) / np.dot(self.mass * h, h))
            h, step = candidate, candidate_step
            sifts += 1
            if o.stopping == "fixed":
                value = sifts
        return _Sifted(h, sifts, counts, value, stop, step)

    def _stopped(self, sifts: int, stable: int, value: float) -> str:
        """The rule that ends sifting before the next sift, or ``""``."""
        o = self.options
        if o.stopping == "sd" and value < o.sd_threshold:
            return "sd"
        if o.stopping == "s_number" and stable >= o.s_number:
            return "s_number"
        if o.stopping == "fixed" and sifts >= o.fixed_sifts:
            return "fixed"
        return "max_sifts" if sifts >= o.max_sifts else ""


def _rfg_excess(mean: np.ndarray, amplitude: np.ndarray, mass: np.ndarray) -> float:
    """How far ``h`` is from an IMF by Rilling, Flandrin & Gonçalvès (2003); ``<= 0`` means done.

    With ``σ = |mean| / amplitude``, ``h`` is an IMF when ``σ < θ₁`` on all but
    a fraction ``α`` of the area and ``σ < θ₂`` everywhere
    (:data:`RFG_THRESHOLDS`).  Returns the larger of the two excesses.
    """
    theta1, theta2, alpha = RFG_THRESHOLDS
    sigma = np.divide(np.abs(mean), amplitude, out=np.full_like(mean, np.inf), where=amplitude > 0)
    sigma[(mean == 0) & (amplitude == 0)] = 0.0
    above = float(np.sum(mass[sigma > theta1]) / np.sum(mass))
    return max(above - alpha, float(np.max(sigma)) - theta2)
