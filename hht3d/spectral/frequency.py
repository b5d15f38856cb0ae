"""Instantaneous frequency of monogenic signals on surfaces (Eq. 23) and a surface's resolution limit.

What the number means
---------------------
For a signal ``f`` with Riesz transform ``R f`` (:func:`hht3d.spectral.riesz_transform.riesz`),
the local phase is ``φ = atan2(|Rf|, f) ∈ [0, π]`` (Eq. 22) and the
instantaneous frequency is its slope ``ω = |∇φ|`` (Eq. 23), in radians per
model unit of length.  In the continuum:

* for a wave that varies in one direction, ``a(x) cos(k·x + β)`` with a slowly
  varying amplitude, ``ω = |k|`` exactly: the wavenumber, ``2π`` over the
  wavelength;
* for patterns that vary in two directions Eq. 23 reads *less* than the
  wavenumber, because ``|Rf|`` mixes the directions: an isotropic random wave
  of wavenumber ``k`` gives ``0.77 k`` (mean weighted by the energy ``a²``;
  unweighted mean 0.84, median 0.86), ``cos kx + cos ky`` gives ``0.69 k``
  (median 0.71), and Laplacian eigenfunctions of a real mesh (spot)
  ``0.77–0.90 √λ`` (``benchmarks/bench_frequency.py``).

No single factor converts Eq. 23 into a wavenumber, since the factor depends on
the local pattern (1 for ridges and 1-D waves, 0.69–0.86 for isotropic
textures depending on the pattern and the statistic), so the estimate is left
in the units of Eq. 23.  Gains of Eq. 26
(:mod:`hht3d.apps.filters`) and the Hilbert spectrum use the same numbers, so
a cutoff read off the spectrum acts where the spectrum shows it.

Estimators (``frequency``)
--------------------------
``"phase"`` (default)
    The phase increment along every edge ``(i, j)`` of the gradient
    stencil, ``Δψ_ij = arg(z_j z̄_i)`` with ``z = f + i q``, ``q = Rf·o_i``
    the Riesz vectors at both ends projected on one orientation ``o_i``
    (``Rf_i/|Rf_i|``, or at the folds where ``Rf_i`` vanishes the principal
    direction of the ring's Riesz vectors); the gradient operator of the
    ``gradient`` option fits ``∇ψ`` to the increments in place of value
    differences, and ``ω = |∇ψ|``.  At vertex ``i``, ``∇ψ = ∇φ``, so this is
    Eq. 23.  Edges whose increment wrapped past ``±π`` (long edges near the
    resolution limit) are unwrapped against the fitted gradient, and the
    Riesz magnitude is divided by the discrete transform's own response to a
    plane wave of the local wavevector (the gradient stencil's symbol over
    the Laplacian's, both relative to their long-wave limits), so that a
    sampled plane wave reads its wavenumber at every vertex.  The increments
    of a plane wave are then exact up to the Nyquist limit of each edge; the
    response is taken at a ring mean of a first estimate, so a regular grid
    reads plane waves within 1.4 % at every vertex down to 4 points per
    wavelength and within 1 % at the median down to 2.2: monotone in the
    true frequency up to the mesh's limit.  Where the phase field curves (patterns
    varying in two directions) the 1-ring fit is off by ``O((kh)²)``: for
    spherical harmonics at 8 points per wavelength +1.6 % (sectoral) to
    +2.4 % (tesseral) of the continuum Eq. 23.
``"gradient"``
    Eq. 23 as the paper writes it: ``∇φ = (f ∇q − q ∇f)/(f² + q²)`` from
    vertex gradients of the sampled fields, ``∇q = Jᵀ Rf/|Rf|`` by the chain
    rule (``J`` the gradient of ``Rf``; at round-off zeros of ``Rf`` its top
    singular direction).  Differentiating a sampled wave scales it by about
    ``sin(kh)/(kh)``: the estimate peaks near 4 points per wavelength and
    falls back towards 0 at the Nyquist limit, so it is not monotone in the
    true frequency.

Resolution limit
----------------
A vertex carrying area ``A_v`` (the lumped mass) resolves wavenumbers up to
``π/√A_v`` (:func:`hht3d.spectral.resolution.resolvable_frequency`): the Nyquist wavenumber of a square
lattice with one sample per ``A_v``, i.e. ``π/h`` on a grid of spacing ``h``
(about 7 % below the isotropic limit of an equilateral triangulation).
Frequencies above it are reported (:func:`resolution_report`), never clipped.
"""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import Executor, ThreadPoolExecutor
from typing import Any, NamedTuple, cast

import numpy as np

from ..errors import InputError
from ..geometry.surface import Surface
from ..linalg.threads import usable_cores
from ..records import renamed_keywords
from .edge_stencil import Block, EdgeStencil, edge_stencil
from .options import FREQUENCY_METHODS, RieszOptions
from .riesz_transform import vertex_gradient

__all__ = ["FREQUENCY_METHODS", "instantaneous_frequency"]

#: ``|Rf|`` below this fraction of its maximum (per signal) is round-off: a zero of ``Rf``.
_ZERO_RTOL = 1e-10
#: Below this fraction of the largest ``|Rf|`` on its ring, a vertex's own Riesz
#: vector no longer orients its phase (a fold); see :func:`_orientation`.
_FOLD_RATIO = 0.1
#: Upper-triangle entries of a symmetric 3×3 tensor, and their places in it.
_PAIRS = ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))
_SYMMETRIC = np.array([[0, 1, 2], [1, 3, 4], [2, 4, 5]])
#: Most unwrapping passes; each refits the gradient with the edges' turns fixed.
_MAX_UNWRAP = 8
#: Floor of the discrete Riesz response (it tends to 0 at the Nyquist limit).
_MIN_RESPONSE = 0.05


def instantaneous_frequency(
    surface: Surface,
    signals: np.ndarray,
    riesz: np.ndarray | None,
    options: RieszOptions | dict | None = None,
    **overrides: Any,
) -> np.ndarray:
    """Instantaneous frequency ``ω = |∇φ|`` (Eq. 23) of ``k`` signals from their Riesz transforms.

    Parameters
    ----------
    surface : Surface
    signals : (k, n) ndarray
        The signals ``f`` (e.g. IMFs).
    riesz : (k, n, 3) ndarray
        Their Riesz transforms ``R f`` (tangent vectors).
    options : RieszOptions or dict, optional
        ``frequency``: the estimator (module notes; formerly the keyword
        ``method``): ``"phase"`` is exact for sampled plane waves up to the
        resolution limit, ``"gradient"`` is the paper's Eq. 23 computed with
        vertex gradients.  ``gradient``: the vertex gradient operator
        (:meth:`hht3d.geometry.surface.Surface.gradient`) the estimator uses,
        as for the Riesz transform.
    **overrides
        Settings that replace those of ``options``.

    The ``"phase"`` route reads each signal's blocks of vertices in parallel
    threads, one per core this process may use (``OMP_NUM_THREADS`` where
    set); the result does not depend on their number.

    Returns
    -------
    (k, n) ndarray
        Radians per model unit of length, ``>= 0``; 0 where ``f`` and ``Rf``
        vanish (no amplitude) and at vertices without neighbours.
    """
    options = RieszOptions.of(
        options, **renamed_keywords(overrides, {"method": "frequency"}, "instantaneous_frequency")
    )
    f = np.asarray(signals, dtype=np.float64)
    r = np.asarray(riesz, dtype=np.float64)
    if f.ndim != 2 or r.shape != (*f.shape, 3) or f.shape[1] != surface.n_vertices:
        raise InputError(
            f"signals must have shape (k, {surface.n_vertices}) and their Riesz transforms "
            f"(k, {surface.n_vertices}, 3), got {f.shape} and {r.shape}"
        )
    if options.frequency == "gradient":
        scale = _unit_scale(f, r)
        return _gradient_frequency(surface, f / scale[:, None], r / scale[:, None, None], options.gradient)
    stencil = edge_stencil(surface, options.gradient)
    omega = np.empty(f.shape)
    threads = usable_cores()
    with ThreadPoolExecutor(threads) as executor:  # NumPy releases the GIL
        pool = _Pool(executor, threads)
        for k in range(len(f)):
            scale = _unit_scale(f[k, None], r[k, None])[0]
            r_t = np.empty((3, f.shape[1]))
            omega[k] = _phase_frequency(stencil, f[k] / scale, np.divide(r[k].T, scale, out=r_t), pool)
    return omega


def _unit_scale(f: np.ndarray, r: np.ndarray) -> np.ndarray:
    """The largest magnitude (k,) of each signal and its Riesz transform, 1 where both vanish.

    The phase, and so ``ω``, does not change with the signal's scale; products of
    signals of magnitude 1e200 would overflow (the fold tensor of :func:`_orientation`).
    """
    scale = np.maximum(_peak(f, 1), _peak(r, (1, 2)))
    return np.where(scale > 0, scale, 1.0)


def _peak(x: np.ndarray, axes: int | tuple[int, ...]) -> np.ndarray:
    """``max |x|`` over ``axes``, without an array of ``|x|``."""
    return np.maximum(x.max(axis=axes, initial=0.0), -x.min(axis=axes, initial=0.0))


# -- the paper's route: vertex gradients of the sampled fields --------------------------------


def _gradient_frequency(surface: Surface, f: np.ndarray, r: np.ndarray, kind: str) -> np.ndarray:
    """``|f ∇q − q ∇f| / (f² + q²)`` with ``q = |Rf|`` and ``∇q`` by the chain rule."""
    q = np.linalg.norm(r, axis=-1)
    energy = f**2 + q**2
    grad_f = vertex_gradient(surface, f, kind)
    grad_q = _norm_gradient(surface, r, q, kind)
    numerator = np.linalg.norm(f[..., None] * grad_q - q[..., None] * grad_f, axis=-1)
    return np.divide(numerator, energy, out=np.zeros_like(energy), where=energy > 0)


def _norm_gradient(surface: Surface, rf: np.ndarray, q: np.ndarray, kind: str) -> np.ndarray:
    """``∇|Rf| = Jᵀ Rf/|Rf|`` per vertex (k, n, 3), with ``J[g, c] = ∂_g (Rf)_c``.

    Never by differencing ``|Rf|``: that has a kink at every extremum of
    ``f`` (the phase folds at 0 and π), and a stencil straddling it
    underestimates ``ω``.  At round-off zeros of ``Rf`` the direction is the
    top right singular vector of ``J`` (steepest slope of the cone ``|Rf|``).
    """
    grad = surface.gradient(kind)  # once: large surfaces build it at each call
    jac = np.stack([vertex_gradient(surface, rf[..., c], kind, grad) for c in range(3)], axis=-1)
    direction = np.divide(rf, q[..., None], out=np.zeros_like(rf), where=q[..., None] > 0)
    zero = q <= _ZERO_RTOL * q.max(axis=1, keepdims=True)
    if zero.any():
        direction[zero] = np.linalg.svd(jac[zero])[2][:, 0, :]
    return np.einsum("kngc,knc->kng", jac, direction)


# -- phase increments along edges --------------------------------------------------------------


def _phase_frequency(st: EdgeStencil, f: np.ndarray, r_t: np.ndarray, pool: _Pool) -> np.ndarray:
    """``|∇ψ|`` (n,) of one signal ``f`` (n,) with Riesz vectors ``r_t`` (3, n), from edge phase increments,
    unwrapped and dispersion-corrected: a first fit, the Riesz response from it (which reads the first
    fit on each vertex's ring), then the corrected fit, each a pass over the stencil's blocks, which the
    ``pool``'s threads share (each writes its blocks' own vertices).

    The vectors come as rows (3, n), as the orientation leaves them: 1-D gathers are the fast ones."""
    q = np.sqrt(r_t[0] ** 2 + r_t[1] ** 2 + r_t[2] ** 2)
    o_t = _orientation(st, r_t, q, pool)
    qo = r_t[0] * o_t[0] + r_t[1] * o_t[1] + r_t[2] * o_t[2]

    def fit(block: Block, response: np.ndarray | None, guess: np.ndarray | None) -> np.ndarray:
        q_i = block.at_start(qo)
        q_j = sum(r_t[c][block.cols] * block.at_start(o_t[c]) for c in range(3))
        if response is not None:
            q_i, q_j = q_i / block.at_start(response), q_j / response[block.cols]
        return _unwrapped_fit(block, block.at_start(f), f[block.cols], q_i, q_j, guess)

    first, response, omega = np.empty((st.n, 3)), np.empty(st.n), np.empty(st.n)

    def first_fit(block: Block) -> None:
        first[block.a : block.b] = fit(block, None, None)

    def corrected_fit(block: Block) -> None:
        omega[block.a : block.b] = np.linalg.norm(fit(block, response, first[block.a : block.b]), axis=1)

    _each_block(pool, st, first_fit)
    energy = f**2 + q**2
    magnitude = np.linalg.norm(first, axis=1)
    moment = energy * magnitude

    def respond(block: Block) -> None:
        response[block.a : block.b] = _riesz_response(block, first, magnitude, moment, energy)

    _each_block(pool, st, respond)
    _each_block(pool, st, corrected_fit)
    return omega


class _Pool(NamedTuple):
    """The threads that share a signal's blocks, and how many they are."""

    executor: Executor
    threads: int


def _each_block(pool: _Pool, st: EdgeStencil, work: Callable[[Block], None]) -> None:
    """``work(block)`` for every block of ``st``, at least one a thread, on the ``pool``'s threads; a block's
    cached offsets go with it once its work is done."""
    list(pool.executor.map(work, st.blocks(pool.threads)))


def _orientation(st: EdgeStencil, r_t: np.ndarray, q: np.ndarray, pool: _Pool) -> np.ndarray:
    """Unit orientation (3, n) of the signed quadrature ``Rf·o``, for Riesz vectors ``r_t`` (3, n).

    ``Rf_i/|Rf_i|``: then ``∇(Rf·o) = ∇|Rf|`` at the vertex, and the fitted
    ``∇ψ`` is Eq. 23's ``∇φ``.  Where ``|Rf_i|`` is below :data:`_FOLD_RATIO`
    of the largest on its ring (a fold of the phase, at an extremum of
    ``f``) its direction is unreliable; the principal direction of
    ``Σ r_j r_jᵀ`` over the vertex and its ring orients the phase there.
    """
    o_t = np.divide(r_t, q, out=np.zeros_like(r_t), where=q > 0)

    def refold(block: Block) -> None:
        ring_max = np.zeros(block.size)
        has = block.counts > 0
        if len(block.cols):
            ring_max[has] = np.maximum.reduceat(q[block.cols], block.starts[has])
        here = q[block.a : block.b]
        fold = np.flatnonzero((here <= _FOLD_RATIO * ring_max) | (here == 0))
        if fold.size:
            tensor = (_fold_ring(block, fold, r_t) + _products(r_t, block.a + fold))[:, _SYMMETRIC]
            o_t[:, block.a + fold] = np.linalg.eigh(tensor)[1][:, :, -1].T

    _each_block(pool, st, refold)
    return o_t


def _products(r_t: np.ndarray, vertices: np.ndarray) -> np.ndarray:
    """The upper triangle (len, 6) of ``r rᵀ`` at ``vertices``, in :data:`_PAIRS` order."""
    return np.stack([r_t[a][vertices] * r_t[b][vertices] for a, b in _PAIRS], axis=1)


def _fold_ring(block: Block, fold: np.ndarray, r_t: np.ndarray) -> np.ndarray:
    """``Σ_j r_j r_jᵀ`` (len(fold), 6) over the ring of each of the block's vertices ``fold``."""
    slot = np.full(block.size, -1)
    slot[fold] = np.arange(len(fold))
    edge_slot = np.repeat(slot, block.counts)
    mine = edge_slot >= 0
    values = _products(r_t, block.cols[mine])
    return np.column_stack(
        [np.bincount(edge_slot[mine], weights=values[:, p], minlength=len(fold)) for p in range(len(_PAIRS))]
    )


def _unwrapped_fit(
    block: Block, f_i: np.ndarray, f_j: np.ndarray, q_i: np.ndarray, q_j: np.ndarray, guess: np.ndarray | None
) -> np.ndarray:
    """Gradient (size, 3) fitted to the edge increments ``arg(z_j z̄_i)``, ``z = f + i q`` at the
    edges' ends, each shifted by the whole turns that bring it closest to the gradient's
    prediction ``∇ψ_i · (x_j − x_i)``.

    Starts from ``guess`` (or the wrapped increments) and refits until no turn changes.
    """
    increment = np.arctan2(f_i * q_j - q_i * f_j, f_i * f_j + q_i * q_j)
    turns = np.zeros_like(increment)
    grad = guess
    for _ in range(_MAX_UNWRAP):
        if grad is not None:
            new_turns = np.round((block.along(grad) - increment) / (2 * np.pi))
            if grad is not guess and np.array_equal(new_turns, turns):
                break
            turns = new_turns
        grad = block.fit(increment + 2 * np.pi * turns)
    return cast(np.ndarray, grad)  # the loop runs at least once


def _riesz_response(
    block: Block, grad: np.ndarray, magnitude: np.ndarray, moment: np.ndarray, energy: np.ndarray
) -> np.ndarray:
    """``|R_h w| / |R w|`` (size,) for the plane wave ``w`` of the local wavevector.

    The wavevector has the direction of ``grad`` (n, 3) at each vertex and the
    energy-weighted mean of ``|grad|`` over the vertex and its ring (``moment`` is
    ``energy·|grad|``, both (n,); a plane wave reads its wavenumber there on average, even where the Riesz
    magnitude is distorted).  The discrete transform ``∇_h L^{-1/2}``
    scales ``R w`` by the gradient stencil's symbol ``|Σ_j c_ij sin(k·d_ij)|/|k|``
    over ``√(Σ_j w_ij (1 − cos k·d_ij) / Σ_j w_ij (k·d_ij)²/2)`` (the
    Laplacian's symbol relative to its long-wave limit); both tend to 1 as
    ``|k| h → 0``.  Floored at :data:`_MIN_RESPONSE`.
    """
    here = slice(block.a, block.b)
    weighted, total = block.ring(moment) + moment[here], block.ring(energy) + energy[here]
    mean = np.divide(weighted, total, out=np.zeros(block.size), where=total > 0)
    moving = magnitude[here, None]
    wave = np.divide(grad[here] * mean[:, None], moving, out=np.zeros((block.size, 3)), where=moving > 0)
    symbol = np.linalg.norm(block.fit(np.sin(block.along(wave))), axis=1)
    gradient_ratio = np.divide(symbol, mean, out=np.ones(block.size), where=mean > 0)
    lap_phase = block.lap_along(wave)
    dispersion = block.lap_sum(1 - np.cos(lap_phase))
    long_wave = block.lap_sum(0.5 * lap_phase**2)
    laplacian_ratio = np.sqrt(
        np.divide(dispersion, long_wave, out=np.ones(block.size), where=(long_wave > 0) & (dispersion > 0))
    )
    return np.clip(gradient_ratio / laplacian_ratio, _MIN_RESPONSE, 1 / _MIN_RESPONSE)
