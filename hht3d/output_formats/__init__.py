"""Every way a result is written to a file: the formats by result kind, each with its suffix, options and writer.

==========  ==========================================================================
kind        formats
==========  ==========================================================================
hht         ``ply`` (mesh + every field as a vertex property), ``npz`` (every array
            and the origin), ``colored_ply`` (one field as vertex colours), ``png``
            (figure: the paper's Fig. 4 layout, the Hilbert spectrum, or one field),
            ``html`` (interactive page of every field, the spectrum and the quality
            figures)
emd         ``npz`` (imfs, residue), ``ply`` (imf_K and residue as vertex properties)
signal      ``npz``, ``colored_ply``, ``png``
surface     ``ply``, ``png`` (shaded), ``html`` (interactive page; a filtered or
            reconstructed surface beside the one it was made from)
features    ``ply`` (the surface with ``feature_count`` and ``feature``, features red),
            ``npz`` (vertices, counts, points, vertex_counts, min_count, origin)
every kind  ``las``, ``laz`` (the points, a LAS input's dimensions, the fields as
            extra bytes; ``lidar`` extra), ``vtu`` (``meshio`` extra), ``vtp``: the
            surface with every field (:mod:`hht3d.output_formats.points`)
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
options (:func:`plain_formats`: ``.ply``, ``.npz``, ``.vtu`` and ``.vtp`` of an HHT
result; ``run_dataset`` writes ``.ply`` and ``.npz`` unless asked); a
pipeline's ``outputs.files`` take any of them (:mod:`hht3d.pipeline.output_checks`),
and ``hht3d ops`` and the JSON Schema list them.

Examples
--------
>>> from hht3d.output_formats import FORMATS, by_suffix, plain_formats
>>> list(plain_formats("hht")), by_suffix()[".ply"]
(['.ply', '.npz', '.vtu', '.vtp'], 'ply')
>>> list(FORMATS["hht"]["png"].options.specs())
['figure', 'field', 'signal_name', 'view', 'up']
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import InputError, shown
from ..io.write import write_colored_ply, write_npz, write_ply
from .options import (
    Format,
    FormatOptions,
    _Colours,
    _FieldColours,
    _HHTFigure,
    _HHTPage,
    _SignalFigure,
    _SurfaceFigure,
    _SurfacePage,
)
from .points import emd_fields, feature_fields, point_formats

if TYPE_CHECKING:
    from hht3d.geometry.surface import Surface
    from hht3d.transform import HHTResult

    View = str | Sequence[float]  # a view's name or (azimuth, elevation); an up axis's name or 3-vector

__all__ = ["Format", "FormatOptions", "FORMATS", "by_suffix", "plain_formats"]

_FEATURE_RED = np.array([0.85, 0.1, 0.1])
_FEATURE_GREY = np.array([0.75, 0.75, 0.73])


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
    return write_npz(path, result.arrays())  # with the origin: the vertices are local (a LAS scan's datum)


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
    from ..viz.figures import hht_figure, spectrum_figure
    from ..viz.panels import field_figure, save_figure

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
    return write_ply(path, surface, emd_fields(decomposition))


def _signal_npz(values: np.ndarray, surface: Surface, path: Path | str) -> Path:
    return write_npz(path, {"signal": values})


def _signal_colored(values: np.ndarray, surface: Surface, path: Path | str, *, cmap: str) -> Path:
    return write_colored_ply(path, surface, values, cmap=cmap, name="signal")


def _signal_png(
    values: np.ndarray, surface: Surface, path: Path | str, *, view: View, up: View, cmap: str, title: str | None
) -> Path:
    from ..viz.panels import render_png

    return render_png(path, surface, values, view=view, up=up, cmap=cmap, title=title or f"{surface.name}: signal")


def _surface_ply(surface: Surface, _: Any, path: Path | str) -> Path:
    return write_ply(path, surface)


def _surface_png(surface: Surface, _: Any, path: Path | str, *, view: View, up: View, title: str | None) -> Path:
    from ..viz.panels import render_png

    return render_png(path, surface, None, view=view, up=up, title=title)


def _surface_html(surface: Surface, origin: Any, path: Path | str, *, view: View, up: View, max_vertices: int) -> Path:
    from ..viz.viewer import SHAPE, surfaces_html, write_page

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
    fields = feature_fields(features, surface)
    colors = np.where(fields["feature"][:, None] > 0, _FEATURE_RED, _FEATURE_GREY)
    return write_ply(path, surface, fields, colors=colors)


def _features_npz(features: Any, surface: Surface, path: Path | str) -> Path:
    return write_npz(
        path,
        {
            "vertices": features.vertices,
            "counts": features.counts,
            "points": features.points,
            "origin": surface.origin,
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
            Format("npz", ".npz", "feature vertices, counts, points, per-vertex counts and the origin", _features_npz),
        )
    },
}

for _kind, _formats in FORMATS.items():  # every kind's surface and fields as points: LAS, LAZ, VTK, ...
    _formats.update({f.name: f for f in point_formats(_kind)})


def by_suffix() -> dict[str, str]:
    """The format each file suffix names when none is given: the first of :data:`FORMATS` writing it.

    Returns
    -------
    dict of str to str
        Format name by suffix.

    Examples
    --------
    >>> from hht3d.output_formats import by_suffix
    >>> by_suffix()[".npz"]
    'npz'
    """
    names: dict[str, str] = {}
    for formats in FORMATS.values():
        for fmt in formats.values():
            names.setdefault(fmt.suffix, fmt.name)
    return names


def plain_formats(kind: str) -> dict[str, Format]:
    """The formats of ``kind`` that take no options, by suffix (the first of each suffix).

    Parameters
    ----------
    kind : str
        A result kind (``"hht"``, ``"surface"``, ...).

    Returns
    -------
    dict of str to Format

    Examples
    --------
    >>> from hht3d.output_formats import plain_formats
    >>> ".npz" in plain_formats("hht")
    True
    """
    plain: dict[str, Format] = {}
    for fmt in FORMATS[kind].values():
        if not fmt.options.specs():
            plain.setdefault(fmt.suffix, fmt)
    return plain
