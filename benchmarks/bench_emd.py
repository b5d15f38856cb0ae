"""EMD benchmark over the public models in ../shared/data (not a test).

For each model (one subprocess per model, so peak memory is the model's own):
load and clean, take the mean-curvature signal (Eq. 24), run
:func:`hht3d.decomposition.decompose.emd` with its defaults and record #vertices, #IMFs, sifts,
factorizations, seconds and peak resident memory.  Then replay the first
IMF's sifts and solve each of their envelopes three ways:

* ``ours``: the default backend with the fixed pattern and one symbolic
  analysis (its cost is included);
* ``superlu-pattern``: the same formulation with SciPy's SuperLU;
* ``baseline``: from scratch with ``scipy.sparse.linalg.spsolve`` on the
  eliminated system ``Q_FF g_F = −Q_FC f_C`` (submatrix extraction included).

Results go to ``benchmarks/results/emd.json`` and ``emd.md``, with the
paper's Table 1 EMD column for comparison.

``pypardiso`` searches ``sys.prefix`` recursively for ``mkl_rt`` every time a
solver is created unless ``PYPARDISO_MKL_RT`` names it; the benchmark looks
it up once, passes it to the workers and reports the lookup time apart.

Usage::

    python -m benchmarks.bench_emd [--models NAME ...] [--with-igea]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

import numpy as np

from benchmarks.common import (
    MESHES,
    PAPER_EMD,
    PAPER_IMFS,
    PAPER_VERTICES,
    fixed,
    machine_meta,
    mkl_environment,
    model_or_skip,
    model_path,
    paper_columns,
    paper_interpolated,
    peak_rss_mb,
    table,
    worker_json,
    write_results,
)

LARGE = ["igea"]
#: Paper Table 1, EMD column: (vertices, IMFs, seconds), MATLAB 2014 on a 4-core i7.
PAPER = paper_columns(PAPER_VERTICES, PAPER_IMFS, PAPER_EMD)


def _replay_first_imf(surface, signal, backend: str) -> dict:
    """Time every envelope of the first IMF's sifts: ours, SuperLU pattern, baseline."""
    import scipy.sparse.linalg as spla

    from hht3d import linalg
    from hht3d.decomposition import EMDOptions, EnvelopeSolver, extrema_spacing
    from hht3d.decomposition.sifting import Sifter

    options = EMDOptions(envelope="biharmonic")
    sifter = Sifter(surface, options, backend)
    superlu = EnvelopeSolver(surface, "superlu")
    energies = sifter.solver.energies
    q = energies.matrix(energies.data(0.0, 1.0))
    t0 = time.perf_counter()
    linalg.SymbolicFactorization(q, backend)  # what the first envelope of `ours` analyses once
    times = {"symbolic": time.perf_counter() - t0, "ours": 0.0, "superlu_pattern": 0.0, "baseline": 0.0}
    q = q.tocsc()
    worst = 0.0
    envelopes = 0
    h = signal

    def energy(f):
        return float(np.dot(sifter.mass * f, f))

    while True:
        is_max, is_min, passive = sifter.extrema(h)
        if min(is_max.sum(), is_min.sum()) < 2:
            break
        means = []
        for extrema in (is_max, is_min):
            constrained = extrema | passive
            spacing = extrema_spacing(surface, extrema.sum())
            t0 = time.perf_counter()
            g = sifter.solver.solve(h, constrained, 0.0, spacing)
            t1 = time.perf_counter()
            superlu.solve(h, constrained, 0.0, spacing)
            t2 = time.perf_counter()
            free = ~constrained
            q_free = q[free]
            reference = spla.spsolve(q_free[:, free].tocsc(), -(q_free[:, constrained] @ h[constrained]))
            t3 = time.perf_counter()
            times["ours"] += t1 - t0
            times["superlu_pattern"] += t2 - t1
            times["baseline"] += t3 - t2
            worst = max(worst, float(np.max(np.abs(g[free] - reference)) / np.max(np.abs(reference))))
            envelopes += 1
            means.append(g)
        mean = 0.5 * (means[0] + means[1])
        sd = energy(mean) / energy(h)
        h = h - mean
        if sd < options.sd_threshold:
            break
    return {
        "envelopes": envelopes,
        "seconds": times,
        "max_relative_difference": worst,
        "speedup_with_symbolic": times["baseline"] / (times["ours"] + times["symbolic"]),
        "speedup_per_envelope": times["baseline"] / times["ours"],
        "baseline_seconds_per_envelope": times["baseline"] / envelopes,
    }


def run_model(name: str) -> dict:
    """Benchmark one model in this process (called in a fresh subprocess)."""
    import hht3d
    from hht3d import linalg
    from hht3d.decomposition import emd
    from hht3d.geometry.signals import mean_curvature

    t0 = time.perf_counter()
    surface = hht3d.load(model_path(name))
    signal = mean_curvature(surface)
    load_seconds = time.perf_counter() - t0
    rss_before = peak_rss_mb()
    result = emd(surface, signal)
    info = result.info
    record = {
        "model": name,
        "vertices": surface.n_vertices,
        "imfs": info["n_imfs"],
        "sifts": info["sifts"],
        "factorizations": info["factorizations"],
        "seconds": info["seconds"],
        "seconds_per_imf": info["seconds"] / max(info["n_imfs"], 1),
        "stop_reason": info["stop_reason"],
        "max_constraint_error": info["max_constraint_error"],
        "sum_error": float(np.max(np.abs(result.imfs.sum(0) + result.residue - signal)) / np.max(np.abs(signal))),
        "per_imf": info["imfs"],
        "backend": info["backend"],
        "load_and_operators_seconds": load_seconds,
        "peak_rss_mb_before_emd": rss_before,
        "peak_rss_mb": peak_rss_mb(),
    }
    replay = _replay_first_imf(surface, signal, linalg.default_backend())
    record["first_imf_replay"] = replay
    ours_per_envelope = replay["seconds"]["ours"] / replay["envelopes"]
    record["baseline_projected_seconds"] = (
        info["seconds"]
        - replay["seconds"]["symbolic"]
        + (replay["baseline_seconds_per_envelope"] - ours_per_envelope) * info["factorizations"]
    )
    return record


def markdown(records: list[dict], meta: dict) -> str:
    lines = [
        "# EMD benchmark (mean-curvature signal, default options)",
        "",
        f"Machine: {meta['machine']}; {meta['cpus']} CPUs; 1-minute load average "
        f"{meta['load_average_1min'][0]:.1f} before and {meta['load_average_1min'][1]:.1f} after the run "
        "(other jobs share the machine, so timings are noisy); "
        f"backend `{meta['backend']}`; Python {meta['python']}.  "
        "Generated by `python -m benchmarks.bench_emd`.",
        "",
        "EMD seconds: `emd()` wall time with the surface operators already built, including "
        "building `Q = L M^-1 L` and the one symbolic analysis.  Not included: pypardiso's "
        f"search for the MKL library ({fixed(meta['pypardiso_mkl_lookup_seconds'])} s per solver "
        "unless `PYPARDISO_MKL_RT` is set; set here once for all workers).",
        "",
    ]
    v, k, _ = np.array(PAPER).T
    rows = []
    for r in records:
        paper = paper_interpolated(r["vertices"], PAPER_EMD)
        paper_imfs = float(np.interp(np.log(r["vertices"]), np.log(v), k))
        rows.append(
            [
                r["model"],
                f"{r['vertices']:,}",
                r["imfs"],
                r["sifts"],
                r["factorizations"],
                f"{r['seconds']:.2f}",
                f"{r['seconds_per_imf']:.2f}",
                f"{r['peak_rss_mb']:.0f}",
                f"{paper:.1f}",
                f"{paper / paper_imfs:.2f}",
            ]
        )
    lines += [
        table(
            [
                "model",
                "#V",
                "#IMFs",
                "sifts",
                "factorizations",
                "EMD s",
                "s/IMF",
                "peak RSS MB",
                "paper s at this #V",
                "paper s/IMF",
            ],
            rows,
        ),
        "",
        "First IMF replayed: every envelope of its sifts solved by our fixed-pattern "
        "solver (symbolic analysis timed apart), by the same formulation on SciPy SuperLU, "
        "and from scratch with `scipy.sparse.linalg.spsolve` on the eliminated system "
        "(baseline).",
        "",
        table(
            [
                "model",
                "envelopes",
                "symbolic s",
                "ours s",
                "SuperLU-pattern s",
                "baseline s",
                "speedup incl. symbolic",
                "speedup per envelope",
                "max rel. diff",
                "whole EMD: ours s",
                "whole EMD: baseline s (projected)",
            ],
            [
                [
                    r["model"],
                    p["envelopes"],
                    f"{t['symbolic']:.2f}",
                    f"{t['ours']:.2f}",
                    f"{t['superlu_pattern']:.2f}",
                    f"{t['baseline']:.2f}",
                    f"{p['speedup_with_symbolic']:.1f}x",
                    f"{p['speedup_per_envelope']:.1f}x",
                    f"{p['max_relative_difference']:.1e}",
                    f"{r['seconds']:.1f}",
                    f"{r['baseline_projected_seconds']:.1f}",
                ]
                for r in records
                for p in [r["first_imf_replay"]]
                for t in [p["seconds"]]
            ],
        ),
    ]
    lines += [
        "",
        "Projected baseline: the EMD time with each of its envelopes costing the replay's "
        "mean baseline envelope instead of ours (and no symbolic analysis).",
    ]
    lines += [
        "",
        "Paper columns: Table 1 EMD time (and IMF count) interpolated log-log in the "
        "vertex count, clamped outside 4,098–100,003 vertices.",
        "",
        "Paper Table 1 (EMD column, MATLAB, 4-core i7): "
        + "; ".join(f"{a:,} V / {b} IMFs: {c} s" for a, b, c in PAPER)
        + ".",
    ]
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--models", nargs="*", default=None, help="model names (default: the ladder)")
    parser.add_argument("--with-igea", action="store_true", help="also run igea (134k vertices)")
    parser.add_argument("--worker", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker:
        json.dump(run_model(args.worker), sys.stdout)
        return 0
    env, lookup = mkl_environment()
    load_before = os.getloadavg()[0]
    names = args.models or MESHES + (LARGE if args.with_igea else [])
    records = []
    for name in names:
        if model_or_skip(name) is None:
            continue
        records.append(worker_json(__file__, ["--worker", name], env=env))
        r = records[-1]
        print(
            f"{name}: {r['vertices']} V, {r['imfs']} IMFs, {r['factorizations']} factorizations, "
            f"{r['seconds']:.2f} s, replay speedup {r['first_imf_replay']['speedup_per_envelope']:.1f}x",
            file=sys.stderr,
        )
    meta = machine_meta(
        load_average_1min=[load_before, os.getloadavg()[0]], paper_table1_emd=PAPER, pypardiso_mkl_lookup_seconds=lookup
    )
    write_results("emd", {"meta": meta, "models": records}, markdown(records, meta), indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
