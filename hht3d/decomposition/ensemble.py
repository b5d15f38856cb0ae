"""Ensemble EMD (Wu & Huang 2009): EMD of noisy copies of a signal, averaged.

Each member decomposes the signal plus one seeded white-noise realisation
(:func:`eemd_member`); members are independent, so the lazy graph runs them
as tasks of their own, and :func:`combine_eemd` averages them.
"""

from __future__ import annotations

import numbers
import warnings
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..errors import HHT3DDeprecationWarning, InputError
from ..geometry.surface import Surface
from ..geometry.validation import check_signal, check_surface
from ..records import route
from .decompose import EMDResult, emd, result_with_quality
from .envelopes import envelope_energies
from .options import EMDOptions, EnsembleOptions
from .quality import quality_warnings_muted

__all__ = ["eemd", "eemd_member", "combine_eemd", "ensemble_settings"]


def ensemble_settings(
    options: EMDOptions | dict | None, ensemble: EnsembleOptions | dict | None, overrides: dict
) -> tuple[EMDOptions, EnsembleOptions]:
    """The EMD and ensemble records from records or dicts, each override sent to the record that has it.

    Raises
    ------
    InputError
        An override that neither record has, or an invalid setting.
    """
    emd_overrides, ensemble_overrides = route(overrides, EMDOptions, EnsembleOptions)
    return EMDOptions.of(options, **emd_overrides), EnsembleOptions.of(ensemble, **ensemble_overrides)


def eemd_member(
    surface: Surface,
    signal: np.ndarray,
    member_index: int,
    options: EMDOptions,
    ensemble: EnsembleOptions,
    backend: str | None = None,
) -> EMDResult:
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
    options : EMDOptions
        The settings of each member's :func:`~hht3d.decomposition.emd`.
    ensemble : EnsembleOptions
        The seed and the noise's standard deviation relative to the signal's.
        (The two records come in :func:`eemd`'s order; the former order,
        ensemble first, is accepted for one release with a DeprecationWarning.)
    backend : str, optional
        Sparse solver of :mod:`hht3d.linalg`.

    Returns
    -------
    EMDResult
        The decomposition of the *noisy* signal (its IMFs plus residue equal
        the signal plus noise); average members with :func:`combine_eemd`.
    """
    f = check_signal(check_surface(surface), signal)
    if isinstance(options, EnsembleOptions) and isinstance(ensemble, EMDOptions):
        warnings.warn(
            "eemd_member(surface, signal, i, ensemble, options) is deprecated: pass the EMD options first, as to eemd",
            HHT3DDeprecationWarning,
            stacklevel=2,
        )
        options, ensemble = ensemble, options
    if isinstance(member_index, bool) or not isinstance(member_index, numbers.Integral) or member_index < 0:
        raise InputError(f"member_index must be an integer >= 0, got {member_index!r}")
    rng = np.random.default_rng(np.random.SeedSequence(ensemble.seed, spawn_key=(int(member_index),)))
    noise = ensemble.noise_std * np.std(f) * rng.standard_normal(len(f))
    with quality_warnings_muted():  # a noisy member's quality is not the ensemble's
        return emd(surface, f + noise, options, backend=backend)


def combine_eemd(surface: Surface, signal: np.ndarray, members: Sequence[Any]) -> EMDResult:
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

    Returns
    -------
    EMDResult
        The members' average IMFs and residue, with their quality figures.
    """
    f = check_signal(check_surface(surface), signal)
    members = list(members)
    if not members:
        raise InputError("EEMD needs at least one ensemble member")
    if any(m.residue.shape != f.shape for m in members):
        raise InputError(f"EEMD members do not match the signal of shape {f.shape}")
    k = max(m.n_imfs for m in members)
    imfs = np.zeros((k, len(f)))
    for m in members:
        imfs[: m.n_imfs] += m.imfs
    imfs /= len(members)
    info = {
        "method": members[0].info.get("method"),
        "ensemble_size": len(members),
        "member_n_imfs": [m.n_imfs for m in members],
        "n_imfs": k,
        "sifts": sum(m.info["sifts"] for m in members),
        "factorizations": sum(m.info["factorizations"] for m in members),
        "seconds": sum(m.info["seconds"] for m in members),
        "backend": members[0].info["backend"],
        "max_constraint_error": max(m.info["max_constraint_error"] for m in members),
    }
    return result_with_quality(surface, f, imfs, info)


def eemd(
    surface: Surface,
    signal: np.ndarray,
    options: EMDOptions | dict | None = None,
    *,
    ensemble: EnsembleOptions | dict | None = None,
    backend: str | None = None,
    **overrides: Any,
) -> EMDResult:
    """Ensemble EMD (Wu & Huang 2009), the remedy for mode mixing.

    Runs :func:`eemd_member` for members ``0 .. ensemble_size − 1`` and
    averages them with :func:`combine_eemd`.

    Parameters
    ----------
    surface : Surface
    signal : (n,) array_like
    options : EMDOptions or dict, optional
        The settings of every member's :func:`~hht3d.decomposition.emd`.
    ensemble : EnsembleOptions or dict, optional
        ``ensemble_size`` (default 100 as in Wu & Huang 2009; the noise left
        in the IMFs falls like ``noise_std / √ensemble_size``), ``noise_std``
        (white noise relative to the signal's standard deviation, default
        0.2) and ``seed`` (the same seed gives identical results).
    backend : str, optional
        Sparse solver of :mod:`hht3d.linalg`.
    **overrides
        Settings of either record, by name (``max_imfs=3, ensemble_size=20``).

    Returns
    -------
    EMDResult
        The ensemble-averaged IMFs, ``residue`` (n,), ``info`` and ``quality``.

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
    options, ensemble = ensemble_settings(options, ensemble, overrides)
    f = check_signal(check_surface(surface), signal)
    held = envelope_energies(surface)  # the surface caches them weakly: held, the members build them once
    members = [eemd_member(surface, f, i, options, ensemble, backend) for i in range(ensemble.ensemble_size)]
    del held
    result = combine_eemd(surface, f, members)
    result.info.update(seed=ensemble.seed, noise_std=ensemble.noise_std)
    return result
