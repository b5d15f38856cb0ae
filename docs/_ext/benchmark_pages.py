"""The measured tables of the Performance page, generated when the site is built (``docs/conf.py``).

Each benchmark writes ``benchmarks/results/NAME.json`` and renders it to Markdown with its own
``markdown`` function (which also states the machine and load it ran on).  At ``builder-inited``
this extension renders every JSON listed in :data:`RENDERERS` with that function into
``docs/benchmarks/NAME.md``, one page per benchmark under ``docs/performance.md``'s table of
contents, so the site's figures are those of the files and never a copy made by hand.
"""

from __future__ import annotations

import importlib
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))  # the checkout's ``benchmarks`` package (``.ci/docs`` also puts it first)
RESULTS = ROOT / "benchmarks" / "results"
PAGES = ROOT / "docs" / "benchmarks"

#: Result file -> (module of ``benchmarks`` with its ``markdown``, the arguments it takes from the JSON).
RENDERERS = {
    "hht": ("hht_report", lambda d: (d,)),
    "backends": ("bench_backends", lambda d: (d,)),
    "emd": ("bench_emd", lambda d: (d["models"], d["meta"])),
    "emd_reuse": ("bench_emd_reuse", lambda d: (d["models"], d["machine"], d["options"])),
    "riesz": ("bench_riesz", lambda d: (d["fig2"], d["ladder"], d["meta"])),
    "frequency": ("bench_frequency", lambda d: (d,)),
    "quality": ("bench_quality", lambda d: (d,)),
    "methods": ("bench_methods", lambda d: (d,)),
    "apps": ("bench_apps", lambda d: (d["models"], d["meta"])),
    "graph": ("bench_graph", lambda d: (d,)),
    "storage": ("bench_storage", lambda d: (d,)),
    "render": ("bench_render", lambda d: (d,)),
    "viewer": ("bench_viewer", lambda d: (d["cases"], d["machine"])),
    "las": ("bench_las", lambda d: (d,)),
    "multiresolution": ("bench_multiresolution", lambda d: (d,)),
    "blocks": ("bench_blocks", lambda d: (d,)),
}
#: Result files that are not measurements of speed or memory (tools/mutants.py: which test catches a fault).
NOT_PERFORMANCE = {"mutants"}


def render(name: str) -> str:
    """The Markdown page of ``benchmarks/results/NAME.json``: its benchmark's own table text."""
    module, arguments = RENDERERS[name]
    markdown = importlib.import_module(f"benchmarks.{module}").markdown
    text = markdown(*arguments(json.loads((RESULTS / f"{name}.json").read_text(encoding="utf-8"))))
    return f"{text.rstrip()}\n\nSource: `benchmarks/results/{name}.json`.\n"


def write_pages(app) -> None:
    """Write ``docs/benchmarks/NAME.md`` for every result file (``builder-inited``)."""
    PAGES.mkdir(exist_ok=True)
    for stale in PAGES.glob("*.md"):
        stale.unlink()
    for name in RENDERERS:
        (PAGES / f"{name}.md").write_text(render(name), encoding="utf-8")


def setup(app) -> dict:
    app.connect("builder-inited", write_pages)
    return {"parallel_read_safe": True}
