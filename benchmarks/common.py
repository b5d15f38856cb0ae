"""Shared pieces of the benchmarks: paths and models, the paper's Table 1, peak memory, timing,
machine facts, worker subprocesses, result files and Markdown.

Every ``bench_*.py`` takes these from here (``from benchmarks.common import ...``) and runs from the
repository root as ``python -m benchmarks.bench_NAME``; its workers run the same way
(:func:`run_worker`), so they import ``hht3d`` and ``benchmarks`` from this checkout.
"""

from __future__ import annotations

import json
import math
import os
import platform
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data"
RESULTS = ROOT / "benchmarks" / "results"
#: Generated meshes, figures, pages and worker files (git-ignored).
SCRATCH = RESULTS / "scratch"
#: The model shipped in the package (present without ../shared/data).
SPOT = ROOT / "hht3d" / "data" / "spot.ply"

#: The six meshes of ``bench_apps`` and ``bench_emd``, in their order.
MESHES = ["sphere_oct4098", "spot", "spacetime_face_neutral", "rocker_arm", "bunny_zipper", "nefertiti"]
#: The 8-model dataset (meshes from 2.9k to 62k vertices and a real 40k-point scan) of ``bench_graph``
#: and ``bench_storage``.
DATASET = MESHES + ["office_kinect_colored", "bunny_scan_bun000"]

#: Paper Table 1 (MATLAB 2014, 4-core i7, 16 GB): name, vertices, IMFs, EMD s, RT s, total s.
PAPER_TABLE1 = [
    ("Octahedron", 4098, 3, 0.6, 5.13, 6.73),
    ("Hygeia", 13424, 5, 3.8, 24.37, 31.45),
    ("Dragon", 31124, 8, 10.9, 110.81, 137.21),
    ("Hand", 61563, 13, 38.2, 238.76, 303.32),
    ("Tyrannosaur", 100003, 15, 101.83, 356.13, 510.73),
]
#: Columns of :data:`PAPER_TABLE1`.
PAPER_VERTICES, PAPER_IMFS, PAPER_EMD, PAPER_RT, PAPER_TOTAL = 1, 2, 3, 4, 5


def paper_columns(*columns: int) -> list[tuple]:
    """Rows of :data:`PAPER_TABLE1` cut to ``columns``, e.g. ``(vertices, IMFs, EMD s)``."""
    return [tuple(row[c] for c in columns) for row in PAPER_TABLE1]


def paper_interpolated(vertices: int, column: int) -> float:
    """A column of the paper's Table 1 interpolated log-log in the vertex count (clamped outside
    4,098-100,003 vertices)."""
    v = np.log([row[PAPER_VERTICES] for row in PAPER_TABLE1])
    s = np.log([row[column] for row in PAPER_TABLE1])
    return float(np.exp(np.interp(np.log(vertices), v, s)))


# -- models ------------------------------------------------------------------------------------------


def model_path(name: str) -> Path | None:
    """``../shared/data/NAME.ply`` if present."""
    path = DATA / f"{name}.ply"
    return path if path.is_file() else None


def model_or_skip(name: str) -> Path | None:
    """:func:`model_path`, saying on stderr that the benchmark skips the model when it is absent."""
    path = model_path(name)
    if path is None:
        print(f"skip {name}: {DATA / (name + '.ply')} not present", file=sys.stderr, flush=True)
    return path


def require_models(names) -> list[Path]:
    """The paths of ``names``; exits naming the absent ones (for benchmarks that need them all)."""
    missing = [name for name in names if model_path(name) is None]
    if missing:
        sys.exit(f"models not found in {DATA}: {', '.join(missing)}")
    return [model_path(name) for name in names]


def mean_adjacent_distance(surface) -> float:
    """Mean distance between the vertices of the surface's adjacency pairs (an edge length)."""
    coo = surface.adjacency.tocoo()
    return np.linalg.norm(surface.vertices[coo.row] - surface.vertices[coo.col], axis=1).mean()


# -- peak memory -------------------------------------------------------------------------------------


def peak_rss_mb() -> float:
    """Peak resident memory of this process (MB; ``ru_maxrss``, MKL allocations included).

    ``ru_maxrss`` is carried across ``exec`` from a forking parent: a subprocess that must report its
    own peak from its start reads ``status_mb("VmHWM")`` instead.
    """
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # kB on Linux


def status_mb(field: str) -> float:
    """A memory field of /proc/self/status in MB (``VmRSS`` now, ``VmHWM`` peak); NaN if absent."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith(field + ":"):
            return int(line.split()[1]) / 1024.0
    return float("nan")


def reset_peak() -> bool:
    """Reset the peak resident set (``VmHWM``, and so ``ru_maxrss``) to the current one (Linux >= 4.0,
    ``/proc/self/clear_refs``); False where the kernel refuses, and the peak then runs on."""
    try:
        Path("/proc/self/clear_refs").write_text("5")
        return True
    except OSError:
        return False


# -- timing and messages -----------------------------------------------------------------------------


def timed(fn):
    """``(fn(), wall seconds)``."""
    start = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - start


def best_of(repeat: int, run) -> float:
    """Shortest wall time of ``repeat`` calls of ``run()``."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        run()
        times.append(time.perf_counter() - start)
    return min(times)


def log(msg: str) -> None:
    """A progress line on stderr with the time of day."""
    print(f"[{time.strftime('%H:%M:%S')}] {msg}", file=sys.stderr, flush=True)


# -- machine -----------------------------------------------------------------------------------------


def load_average(digits: int = 2) -> list[float]:
    """The 1-, 5- and 15-minute load averages, rounded."""
    return [round(x, digits) for x in os.getloadavg()]


def machine() -> dict:
    """What the numbers were measured on."""
    from hht3d import linalg

    return {
        "platform": platform.platform(),
        "cpus": os.cpu_count(),
        "python": platform.python_version(),
        "backend": linalg.default_backend(),
        "load_average": load_average(),
    }


def machine_meta(**facts) -> dict:
    """:func:`machine` under the keys of the ``meta`` records of ``apps``, ``emd`` and ``riesz.json``
    (``machine`` is the platform), then ``facts``."""
    m = machine()
    return {"machine": m["platform"], "cpus": m["cpus"], "backend": m["backend"], "python": m["python"], **facts}


def mkl_environment() -> tuple[dict, float | None]:
    """Environment for worker processes with ``PYPARDISO_MKL_RT`` set, and the lookup time.

    pypardiso otherwise searches the installation tree for ``mkl_rt`` once per process.
    """
    env = dict(os.environ)
    try:
        import pypardiso
    except ImportError:
        return env, None
    start = time.perf_counter()
    solver = pypardiso.PyPardisoSolver()
    lookup = time.perf_counter() - start
    env.setdefault("PYPARDISO_MKL_RT", solver.libmkl._name)
    return env, lookup


# -- worker subprocesses -----------------------------------------------------------------------------


def worker_command(script: str, *args: str) -> list[str]:
    """``python -m benchmarks.SCRIPT ARGS``: a benchmark's own module in a fresh interpreter
    (``script`` is its ``__file__``), so that the worker's peak memory and threads are its own."""
    return [sys.executable, "-m", f"benchmarks.{Path(script).stem}", *args]


def run_worker(
    script: str, args, *, env: dict | None = None, timeout: float | None = None, **options
) -> subprocess.CompletedProcess:
    """Run :func:`worker_command` from the repository root; output captured as text unless
    ``options`` redirect ``stdout`` or ``stderr``."""
    if "stdout" not in options and "stderr" not in options:
        options["capture_output"] = True
    return subprocess.run(worker_command(script, *args), cwd=ROOT, env=env, timeout=timeout, text=True, **options)


def worker_answer(done: subprocess.CompletedProcess):
    """The JSON on the last line that a worker printed."""
    return json.loads(done.stdout.strip().splitlines()[-1])


def worker_json(script: str, args, **options):
    """:func:`run_worker` and its answer; RuntimeError with the end of its stderr if it failed."""
    done = run_worker(script, args, **options)
    if done.returncode != 0:
        raise RuntimeError(f"worker {list(args)} failed (exit {done.returncode}):\n{done.stderr[-3000:]}")
    return worker_answer(done)


# -- result files and Markdown -----------------------------------------------------------------------


def previous_results(name: str) -> dict:
    """``results/NAME.json`` of the last run ({} if none): benchmarks that re-run some parts keep the
    records of the others."""
    path = RESULTS / f"{name}.json"
    return json.loads(path.read_text()) if path.is_file() else {}


def write_results(name: str, records: dict, markdown: str, indent: int = 2) -> list[Path]:
    """Write ``results/NAME.json`` and ``results/NAME.md``."""
    RESULTS.mkdir(parents=True, exist_ok=True)
    json_path, md_path = RESULTS / f"{name}.json", RESULTS / f"{name}.md"
    json_path.write_text(json.dumps(records, indent=indent, default=float))
    md_path.write_text(markdown)
    return [json_path, md_path]


def table(header: list[str], rows: list[list]) -> str:
    """A Markdown table."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


def fixed(x, digits: int = 2, missing: str = "n/a") -> str:
    """``x`` with ``digits`` decimals; ``missing`` for None or NaN."""
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return missing
    return f"{x:.{digits}f}"


def short(x, digits: int = 2) -> str:
    """``x`` with ``digits`` decimals, or as ``1.2e-05`` below ``10**-digits``; "n/a" for None or
    not finite."""
    if x is None or not np.isfinite(x):
        return "n/a"
    return f"{x:.{digits}f}" if abs(x) >= 10**-digits else f"{x:.1e}"
