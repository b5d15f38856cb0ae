"""Direct against iterative solves on hht3d's second-order systems (issue 39), in one run.

Two parts:

* **preconditioners** — on one model: PCG iterations and seconds with a Jacobi and with a pyamg
  smoothed-aggregation (SA) preconditioner, beside one SuperLU factorization and solve, to a
  relative residual of 1e-10, on the membrane resolvent ``M + tL`` at the ``t = 1/ω_c²`` of each
  IMF of a real ``emd(method="filtering", filter="membrane")`` run, on ``L + σM`` at every third
  shift of the Riesz quadrature (``tol=1e-8``) and the spectral bounds' tiny shift, and on the
  bilaplacian filter ``M + t²LM̃⁻¹L`` at the first and last ``t`` (what ``cg`` refuses).
* **runs** — per model and backend (``pardiso``, ``superlu``, ``cg``), each in its own
  subprocess: the membrane filtering EMD of the mean curvature and the Riesz transform of its
  IMFs, seconds of each, peak memory (``VmHWM``), the ratio to PARDISO's in the same run, and the
  largest difference of the IMFs and Riesz fields from PARDISO's (relative to the largest value).

Models: ``nefertiti`` (50k), ``igea`` (134k) and the generated sizes of
:data:`benchmarks.meshes.SCALING` (``500k``, ``1m``). Run:
``python -m benchmarks.bench_iterative [--models nefertiti igea 500k] [--parts preconditioners runs]``.
Writes ``results/iterative.json`` and ``results/iterative.md``.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time

import numpy as np

from benchmarks.common import (
    SCRATCH,
    log,
    machine,
    mkl_environment,
    model_path,
    previous_results,
    run_worker,
    short,
    status_mb,
    table,
    worker_answer,
    write_results,
)
from benchmarks.meshes import SCALING

BACKENDS = ("pardiso", "superlu", "cg")
#: A case still running after this many seconds is stopped and reported as such.
CASE_TIMEOUT = 1800


def mesh_path(name: str):
    """The public model, or the generated mesh of :data:`SCALING` (made on first use)."""
    if name not in SCALING:
        return model_path(name)
    from benchmarks.meshes import generate

    path = SCRATCH / f"scaling_{name}.ply"
    if not path.is_file():
        log(f"generating {name}: {generate(name, path)}")
    return path


def _pcg(a, b, precondition, rtol=1e-10, cap=3000):
    """Iterations and seconds of PCG to ``rtol`` (``-1`` iterations: not converged within ``cap``)."""
    start = time.perf_counter()
    x, r = np.zeros_like(b), b.copy()
    z = precondition(r)
    p, rz, bound = z.copy(), r @ z, rtol * np.linalg.norm(b)
    for k in range(1, cap + 1):
        q = a @ p
        step = rz / (p @ q)
        x += step * p
        r -= step * q
        if np.linalg.norm(r) <= bound:
            return k, time.perf_counter() - start
        z = precondition(r)
        rz, previous = r @ z, rz
        p = z + (rz / previous) * p
    return -1, time.perf_counter() - start


def preconditioners(name: str) -> list[dict]:
    """The rows of the preconditioners part on one model (module notes)."""
    import pyamg
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    import hht3d
    from hht3d.decomposition import emd
    from hht3d.geometry.signals import mean_curvature
    from hht3d.linalg.superlu import SUPERLU_OPTIONS
    from hht3d.spectral import quadrature_plan

    surface = hht3d.load(mesh_path(name))
    f = mean_curvature(surface)
    log(f"{name}: membrane filtering EMD for its cuts")
    lap, mass = surface.stiffness.tocsr(), sp.diags(surface.mass_diagonal)
    cuts = [i["cut_frequency"] for i in emd(surface, f, method="filtering", filter="membrane").info["imfs"]]
    plan = quadrature_plan(surface, 1e-8)
    systems = [("membrane", f"t={1 / c**2:.3g}", mass + lap / c**2) for c in cuts]
    systems += [("L + σM", f"σ={s:.3g}", lap + s * mass) for s in plan.sigmas[::3]]
    systems += [("L + σM", f"σ={1e-9 * plan.bounds[1]:.3g} (bounds)", lap + 1e-9 * plan.bounds[1] * mass)]
    smoothing = lap @ sp.diags(1 / surface.mass_diagonal) @ lap
    systems += [("bilaplacian", f"t={1 / c**2:.3g}", mass + smoothing / c**4) for c in (cuts[0], cuts[-1])]
    b = surface.mass_diagonal * f
    rows = []
    for kind, parameter, a in systems:
        a = a.tocsr()
        start = time.perf_counter()
        spla.splu(a.tocsc(), permc_spec="MMD_AT_PLUS_A", **SUPERLU_OPTIONS).solve(b)
        direct = time.perf_counter() - start
        inverse = 1.0 / a.diagonal()
        jacobi = _pcg(a, b, lambda r, d=inverse: d * r)
        start = time.perf_counter()
        sa = pyamg.smoothed_aggregation_solver(a).aspreconditioner()
        setup = time.perf_counter() - start
        aggregation = _pcg(a, b, lambda r, m=sa: m @ r)
        rows.append(
            {"model": name, "n": a.shape[0], "system": kind, "parameter": parameter, "superlu_s": direct}
            | {"jacobi_iterations": jacobi[0], "jacobi_s": jacobi[1], "sa_setup_s": setup}
            | {"sa_iterations": aggregation[0], "sa_s": aggregation[1]}
        )
        log(f"{name} {kind} {parameter}: jacobi {jacobi[0]}, SA {aggregation[0]} iterations")
    return rows


def worker(name: str, backend: str) -> dict:
    """One model on one backend: membrane filtering EMD, then the Riesz transform of its IMFs."""
    import hht3d
    from hht3d.decomposition import emd
    from hht3d.geometry.signals import mean_curvature
    from hht3d.spectral import riesz

    surface = hht3d.load(mesh_path(name))
    f = mean_curvature(surface)
    start = time.perf_counter()
    result = emd(surface, f, method="filtering", filter="membrane", backend=backend)
    emd_s = time.perf_counter() - start
    start = time.perf_counter()
    fields = riesz(surface, result.imfs, backend=backend)
    riesz_s = time.perf_counter() - start
    np.savez(SCRATCH / f"iterative_{name}_{backend}.npz", imfs=result.imfs, riesz=fields, signal=f)
    return {"vertices": surface.n_vertices, "imfs": len(result.imfs), "emd_s": emd_s, "riesz_s": riesz_s}


def runs(names, backends) -> list[dict]:
    """The rows of the runs part: every model on every backend, in subprocesses (module notes)."""
    env, _ = mkl_environment()
    SCRATCH.mkdir(parents=True, exist_ok=True)
    rows = []
    for name in names:
        if mesh_path(name) is None:
            continue
        found = {}
        for backend in backends:
            log(f"{name} on {backend}")
            try:
                done = run_worker(__file__, ["--worker", name, backend], env=env, timeout=CASE_TIMEOUT)
            except subprocess.TimeoutExpired:
                found[backend] = {"stopped_s": CASE_TIMEOUT}
                continue
            if done.returncode != 0:
                raise RuntimeError(f"{name} on {backend} failed:\n{done.stderr[-3000:]}")
            found[backend] = worker_answer(done)
        base = found.get("pardiso", {})
        for backend, row in found.items():
            if "emd_s" in row and "emd_s" in base:
                row["total_ratio"] = (row["emd_s"] + row["riesz_s"]) / (base["emd_s"] + base["riesz_s"])
                row |= _differences(name, backend)
            rows.append({"model": name, "backend": backend, **row})
    return rows


def _differences(name: str, backend: str) -> dict:
    """The largest differences of ``backend``'s IMFs and Riesz fields from PARDISO's, relative to their largest."""
    mine, base = (np.load(SCRATCH / f"iterative_{name}_{b}.npz") for b in (backend, "pardiso"))
    if mine["imfs"].shape != base["imfs"].shape:
        return {"imfs_differ": f"{len(mine['imfs'])} IMFs, PARDISO {len(base['imfs'])}"}
    scale = np.abs(base["signal"]).max()
    return {
        "imf_difference": float(np.abs(mine["imfs"] - base["imfs"]).max() / scale),
        "riesz_difference": float(np.abs(mine["riesz"] - base["riesz"]).max() / np.abs(base["riesz"]).max()),
    }


def markdown(data: dict) -> str:
    """The page of ``results/iterative.json``."""
    meta = data["meta"]
    out = [
        "# Direct and iterative solves of the second-order systems",
        "",
        f"Machine: {meta['platform']}, {meta['cpus']} CPUs, load {meta['load_average']} at the start "
        f"({meta['date']}). Membrane filtering EMD and the Riesz transform; `cg` is PCG with pyamg's "
        "smoothed aggregation (hht3d.linalg.cg).",
        "",
    ]
    if data.get("preconditioners"):
        out += ["## Preconditioners (PCG to a relative residual of 1e-10; -1: not within 3,000)", ""]
        header = ["model", "system", "parameter", "SuperLU s", "Jacobi its", "Jacobi s", "SA setup s"]
        rows = [
            [r["model"], r["system"], r["parameter"], short(r["superlu_s"]), r["jacobi_iterations"]]
            + [short(r["jacobi_s"]), short(r["sa_setup_s"]), r["sa_iterations"], short(r["sa_s"])]
            for r in data["preconditioners"]
        ]
        out += [table(header + ["SA its", "SA s"], rows), ""]
    if data.get("runs"):
        out += ["## Whole runs (each in its own process)", ""]
        rows = [
            [r["model"], r.get("vertices", ""), r["backend"], short(r.get("emd_s")), short(r.get("riesz_s"))]
            + [short(r.get("total_ratio")), short(r.get("peak_mb"), 0), r.get("imfs", "")]
            + [short(r.get("imf_difference")), short(r.get("riesz_difference"))]
            if "emd_s" in r
            else [r["model"], "", r["backend"], f"stopped at {r['stopped_s']} s"] + [""] * 6
            for r in data["runs"]
        ]
        header = ["model", "vertices", "backend", "EMD s", "Riesz s", "× PARDISO", "peak MB", "IMFs"]
        out += [table(header + ["IMF diff", "Riesz diff"], rows), ""]
    return "\n".join(out)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--models", nargs="+", default=["nefertiti", "igea", "500k"])
    parser.add_argument("--backends", nargs="+", default=list(BACKENDS))
    parser.add_argument("--parts", nargs="+", default=["preconditioners", "runs"])
    parser.add_argument("--worker", nargs=2, default=None, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker:
        answer = worker(*args.worker)
        print(json.dumps(answer | {"peak_mb": status_mb("VmHWM")}))
        return 0
    data = previous_results("iterative")
    data["meta"] = machine() | {"date": time.strftime("%Y-%m-%d %H:%M")}
    if "preconditioners" in args.parts:
        data["preconditioners"] = preconditioners(args.models[0])
    if "runs" in args.parts:
        data["runs"] = runs(args.models, args.backends)
    data["meta"]["load_average_end"] = machine()["load_average"]
    for path in write_results("iterative", data, markdown(data)):
        print(path, file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
