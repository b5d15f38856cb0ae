"""Typed parameters of pipeline operations and outputs, checked before anything runs.

A :class:`Param` knows its type, default, allowed range or choices and a
one-line description; :meth:`Param.check` turns a YAML value into the value
the core function receives, or raises :class:`~hht3d.errors.PipelineError`
saying where, what was expected and what was found.  :func:`did_you_mean`
adds the closest known name to messages about unknown names.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from ..apps.filters import GAINS, make_gain
from ..errors import InputError, PipelineError, did_you_mean, one_line, shown
from ..records import KINDS as RECORD_KINDS
from ..records import Record, Spec

__all__ = ["Param", "REQUIRED", "did_you_mean", "record_params", "yaml_text"]


class _Required:
    def __repr__(self) -> str:
        return "required"


#: Default of a parameter that must be given.
REQUIRED = _Required()

#: The kinds of :data:`hht3d.records.KINDS` and ``"gain"``.
KINDS = (*RECORD_KINDS, "gain")


def yaml_text(value: Any) -> str:
    """A value as it would be written in YAML (``null``, ``true``, ``0.2``, ``cotan``)."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    return str(value)


def _what(value: Any) -> str:
    """How a YAML value reads in a message: ``'six' (a string)``, ``null``."""
    names = {
        str: "a string",
        bool: "a boolean",
        int: "an integer",
        float: "a number",
        list: "a list",
        dict: "a mapping",
    }
    kind = next((n for t, n in names.items() if isinstance(value, t)), type(value).__name__)
    return "null" if value is None else f"{shown(value)} ({kind})"


@dataclass(frozen=True)
class Param:
    """One parameter: a name, a default and the allowed values of a :class:`~hht3d.records.Spec`.

    ``kind`` is a :data:`hht3d.records.KINDS` kind or ``"gain"`` (a mapping
    ``{kind: band_stop, ...}`` of :func:`hht3d.apps.make_gain`), the one kind
    option records lack.  A default of ``None`` or ``nullable`` makes ``null``
    an allowed value; :data:`REQUIRED` makes the parameter mandatory.  The
    parameters of a setting declared in an option record are made by
    :func:`record_params`, never written again.
    """

    name: str
    kind: str
    doc: str
    default: object = REQUIRED
    choices: Sequence = ()
    minimum: float | None = None
    maximum: float | None = None
    open_minimum: bool = False
    open_maximum: bool = False
    nullable: bool = False

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"parameter {self.name}: unknown kind {self.kind!r}")

    @classmethod
    def of_spec(cls, name: str, spec: Spec, default: Any) -> "Param":
        """The parameter of a record's setting: its spec under ``name`` with ``default``."""
        return cls(name, default=default, **dataclasses.asdict(spec))

    @property
    def required(self) -> bool:
        return self.default is REQUIRED

    @property
    def spec(self) -> Spec:
        """The parameter's allowed values as an option :class:`~hht3d.records.Spec`."""
        return Spec(
            self.doc,
            self.kind,
            self.choices,
            self.minimum,
            self.maximum,
            self.open_minimum,
            self.open_maximum,
            self.nullable or self.default is None,
        )

    def describe(self) -> str:
        """The type and range, e.g. ``int >= 0``, ``float in (0.5, 1]``, ``sd | s_number | fixed``."""
        if self.kind == "choice":
            return " | ".join(map(str, self.choices))
        if self.kind == "gain":
            return f"gain {{kind: {' | '.join(GAINS)}, ...}}"
        text = self.kind + self.spec.range_text()
        return f"{text} or null" if self.spec.nullable else text

    def check(self, value: Any, where: str) -> Any:
        """The checked value (ints stay ints, gains become :class:`~hht3d.apps.Gain` objects).

        Raises
        ------
        PipelineError
            ``"{where}: parameter NAME must be ..., got ..."``.
        """
        if self.kind == "gain":
            return _gain(value, f"{where}: parameter {self.name}")
        spec = self.spec
        if spec.accepts(value):
            return value if value is None or self.kind != "float" else float(value)
        expected = spec.expected(null="")
        if value is None and self.kind in ("int", "float"):
            expected += " (not null)"
        hint = did_you_mean(value, self.choices, listing=False) if self.kind == "choice" else ""
        raise PipelineError(f"{where}: parameter {self.name} must be {expected}; got {_what(value)}{hint}")


def _gain(value: Any, where: str) -> Any:
    """A gain from ``{kind: NAME, PARAM: VALUE, ...}``."""
    if not isinstance(value, dict) or "kind" not in value:
        raise PipelineError(
            f"{where} must be a mapping with a kind ({', '.join(GAINS)}) and its "
            f"parameters, e.g. {{kind: band_stop, low: 8, high: 20}}; got {_what(value)}"
        )
    options = dict(value)
    kind = options.pop("kind")
    if not isinstance(kind, str) or kind not in GAINS:
        raise PipelineError(f"{where}: unknown gain kind {shown(kind)}{did_you_mean(kind, GAINS)}")
    fields = [f.name for f in dataclasses.fields(GAINS[kind])]
    for key in options:
        if key not in fields:
            raise PipelineError(f"{where}: gain {kind} has no parameter {shown(key)}{did_you_mean(key, fields)}")
    try:
        return make_gain(kind, **options)
    except InputError as exc:
        raise PipelineError(f"{where}: {one_line(exc)}") from None


def record_params(record: type[Record]) -> tuple[Param, ...]:
    """One parameter per setting of an option record, with the record's default, range and description."""
    defaults = record.defaults()
    return tuple(
        Param.of_spec(name, spec, REQUIRED if defaults[name] is dataclasses.MISSING else defaults[name])
        for name, spec in record.specs().items()
    )
