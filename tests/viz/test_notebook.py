"""Results in a notebook: compact reprs, a summary table, the viewer inline and the notebook's progress bar."""

from __future__ import annotations

import html
import importlib.util
import re
import sys
import types
from html.parser import HTMLParser

import numpy as np
import pytest

import hht3d
from helpers.meshes import disjoint_union, fibonacci_sphere, grid, open_cylinder
from helpers.pages import field_values, page_json
from hht3d.execution import schedulers
from hht3d.execution.progress import in_notebook
from hht3d.pipeline import parse_pipeline
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
    monkeypatch.setattr("hht3d.io.sealed._REGISTRY", {})  # no storage options of earlier tests to share
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


# -- a surface and a pipeline plan ---------------------------------------------------------------


def _cells(page: str) -> dict[str, str]:
    """The two-column facts of a summary ``<div>``: label -> value (unescaped)."""
    cells = re.findall(r"<tr><td[^>]*>([^<]*)</td><td[^>]*>([^<]*)</td></tr>", page)
    return {html.unescape(label): html.unescape(value) for label, value in cells}


def _self_contained(page: str) -> None:
    """Well-formed, and nothing loaded from elsewhere: no script, no link, no src or href."""
    checked = Checked(page)
    assert {tag for tag, _ in checked.tags} <= {"div", "b", "table", "tr", "th", "td", "ul", "li"}
    assert not [a for _, a in checked.tags if {"src", "href"} & set(a)]


def _boundary_loops(faces: np.ndarray) -> int:
    """Loops of edges of one face, walked: each boundary vertex of these meshes has two boundary edges."""
    count: dict[tuple[int, int], int] = {}
    for f in faces:
        for a, b in ((f[0], f[1]), (f[1], f[2]), (f[2], f[0])):
            key = (min(a, b), max(a, b))
            count[key] = count.get(key, 0) + 1
    nearby: dict[int, list[int]] = {}
    for (a, b), n in count.items():
        if n == 1:
            nearby.setdefault(a, []).append(b)
            nearby.setdefault(b, []).append(a)
    seen: set[int] = set()
    loops = 0
    for start in nearby:
        if start not in seen:
            loops += 1
            todo = [start]
            while todo:
                v = todo.pop()
                if v not in seen:
                    seen.add(v)
                    todo += nearby[v]
    return loops


def test_a_surface_summary_holds_its_numbers():
    """An open cylinder beside a square: 2 components, 3 boundary loops; area and diagonal from the arrays."""
    vertices, faces = disjoint_union(open_cylinder(6, 16, length=2.0), grid(5, 4))
    vertices[-20:] += [3.0, 0.0, 0.0]
    height = vertices[:, 2].copy()
    surface = hht3d.Surface(vertices, faces, attributes={"height": height}, name="pair <a&b>")
    page = surface._repr_html_()
    _self_contained(page)
    facts = _cells(page)
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum()
    assert _boundary_loops(faces) == 3
    assert facts == {
        "vertices": f"{len(vertices):,}",
        "faces": f"{len(faces):,}",
        "components": "2",
        "boundary loops": "3",
        "area": f"{area:.4g}",
        "bounding-box diagonal": f"{np.linalg.norm(np.ptp(vertices, axis=0)):.4g}",
        "height": f"{np.percentile(height, 5):.3g} – {np.percentile(height, 95):.3g}",
    }
    assert "<b>Surface: pair &lt;a&amp;b&gt;</b>" in page
    assert repr(surface) == f"Surface('pair <a&b>': {len(vertices)} vertices, mesh, {len(faces)} faces)"


def test_a_point_cloud_summary_waits_for_its_laplacian():
    surface = hht3d.Surface(fibonacci_sphere(400), name="cloud")
    before = _cells(surface._repr_html_())
    assert before["faces"] == "none: a point cloud" and "area" not in before
    assert "operators" not in surface.cache  # a repr builds no Laplacian
    surface.stiffness  # builds the operators, as an HHT does
    after = _cells(surface._repr_html_())
    assert after["components"] == "1" and after["area"] == f"{surface.mass_diagonal.sum():.4g}"
    assert abs(surface.mass_diagonal.sum() - 4 * np.pi) < 0.2  # the unit sphere
    _self_contained(surface._repr_html_())


def test_surface_show_draws_its_fields_inline(result):
    surface = hht3d.Surface(result.surface.vertices, result.surface.faces, attributes={"h": result.signal}, name="s")
    view = surface.show(height=300)
    ((tag, attrs),) = Checked(view._repr_html_()).tags
    assert tag == "iframe" and "height:300px" in attrs["style"] and attrs["title"] == "s: surface"
    assert not [a for _, a in Checked(view.page).tags if "src" in a or a.get("rel") == "stylesheet"]
    np.testing.assert_allclose(field_values(page_json(view.page), "h"), result.signal, rtol=1e-6)
    shown = surface.show(result.imfs[0])
    assert page_json(shown.page)["initial"] == "field"
    np.testing.assert_allclose(field_values(page_json(shown.page), "field"), result.imfs[0], rtol=1e-6, atol=1e-9)
    assert "a decimated copy with" in surface.show(max_vertices=1000).page
    assert surface.show(max_bytes=1000).page is None


def test_a_pipeline_plan_lists_inputs_steps_with_parameters_and_outputs(tmp_path):
    model = hht3d.data_path("spot.ply")
    plan = parse_pipeline(
        f"version: 1\ninputs: [{model}]\nsteps:\n  - {{id: curvature, op: signal, params: {{kind: mean_curvature}}}}\n"
        f"  - {{id: decompose, op: emd, params: {{max_imfs: 2}}}}\noutputs:\n  folder: {tmp_path}\n"
        '  files: [{from: decompose, path: "{stem}_imfs.npz"}]\n'
    )
    page = plan._repr_html_()
    _self_contained(page)
    rows = [
        [html.unescape(c) for c in re.findall(r"<td[^>]*>([^<]*)</td>", r)] for r in re.findall(r"<tr>.*?</tr>", page)
    ]
    assert [str(model)] in rows
    assert ["curvature", "signal", "surface=load", "kind=mean_curvature", "signal"] in rows
    assert ["decompose", "emd", "surface=load, signal=curvature", "max_imfs=2", "emd"] in rows
    assert ["decompose", "{stem}_imfs.npz", "npz", str(tmp_path / "spot_imfs.npz")] in rows
    assert repr(plan) == f"Pipeline('<pipeline>': 1 input, 3 steps, 1 output per input, folder {str(tmp_path)!r})"
