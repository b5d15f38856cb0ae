"""Empirical mode decomposition (EMD) of signals on surfaces (Sec. 3.1, 4.1).

A signal ``f`` is split into intrinsic mode functions (IMFs) and a residue,

    f = Σ_k f_k + r_N                                              (Eq. 1)

one IMF at a time, by one of the :data:`METHODS`: *sifting* (Huang et al.
1998; :mod:`.sifting`): find the local maxima and minima of the current
signal ``h``, interpolate each set by a smooth envelope, subtract the
envelopes' mean, repeat until ``h`` is an IMF; or *iterative filtering*
(:mod:`.filtering`): a fixed high-pass of the residue whose cut comes from
its extrema spacing.  Either continues on the residue.

The steps live in their own modules: extrema (:mod:`.extrema`), envelopes
(:mod:`.envelopes`), sifting with the cancellation guard and the local-mean
correction (:mod:`.sifting`), iterative filtering (:mod:`.filtering`),
settings (:mod:`.options`), ensemble EMD (:mod:`.ensemble`) and the quality
figures (:mod:`.quality`).  A method is a class built from
``(surface, options, backend)`` whose ``imf(residue)`` returns the next IMF
and its diagnostics, or ``None`` when the residue has too few extrema, with
its ``solver`` and ``totals()``.

Components
----------
A connected component without a maximum or without a minimum (a monotone or
constant patch, or an isolated vertex) has no envelope; all of its vertices
are then constrained in both envelopes, so their mean envelope is the signal
itself: such a component contributes nothing to the IMFs and stays in the
residue.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from .. import linalg
from ..errors import InputError
from ..geometry.signals import fluctuation, fluctuation_energy
from ..geometry.surface import Surface
from ..geometry.validation import check_signal, check_surface
from .filtering import Filterer
from .multiresolution import MultilevelFilterer, uses_levels
from .options import EMDOptions
from .quality import Quality, decomposition_html, decomposition_quality, decomposition_repr, warn_quality
from .sifting import Sifter

__all__ = ["EMDResult", "emd", "result_with_quality", "METHOD_CLASSES"]

#: The class of each decomposition method of :data:`~hht3d.decomposition.options.METHODS` (module notes).
METHOD_CLASSES: dict[str, type[Sifter] | type[Filterer]] = {"sifting": Sifter, "filtering": Filterer}

#: A signal whose deviation from its per-component mean is below this fraction
#: of its magnitude is constant up to round-off and is not decomposed.
FLAT_RTOL = 1e3 * np.finfo(np.float64).eps


@dataclass
class EMDResult:
    """The outcome of :func:`emd` or :func:`eemd`.

    Attributes
    ----------
    imfs : (k, n) ndarray
        Intrinsic mode functions, finest first; ``k`` may be 0.
    residue : (n,) ndarray
        ``signal − imfs.sum(axis=0)``, kept apart from the IMFs (Eq. 1).
    info : dict
        Diagnostics.  ``"imfs"`` is a list with one dict per IMF (``sifts``,
        ``n_maxima``, ``n_minima`` of the IMF, ``stopping_value`` reached,
        ``stop`` — why sifting stopped: ``"sd"``, ``"rfg"``, ``"s_number"``,
        ``"fixed"``, ``"max_sifts"``, ``"extrema"`` or ``"guard"`` —,
        ``envelope`` and ``tension`` used, ``attempts`` of the cancellation
        guard and ``skipped_tensions`` whose systems were not definite, ``step_energy_ratio``,
        ``mean_share`` (norm of the removed
        local mean over the IMF's), ``factorizations``, ``seconds``);
        totals ``sifts``, ``factorizations``, ``seconds``; ``backend``;
        ``stop_reason``; ``max_constraint_error`` (relative envelope error at
        the extrema) and the options used.
    quality : Quality, optional
        Energy ratio, index of orthogonality and warnings
        (:func:`hht3d.decomposition.quality.decomposition_quality`).
    levels : tuple of (int, ndarray, ndarray or None, ndarray or None)
        With the hierarchy (:mod:`.multiresolution`): each IMF on the level it was filtered on, as
        ``(level, values, source, potential)`` (on level 0 ``values`` is the IMF's row of ``imfs``,
        not a copy); when the filter was a polynomial, ``potential`` is
        the IMF's Riesz potential on that level (to ``POTENTIAL_TOLERANCE``) and ``source`` the
        signal whose polynomial gives it to any other tolerance (both ``None`` otherwise); empty
        without the hierarchy.
    """

    imfs: np.ndarray
    residue: np.ndarray
    info: dict
    quality: Quality | None = None
    levels: tuple = ()

    @property
    def n_imfs(self) -> int:
        """Number of IMFs."""
        return len(self.imfs)

    def __repr__(self) -> str:
        return decomposition_repr("EMDResult", f"{self.n_imfs} IMFs of {len(self.residue):,} vertices", self.quality)

    def _repr_html_(self) -> str:
        facts = [("vertices", f"{len(self.residue):,}"), ("IMFs", str(self.n_imfs))]
        facts += [
            (key.replace("_", " "), str(self.info[key]))
            for key in ("stop_reason", "sifts", "backend")
            if key in self.info
        ]
        per_imf = self.info.get("imfs") or [{}] * self.n_imfs
        columns = {
            label: [str(imf.get(key, "")) for imf in per_imf]
            for label, key in (("sifts", "sifts"), ("maxima", "n_maxima"), ("minima", "n_minima"), ("stop", "stop"))
        }
        return decomposition_html("EMDResult", facts, self.n_imfs, columns, self.quality)


def emd(
    surface: Surface,
    signal: np.ndarray,
    options: EMDOptions | dict | None = None,
    *,
    backend: str | None = None,
    **overrides: Any,
) -> EMDResult:
    """Empirical mode decomposition of a signal on a surface (Sec. 4.1, Eq. 1).

    Parameters
    ----------
    surface : Surface
        Mesh or point cloud; its stiffness ``L`` and lumped mass ``M`` define
        the envelopes.
    signal : (n,) array_like
        One finite value per vertex.
    options : EMDOptions or dict, optional
        The settings below, as a record (presets: :data:`~hht3d.decomposition.options.EMD_DEFAULTS`,
        :data:`~hht3d.decomposition.options.PAPER_OPTIONS`) or a dict; default
        :data:`~hht3d.decomposition.options.EMD_DEFAULTS`.
    backend : str, optional
        Sparse solver of :mod:`hht3d.linalg`; default the fastest installed.
    **overrides
        Settings that replace those of ``options``:

    max_imfs : int
        At most this many IMFs (0 returns the signal as residue).
    stopping : {"sd", "rfg", "s_number", "fixed"}
        When sifting an IMF stops:

        ``"sd"`` (default)
            Cauchy-type criterion of Huang et al. (1998) in the summed form
            used by MATLAB's ``emd`` (``SiftRelativeTolerance``):
            ``SD = ∫(h_{k−1} − h_k)² dA / ∫h_{k−1}² dA < sd_threshold``.
        ``"rfg"``
            Rilling, Flandrin & Gonçalvès (2003): the mean envelope is small
            against the mode amplitude, ``|m|/a < 0.05`` on all but 5% of the
            area and ``< 0.5`` everywhere.  Sifts 5–10× more often than
            ``"sd"`` without less cancellation on real meshes.
        ``"s_number"``
            Huang et al. (2003): the numbers of maxima and minima stay
            unchanged for ``s_number`` consecutive sifts (zero crossings, the
            1-D rule's other count, have no vertex analogue and are not used).
        ``"fixed"``
            Exactly ``fixed_sifts`` sifts.

        Every rule is capped at ``max_sifts`` sifts, and sifting also stops
        when the signal has fewer than 2 maxima or 2 minima, or by the
        cancellation guard.
    sd_threshold : float
        Default 0.2 (Huang et al. 1998 suggest 0.2–0.3; MATLAB uses 0.2).
    s_number : int
        Default 4 (Huang et al. 2003 recommend 4–8).
    fixed_sifts : int
        Default 10 (Wu & Huang 2009 use 10 sifts in EEMD).
    max_sifts : int
        Cap on sifts per IMF, default 50.
    envelope : {"tension", "biharmonic", "harmonic"}
        Interpolant through the extrema (:mod:`.envelopes`): thin plate in
        tension (default), the paper's thin plate ``L M⁻¹ L g = 0`` (Eqs. 8,
        11) or the membrane ``L g = 0``.
    tension : float
        ``τ`` of the tension envelope, relative to the extrema spacing;
        default 3.
    cancellation_tolerance : float or None
        The guard of :mod:`.sifting`: the largest step energy ratio
        ``1 + δ`` one IMF extraction may reach before more tension is tried;
        default ``δ = 0.05``.  ``None`` switches the guard off.
    mean_correction : float or None
        ``c`` of the local-mean correction (:mod:`.sifting`): each IMF's
        mean and its part slower than ``c`` times its extrema spacing move
        to the residue; default 0.6, ``None`` off.  :data:`~hht3d.decomposition.options.PAPER_OPTIONS` is the
        paper's method.
    extrema : {"strict", "relaxed"}
        Extremum rule of :func:`local_extrema`: 1-ring (default) or the
        relaxed ``ring``-ring rule with fraction ``ratio`` (Sec. 5.2).
    ring, ratio : int, float
        Used with ``extrema="relaxed"``; defaults 2 and 0.8 as in Sec. 5.2.
    boundary_extrema : bool
        Whether vertices on an open boundary may be extrema.  Default
        ``False``: like the mirrored ends of 1-D EMD codes, a boundary creates
        no extremum, so a trend across an open surface stays in the residue
        (with the Neumann envelopes of :mod:`.envelopes`).  ``True`` is the
        paper's rule (:data:`~hht3d.decomposition.options.PAPER_OPTIONS`).
    energy_threshold : float
        Decomposition stops when the residue's fluctuation energy
        ``∫(r − r̄)² dA`` (``r̄`` its mean per component) falls below this
        fraction of the signal's; default 1e-8.

    Returns
    -------
    EMDResult
        ``imfs`` (k, n), ``residue`` (n,), ``info`` diagnostics and
        ``quality``; a :class:`~hht3d.decomposition.quality.QualityWarning` is issued
        when the quality figures are past their limits.

    Notes
    -----
    The decomposition stops at ``max_imfs`` IMFs, when the residue has fewer
    than 2 maxima or 2 minima (``stop_reason`` ``"extrema"``), or when its
    energy falls below ``energy_threshold`` (``"energy"``).  A signal that
    is constant up to round-off on every component gives no IMFs
    (``"constant"``).  The signal is divided by its largest magnitude before
    sifting, so every threshold is relative, scaling the signal scales every
    IMF alike, and signals of magnitude 1e-200 or 1e200 decompose too.
    Components without a maximum or minimum stay in the residue (see the
    module notes).

    Raises
    ------
    InputError
        Wrong signal length, non-finite values, an unknown or invalid setting.

    Examples
    --------
    Two IMFs of the mean curvature, nearly orthogonal (energy ratio and IO
    within the limits of :mod:`hht3d.decomposition.quality`):

    >>> from hht3d import data_path, emd, load
    >>> from hht3d.geometry.signals import mean_curvature
    >>> surface = load(data_path("spot.ply"))
    >>> signal = mean_curvature(surface)
    >>> result = emd(surface, signal, max_imfs=2)
    >>> result.imfs.shape
    (2, 2930)
    >>> result.quality.ok
    True
    """
    options = EMDOptions.of(options, **overrides)
    f = check_signal(check_surface(surface), signal)
    start = time.perf_counter()
    _check_second_order(options, backend)
    if options.method == "filtering" and options.evaluation == "polynomial" and options.cut == "local":
        raise InputError(
            "evaluation='polynomial' needs cut='global': a local cut's filter is not a function of one "
            "operator, so no polynomial applies it; use evaluation='solves' or 'auto'"
        )
    method = (MultilevelFilterer if uses_levels(options, len(f)) else METHOD_CLASSES[options.method])(
        surface, options, backend
    )
    magnitude = float(np.max(np.abs(f)))
    unit = f / magnitude if magnitude > 0 else f
    imfs: list[np.ndarray] = []
    per_imf: list[dict] = []
    residue = unit
    reference = fluctuation_energy(surface, unit)
    if np.max(np.abs(fluctuation(surface, unit)), initial=0.0) <= FLAT_RTOL:
        reason = "constant"
    else:
        reason = "max_imfs"
        while len(imfs) < options.max_imfs:
            if fluctuation_energy(surface, residue) <= options.energy_threshold * reference:
                reason = "energy"
                break
            extracted = method.imf(residue)
            if extracted is None:
                reason = "extrema"
                break
            imfs.append(extracted[0])
            per_imf.append(extracted[1])
            residue = unit - np.sum(imfs, axis=0)
    scale = magnitude if magnitude > 0 else 1.0
    stacked = np.array(imfs).reshape(len(imfs), len(f)) * scale
    info = {
        "imfs": per_imf,
        "n_imfs": len(per_imf),
        "method": options.method,
        **method.totals(),
        "seconds": time.perf_counter() - start,
        "stop_reason": reason,
        "options": options.as_dict(),
    }
    levels = tuple(
        (level, stacked[k] if level == 0 else values * scale, *(None if v is None else v * scale for v in rest))
        for k, (level, values, *rest) in enumerate(getattr(method, "levels", ()))
    )  # an IMF of the input's level is its row of the IMFs: one copy of it
    return result_with_quality(surface, f, stacked, info, levels)


def result_with_quality(surface: Surface, f: np.ndarray, imfs: np.ndarray, info: dict, levels: tuple = ()) -> EMDResult:
    """The result with its quality figures; each warning is also issued as a QualityWarning."""
    residue = f - imfs.sum(axis=0)
    quality = decomposition_quality(surface, f, imfs, residue)
    for message in quality.warnings:
        warn_quality(f"{surface.name}: {message}", stacklevel=3)
    return EMDResult(imfs, residue, info, quality, levels)


def _check_second_order(options: EMDOptions, backend: str | None) -> None:
    """Refuse an iterative backend for the fourth-order systems of sifting and the bilaplacian filter."""
    name = linalg.check_backend(backend)
    if linalg.SOLVER_BACKENDS[name].iterative and (options.method, options.filter) != ("filtering", "membrane"):
        raise InputError(
            f"backend {name!r} solves second-order systems only; EMD with method={options.method!r}"
            + (f", filter={options.filter!r}" if options.method == "filtering" else "")
            + " factorizes fourth-order (bilaplacian) ones: use method='filtering', filter='membrane' "
            "or a direct backend"
        )
