"""Look at a decomposition interactively: one self-contained HTML page per result.

:func:`result_html` writes every field of an :class:`~hht3d.transform.HHTResult`
— the signal, each IMF, the residue, each local amplitude, phase and
instantaneous frequency — as one HTML file that opens offline in any
browser (plotly.js is embedded; the page loads nothing from the network).
:func:`surfaces_html` writes a filtered or reconstructed surface beside the
original, and :func:`file_html` the page of a saved result (``.npz`` or
``.ply`` from :meth:`HHTResult.save <hht3d.transform.HHTResult.save>`) or of any
surface file with per-vertex properties.

The page
--------
* A field selector (with the plain shaded model as ``shape``), the colour
  bar and hover values of the selected field, and a colour-scale selector:
  *symmetric* (diverging, limits ``±max(|p_low|, |p_high|)``) or
  *sequential* (limits ``[p_low, p_high]``), with the percentiles
  :data:`PERCENTILES` of the field's values on every vertex; *auto* picks
  symmetric for fields with both signs, as the PNG figures do
  (:func:`hht3d.viz.render.color_scale`).
* The model's name and size; point clouds are drawn as points.
* Side by side surfaces (original and filtered) share one camera.
* The marginal Hilbert spectrum ``h(ω)`` and each IMF's share of it beside
  the surface, as in :func:`hht3d.viz.figures.spectrum_figure`; selecting a
  frequency field shades its colour range there.  A resolution limit that
  the spectrum reports (``resolvable_frequency``) is marked.
* The quality figures of the decomposition (:mod:`hht3d.decomposition.quality`), each
  IMF's energy share in the selector, and the warnings.

Size
----
The geometry is stored once per surface and the fields once per drawn copy,
all as little-endian float32 (int32 faces) in base64, the typed-array
encoding plotly.js reads; switching fields recolours the same geometry.
Per vertex that is about ``5.3 (3 + 6 + F)`` bytes for a mesh with ``F``
fields (a point cloud has no faces), plus about 4.8 MB of plotly.js.  A
surface with more than ``max_vertices`` (:data:`VERTEX_BUDGET`) vertices is
drawn as a decimated copy — Open3D's quadric decimation for meshes, a
random subset (seed 0) for point clouds — whose every vertex carries the
fields of the nearest original vertex; the page says so.  Colour limits,
the spectrum and the quality figures always come from every vertex.
``benchmarks/bench_viewer.py`` measures the page size and load time against
:data:`PAGE_BUDGETS`.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..decomposition.quality import Quality
from ..errors import InputError
from ..geometry.surface import Surface
from ..io.atomic import atomic_path
from ..spectral.spectrum import HilbertSpectrum
from ..transform import HHTResult
from .page import viewer_page
from .page_data import colorscale, field_title, figure_json, order, quality_data, size_text, spectrum_data, typed
from .render import PERCENTILES, SEQUENTIAL_CMAP, SYMMETRIC_CMAP, camera
from .saved import read_fields, saved_decomposition
from .shown import VERTEX_BUDGET, Shown, color_limits, shown_copy

__all__ = [
    "PAGE_BUDGETS",
    "SHAPE",
    "page_html",
    "write_page",
    "result_html",
    "result_page",
    "surfaces_html",
    "read_fields",
    "file_html",
]

#: What a page may cost, by vertices of the surface: (MB on disk, seconds until drawn in
#: headless Chromium with software WebGL on this project's 2-core machine).
PAGE_BUDGETS = {100_000: (30.0, 15.0), 1_000_000: (40.0, 20.0)}
#: The pseudo-field that shows the plain shaded model.
SHAPE = "shape"
#: Colour of the plain shaded model.
SHAPE_COLOR = "#c9c7c0"


# -- the page ------------------------------------------------------------------------------------


def write_page(path: Path | str, surfaces: Sequence[Surface], fields: dict, **options: Any) -> Path:
    """Write :func:`page_html` (with these ``options``) to the ``.html`` file ``path``, atomically (errors name it).

    Parameters
    ----------
    path : Path or str
        The ``.html`` file to write.
    surfaces : sequence of Surface
        The surfaces shown side by side.
    fields : dict
        The per-vertex fields, by name.
    **options
        Keyword arguments of :func:`page_html`.

    Returns
    -------
    Path
        The path written.
    """
    path = Path(path)
    page = page_html(surfaces, fields, page_name=path.name, **options)
    with atomic_path(path) as tmp:
        tmp.write_text(page, encoding="utf-8")
    return path


def page_html(
    surfaces: Sequence[Surface],
    fields: dict,
    *,
    title: str,
    labels: Sequence[str] | None = None,
    spectrum: HilbertSpectrum | None = None,
    quality: Quality | None = None,
    field: str | None = None,
    max_vertices: int = VERTEX_BUDGET,
    percentiles: tuple[float, float] = PERCENTILES,
    view: str | Sequence[float] = "front",
    up: str | Sequence[float] = "y",
    page_name: str = "page",
) -> str:
    """The viewer page of one or more surfaces sharing per-vertex fields, as one HTML text.

    Parameters
    ----------
    surfaces : sequence of Surface
        Drawn side by side with one camera; each must have as many vertices
        as the fields have values.
    fields : dict of str to (n,) array_like
        The fields of the selector, e.g. :meth:`HHTResult.vertex_attributes
        <hht3d.transform.HHTResult.vertex_attributes>`; may be empty.
    title : str
    labels : sequence of str, optional
        Names over the surfaces (default: their names).
    spectrum : HilbertSpectrum, optional
        Its marginal spectrum is drawn beside the surfaces.
    quality : Quality, optional
        Shown beside the surfaces; energy shares label the IMFs.
    field : str, optional
        The field shown first (default: ``signal`` if present, else the
        first field, else the plain ``shape``).
    max_vertices : int
        Larger surfaces are drawn as decimated copies (:func:`shown_copy`).
    percentiles : (float, float)
        Robust colour limits (:func:`color_limits`).
    view, up
        Initial camera, as for the PNG figures (:func:`hht3d.viz.render.camera`).
    page_name : str
        What error messages call the page (:func:`write_page`: the file name).

    Returns
    -------
    str

    Raises
    ------
    InputError
        No surface, a field of the wrong length or without finite values, an
        unknown initial field, or bad percentiles, view or up axis.
    """
    surfaces = list(surfaces)
    if not surfaces or not all(isinstance(s, Surface) for s in surfaces):
        raise InputError(f"{page_name}: expected one or more hht3d.Surface objects to draw")
    labels = [s.name for s in surfaces] if labels is None else list(labels)
    arrays = {str(k): np.asarray(v, dtype=np.float64) for k, v in fields.items()}
    for name, values in arrays.items():
        for s in surfaces:
            if values.shape != (s.n_vertices,):
                raise InputError(
                    f"{page_name}: field {name!r} has shape {values.shape}; {s.name} has {s.n_vertices} vertices"
                )
    initial = field or ("signal" if "signal" in arrays else next(iter(arrays), SHAPE))
    if initial != SHAPE and initial not in arrays:
        raise InputError(
            f"{page_name}: no field {initial!r} to show first; available: {', '.join([SHAPE, *order(arrays)])}"
        )
    camera(view, up)  # checks view and up before the expensive part
    shown = [shown_copy(s, max_vertices) for s in surfaces]
    copies: list[Shown] = []
    copy_of: list[int] = []
    for one in shown:
        same = next((c for c, other in enumerate(copies) if np.array_equal(other.source, one.source)), None)
        copy_of.append(len(copies) if same is None else same)
        if same is None:
            copies.append(one)
    shares = {}
    if quality is not None:
        shares = {f"imf_{k + 1}": share for k, share in enumerate(quality.energy_share[:-1])}
        shares["residue"] = quality.energy_share[-1]
    entries = []
    for name in order(arrays):
        short, group = field_title(name)
        label = short + (f" — {shares[name]:.1%} of the energy" if name in shares else "")
        try:
            limits = color_limits(arrays[name], percentiles)
        except InputError as exc:
            raise InputError(f"{page_name}: field {name!r}: {exc}") from None
        entries.append(
            {
                "name": name,
                "title": short,
                "label": label,
                "group": group,
                **limits,
                "values": [typed(c.carry(arrays[name])) for c in copies],
            }
        )
    notices = [
        f"{label}: {s.n_original:,} vertices, more than {max_vertices:,}: showing "
        + (
            f"a random subset of {len(s.source):,} points. "
            if s.faces is None
            else f"a decimated copy with {len(s.source):,} vertices, each carrying the fields of the nearest "
            "original vertex. "
        )
        + "Colour limits, spectrum and quality figures use every vertex."
        for s, label in zip(shown, labels)
        if s.decimated
    ]
    meta = {
        "title": title,
        "size": "; ".join(
            f"{label}: {size_text(s)}" if len(surfaces) > 1 else size_text(s) for s, label in zip(surfaces, labels)
        ),
        "notices": notices,
        "fields": entries,
        "initial": initial,
        "shape": SHAPE,
        "shape_color": SHAPE_COLOR,
        "percentiles": [float(p) for p in percentiles],
        "colorscales": {
            scale: colorscale(cmap) for scale, cmap in (("symmetric", SYMMETRIC_CMAP), ("sequential", SEQUENTIAL_CMAP))
        },
        "surfaces": [
            {"label": label, "copy": c, "points": s.faces is None} for s, label, c in zip(shown, labels, copy_of)
        ],
        "spectrum": None if spectrum is None else spectrum_data(spectrum),
        "quality": None if quality is None else quality_data(quality),
        "config": {"displaylogo": False, "responsive": True},
    }
    figure = figure_json(shown, labels, view, up)
    return viewer_page(title, json.dumps(meta, allow_nan=False)[:-1] + ', "figure": ' + figure + "}")


# -- entry points ------------------------------------------------------------------------------
def result_html(result: HHTResult, path: Path | str, **options: Any) -> Path:
    """Write :func:`result_page` (with these ``options``) to the ``.html`` file ``path``, atomically.

    Parameters
    ----------
    result : HHTResult
        The result to show.
    path : Path or str
        The ``.html`` file to write.
    **options
        Keyword arguments of :func:`result_page`.

    Returns
    -------
    Path
        The path written.
    """
    path = Path(path)
    page = result_page(result, page_name=path.name, **options)
    with atomic_path(path) as tmp:
        tmp.write_text(page, encoding="utf-8")
    return path


def result_page(result: HHTResult, *, beside: Any = None, **options: Any) -> str:
    """The page of an HHT result: every field, the marginal spectrum and the quality figures.

    Parameters
    ----------
    result : HHTResult
    beside : Surface, optional
        A surface with the same vertices, e.g. from
        :func:`hht3d.apps.filter_geometry`, drawn beside the result's surface
        with the same field at each vertex.
    **options
        ``field``, ``max_vertices``, ``percentiles``, ``view``, ``up``: see :func:`page_html`.
    """
    if not all(hasattr(result, name) for name in ("surface", "vertex_attributes", "spectrum", "quality")):
        raise InputError(f"expected an HHTResult (from hht3d.hht), got {type(result).__name__}")
    surfaces = [result.surface] if beside is None else [result.surface, beside]
    return page_html(
        surfaces,
        result.vertex_attributes(),
        title=f"{result.surface.name}: HHT" + (", iterative filtering" if result.method == "filtering" else ""),
        spectrum=result.spectrum,
        quality=result.quality,
        **options,
    )


def surfaces_html(
    path: Path | str,
    original: Surface,
    changed: Surface,
    *,
    max_vertices: int = VERTEX_BUDGET,
    percentiles: tuple[float, float] = PERCENTILES,
    view: str | Sequence[float] = "front",
    up: str | Sequence[float] = "y",
) -> Path:
    """The page of a filtered or reconstructed surface beside the original.

    With the same vertex count, the selector offers ``displacement``: the
    signed move of each vertex along the original normal, on both surfaces;
    the page opens on the plain shapes, as the paper's Figs. 5–6 show them.

    Parameters
    ----------
    path : Path or str
        The ``.html`` file to write.
    original, changed : Surface
        The surface before, and after filtering or reconstruction.
    max_vertices : int, optional
        The vertex budget of each drawn surface (default 150 000).
    percentiles : tuple of float, optional
        The colour range's percentiles (default ``(1, 99)``).
    view, up : str or sequence of float, optional
        The camera's direction and up axis, names or vectors (default ``"front"`` and ``"y"``).

    Returns
    -------
    Path
        The path written.
    """
    fields = {}
    if changed.n_vertices == original.n_vertices:
        fields["displacement"] = np.einsum("ij,ij->i", changed.vertices - original.vertices, original.normals)
    return write_page(
        path,
        [original, changed],
        fields,
        title=f"{changed.name} beside {original.name}",
        field=SHAPE,
        max_vertices=max_vertices,
        percentiles=percentiles,
        view=view,
        up=up,
    )


def file_html(
    source: Path | str,
    path: Path | str | None = None,
    *,
    field: str | None = None,
    max_vertices: int = VERTEX_BUDGET,
    percentiles: tuple[float, float] = PERCENTILES,
    view: str | Sequence[float] = "front",
    up: str | Sequence[float] = "y",
) -> Path:
    """The page of a saved result or surface file (see :func:`read_fields`).

    Parameters
    ----------
    source : str or Path
        An ``.npz`` or ``.ply`` from :meth:`HHTResult.save
        <hht3d.transform.HHTResult.save>`, or any surface file.
    path : str or Path, optional
        Default: ``source`` with the suffix ``.html``.
    field, max_vertices, percentiles, view, up
        See :func:`page_html`.

    Notes
    -----
    When the file holds IMFs with their amplitudes and frequencies, the page
    also shows the marginal spectrum, and with ``signal`` and ``residue``
    the quality figures.
    """
    source = Path(source)
    surface, fields, area = read_fields(source)
    spectrum, quality = saved_decomposition(surface, fields, area)
    return write_page(
        source.with_suffix(".html") if path is None else path,
        [surface],
        fields,
        title=surface.name,
        spectrum=spectrum,
        quality=quality,
        field=field,
        max_vertices=max_vertices,
        percentiles=percentiles,
        view=view,
        up=up,
    )
