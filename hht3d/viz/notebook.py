"""The viewer inline in a notebook: :meth:`HHTResult.show <hht3d.transform.HHTResult.show>` and
:meth:`Surface.show <hht3d.geometry.Surface.show>`, and the summary table of a surface.

The page of :func:`hht3d.viz.viewer.result_page` (or of :func:`~hht3d.viz.viewer.page_html` for a
surface and its fields), self-contained as the HTML
file is (plotly.js embedded), goes into an ``<iframe srcdoc>``, so that its
script runs apart from the notebook's.  A notebook keeps its outputs, so the
inline page draws at most :data:`INLINE_VERTEX_BUDGET` vertices (a decimated
copy of a larger surface, which the page says) and is at most
:data:`INLINE_MAX_BYTES`; past that the view is a notice that points to
:meth:`~hht3d.transform.HHTResult.to_html`.
"""

from __future__ import annotations

import html
from typing import Any, cast

import numpy as np

from ..decomposition.display import summary_html, value_range
from ..errors import InputError
from ..geometry import Surface
from ..geometry.topology import boundary_loops, edge_face_counts
from ..transform import HHTResult
from .viewer import page_html, result_page

__all__ = ["InlineView", "inline_view", "surface_view", "surface_html", "INLINE_VERTEX_BUDGET", "INLINE_MAX_BYTES"]

#: Vertices an inline page draws at most (a third of the file's :data:`~hht3d.viz.shown.VERTEX_BUDGET`).
INLINE_VERTEX_BUDGET = 50_000
#: Size of an inline page above which a notice is shown instead (plotly.js alone is about 4.8 MB).
INLINE_MAX_BYTES = 20_000_000


class InlineView:
    """A viewer page that a notebook shows inline (``_repr_html_``): the last expression of a cell,
    or ``IPython.display.display(view)``.

    Attributes
    ----------
    page : str or None
        The whole viewer page; None when it was larger than the limit.
    html : str
        What the notebook shows: the ``<iframe>``, or the notice.
    """

    def __init__(self, page: str | None, html_text: str):
        self.page = page
        self.html = html_text

    def _repr_html_(self) -> str:
        return self.html

    def __repr__(self) -> str:
        size = "no page" if self.page is None else f"{len(self.page.encode()) / 1e6:.1f} MB page"
        return f"InlineView({size}; shown inline by a notebook)"


def inline_view(
    result: HHTResult,
    *,
    height: int = 600,
    max_vertices: int = INLINE_VERTEX_BUDGET,
    max_bytes: int = INLINE_MAX_BYTES,
    **options: Any,
) -> InlineView:
    """The viewer page of ``result`` in an ``<iframe>`` for a notebook.

    Parameters
    ----------
    result : HHTResult
    height : int
        Height of the frame in pixels; it takes the notebook's width.
    max_vertices : int
        A larger surface is drawn as a decimated copy (:func:`~hht3d.viz.shown.shown_copy`).
    max_bytes : int
        A larger page is not embedded: the view is a notice to write it with ``to_html``.
    **options
        ``beside``, ``field``, ``percentiles``, ``view``, ``up``: see :func:`~hht3d.viz.viewer.result_page`.

    Returns
    -------
    InlineView

    Examples
    --------
    >>> import hht3d
    >>> from hht3d.geometry import mean_curvature
    >>> surface = hht3d.load(hht3d.data_path("spot.ply"))
    >>> view = inline_view(hht3d.hht(surface, mean_curvature(surface), max_imfs=1))
    >>> view.html.startswith("<iframe srcdoc=")
    True
    """
    page = result_page(result, max_vertices=max_vertices, **options)
    return _framed(page, result.surface.name, "HHT", "result", height, max_bytes)


def surface_view(
    surface: Surface,
    field: str | np.ndarray | None = None,
    *,
    height: int = 600,
    max_vertices: int = INLINE_VERTEX_BUDGET,
    max_bytes: int = INLINE_MAX_BYTES,
    **options: Any,
) -> InlineView:
    """The viewer page of ``surface`` and its :attr:`~hht3d.geometry.Surface.attributes` in an ``<iframe>``.

    Parameters
    ----------
    surface : Surface
    field : str or (n,) array_like, optional
        The attribute shown first, or values to show (as ``field``, first); default: the
        first attribute, else the plain shape.
    height, max_vertices, max_bytes
        As for :func:`inline_view`.
    **options
        ``percentiles``, ``view``, ``up``: see :func:`~hht3d.viz.viewer.page_html`.

    Returns
    -------
    InlineView

    Examples
    --------
    >>> import hht3d
    >>> surface = hht3d.load(hht3d.data_path("spot.ply"))
    >>> view = surface_view(surface, surface.vertices[:, 1])
    >>> view.html.startswith("<iframe srcdoc=") and "2,930 vertices" in view.page
    True
    """
    fields: dict[str, Any] = dict(surface.attributes)
    if field is not None and not isinstance(field, str):
        fields, field = {"field": field, **fields}, "field"
    page = page_html([surface], fields, title=surface.name, field=field, max_vertices=max_vertices, **options)
    return _framed(page, surface.name, "surface", "surface", height, max_bytes)


def _framed(page: str, name: str, what: str, owner: str, height: int, max_bytes: int) -> InlineView:
    """``page`` in an ``<iframe>`` titled ``name: what``, or past ``max_bytes`` a notice to write it
    with ``owner.to_html`` (or, for a surface, to draw fewer vertices)."""
    size = len(page.encode())
    if size > max_bytes:
        fix = f"write it with {owner}.to_html({name + '.html'!r}) and open the file, or " if owner == "result" else ""
        notice = (
            f"The viewer page of {name} would be {size / 1e6:.1f} MB, more than the inline "
            f"limit of {max_bytes / 1e6:.1f} MB: {fix}show fewer vertices (max_vertices)."
        )
        return InlineView(None, f"<p>{html.escape(notice, quote=False)}</p>")
    frame = (
        f'<iframe srcdoc="{html.escape(page, quote=True)}" title="{html.escape(name)}: {what}" '
        f'style="width:100%;height:{int(height)}px;border:1px solid #ddd"></iframe>'
    )
    return InlineView(page, frame)


def surface_html(surface: Surface) -> str:
    """The summary table of a surface (:meth:`Surface._repr_html_ <hht3d.geometry.Surface>`): vertices,
    faces, connected components, boundary loops, area, bounding-box diagonal and the attributes with
    their 5–95 % ranges.

    A point cloud's components and area come from its Laplacian: shown once the operators are built
    (an HHT builds them), rather than building them for a repr.

    Parameters
    ----------
    surface : Surface

    Returns
    -------
    str
        One self-contained ``<div>`` (:func:`~hht3d.decomposition.display.summary_html`).

    Examples
    --------
    >>> from hht3d import data_path, load
    >>> spot = load(data_path("spot.ply"))
    >>> from hht3d.viz import surface_html
    >>> html = surface_html(spot)
    >>> html.startswith("<div"), "2,930" in html
    (True, True)
    """
    if not isinstance(surface, Surface):
        raise InputError(f"expected an hht3d.Surface, got {type(surface).__name__}")
    facts = [("vertices", f"{surface.n_vertices:,}")]
    if surface.is_mesh:
        faces = cast(np.ndarray, surface.faces)
        loops = boundary_loops(surface.n_vertices, *edge_face_counts(faces))
        facts += [("faces", f"{len(faces):,}"), ("components", str(surface.n_components))]
        facts += [("boundary loops", str(loops)), ("area", f"{surface.face_areas.sum():.4g}")]
    elif "operators" in surface.cache:
        facts += [("faces", "none: a point cloud"), ("components", str(surface.n_components))]
        facts += [("area", f"{surface.mass_diagonal.sum():.4g}")]
    else:
        facts += [("faces", "none: a point cloud"), ("components, area", "once the Laplacian is built")]
    facts.append(("bounding-box diagonal", f"{surface.bounding_box_diagonal:.4g}"))
    rows = [[name, value_range(values)] for name, values in surface.attributes.items()]
    return summary_html(f"Surface: {surface.name}", facts, [(["attribute", "5–95 %"], rows)] if rows else [])
