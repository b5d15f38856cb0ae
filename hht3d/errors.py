"""Exception hierarchy of hht3d.

Every error raised for bad user input is an :class:`HHT3DError`, so callers
(the CLI, the pipeline runner, a notebook) can catch one type and show its
message, which names the file or parameter at fault and what to change.
"""


class HHT3DError(Exception):
    """Base class of every error hht3d raises on purpose."""


class InputError(HHT3DError, ValueError):
    """Bad input: unreadable or degenerate geometry, wrong signal, bad parameter."""


class NumericalError(HHT3DError, RuntimeError):
    """A numerical step failed (singular system, factorization error)."""


class PipelineError(HHT3DError):
    """An invalid pipeline description or a failed pipeline step."""
