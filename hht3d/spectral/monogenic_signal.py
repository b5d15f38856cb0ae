"""Monogenic signals of IMFs on surfaces: local amplitude, phase and frequency (Sec. 4.3).

For an IMF ``f`` with Riesz transform ``R f`` (:func:`hht3d.spectral.riesz_transform.riesz`),
the monogenic signal ``f + (i, j, k)·R f`` (Eq. 20) has, with ``q = |R f|``,

* local amplitude ``a = √(f² + q²)`` (Eq. 21),
* local phase ``φ = atan2(q, f) ∈ [0, π]`` (Eq. 22, the arctangent of
  ``q / f`` taken in the right half-turn),
* instantaneous frequency ``ω = |∇φ|`` (Eq. 23), estimated by
  :func:`hht3d.spectral.frequency.instantaneous_frequency`: by default from the
  phase increments along edges (exact for sampled plane waves up to the
  mesh's resolution limit), or with ``frequency="gradient"`` by
  differentiating the sampled fields as the paper writes it.  The module
  notes of :mod:`hht3d.spectral.frequency` say what the number means (the wavenumber
  for 1-D waves, about 0.80 of it for isotropic patterns) and how far a
  surface resolves it.

Since ``a cos φ = f`` exactly, ``Σ_k a_k cos φ_k + residue`` reproduces the
signal.  Frequencies are in radians per model unit of length.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InputError
from ..geometry.surface import Surface
from ..geometry.validation import as_signals, check_surface
from .frequency import instantaneous_frequency
from .options import RieszOptions
from .resolution import ResolutionReport, resolution_report, resolvable_from_area
from .riesz_transform import fractional_laplacian, vertex_gradient

__all__ = ["MonogenicSignal", "monogenic", "monogenic_from_potential", "monogenic_from_riesz"]


@dataclass(frozen=True)
class MonogenicSignal:
    """Monogenic quantities of ``k`` signals (e.g. IMFs) on ``n`` vertices.

    Attributes
    ----------
    imfs : (k, n) ndarray
        The input signals ``f_k`` (IMFs).
    riesz : (k, n, 3) ndarray
        Riesz transforms ``R f_k`` (tangent vectors).
    amplitude : (k, n) ndarray
        Local amplitude ``a_k`` (Eq. 21).
    phase : (k, n) ndarray
        Local phase ``φ_k ∈ [0, π]`` (Eq. 22).
    frequency : (k, n) ndarray
        Instantaneous frequency ``|∇φ_k|`` (Eq. 23), radians per unit
        length; 0 where ``a_k = 0``.  What it means for 1-D and isotropic
        patterns: :mod:`hht3d.spectral.frequency`.
    area : (n,) ndarray, optional
        Vertex areas ``A_v`` (the lumped mass): they give the resolution
        limit ``π/√A_v`` (:attr:`resolvable`) and weigh the energy
        ``a² A_v`` of :attr:`resolution`.
    """

    imfs: np.ndarray
    riesz: np.ndarray
    amplitude: np.ndarray
    phase: np.ndarray
    frequency: np.ndarray
    area: np.ndarray | None = None

    @property
    def n_signals(self) -> int:
        return len(self.imfs)

    @property
    def resolvable(self) -> np.ndarray:
        """Per-vertex resolution limit ``π/√A_v`` (:func:`hht3d.spectral.resolution.resolvable_from_area`)."""
        return resolvable_from_area(self._area())

    def _area(self) -> np.ndarray:
        if self.area is None:
            raise InputError(
                "this monogenic signal carries no vertex areas; build it with hht3d.spectral.monogenic or pass area="
            )
        return self.area

    def reconstruct(self) -> np.ndarray:
        """``Σ_k a_k cos φ_k`` (n,): the sum of the signals, to round-off."""
        return np.sum(self.amplitude * np.cos(self.phase), axis=0)

    @property
    def resolution(self) -> ResolutionReport:
        """Frequencies above their vertex's resolution limit, weighted by the energy ``a² A_v``.

        The same figures as :attr:`hht3d.spectral.spectrum.HilbertSpectrum.resolution`.
        """
        area = self._area()
        return resolution_report(self.frequency, self.resolvable, self.amplitude**2 * area, area)


def monogenic(
    surface: Surface,
    imfs: np.ndarray,
    options: RieszOptions | dict | None = None,
    *,
    backend: str | None = None,
    **overrides: Any,
) -> MonogenicSignal:
    """Monogenic signal of every IMF: Algorithm 2, steps 2–5 (Eqs. 20–23).

    ``L^{-1/2}`` of all IMFs comes from one multi-signal call of
    :func:`hht3d.spectral.riesz_transform.fractional_laplacian`, then
    :func:`monogenic_from_potential`.

    Parameters
    ----------
    surface : Surface
    imfs : (k, n) or (n,) array_like
        IMFs (a single signal is treated as ``k = 1``).
    options : RieszOptions or dict, optional
        ``gradient`` (used for the Riesz transform and for ``∇φ``),
        ``frequency`` (the estimator of Eq. 23,
        :func:`hht3d.spectral.frequency.instantaneous_frequency`: edge phase
        increments, exact for plane waves up to the resolution limit, or the
        paper's gradients of the sampled fields), and ``potential``, ``tol``,
        ``eigenpairs`` (how ``L^{-1/2}`` is applied, see
        :func:`hht3d.spectral.riesz_transform.fractional_laplacian`);
        default :data:`~hht3d.spectral.options.RIESZ_DEFAULTS`.
    backend : str, optional
        Sparse solver of :mod:`hht3d.linalg`.
    **overrides
        Settings that replace those of ``options``.

    Returns
    -------
    MonogenicSignal

    Examples
    --------
    Amplitude and phase give the signals back, ``a cos φ = f`` (Eqs. 21-22),
    with ``φ`` in ``[0, π]``:

    >>> import numpy as np
    >>> from hht3d import data_path, load, monogenic
    >>> sphere = load(data_path("sphere_oct4098.ply"))
    >>> x, y, z = sphere.vertices.T
    >>> signals = np.stack([z, x * y])
    >>> mono = monogenic(sphere, signals)
    >>> # the Riesz transform keeps the energy of a mean-free signal, ‖R f‖ = ‖f‖ (to the mesh's accuracy)
    >>> m = sphere.mass_diagonal
    >>> energy = np.einsum("kvi,kvi,v->k", mono.riesz, mono.riesz, m) / np.einsum("kv,kv,v->k", signals, signals, m)
    >>> np.round(energy, 2)
    array([1., 1.])
    """
    options = RieszOptions.of(options, **overrides)
    f = _signals(surface, imfs)
    potential = fractional_laplacian(surface, f, -0.5, options, backend=backend)
    return monogenic_from_potential(surface, f, potential, options)


def _signals(surface: Surface, imfs: np.ndarray) -> np.ndarray:
    return as_signals(check_surface(surface), imfs, "imfs")[0]


def monogenic_from_potential(
    surface: Surface,
    imfs: np.ndarray,
    potential: np.ndarray,
    options: RieszOptions | dict | None = None,
    **overrides: Any,
) -> MonogenicSignal:
    """Monogenic signal from precomputed ``L^{-1/2}`` of the IMFs (Eqs. 16, 20–23).

    Parameters
    ----------
    surface : Surface
    imfs : (k, n) or (n,) array_like
    potential : array_like, shape of ``imfs``
        ``L^{-1/2}`` of the IMFs, e.g. from
        :func:`hht3d.spectral.combine_quadrature_parts`.
    options : RieszOptions or dict, optional
        ``gradient`` and ``frequency`` (the estimator of Eq. 23) are used; see :func:`monogenic`.
    **overrides
        Settings that replace those of ``options``.

    Returns
    -------
    MonogenicSignal
    """
    options = RieszOptions.of(options, **overrides)
    f = _signals(surface, imfs)
    u = as_signals(surface, potential, "potential")[0]
    if u.shape != f.shape:
        raise InputError(f"potential has shape {u.shape}; the imfs have {f.shape}")
    return monogenic_from_riesz(surface, f, vertex_gradient(surface, u, options.gradient), options)


def monogenic_from_riesz(
    surface: Surface, imfs: np.ndarray, rf: np.ndarray, options: RieszOptions | dict | None = None
) -> MonogenicSignal:
    """Monogenic signal from the IMFs and their Riesz vectors (Eqs. 20–23).

    Parameters
    ----------
    surface : Surface
    imfs : (k, n) or (n,) array_like
    rf : (k, n, 3) array_like
        Tangent Riesz vectors of the IMFs (:func:`hht3d.spectral.multilevel.riesz_part`).
    options : RieszOptions or dict, optional
        ``frequency`` (the estimator of Eq. 23) is used.

    Returns
    -------
    MonogenicSignal

    Examples
    --------
    >>> import numpy as np
    >>> from hht3d import data_path, load
    >>> from hht3d.spectral import monogenic_from_riesz, riesz
    >>> sphere = load(data_path("sphere_oct4098.ply"))
    >>> z = sphere.vertices[:, 2]
    >>> mono = monogenic_from_riesz(sphere, z[None], riesz(sphere, z)[None])
    >>> bool(np.allclose(mono.amplitude * np.cos(mono.phase), z))  # a cos φ = f (Eqs. 21-22)
    True
    """
    options = RieszOptions.of(options)
    f = _signals(surface, imfs)
    rf = np.asarray(rf, dtype=np.float64)
    if rf.shape != (*f.shape, 3):
        raise InputError(f"riesz vectors have shape {rf.shape}; the imfs need {(*f.shape, 3)}")
    omega = instantaneous_frequency(surface, f, rf, options)  # first: its work arrays are the stage's peak
    q = np.hypot(np.hypot(rf[..., 0], rf[..., 1]), rf[..., 2])  # no overflow at 1e200, no underflow at 1e-200
    return MonogenicSignal(
        imfs=f,
        riesz=rf,
        amplitude=np.hypot(f, q),
        phase=np.arctan2(q, f),
        frequency=omega,
        area=surface.mass_diagonal.copy(),
    )
