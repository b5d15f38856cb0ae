"""The filter of :mod:`.filtering` applied by solves: its pass band in Clenshaw form, and the bilaplacian's
resolvent as one complex factorization of a second-order system.

``P(W)`` (:func:`passband`) is a polynomial of degree ``2m − 1`` in the low-pass ``W = (M̃ + K)⁻¹ M̃``;
:func:`apply_passband` takes it with ``2m − 1`` solves.  For the bilaplacian's global cut,
``K = t² L M̃⁻¹ L`` and

    M̃ + t² L M̃⁻¹ L = (M̃ + i t L) M̃⁻¹ (M̃ − i t L),   so   (M̃ + K)⁻¹ y = Re (M̃ + i t L)⁻¹ y

for a real ``y`` (in ``A = M̃⁻¹L``'s eigenbasis, ``Re 1/(1 + i tλ) = 1/(1 + t²λ²)``).  The complex system has
the pattern of ``L``, not of ``L M̃⁻¹ L``, which reaches the 2-ring: on nefertiti (50k vertices) SuperLU factorizes
it in 0.34 s against 0.81 s for the real fourth-order one, and its 31 solves take as long (0.74 s).
:func:`resolvent` uses it on a backend that factorizes complex symmetric systems
(:attr:`~hht3d.linalg.backends.Backend.complex_solver`: SuperLU), the real system elsewhere.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import lru_cache

import numpy as np
import scipy.sparse as sp
from scipy.special import betainc

from .. import linalg
from ..geometry.surface import Surface
from .envelopes import membrane_laplacian

__all__ = ["passband", "apply_passband", "resolvent"]


def passband(g: np.ndarray | float, order: int) -> np.ndarray:
    """``P(g) = 1 − I_g(m, m)``: the share of a component with low-pass response ``g`` kept in the IMF."""
    return 1.0 - betainc(order, order, np.clip(g, 0.0, 1.0))


@lru_cache(maxsize=None)
def _chebyshev(order: int) -> np.ndarray:
    """Chebyshev coefficients (in ``y = 2G − 1``) of :func:`passband`, a polynomial of degree ``2m − 1``."""
    degree = 2 * order - 1
    return np.polynomial.chebyshev.chebinterpolate(lambda y: passband((y + 1) / 2, order), degree)


def apply_passband(
    solve: Callable[[np.ndarray], np.ndarray], mass: np.ndarray, r: np.ndarray, order: int
) -> np.ndarray:
    """``P(W) r`` for ``W v = solve(mass · v)``, by Clenshaw's recurrence in ``Y = 2W − I``.

    ``P`` (:func:`passband`) has degree ``2m − 1`` in ``W``, written in Chebyshev form, so the
    recurrence is stable for any ``m``; it costs ``2m − 1`` solves.
    """
    coefficients = _chebyshev(order)

    def y(v: np.ndarray) -> np.ndarray:
        return 2.0 * solve(mass * v) - v

    b1, b2 = coefficients[-1] * r, np.zeros_like(r)
    for c in coefficients[-2:0:-1]:
        b1, b2 = c * r + 2.0 * y(b1) - b2, b1
    return coefficients[0] * r + y(b1) - b2


def resolvent(
    surface: Surface,
    mass: np.ndarray,
    width: float | None,
    backend: str | None,
    real: Callable[[], Callable[[np.ndarray], np.ndarray]],
) -> tuple[Callable[[np.ndarray], np.ndarray], bool]:
    """``y ↦ (M̃ + K)⁻¹ y`` after one factorization, and whether it was the complex one (module notes).

    Parameters
    ----------
    surface : Surface
    mass : (n,) ndarray
        ``M̃``.
    width : float or None
        ``t`` of a bilaplacian filter with a global cut, for the complex system; ``None`` otherwise.
    backend : str or None
        The sparse solver.
    real : callable
        Factorizes the real system ``M̃ + K`` and gives its solve; called only when it is used.
    """
    complex_solver = linalg.SOLVER_BACKENDS[linalg.check_backend(backend)].complex_solver
    if width is None or complex_solver is None:
        return real(), False
    solve = complex_solver(sp.diags(mass) + 1j * width * membrane_laplacian(surface), surface.vertices)
    return (lambda y: solve(y).real), True
