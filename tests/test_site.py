"""The built documentation site, tried as a new user would in headless chromium (issue 35).

``docs/_build/html`` (``bash .ci/docs``, which ``.ci/run`` runs before the suite) is served on
127.0.0.1; the front page, a gallery example, an API page and a page of equations render, every
image of theirs loads, nothing is logged as an error, no request fails or leaves localhost (Sphinx
would fetch MathJax from a CDN, sphinx-gallery its tables' scripts), and the search page finds
``emd``.  Without a built site the tests skip, except in CI, where they fail.
"""

from __future__ import annotations

import functools
import os
import threading
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

import pytest

from helpers.browser import headless_chromium

SITE = Path(__file__).resolve().parents[1] / "docs" / "_build" / "html"


class _Quiet(SimpleHTTPRequestHandler):
    def log_message(self, format, *args):  # noqa: A002 - the base class's name
        pass


@pytest.fixture(scope="module")
def site():
    """The origin ``http://127.0.0.1:PORT`` serving the built site."""
    if not (SITE / "index.html").is_file():
        message = f"no built site at {SITE}: `bash .ci/docs` builds it"
        if os.environ.get("CI"):
            pytest.fail(message)
        pytest.skip(message)
    server = ThreadingHTTPServer(("127.0.0.1", 0), functools.partial(_Quiet, directory=str(SITE)))
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{server.server_address[1]}"
    server.shutdown()
    server.server_close()
    thread.join(timeout=10)


@pytest.fixture(scope="module")
def browser():
    yield from headless_chromium()


class Visit:
    """A page of the site in chromium, with its errors and every request outside the site's origin (aborted)."""

    def __init__(self, browser, site: str, path: str):
        self.page = browser.new_page(viewport={"width": 1280, "height": 900})
        self.errors: list[str] = []
        self.outside: list[str] = []
        self.page.on("console", lambda m: self.errors.append(f"console: {m.text}") if m.type == "error" else None)
        self.page.on("pageerror", lambda e: self.errors.append(f"page error: {e}"))
        self.page.on("requestfailed", lambda r: self.errors.append(f"failed: {r.url}"))
        self.page.on("response", lambda r: self.errors.append(f"{r.status}: {r.url}") if r.status >= 400 else None)
        self.page.route("**/*", functools.partial(self._route, site))
        self.response = self.page.goto(f"{site}/{path}", wait_until="load")
        self.page.wait_for_load_state("networkidle")

    def _route(self, site, route):
        url = route.request.url
        if url.startswith(f"{site}/") or url.startswith(("data:", "blob:")):
            route.continue_()
        else:
            self.outside.append(url)
            route.abort()

    def images(self) -> list[dict]:
        return self.page.evaluate(
            "() => Array.from(document.images).map(i => ({src: i.src, loaded: i.complete && i.naturalWidth > 0}))"
        )

    def check(self) -> None:
        """Served, no errors, nothing fetched from elsewhere, every image drawn."""
        assert self.response is not None and self.response.ok
        assert self.outside == [], f"requests outside the site: {self.outside}"
        assert self.errors == [], self.errors
        broken = [image["src"] for image in self.images() if not image["loaded"]]
        assert broken == [], f"images that did not load: {broken}"


@pytest.fixture
def visit(browser, site):
    visits = []

    def open_page(path: str) -> Visit:
        visits.append(Visit(browser, site, path))
        return visits[-1]

    yield open_page
    for v in visits:
        v.page.close()


def test_front_page_renders(visit):
    page = visit("index.html")
    page.check()
    assert "hht3d" in page.page.title()
    assert page.page.locator("nav a[href*='auto_examples/index.html']").count() > 0  # the gallery is reachable


def test_gallery_example_shows_its_figures(visit):
    page = visit("auto_examples/plot_fig4_spot.html")
    page.check()
    assert "spot" in page.page.title().lower()
    figures = [image for image in page.images() if "/_images/sphx_glr_plot_fig4_spot" in image["src"]]
    assert figures and all(image["loaded"] for image in figures), page.images()


def test_api_page_documents_emd_with_its_example(visit):
    page = visit("api/generated/hht3d.emd.html")
    page.check()
    assert "hht3d.emd" in page.page.title()
    signature = page.page.locator("dt.sig[id='hht3d.emd']")
    assert signature.count() == 1 and "emd(" in signature.inner_text()
    assert page.page.locator("div.highlight-pycon, div.doctest").count() > 0  # the Examples, rendered


def test_equations_are_typeset_by_the_sites_own_mathjax(visit):
    page = visit("guide/concepts.html")
    page.check()  # first: a MathJax from elsewhere is aborted, and would time out below
    page.page.wait_for_selector("mjx-container", timeout=30_000)
    page.page.wait_for_load_state("networkidle")
    page.check()
    scripts = page.page.evaluate("() => Array.from(document.scripts).map(s => s.src).filter(s => /mathjax/i.test(s))")
    assert scripts and all("/_static/mathjax/" in src for src in scripts), scripts
    assert page.page.locator("mjx-container").count() > 3


def test_search_finds_emd(visit):
    page = visit("search.html?q=emd")
    results = page.page.locator("#search-results ul.search li")
    results.first.wait_for(timeout=30_000)
    page.check()
    links = results.locator("a").evaluate_all("links => links.map(a => a.getAttribute('href'))")
    assert any("hht3d.emd.html" in link for link in links), links
