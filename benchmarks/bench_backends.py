"""What a plain ``pip install hht3d`` gets: sparse solvers compared on real meshes, in one run.

Two parts, both on nefertiti (50k vertices) and igea (134k):

* **factorizations** — the candidates for a permissive solver in the core
  dependencies, on the two kinds of system hht3d factorizes: EMD's envelope
  system (a tenth of the vertices constrained, as in the issue's measurement),
  its mean-correction filter ``M + (0.6 d)⁴ S`` (ill-conditioned: the system
  where pivoting hurt most) and the Riesz quadrature's ``L + σM`` at its
  smallest shift.  Seconds of one
  numeric factorization on an already analysed pattern (``first`` includes
  the ordering / analysis), fill, and the largest relative difference of a
  solve from PARDISO's.  SuperLU as hht3d called it before (partial pivoting,
  ``diag_pivot_thresh=1``) is the "before" row; ``qdldl`` (Apache-2.0) and
  ``cholespy`` (BSD) are measured when installed.
* **whole HHT** — ``hht3d.hht`` of the mean-curvature signal from the file,
  every installed backend in its own subprocess (``HHT3D_BACKEND``), with its
  wall time, ratio to PARDISO's in the same run, and peak resident memory
  (``VmHWM`` of the subprocess: Linux carries ``ru_maxrss`` across ``exec``
  from the forking parent, so it would report this process's peak).  ``superlu`` is what a plain install
  runs.  Targets: nefertiti <= 5x PARDISO and <= 2 GB, igea <= 6x and <= 4 GB.

The whole-HHT rows calibrate :data:`hht3d.linalg.estimate.COSTS`: the fitted
constants are printed and stored with the results.

Run: ``python -m benchmarks.bench_backends [--models nefertiti igea] [--skip-factorizations]``.
Writes ``results/backends.json`` and ``results/backends.md``.
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import time

from benchmarks.common import (
    log,
    machine,
    mkl_environment,
    model_path,
    run_worker,
    status_mb,
    table,
    timed,
    worker_answer,
    write_results,
)

MODELS = ("nefertiti", "igea")
TARGETS = {"nefertiti": (5.0, 2.0), "igea": (6.0, 4.0)}  # (x PARDISO, GB)
#: Scale d of the mean-correction filter M + (0.6 d)^4 S measured, as a fraction of the bounding-box
#: diagonal (10 model units on nefertiti, 658 across: an IMF with ~100 extrema).
MEAN_SCALE = 0.015
#: The slow "before" SuperLU (pivoting) is timed only below this many vertices: minutes per factorization above.
BEFORE_MAX_VERTICES = 60_000


def systems(surface) -> dict:
    """The envelope system with 10% of the vertices constrained, a mean filter and the smallest shift's."""
    import numpy as np

    from hht3d.decomposition.envelopes import envelope_energies
    from hht3d.spectral.quadrature import quadrature_plan
    from hht3d.spectral.shifts import shifted_matrix

    e = envelope_energies(surface)
    q = e.data(3.0, 1.0)
    n = surface.n_vertices
    constrained = np.zeros(n, bool)
    constrained[np.random.default_rng(0).choice(n, n // 10, replace=False)] = True
    diag = q[e.diagonal]
    data = q * e.free_entries(~constrained)
    data[e.diagonal[constrained]] = np.where(diag > 0, diag, 1.0)[constrained]
    diagonal = float(np.linalg.norm(np.ptp(surface.vertices, axis=0)))
    mean = (0.6 * MEAN_SCALE * diagonal) ** 4 * e.smoothing
    mean[e.diagonal] += surface.mass_diagonal
    plan = quadrature_plan(surface)
    return {
        "envelope": e.matrix(data),
        "mean filter": e.matrix(mean),
        "shifted": shifted_matrix(surface, float(plan.sigmas[0])),
    }


def candidates(a, points) -> dict:
    """``name -> (first(), again())``: each returns a solve function; ``again`` reuses the analysis.  The
    installed backends get the vertices ``points``, as hht3d gives them (SuperLU orders by them)."""
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    from hht3d import linalg

    out = {}
    for name in linalg.available_backends():

        def first(name=name):
            symbolic = linalg.SymbolicFactorization(a, name, points=points)
            out[name + ":symbolic"] = symbolic
            return symbolic.factorize(a).solve

        out[name] = (first, lambda name=name: out[name + ":symbolic"].factorize(a).solve)
    if a.shape[0] <= BEFORE_MAX_VERTICES:

        def before():
            return spla.splu(a.tocsc(), permc_spec="MMD_AT_PLUS_A", options={"SymmetricMode": True}).solve

        out["superlu, before (pivoting)"] = (before, before)
    try:
        import qdldl

        upper = sp.triu(a, format="csc")
        solver = {}

        def qfirst():
            solver["s"] = qdldl.Solver(upper, upper=True)
            return solver["s"].solve

        def qagain():
            solver["s"].update(upper, upper=True)
            return solver["s"].solve

        out["qdldl"] = (qfirst, qagain)
    except ImportError:
        pass
    try:
        import cholespy
        import numpy as np

        csc = a.tocsc()

        def cfirst():
            s = cholespy.CholeskySolverD(
                a.shape[0],
                csc.indptr.astype(np.int32),
                csc.indices.astype(np.int32),
                csc.data.copy(),
                cholespy.MatrixType.CSC,
            )

            def solve(b):
                x = np.zeros_like(b)
                s.solve(np.ascontiguousarray(b), x)
                return x

            return solve

        out["cholespy (no refactorization)"] = (cfirst, cfirst)
    except ImportError:
        pass
    return {k: v for k, v in out.items() if not k.endswith(":symbolic")}


def factorization_part(name: str) -> list[dict]:
    import numpy as np

    import hht3d

    surface = hht3d.load(model_path(name))
    rows = []
    for kind, a in systems(surface).items():
        b = np.random.default_rng(1).standard_normal(a.shape[0])
        reference = None
        for cand, (first, again) in candidates(a, surface.vertices).items():
            solve, t_first = timed(first)
            solve, t_again = timed(again)
            x, t_solve = timed(lambda solve=solve: solve(b))
            reference = x if reference is None else reference
            diff = float(np.max(np.abs(x - reference)) / np.max(np.abs(reference)))
            rows.append(
                {
                    "model": name,
                    "vertices": surface.n_vertices,
                    "system": kind,
                    "solver": cand,
                    "first_s": t_first,
                    "refactor_s": t_again,
                    "solve_s": t_solve,
                    "max_rel_diff": diff,
                }
            )
            log(f"{name} {kind} {cand}: first {t_first:.2f} s, again {t_again:.2f} s, diff {diff:.1e}")
            del solve
    return rows


def worker(name: str) -> None:
    """The whole HHT of one model on the backend of HHT3D_BACKEND; prints one JSON line."""
    import warnings

    import hht3d
    from hht3d.geometry.signals import mean_curvature

    warnings.simplefilter("ignore")
    start = time.perf_counter()
    surface = hht3d.load(model_path(name))
    result = hht3d.hht(surface, mean_curvature(surface))
    total = time.perf_counter() - start
    print(
        json.dumps(
            {
                "vertices": surface.n_vertices,
                "imfs": result.n_imfs,
                "total_s": total,
                "emd_s": result.info["seconds"]["emd"],
                "spectra_s": result.info["seconds"]["spectra"],
                "factorizations": result.info["emd"]["factorizations"],
                "backend": result.info["emd"]["backend"],
                "peak_mb": status_mb("VmHWM"),
            }
        )
    )


def whole_part(name: str, backends: list[str], timeout: float) -> list[dict]:
    env, _ = mkl_environment()
    rows = []
    for backend in backends:
        run_env = {**env, "HHT3D_BACKEND": backend}
        try:
            done = run_worker(__file__, ["--worker", name], env=run_env, timeout=timeout)
        except subprocess.TimeoutExpired:
            rows.append({"model": name, "backend": backend, "error": f"over {timeout:.0f} s"})
            continue
        if done.returncode:
            rows.append({"model": name, "backend": backend, "error": done.stderr.strip().splitlines()[-1]})
            continue
        row = {"model": name, **worker_answer(done)}
        rows.append(row)
        log(f"{name} whole HHT {backend}: {row['total_s']:.1f} s, peak {row['peak_mb']:.0f} MB")
    return rows


def fit_costs(rows: list[dict]) -> dict:
    """``COSTS`` constants from two models per backend: peak BASELINE + n(a + b log2 n), time t50k (n/50k)^e.

    ``a, b >= 0``, so that the model never falls below linear growth when extrapolated: the
    line through both points when it has them; else the coefficient left alone is the largest
    that any model needs (the other 0), so that no measured peak is underestimated.
    """
    from hht3d.linalg.estimate import BASELINE

    fits = {}
    for backend in sorted({r["backend"] for r in rows if "error" not in r}):
        pts = sorted(
            (r["vertices"], r["peak_mb"] * 2**20 - BASELINE, r["total_s"])
            for r in rows
            if r.get("backend") == backend and "error" not in r
        )
        if len(pts) < 2:
            continue
        (n1, p1, t1), (n2, p2, t2) = pts[0], pts[-1]
        b = (p2 / n2 - p1 / n1) / (math.log2(n2) - math.log2(n1))
        a = p1 / n1 - b * math.log2(n1)
        if b < 0:
            a, b = max(p1 / n1, p2 / n2), 0.0
        elif a < 0:
            a, b = 0.0, max(p1 / (n1 * math.log2(n1)), p2 / (n2 * math.log2(n2)))
        e = math.log(t2 / t1) / math.log(n2 / n1)
        fits[backend] = {
            "a": round(a, 1),
            "b": round(b, 1),
            "seconds_50k": round(t1 * (50_000 / n1) ** e, 2),
            "exponent": round(e, 3),
        }
    return fits


def markdown(record: dict) -> str:
    lines = [
        "# Sparse solvers for a plain install",
        "",
        __doc__.split("\n\n")[0],
        "",
        f"Machine: {record['machine']}",
        "",
    ]
    if record["factorizations"]:
        lines += [
            "## Factorizations",
            "",
            table(
                ["model", "#V", "system", "solver", "first s", "refactorization s", "solve s", "max rel. diff"],
                [
                    [
                        r["model"],
                        f"{r['vertices']:,}",
                        r["system"],
                        r["solver"],
                        f"{r['first_s']:.2f}",
                        f"{r['refactor_s']:.2f}",
                        f"{r['solve_s']:.3f}",
                        f"{r['max_rel_diff']:.1e}",
                    ]
                    for r in record["factorizations"]
                ],
            ),
            "",
        ]
    rows = []
    for r in record["whole"]:
        if "error" in r:
            rows.append([r["model"], "", r["backend"], "", "", "", "", r["error"], "", "", ""])
            continue
        base = next(
            (
                p["total_s"]
                for p in record["whole"]
                if p["model"] == r["model"] and p.get("backend") == "pardiso" and "error" not in p
            ),
            None,
        )
        ratio = r["total_s"] / base if base else float("nan")
        target = ""
        if r["backend"] == "superlu" and r["model"] in TARGETS:
            x, gb = TARGETS[r["model"]]
            met = ratio <= x and r["peak_mb"] <= gb * 1000
            target = f"<= {x:g}x and <= {gb:g} GB: {'met' if met else '**missed**'}"
        rows.append(
            [
                r["model"],
                f"{r['vertices']:,}",
                r["backend"],
                r["imfs"],
                r["factorizations"],
                f"{r['emd_s']:.1f}",
                f"{r['spectra_s']:.1f}",
                f"{r['total_s']:.1f}",
                f"{ratio:.2f}x",
                f"{r['peak_mb']:,.0f}",
                target,
            ]
        )
    lines += [
        "## Whole HHT from the file",
        "",
        table(
            [
                "model",
                "#V",
                "backend",
                "#IMFs",
                "factorizations",
                "EMD s",
                "spectra s",
                "total s",
                "/ PARDISO",
                "peak MB",
                "target",
            ],
            rows,
        ),
    ]
    lines += [
        "",
        "## Fitted costs (hht3d.linalg.estimate.COSTS)",
        "",
        "```",
        json.dumps(record["costs"], indent=2),
        "```",
        "",
    ]
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--models", nargs="+", default=list(MODELS))
    parser.add_argument("--skip-factorizations", action="store_true")
    parser.add_argument("--timeout", type=float, default=1800.0, help="seconds per whole-HHT subprocess")
    parser.add_argument("--worker", default=None, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker:
        worker(args.worker)
        return 0
    from hht3d import linalg

    models = [m for m in args.models if model_path(m) is not None]
    record = {"machine": machine(), "factorizations": [], "whole": []}
    for name in models:
        if not args.skip_factorizations:
            record["factorizations"] += factorization_part(name)
        record["whole"] += whole_part(name, linalg.available_backends(), args.timeout)
    record["costs"] = fit_costs(record["whole"])
    print(json.dumps(record["costs"], indent=2))
    for path in write_results("backends", record, markdown(record)):
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
