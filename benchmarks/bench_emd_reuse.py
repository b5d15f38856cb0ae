"""What reusing the previous sift's factor would gain in EMD (not a test; input for issue 12).

EMD factorizes one envelope system per envelope (two per sift).  Between sifts
of one IMF the extrema, hence the constrained vertices, change little, so the
factor of the previous upper (lower) envelope is a near-exact preconditioner
for the next one: the two matrices differ in the rows and columns of the
vertices whose constraint status changed, a low-rank change, and conjugate
gradients converge in a few iterations.

This script replays the first ``--imfs`` IMFs of the mean-curvature signal
with EMD's default rules (strict 1-ring extrema, biharmonic envelopes, SD 0.2)
and the formulation of :mod:`hht3d.decomposition.decompose` (one pattern, constrained rows
replaced by their diagonal), using only public API (:func:`hht3d.decomposition.envelope_operator`,
:func:`hht3d.decomposition.local_extrema`, :class:`hht3d.linalg.backends.SymbolicFactorization`).
Every envelope is solved two ways and timed:

``refactor``  what EMD does today: one numeric factorization and one solve;
``lagged``    keep the last factor of the same envelope kind (upper / lower; two
              analyses); run preconditioned CG (relative residual ``--rtol``,
              at most ``--max-cg`` iterations) and refactorize only when the
              constraint set changed by more than ``--refactor-above`` of its
              size or CG did not converge.

The sifting itself advances with the ``refactor`` envelopes, so both see the
same systems; the table gives the iterations, refactorizations, seconds and
the largest relative difference between the two envelopes.

Usage::

    python -m benchmarks.bench_emd_reuse [--models nefertiti igea] [--imfs 3] [--backend NAME]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

import numpy as np

from benchmarks.common import machine, mkl_environment, model_path, table, worker_json, write_results


def envelope_system(q, rows, diagonal, f, constrained):
    """The envelope matrix on Q's pattern and its right-hand side (the hht3d.decomposition.decompose notes)."""
    import scipy.sparse as sp

    free = ~constrained
    data = q.data * (free[rows] & free[q.indices])
    scale = q.data[diagonal]
    data[diagonal[constrained]] = scale[constrained]
    rhs = -(q @ np.where(constrained, f, 0.0))
    rhs[constrained] = scale[constrained] * f[constrained]
    return sp.csr_matrix((data, q.indices, q.indptr), shape=q.shape), rhs


def replay(name: str, imfs: int, backend: str | None, rtol: float, max_cg: int, refactor_above: float) -> dict:
    import scipy.sparse.linalg as spla

    import hht3d
    from hht3d import linalg
    from hht3d.decomposition import envelope_operator, local_extrema
    from hht3d.geometry.signals import mean_curvature

    surface = hht3d.load(model_path(name))
    mass = surface.mass_diagonal
    n = surface.n_vertices
    q = envelope_operator(surface, envelope="biharmonic")  # Q = L M⁻¹ L, which needs no spacing
    rows = np.repeat(np.arange(n), np.diff(q.indptr))
    diagonal = np.flatnonzero(q.indices == rows)
    backend = backend or linalg.default_backend()
    start = time.perf_counter()
    direct = linalg.SymbolicFactorization(q, backend)
    analysis = time.perf_counter() - start
    start = time.perf_counter()
    lagged = {kind: linalg.SymbolicFactorization(q, backend) for kind in ("upper", "lower")}
    lagged_analysis = time.perf_counter() - start
    current = {"upper": None, "lower": None}  # (factor, constraint mask)
    log = []
    residue = mean_curvature(surface)
    for imf in range(imfs):
        h = residue
        for sift in range(50):
            maxima, minima = local_extrema(surface, h)
            if min(len(maxima), len(minima)) < 2:
                break
            envelopes = []
            for kind, where in (("upper", maxima), ("lower", minima)):
                constrained = np.zeros(n, dtype=bool)
                constrained[where] = True
                a, rhs = envelope_system(q, rows, diagonal, h, constrained)
                t0 = time.perf_counter()
                g = direct.factorize(a).solve(rhs)
                t_direct = time.perf_counter() - t0
                t0 = time.perf_counter()
                previous = current[kind]
                changed = (
                    np.inf if previous is None else np.count_nonzero(previous[1] != constrained) / constrained.sum()
                )
                iterations, converged = 0, False
                if changed <= refactor_above:
                    factor = previous[0]
                    counter = []
                    op = spla.LinearOperator(a.shape, matvec=factor.solve, dtype=float)
                    x, info = spla.cg(
                        a,
                        rhs,
                        x0=factor.solve(rhs),
                        rtol=rtol,
                        maxiter=max_cg,
                        M=op,
                        callback=lambda _: counter.append(1),
                    )
                    iterations, converged = len(counter), info == 0
                if not converged:
                    factor = lagged[kind].factorize(a)
                    current[kind] = (factor, constrained)
                    x = factor.solve(rhs)
                t_lagged = time.perf_counter() - t0
                log.append(
                    {
                        "imf": imf,
                        "sift": sift,
                        "kind": kind,
                        "constrained": int(constrained.sum()),
                        "changed_fraction": float(changed),
                        "cg_iterations": iterations,
                        "refactorized": not converged,
                        "direct_s": t_direct,
                        "lagged_s": t_lagged,
                        "difference": float(np.max(np.abs(x - g)) / np.max(np.abs(g))),
                    }
                )
                envelopes.append(g)
            mean = 0.5 * (envelopes[0] + envelopes[1])
            sd = np.dot(mass * mean, mean) / np.dot(mass * h, h)
            h = h - mean
            if sd < 0.2:
                break
        residue = residue - h
    direct_s = sum(e["direct_s"] for e in log)
    lagged_s = sum(e["lagged_s"] for e in log)
    return {
        "model": name,
        "vertices": n,
        "backend": backend,
        "imfs": imfs,
        "envelopes": len(log),
        "analysis_s": analysis,
        "lagged_analysis_s": lagged_analysis,
        "direct_s": direct_s,
        "lagged_s": lagged_s,
        "refactorizations": sum(e["refactorized"] for e in log),
        "cg_iterations": sum(e["cg_iterations"] for e in log),
        "max_difference": max(e["difference"] for e in log),
        "speedup": direct_s / lagged_s,
        "speedup_with_analysis": (direct_s + analysis) / (lagged_s + lagged_analysis),
        "log": log,
        "load_average_1min": os.getloadavg()[0],
    }


def markdown(records: list[dict], meta: dict, options: dict) -> str:
    rows = [
        [
            r["model"],
            f"{r['vertices']:,}",
            r["backend"],
            r["imfs"],
            r["envelopes"],
            r["refactorizations"],
            r["cg_iterations"],
            f"{r['direct_s']:.2f}",
            f"{r['lagged_s']:.2f}",
            f"{r['speedup']:.2f}x",
            f"{r['speedup_with_analysis']:.2f}x",
            f"{r['max_difference']:.1e}",
            f"{r['load_average_1min']:.1f}",
        ]
        for r in records
    ]
    lines = [
        "# EMD: reusing the previous sift's factor as a preconditioner",
        "",
        (
            f"Machine: {meta['platform']}; {meta['cpus']} CPUs shared with other jobs.  Generated by "
            "`python -m benchmarks.bench_emd_reuse`; the method is in its docstring.  Options: "
            + ", ".join(f"{k} {v}" for k, v in options.items())
            + "."
        ),
        "",
        table(
            [
                "model",
                "#V",
                "backend",
                "IMFs replayed",
                "envelopes",
                "refactorizations (lagged)",
                "CG iterations",
                "refactor s",
                "lagged s",
                "speed-up",
                "speed-up incl. analyses",
                "max rel. difference",
                "load avg",
            ],
            rows,
        ),
        "",
        (
            "*refactor s*: numeric factorization + solve of every envelope (today's EMD); *lagged s*: CG "
            "preconditioned by the last factor of the same envelope kind, refactorizing when the "
            "constraint set changed too much or CG stalls; *incl. analyses* adds one symbolic analysis "
            "to today's and two (upper and lower factors alive at once) to the lagged scheme."
        ),
        "",
    ]
    for r in records:
        per = [
            [
                e["imf"],
                e["sift"],
                e["kind"],
                e["constrained"],
                f"{e['changed_fraction']:.3f}",
                e["cg_iterations"],
                "yes" if e["refactorized"] else "",
                f"{e['direct_s']:.3f}",
                f"{e['lagged_s']:.3f}",
                f"{e['difference']:.1e}",
            ]
            for e in r["log"]
        ]
        lines += [
            f"## {r['model']}: every envelope",
            "",
            table(
                [
                    "IMF",
                    "sift",
                    "envelope",
                    "#constrained",
                    "changed fraction",
                    "CG iterations",
                    "refactorized",
                    "refactor s",
                    "lagged s",
                    "rel. difference",
                ],
                per,
            ),
            "",
        ]
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--models", nargs="+", default=["nefertiti", "igea"])
    parser.add_argument("--imfs", type=int, default=3, help="IMFs to replay per model")
    parser.add_argument("--backend", default=None, help="sparse solver (default: the fastest installed)")
    parser.add_argument("--rtol", type=float, default=1e-10, help="CG relative residual")
    parser.add_argument("--max-cg", type=int, default=20, help="CG iterations before refactorizing")
    parser.add_argument(
        "--refactor-above",
        type=float,
        default=0.2,
        help="refactorize without trying CG when this fraction of the constraints changed",
    )
    parser.add_argument("--worker", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    options = {"imfs": args.imfs, "rtol": args.rtol, "max_cg": args.max_cg, "refactor_above": args.refactor_above}
    if args.worker:
        print(json.dumps(replay(args.worker, args.imfs, args.backend, args.rtol, args.max_cg, args.refactor_above)))
        return 0
    env, _ = mkl_environment()
    records = []
    for name in [m for m in args.models if model_path(m) is not None]:
        command = [
            "--worker",
            name,
            "--imfs",
            str(args.imfs),
            "--rtol",
            str(args.rtol),
            "--max-cg",
            str(args.max_cg),
            "--refactor-above",
            str(args.refactor_above),
        ]
        records.append(worker_json(__file__, command + (["--backend", args.backend] if args.backend else []), env=env))
        r = records[-1]
        print(
            f"{name}: refactor {r['direct_s']:.1f} s, lagged {r['lagged_s']:.1f} s ({r['speedup']:.2f}x), "
            f"{r['refactorizations']} of {r['envelopes']} refactorized",
            file=sys.stderr,
        )
    meta = machine()
    write_results(
        "emd_reuse", {"machine": meta, "options": options, "models": records}, markdown(records, meta, options)
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
