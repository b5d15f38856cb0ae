"""Typed parameters of pipeline operations and outputs, checked before anything runs.

A :class:`Param` knows its type, default, allowed range or choices and a
one-line description; :meth:`Param.check` turns a YAML value into the value
the core function receives, or raises :class:`~hht3d.errors.PipelineError`
saying where, what was expected and what was found.  :func:`did_you_mean`
adds the closest known name to messages about unknown names.
"""
from __future__ import annotations

import dataclasses
import inspect
import math
from dataclasses import dataclass

from ..apps.filters import GAINS, make_gain
from ..errors import InputError, PipelineError, did_you_mean, one_line, shown
from ..records import Record, Spec

__all__ = ["Param", "REQUIRED", "did_you_mean", "record_params", "with_defaults", "yaml_text"]


class _Required:
    def __repr__(self) -> str:
        return "required"


#: Default of a parameter that must be given.
REQUIRED = _Required()
#: Default to be read from the signature of the core function (see :func:`with_defaults`).
_SIGNATURE = object()

KINDS = ("int", "float", "bool", "str", "choice", "gain")


def yaml_text(value) -> str:
    """A value as it would be written in YAML (``null``, ``true``, ``0.2``, ``cotan``)."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    return str(value)


def _what(value) -> str:
    """How a YAML value reads in a message: ``'six' (a string)``, ``null``."""
    names = {str: "a string", bool: "a boolean", int: "an integer", float: "a number", list: "a list",
             dict: "a mapping"}
    kind = next((n for t, n in names.items() if isinstance(value, t)), type(value).__name__)
    return "null" if value is None else f"{shown(value)} ({kind})"


@dataclass(frozen=True)
class Param:
    """One parameter: name, type, default, range or choices, description.

    ``kind`` is ``"int"``, ``"float"``, ``"bool"``, ``"str"``, ``"choice"``
    (one of ``choices``) or ``"gain"`` (a mapping ``{kind: band_stop, ...}``
    of :func:`hht3d.apps.make_gain`).  A default of ``None`` or ``nullable``
    makes ``null`` an allowed value; :data:`REQUIRED` makes the parameter
    mandatory.
    """

    name: str
    kind: str
    doc: str
    default: object = _SIGNATURE
    choices: tuple = ()
    minimum: float | None = None
    maximum: float | None = None
    open_minimum: bool = False
    open_maximum: bool = False
    nullable: bool = False

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValueError(f"parameter {self.name}: unknown kind {self.kind!r}")

    @property
    def required(self) -> bool:
        return self.default is REQUIRED

    def describe(self) -> str:
        """The type and range, e.g. ``int >= 0``, ``float in (0.5, 1]``, ``sd | s_number | fixed``."""
        if self.kind == "choice":
            return " | ".join(map(str, self.choices))
        if self.kind == "gain":
            return f"gain {{kind: {' | '.join(GAINS)}, ...}}"
        text = self.kind + self._range()
        return f"{text} or null" if self.default is None or self.nullable else text

    @property
    def spec(self) -> Spec:
        """The parameter's allowed values as an option :class:`~hht3d.records.Spec`."""
        return Spec(self.doc, self.kind, self.choices, self.minimum, self.maximum, self.open_minimum,
                    self.open_maximum, self.nullable)

    def _range(self) -> str:
        return self.spec.range_text()

    def check(self, value, where: str):
        """The checked value (ints stay ints, gains become :class:`~hht3d.apps.Gain` objects).

        Raises
        ------
        PipelineError
            ``"{where}: parameter NAME must be ..., got ..."``.
        """
        if value is None and (self.default is None or self.nullable):
            return None
        if self.kind == "choice":
            if value not in self.choices:
                raise PipelineError(f"{where}: parameter {self.name} must be one of "
                                    f"{', '.join(map(str, self.choices))}; got {_what(value)}"
                                    f"{did_you_mean(value, self.choices, listing=False)}")
            return value
        if self.kind == "gain":
            return _gain(value, f"{where}: parameter {self.name}")
        if self.kind == "bool":
            if not isinstance(value, bool):
                self._fail(where, value)
            return value
        if self.kind == "str":
            if not isinstance(value, str):
                self._fail(where, value)
            return value
        if isinstance(value, bool) or not isinstance(value, (int, float)) \
                or (self.kind == "int" and not isinstance(value, int)) or not math.isfinite(value):
            self._fail(where, value)
        if not self._in_range(value):
            self._fail(where, value)
        return value if self.kind == "int" else float(value)

    def _in_range(self, x) -> bool:
        return self.spec.in_range(x)

    def _fail(self, where: str, value):
        article = {"int": "an integer", "float": "a number", "bool": "true or false", "str": "a string"}
        expected = article[self.kind] + self._range()
        if value is None and self.kind in ("int", "float"):
            expected += " (not null)"
        raise PipelineError(f"{where}: parameter {self.name} must be {expected}; got {_what(value)}")


def _gain(value, where: str):
    """A gain from ``{kind: NAME, PARAM: VALUE, ...}``."""
    if not isinstance(value, dict) or "kind" not in value:
        raise PipelineError(f"{where} must be a mapping with a kind ({', '.join(GAINS)}) and its "
                            f"parameters, e.g. {{kind: band_stop, low: 8, high: 20}}; got {_what(value)}")
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
    return tuple(Param(name, spec.kind, spec.doc, default=defaults[name], choices=spec.choices,
                       minimum=spec.minimum, maximum=spec.maximum, open_minimum=spec.open_minimum,
                       open_maximum=spec.open_maximum, nullable=spec.nullable)
                 for name, spec in record.specs().items())


def with_defaults(func, *params: Param) -> tuple[Param, ...]:
    """``params`` with every unset default read from the signature of ``func``.

    Keeps the documented defaults of ``hht3d ops`` equal to the core's own.
    """
    signature = inspect.signature(func).parameters
    return tuple(dataclasses.replace(p, default=signature[p.name].default) if p.default is _SIGNATURE else p
                 for p in params)
