"""Every way a result is written to a file: the formats by result kind, each with its suffix, options and writer.

==========  ==========================================================================
kind        formats
==========  ==========================================================================
hht         ``ply`` (mesh + every field as a vertex property), ``npz`` (every array),
            ``colored_ply`` (one field as vertex colours), ``png`` (figure: the
            paper's Fig. 4 layout, the Hilbert spectrum, or one field), ``html``
            (interactive page of every field, the spectrum and the quality figures)
emd         ``npz`` (imfs, residue), ``ply`` (imf_K and residue as vertex properties)
signal      ``npz``, ``colored_ply``, ``png``
surface     ``ply``, ``png`` (shaded), ``html`` (interactive page; a filtered or
            reconstructed surface beside the one it was made from)
features    ``ply`` (the surface with ``feature_count`` and ``feature``, features red),
            ``npz`` (vertices, counts, points, vertex_counts, min_count)
==========  ==========================================================================

Every writer is ``write(value, surface, path, **options) -> Path`` and writes
atomically; ``surface`` is the surface the result was computed from
(:meth:`Pipeline.origin_of <hht3d.pipeline.plan.Pipeline.origin_of>`): the one
it lives on, or for a surface made from another (``filter_geometry``,
``reconstruct``, ...) that other surface.  A format's options are the fields
of a :class:`FormatOptions` record (:func:`hht3d.records.option`), whose
pipeline parameters :func:`hht3d.pipeline.params.record_params` makes.

:meth:`HHTResult.save <hht3d.transform.HHTResult.save>` and
:func:`hht3d.dataset.run_dataset` write the formats of a kind that take no
options (:func:`plain_formats`: ``.ply`` and ``.npz`` of an HHT result); a
pipeline's ``outputs.files`` take any of them (:mod:`hht3d.pipeline.output_checks`),
and ``hht3d ops`` and the JSON Schema list them.

Examples
--------
>>> from hht3d.output_formats import FORMATS, by_suffix, plain_formats
>>> list(plain_formats("hht")), by_suffix()[".ply"]
(['.ply', '.npz'], 'ply')
>>> list(FORMATS["hht"]["png"].options.specs())
['figure', 'field', 'signal_name', 'view', 'up']
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .errors import InputError, did_you_mean, shown
from .io.write import write_colored_ply, write_npz, write_ply
from .records import Record, option
from .transform import FIELDS, IMF_FIELDS, field_imf
from .viz.render import UP_AXES, VIEWS
from .viz.viewer import VERTEX_BUDGET

if TYPE_CHECKING:
    from hht3d.geometry.surface import Surface
    from hht3d.transform import HHTResult

    View = str | Sequence[float]  # a view's name or (azimuth, elevation); an up axis's name or 3-vector

__all__ = ["Format", "FormatOptions", "FORMATS", "by_suffix", "plain_formats"]

_NAMES = (*FIELDS, *(f"{kind}_K" for kind in IMF_FIELDS))
#: The fields of an HHT result, in words: ``signal, residue, imf_K, ... or frequency_K``.
_FIELDS_TEXT = f"{', '.join(_NAMES[:-1])} or {_NAMES[-1]}"
_FEATURE_RED = np.array([0.85, 0.1, 0.1])
_FEATURE_GREY = np.array([0.75, 0.75, 0.73])


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


def _hht_field(result: HHTResult, name: str) -> np.ndarray:
    fields = result.vertex_attributes()
    if name not in fields:
        raise InputError(
            f"{result.surface.name} has no field {shown(name)} ({result.n_imfs} IMFs); available: {', '.join(fields)}"
        )
    return fields[name]


def _hht_ply(result: HHTResult, surface: Surface, path: Path | str) -> Path:
    return write_ply(path, result.surface, result.vertex_attributes())


def _hht_npz(result: HHTResult, surface: Surface, path: Path | str) -> Path:
    return write_npz(path, result.arrays())


def _hht_colored(result: HHTResult, surface: Surface, path: Path | str, *, field: str, cmap: str) -> Path:
    return write_colored_ply(path, result.surface, _hht_field(result, field), cmap=cmap, name=field)


def _hht_png(
    result: HHTResult,
    surface: Surface,
    path: Path | str,
    *,
    figure: bool,
    field: str,
    signal_name: str,
    view: View,
    up: View,
) -> Path:
    from .viz.figures import hht_figure, spectrum_figure
    from .viz.panels import field_figure, save_figure

    if figure == "hht":
        fig = hht_figure(result, view=view, up=up, signal_name=signal_name)
    elif figure == "spectrum":
        fig = spectrum_figure(result)
    else:
        fig = field_figure(
            result.surface, _hht_field(result, field), title=f"{result.surface.name}: {field}", view=view, up=up
        )
    return save_figure(fig, path)


def _hht_html(
    result: HHTResult, surface: Surface, path: Path | str, *, field: str, view: View, up: View, max_vertices: int
) -> Path:
    return result.to_html(path, field=field, view=view, up=up, max_vertices=max_vertices)


def _emd_npz(decomposition: Any, surface: Surface, path: Path | str) -> Path:
    return write_npz(path, {"imfs": decomposition.imfs, "residue": decomposition.residue})


def _emd_ply(decomposition: Any, surface: Surface, path: Path | str) -> Path:
    fields = {f"imf_{k + 1}": imf for k, imf in enumerate(decomposition.imfs)}
    return write_ply(path, surface, {**fields, "residue": decomposition.residue})


def _signal_npz(values: np.ndarray, surface: Surface, path: Path | str) -> Path:
    return write_npz(path, {"signal": values})


def _signal_colored(values: np.ndarray, surface: Surface, path: Path | str, *, cmap: str) -> Path:
    return write_colored_ply(path, surface, values, cmap=cmap, name="signal")


def _signal_png(
    values: np.ndarray, surface: Surface, path: Path | str, *, view: View, up: View, cmap: str, title: str | None
) -> Path:
    from .viz.panels import render_png

    return render_png(path, surface, values, view=view, up=up, cmap=cmap, title=title or f"{surface.name}: signal")


def _surface_ply(surface: Surface, _: Any, path: Path | str) -> Path:
    return write_ply(path, surface)


def _surface_png(surface: Surface, _: Any, path: Path | str, *, view: View, up: View, title: str | None) -> Path:
    from .viz.panels import render_png

    return render_png(path, surface, None, view=view, up=up, title=title)


def _surface_html(surface: Surface, origin: Any, path: Path | str, *, view: View, up: View, max_vertices: int) -> Path:
    from .viz.viewer import SHAPE, surfaces_html, write_page

    if origin is surface:
        return write_page(
            path,
            [surface],
            surface.attributes,
            title=surface.name,
            field=SHAPE,
            view=view,
            up=up,
            max_vertices=max_vertices,
        )
    return surfaces_html(path, origin, surface, view=view, up=up, max_vertices=max_vertices)


def _features_ply(features: Any, surface: Surface, path: Path | str) -> Path:
    is_feature = np.zeros(surface.n_vertices)
    is_feature[features.vertices] = 1.0
    colors = np.where(is_feature[:, None] > 0, _FEATURE_RED, _FEATURE_GREY)
    return write_ply(
        path,
        surface,
        {"feature_count": features.vertex_counts.astype(np.float64), "feature": is_feature},
        colors=colors,
    )


def _features_npz(features: Any, surface: Surface, path: Path | str) -> Path:
    return write_npz(
        path,
        {
            "vertices": features.vertices,
            "counts": features.counts,
            "points": features.points,
            "vertex_counts": features.vertex_counts,
            "min_count": features.min_count,
        },
    )


#: Formats by result kind, then by name.
FORMATS: dict[str, dict[str, Format]] = {
    "hht": {
        f.name: f
        for f in (
            Format("ply", ".ply", "the surface with every field as a vertex property", _hht_ply),
            Format("npz", ".npz", "every array (imfs, residue, riesz, amplitude, phase, frequency, ...)", _hht_npz),
            Format(
                "colored_ply", ".ply", "one field as vertex colours (and as a property)", _hht_colored, _FieldColours
            ),
            Format(
                "png", ".png", "a figure: Fig. 4 layout (hht), the Hilbert spectrum, or one field", _hht_png, _HHTFigure
            ),
            Format(
                "html",
                ".html",
                "an interactive page: every field, the spectrum and the quality figures",
                _hht_html,
                _HHTPage,
            ),
        )
    },
    "emd": {
        f.name: f
        for f in (
            Format("npz", ".npz", "imfs and residue", _emd_npz),
            Format("ply", ".ply", "the surface with imf_K and residue as vertex properties", _emd_ply),
        )
    },
    "signal": {
        f.name: f
        for f in (
            Format("npz", ".npz", "the values", _signal_npz),
            Format("colored_ply", ".ply", "the values as vertex colours", _signal_colored, _Colours),
            Format("png", ".png", "a rendering with a colour bar", _signal_png, _SignalFigure),
        )
    },
    "surface": {
        f.name: f
        for f in (
            Format("ply", ".ply", "the surface", _surface_ply),
            Format("png", ".png", "a shaded rendering", _surface_png, _SurfaceFigure),
            Format(
                "html",
                ".html",
                "an interactive page; a filtered or reconstructed surface beside its original",
                _surface_html,
                _SurfacePage,
            ),
        )
    },
    "features": {
        f.name: f
        for f in (
            Format(
                "ply", ".ply", "the surface with feature_count and feature properties, features in red", _features_ply
            ),
            Format("npz", ".npz", "feature vertices, counts, points and per-vertex counts", _features_npz),
        )
    },
}


def by_suffix() -> dict[str, str]:
    """The format each file suffix names when none is given: the first of :data:`FORMATS` writing it."""
    names: dict[str, str] = {}
    for formats in FORMATS.values():
        for fmt in formats.values():
            names.setdefault(fmt.suffix, fmt.name)
    return names


def plain_formats(kind: str) -> dict[str, Format]:
    """The formats of ``kind`` that take no options, by suffix (the first of each suffix)."""
    plain: dict[str, Format] = {}
    for fmt in FORMATS[kind].values():
        if not fmt.options.specs():
            plain.setdefault(fmt.suffix, fmt)
    return plain
