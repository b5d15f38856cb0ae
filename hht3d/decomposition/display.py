"""Compact summaries of results, for a console (``repr``) and a notebook (``_repr_html_``); the
summaries of decompositions are :func:`hht3d.decomposition.quality.decomposition_html` and ``_repr``.

A summary gives sizes, figures and warnings, never an array: a result of a
million vertices has a repr of one line and an HTML table of a few rows.
The HTML is one self-contained ``<div>`` (inline styles only, no script).
"""

from __future__ import annotations

import html
from collections.abc import Sequence

import numpy as np

__all__ = ["share_text", "value_range", "summary_html", "Facts", "Table"]

#: Rows of (label, value) shown as a two-column list.
Facts = Sequence[tuple[str, str]]
#: A header and its rows, shown as a table.
Table = tuple[Sequence[str], Sequence[Sequence[str]]]

_CELL = "padding:2px 10px;text-align:left;border-bottom:1px solid #ddd"


def share_text(energy_share: np.ndarray) -> str:
    """The energy shares of the IMFs then the residue, e.g. ``'61.2% 30.1% + residue 8.7%'``."""
    shares = [f"{x:.1%}" for x in np.asarray(energy_share, dtype=float)]
    return " ".join(shares[:-1]) + (" + " if len(shares) > 1 else "") + f"residue {shares[-1]}"


def value_range(values: np.ndarray) -> str:
    """The 5th to 95th percentile of the finite ``values``, e.g. ``'0.12 – 3.4'`` (``'–'`` when none is)."""
    finite = np.asarray(values, dtype=float)
    finite = finite[np.isfinite(finite)]
    if not finite.size:
        return "–"
    low, high = np.percentile(finite, [5, 95])
    return f"{low:.3g} – {high:.3g}"


def summary_html(title: str, facts: Facts, tables: Sequence[Table] = (), warnings: Sequence[str] = ()) -> str:
    """One ``<div>``: a bold ``title``, the ``facts``, the ``tables`` and the ``warnings``, all escaped.

    >>> summary_html("Quality", [("energy ratio", "1.02")], warnings=["a < b"])
    '<div ...<b>Quality</b>...<td ...>energy ratio</td><td ...>1.02</td>...<li>a &lt; b</li>...</div>'
    """

    def row(cells: Sequence[str], tag: str = "td") -> str:
        return "<tr>" + "".join(f'<{tag} style="{_CELL}">{html.escape(c)}</{tag}>' for c in cells) + "</tr>"

    parts = [f'<div style="font-family:sans-serif;font-size:13px"><b>{html.escape(title)}</b>']
    parts.append('<table style="border-collapse:collapse">' + "".join(row(f) for f in facts) + "</table>")
    for header, rows in tables:
        parts.append(
            '<table style="border-collapse:collapse;margin-top:6px">'
            + row(header, "th")
            + "".join(row(r) for r in rows)
            + "</table>"
        )
    if warnings:
        items = "".join(f"<li>{html.escape(w)}</li>" for w in warnings)
        parts.append(f'<ul style="color:#a33;margin:6px 0">{items}</ul>')
    return "".join(parts) + "</div>"
