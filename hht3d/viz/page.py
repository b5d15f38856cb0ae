"""The viewer's HTML page: its template (``viz/web/viewer.html``) filled with plotly.js, the viewer's script
and the page data, offline in one file.

The template is filled in one pass over the template only (:func:`fill`): a
title, a field name or a script that holds ``{{SCRIPT}}`` or ``<script>`` is
data, never substituted into and never markup (the title is HTML-escaped,
the data a JSON script block with ``<``, ``>`` and ``&`` escaped).
"""

from __future__ import annotations

import html
import re
from importlib import resources

from ..version import __version__

__all__ = ["viewer_page", "fill", "json_script"]


def viewer_page(title: str, data_json: str) -> str:
    """The page: ``title`` (plain text) and the page data ``data_json`` (a JSON text)."""
    return fill(
        _asset("viewer.html"),
        {
            "VERSION": __version__,
            "TITLE": html.escape(title),
            "PLOTLY": _plotly_js(),
            "SCRIPT": _asset("viewer.js"),
            "DATA": json_script(data_json),
        },
    )


def json_script(text: str) -> str:
    """JSON made safe inside a <script> element."""
    return text.replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")


def _asset(name: str) -> str:
    return (resources.files("hht3d") / "viz" / "web" / name).read_text(encoding="utf-8")


#: A marker of the page template: ``{{NAME}}``.
_MARKER = re.compile(r"\{\{([A-Z]+)\}\}")


def fill(template: str, values: dict) -> str:
    """The template with each ``{{NAME}}`` replaced by ``values[NAME]``, in one pass over the template
    only: a title, a field name or a script that holds a marker is never substituted into."""
    return _MARKER.sub(lambda match: values[match.group(1)], template)


def _plotly_js() -> str:
    from plotly.offline import get_plotlyjs

    return get_plotlyjs()
