"""Guarded tasks: an exception inside a dataset item's task becomes a record its later tasks pass along.

So one unreadable or degenerate file is reported with its step and reason
while the other files of a dataset or pipeline run finish.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any

from ..decomposition.quality import quality_warnings_muted
from ..errors import one_line

__all__ = ["Failure", "Guarded", "Timed", "MAX_ERROR"]

#: Characters of an exception's message kept in a summary row.
MAX_ERROR = 500


@dataclass(frozen=True)
class Failure:
    """Why a dataset item failed: the step, the input file and the error."""

    step: str
    source: str
    error: str


@dataclass(frozen=True)
class Timed:
    """A guarded task's value and its own run time."""

    value: object
    seconds: float


class Guarded:
    """Run ``func`` unless an input already failed; turn an exception into a :class:`Failure`."""

    def __init__(self, step: str, func: Callable[..., Any], source: str):
        self.step, self.func, self.source = step, func, source
        self.__name__ = f"{step}"

    def __dask_tokenize__(self) -> tuple:
        return (self.step, self.func.__module__, self.func.__qualname__, self.source)

    def __call__(self, *args: Any, **kwargs: Any) -> Timed | Failure:
        values = [_unwrap(a) for a in args]
        kwargs = {k: _unwrap(v) for k, v in kwargs.items()}
        failed = next((a for a in _flat(values, kwargs) if isinstance(a, Failure)), None)
        if failed is not None:
            return failed
        start = time.perf_counter()
        try:
            with quality_warnings_muted():  # the summary row reports the quality figures instead
                value = self.func(*values, **kwargs)
        except Exception as exc:  # a dataset item must never take the others down
            return Failure(self.step, self.source, one_line(f"{type(exc).__name__}: {exc}", MAX_ERROR))
        return Timed(value, time.perf_counter() - start)


def _unwrap(value: Any) -> Any:
    if isinstance(value, Timed):
        return value.value
    if isinstance(value, (list, tuple)):
        return type(value)(_unwrap(v) for v in value)
    return value


def _flat(args: Sequence[Any], kwargs: dict[str, Any]) -> Iterator[Any]:
    for value in [*args, *kwargs.values()]:
        yield from (value if isinstance(value, (list, tuple)) else [value])
