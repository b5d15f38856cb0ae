"""Frozen, validated option records: each setting's type, range and description written once.

The settings of a method (:class:`~hht3d.decomposition.options.EMDOptions`,
:class:`~hht3d.decomposition.options.EnsembleOptions`,
:class:`~hht3d.spectral.options.RieszOptions`) are frozen dataclasses whose
fields are declared with :func:`option`.  The record checks every field when
it is made, presets are instances varied with :func:`dataclasses.replace`,
and the functions that take a record also take a dict (:meth:`Record.of`).
The pipeline's parameters, ``hht3d ops`` and the JSON Schema read the same
declarations (:meth:`Record.specs`), so a range or a description is never
written twice.

Examples
--------
>>> from dataclasses import dataclass
>>> from hht3d.records import Record, option
>>> @dataclass(frozen=True)
... class Smoothing(Record):
...     label = "smoothing"
...     steps: int = option(3, "diffusion steps", minimum=1, maximum=100)
...     method: str = option("heat", "kernel", choices=("heat", "mean"))
>>> Smoothing.of({"steps": 5}).steps
5
>>> Smoothing.of(steps=0)
Traceback (most recent call last):
...
hht3d.errors.InputError: smoothing option steps must be an integer in [1, 100]; got 0 (diffusion steps)
"""

from __future__ import annotations

import dataclasses
import math
import numbers
import warnings
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, TypeVar, cast

from .errors import HHT3DDeprecationWarning, InputError, did_you_mean, shown

R = TypeVar("R", bound="Record")

__all__ = ["Spec", "Record", "option", "route", "renamed_keywords"]

#: Kinds of settings (``ints``: a list of integers, each in the range; ``strs``: a list of names).
KINDS = ("int", "float", "bool", "str", "choice", "ints", "strs")


@dataclass(frozen=True)
class Spec:
    """One setting's type, allowed values and one-line description.

    ``kind`` is one of :data:`KINDS`; ``choices`` the values of a
    ``"choice"``; ``minimum``/``maximum`` the range of numbers (of each number of ``"ints"``), open at an
    end when ``open_minimum``/``open_maximum``; ``nullable`` allows ``None``.
    """

    doc: str
    kind: str
    choices: Sequence = ()
    minimum: float | None = None
    maximum: float | None = None
    open_minimum: bool = False
    open_maximum: bool = False
    nullable: bool = False

    def range_text(self) -> str:
        """The range, e.g. ``" in (0.5, 1]"``, ``" >= 0"`` or ``""``."""
        lo, hi = (
            None if x is None else f"{x:d}" if isinstance(x, int) else f"{x:g}" for x in (self.minimum, self.maximum)
        )
        if lo is not None and hi is not None:
            return f" in {'(' if self.open_minimum else '['}{lo}, {hi}{')' if self.open_maximum else ']'}"
        if lo is not None:
            return f" {'>' if self.open_minimum else '>='} {lo}"
        if hi is not None:
            return f" {'<' if self.open_maximum else '<='} {hi}"
        return ""

    def expected(self, null: str = "None") -> str:
        """What a valid value is, in words: ``an integer in [1, 100]``, ``one of sd, rfg``;
        ``null`` names the empty value of a nullable setting (``""``: leave it out)."""
        if self.kind == "choice":
            text = "one of " + ", ".join(map(str, self.choices))
        else:
            text = {
                "int": "an integer",
                "float": "a number",
                "bool": "true or false",
                "str": "a string",
                "ints": "a list of integers",
                "strs": "a list of names",
            }[self.kind] + self.range_text()
        return text + (f" or {null}" if self.nullable and null else "")

    def accepts(self, value: Any) -> bool:
        """Whether ``value`` is a valid setting."""
        if value is None:
            return self.nullable
        if self.kind == "choice":
            return isinstance(value, str) and value in self.choices
        if self.kind == "bool":
            return isinstance(value, bool)
        if self.kind == "str":
            return isinstance(value, str)
        if self.kind == "strs":
            return isinstance(value, (list, tuple)) and bool(value) and all(isinstance(v, str) and v for v in value)
        if self.kind == "ints":
            return (
                isinstance(value, (list, tuple)) and bool(value) and all(_is_int(v) and self.in_range(v) for v in value)
            )
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            return False
        if self.kind == "int" and not isinstance(value, numbers.Integral):
            return False
        return math.isfinite(value) and self.in_range(cast(float, value))

    def in_range(self, x: float) -> bool:
        lo, hi = self.minimum, self.maximum
        return (lo is None or (x > lo if self.open_minimum else x >= lo)) and (
            hi is None or (x < hi if self.open_maximum else x <= hi)
        )


def option(
    default: Any,
    doc: str,
    *,
    choices: tuple = (),
    kind: str | None = None,
    minimum: float | None = None,
    maximum: float | None = None,
    open_minimum: bool = False,
    open_maximum: bool = False,
    nullable: bool = False,
    like: Spec | None = None,
) -> Any:
    """A dataclass field of a :class:`Record` with its :class:`Spec`.

    The kind follows from ``choices`` or the default's type unless given;
    a default of ``None`` makes the setting nullable.  ``like``: the kind,
    choices and range of another record's setting of the same name (e.g.
    ``like=EMDOptions.specs()["ring"]``), so that its range is written once.
    A default of :data:`dataclasses.MISSING` makes the setting required.
    """
    if like is not None:
        spec = dataclasses.replace(like, doc=doc, nullable=nullable or default is None)
    else:
        if kind is None:
            kind = (
                "choice"
                if choices
                else "bool"
                if isinstance(default, bool)
                else "int"
                if isinstance(default, int)
                else "float"
                if isinstance(default, float)
                else "str"
            )
        spec = Spec(
            doc, kind, tuple(choices), minimum, maximum, open_minimum, open_maximum, nullable or default is None
        )
    return dataclasses.field(default=default, metadata={"spec": spec})


def route(settings: dict, *records: type[Record]) -> list[dict]:
    """``settings`` split by the record that declares each name (their names are disjoint).

    Raises
    ------
    InputError
        A name no record declares, with the closest known one.
    """
    known = [name for record in records for name in record.specs()]
    renamed = {old: new for record in records for old, new in record.renamed.items()}
    for key in settings:
        if key not in known:
            hint = (
                f"; did you mean {renamed[key]} (its new name)?"
                if key in renamed
                else did_you_mean(str(key), known, listing=False)
            )
            raise InputError(f"unknown option {shown(key)}{hint}; the options are {', '.join(known)}")
    return [{k: v for k, v in settings.items() if k in record.specs()} for record in records]


def _is_int(value: Any) -> bool:
    return isinstance(value, numbers.Integral) and not isinstance(value, bool)


def _converted(spec: Spec, value: Any) -> Any:
    """A valid value with ints as ``int``, numbers as ``float`` and lists as tuples."""
    if spec.kind == "ints" and value is not None:
        return tuple(int(v) for v in value)
    if spec.kind == "strs" and value is not None:
        return tuple(value)
    if value is None or spec.kind not in ("int", "float"):
        return value
    return int(value) if spec.kind == "int" else float(value)


def renamed_keywords(overrides: dict, renamed: dict[str, str], function: str) -> dict:
    """``overrides`` with former keyword names of ``function`` replaced by their new ones, each with a
    DeprecationWarning (the shims of one release)."""
    overrides = dict(overrides)
    for old in set(overrides) & set(renamed):
        new = renamed[old]
        if new in overrides:
            raise InputError(f"{function}: give {new} only ({old} is its former name)")
        warnings.warn(
            f"{function}({old}=...) is deprecated; write {new}={shown(overrides[old])}",
            HHT3DDeprecationWarning,
            stacklevel=3,
        )
        overrides[new] = overrides.pop(old)
    return overrides


class Record:
    """Base of the option records: checks every field on creation; :meth:`of` takes a record or a dict."""

    #: How messages name the record's settings ("EMD option max_imfs ...").
    label: ClassVar[str] = "option"
    #: Former names of settings, accepted by :meth:`of` for one release with a DeprecationWarning.
    renamed: ClassVar[dict[str, str]] = {}

    def __post_init__(self) -> None:
        for name, spec in self.specs().items():
            value = getattr(self, name)
            if not spec.accepts(value):
                raise InputError(
                    f"{self.label} option {name} must be {spec.expected()}; got {shown(value)} ({spec.doc})"
                )
            object.__setattr__(self, name, _converted(spec, value))

    @classmethod
    def specs(cls) -> dict[str, Spec]:
        """Every setting's :class:`Spec`, in field order."""
        return {f.name: f.metadata["spec"] for f in dataclasses.fields(cast(Any, cls))}  # subclasses are dataclasses

    @classmethod
    def defaults(cls) -> dict:
        """Every setting's default."""
        return {f.name: f.default for f in dataclasses.fields(cast(Any, cls))}

    @classmethod
    def of(cls: type[R], value: Any = None, /, **overrides: Any) -> R:
        """A record from ``None`` (the defaults), a record or a dict, with ``overrides`` applied.

        Raises
        ------
        InputError
            An unknown setting (with the closest known name) or an invalid value.
        """
        settings: dict[str, Any]
        if isinstance(value, cls):
            settings = {}
        elif value is None:
            settings = {}
        elif isinstance(value, dict):
            settings = dict(value)
        else:
            raise InputError(f"{cls.label} options must be a {cls.__name__} or a dict; got {shown(value)}")
        settings.update(overrides)
        given = sorted(set(settings) & set(cls.renamed))
        for old in given:
            new = cls.renamed[old]
            warnings.warn(
                f"{cls.label} option {old} is now called {new}; write {new}={shown(settings[old])}",
                HHT3DDeprecationWarning,
                stacklevel=3,
            )
            settings[new] = settings.pop(old)
        cls.check_names(settings)
        try:
            return dataclasses.replace(cast(Any, value), **settings) if isinstance(value, cls) else cls(**settings)
        except InputError as exc:
            if not given:
                raise
            raise InputError(f"{exc} (given as {', '.join(given)})") from None

    @classmethod
    def check(cls, name: str, value: Any) -> Any:
        """``value`` if it is a valid setting ``name`` of this record (ints stay ints, numbers become floats).

        Raises
        ------
        InputError
            ``"NAME must be ..., got VALUE"``.
        """
        spec = cls.specs()[name]
        if not spec.accepts(value):
            raise InputError(f"{name} must be {spec.expected()}, got {shown(value)}")
        return _converted(spec, value)

    @classmethod
    def check_names(cls, settings: Iterable[str]) -> None:
        """Raise :class:`InputError` for a name that is not a setting of this record."""
        known = tuple(cls.specs())
        for key in settings:
            if key not in known:
                raise InputError(
                    f"unknown {cls.label} option {shown(key)}"
                    f"{did_you_mean(str(key), known, listing=False)}; "
                    f"{cls.label} options are {', '.join(known)}"
                )

    def as_dict(self) -> dict:
        """The settings by name."""
        return {name: getattr(self, name) for name in self.specs()}
