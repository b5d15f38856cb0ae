"""Empirical mode decomposition (EMD) of signals on surfaces (Sec. 3.1, 4.1).

A signal ``f`` is split into intrinsic mode functions (IMFs) and a residue,

    f = Σ_k f_k + r_N                                              (Eq. 1)

by *sifting* (Huang et al. 1998): find the local maxima and minima of the
current signal ``h``, interpolate each set by a smooth envelope, subtract the
envelopes' mean, repeat until ``h`` is an IMF, then continue on the residue.

Envelopes
---------
On a surface the cubic spline of 1-D EMD becomes the biharmonic field of
Eqs. (8)–(11) (Wang et al. 2012): ``g`` minimises the thin-plate energy
``gᵀ Q g``, ``Q = L M⁻¹ L``, subject to ``g = f`` at the extrema.  Between
sparse extrema a thin plate overshoots: through one sharp crease it bulges
over the whole neighbourhood, and the IMFs then cancel each other (energy
ratio 18.9 on the demo model, see :mod:`hht3d.decomposition.quality`).  The default
envelope is therefore a thin plate *in tension* (Smith & Wessel 1990),

    Q_τ = L M⁻¹ L + (τ / d)² L,      d = √(A / |C|),

with ``A`` the surface area and ``|C|`` the number of extrema, so ``d`` is
their mean spacing, ``L`` in the tension term the membrane part of the
Laplacian (its non-negative edge weights, :func:`_membrane`; all of ``L`` on
a Delaunay mesh), and the tension ``τ`` is scale-free: the same ``τ``
behaves alike on every IMF and every model.  ``τ = 0`` is the paper's
biharmonic envelope and ``τ → ∞`` the membrane (harmonic) one, ``L g = 0``,
which obeys a discrete maximum principle but loses the scale separation of
the thin plate (white noise: extrema density 1.5× lower per IMF instead of
about 3.5×).

Cancellation guard
------------------
Each extraction of an IMF ``f_k`` from the residue ``r_{k−1}`` is checked by
its *step energy ratio* ``(‖f̃_k‖² + ‖r̃_k‖²) / ‖r̃_{k−1}‖²`` (M-norms of
the fluctuations about the per-component mean), which exceeds 1 exactly when
the new IMF and what is left cancel.  With ``cancellation_tolerance = δ``:
sifting stops before a sift that would push the ratio above ``1 + δ``, and
when already the first sift does, the IMF is extracted again with 4× the
tension (:data:`GUARD_TENSIONS`, then the harmonic envelope).  Signals whose
extrema are dense and regular (noise, eigenfunctions) never trigger it, so
they keep the thin plate's dyadic scale separation; intermittent signals
(sharp creases on smooth patches) get the tension they need.  The IMFs then
add up without cancelling (per-step ratios multiply up to the total of
:func:`hht3d.decomposition.quality.decomposition_quality`).

Local-mean correction
---------------------
Envelopes through sparse extrema leave a slow part in every IMF: a bump
spanning several of its oscillations that the next IMFs and the residue
then carry with the opposite sign (on a sphere with 60 random bumps, 17% of
the curvature's norm sat in the lowest ten eigenfunctions of IMFs and
residue against 1% in the signal).  An IMF has zero local mean by
definition, so after sifting, the part of ``f_k`` slower than its own
oscillation is moved to the residue:

    m_k = (M + t² L M̃⁻¹ L)⁻¹ M f_k,   t = (c d_k)²,   f_k ← f_k − m_k,

with ``d_k`` the IMF's scale (its extrema spacing or ``π`` over its RMS
wavenumber, the larger) and ``c = mean_correction``.  ``L`` is the membrane
part of the Laplacian and ``M̃`` the vertex areas floored at
:data:`MASS_FLOOR` of their median, so the system stays definite on scans
with caps and tiny areas.  The filter passes a fraction ``1 / (1 + (c d_k
ω)⁴)`` of frequency ``ω``: at the IMF's own ``ω ≈ π/d_k`` (``c = 0.6``) 7%,
at a third of it 86%.  One more numeric factorization per IMF, on the
envelopes' pattern.

Solver design
-------------
Every envelope of a surface is solved with one matrix *pattern* (that of
``L M⁻¹ L`` and ``L`` together): the rows and columns of the constrained
vertices ``C`` are replaced by diagonal rows and columns (their off-diagonal
entries stored as explicit zeros),

    [Q_FF  0   ] [g_F]   [-Q_FC f_C]
    [0     D_CC] [g_C] = [ D_CC f_C ],      D_CC = diag(Q)_CC,

which is exactly the eliminated system ``Q_FF g_F = −Q_FC f_C`` plus
``g_C = f_C``, symmetric positive definite whenever every connected component
holds a constraint.  The sparsity pattern never changes, whatever the
tension, so the fill-reducing ordering and symbolic factorization are done
once per EMD run (:class:`hht3d.linalg.backends.SymbolicFactorization`) and each
envelope costs one numeric factorization and one solve.

Boundaries
----------
``L`` is the Neumann Laplacian, so on an open surface the envelopes have zero
normal derivative at the boundary: on a strip or cylinder a biharmonic
envelope is the *clamped* cubic spline through the extrema, the surface
analogue of the mirrored end extrema of 1-D EMD codes.

Components
----------
A connected component without a maximum or without a minimum (a monotone or
constant patch, or an isolated vertex) has no envelope; all of its vertices
are then constrained in both envelopes, so their mean envelope is the signal
itself: such a component contributes nothing to the IMFs and stays in the
residue.
"""
from __future__ import annotations

import math
import time
import warnings
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .. import linalg
from ..errors import InputError, NumericalError
from .quality import QualityWarning, Quality, decomposition_quality, fluctuation
from ..geometry.surface import Surface
from ..geometry.validation import check_choice, check_int, check_signal, check_surface, did_you_mean, nonnegative

__all__ = [
    "EMDResult",
    "EMDOptions",
    "EMD_DEFAULTS",
    "EnvelopeSolver",
    "Sifter",
    "emd",
    "eemd",
    "eemd_member",
    "combine_eemd",
    "check_emd_options",
    "local_extrema",
    "envelope_operator",
    "envelope_interpolation",
    "extrema_spacing",
    "STOPPING_RULES",
    "ENVELOPES",
    "EXTREMA_RULES",
    "GUARD_TENSIONS",
    "PAPER_OPTIONS",
    "RFG_THRESHOLDS",
    "TIE_RTOL",
]

#: Sifting stopping rules.
STOPPING_RULES = ("sd", "rfg", "s_number", "fixed")
#: Envelope interpolants: thin plate in tension (default), the paper's thin plate (Eq. 11), membrane.
ENVELOPES = ("tension", "biharmonic", "harmonic")
#: Extremum rules: all of the ring (``strict``) or a fraction ``ratio`` of it (``ring``, Sec. 5.2).
EXTREMA_RULES = ("strict", "ring")
#: Tensions the cancellation guard tries, in order, above the starting one; then the harmonic envelope.
GUARD_TENSIONS = (3.0, 12.0, 48.0)
#: The options that give the paper's EMD (Sec. 4.1): thin-plate envelopes, no guard, no mean correction.
PAPER_OPTIONS = {"envelope": "biharmonic", "cancellation_tolerance": None, "mean_correction": None}
#: Rilling, Flandrin & Gonçalvès (2003) thresholds ``(θ₁, θ₂, α)`` of the ``"rfg"`` stopping rule.
RFG_THRESHOLDS = (0.05, 0.5, 0.05)

#: A signal whose deviation from its per-component mean is below this fraction
#: of its magnitude is constant up to round-off and is not decomposed.
_FLAT_RTOL = 1e3 * np.finfo(np.float64).eps
#: The local-mean correction's bilaplacian divides by vertex areas floored at this fraction of
#: their median, so tiny vertices of a scan do not make its system numerically indefinite.
MASS_FLOOR = 0.1
#: Neighbouring values closer than this fraction of the signal's range are ties.
TIE_RTOL = 1e-9


# -- options -----------------------------------------------------------------------------

@dataclass(frozen=True)
class EMDOptions:
    """The options of :func:`emd`, checked; the field defaults are :func:`emd`'s defaults.

    Frozen, so that one value describes one decomposition (it is recorded in
    ``EMDResult.info["options"]``).  The fields and their meaning are the
    keyword arguments of :func:`emd`; ``backend`` is not an option of the
    method and is passed apart.

    Raises
    ------
    InputError
        An unknown choice, a negative or non-finite number, a non-integer count.

    Examples
    --------
    >>> from hht3d.decomposition.decompose import EMDOptions
    >>> EMDOptions().sd_threshold
    0.2
    >>> EMDOptions(envelope="biharmonic").tensions
    (0.0, 3.0, 12.0, 48.0, inf)
    """

    max_imfs: int = 10
    stopping: str = "sd"
    sd_threshold: float = 0.2
    s_number: int = 4
    fixed_sifts: int = 10
    max_sifts: int = 50
    envelope: str = "tension"
    tension: float = 3.0
    cancellation_tolerance: float | None = 0.05
    mean_correction: float | None = 0.6
    extrema: str = "strict"
    ring: int = 2
    ratio: float = 0.8
    energy_threshold: float = 1e-8

    def __post_init__(self):
        for name, allowed in (("stopping", STOPPING_RULES), ("envelope", ENVELOPES),
                              ("extrema", EXTREMA_RULES)):
            check_choice(getattr(self, name), allowed, f"EMD {name}", suggest=True)
        check_int("max_imfs", self.max_imfs, 0)
        for name in ("s_number", "fixed_sifts", "max_sifts", "ring"):
            check_int(name, getattr(self, name), 1)
        for name in ("sd_threshold", "energy_threshold", "tension"):
            nonnegative(name, getattr(self, name))
        for name in ("cancellation_tolerance", "mean_correction"):
            if getattr(self, name) is not None:
                nonnegative(name, getattr(self, name))
        if not (isinstance(self.ratio, (int, float, np.number)) and 0.5 < self.ratio <= 1):
            raise InputError(f"EMD option ratio must lie in (0.5, 1], got {self.ratio!r}")

    @property
    def tensions(self) -> tuple[float, ...]:
        """The starting tension, then those the cancellation guard may try (module notes)."""
        start = _start_tension(self.envelope, self.tension)
        if self.cancellation_tolerance is None:
            return (start,)
        return (start, *(t for t in GUARD_TENSIONS if t > start), *((math.inf,) if start < math.inf else ()))


#: The defaults of :func:`emd`.
EMD_DEFAULTS = EMDOptions()
#: Names of the EMD options, as :func:`emd` takes them.
_OPTION_NAMES = tuple(EMDOptions.__dataclass_fields__)


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
        guard and ``skipped_tensions`` whose systems were not definite, ``step_energy_ratio``, ``mean_share`` (norm of the removed
        local mean over the IMF's), ``factorizations``, ``seconds``);
        totals ``sifts``, ``factorizations``, ``seconds``; ``backend``;
        ``stop_reason``; ``max_constraint_error`` (relative envelope error at
        the extrema) and the options used.
    quality : Quality, optional
        Energy ratio, index of orthogonality and warnings
        (:func:`hht3d.decomposition.quality.decomposition_quality`).
    """

    imfs: np.ndarray
    residue: np.ndarray
    info: dict
    quality: Quality | None = None

    @property
    def n_imfs(self) -> int:
        """Number of IMFs."""
        return len(self.imfs)


# -- extrema -----------------------------------------------------------------------------

def local_extrema(surface: Surface, f, *, rule: str = "strict", ring: int | None = None,
                  ratio: float = 0.8, tie_rtol: float = TIE_RTOL) -> tuple[np.ndarray, np.ndarray]:
    """Indices of the local maxima and minima of a per-vertex signal.

    Parameters
    ----------
    surface : Surface
    f : (n,) array_like
    rule : {"strict", "ring"}
        ``"strict"``: ``f_i`` is ``≥`` every neighbour in its ``ring``-ring.
        ``"ring"``: the relaxed rule of Sec. 5.2, ``f_i ≥ f_j`` for at least
        a fraction ``ratio`` of its ``ring``-ring, ``|N⁺(i)| ≥ t |N_k(i)|``.
        Minima likewise with ``≤``.
    ring : int, optional
        Neighbourhood size in edges; default 1 for ``"strict"`` and 2 for
        ``"ring"`` (the paper's two-ring).
    ratio : float
        The paper's ``t`` in ``(0.5, 1]``; used by ``"ring"`` only.
    tie_rtol : float
        Values closer than ``tie_rtol · (max f − min f)`` count as equal.

    Returns
    -------
    max_idx, min_idx : ndarray of int
        Sorted vertex indices.

    Notes
    -----
    Ties: a maximum must also be *strictly* greater than at least one
    neighbour (a minimum strictly smaller), so a constant patch, the interior
    of a plateau, a constant signal and an isolated vertex give no extrema,
    while a flat ridge (e.g. a signal constant across a strip) gives a line of
    maxima.  Equality is up to ``tie_rtol`` of the signal's range, so a ridge
    that is flat up to solver round-off (about 1e-12 of the range after an
    envelope solve) is still one ridge; the tolerance scales with the signal
    and ignores constant offsets.
    """
    is_max, is_min = _extrema_masks(surface, _as_signal(surface, f), rule, ring, ratio, tie_rtol)
    return np.flatnonzero(is_max), np.flatnonzero(is_min)


def _extrema_masks(surface: Surface, f: np.ndarray, rule: str, ring: int | None,
                   ratio: float, tie_rtol: float = TIE_RTOL) -> tuple[np.ndarray, np.ndarray]:
    """Boolean maximum and minimum masks (see :func:`local_extrema`)."""
    check_choice(rule, EXTREMA_RULES, "extrema rule")
    if rule == "strict":
        ring, ratio = (1 if ring is None else ring), 1.0
    else:
        ring = 2 if ring is None else ring
        if not 0.5 < ratio <= 1:
            raise InputError(f"extrema ratio must lie in (0.5, 1], got {ratio!r}")
    adj = surface.ring(ring)
    degree = np.diff(adj.indptr)
    rows = np.repeat(np.arange(len(f)), degree)
    diff = f[rows] - f[adj.indices]
    tol = tie_rtol * (np.max(f) - np.min(f))
    n = len(f)
    n_above = np.bincount(rows[diff > tol], minlength=n)  # neighbours clearly below f_i
    n_below = np.bincount(rows[diff < -tol], minlength=n)  # neighbours clearly above f_i
    need = ratio * degree
    is_max = (degree - n_below >= need) & (n_above > 0)
    is_min = (degree - n_above >= need) & (n_below > 0)
    return is_max, is_min


# -- envelopes ---------------------------------------------------------------------------

def extrema_spacing(surface: Surface, n_extrema: int) -> float:
    """``d = √(A / n)``: the mean spacing of ``n`` extrema spread over the surface area ``A``."""
    return math.sqrt(float(surface.mass_diagonal.sum()) / max(int(n_extrema), 1))


class _EnvelopeEnergies:
    """``L M⁻¹ L`` and the membrane ``L`` stored on one pattern (theirs together, diagonal included).

    Every envelope energy ``Q_τ`` is a combination of the two data arrays, so
    all tensions share one symbolic analysis.
    """

    def __init__(self, surface: Surface):
        lap = surface.stiffness
        bilaplacian = lap @ sp.diags(1.0 / surface.mass_diagonal) @ lap
        bilaplacian = 0.5 * (bilaplacian + bilaplacian.T)
        n = surface.n_vertices
        pattern = (abs(bilaplacian) + abs(lap) + sp.eye(n)).tocsr()
        pattern.sort_indices()
        self.indptr, self.indices, self.n = pattern.indptr, pattern.indices, n
        self.rows = np.repeat(np.arange(n), np.diff(pattern.indptr))
        self.diagonal = np.flatnonzero(self.indices == self.rows)
        self.bilaplacian = self._on_pattern(bilaplacian)
        membrane = _membrane(lap)
        self.laplacian = self._on_pattern(membrane)
        floored = np.maximum(surface.mass_diagonal, MASS_FLOOR * np.median(surface.mass_diagonal))
        self.smoothing = self._on_pattern(membrane @ sp.diags(1.0 / floored) @ membrane)

    def _on_pattern(self, a) -> np.ndarray:
        """The entries of ``a`` at the positions of the shared pattern (zeros elsewhere)."""
        keys = self.rows.astype(np.int64) * self.n + self.indices
        coo = a.tocoo()
        data = np.zeros(len(keys))
        np.add.at(data, np.searchsorted(keys, coo.row.astype(np.int64) * self.n + coo.col), coo.data)
        return data

    def data(self, tension: float, spacing: float) -> np.ndarray:
        """Entries of ``Q_τ = L M⁻¹ L + (τ/d)² L``; ``τ = inf`` gives ``L`` (the harmonic limit)."""
        if math.isinf(tension):
            return self.laplacian
        if tension == 0:
            return self.bilaplacian
        return self.bilaplacian + (tension / spacing) ** 2 * self.laplacian

    def matrix(self, data: np.ndarray) -> sp.csr_matrix:
        return sp.csr_matrix((data, self.indices.copy(), self.indptr.copy()), shape=(self.n, self.n))


def _membrane(lap: sp.csr_matrix) -> sp.csr_matrix:
    """``L`` without its positive off-diagonal entries (negative cotangent weights of
    non-Delaunay edges), the diagonal rebuilt so rows still sum to 0.

    An M-matrix: the membrane envelope then obeys a discrete maximum principle, and every
    constrained system stays numerically definite even with caps whose cotangents reach −500
    (dragon_vrip).  On a Delaunay mesh it is ``L`` itself.
    """
    off = sp.csr_matrix(lap - sp.diags(lap.diagonal()))
    off.data = np.minimum(off.data, 0.0)
    off.eliminate_zeros()
    return (off - sp.diags(np.asarray(off.sum(axis=1)).ravel())).tocsr()


def _energies(surface: Surface) -> _EnvelopeEnergies:
    key = "emd:energies"
    if key not in surface.cache:
        surface.cache[key] = _EnvelopeEnergies(surface)
    return surface.cache[key]


def _start_tension(envelope: str, tension: float) -> float:
    check_choice(envelope, ENVELOPES, "envelope")
    return {"tension": float(tension), "biharmonic": 0.0, "harmonic": math.inf}[envelope]


def envelope_operator(surface: Surface, envelope: str = "biharmonic", *, tension: float = EMD_DEFAULTS.tension,
                      spacing: float | None = None) -> sp.csr_matrix:
    """The energy matrix ``Q`` of the envelope interpolation (Eqs. 8–11).

    ``Q = L M⁻¹ L`` for ``"biharmonic"`` (thin-plate energy, the paper's
    choice; on a line it gives cubic splines), ``Q = L M⁻¹ L + (τ/d)² L``
    for ``"tension"`` and ``Q = L`` for ``"harmonic"`` (membrane energy,
    piecewise-linear on a line).  ``Q`` is symmetric PSD, stored on the
    pattern shared by all envelopes with every diagonal entry present.

    Parameters
    ----------
    surface : Surface
    envelope : {"biharmonic", "tension", "harmonic"}
    tension : float
        ``τ >= 0`` of ``"tension"``.
    spacing : float, optional
        ``d`` of ``"tension"`` (e.g. :func:`extrema_spacing`); required for it.
    """
    start = _start_tension(envelope, nonnegative("tension", tension))
    if envelope == "tension" and spacing is None:
        raise InputError("the tension envelope needs the extrema spacing d (see extrema_spacing)")
    energies = _energies(check_surface(surface))
    return energies.matrix(energies.data(start, spacing or 1.0))


class EnvelopeSolver:
    """Constrained envelope solves sharing one symbolic factorization.

    The fill-reducing ordering and symbolic analysis of the shared pattern
    are done on the first solve; every envelope then costs one numeric
    factorization and one solve (module notes).
    """

    def __init__(self, surface: Surface, backend: str | None):
        self.backend = linalg.check_backend(backend)
        self.energies = _energies(surface)
        self._symbolic: linalg.SymbolicFactorization | None = None

    @property
    def n_factorizations(self) -> int:
        return 0 if self._symbolic is None else self._symbolic.n_factorizations

    def factorize(self, matrix: sp.csr_matrix) -> linalg.Factor:
        """Numeric factorization of an SPD matrix on the shared pattern (analysed on first use)."""
        if self._symbolic is None:
            self._symbolic = linalg.SymbolicFactorization(matrix, self.backend)
        return self._symbolic.factorize(matrix)

    def solve(self, f: np.ndarray, constrained: np.ndarray, tension: float, spacing: float) -> np.ndarray:
        """The envelope ``g`` with ``g_C = f_C`` minimising ``gᵀQ_τg`` (Eq. 11 for ``τ = 0``)."""
        e = self.energies
        q = e.data(tension, spacing)
        diag = q[e.diagonal]
        scale = np.where(diag > 0, diag, 1.0)
        free = ~constrained
        data = q * (free[e.rows] & free[e.indices])
        data[e.diagonal[constrained]] = scale[constrained]
        factor = self.factorize(e.matrix(data))
        rhs = -(e.matrix(q) @ np.where(constrained, f, 0.0))
        rhs[constrained] = scale[constrained] * f[constrained]
        return factor.solve(rhs)


def envelope_interpolation(surface: Surface, values, constrained, *, envelope: str = "biharmonic",
                           tension: float = EMD_DEFAULTS.tension, backend: str | None = None) -> np.ndarray:
    """Interpolate ``values`` from the ``constrained`` vertices (Eq. 11).

    Solves ``min gᵀQg`` subject to ``g_C = values_C`` with ``Q`` from
    :func:`envelope_operator`; this is one EMD envelope.

    Parameters
    ----------
    surface : Surface
    values : (n,) array_like
        Only the entries at ``constrained`` are used.
    constrained : (n,) bool array_like or int indices
        The vertices ``C``; every connected component needs at least one.
    envelope : {"biharmonic", "tension", "harmonic"}
    tension : float
        ``τ`` of ``"tension"``; the spacing ``d`` is :func:`extrema_spacing` of ``|C|``.
    backend : str, optional
        Sparse solver of :mod:`hht3d.linalg.backends`.

    Returns
    -------
    (n,) ndarray
    """
    f = _as_signal(surface, values)
    start = _start_tension(envelope, nonnegative("tension", tension))
    c = np.asarray(constrained)
    if c.dtype == bool and c.shape != f.shape:
        raise InputError(f"constrained mask has shape {c.shape}; expected {f.shape}")
    if c.dtype != bool and (c.size and (not np.issubdtype(c.dtype, np.integer)
                                        or c.min() < -len(f) or c.max() >= len(f))):
        raise InputError(f"constrained indices must be integers in [0, {len(f)})")
    mask = np.zeros(len(f), dtype=bool)
    mask[c] = True
    covered = np.bincount(surface.component_labels[mask], minlength=surface.n_components) > 0
    if not covered.all():
        raise InputError(f"{int((~covered).sum())} connected components of {surface.name} have no "
                         "constrained vertex; their interpolant is undefined")
    return EnvelopeSolver(surface, backend).solve(f, mask, start, extrema_spacing(surface, mask.sum()))


def check_emd_options(options: dict) -> None:
    """Raise :class:`InputError` for an option :func:`emd` does not take (``"backend"`` included)."""
    known = (*_OPTION_NAMES, "backend")
    for key in options:
        if key not in known:
            raise InputError(f"unknown EMD option {key!r}{did_you_mean(str(key), known, listing=False)}; "
                             f"EMD takes {', '.join(_OPTION_NAMES)} and backend")


def _as_signal(surface: Surface, signal) -> np.ndarray:
    return check_signal(check_surface(surface), signal)


# -- sifting -----------------------------------------------------------------------------

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
        self.labels = surface.component_labels
        self.n_components = surface.n_components
        self.mass = surface.mass_diagonal
        self.max_constraint_error = 0.0

    def extrema(self, h: np.ndarray):
        """Maximum and minimum masks plus the mask of components lacking either."""
        o = self.options
        is_max, is_min = _extrema_masks(self.surface, h, o.extrema,
                                        1 if o.extrema == "strict" else o.ring, o.ratio)
        has_max = np.bincount(self.labels[is_max], minlength=self.n_components) > 0
        has_min = np.bincount(self.labels[is_min], minlength=self.n_components) > 0
        passive = ~(has_max & has_min)[self.labels]
        return is_max & ~passive, is_min & ~passive, passive

    def envelopes(self, h: np.ndarray, is_max, is_min, passive, tension: float):
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
        """``f_k − m_k``, the IMF without its local mean (module notes); ``info`` records ``mean_share``.

        ``d_k`` is the larger of the extrema spacing and ``π / ω_k`` with ``ω_k² = f_kᵀ L f_k /
        f_kᵀ M f_k`` (the RMS wavenumber): extrema crowding in one region overstate the scale,
        spikes at bad triangles understate it, and only an understated scale is harmful (the
        filter then takes the IMF itself).
        """
        c = self.options.mean_correction
        stiffness = float(imf @ (self.surface.stiffness @ imf))
        if c is None or not stiffness > 0:
            return imf
        e = self.solver.energies
        spacing = max(extrema_spacing(self.surface, info["n_maxima"] + info["n_minima"]),
                      np.pi * np.sqrt(float(np.dot(self.mass * imf, imf)) / stiffness))
        data = (c * spacing) ** 4 * e.smoothing
        data[e.diagonal] += self.mass
        try:
            mean = self.solver.factorize(e.matrix(data)).solve(self.mass * imf)
        except NumericalError:  # not definite in floating point: leave the IMF as sifted
            return imf
        info["mean_share"] = float(np.sqrt(self.energy(mean) / max(self.energy(imf), 1e-300)))
        info["factorizations"] += 1
        return imf - mean

    def energy(self, f: np.ndarray) -> float:
        """``‖f̃‖²_M`` of the fluctuation about the per-component mean."""
        g = fluctuation(self.surface, f)
        return float(np.dot(self.mass * g, g))

    def imf(self, residue: np.ndarray):
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
        sifted, tension = best
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
            if o.cancellation_tolerance is not None and sifts > 0 \
                    and candidate_step > 1 + o.cancellation_tolerance:
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


# -- decomposition -----------------------------------------------------------------------

def emd(surface: Surface, signal, *, max_imfs: int = EMD_DEFAULTS.max_imfs, stopping: str = EMD_DEFAULTS.stopping,
        sd_threshold: float = EMD_DEFAULTS.sd_threshold, s_number: int = EMD_DEFAULTS.s_number,
        fixed_sifts: int = EMD_DEFAULTS.fixed_sifts, max_sifts: int = EMD_DEFAULTS.max_sifts,
        envelope: str = EMD_DEFAULTS.envelope, tension: float = EMD_DEFAULTS.tension,
        cancellation_tolerance: float | None = EMD_DEFAULTS.cancellation_tolerance,
        mean_correction: float | None = EMD_DEFAULTS.mean_correction, extrema: str = EMD_DEFAULTS.extrema,
        ring: int = EMD_DEFAULTS.ring, ratio: float = EMD_DEFAULTS.ratio,
        energy_threshold: float = EMD_DEFAULTS.energy_threshold, backend: str | None = None) -> EMDResult:
    """Empirical mode decomposition of a signal on a surface (Sec. 4.1, Eq. 1).

    Parameters
    ----------
    surface : Surface
        Mesh or point cloud; its stiffness ``L`` and lumped mass ``M`` define
        the envelopes.
    signal : (n,) array_like
        One finite value per vertex.
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
        Interpolant through the extrema (module notes): thin plate in
        tension (default), the paper's thin plate ``L M⁻¹ L g = 0`` (Eqs. 8,
        11) or the membrane ``L g = 0``.
    tension : float
        ``τ`` of the tension envelope, relative to the extrema spacing;
        default 3.
    cancellation_tolerance : float or None
        The guard of the module notes: the largest step energy ratio
        ``1 + δ`` one IMF extraction may reach before more tension is tried;
        default ``δ = 0.05``.  ``None`` switches the guard off.
    mean_correction : float or None
        ``c`` of the local-mean correction (module notes): the part of each
        IMF slower than ``c`` times its extrema spacing moves to the
        residue; default 0.6, ``None`` off.  :data:`PAPER_OPTIONS` give the
        paper's method.
    extrema : {"strict", "ring"}
        Extremum rule of :func:`local_extrema`: 1-ring (default) or the
        relaxed ``ring``-ring rule with fraction ``ratio`` (Sec. 5.2).
    ring, ratio : int, float
        Used with ``extrema="ring"``; defaults 2 and 0.8 as in Sec. 5.2.
    energy_threshold : float
        Decomposition stops when the residue's fluctuation energy
        ``∫(r − r̄)² dA`` (``r̄`` its mean per component) falls below this
        fraction of the signal's; default 1e-8.
    backend : str, optional
        Sparse solver of :mod:`hht3d.linalg.backends`; default the fastest installed.

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
        Wrong signal length, non-finite values or invalid options.

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
    options = EMDOptions(max_imfs, stopping, sd_threshold, s_number, fixed_sifts, max_sifts, envelope, tension,
                       cancellation_tolerance, mean_correction, extrema, ring, ratio, energy_threshold)
    f = _as_signal(surface, signal)
    start = time.perf_counter()
    sifter = Sifter(surface, options, backend)
    magnitude = float(np.max(np.abs(f)))
    unit = f / magnitude if magnitude > 0 else f
    imfs, per_imf = [], []
    residue = unit
    reference = sifter.energy(unit)
    if np.max(np.abs(fluctuation(surface, unit)), initial=0.0) <= _FLAT_RTOL:
        reason = "constant"
    else:
        reason = "max_imfs"
        while len(imfs) < options.max_imfs:
            if sifter.energy(residue) <= energy_threshold * reference:
                reason = "energy"
                break
            sifted = sifter.imf(residue)
            if sifted is None:
                reason = "extrema"
                break
            imfs.append(sifter.corrected(*sifted))
            per_imf.append(sifted[1])
            residue = unit - np.sum(imfs, axis=0)
    imfs = np.array(imfs).reshape(len(imfs), len(f)) * (magnitude if magnitude > 0 else 1.0)
    info = {
        "imfs": per_imf,
        "n_imfs": len(per_imf),
        "sifts": sum(d["sifts"] for d in per_imf),
        "factorizations": sifter.solver.n_factorizations,
        "seconds": time.perf_counter() - start,
        "backend": sifter.solver.backend,
        "stop_reason": reason,
        "max_constraint_error": sifter.max_constraint_error,
        "options": {k: getattr(options, k) for k in _OPTION_NAMES},
    }
    return _with_quality(surface, f, imfs, info)


def _with_quality(surface: Surface, f: np.ndarray, imfs: np.ndarray, info: dict) -> EMDResult:
    """The result with its quality figures; each warning is also issued as a QualityWarning."""
    residue = f - imfs.sum(axis=0)
    quality = decomposition_quality(surface, f, imfs, residue)
    for message in quality.warnings:
        warnings.warn(f"{surface.name}: {message}", QualityWarning, stacklevel=3)
    return EMDResult(imfs, residue, info, quality)


# -- ensemble EMD ------------------------------------------------------------------------

def eemd_member(surface: Surface, signal, member_index: int, seed: int, noise_std: float = 0.2,
                **emd_options) -> EMDResult:
    """EMD of the signal plus one seeded white-noise realisation (Wu & Huang 2009).

    Parameters
    ----------
    surface : Surface
    signal : (n,) array_like
    member_index : int
        Which ensemble member; its noise comes from
        ``numpy.random.default_rng(SeedSequence(seed, spawn_key=(member_index,)))``,
        i.e. the ``member_index``-th child of ``SeedSequence(seed).spawn``, so
        members are independent and reproducible in any order or process.
    seed : int
        Ensemble seed.
    noise_std : float
        Noise standard deviation relative to the signal's standard deviation.
    **emd_options
        Passed to :func:`emd`.

    Returns
    -------
    EMDResult
        The decomposition of the *noisy* signal (its IMFs plus residue equal
        the signal plus noise); average members with :func:`combine_eemd`.
    """
    f = _as_signal(surface, signal)
    check_int("member_index", member_index, 0)
    check_int("seed", seed, 0)
    nonnegative("noise_std", noise_std)
    check_emd_options(emd_options)
    rng = np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=(int(member_index),)))
    noise = noise_std * np.std(f) * rng.standard_normal(len(f))
    with warnings.catch_warnings():  # a noisy member's quality is not the ensemble's
        warnings.simplefilter("ignore", QualityWarning)
        return emd(surface, f + noise, **emd_options)


def combine_eemd(surface: Surface, signal, members) -> EMDResult:
    """Average EEMD members into one decomposition.

    The IMFs are the member averages (members with fewer IMFs count as zero
    for the missing ones); the residue is ``signal − Σ IMFs``, so the mean
    noise left by a finite ensemble sits in the residue.

    Parameters
    ----------
    surface : Surface
        The surface of the members (for the quality figures).
    signal : (n,) array_like
        The noise-free signal given to :func:`eemd_member`.
    members : sequence of EMDResult
        Results of :func:`eemd_member`.
    """
    f = _as_signal(surface, signal)
    members = list(members)
    if not members:
        raise InputError("EEMD needs at least one ensemble member")
    if any(m.residue.shape != f.shape for m in members):
        raise InputError(f"EEMD members do not match the signal of shape {f.shape}")
    k = max(m.n_imfs for m in members)
    imfs = np.zeros((k, len(f)))
    for m in members:
        imfs[:m.n_imfs] += m.imfs
    imfs /= len(members)
    info = {
        "ensemble_size": len(members),
        "member_n_imfs": [m.n_imfs for m in members],
        "n_imfs": k,
        "sifts": sum(m.info["sifts"] for m in members),
        "factorizations": sum(m.info["factorizations"] for m in members),
        "seconds": sum(m.info["seconds"] for m in members),
        "backend": members[0].info["backend"],
        "max_constraint_error": max(m.info["max_constraint_error"] for m in members),
    }
    return _with_quality(surface, f, imfs, info)


def eemd(surface: Surface, signal, *, ensemble_size: int = 100, noise_std: float = 0.2,
         seed: int = 0, max_imfs: int = EMD_DEFAULTS.max_imfs, **emd_options) -> EMDResult:
    """Ensemble EMD (Wu & Huang 2009), the remedy for mode mixing.

    Runs :func:`eemd_member` for members ``0 .. ensemble_size − 1`` and
    averages them with :func:`combine_eemd`.

    Parameters
    ----------
    surface : Surface
    signal : (n,) array_like
    ensemble_size : int
        Number of noisy copies; default 100 as in Wu & Huang (2009).  The
        noise left in the IMFs falls like ``noise_std / √ensemble_size``.
    noise_std : float
        White-noise standard deviation relative to the signal's; default
        0.2 (Wu & Huang 2009).
    seed : int
        The same seed gives identical results; different seeds differ.
    max_imfs : int
        Passed to every member.
    **emd_options
        Further :func:`emd` options.

    Examples
    --------
    >>> from hht3d import data_path, eemd, load
    >>> from hht3d.geometry.signals import mean_curvature
    >>> surface = load(data_path("spot.ply"))
    >>> signal = mean_curvature(surface)
    >>> result = eemd(surface, signal, ensemble_size=4, max_imfs=2, seed=1)
    >>> result.n_imfs, result.quality.ok
    (2, True)
    """
    check_int("ensemble_size", ensemble_size, 1)
    f = _as_signal(surface, signal)
    members = [eemd_member(surface, f, i, seed, noise_std, max_imfs=max_imfs, **emd_options)
               for i in range(int(ensemble_size))]
    result = combine_eemd(surface, f, members)
    result.info.update(seed=int(seed), noise_std=float(noise_std))
    return result
