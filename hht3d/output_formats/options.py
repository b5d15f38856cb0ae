"""What an output format is (:class:`Format`), and its options: :class:`FormatOptions` and the records
of the formats that take some."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from ..errors import InputError, did_you_mean, shown
from ..records import Record, option
from ..transform import FIELDS, IMF_FIELDS, field_imf
from ..viz.render import UP_AXES, VIEWS
from ..viz.viewer import VERTEX_BUDGET

__all__ = ["Format", "FormatOptions"]

_NAMES = (*FIELDS, *(f"{kind}_K" for kind in IMF_FIELDS))
#: The fields of an HHT result, in words: ``signal, residue, imf_K, ... or frequency_K``.
_FIELDS_TEXT = f"{', '.join(_NAMES[:-1])} or {_NAMES[-1]}"


@dataclass(frozen=True)
class FormatOptions(Record):
    """Base of a format's options; besides the fields' types and ranges it refuses what a
    :class:`~hht3d.records.Spec` cannot say: a ``field`` no HHT result has (``imf_0``,
    ``frequncy_1``) and a ``cmap`` Matplotlib does not know."""

    label = "output"

    def __post_init__(self) -> None:
        super().__post_init__()
        name = getattr(self, "field", None)
        if name is not None and name not in FIELDS and field_imf(name) is None:
            raise InputError(f"unknown field {shown(name)}; use {_FIELDS_TEXT} (K = 1 for the finest IMF)")
        cmap = getattr(self, "cmap", None)
        if cmap is not None:
            import matplotlib

            if cmap not in matplotlib.colormaps:
                raise InputError(
                    f"unknown colour map {shown(cmap)}{did_you_mean(cmap, matplotlib.colormaps, listing=False)}"
                )


@dataclass(frozen=True)
class Format:
    """A way to write one kind of result: its name, file suffix, summary, writer and options."""

    name: str
    suffix: str
    summary: str
    write: Callable = field(repr=False)
    options: type[FormatOptions] = FormatOptions


def _field() -> Any:
    return option("signal", _FIELDS_TEXT)


def _view() -> Any:
    return option("front", "camera direction", choices=tuple(VIEWS))


def _up() -> Any:
    return option("y", "the model's up axis", choices=UP_AXES)


def _max_vertices() -> Any:
    return option(VERTEX_BUDGET, "larger surfaces are shown as a decimated copy carrying the fields", minimum=4)


@dataclass(frozen=True)
class _FieldColours(FormatOptions):
    field: str = _field()
    cmap: str = option("viridis", "Matplotlib colour map")


@dataclass(frozen=True)
class _Colours(FormatOptions):
    cmap: str = option("viridis", "Matplotlib colour map")


@dataclass(frozen=True)
class _HHTFigure(FormatOptions):
    figure: str = option("hht", "which figure", choices=("hht", "spectrum", "field"))
    field: str = _field()
    signal_name: str = option("signal", "name of the signal in titles")
    view: str = _view()
    up: str = _up()


@dataclass(frozen=True)
class _View(FormatOptions):
    view: str = _view()
    up: str = _up()


@dataclass(frozen=True)
class _FieldView(FormatOptions):
    field: str = _field()
    view: str = _view()
    up: str = _up()


@dataclass(frozen=True)
class _HHTPage(_FieldView):
    max_vertices: int = _max_vertices()


@dataclass(frozen=True)
class _SignalFigure(_View):
    cmap: str | None = option(None, "Matplotlib colour map (default: diverging for signed fields)", kind="str")
    title: str | None = option(None, "figure title (default: the surface name)", kind="str")


@dataclass(frozen=True)
class _SurfaceFigure(_View):
    title: str | None = option(None, "figure title (default: the surface name)", kind="str")


@dataclass(frozen=True)
class _SurfacePage(_View):
    max_vertices: int = _max_vertices()


@dataclass(frozen=True)
class Points(FormatOptions):
    """The options of the point formats (LAS, LAZ)."""

    precision: str = option(
        "float64", "type of the fields added as extra-bytes dimensions", choices=("float32", "float64")
    )
