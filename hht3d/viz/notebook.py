"""The viewer inline in a notebook: :meth:`HHTResult.show <hht3d.transform.HHTResult.show>`.

The page of :func:`hht3d.viz.viewer.result_page`, self-contained as the HTML
file is (plotly.js embedded), goes into an ``<iframe srcdoc>``, so that its
script runs apart from the notebook's.  A notebook keeps its outputs, so the
inline page draws at most :data:`INLINE_VERTEX_BUDGET` vertices (a decimated
copy of a larger surface, which the page says) and is at most
:data:`INLINE_MAX_BYTES`; past that the view is a notice that points to
:meth:`~hht3d.transform.HHTResult.to_html`.
"""

from __future__ import annotations

import html
from typing import Any

from ..transform import HHTResult
from .viewer import result_page

__all__ = ["InlineView", "inline_view", "INLINE_VERTEX_BUDGET", "INLINE_MAX_BYTES"]

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
    size = len(page.encode())
    if size > max_bytes:
        notice = (
            f"The viewer page of {result.surface.name} would be {size / 1e6:.1f} MB, more than the inline "
            f"limit of {max_bytes / 1e6:.1f} MB: write it with result.to_html({result.surface.name + '.html'!r}) "
            "and open the file, or show fewer vertices (max_vertices)."
        )
        return InlineView(None, f"<p>{html.escape(notice, quote=False)}</p>")
    frame = (
        f'<iframe srcdoc="{html.escape(page, quote=True)}" title="{html.escape(result.surface.name)}: HHT" '
        f'style="width:100%;height:{int(height)}px;border:1px solid #ddd"></iframe>'
    )
    return InlineView(page, frame)
