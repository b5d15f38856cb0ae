"""Empirical mode decomposition (EMD) of signals on surfaces (Sec. 3.1, 4.1).

A signal ``f`` is split into intrinsic mode functions (IMFs) and a residue,

    f = Σ_k f_k + r_N                                              (Eq. 1)

by *sifting* (Huang et al. 1998): find the local maxima and minima of the
current signal ``h``, interpolate each set by a smooth envelope, subtract the
envelopes' mean, repeat until ``h`` is an IMF, then continue on the residue.
On a surface the cubic spline of 1-D EMD becomes the biharmonic field of
Eqs. (8)–(11) (Wang et al. 2012): ``g`` minimises the discrete thin-plate
energy ``gᵀ Q g``, ``Q = L M⁻¹ L``, subject to ``g = f`` at the extrema.

Solver design
-------------
Every envelope of a surface is solved with one matrix *pattern*: the rows and
columns of the constrained vertices ``C`` are replaced by diagonal rows and
columns (their off-diagonal entries stored as explicit zeros),

    [Q_FF  0   ] [g_F]   [-Q_FC f_C]
    [0     D_CC] [g_C] = [ D_CC f_C ],      D_CC = diag(Q)_CC,

which is exactly the eliminated system ``Q_FF g_F = −Q_FC f_C`` plus
``g_C = f_C``, symmetric positive definite whenever every connected component
holds a constraint.  The sparsity pattern never changes, so the fill-reducing
ordering and symbolic factorization are done once per EMD run
(:class:`hht3d.linalg.SymbolicFactorization`) and each envelope costs one
numeric factorization and one solve.  The upper and lower envelopes have
different constraint sets, so a sift costs two factorizations.

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

import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from . import linalg
from .errors import InputError
from .signals import check_signal
from .surface import Surface

__all__ = [
    "EMDResult",
    "emd",
    "eemd",
    "eemd_member",
    "combine_eemd",
    "local_extrema",
    "envelope_operator",
    "envelope_interpolation",
    "STOPPING_RULES",
    "ENVELOPES",
    "EXTREMA_RULES",
    "TIE_RTOL",
]

#: Sifting stopping rules.
STOPPING_RULES = ("sd", "s_number", "fixed")
#: Envelope interpolants: thin-plate ``L M⁻¹ L`` (Eq. 11) or membrane ``L``.
ENVELOPES = ("biharmonic", "harmonic")
#: Extremum rules: all of the ring (``strict``) or a fraction ``ratio`` of it (``ring``, Sec. 5.2).
EXTREMA_RULES = ("strict", "ring")

#: A signal whose deviation from its per-component mean is below this fraction
#: of its magnitude is constant up to round-off and is not decomposed.
_FLAT_RTOL = 1e3 * np.finfo(np.float64).eps
#: Neighbouring values closer than this fraction of the signal's range are ties.
TIE_RTOL = 1e-9


@dataclass
class EMDResult:
    """The outcome of :func:`emd` or :func:`eemd`.

    Attributes
    ----------
    imfs : (k, n) ndarray
        Intrinsic mode functions, finest first; ``k`` may be 0.
    residue : (n,) ndarray
        ``signal − imfs.sum(axis=0)``, so ``imfs.sum(0) + residue`` equals the
        signal to round-off (Eq. 1).
    info : dict
        Diagnostics.  ``"imfs"`` is a list with one dict per IMF (``sifts``,
        ``n_maxima``, ``n_minima`` of the IMF, ``stopping_value`` reached,
        ``factorizations``, ``seconds``); totals ``sifts``,
        ``factorizations``, ``seconds``; ``backend``; ``stop_reason``;
        ``max_constraint_error`` (relative envelope error at the extrema) and
        the options used.
    """

    imfs: np.ndarray
    residue: np.ndarray
    info: dict

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
    if rule not in EXTREMA_RULES:
        raise InputError(f"unknown extrema rule {rule!r}; choose one of {EXTREMA_RULES}")
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

def envelope_operator(surface: Surface, envelope: str = "biharmonic") -> sp.csr_matrix:
    """The energy matrix ``Q`` of the envelope interpolation (Eqs. 8–11).

    ``Q = L M⁻¹ L`` for ``"biharmonic"`` (thin-plate energy, the paper's
    choice; on a line it gives cubic splines) and ``Q = L`` for
    ``"harmonic"`` (membrane energy, piecewise-linear on a line).  ``Q`` is
    symmetric PSD with the diagonal stored for every vertex; it is cached in
    ``surface.cache``.
    """
    if envelope not in ENVELOPES:
        raise InputError(f"unknown envelope {envelope!r}; choose one of {ENVELOPES}")

    def build() -> sp.csr_matrix:
        lap = surface.stiffness
        q = lap if envelope == "harmonic" else lap @ sp.diags(1.0 / surface.mass_diagonal) @ lap
        q = sp.coo_matrix(0.5 * (q + q.T))
        n = surface.n_vertices
        diag = np.arange(n)
        q = sp.csr_matrix((np.concatenate([q.data, np.zeros(n)]),
                           (np.concatenate([q.row, diag]), np.concatenate([q.col, diag]))),
                          shape=(n, n))  # explicit zeros keep every diagonal entry in the pattern
        q.sort_indices()
        return q

    key = f"emd:operator:{envelope}"
    if key not in surface.cache:
        surface.cache[key] = build()
    return surface.cache[key]


class _EnvelopeSolver:
    """Constrained envelope solves sharing one symbolic factorization.

    The fill-reducing ordering and symbolic analysis of ``Q``'s pattern are
    done on the first solve; every envelope then costs one numeric
    factorization and one solve (module notes).
    """

    def __init__(self, surface: Surface, envelope: str, backend: str | None):
        self.backend = linalg.default_backend() if backend is None else backend
        if self.backend not in linalg.available_backends():
            raise InputError(f"sparse solver backend {self.backend!r} is not available; "
                             f"installed: {linalg.available_backends()}")
        self.q = envelope_operator(surface, envelope)
        self._rows = np.repeat(np.arange(surface.n_vertices), np.diff(self.q.indptr))
        self._diag_pos = np.flatnonzero(self.q.indices == self._rows)
        diag = self.q.data[self._diag_pos]
        self._scale = np.where(diag > 0, diag, 1.0)
        self._symbolic: linalg.SymbolicFactorization | None = None

    @property
    def n_factorizations(self) -> int:
        return 0 if self._symbolic is None else self._symbolic.n_factorizations

    def solve(self, f: np.ndarray, constrained: np.ndarray) -> np.ndarray:
        """The envelope ``g`` with ``g_C = f_C`` minimising ``gᵀQg`` (Eq. 11)."""
        free = ~constrained
        data = self.q.data * (free[self._rows] & free[self.q.indices])
        data[self._diag_pos[constrained]] = self._scale[constrained]
        matrix = sp.csr_matrix((data, self.q.indices.copy(), self.q.indptr.copy()), shape=self.q.shape)
        if self._symbolic is None:
            self._symbolic = linalg.SymbolicFactorization(self.q, self.backend)
        factor = self._symbolic.factorize(matrix)
        rhs = -(self.q @ np.where(constrained, f, 0.0))
        rhs[constrained] = self._scale[constrained] * f[constrained]
        return factor.solve(rhs)


def envelope_interpolation(surface: Surface, values, constrained, *, envelope: str = "biharmonic",
                           backend: str | None = None) -> np.ndarray:
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
    envelope : {"biharmonic", "harmonic"}
    backend : str, optional
        Sparse solver of :mod:`hht3d.linalg`.

    Returns
    -------
    (n,) ndarray
    """
    f = _as_signal(surface, values)
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
    return _EnvelopeSolver(surface, envelope, backend).solve(f, mask)


# -- sifting -----------------------------------------------------------------------------

@dataclass(frozen=True)
class _Options:
    max_imfs: int
    stopping: str
    sd_threshold: float
    s_number: int
    fixed_sifts: int
    max_sifts: int
    envelope: str
    extrema: str
    ring: int
    ratio: float
    energy_threshold: float

    def __post_init__(self):
        for name, allowed in (("stopping", STOPPING_RULES), ("envelope", ENVELOPES),
                              ("extrema", EXTREMA_RULES)):
            if getattr(self, name) not in allowed:
                raise InputError(f"unknown EMD {name} {getattr(self, name)!r}; choose one of {allowed}")
        _check_int("max_imfs", self.max_imfs, 0)
        for name in ("s_number", "fixed_sifts", "max_sifts", "ring"):
            _check_int(name, getattr(self, name), 1)
        _check_number("sd_threshold", self.sd_threshold)
        _check_number("energy_threshold", self.energy_threshold)
        if not (isinstance(self.ratio, (int, float, np.number)) and 0.5 < self.ratio <= 1):
            raise InputError(f"EMD option ratio must lie in (0.5, 1], got {self.ratio!r}")


def _check_int(name: str, value, minimum: int) -> None:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise InputError(f"{name} must be an integer >= {minimum}, got {value!r}")


def _check_number(name: str, value) -> None:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.number)) \
            or not np.isfinite(value) or value < 0:
        raise InputError(f"{name} must be a finite number >= 0, got {value!r}")


class _Sifter:
    """Extracts IMFs one at a time from a residue (Sec. 4.1)."""

    def __init__(self, surface: Surface, options: _Options, backend: str | None):
        self.surface = surface
        self.options = options
        self.solver = _EnvelopeSolver(surface, options.envelope, backend)
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

    def mean_envelope(self, h: np.ndarray, is_max, is_min, passive) -> np.ndarray:
        """Mean of the upper and lower biharmonic envelopes (Eq. 11)."""
        upper = self._envelope(h, is_max | passive)
        lower = self._envelope(h, is_min | passive)
        return 0.5 * (upper + lower)

    def _envelope(self, h: np.ndarray, constrained: np.ndarray) -> np.ndarray:
        g = self.solver.solve(h, constrained)
        scale = np.max(np.abs(h[constrained]))
        if scale > 0:
            error = np.max(np.abs(g[constrained] - h[constrained])) / scale
            self.max_constraint_error = max(self.max_constraint_error, float(error))
        g[constrained] = h[constrained]  # exact, so passive components give exactly zero IMFs
        return g

    def imf(self, residue: np.ndarray):
        """Sift one IMF out of ``residue``; ``None`` when it has < 2 maxima or minima."""
        o = self.options
        start, factorizations = time.perf_counter(), self.solver.n_factorizations
        h = residue
        sifts, stable, previous = 0, 0, None
        value = float(np.inf) if o.stopping == "sd" else 0.0
        while True:
            is_max, is_min, passive = self.extrema(h)
            counts = (int(is_max.sum()), int(is_min.sum()))
            if min(counts) < 2:
                if sifts == 0:
                    return None
                break
            if o.stopping == "s_number":
                stable = stable + 1 if counts == previous else 0
                previous, value = counts, stable
            done = {"sd": value < o.sd_threshold, "s_number": stable >= o.s_number,
                    "fixed": sifts >= o.fixed_sifts}[o.stopping]
            if done or sifts >= o.max_sifts:
                break
            mean = self.mean_envelope(h, is_max, is_min, passive)
            if o.stopping == "sd":  # Cauchy criterion: |h_k-1 - h_k|² / |h_k-1|²
                value = _weighted_norm2(mean, self.mass) / _weighted_norm2(h, self.mass)
            h = h - mean
            sifts += 1
            if o.stopping == "fixed":
                value = sifts
        return h, {
            "sifts": sifts,
            "n_maxima": counts[0],
            "n_minima": counts[1],
            "stopping_value": float(value),
            "factorizations": self.solver.n_factorizations - factorizations,
            "seconds": time.perf_counter() - start,
        }


def _weighted_norm2(f: np.ndarray, mass: np.ndarray) -> float:
    """``∫ f² dA`` with the lumped mass."""
    return float(np.dot(mass * f, f))


def _fluctuation(f: np.ndarray, mass: np.ndarray, labels: np.ndarray) -> np.ndarray:
    """``f`` minus its area-weighted mean on each connected component."""
    area = np.bincount(labels, weights=mass)
    mean = np.bincount(labels, weights=mass * f) / area
    return f - mean[labels]


def _as_signal(surface: Surface, signal) -> np.ndarray:
    if not isinstance(surface, Surface):
        raise InputError(f"expected an hht3d.Surface, got {type(surface).__name__}")
    return check_signal(surface, signal)


# -- decomposition -----------------------------------------------------------------------

def emd(surface: Surface, signal, *, max_imfs: int = 10, stopping: str = "sd",
        sd_threshold: float = 0.2, s_number: int = 4, fixed_sifts: int = 10, max_sifts: int = 50,
        envelope: str = "biharmonic", extrema: str = "strict", ring: int = 2, ratio: float = 0.8,
        energy_threshold: float = 1e-8, backend: str | None = None) -> EMDResult:
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
    stopping : {"sd", "s_number", "fixed"}
        When sifting an IMF stops:

        ``"sd"`` (default)
            Cauchy-type criterion of Huang et al. (1998) in the summed form
            used by MATLAB's ``emd`` (``SiftRelativeTolerance``):
            ``SD = ∫(h_{k−1} − h_k)² dA / ∫h_{k−1}² dA < sd_threshold``.
        ``"s_number"``
            Huang et al. (2003): the numbers of maxima and minima stay
            unchanged for ``s_number`` consecutive sifts (zero crossings, the
            1-D rule's other count, have no vertex analogue and are not used).
        ``"fixed"``
            Exactly ``fixed_sifts`` sifts.

        Every rule is capped at ``max_sifts`` sifts, and sifting also stops
        when the signal has fewer than 2 maxima or 2 minima.
    sd_threshold : float
        Default 0.2 (Huang et al. 1998 suggest 0.2–0.3; MATLAB uses 0.2).
    s_number : int
        Default 4 (Huang et al. 2003 recommend 4–8).
    fixed_sifts : int
        Default 10 (Wu & Huang 2009 use 10 sifts in EEMD).
    max_sifts : int
        Cap on sifts per IMF, default 50.
    envelope : {"biharmonic", "harmonic"}
        Interpolant through the extrema: ``L M⁻¹ L g = 0`` (Eqs. 8, 11;
        default) or ``L g = 0``; see :func:`envelope_operator`.
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
        Sparse solver of :mod:`hht3d.linalg`; default the fastest installed.

    Returns
    -------
    EMDResult
        ``imfs`` (k, n), ``residue`` (n,) and ``info`` diagnostics.

    Notes
    -----
    The decomposition stops at ``max_imfs`` IMFs, when the residue has fewer
    than 2 maxima or 2 minima (``stop_reason`` ``"extrema"``), or when its
    energy falls below ``energy_threshold`` (``"energy"``).  A signal that
    is constant up to round-off on every component gives no IMFs
    (``"constant"``).  All thresholds are relative, so scaling the signal by
    a constant scales every IMF by the same constant.  Components without a
    maximum or minimum stay in the residue (see the module notes).

    Raises
    ------
    InputError
        Wrong signal length, non-finite values or invalid options.
    """
    options = _Options(max_imfs, stopping, sd_threshold, s_number, fixed_sifts, max_sifts,
                       envelope, extrema, ring, ratio, energy_threshold)
    f = _as_signal(surface, signal)
    start = time.perf_counter()
    sifter = _Sifter(surface, options, backend)
    imfs, per_imf = [], []
    residue = f
    fluctuation = _fluctuation(f, sifter.mass, sifter.labels)
    reference = _weighted_norm2(fluctuation, sifter.mass)
    if np.max(np.abs(fluctuation)) <= _FLAT_RTOL * np.max(np.abs(f)):
        reason = "constant"
    else:
        reason = "max_imfs"
        while len(imfs) < options.max_imfs:
            fluctuation = _fluctuation(residue, sifter.mass, sifter.labels)
            if _weighted_norm2(fluctuation, sifter.mass) <= energy_threshold * reference:
                reason = "energy"
                break
            sifted = sifter.imf(residue)
            if sifted is None:
                reason = "extrema"
                break
            imfs.append(sifted[0])
            per_imf.append(sifted[1])
            residue = f - np.sum(imfs, axis=0)
    imfs = np.array(imfs).reshape(len(imfs), len(f))
    info = {
        "imfs": per_imf,
        "n_imfs": len(per_imf),
        "sifts": sum(d["sifts"] for d in per_imf),
        "factorizations": sifter.solver.n_factorizations,
        "seconds": time.perf_counter() - start,
        "backend": sifter.solver.backend,
        "stop_reason": reason,
        "max_constraint_error": sifter.max_constraint_error,
        "options": {k: getattr(options, k) for k in options.__dataclass_fields__},
    }
    return EMDResult(imfs, f - imfs.sum(axis=0), info)


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
    _check_int("member_index", member_index, 0)
    _check_int("seed", seed, 0)
    _check_number("noise_std", noise_std)
    rng = np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=(int(member_index),)))
    noise = noise_std * np.std(f) * rng.standard_normal(len(f))
    return emd(surface, f + noise, **emd_options)


def combine_eemd(signal, members) -> EMDResult:
    """Average EEMD members into one decomposition.

    The IMFs are the member averages (members with fewer IMFs count as zero
    for the missing ones); the residue is ``signal − Σ IMFs``, so IMFs plus
    residue equal the noise-free signal (Eq. 1) and the mean noise left by a
    finite ensemble sits in the residue.

    Parameters
    ----------
    signal : (n,) array_like
        The noise-free signal given to :func:`eemd_member`.
    members : sequence of EMDResult
        Results of :func:`eemd_member`.
    """
    f = np.asarray(signal, dtype=np.float64)
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
    return EMDResult(imfs, f - imfs.sum(axis=0), info)


def eemd(surface: Surface, signal, *, ensemble_size: int = 100, noise_std: float = 0.2,
         seed: int = 0, max_imfs: int = 10, **emd_options) -> EMDResult:
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
    """
    _check_int("ensemble_size", ensemble_size, 1)
    f = _as_signal(surface, signal)
    members = [eemd_member(surface, f, i, seed, noise_std, max_imfs=max_imfs, **emd_options)
               for i in range(int(ensemble_size))]
    result = combine_eemd(f, members)
    result.info.update(seed=int(seed), noise_std=float(noise_std))
    return result
