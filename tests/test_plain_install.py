"""What a plain ``pip install hht3d`` gets: the SuperLU path's memory, estimates known in advance,
a refusal before computing when they cannot fit, and one warning on large meshes.

Memory oracle: the peak resident memory of a real subprocess (``VmHWM``, Linux).  The bound is
the estimator's (:func:`hht3d.linalg.estimate.estimate_hht`, fitted on nefertiti and igea by
``benchmarks/bench_backends.py``): the HHT of a 10k-vertex sphere must not grow the process by
more than the estimate of its own increment (measured 42 MB against 58 MB).  Keeping every
SuperLU factor of the run alive, as a reference cycle through ``Factor.solve`` once did in a
benchmark, grew it by 1,019 MB.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import warnings
from pathlib import Path

import pytest
import scipy.sparse as sp

from hht3d import linalg
from hht3d.cli import main
from hht3d.errors import InputError
from hht3d.linalg import estimate as estimates

TESTS = Path(__file__).resolve().parent

#: The HHT of a sphere on SuperLU in a fresh process: its size, the peak before and after (bytes), seconds.
#: Peaks are VmHWM: Linux carries ru_maxrss across exec from the forking parent (here pytest).
CHILD = f"""
import json, resource, sys, time
def peak():
    with open("/proc/self/status") as status:
        return next(int(line.split()[1]) * 1024 for line in status if line.startswith("VmHWM:"))
sys.path.insert(0, {str(TESTS)!r})
from helpers.meshes import random_bump_sphere
from hht3d import hht
from hht3d.geometry.signals import mean_curvature
from hht3d.geometry.surface import Surface
vertices, faces, _, _ = random_bump_sphere(5)
surface = Surface(vertices, faces)
signal = mean_curvature(surface)
limit = sys.argv[1:] and int(sys.argv[1])
if limit:  # an address-space limit this far above what the process maps now (ulimit -v)
    import psutil
    resource.setrlimit(resource.RLIMIT_AS, (psutil.Process().memory_info().vms + limit, resource.RLIM_INFINITY))
before = peak()
start = time.perf_counter()
try:
    result = hht(surface, signal, max_imfs=2)
    error = None
except Exception as exc:
    error = f"{{type(exc).__name__}}: {{exc}}"
print(json.dumps({{"vertices": surface.n_vertices, "before": before, "seconds": time.perf_counter() - start,
                  "after": peak(), "error": error}}))
"""


def _child(*args) -> dict:
    env = {**os.environ, linalg.BACKEND_VARIABLE: "superlu", "PYTHONWARNINGS": "ignore"}
    done = subprocess.run(
        [sys.executable, "-c", CHILD, *map(str, args)], env=env, capture_output=True, text=True, timeout=300, check=True
    )
    return json.loads(done.stdout.strip().splitlines()[-1])


@pytest.mark.skipif(not Path("/proc/self/status").is_file(), reason="peak memory read from Linux's /proc")
def test_superlu_hht_stays_within_the_estimated_memory():
    run = _child()
    assert run["error"] is None
    found = linalg.estimate_hht(run["vertices"], "superlu")
    bound = found.added_bytes
    assert 0 < run["after"] - run["before"] <= bound, (run, bound)


@pytest.mark.skipif(not Path("/proc/self/status").is_file(), reason="peak memory read from Linux's /proc")
def test_memory_estimate_above_the_limit_stops_in_seconds_with_the_fix():
    run = _child(linalg.estimate_hht(10_242, "superlu").added_bytes // 2)
    assert run["error"] is not None and run["error"].startswith("InputError: a surface of 10,242 vertices needs")
    assert all(part in run["error"] for part in ("superlu", "available", "hht3d[fast]", "decimate", "cluster"))
    assert run["seconds"] < 5


def test_check_memory_refuses_with_one_line_before_computing():
    with pytest.raises(InputError) as info:
        linalg.check_memory(1_000_000, "superlu", available=2**30)
    message = str(info.value)
    assert "\n" not in message and "1,000,000 vertices" in message and "only 1.0 GiB is available" in message
    assert linalg.check_memory(1_000_000, "superlu", available=2**50).peak_bytes > 2**30


def test_estimates_grow_with_the_mesh_and_superlu_costs_most():
    for name in _calibrated():
        small, large = linalg.estimate_hht(50_000, name), linalg.estimate_hht(134_000, name)
        assert large.peak_bytes > small.peak_bytes > 0 and large.seconds > small.seconds > 0
    fastest = linalg.estimate_hht(50_000, linalg.available_backends()[0])
    assert linalg.estimate_hht(50_000, "superlu").seconds >= fastest.seconds


def test_info_backends_prints_each_installed_backends_estimate(capsys):
    assert main(["info", "--backends", "--vertices", "134345"]) == 0
    out = capsys.readouterr().out
    assert "estimated whole HHT of 134,345 vertices" in out
    rows = [line.split() for line in out.splitlines() if line.startswith("    ") and "peak" in line]
    assert [row[0] for row in rows] == _calibrated()


def test_slow_fallback_warns_once_and_only_on_large_meshes(monkeypatch):
    monkeypatch.setattr(estimates, "_WARNED", set())
    large = sp.identity(estimates.SLOW_FALLBACK_VERTICES + 1, format="csr")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        linalg.SymbolicFactorization(sp.identity(100, format="csr"), "superlu")
        for _ in range(3):
            linalg.SymbolicFactorization(large, "superlu").factorize(large)
    slow = [w for w in caught if issubclass(w.category, linalg.SlowSolverWarning)]
    assert len(slow) == 1 and "pip install 'hht3d[fast]'" in str(slow[0].message)
    for name in linalg.available_backends():
        assert (linalg.slow_fallback(10**6, name) is None) == (name != "superlu")


@pytest.mark.filterwarnings("ignore::hht3d.linalg.estimate.SlowSolverWarning")
def test_pipeline_summary_and_cli_carry_the_advice_once(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv(linalg.BACKEND_VARIABLE, "superlu")
    monkeypatch.setattr(estimates, "SLOW_FALLBACK_VERTICES", 1_000)  # the shipped model has 2,930
    out = tmp_path / "demo"
    assert (
        main(
            [
                "demo",
                "--out",
                str(out),
                "--scheduler",
                "synchronous",
                "--quiet",
                "--set",
                "steps.hht.params.max_imfs=1",
                "--set",
                "outputs.summary=true",
            ]
        )
        == 0
    )
    err = capsys.readouterr().err
    assert err.count("warning: superlu is a slow sparse solver for 2,930 vertices") == 1
    rows = json.loads((out / "summary.json").read_text())
    assert "hht3d[fast]" in rows[0]["solver_advice"]


def _calibrated() -> list[str]:
    """The installed backends with a fitted whole-HHT cost (not ``cg``: the default EMD refuses it)."""
    return [name for name in linalg.available_backends() if name in estimates.COSTS]
