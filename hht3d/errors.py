"""Exception hierarchy of hht3d, and how messages show user values.

Every error raised for bad user input is an :class:`HHT3DError`, so callers
(the CLI, the pipeline runner, a notebook) can catch one type and show its
message, which names the file or parameter at fault and what to change.
Messages echo user values through :func:`shown` and exception texts through
:func:`one_line`, so a huge value (a YAML alias bomb, a megabyte string)
never floods the terminal, every message stays on one line and no credential
is shown.
"""

import difflib
import reprlib
from collections.abc import Collection
from typing import Any

from .redaction import redact

__all__ = [
    "HHT3DError",
    "InputError",
    "NumericalError",
    "PipelineError",
    "OutputError",
    "shown",
    "one_line",
    "MAX_SHOWN",
    "did_you_mean",
    "HHT3DDeprecationWarning",
]

#: Characters of a user value a message echoes before cutting it short.
MAX_SHOWN = 80


class HHT3DError(Exception):
    """Base class of every error hht3d raises on purpose."""


class HHT3DDeprecationWarning(DeprecationWarning):
    """A former name or call shape of hht3d, accepted for one release (the test suite makes it an error)."""


class InputError(HHT3DError, ValueError):
    """Bad input: unreadable or degenerate geometry, wrong signal, bad parameter."""


class NumericalError(HHT3DError, RuntimeError):
    """A numerical step failed (singular system, factorization error)."""


class PipelineError(HHT3DError):
    """An invalid pipeline description or a failed pipeline step."""


class OutputError(HHT3DError):
    """An output location cannot be written: no permission, a file in the way, a full disk."""


def _cut(text: str, limit: int) -> str:
    if len(text) <= limit:
        return text
    return f"{text[:limit]}... ({len(text)} characters)"


def _short_repr() -> reprlib.Repr:
    """A :class:`reprlib.Repr` that abbreviates nested and long values (keywords need Python 3.12)."""
    short = reprlib.Repr()
    short.maxlevel, short.maxstring, short.maxother = 3, MAX_SHOWN, MAX_SHOWN
    short.maxtuple = short.maxlist = short.maxset = 6
    short.maxdict = 4
    return short


_REPR = _short_repr()


def shown(value: Any, limit: int = MAX_SHOWN) -> str:
    """``repr(value)`` for a message, cut to about ``limit`` characters.

    Nested containers are abbreviated while they are formatted
    (:mod:`reprlib`), so an alias-expanded YAML value of millions of items
    costs no more than a short one.  A string is redacted before it is cut,
    so that cutting cannot separate a URL's password from the ``@`` that
    marks it.
    """
    return _cut(_REPR.repr(redact(value) if isinstance(value, str) else value), limit)


def one_line(text: object, limit: int = 4 * MAX_SHOWN) -> str:
    """``text`` with its whitespace runs (newlines included) made single spaces, secrets redacted
    (:func:`hht3d.redaction.redact`), cut to ``limit``."""
    return _cut(" ".join(redact(text).split()), limit)


def did_you_mean(word: str, known: Collection[str], *, listing: bool = True) -> str:
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
