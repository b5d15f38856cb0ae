"""The interactive HTML viewer (hht3d.viz.viewer): what the page holds, and how it renders in a real browser.

The browser tests drive Debian's chromium (installed by ``bash .ci/setup``) through Playwright; they
skip only where chromium is not installed and this is not CI.
"""

from __future__ import annotations

import io
import re
from pathlib import Path

import numpy as np
import pytest

import hht3d
from helpers.browser import headless_chromium
from helpers.meshes import icosphere
from helpers.pages import cloud_with_spectrum, field_values, page_data
from hht3d import Surface
from hht3d.apps import filter_geometry
from hht3d.apps.filters import LowPass
from hht3d.cli import main
from hht3d.errors import InputError
from hht3d.viz.viewer import SHAPE, file_html, read_fields, surfaces_html, write_page


# -- fixtures ------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def browser():
    yield from headless_chromium()


class Opened:
    """A page loaded in chromium, with what it logged and requested."""

    def __init__(self, browser, path):
        self.page = browser.new_page(viewport={"width": 1280, "height": 760})
        self.errors, self.requests = [], []
        self.page.on(
            "console", lambda m: self.errors.append(f"console {m.type}: {m.text}") if m.type == "error" else None
        )
        self.page.on("pageerror", lambda e: self.errors.append(f"page error: {e}"))
        self.page.on("request", lambda r: self.requests.append(r.url))
        self.page.goto(path.as_uri())
        self.page.wait_for_selector("body[data-ready=true]", timeout=90_000)
        self.url = path.as_uri()

    def select(self, control: str, value: str) -> None:
        """Choose an option of the page's own <select> and wait until it is drawn."""
        self.page.select_option(control, value)
        attribute = "field" if control == "#hht3d-field" else "scale"
        self.page.wait_for_selector(f"body[data-{attribute}='{value}']", timeout=30_000)
        self.page.evaluate("() => new Promise(r => requestAnimationFrame(() => requestAnimationFrame(r)))")

    def picture(self) -> np.ndarray:
        """The surface panel as an (h, w, 3) array."""
        from PIL import Image

        png = self.page.locator("#hht3d-surface").screenshot()
        return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=np.float64)


@pytest.fixture
def opened(browser):
    pages = []

    def open_page(path):
        pages.append(Opened(browser, path))
        return pages[-1]

    yield open_page
    for p in pages:
        p.page.close()


def not_blank(picture: np.ndarray) -> tuple[float, int]:
    """Share of pixels that differ from the white background, and distinct colours."""
    covered = np.any(np.abs(picture - 255) > 12, axis=2)
    colours = len(np.unique((picture[covered] // 8).astype(int) @ np.array([1024, 32, 1])))
    return float(covered.mean()), colours


# -- what the page holds -------------------------------------------------------------------------
def test_page_holds_every_field_of_the_result_as_float32(result, result_page):
    data = page_data(result_page)
    attributes = result.vertex_attributes()
    assert {f["name"] for f in data["fields"]} == set(attributes)
    for name, values in attributes.items():
        np.testing.assert_array_equal(field_values(data, name), values.astype(np.float32))
    names = [f["name"] for f in data["fields"]]
    assert names[:4] == ["signal", "imf_1", "imf_2", "residue"]
    assert data["initial"] == "signal" and data["title"] == "spot: HHT"
    assert data["size"] == "2,930 vertices, 5,856 triangles" and data["notices"] == []


def test_bad_input_is_reported_with_the_file_and_field(result, tmp_path):
    with pytest.raises(InputError, match="no field 'imf_7'.*available: shape, signal, imf_1"):
        result.to_html(tmp_path / "x.html", field="imf_7")
    with pytest.raises(InputError, match="field 'f' has shape"):
        write_page(tmp_path / "x.html", [result.surface], {"f": np.zeros(5)}, title="x")
    with pytest.raises(InputError, match="max_vertices"):
        result.to_html(tmp_path / "x.html", max_vertices=2)
    with pytest.raises(InputError, match="unknown view"):
        result.to_html(tmp_path / "x.html", view="sideways")
    assert not list(tmp_path.iterdir())


# -- saved results, surfaces beside each other, CLI ------------------------------------------------------
@pytest.mark.parametrize("suffix", [".npz", ".ply"])
def test_saved_result_gives_the_same_page(result, tmp_path, suffix, capsys):
    saved = result.save(tmp_path / f"spot_hht{suffix}")
    surface, fields, _ = read_fields(saved)
    assert surface.n_vertices == result.surface.n_vertices
    for name, values in result.vertex_attributes().items():
        np.testing.assert_allclose(fields[name], values, rtol=0, atol=0)
    assert main(["view", str(saved), "--field", "frequency_1"]) == 0
    page = tmp_path / "spot_hht.html"
    assert capsys.readouterr().out.strip() == str(page)
    data = page_data(page)
    assert data["initial"] == "frequency_1" and data["spectrum"] is not None
    assert data["quality"]["rows"][0][1] == f"{result.quality.energy_ratio:.3g}"
    np.testing.assert_array_equal(field_values(data, "imf_2"), result.imfs[1].astype(np.float32))


def test_view_reports_a_missing_file(tmp_path, capsys):
    assert main(["view", str(tmp_path / "none.npz")]) == 1
    assert "none.npz: no such file" in capsys.readouterr().err


def test_filtered_surface_beside_the_original(result, tmp_path):
    filtered = filter_geometry(result, LowPass(cutoff=5.0, width=2.0))
    page = surfaces_html(tmp_path / "pair.html", result.surface, filtered)
    data = page_data(page)
    assert [s["label"] for s in data["surfaces"]] == ["spot", "spot_filtered"]
    assert data["initial"] == SHAPE and len(data["figure"]["data"]) == 2
    expected = np.einsum("ij,ij->i", filtered.vertices - result.surface.vertices, result.surface.normals)
    np.testing.assert_array_equal(field_values(data, "displacement"), expected.astype(np.float32))
    # both surfaces have all their vertices: one copy of each field serves both
    assert [s["copy"] for s in data["surfaces"]] == [0, 0]


def test_file_html_of_a_plain_surface_shows_its_properties(tmp_path):
    v, f = icosphere(2)
    path = tmp_path / "ball.ply"
    hht3d.io.write_ply(path, Surface(v, f, name="ball"), {"height": v[:, 2]})
    data = page_data(file_html(path))
    assert [e["name"] for e in data["fields"]] == ["height"]
    assert data["spectrum"] is None and data["quality"] is None


# -- in a real browser ---------------------------------------------------------------------------
def test_page_renders_offline_without_errors_and_switches_fields(browser, opened, result_page):
    page = opened(result_page)
    first = page.picture()
    share, colours = not_blank(first)
    assert share > 0.05 and colours > 30, (share, colours)
    page.select("#hht3d-field", "imf_1")
    second = page.picture()
    changed = np.any(np.abs(second - first) > 24, axis=2).mean()
    assert changed > 0.02, changed
    page.select("#hht3d-scale", "sequential")
    assert np.any(np.abs(page.picture() - second) > 24, axis=2).mean() > 0.02
    assert "p1 to p99" in page.page.text_content("#hht3d-limits")
    assert page.errors == []
    assert page.requests == [page.url]  # nothing fetched: plotly.js and the data are in the file


def test_page_shows_hover_values_and_the_spectrum(browser, opened, result_page):
    page = opened(result_page)
    box = page.page.locator("#hht3d-surface").bounding_box()
    for dx in (0.0, -0.05, 0.05):
        page.page.mouse.move(box["x"] + box["width"] * (0.5 + dx), box["y"] + box["height"] * 0.55)
        label = page.page.locator(".hovertext")
        if label.count():
            break
    assert label.count() and re.search(r"signal -?[0-9.]+", label.first.text_content()), "no hover label"
    assert page.page.locator("#hht3d-spectrum .main-svg").count() > 0
    assert page.errors == []


def test_side_by_side_surfaces_share_the_camera(browser, opened, result, tmp_path):
    filtered = filter_geometry(result, LowPass(cutoff=5.0, width=2.0))
    page = opened(surfaces_html(tmp_path / "pair.html", result.surface, filtered))
    share, _ = not_blank(page.picture())
    assert share > 0.05
    eye = page.page.evaluate("""() => {
        const plot = document.getElementById('hht3d-surface');
        return Plotly.relayout(plot, {'scene.camera': {eye: {x: 0.3, y: 1.4, z: 0.2}, up: {x: 0, y: 0, z: 1}}})
            .then(() => new Promise(r => setTimeout(r, 200)))
            .then(() => plot.layout.scene2.camera.eye);
    }""")
    assert eye == {"x": 0.3, "y": 1.4, "z": 0.2}
    assert page.errors == []


def test_point_cloud_page_renders(browser, opened, tmp_path):
    page = opened(cloud_with_spectrum(tmp_path))
    share, colours = not_blank(page.picture())
    assert share > 0.03 and colours > 10, (share, colours)
    assert "resolution limit" in page.page.text_content("#hht3d-spectrum")
    assert page.page.text_content("#hht3d-title") == "cloud"
    low, high = page.page.evaluate("document.getElementById('hht3d-spectrum').layout.xaxis.range")
    assert 0 < low < np.log10(12.0) < high < 2  # the log axis spans the spectrum, not the marker's log10
    assert page.errors == []


# -- names carrying template markers and markup ----------------------------------------------------
PAYLOAD_NAME = '{{SCRIPT}}{{DATA}}{{TITLE}}<img src=x onerror="window.pwned=1">'
PAYLOAD_FIELD = '<svg onload="window.pwned=2">{{PLOTLY}}'


def test_names_with_template_markers_and_markup_are_shown_as_text(browser, opened, tmp_path, capsys):
    """A file or field name is data: the page builds, nothing in it runs, it is shown literally."""
    v, f = icosphere(2)
    source = tmp_path / f"{PAYLOAD_NAME}.npz"
    np.savez(source, vertices=v, faces=f, **{PAYLOAD_FIELD: v[:, 0], "height": v[:, 2]})
    assert main(["view", str(source)]) == 0
    page_path = Path(capsys.readouterr().out.strip())
    assert page_path.name == f"{PAYLOAD_NAME}.html"
    data = page_data(page_path)
    assert {e["name"] for e in data["fields"]} == {PAYLOAD_FIELD, "height"}
    page = opened(page_path)
    assert page.page.evaluate("() => window.pwned") is None
    assert page.page.text_content("#hht3d-title") == PAYLOAD_NAME
    assert PAYLOAD_FIELD in page.page.locator("#hht3d-field option").all_text_contents()
    page.select("#hht3d-field", PAYLOAD_FIELD)
    assert page.page.evaluate("() => window.pwned") is None
    assert page.errors == [] and page.requests == [page.url]


# -- inline in a notebook ------------------------------------------------------------------------
def test_the_inline_view_draws_in_its_frame_offline(browser, result, tmp_path):
    """``result.show()`` as a notebook holds it: the iframe's srcdoc page draws, fetching nothing."""
    host = tmp_path / "notebook.html"
    host.write_text(f"<!DOCTYPE html><html><body>{result.show(height=500)._repr_html_()}</body></html>")
    page = browser.new_page(viewport={"width": 1280, "height": 760})
    errors, requests = [], []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.on("request", lambda r: requests.append(r.url))
    page.goto(host.as_uri())
    (frame,) = [f for f in page.frames if f is not page.main_frame]
    frame.wait_for_selector("body[data-ready=true]", timeout=90_000)
    from PIL import Image

    picture = np.asarray(Image.open(io.BytesIO(frame.locator("#hht3d-surface").screenshot())).convert("RGB"), float)
    share, colours = not_blank(picture)
    assert share > 0.05 and colours > 30, (share, colours)
    assert errors == [] and requests == [host.as_uri()]
    page.close()
