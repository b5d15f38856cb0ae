"""Checks of user input shared by the core: surfaces, signals, choices, integers, numbers.

Every function either returns the checked value (converted where that is
the point, e.g. a signal to a float64 array) or raises
:class:`~hht3d.errors.InputError` with a message that names the argument,
what it must be and what was given.  Modules check their arguments with
these instead of writing their own; a new check belongs here when a second
module needs it.
"""
from __future__ import annotations

import difflib
import math

import numpy as np

from ..errors import InputError
from .surface import Surface

__all__ = [
    "check_surface",
    "check_signal",
    "as_signals",
    "as_imfs",
    "check_choice",
    "did_you_mean",
    "check_int",
    "nonnegative",
    "finite",
    "positive",
    "check_distance",
]


def check_surface(surface) -> Surface:
    """``surface`` if it is an :class:`~hht3d.geometry.surface.Surface`.

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


def check_signal(surface: Surface, values, what: str = "signal") -> np.ndarray:
    """One finite real float per vertex of ``surface``, as an ``(n,)`` float64 array.

    Complex values are refused rather than cut to their real part; a wrong
    length after cleaning says how to index the signal.
    """
    if np.iscomplexobj(values):
        raise InputError(f"{what} is complex; pass a real signal, e.g. its real part (values.real) or its "
                         "magnitude (abs(values))")
    try:
        a = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"{what} is not numeric") from None
    if a.ndim != 1 or len(a) != surface.n_vertices:
        hint = ""
        if surface.clean_report is not None and surface.clean_report.changed and a.ndim == 1:
            hint = (f"; cleaning changed the vertex count ({surface.clean_report.summary()}): "
                    "index it with surface.clean_report.kept_vertices or load with clean=False")
        raise InputError(f"{what} has shape {a.shape}; {surface.name} has {surface.n_vertices} vertices{hint}")
    bad = ~np.isfinite(a)
    if bad.any():
        raise InputError(f"{what} has {int(bad.sum())} NaN or infinite values "
                         f"(first at vertex {int(np.flatnonzero(bad)[0])})")
    return a


def as_signals(surface: Surface, f, what: str = "signal") -> tuple[np.ndarray, bool]:
    """``f`` as a finite ``(k, n)`` float array, and whether it was a single ``(n,)`` signal."""
    try:
        a = np.asarray(f, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"{what} is not numeric") from None
    n = surface.n_vertices
    if a.ndim not in (1, 2) or a.shape[-1] != n:
        raise InputError(f"{what} must have shape ({n},) or (k, {n}) for {surface.name} "
                         f"({n} vertices), got {a.shape}")
    bad = ~np.isfinite(a)
    if bad.any():
        first = np.argwhere(bad)[0]
        where = f"row {first[0]}, vertex {first[1]}" if a.ndim == 2 else f"vertex {first[0]}"
        raise InputError(f"{what} has {int(bad.sum())} NaN or infinite values (first at {where})")
    return np.atleast_2d(a), a.ndim == 1


def as_imfs(surface: Surface, imfs) -> np.ndarray:
    """At least one finite IMF as a ``(k, n)`` array, from an array, an EMD or an HHT result."""
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


def did_you_mean(word, known, *, listing: bool = True) -> str:
    """``"; did you mean 'x'?"`` for the closest of ``known``; else the list of ``known``
    (with ``listing``) or nothing.

    Examples
    --------
    >>> did_you_mean("quadratur", ("quadrature", "spectral", "dense"))
    "; did you mean 'quadrature'?"
    >>> did_you_mean("x", ("quadrature", "dense"))
    '; known: dense, quadrature'
    >>> did_you_mean("x", ("quadrature", "dense"), listing=False)
    ''
    """
    known = [str(k) for k in known]
    plausible = isinstance(word, str) and len(word) <= 100  # never format a huge or nested value
    close = difflib.get_close_matches(word, known, n=1, cutoff=0.6) if plausible else []
    if close:
        return f"; did you mean {close[0]!r}?"
    return f"; known: {', '.join(sorted(known))}" if known and listing else ""


def check_choice(value, choices, what: str, *, suggest: bool = False):
    """``value`` if it is one of ``choices``; ``suggest`` adds the closest one to the message."""
    if value not in choices:
        hint = did_you_mean(str(value), choices, listing=False) if suggest else ""
        raise InputError(f"unknown {what} {value!r}; choose one of {choices}{hint}")
    return value


def check_int(name: str, value, minimum: int) -> int:
    """``value`` if it is an integer (not a bool) ``>= minimum``."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise InputError(f"{name} must be an integer >= {minimum}, got {value!r}")
    return value


def nonnegative(name: str, value) -> float:
    """``value`` as a float if it is a real number (not a bool or a string), finite and ``>= 0``."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.number)) \
            or not np.isfinite(value) or value < 0:
        raise InputError(f"{name} must be a finite number >= 0, got {value!r}")
    return float(value)


def _number(name: str, value) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a number, got {value!r}") from None


def finite(name: str, value) -> float:
    """``float(value)`` if that is a finite number."""
    x = _number(name, value)
    if not math.isfinite(x):
        raise InputError(f"{name} must be finite, got {value!r}")
    return x


def positive(name: str, value) -> float:
    """``float(value)`` if that is a finite number ``> 0``."""
    x = _number(name, value)
    if not (math.isfinite(x) and x > 0):
        raise InputError(f"{name} must be a finite number > 0, got {value!r}")
    return x


def check_distance(name: str, value) -> float:
    """A length in model units: ``float(value)``, finite and ``>= 0``; ``None`` is 0."""
    if value is None:
        return 0.0
    x = _number(name, value)
    if not (math.isfinite(x) and x >= 0):
        raise InputError(f"{name} must be a finite distance >= 0, got {value!r}")
    return x
