"""Checks of user input shared by the core: surfaces, signals and IMFs, arrays of per-vertex values.

Every function either returns the checked value (converted where that is
the point, e.g. a signal to a float64 array) or raises
:class:`~hht3d.errors.InputError` with a message that names the argument,
what it must be and what was given.  Modules check their arguments with
these instead of writing their own; a new check belongs here when a second
module needs it.  Scalar settings are checked by the option records that
declare them (:mod:`hht3d.records`).
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from .surface import Surface

__all__ = ["check_surface", "check_signal", "as_signals", "as_imfs"]


def check_surface(surface: object) -> Surface:
    """``surface`` if it is an :class:`~hht3d.geometry.surface.Surface`.

    Parameters
    ----------
    surface : object
        The value to check.

    Returns
    -------
    Surface
        ``surface`` itself.

    Examples
    --------
    >>> from hht3d import load, data_path
    >>> check_surface(load(data_path("spot.ply"))).n_vertices
    2930
    >>> check_surface("spot.ply")
    Traceback (most recent call last):
    hht3d.errors.InputError: expected an hht3d.Surface, got str
    """
    if not isinstance(surface, Surface):
        raise InputError(f"expected an hht3d.Surface, got {type(surface).__name__}")
    return surface


def check_signal(surface: Surface, values: np.ndarray, what: str = "signal") -> np.ndarray:
    """One finite real float per vertex of ``surface``, as an ``(n,)`` float64 array.

    Complex values are refused rather than cut to their real part; a wrong
    length after cleaning says how to index the signal.

    Parameters
    ----------
    surface : Surface
        The surface the signal lives on.
    values : array_like
        One value per vertex.
    what : str, optional
        What the errors call ``values`` (default ``"signal"``).

    Returns
    -------
    (n,) ndarray
        The values as float64.

    Examples
    --------
    >>> from hht3d import data_path, load
    >>> spot = load(data_path("spot.ply"))
    >>> import numpy as np
    >>> from hht3d.geometry import check_signal
    >>> check_signal(spot, np.arange(2930)).dtype
    dtype('float64')
    >>> check_signal(spot, np.zeros(10))
    Traceback (most recent call last):
    hht3d.errors.InputError: signal has shape (10,); spot has 2930 vertices
    """
    if np.iscomplexobj(values):
        raise InputError(
            f"{what} is complex; pass a real signal, e.g. its real part (values.real) or its magnitude (abs(values))"
        )
    try:
        a = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"{what} is not numeric") from None
    if a.ndim != 1 or len(a) != surface.n_vertices:
        hint = ""
        if surface.clean_report is not None and surface.clean_report.changed and a.ndim == 1:
            hint = (
                f"; cleaning changed the vertex count ({surface.clean_report.summary()}): "
                "index it with surface.clean_report.kept_vertices or load with clean=False"
            )
        raise InputError(f"{what} has shape {a.shape}; {surface.name} has {surface.n_vertices} vertices{hint}")
    bad = ~np.isfinite(a)
    if bad.any():
        raise InputError(
            f"{what} has {int(bad.sum())} NaN or infinite values (first at vertex {int(np.flatnonzero(bad)[0])})"
        )
    return a


def as_signals(surface: Surface, f: np.ndarray, what: str = "signal") -> tuple[np.ndarray, bool]:
    """``f`` as a finite ``(k, n)`` float array, and whether it was a single ``(n,)`` signal.

    Parameters
    ----------
    surface : Surface
        The surface the signals live on.
    f : ndarray
        One signal ``(n,)`` or a stack ``(k, n)``.
    what : str, optional
        What the errors call ``f`` (default ``"signal"``).

    Returns
    -------
    signals : (k, n) ndarray
        The signals as float64.
    single : bool
        Whether ``f`` was one ``(n,)`` signal.

    Examples
    --------
    >>> from hht3d import data_path, load
    >>> spot = load(data_path("spot.ply"))
    >>> import numpy as np
    >>> from hht3d.geometry import as_signals
    >>> signals, single = as_signals(spot, np.ones(2930))
    >>> signals.shape, single
    ((1, 2930), True)
    """
    try:
        a = np.asarray(f, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"{what} is not numeric") from None
    n = surface.n_vertices
    if a.ndim not in (1, 2) or a.shape[-1] != n:
        raise InputError(f"{what} must have shape ({n},) or (k, {n}) for {surface.name} ({n} vertices), got {a.shape}")
    bad = ~np.isfinite(a)
    if bad.any():
        first = np.argwhere(bad)[0]
        where = f"row {first[0]}, vertex {first[1]}" if a.ndim == 2 else f"vertex {first[0]}"
        raise InputError(f"{what} has {int(bad.sum())} NaN or infinite values (first at {where})")
    return np.atleast_2d(a), a.ndim == 1


def as_imfs(surface: Surface, imfs: np.ndarray) -> np.ndarray:
    """At least one finite IMF as a ``(k, n)`` array, from an array, an EMD or an HHT result.

    Parameters
    ----------
    surface : Surface
        The surface the IMFs live on.
    imfs : ndarray or EMDResult or HHTResult
        The IMFs, ``(k, n)`` or one ``(n,)``, or a result with an ``imfs`` attribute.

    Returns
    -------
    (k, n) ndarray
        The IMFs as float64, ``k >= 1``.

    Examples
    --------
    >>> from hht3d import data_path, load
    >>> spot = load(data_path("spot.ply"))
    >>> import numpy as np
    >>> from hht3d.geometry import as_imfs
    >>> as_imfs(spot, np.ones(2930)).shape  # one IMF becomes a stack of one
    (1, 2930)
    """
    a = getattr(imfs, "imfs", imfs)
    try:
        a = np.asarray(a, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError("imfs are not numeric") from None
    if a.ndim == 1:
        a = a[None]
    if a.ndim != 2 or a.shape[1] != surface.n_vertices:
        raise InputError(f"imfs must have shape (k, {surface.n_vertices}) for {surface.name}, got {a.shape}")
    if len(a) == 0:
        raise InputError(f"{surface.name}: the decomposition has no IMFs; there are no extrema to count")
    if not np.all(np.isfinite(a)):
        raise InputError("imfs have NaN or infinite values")
    return a
