"""hht3d's loggers: one hierarchy under ``hht3d``, with secrets redacted from every record.

Progress lines, the memory and time estimates of a run and the Dask dashboard's
address are records of the ``hht3d`` loggers (:func:`get_logger`); warnings
about results stay :mod:`warnings`.  Every logger made by :func:`get_logger`
carries :class:`Redacting`, so no handler, the application's included, can
print a credential or a signed URL's signature (:func:`hht3d.redaction.redact`).

As a library hht3d configures nothing: its top logger has a ``NullHandler``.
:func:`showing` makes its records visible for one call where the application has
attached no handler to them (``compute(progress=True)``, the CLI's ``-v``/``-q``).

Examples
--------
>>> import io, logging
>>> from hht3d.logs import get_logger
>>> stream = io.StringIO()
>>> logger = get_logger("hht3d.example")
>>> handler = logging.StreamHandler(stream)
>>> logger.addHandler(handler)
>>> logger.warning("reading %s", "https://b.example/x.ply?X-Amz-Signature=abc")
>>> logger.removeHandler(handler)
>>> stream.getvalue()
'reading https://b.example/x.ply?X-Amz-Signature=***\\n'
"""

from __future__ import annotations

import argparse
import contextlib
import logging
import sys
from collections.abc import Iterator
from typing import Any

from .redaction import redact

__all__ = [
    "LOGGER",
    "PROGRESS",
    "LEVELS",
    "Redacting",
    "get_logger",
    "showing",
    "quieted",
    "logging_options",
    "log_level",
]

#: The top of hht3d's logger hierarchy.
LOGGER = "hht3d"
#: The logger of progress lines (:class:`hht3d.execution.progress.ProgressLines`).
PROGRESS = "hht3d.progress"
#: Level names the CLI's ``--log-level`` takes.
LEVELS = ("debug", "info", "warning", "error")


class Redacting(logging.Filter):
    """Replaces a record's message by its redacted text (its arguments merged in first)."""

    def filter(self, record: logging.LogRecord) -> bool:
        record.msg, record.args = redact(record.getMessage()), ()
        return True


_REDACTING = Redacting()


def get_logger(name: str = LOGGER) -> logging.Logger:
    """The logger ``name`` (``hht3d`` or one below it), redacting every record it makes."""
    logger = logging.getLogger(name)
    if _REDACTING not in logger.filters:
        logger.addFilter(_REDACTING)
    return logger


get_logger().addHandler(logging.NullHandler())


class _Prefixed(logging.Formatter):
    """``hht3d: MESSAGE``, and ``hht3d: warning: MESSAGE`` from warnings up."""

    def format(self, record: logging.LogRecord) -> str:
        level = "" if record.levelno < logging.WARNING else f"{record.levelname.lower()}: "
        return f"hht3d: {level}{record.getMessage()}"


def _configured(logger: logging.Logger) -> bool:
    """Whether the application attached a handler of its own to ``hht3d`` (or one of its loggers):
    then it decides where hht3d's records go.  A handler on the root logger alone does not count."""
    names = {name for name in logging.root.manager.loggerDict if name == LOGGER or name.startswith(LOGGER + ".")}
    return any(
        not isinstance(h, logging.NullHandler) and not getattr(h, "_hht3d", False)
        for name in names | {logger.name}
        for h in logging.getLogger(name).handlers
    )


@contextlib.contextmanager
def showing(level: int = logging.INFO, *, info: Any = None, force: bool = False) -> Iterator[None]:
    """hht3d's records of ``level`` and above on stderr while inside.

    With ``info`` (a stream; the CLI gives stdout), records below WARNING other than progress
    lines go there instead, beside the command's results, so that stderr holds only progress,
    warnings and errors.  Where the application has configured logging it decides, unless
    ``force`` (the CLI, whose ``-v``/``-q``/``--log-level`` set ``level``).  The top logger's
    level and handlers are restored on exit.
    """
    logger = get_logger()
    if _configured(logger) and not force:
        yield
        return
    handlers = [logging.StreamHandler(sys.stderr)]
    if info is not None:
        handlers[0].addFilter(lambda r: r.levelno >= logging.WARNING or r.name == PROGRESS)
        handlers.append(logging.StreamHandler(info))
        handlers[1].addFilter(lambda r: r.levelno < logging.WARNING and r.name != PROGRESS)
    previous = logger.level, logger.propagate
    for handler in handlers:
        handler.setFormatter(_Prefixed())
        setattr(handler, "_hht3d", True)  # ours, not the application's
        logger.addHandler(handler)
    logger.setLevel(level)
    logger.propagate = False
    try:
        yield
    finally:
        for handler in handlers:
            logger.removeHandler(handler)
        logger.level, logger.propagate = previous


@contextlib.contextmanager
def quieted(name: str, level: int = logging.CRITICAL) -> Iterator[None]:
    """Another library's logger ``name`` at ``level`` while inside, its own level restored on exit."""
    logger = logging.getLogger(name)
    previous = logger.level
    logger.setLevel(level)
    try:
        yield
    finally:
        logger.setLevel(previous)


def logging_options() -> argparse.ArgumentParser:
    """The CLI's ``-v``, ``-q`` and ``--log-level``, which every command takes (an argparse parent)."""
    common = argparse.ArgumentParser(add_help=False)
    loudness = common.add_mutually_exclusive_group()
    loudness.add_argument("-v", "--verbose", action="store_true", help="also debugging messages")
    loudness.add_argument(
        "-q",
        "--quiet",
        action="store_true",
        help="warnings and errors only: no progress, estimates or dashboard address",
    )
    loudness.add_argument(
        "--log-level", choices=LEVELS, default=None, help="the least important messages shown (default: info)"
    )
    return common


def log_level(args: argparse.Namespace) -> int:
    """The level of hht3d's messages on stderr that ``-v``, ``-q`` or ``--log-level`` ask for."""
    if args.log_level:
        return getattr(logging, args.log_level.upper())
    return logging.DEBUG if args.verbose else logging.WARNING if args.quiet else logging.INFO
