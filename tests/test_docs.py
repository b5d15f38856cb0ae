"""The API reference of the documentation site covers the public API.

Every name of the ``__all__`` of :mod:`hht3d` and of each subpackage is an entry of the
``autosummary`` of its page in ``docs/api/`` (which the site build turns into a page per name),
and no entry is a name that is no longer public: a new public function without a place in the
reference fails here, before the site is built.
"""

from __future__ import annotations

import importlib
import json
import pkgutil
import re
import sys
from pathlib import Path

import pytest

import hht3d

API = Path(__file__).resolve().parents[1] / "docs" / "api"
PACKAGES = ["hht3d", *(f"hht3d.{m.name}" for m in pkgutil.iter_modules(hht3d.__path__) if m.ispkg)]


def reference() -> dict[str, list[str]]:
    """``package -> entries`` of every ``autosummary`` directive of the API pages, by ``currentmodule``."""
    found: dict[str, list[str]] = {}
    for page in sorted(API.glob("*.rst")):
        module = None
        lines = page.read_text().splitlines()
        for i, line in enumerate(lines):
            if match := re.fullmatch(r"\.\. currentmodule:: (\S+)", line.strip()):
                module = match.group(1)
            elif line.strip() == ".. autosummary::":
                assert module, f"{page.name}: an autosummary before any currentmodule"
                entries = found.setdefault(module, [])
                for entry in lines[i + 1 :]:
                    if entry and not entry.startswith("   "):
                        break
                    if entry.strip() and not entry.strip().startswith(":"):
                        entries.append(entry.strip())
    return found


def test_the_reference_is_read():
    documented = reference()
    assert "emd" in documented["hht3d"] and "HHTResult" in documented["hht3d"]


@pytest.mark.parametrize("package", PACKAGES)
def test_every_public_name_is_in_the_api_reference(package):
    module = importlib.import_module(package)
    public = module.__dict__.get("__all__")
    assert public, f"{package} has no __all__: list its public names"
    absent = [name for name in public if not hasattr(module, name)]
    assert not absent, f"{package}.__all__ names what the package does not define (import it): {absent}"
    entries = reference().get(package, [])
    missing = [name for name in public if name not in entries]
    assert not missing, f"not in docs/api/ (an autosummary under currentmodule {package}): {missing}"
    stale = [name for name in entries if name not in public]
    assert not stale, f"docs/api/ lists names {package}.__all__ does not: {stale}"
    assert len(entries) == len(set(entries)), f"{package}: an entry listed twice"


def _benchmark_pages():
    sys.path.insert(0, str(API.parent / "_ext"))
    try:
        return importlib.import_module("benchmark_pages")
    finally:
        sys.path.remove(str(API.parent / "_ext"))


def test_every_benchmark_result_is_a_generated_performance_page():
    """Each ``benchmarks/results/*.json`` becomes a page of the Performance section at build time,
    drawn by its benchmark's own table code from the JSON, with the machine it was measured on."""
    pages = _benchmark_pages()
    results = {path.stem for path in pages.RESULTS.glob("*.json")}
    assert results - pages.NOT_PERFORMANCE == set(pages.RENDERERS), (
        "a results file without a page, or a page without one"
    )
    toctree = (API.parent / "performance.md").read_text()
    for name in pages.RENDERERS:
        text = pages.render(name)
        assert text.startswith("# ") and "\nMachine: " in text and "\n|---" in text, name
        assert f"\nbenchmarks/{name}\n" in toctree, f"docs/performance.md does not list benchmarks/{name}"
    data = json.loads((pages.RESULTS / "viewer.json").read_text())
    sizes = [f"{case['vertices']:,}" for case in data["cases"]]
    assert all(size in pages.render("viewer") for size in sizes), "the figures come from the JSON"
