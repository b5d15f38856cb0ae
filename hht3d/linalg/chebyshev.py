"""Functions of a Laplacian by Chebyshev series: ``φ(A) v`` with sparse products only (issue 39).

For ``A = M⁻¹L``, ``L`` symmetric positive semidefinite and ``M`` a positive
diagonal, ``A`` is self-adjoint in the ``M`` inner product with its spectrum in
``[0, λ̄]``, ``λ̄`` an upper bound (:func:`spectral_radius_bound`).  A function
``φ`` smooth on that interval is the series ``Σ c_j T_j(y)``, ``y = 2λ/λ̄ − 1``
(:func:`chebyshev_series`: interpolation at Chebyshev points by one DCT,
truncated where the tail ``Σ_{j>n} |c_j|`` falls below ``tol``, a bound on
``max |φ − p|`` over the interval), and :func:`apply_series` evaluates ``p(A) v``
by Clenshaw's recurrence: one product with ``L`` per degree (on
:func:`recurrence_matrix`, which folds in ``M⁻¹`` and the shift), four vectors of
memory and no factorization, so no fill.  In the ``M`` norm
``‖p(A)v − φ(A)v‖ ≤ tol ‖v‖`` on every signal.  The products are memory-bound and
release the GIL, so the rows are shared by threads (one per core,
:func:`~hht3d.linalg.threads.usable_cores`): 1.55× faster on 2 cores on a 4M-row
Laplacian, the same result to the bit.

A transition of ``φ`` at ``λ_c`` near the bottom of the spectrum needs a
degree of about ``√(λ̄ / λ_c)`` times a factor set by the transition's
sharpness and ``tol`` (Chebyshev points crowd at the ends of the interval at
spacing ``λ̄ / n²``).  So ``λ̄`` should be tight: a few badly shaped vertices
set it.

The products stream the matrix from memory and gather the vector's entries at each row's
columns.  :func:`recurrence_matrix` numbers the rows in reverse Cuthill–McKee order, which
keeps each row's columns close together: on 1M vertices the gathers then hit the cache and a
product takes 0.69–0.72 of its time in the file's order (a subdivided mesh and its vertices
as a point cloud); below about 200k vertices the whole matrix fits in the cache and the order
changes nothing.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np
import scipy.fft
import scipy.sparse as sp
from scipy.sparse.csgraph import reverse_cuthill_mckee

from ..errors import NumericalError
from .threads import usable_cores

__all__ = [
    "spectral_radius_bound",
    "chebyshev_series",
    "Recurrence",
    "recurrence_matrix",
    "apply_series",
    "POWER_ITERATIONS",
    "MAX_DEGREE",
    "THREAD_ROWS",
]

#: Bounds :func:`spectral_radius_bound` evaluates (Gershgorin's, then power iterations).
POWER_ITERATIONS = 10
#: Largest degree :func:`chebyshev_series` gives before refusing.
MAX_DEGREE = 1 << 16
#: :func:`apply_series` gives each thread a block of at least this many rows.
THREAD_ROWS = 100_000
#: The first interpolation degree tried; it doubles until the series has converged.
_START_DEGREE = 64


def spectral_radius_bound(stiffness: sp.spmatrix, mass: np.ndarray, iterations: int = POWER_ITERATIONS) -> float:
    """``λ̄ ≥ λ_max(M⁻¹L)``: the Collatz–Wielandt bound for ``M⁻¹|L|``.

    ``λ_max(M⁻¹L) ≤ ρ(M⁻¹|L|)`` because ``|xᵀLx| ≤ |x|ᵀ|L||x|``, and for the
    non-negative ``M⁻¹|L|`` and any positive ``w``, ``ρ ≤ max_i (M⁻¹|L|w)_i / w_i``.
    With ``w = 1`` this is Gershgorin's bound ``max_i Σ_j |L_ij| / M_ii``; power
    iterations ``w ← M⁻¹|L|w`` tighten it towards ``ρ``.  Every iterate gives a
    valid bound and the smallest is kept.  On meshes ``ρ`` is within a few per
    cent of ``λ_max`` (the top eigenvector sits at the worst-shaped vertices),
    where Gershgorin is 1.3–2× above it.

    Parameters
    ----------
    stiffness : sparse (n, n)
        ``L``.
    mass : (n,) ndarray
        The diagonal of ``M``, positive.
    iterations : int
        Bounds evaluated, the first Gershgorin's.

    Examples
    --------
    >>> import scipy.sparse as sp
    >>> path = sp.diags([[-1.0] * 3, [1.0, 2.0, 2.0, 1.0], [-1.0] * 3], [-1, 0, 1])
    >>> round(spectral_radius_bound(path, np.ones(4)), 6)  # λ_max = 2 + √2
    3.414214
    """
    lap = abs(sp.csr_matrix(stiffness))
    inv_mass = 1.0 / np.asarray(mass, dtype=float)
    w = np.ones(lap.shape[0])
    best = np.inf
    for _ in range(iterations):
        y = inv_mass * (lap @ w)
        top = float(np.max(y))
        best = min(best, float(np.max(y / w)))
        if top == 0:
            break
        # rows of |L| that are zero give 0 whatever w is: keep w positive there
        w = np.where(y > 0, y / top, 1.0)
    return best


def chebyshev_series(
    function: Callable[[np.ndarray], np.ndarray], top: float, tol: float, scale: float | None = None
) -> np.ndarray:
    """Chebyshev coefficients of ``function`` on ``[0, top]``, truncated to ``max |φ − p| ≤ tol``.

    The interpolant at ``N`` Chebyshev points (one DCT) is taken with ``N`` doubling until
    its last quarter of coefficients sums below ``tol / 10``; the series is then cut where
    the sum of the remaining ``|c_j|`` drops below ``tol``.  ``N`` starts at 64, or where
    the points are 1/4 of ``scale`` apart at 0, so that a change of ``φ`` near 0 is not
    missed between them.

    Parameters
    ----------
    function : callable
        Vectorised ``φ(λ)``, smooth on ``[0, top]``.
    top : float
        ``λ̄ > 0``.
    tol : float
        Bound on the uniform error.
    scale : float, optional
        Width of ``φ``'s sharpest change near 0 (a cut, a knee).

    Returns
    -------
    (n + 1,) ndarray
        ``c_0 … c_n`` in ``T_j(2λ/λ̄ − 1)``.

    Raises
    ------
    NumericalError
        When more than :data:`MAX_DEGREE` degrees would be needed.

    Examples
    --------
    >>> c = chebyshev_series(lambda lam: np.exp(-lam), 4.0, 1e-12)
    >>> len(c) < 30, bool(abs(np.polynomial.chebyshev.chebval(0.0, c) - np.exp(-2.0)) < 1e-12)
    (True, True)
    """
    n = _START_DEGREE
    if scale is not None:  # the first points are top·π²/(2N²) apart
        n = max(n, 1 << math.ceil(math.log2(math.pi * math.sqrt(2 * top / scale))))
    while n <= MAX_DEGREE:
        nodes = np.cos(np.pi * (np.arange(n) + 0.5) / n)
        c = scipy.fft.dct(function((nodes + 1.0) * (0.5 * top)), type=2) / n
        c[0] /= 2.0
        tail = np.cumsum(np.abs(c[::-1]))[::-1]
        if tail[3 * n // 4] < 0.1 * tol:
            return c[: max(1, int(np.argmax(tail < tol)))].copy()
        n *= 2
    raise NumericalError(f"the Chebyshev series needs more than {MAX_DEGREE} degrees for tolerance {tol:g}")


@dataclass(frozen=True)
class Recurrence:
    """The matrix of :func:`apply_series`'s recurrence, its rows in a cache-friendly order (module notes).

    Attributes
    ----------
    matrix : csr (n, n)
        ``Y₂[order][:, order]``, with ``Y₂ = 4 M⁻¹L / λ̄ − 2I``.
    order : (n,) int ndarray
        The vertex of each row of ``matrix``.
    """

    matrix: sp.csr_matrix
    order: np.ndarray


def recurrence_matrix(stiffness: sp.spmatrix, mass: np.ndarray, top: float) -> Recurrence:
    """``Y₂ = 4 M⁻¹L / λ̄ − 2I``: twice the argument ``2A/λ̄ − I`` of the series, as one sparse matrix, its
    rows and columns in reverse Cuthill–McKee order (module notes).

    Parameters
    ----------
    stiffness : sparse (n, n)
        ``L``, symmetric.
    mass : (n,) ndarray
        The diagonal of ``M``.
    top : float
        ``λ̄`` of the series.

    Examples
    --------
    >>> import scipy.sparse as sp
    >>> y2 = recurrence_matrix(sp.csr_matrix([[1.0, -1.0], [-1.0, 1.0]]), np.ones(2), 2.0)
    >>> y2.matrix.toarray()
    array([[ 0., -2.],
           [-2.,  0.]])
    """
    lap = sp.csr_matrix(stiffness)
    order = reverse_cuthill_mckee(lap, symmetric_mode=True).astype(np.int64)
    y2 = lap[order]  # a copy: its rows in the new order, then its columns renamed
    inverse = np.empty(len(order), dtype=y2.indices.dtype)
    inverse[order] = np.arange(len(order))
    y2.indices = inverse[y2.indices]
    y2.data *= np.repeat(4.0 / (top * np.asarray(mass, dtype=float)[order]), np.diff(y2.indptr))
    y2.setdiag(y2.diagonal() - 2.0)
    y2.sort_indices()
    return Recurrence(y2, order)


def apply_series(coefficients: np.ndarray, y2: Recurrence, v: np.ndarray, threads: int | None = None) -> np.ndarray:
    """``p(A) v`` for ``p = Σ c_j T_j(2λ/λ̄ − 1)``, by the three-term recurrence ``T_{j+1}(Y) v = Y₂ T_j(Y) v −
    T_{j−1}(Y) v``.

    Several series share the vectors ``T_j(Y) v``: one sparse product per degree for all of them.

    Parameters
    ----------
    coefficients : (d + 1,) or (s, d + 1) ndarray
        From :func:`chebyshev_series`: one series, or ``s`` of them (shorter ones padded with zeros).
    y2 : Recurrence
        :func:`recurrence_matrix` with the series' ``λ̄``.
    v : (n,) or (n, k) ndarray
        Signals (columns), transformed together.
    threads : int, optional
        Threads that share the rows (:func:`~hht3d.linalg.threads.usable_cores` by default; one per
        :data:`THREAD_ROWS` rows at most).  The result does not depend on their number, to the bit.

    Returns
    -------
    ndarray
        The shape of ``v`` for one series; ``(s, *v.shape)`` for ``s``.

    Examples
    --------
    >>> import scipy.linalg, scipy.sparse as sp
    >>> path = sp.diags([[-1.0] * 3, [1.0, 2.0, 2.0, 1.0], [-1.0] * 3], [-1, 0, 1]).tocsr()
    >>> c = chebyshev_series(lambda lam: np.exp(-lam), 4.0, 1e-12)
    >>> v = np.array([1.0, 0.0, 0.0, 0.0])
    >>> p = apply_series(c, recurrence_matrix(path, np.ones(4), 4.0), v)
    >>> bool(np.allclose(p, scipy.linalg.expm(-path.toarray()) @ v))
    True
    """
    v = np.asarray(v, dtype=float)[y2.order]
    c = np.asarray(coefficients, dtype=float)
    rows = c[:, None] if c.ndim == 1 else c.T  # (d + 1, s): row j scales T_j v in each series
    out = np.multiply.outer(rows[0], v)
    blocks = _row_blocks(y2.matrix, usable_cores() if threads is None else threads)
    # T_{j-1} and T_j alternate between two vectors: each block overwrites its own rows of T_{j-1} with
    # T_{j+1} = Y₂ T_j − T_{j−1}, which only its own rows of T_{j−1} enter
    vectors = [np.array(v), np.empty_like(v)]
    scaled = [np.empty_like(v[block]) for block, _ in blocks]

    def step(index: int, j: int, weights: np.ndarray) -> None:
        block, y2_block = blocks[index]
        current, previous = vectors[(j + 1) % 2], vectors[j % 2]
        t = np.asarray(y2_block @ current)
        if j == 1:
            t *= 0.5  # T_1 = Y v
        else:
            t -= previous[block]
        previous[block] = t
        for series, weight in enumerate(weights):
            if weight != 0.0:
                out[series, block] += np.multiply(t, weight, out=scaled[index])

    with ThreadPoolExecutor(len(blocks)) if len(blocks) > 1 else contextlib.nullcontext() as pool:
        for j, weights in enumerate(rows[1:], start=1):
            if pool is None:
                step(0, j, weights)
            else:
                list(pool.map(step, range(len(blocks)), [j] * len(blocks), [weights] * len(blocks)))
    result = np.empty_like(out)
    result[:, y2.order] = out  # back to the vertices' order
    return result[0] if c.ndim == 1 else result


def _row_blocks(y2: sp.csr_matrix, threads: int) -> list[tuple[slice, sp.csr_matrix]]:
    """``y2`` cut into up to ``threads`` blocks of consecutive rows of at least :data:`THREAD_ROWS`, each a view
    of its rows (no copy of the matrix)."""
    n = y2.shape[0]
    bounds = np.linspace(0, n, max(1, min(threads, n // THREAD_ROWS)) + 1).astype(np.int64)
    blocks = []
    for low, high in zip(bounds[:-1], bounds[1:]):
        first, last = y2.indptr[low], y2.indptr[high]
        rows = sp.csr_matrix(
            (y2.data[first:last], y2.indices[first:last], y2.indptr[low : high + 1] - first),
            shape=(int(high - low), y2.shape[1]),
            copy=False,
        )
        blocks.append((slice(int(low), int(high)), rows))
    return blocks
