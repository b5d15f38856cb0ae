"""Results in a notebook: compact reprs, a summary table, the viewer inline and the notebook's progress bar."""

from __future__ import annotations

import importlib.util
import sys
import types
from html.parser import HTMLParser

import numpy as np
import pytest

import hht3d
from hht3d.execution import schedulers
from hht3d.execution.progress import in_notebook
from hht3d.viz.notebook import INLINE_VERTEX_BUDGET, inline_view

#: Elements that have no end tag.
VOID = {"br", "hr", "img", "input", "meta", "link"}


class Checked(HTMLParser):
    """Tags nested and closed in order, and every tag, attribute and iframe ``srcdoc`` seen."""

    def __init__(self, text: str):
        super().__init__(convert_charrefs=True)
        self.open: list[str] = []
        self.tags: list[tuple[str, dict]] = []
        self.feed(text)
        self.close()
        assert not self.open, f"unclosed: {self.open}"

    def handle_starttag(self, tag, attrs):
        self.tags.append((tag, dict(attrs)))
        if tag not in VOID:
            self.open.append(tag)

    def handle_endtag(self, tag):
        assert self.open and self.open[-1] == tag, f"</{tag}> closes {self.open[-1:]}"
        self.open.pop()


def _shares(result) -> np.ndarray:
    """Energy shares of the IMFs and the residue, from the arrays: ``x_kᵀ M x_k`` over their sum, the residue
    less its area-weighted mean (spot is one connected piece)."""
    area = result.surface.mass_diagonal
    residue = result.residue - (area @ result.residue) / area.sum()
    energies = np.array([*(area @ imf**2 for imf in result.imfs), area @ residue**2])
    return energies / energies.sum()


def _no_arrays(text: str) -> None:
    assert "array(" not in text and "..." not in text and "\n" not in text
    assert "[" not in text, text  # no list or array printed


def test_reprs_hold_the_numbers_and_no_arrays(result):
    assert result.surface.n_components == 1
    shares = _shares(result)
    text = repr(result)
    assert text.startswith("HHTResult('spot': 2 IMFs of 2,930 vertices, shares ")
    assert f"{shares[0]:.1%} {shares[1]:.1%} + residue {shares[2]:.1%}" in text
    _no_arrays(text)
    _no_arrays(repr(result.quality))
    emd = hht3d.emd(result.surface, result.signal, max_imfs=2)
    assert repr(emd).startswith("EMDResult(2 IMFs of 2,930 vertices, shares ")
    _no_arrays(repr(emd))


def test_the_summary_table_holds_shares_frequency_ranges_and_quality(result):
    page = result._repr_html_()
    assert len(page) < 6000
    checked = Checked(page)
    assert {tag for tag, _ in checked.tags} <= {"div", "b", "table", "tr", "th", "td", "ul", "li"}  # no script
    assert "array(" not in page and "..." not in page
    for k, share in enumerate(_shares(result)[:-1]):
        low, high = np.percentile(result.monogenic.frequency[k], [5, 95])
        assert f">{k + 1}<" in page and f">{low:.3g} – {high:.3g}<" in page and f">{share:.1%}<" in page
    area = result.surface.mass_diagonal
    s = result.signal - (area @ result.signal) / area.sum()
    r = result.residue - (area @ result.residue) / area.sum()
    ratio = (sum(area @ imf**2 for imf in result.imfs) + area @ r**2) / (area @ s**2)
    assert f">{ratio:.3g}<" in page and ">ok<" in page
    Checked(result.quality._repr_html_())
    Checked(hht3d.emd(result.surface, result.signal, max_imfs=2)._repr_html_())


def test_quality_warnings_are_listed_and_escaped(result):
    from dataclasses import replace

    warned = replace(result.quality, warnings=("IO 0.3 > 0.25: read <adjacent> IMFs together",))
    page = warned._repr_html_()
    Checked(page)
    assert "<li>IO 0.3 &gt; 0.25: read &lt;adjacent&gt; IMFs together</li>" in page
    assert repr(warned).endswith("1 warning(s))")


def test_show_embeds_the_self_contained_viewer_in_a_frame(result):
    view = result.show(height=400)
    checked = Checked(view._repr_html_())
    ((tag, attrs),) = checked.tags
    assert tag == "iframe" and "height:400px" in attrs["style"]
    page = attrs["srcdoc"]
    assert page == view.page and page.startswith("<!DOCTYPE html>")
    inner = Checked(page)
    assert not [a for _, a in inner.tags if "src" in a or a.get("rel") == "stylesheet"]  # scripts and styles inline
    assert "2,930 vertices" in page and INLINE_VERTEX_BUDGET < 150_000


def test_a_large_surface_is_decimated_and_a_huge_page_is_a_notice(result):
    assert "a decimated copy with" in inline_view(result, max_vertices=1000).page
    notice = inline_view(result, max_bytes=1_000_000)
    assert notice.page is None and "result.to_html('spot.html')" in notice.html
    Checked(notice.html)


def _kernel(monkeypatch, kernel) -> None:
    """IPython loaded with a shell whose ``kernel`` is ``kernel``, and ipywidgets importable."""
    shell = types.SimpleNamespace(kernel=kernel)
    monkeypatch.setitem(sys.modules, "IPython", types.SimpleNamespace(get_ipython=lambda: shell))
    find_spec = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name: True if name == "ipywidgets" else find_spec(name))


def test_a_notebook_gets_the_distributed_progress_widget(monkeypatch):
    """In a Jupyter kernel the distributed bar is the notebook's widget, not the terminal bar."""
    assert not in_notebook()
    _kernel(monkeypatch, None)  # IPython's terminal shell: no kernel
    assert not in_notebook()
    _kernel(monkeypatch, object())
    assert in_notebook()
    shown = []
    monkeypatch.setattr("distributed.progress", lambda futures, notebook: f"widget of {futures}, notebook={notebook}")
    monkeypatch.setitem(sys.modules, "IPython.display", types.SimpleNamespace(display=shown.append))
    monkeypatch.setattr(schedulers, "gather_bounded", lambda client, futures, where: futures)
    client = types.SimpleNamespace(compute=lambda graphs: graphs)
    assert schedulers._compute_distributed(client, [1, 2], progress=True) == (1, 2)
    assert shown == ["widget of [1, 2], notebook=True"]  # displayed: distributed returns the widget


@pytest.mark.parametrize("notebook", [False, True])
def test_a_local_run_in_a_notebook_draws_the_bar(monkeypatch, notebook):
    from dask.diagnostics import ProgressBar

    from hht3d.execution.progress import ProgressLines, local_progress

    if notebook:
        _kernel(monkeypatch, object())
    assert isinstance(local_progress(), ProgressBar if notebook else ProgressLines)
