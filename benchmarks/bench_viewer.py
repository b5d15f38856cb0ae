"""Viewer benchmark: size and load time of the HTML page of hht3d.viz.viewer (not a test).

Cases: spot (2,930 vertices, shipped in the package), igea decimated to 100k
vertices (the size of the first budget), igea (134,345 vertices, the paper's
Hygeia, from ../shared/data) and igea Loop-subdivided to 1M vertices
(``benchmarks.meshes.generate``, kept in ``results/scratch/``).  The fields are those
of ``bench_render.synthetic_result`` (5 IMFs: 22 fields); a page's cost
depends on the numbers of vertices, triangles and fields, not on the values.

Per case:

- ``write s``: :meth:`HHTResult.to_html` from a result in memory (colour
  limits, spectrum, quality figures, and above
  :data:`hht3d.viz.viewer.VERTEX_BUDGET` vertices the quadric decimation, timed
  on its own as ``decimate s``);
- ``MB``: the file, of which plotly.js is a fixed 4.8 MB;
- ``load s``: from navigation until the page marks itself drawn
  (``body[data-ready]``: data decoded, both plots drawn) in headless Debian
  chromium with software WebGL (SwiftShader, ``--disable-gpu``), best and
  median of ``--loads`` fresh tabs;
- ``switch s``: choosing another field with the page's selector until it is
  drawn.

Budgets (:data:`hht3d.viz.viewer.PAGE_BUDGETS`) are checked at 100k and 1M
vertices.  A screenshot of every page goes to ``results/scratch/``.

Usage::

    python -m benchmarks.bench_viewer [--cases 3k 100k 134k 1m] [--loads 3]
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import sys
import time
from pathlib import Path

import hht3d
from benchmarks.bench_render import synthetic_result
from benchmarks.common import SCRATCH, machine, model_path, table, write_results
from benchmarks.meshes import generate
from hht3d.viz.viewer import PAGE_BUDGETS, VERTEX_BUDGET, shown_copy

CASES = ("3k", "100k", "134k", "1m")
CHROMIUM_FLAGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


def surface_of(case: str) -> hht3d.Surface | None:
    """The mesh of a case; ``None`` when its source model is absent."""
    if case == "3k":
        from hht3d.cli import demo_model_path

        return hht3d.load(demo_model_path())
    igea = model_path("igea")
    if igea is None:
        return None
    if case == "1m":
        mesh = SCRATCH / "igea_1m.ply"
        if not mesh.is_file():
            generate("1m", mesh)
        return hht3d.load(mesh, clean=False)
    surface = hht3d.load(igea)
    if case == "100k":
        small = shown_copy(surface, 100_000)
        return hht3d.Surface(small.vertices, small.faces, name="igea_100k")
    return surface


def measure_page(browser, path: Path, loads: int, shot: Path) -> dict:
    seconds, errors = [], []
    for attempt in range(loads):
        page = browser.new_page(viewport={"width": 1400, "height": 820})
        page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
        page.on("pageerror", lambda e: errors.append(str(e)))
        start = time.perf_counter()
        page.goto(path.as_uri(), timeout=600_000)
        page.wait_for_selector("body[data-ready=true]", timeout=600_000)
        seconds.append(time.perf_counter() - start)
        if attempt == loads - 1:
            start = time.perf_counter()
            page.select_option("#hht3d-field", "imf_1")
            page.wait_for_selector("body[data-field=imf_1]", timeout=600_000)
            switch = time.perf_counter() - start
            page.screenshot(path=str(shot))
        page.close()
    return {
        "load_s_best": min(seconds),
        "load_s_median": statistics.median(seconds),
        "load_s_all": seconds,
        "switch_s": switch,
        "js_errors": errors,
    }


def run_case(case: str, browser, loads: int) -> dict | None:
    surface = surface_of(case)
    if surface is None:
        print(f"{case}: skipped (../shared/data/igea.ply absent)", flush=True)
        return None
    result = synthetic_result(surface)
    start = time.perf_counter()
    shown = shown_copy(surface)
    decimate = time.perf_counter() - start if shown.decimated else 0.0
    path = SCRATCH / f"viewer_{case}.html"
    start = time.perf_counter()
    result.to_html(path)
    write = time.perf_counter() - start
    from plotly.offline import get_plotlyjs

    record = {
        "case": case,
        "vertices": surface.n_vertices,
        "triangles": len(surface.faces),
        "shown_vertices": len(shown.source),
        "fields": len(result.vertex_attributes()),
        "write_s": write,
        "decimate_s": decimate,
        "page_mb": path.stat().st_size / 1e6,
        "plotly_js_mb": len(get_plotlyjs().encode()) / 1e6,
        "load_average": os.getloadavg()[0],
    }
    record.update(measure_page(browser, path, loads, SCRATCH / f"viewer_{case}.png"))
    print(f"{case}: {record['page_mb']:.1f} MB, write {write:.1f} s, load {record['load_s_best']:.1f} s", flush=True)
    return record


def budget_rows(records: list[dict]) -> list[list]:
    rows = []
    for vertices, (mb, seconds) in PAGE_BUDGETS.items():
        near = [r for r in records if 0.75 * vertices <= r["vertices"] <= 1.25 * vertices]
        for r in near:
            met = r["page_mb"] <= mb and r["load_s_median"] <= seconds
            rows.append(
                [
                    f"{vertices:,}",
                    f"≤ {mb:g} MB, ≤ {seconds:g} s",
                    f"{r['case']}: {r['page_mb']:.1f} MB, {r['load_s_median']:.1f} s",
                    "met" if met else "MISSED",
                ]
            )
    return rows


def markdown(records: list[dict], info: dict) -> str:
    out = [
        "# Viewer: page size and load time",
        "",
        f"Machine: {info['platform']}, {info['cpus']} CPUs, load average at start {info['load_average']}. "
        f"Headless Debian chromium, software WebGL. Vertex budget {VERTEX_BUDGET:,}: larger meshes are shown "
        "decimated. Fields: a synthetic 5-IMF result (22 fields).",
        "",
        table(
            [
                "case",
                "vertices",
                "shown",
                "MB (plotly.js)",
                "write s",
                "decimate s",
                "load s best / median",
                "switch s",
            ],
            [
                [
                    r["case"],
                    f"{r['vertices']:,}",
                    f"{r['shown_vertices']:,}",
                    f"{r['page_mb']:.1f} ({r['plotly_js_mb']:.1f})",
                    f"{r['write_s']:.1f}",
                    f"{r['decimate_s']:.1f}",
                    f"{r['load_s_best']:.1f} / {r['load_s_median']:.1f}",
                    f"{r['switch_s']:.2f}",
                ]
                for r in records
            ],
        ),
        "",
        "## Budgets (hht3d.viz.viewer.PAGE_BUDGETS)",
        "",
        table(["vertices", "budget", "measured", ""], budget_rows(records)),
        "",
    ]
    errors = [f"{r['case']}: {e}" for r in records for e in r["js_errors"]]
    out.append("JavaScript errors: " + ("; ".join(errors) if errors else "none") + ".")
    return "\n".join(out) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="+", choices=CASES, default=list(CASES))
    parser.add_argument("--loads", type=int, default=3, help="fresh tabs per page")
    args = parser.parse_args(argv)
    from playwright.sync_api import sync_playwright

    executable = shutil.which("chromium")
    if executable is None:
        raise SystemExit("Debian's chromium is needed: bash .ci/setup installs it")
    SCRATCH.mkdir(parents=True, exist_ok=True)
    info = machine()
    records = []
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=executable, args=CHROMIUM_FLAGS, headless=True)
        for case in args.cases:
            record = run_case(case, browser, args.loads)
            if record is not None:
                records.append(record)
        browser.close()
    for path in write_results("viewer", {"machine": info, "cases": records}, markdown(records, info)):
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
