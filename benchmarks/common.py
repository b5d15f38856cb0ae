"""Shared pieces of the benchmarks: paths, the paper's Table 1, machine facts, result files."""
from __future__ import annotations

import json
import os
import platform
import resource
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data"
RESULTS = ROOT / "benchmarks" / "results"

if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

#: Paper Table 1 (MATLAB 2014, 4-core i7, 16 GB): vertices, IMFs, EMD s, RT s, total s.
PAPER_TABLE1 = [
    ("Octahedron", 4098, 3, 0.6, 5.13, 6.73),
    ("Hygeia", 13424, 5, 3.8, 24.37, 31.45),
    ("Dragon", 31124, 8, 10.9, 110.81, 137.21),
    ("Hand", 61563, 13, 38.2, 238.76, 303.32),
    ("Tyrannosaur", 100003, 15, 101.83, 356.13, 510.73),
]


def mkl_environment() -> tuple[dict, float | None]:
    """Environment for worker processes with ``PYPARDISO_MKL_RT`` set, and the lookup time.

    pypardiso otherwise searches the installation tree for ``mkl_rt`` once per process.
    """
    import time

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


def model_path(name: str) -> Path | None:
    """``../shared/data/NAME.ply`` if present."""
    path = DATA / f"{name}.ply"
    return path if path.is_file() else None


def peak_rss_mb() -> float:
    """Peak resident memory of this process (MB); MKL allocations included."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def status_mb(field: str) -> float:
    """A memory field of /proc/self/status in MB (``VmRSS`` now, ``VmHWM`` peak)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith(field + ":"):
            return int(line.split()[1]) / 1024.0
    return float("nan")


def machine() -> dict:
    """What the numbers were measured on."""
    from hht3d import linalg

    return {"platform": platform.platform(), "cpus": os.cpu_count(), "python": platform.python_version(),
            "backend": linalg.default_backend(), "load_average": [round(x, 2) for x in os.getloadavg()]}


def write_results(name: str, records: dict, markdown: str) -> list[Path]:
    """Write ``results/NAME.json`` and ``results/NAME.md``."""
    RESULTS.mkdir(parents=True, exist_ok=True)
    json_path, md_path = RESULTS / f"{name}.json", RESULTS / f"{name}.md"
    json_path.write_text(json.dumps(records, indent=2, default=float))
    md_path.write_text(markdown)
    return [json_path, md_path]


def table(header: list[str], rows: list[list]) -> str:
    """A Markdown table."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)
