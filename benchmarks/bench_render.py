"""Rendering benchmark over the public models in ../shared/data (not a test).

Per model and per available backend (:func:`hht3d.viz.render.available_backends`):

- ``first field``: build a renderer and draw one field (x coordinate) at
  800×800 pixels — for the software renderer this includes rasterising the
  geometry (supersampling 1 and 2 are both timed);
- ``next field``: draw a second field from the same renderer (the software
  renderer reuses its rasterisation; Open3D redraws);
- the same for the model's vertices as a point cloud (software splats; the
  Open3D point renderer).

Open3D runs in a child process per model (Filament on Mesa's CPU Vulkan
driver busy-waits for minutes now and then; a run past the time limit is
reported, not waited for, and the best-of-N numbers hide slow repeats).

Then the composite figure (:func:`hht3d.viz.figures.hht_figure`, paper Fig. 4:
model, signal, 5 IMFs, residue, 5 frequency and 5 amplitude maps = 18
panels, default size) and the spectrum figure, drawn and saved as PNG.  The
HHT itself is not run: the figure's cost does not depend on the values, so
the IMF-like fields are synthetic (sines of the coordinates at 5 scales,
their amplitude and a frequency-like field); the lumped mass the spectrum
needs is built before timing.  Loading and normals are not timed.

Everything runs in this one process, one timing at a time (the machine's two
cores are shared).  Results: ``benchmarks/results/render.json`` and
``render.md``; the figures go to ``benchmarks/results/scratch/``.

Usage::

    python -m benchmarks.bench_render [--models NAME ...] [--repeat N]
"""

from __future__ import annotations

import argparse
import json
import subprocess

import numpy as np

from benchmarks.common import (
    ROOT,
    SCRATCH,
    best_of,
    load_average,
    machine,
    model_path,
    require_models,
    run_worker,
    table,
    worker_answer,
    write_results,
)
from hht3d.geometry.surface import Surface
from hht3d.io.read import load
from hht3d.spectral.monogenic_signal import MonogenicSignal
from hht3d.transform import HHTResult
from hht3d.viz import figures, panels, render

MODELS = ["bunny_zipper", "nefertiti", "igea"]
SIZE = (800, 800)
N_IMFS = 5
OPEN3D_TIMEOUT = 300


def time_backend(surface: Surface, backend: str, repeat: int, **options) -> dict:
    x, y = surface.vertices[:, 0], surface.vertices[:, 1]
    scale_x, scale_y = render.color_scale(x), render.color_scale(y)
    holder = {}

    def first():
        holder["drawer"] = render.renderer(surface, size=SIZE, backend=backend, **options)
        holder["image"] = holder["drawer"].render(x, scale_x)

    first_seconds = best_of(repeat, first)
    next_seconds = best_of(repeat, lambda: holder["drawer"].render(y, scale_y))
    return {
        "first_field_s": first_seconds,
        "next_field_s": next_seconds,
        "coverage": float(holder["image"].mask.mean()),
    }


def synthetic_result(surface: Surface) -> HHTResult:
    """An HHTResult of the right shapes with IMF-like fields (the figure's cost is value-free)."""
    v = (surface.vertices - surface.vertices.mean(axis=0)) / surface.bounding_box_diagonal
    scales = 2.0 ** np.arange(N_IMFS, 0, -1) * 4
    imfs = np.array([np.sin(s * v[:, 0]) * np.cos(s * v[:, 1] + 1.3 * s * v[:, 2]) / s for s in scales])
    residue = v[:, 1]
    amplitude = np.abs(imfs) + 0.1 / scales[:, None]
    frequency = scales[:, None] * (1.2 + np.cos(7 * v[:, 0]))[None, :] / surface.bounding_box_diagonal
    mono = MonogenicSignal(
        imfs=imfs,
        riesz=np.zeros(imfs.shape + (3,)),
        amplitude=amplitude,
        phase=np.arccos(np.clip(imfs / amplitude, -1, 1)),
        frequency=frequency,
        area=surface.mass_diagonal,
    )
    return HHTResult(surface=surface, signal=imfs.sum(axis=0) + residue, imfs=imfs, residue=residue, monogenic=mono)


def time_figures(surface: Surface, repeat: int) -> dict:
    result = synthetic_result(surface)
    surface.mass_diagonal  # the spectrum's vertex areas: built before timing
    SCRATCH.mkdir(parents=True, exist_ok=True)
    hht_path = SCRATCH / f"render_{surface.name}_hht.png"
    spectrum_path = SCRATCH / f"render_{surface.name}_spectrum.png"
    composite = best_of(repeat, lambda: panels.save_figure(figures.hht_figure(result), hht_path))
    spectrum = best_of(repeat, lambda: panels.save_figure(figures.spectrum_figure(result), spectrum_path))
    return {
        "composite_s": composite,
        "spectrum_s": spectrum,
        "composite_png": str(hht_path.relative_to(ROOT)),
        "spectrum_png": str(spectrum_path.relative_to(ROOT)),
    }


def geometries(name: str) -> dict[str, Surface]:
    """The model as a mesh and its vertices as a point cloud (normals built, not timed)."""
    surface = load(model_path(name))
    surface.normals
    return {"mesh": surface, "points": Surface(surface.vertices, normals=surface.normals, name=f"{name} (points)")}


def software_rows(shapes: dict[str, Surface], repeat: int) -> list[dict]:
    return [
        {
            "geometry": kind,
            "backend": "software",
            "supersample": ss,
            **time_backend(geometry, "software", repeat, supersample=ss),
        }
        for kind, geometry in shapes.items()
        for ss in (1, 2)
    ]


def open3d_rows(name: str, repeat: int) -> list[dict]:
    """Open3D timings in a child process: Filament on a CPU Vulkan driver has hung now and then."""
    try:
        done = run_worker(__file__, ["--open3d-worker", name, "--repeat", str(repeat)], timeout=OPEN3D_TIMEOUT)
    except subprocess.TimeoutExpired:
        return [
            {
                "geometry": "mesh+points",
                "backend": "open3d",
                "supersample": None,
                "error": f"no answer within {OPEN3D_TIMEOUT} s (hung)",
            }
        ]
    if done.returncode != 0:
        return [
            {
                "geometry": "mesh+points",
                "backend": "open3d",
                "supersample": None,
                "error": f"exit code {done.returncode}: {done.stderr.strip().splitlines()[-1:]}",
            }
        ]
    return worker_answer(done)


def open3d_worker(name: str, repeat: int) -> None:
    rows = [
        {"geometry": kind, "backend": "open3d", "supersample": None, **time_backend(geometry, "open3d", repeat)}
        for kind, geometry in geometries(name).items()
    ]
    print(json.dumps(rows))


def run_model(name: str, backends: list[str], repeat: int) -> dict:
    shapes = geometries(name)
    surface = shapes["mesh"]
    row = {
        "model": name,
        "vertices": surface.n_vertices,
        "faces": len(surface.faces),
        "renders": software_rows(shapes, repeat) + (open3d_rows(name, repeat) if "open3d" in backends else []),
    }
    for r in row["renders"]:
        timing = r.get("error") or f"first {r['first_field_s']:.2f} s, next {r['next_field_s']:.2f} s"
        print(f"{name} {r['geometry']} {r['backend']} ss={r['supersample']}: {timing}", flush=True)
    row.update(time_figures(surface, repeat))
    print(f"{name}: composite {row['composite_s']:.2f} s, spectrum {row['spectrum_s']:.2f} s", flush=True)
    return row


def markdown(report: dict) -> str:
    lines = [
        "# Rendering benchmark",
        "",
        f"Machine: {report['machine']}.  Generated by `python -m benchmarks.bench_render`; the method is "
        f"in its docstring.  Image {SIZE[0]}×{SIZE[1]} pixels; best of {report['repeat']} runs.  "
        f"Backends available: {', '.join(report['backends'])}.",
        "",
        "## One field on the model",
        "",
        "`first field`: renderer set-up (software: rasterisation) + one field; `next field`: another "
        "field from the same renderer.",
        "",
        table(
            ["model", "#V", "geometry", "backend", "supersample", "first field s", "next field s", "coverage"],
            [
                [row["model"], f"{row['vertices']:,}", r["geometry"], r["backend"], r["supersample"] or "–"]
                + (
                    [r["error"], "", ""]
                    if "error" in r
                    else [f"{r['first_field_s']:.2f}", f"{r['next_field_s']:.2f}", f"{r['coverage']:.2f}"]
                )
                for row in report["models"]
                for r in row["renders"]
            ],
        ),
    ]
    if "open3d" in report["backends"]:
        lines += [
            "",
            "Open3D here is Filament on Mesa's CPU Vulkan driver (lavapipe): single renders "
            "sometimes busy-wait for minutes (both cores spinning) — the best-of numbers above hide "
            "those repeats; it is for machines with a GPU driver.",
        ]
    lines += [
        "",
        f"## Figures (auto backend, {N_IMFS} IMFs: 18 panels)",
        "",
        table(
            ["model", "#V", "composite (Fig. 4) s", "spectrum s", "composite PNG"],
            [
                [
                    row["model"],
                    f"{row['vertices']:,}",
                    f"{row['composite_s']:.2f}",
                    f"{row['spectrum_s']:.2f}",
                    f"`{row['composite_png']}`",
                ]
                for row in report["models"]
            ],
        ),
    ]
    return "\n".join(lines) + "\n"


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--models", nargs="+", default=MODELS)
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--open3d-worker", metavar="MODEL", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.open3d_worker:
        return open3d_worker(args.open3d_worker, args.repeat)
    require_models(args.models)
    backends = render.available_backends()
    facts = machine()
    report = {
        "machine": f"{facts['platform']}; {facts['cpus']} CPUs (shared; load average {load_average(1)}); "
        f"Python {facts['python']}",
        "repeat": args.repeat,
        "size": SIZE,
        "backends": backends,
        "models": [run_model(m, backends, args.repeat) for m in args.models],
    }
    write_results("render", report, markdown(report))
    print(markdown(report))


if __name__ == "__main__":
    main()
