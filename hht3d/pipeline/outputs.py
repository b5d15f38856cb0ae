"""How each kind of step result is written to a file, by format.

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
``reconstruct``, ...) that other surface.
"""
from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError, PipelineError, shown
from ..io.write import write_colored_ply, write_npz, write_ply
from ..viz.render import UP_AXES, VIEWS
from ..viz.viewer import VERTEX_BUDGET
from .params import Param, did_you_mean

__all__ = ["Format", "FORMATS", "SUFFIXES", "check_options", "field_imf"]

#: File suffix of each format.
SUFFIXES = {"ply": ".ply", "colored_ply": ".ply", "npz": ".npz", "png": ".png", "html": ".html"}

_FIELD = re.compile(r"^(signal|residue|(imf|amplitude|phase|frequency)_([1-9][0-9]*))$")
_FEATURE_RED = np.array([0.85, 0.1, 0.1])
_FEATURE_GREY = np.array([0.75, 0.75, 0.73])


@dataclass(frozen=True)
class Format:
    """A way to write one kind of result: its name, options and writer."""

    name: str
    summary: str
    write: Callable = field(repr=False)
    params: tuple[Param, ...] = ()

    @property
    def suffix(self) -> str:
        return SUFFIXES[self.name]


_VIEW = (Param("view", "choice", "camera direction", default="front", choices=tuple(VIEWS)),
         Param("up", "choice", "the model's up axis", default="y", choices=UP_AXES))
_CMAP = Param("cmap", "str", "Matplotlib colour map", default="viridis")
_TITLE = Param("title", "str", "figure title (default: the surface name)", default=None)
_AUTO_CMAP = Param("cmap", "str", "Matplotlib colour map (default: diverging for signed fields)", default=None)
_HHT_FIELD = Param("field", "str", "signal, residue, imf_K, amplitude_K, phase_K or frequency_K",
                   default="signal")
_MAX_VERTICES = Param("max_vertices", "int", "larger surfaces are shown as a decimated copy carrying the fields",
                      default=VERTEX_BUDGET, minimum=4)


def check_options(options: dict, where: str) -> None:
    """Reject field names no HHT result has (``imf_0``, ``frequncy_1``) and unknown colour maps."""
    name = options.get("field")
    if name is not None and not _FIELD.match(name):
        raise PipelineError(f"{where}: unknown field {shown(name)}; use signal, residue, imf_K, amplitude_K, "
                            "phase_K or frequency_K (K = 1 for the finest IMF)")
    cmap = options.get("cmap")
    if cmap is not None:
        import matplotlib

        if cmap not in matplotlib.colormaps:
            raise PipelineError(f"{where}: unknown colour map {shown(cmap)}"
                                f"{did_you_mean(cmap, matplotlib.colormaps, listing=False)}")


def field_imf(name) -> int | None:
    """The IMF number K of a field ``imf_K``, ``amplitude_K``, ``phase_K`` or ``frequency_K`` (else None)."""
    match = _FIELD.match(name) if isinstance(name, str) else None
    return int(match.group(3)) if match and match.group(3) else None


def _hht_field(result, name: str) -> np.ndarray:
    fields = result.vertex_attributes()
    if name not in fields:
        raise InputError(f"{result.surface.name} has no field {shown(name)} ({result.n_imfs} IMFs); "
                         f"available: {', '.join(fields)}")
    return fields[name]


def _save_hht(result, surface, path):
    return result.save(path)


def _hht_colored(result, surface, path, *, field, cmap):
    return write_colored_ply(path, result.surface, _hht_field(result, field), cmap=cmap, name=field)


def _hht_png(result, surface, path, *, figure, field, signal_name, view, up):
    from ..viz.figures import hht_figure, spectrum_figure
    from ..viz.panels import field_figure, save_figure

    if figure == "hht":
        fig = hht_figure(result, view=view, up=up, signal_name=signal_name)
    elif figure == "spectrum":
        fig = spectrum_figure(result)
    else:
        fig = field_figure(result.surface, _hht_field(result, field), title=f"{result.surface.name}: {field}",
                           view=view, up=up)
    return save_figure(fig, path)


def _hht_html(result, surface, path, *, field, view, up, max_vertices):
    return result.to_html(path, field=field, view=view, up=up, max_vertices=max_vertices)


def _emd_npz(decomposition, surface, path):
    return write_npz(path, {"imfs": decomposition.imfs, "residue": decomposition.residue})


def _emd_ply(decomposition, surface, path):
    fields = {f"imf_{k + 1}": imf for k, imf in enumerate(decomposition.imfs)}
    return write_ply(path, surface, {**fields, "residue": decomposition.residue})


def _signal_npz(values, surface, path):
    return write_npz(path, {"signal": values})


def _signal_colored(values, surface, path, *, cmap):
    return write_colored_ply(path, surface, values, cmap=cmap, name="signal")


def _signal_png(values, surface, path, *, view, up, cmap, title):
    from ..viz.panels import render_png

    return render_png(path, surface, values, view=view, up=up, cmap=cmap, title=title or f"{surface.name}: signal")


def _surface_ply(surface, _, path):
    return write_ply(path, surface)


def _surface_png(surface, _, path, *, view, up, title):
    from ..viz.panels import render_png

    return render_png(path, surface, None, view=view, up=up, title=title)


def _surface_html(surface, origin, path, *, view, up, max_vertices):
    from ..viz.viewer import SHAPE, surfaces_html, write_page

    if origin is surface:
        return write_page(path, [surface], surface.attributes, title=surface.name, field=SHAPE, view=view, up=up,
                          max_vertices=max_vertices)
    return surfaces_html(path, origin, surface, view=view, up=up, max_vertices=max_vertices)


def _features_ply(features, surface, path):
    is_feature = np.zeros(surface.n_vertices)
    is_feature[features.vertices] = 1.0
    colors = np.where(is_feature[:, None] > 0, _FEATURE_RED, _FEATURE_GREY)
    return write_ply(path, surface, {"feature_count": features.vertex_counts.astype(np.float64),
                                     "feature": is_feature}, colors=colors)


def _features_npz(features, surface, path):
    return write_npz(path, {"vertices": features.vertices, "counts": features.counts, "points": features.points,
                            "vertex_counts": features.vertex_counts, "min_count": features.min_count})


#: Formats by result kind.
FORMATS: dict[str, dict[str, Format]] = {
    "hht": {f.name: f for f in (
        Format("ply", "the surface with every field as a vertex property", _save_hht),
        Format("npz", "every array (imfs, residue, riesz, amplitude, phase, frequency, ...)", _save_hht),
        Format("colored_ply", "one field as vertex colours (and as a property)", _hht_colored,
               (_HHT_FIELD, _CMAP)),
        Format("png", "a figure: Fig. 4 layout (hht), the Hilbert spectrum, or one field", _hht_png,
               (Param("figure", "choice", "which figure", default="hht", choices=("hht", "spectrum", "field")),
                _HHT_FIELD, Param("signal_name", "str", "name of the signal in titles", default="signal"),
                *_VIEW)),
        Format("html", "an interactive page: every field, the spectrum and the quality figures", _hht_html,
               (_HHT_FIELD, *_VIEW, _MAX_VERTICES)),
    )},
    "emd": {f.name: f for f in (
        Format("npz", "imfs and residue", _emd_npz),
        Format("ply", "the surface with imf_K and residue as vertex properties", _emd_ply),
    )},
    "signal": {f.name: f for f in (
        Format("npz", "the values", _signal_npz),
        Format("colored_ply", "the values as vertex colours", _signal_colored, (_CMAP,)),
        Format("png", "a rendering with a colour bar", _signal_png, (*_VIEW, _AUTO_CMAP, _TITLE)),
    )},
    "surface": {f.name: f for f in (
        Format("ply", "the surface", _surface_ply),
        Format("png", "a shaded rendering", _surface_png, (*_VIEW, _TITLE)),
        Format("html", "an interactive page; a filtered or reconstructed surface beside its original",
               _surface_html, (*_VIEW, _MAX_VERTICES)),
    )},
    "features": {f.name: f for f in (
        Format("ply", "the surface with feature_count and feature properties, features in red", _features_ply),
        Format("npz", "feature vertices, counts, points and per-vertex counts", _features_npz),
    )},
}
