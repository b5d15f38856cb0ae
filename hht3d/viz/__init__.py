"""Presentation: rendered figures (PNG) and the interactive HTML viewer.

Data flow: :mod:`.render` (colour scales, cameras, renderers) → :mod:`.figures`
(the paper's figures) and :mod:`.shown` → :mod:`.page_data` → :mod:`.viewer`
(one self-contained page).
"""

from .figures import hht_figure, spectrum_figure, write_figures
from .notebook import INLINE_MAX_BYTES, INLINE_VERTEX_BUDGET, InlineView, inline_view, surface_html, surface_view
from .panels import field_figure, render_png, save_figure
from .shown import VERTEX_BUDGET, color_limits, shown_copy
from .viewer import (
    PAGE_BUDGETS,
    SHAPE,
    file_html,
    page_html,
    read_fields,
    result_html,
    result_page,
    surfaces_html,
    write_page,
)

__all__ = [
    "hht_figure",
    "render_png",
    "field_figure",
    "save_figure",
    "spectrum_figure",
    "write_figures",
    "VERTEX_BUDGET",
    "color_limits",
    "shown_copy",
    "PAGE_BUDGETS",
    "SHAPE",
    "file_html",
    "page_html",
    "read_fields",
    "result_html",
    "result_page",
    "surfaces_html",
    "write_page",
    "InlineView",
    "inline_view",
    "surface_view",
    "surface_html",
    "INLINE_VERTEX_BUDGET",
    "INLINE_MAX_BYTES",
]
