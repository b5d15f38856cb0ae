"""End-to-end HHT benchmark against the paper's Table 1, and scaling to 1M vertices (not a test).

Every case runs in its own subprocess, so the peak resident memory (``ru_maxrss``
semantics: MKL/PARDISO allocations included) is that case's own.  A case is
the full transform of the mean-curvature signal, timed stage by stage:

``load``       ``hht3d.load(path)``: PLY reading and cleaning;
``operators``  stiffness ``L`` and lumped mass ``M``, vertex normals, adjacency and
               connected components, the least-squares gradient ``G``;
``signal``     :func:`hht3d.geometry.signals.mean_curvature` (Eq. 24);
``emd``        :func:`hht3d.decomposition.decompose.emd` as in the paper (``PAPER_OPTIONS``: sd 0.2,
               biharmonic envelopes, ``max_imfs`` 10 unless capped), including
               building ``Q = L M^-1 L`` and its one symbolic analysis;
``rt``         :func:`hht3d.spectral.monogenic_signal.monogenic` of all IMFs (Riesz transform by
               the exact elliptic quadrature at tol 1e-8, then amplitude, phase
               and frequency): spectral bounds (shift-invert Lanczos for
               lambda_1), one numeric factorization per shift with all IMFs as
               one multi-column solve, then the monogenic quantities.

``emd`` + ``rt`` is exactly what :func:`hht3d.transform.hht` runs; they are called
separately here to time and measure them apart.  *Total* = all five stages,
from the file to the spectra (the paper's total also exceeds its EMD + RT).

Instrumentation (benchmark only, no effect on the numerics): the PARDISO
phases of :mod:`hht3d.linalg` (analysis 11, numeric factorization 22, solve 33)
are timed and PARDISO's own memory report is read after phases 11 and 22
(``iparm`` 15-18: peak symbolic, permanent, factor + solve memory in KB, nnz
of the factor; peak = max(iparm15, iparm16 + iparm17)); ``spectral_bounds``,
``monogenic_from_potential`` and ``envelope_energies`` are wrapped by timers.
Per stage the peak RSS is measured by resetting the high-water mark at the
stage's start (``/proc/self/clear_refs``); the case's peak is the largest.  Wall and CPU
seconds (process time, all threads) are both recorded: the machine is shared,
and CPU seconds are the less load-sensitive of the two.

Scaling cases are generated from igea (134k vertices, the paper's Hygeia at
full resolution), one family so the signal content stays comparable:
Open3D quadric decimation to ``base`` vertices, then ``levels`` Loop
subdivisions (``4^levels`` times the vertices): 62.5k x 4 = 250k,
125k x 4 = 500k, 62.5k x 16 = 1M.  Written (float32 PLY, as the public
models) to ``benchmarks/results/scratch/`` (git-ignored) in a separate
subprocess, so generation neither counts in the times nor in the peak; then
loaded like any model.  Note that a subdivided mesh carries the geometric
detail of its base mesh only (its mean curvature is smoother than a scan of
that size would be), so the IMF count can differ from the ladder's.  With ``--kinds cloud`` each
size's vertices run as a point cloud (no faces: normals, the robust point-cloud Laplacian
and everything else are built from the points, in the case's time).

A part can be re-run alone: the records of cases not re-run are kept from the
previous ``hht.json``.

Usage::

    python -m benchmarks.bench_hht [--parts ladder scaling backends] [--models NAME ...]
        [--sizes 250k 500k 1m] [--scaling-max-imfs K] [--kinds mesh cloud] [--keep-meshes]

The stage recorder is in :mod:`benchmarks.hht_recorder`, the generated meshes in
:mod:`benchmarks.meshes`, the report in :mod:`benchmarks.hht_report`.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from benchmarks.common import (
    PAPER_TABLE1,
    SCRATCH,
    log,
    machine,
    mkl_environment,
    model_or_skip,
    model_path,
    previous_results,
    run_worker,
    status_mb,
    write_results,
)
from benchmarks.hht_recorder import STAGES, Recorder, nbytes, sparse_mb
from benchmarks.hht_report import TARGET_FACTOR, markdown
from benchmarks.meshes import DEFAULT_SIZES, SCALING, SCALING_SOURCE, cloud_of, generate
from hht3d.linalg import BACKEND_VARIABLE

LADDER = [
    "spot",
    "sphere_oct4098",
    "spacetime_face_neutral",
    "rocker_arm",
    "bunny_zipper",
    "nefertiti",
    "office_kinect_colored",
    "igea",
]
#: Models and backends of the backend comparison (superlu only with --with-superlu: minutes per model).
BACKEND_MODELS = ["nefertiti", "igea"]


# -- a case (worker side) ----------------------------------------------------------------------------


def run_case(name: str, path: Path, max_imfs: int | None, preset: str = "paper") -> dict:
    """The whole HHT of one mesh, stage by stage (runs in a fresh subprocess); ``preset`` names
    the EMD settings: ``"paper"`` (``PAPER_OPTIONS``), ``"defaults"``, ``"filtering"``
    (``FILTERING_OPTIONS`` at full resolution) or ``"filtering-levels"`` (the same on the hierarchy of
    :mod:`hht3d.decomposition.multiresolution`, each IMF's Riesz transform on its level)."""
    import hht3d
    from hht3d import linalg
    from hht3d.decomposition import EMD_DEFAULTS, FILTERING_OPTIONS, PAPER_OPTIONS, emd
    from hht3d.geometry.signals import mean_curvature
    from hht3d.spectral import monogenic_signal, multilevel, quadrature_nodes
    from hht3d.spectral.options import RIESZ_DEFAULTS

    rec = Recorder()
    rec.instrument()
    baseline_mb = status_mb("VmRSS")
    started = time.strftime("%Y-%m-%d %H:%M:%S")
    load_before = os.getloadavg()[0]
    with rec.stage("load"):
        surface = hht3d.load(path)
    levels = "always" if preset == "filtering-levels" else "never"
    with rec.stage("operators"):
        timings = {}
        builds = [
            ("laplacian_mass", lambda: surface.stiffness),
            ("normals", lambda: surface.normals),
            ("adjacency_components", lambda: surface.component_labels),
            ("gradient_lsq", lambda: surface.gradient("lsq")),
        ]
        # on levels the input's gradient serves only the Riesz vectors of its own IMFs: built there, as the
        # package does, so that it is not resident through the EMD
        for key, build in builds[:-1] if levels == "always" else builds:
            t0 = time.perf_counter()
            build()
            timings[key] = time.perf_counter() - t0
            rec.peaks[f"operators:{key}"] = rec.checkpoint()
    with rec.stage("signal"):
        signal = mean_curvature(surface)
    chosen = {"paper": PAPER_OPTIONS, "defaults": EMD_DEFAULTS, "filtering": FILTERING_OPTIONS}[preset.split("-")[0]]
    options = chosen.as_dict() | {"multiresolution": levels} | ({} if max_imfs is None else {"max_imfs": max_imfs})
    with rec.stage("emd"):
        decomposition = emd(surface, signal, **options)
    with rec.stage("rt"):
        if levels == "always":  # each IMF's Riesz vectors on its level and band (hht3d.spectral.multilevel)
            # through the modules: the recorder wraps riesz_part and monogenic_from_riesz there
            vectors = multilevel.riesz_vectors(surface, decomposition, RIESZ_DEFAULTS)  # as hht3d.hht
            mono = monogenic_signal.monogenic_from_riesz(surface, decomposition.imfs, vectors)
        else:
            mono = monogenic_signal.monogenic(surface, decomposition.imfs)
    info = decomposition.info
    m, mbar = surface.cache.get("riesz:bounds", (np.nan, np.nan))
    shifts = len(quadrature_nodes(m, mbar, 1e-8)[0]) if np.isfinite(m) else 0
    stages = rec.stages
    total = sum(stages[s]["seconds"] for s in STAGES)
    return {
        "case": name,
        "source": str(path),
        "vertices": surface.n_vertices,
        "faces": 0 if surface.faces is None else len(surface.faces),
        "components": surface.n_components,
        "backend": linalg.default_backend(),
        "emd_options": preset,
        "max_imfs": max_imfs if max_imfs is not None else 10,
        "imfs": info["n_imfs"],
        "sifts": info["sifts"],
        "factorizations": info["factorizations"],
        "stop_reason": info["stop_reason"],
        "shifts": shifts,
        "condition": mbar / m,
        "stages": stages,
        "operators_detail": timings,
        "timers": rec.timers,
        "solver": rec.solver,
        "substep_peak_mb": rec.peaks,
        "signal_mean": float(np.mean(signal)),
        "signal_relative_std": float(np.std(signal) / np.mean(np.abs(signal))),
        "cpu_seconds": {s: stages[s]["cpu_seconds"] for s in STAGES}
        | {"total": sum(stages[s]["cpu_seconds"] for s in STAGES)},
        "seconds": {s: stages[s]["seconds"] for s in STAGES}
        | {"total": total, "emd_rt": stages["emd"]["seconds"] + stages["rt"]["seconds"]},
        "peak_rss_mb": max(st["peak_mb"] for st in stages.values()),
        "baseline_rss_mb": baseline_mb,
        "peak_resets": rec.peak_resets,
        "memory_mb": {
            "L": sparse_mb(surface.stiffness),
            "G_lsq": sparse_mb(surface.gradient("lsq")),
            "Q": rec.energies_mb,
            "imfs": nbytes(decomposition.imfs),
            "monogenic_outputs": nbytes(mono.imfs, mono.riesz, mono.amplitude, mono.phase, mono.frequency),
            "jacobian_transient": 72 * info["n_imfs"] * surface.n_vertices / 2**20,
        },
        "sum_error": float(
            np.max(np.abs(decomposition.imfs.sum(0) + decomposition.residue - signal)) / np.max(np.abs(signal))
        ),
        "reconstruct_error": float(
            np.max(np.abs(mono.reconstruct() - decomposition.imfs.sum(0))) / np.max(np.abs(signal))
        )
        if info["n_imfs"]
        else 0.0,
        "started": started,
        "load_average_1min": [round(load_before, 2), round(os.getloadavg()[0], 2)],
    }


# -- driver ----------------------------------------------------------------------------------------


def _worker(args: list[str], env: dict, out: Path) -> dict:
    out.unlink(missing_ok=True)
    done = run_worker(
        __file__, ["--worker", *args, "--out", str(out)], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE
    )
    if done.returncode != 0 or not out.is_file():
        raise RuntimeError(f"worker {args} failed (exit {done.returncode}):\n{done.stderr[-3000:]}")
    record = json.loads(out.read_text())
    out.unlink()
    return record


def _store(results: dict, part: str, record: dict) -> None:
    """Put ``record`` in ``results[part]`` in place of the record of the same case (and backend, in the
    backends part: elsewhere a failed run's record, which has none, is replaced by its success too)."""
    results[part] = [
        r
        for r in results[part]
        if r["case"] != record["case"] or (part == "backends" and r.get("backend") != record.get("backend"))
    ]
    results[part].append(record)


def _case(results: dict, part: str, key: dict, args: list[str], env: dict, out: Path) -> dict | None:
    """Run one case (``key``: its ``case`` and ``backend``) in a worker and store its record, or the error."""
    try:
        r = _worker(["case", *args], env, out)
    except RuntimeError as exc:
        log(str(exc))
        _store(results, part, key | {"error": str(exc)[-2000:]})
        return None
    _store(results, part, r)
    return r


def _summary(r: dict) -> str:
    return (
        f"  {r['vertices']:,} V, {r['imfs']} IMFs, EMD {r['seconds']['emd']:.1f} s, RT "
        f"{r['seconds']['rt']:.1f} s, total {r['seconds']['total']:.1f} s, peak {r['peak_rss_mb']:.0f} MB"
    )


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--parts", nargs="+", choices=["ladder", "scaling", "backends"], default=["ladder", "scaling", "backends"]
    )
    parser.add_argument(
        "--models",
        nargs="+",
        default=None,
        help=f"models of the ladder (default: {' '.join(LADDER)}) and of the backends part "
        f"(default: {' '.join(BACKEND_MODELS)})",
    )
    parser.add_argument("--sizes", nargs="+", choices=list(SCALING), default=DEFAULT_SIZES)
    parser.add_argument(
        "--backend", default=None, help="sparse solver of the ladder and scaling cases (default: the fastest installed)"
    )
    parser.add_argument("--with-superlu", action="store_true", help="add SciPy SuperLU to the backends part")
    parser.add_argument(
        "--emd",
        choices=["paper", "defaults", "filtering", "filtering-levels"],
        default="paper",
        help="EMD settings: the paper's (PAPER_OPTIONS, as Table 1), hht3d's defaults or iterative filtering "
        "(FILTERING_OPTIONS), at full resolution or on levels; cases run with the others are named "
        "'<case> (defaults)', '<case> (filtering)' or '<case> (filtering-levels)'",
    )
    parser.add_argument("--max-imfs", type=int, default=None, help="cap on IMFs for the ladder (default: emd's 10)")
    parser.add_argument(
        "--scaling-max-imfs", type=int, default=None, help="cap on IMFs for the scaling cases (default: emd's 10)"
    )
    parser.add_argument(
        "--kinds",
        nargs="+",
        choices=["mesh", "cloud"],
        default=["mesh"],
        help="scaling cases: the generated meshes, and/or their vertices as point clouds (normals and Laplacian "
        "from the points; default: mesh)",
    )
    parser.add_argument("--keep-meshes", action="store_true", help="keep the generated meshes in results/scratch")
    parser.add_argument(
        "--drop", nargs="+", default=[], metavar="CASE", help="remove these cases' rows of earlier runs"
    )
    parser.add_argument("--blas-threads", type=int, default=1, help="OpenBLAS threads of the workers (ARPACK)")
    parser.add_argument("--worker", nargs="+", help=argparse.SUPPRESS)
    parser.add_argument("--out", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)

    if args.worker:
        kind, *rest = args.worker
        if kind == "generate":
            record = generate(rest[0], Path(rest[1]))
        else:
            name, path, cap, preset = rest
            record = run_case(name, Path(path), None if cap == "none" else int(cap), preset)
        Path(args.out).write_text(json.dumps(record, default=float))
        return 0

    env, lookup = mkl_environment()
    env["OPENBLAS_NUM_THREADS"] = str(args.blas_threads)
    if args.backend:
        env[BACKEND_VARIABLE] = args.backend
    SCRATCH.mkdir(parents=True, exist_ok=True)
    out = SCRATCH / f"hht_worker_{os.getpid()}.json"
    results = previous_results("hht")
    results.setdefault("ladder", [])
    results.setdefault("scaling", [])
    results.setdefault("generated", {})
    results.setdefault("backends", [])
    for part in ("ladder", "scaling", "backends"):
        results[part] = [r for r in results[part] if r.get("case") not in args.drop]

    suffix = "" if args.emd == "paper" else f" ({args.emd})"

    def run(part: str, case: str, path: Path, max_imfs: int | None) -> None:
        log(f"{part} {case} ...")
        r = _case(results, part, {"case": case}, [case, str(path), str(max_imfs or "none"), args.emd], env, out)
        if r is not None:
            log(_summary(r))

    if "ladder" in args.parts:
        for name in args.models or LADDER:
            path = model_or_skip(name)
            if path is None:
                continue
            run("ladder", name + suffix, path, args.max_imfs)
    if "scaling" in args.parts:
        if model_path(SCALING_SOURCE) is None:
            log(f"skip scaling: {SCALING_SOURCE}.ply not present")
        for size in args.sizes if model_path(SCALING_SOURCE) is not None else []:
            name = f"{SCALING_SOURCE}_{size}"
            mesh = SCRATCH / f"{name}.ply"
            if not mesh.is_file() or size not in results["generated"]:
                log(f"generate {name} ...")
                results["generated"][size] = _worker(["generate", size, str(mesh)], env, out)
            cases = [(name, mesh)] if "mesh" in args.kinds else []
            if "cloud" in args.kinds:
                cloud = SCRATCH / f"{name}_cloud.ply"
                if not cloud.is_file():
                    cloud_of(mesh, cloud)
                cases.append((f"{name} cloud", cloud))
            try:
                for case, path in cases:
                    run("scaling", case + suffix, path, args.scaling_max_imfs)
            finally:
                if not args.keep_meshes:
                    for _, path in cases:
                        path.unlink(missing_ok=True)
    if "backends" in args.parts:
        from hht3d.linalg import available_backends

        backends = [b for b in available_backends() if b != "superlu" or args.with_superlu]
        for name in [m for m in args.models or BACKEND_MODELS if model_path(m) is not None]:
            for backend in backends:  # interleaved per model: every ratio comes from one run
                log(f"backends {name} {backend} ...")
                r = _case(
                    results,
                    "backends",
                    {"case": name, "backend": backend},
                    [name, str(model_path(name)), "none", "paper"],
                    env | {BACKEND_VARIABLE: backend},
                    out,
                )
                if r is not None:
                    log(
                        f"  EMD {r['seconds']['emd']:.1f} s, RT {r['seconds']['rt']:.1f} s, total "
                        f"{r['seconds']['total']:.1f} s, peak {r['peak_rss_mb']:.0f} MB"
                    )
    order = {n: i for i, n in enumerate(LADDER)}
    results["ladder"].sort(key=lambda r: order.get(r["case"], len(order)))
    results["scaling"].sort(key=lambda r: r.get("vertices", 0))
    results["meta"] = {
        "machine": machine(),
        "openblas_threads": args.blas_threads,
        "pypardiso_mkl_lookup_seconds": lookup,
        "paper_table1": PAPER_TABLE1,
        "target": f"total <= paper total / {TARGET_FACTOR}",
        "written": time.strftime("%Y-%m-%d %H:%M:%S"),
    }
    for path in write_results("hht", results, markdown(results)):
        log(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
