"""The page (hht3d.viz.page): self-contained, no external script or style."""

from __future__ import annotations

import re
from html.parser import HTMLParser


class _References(HTMLParser):
    """Every script source, stylesheet link and CSS import/url() of a page."""

    def __init__(self):
        super().__init__()
        self.found, self._in_style = [], False

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if tag == "script" and attrs.get("src"):
            self.found.append(f"script src={attrs['src']}")
        if tag == "link" and attrs.get("href"):
            self.found.append(f"link href={attrs['href']}")
        self._in_style = tag == "style"

    def handle_endtag(self, tag):
        self._in_style = False

    def handle_data(self, data):
        if self._in_style:
            self.found += [f"css {m}" for m in re.findall(r"@import[^;]*|url\([^)]*\)", data)]


def test_page_holds_no_external_script_or_style(result_page):
    finder = _References()
    finder.feed(result_page.read_text(encoding="utf-8"))
    assert finder.found == []
