"""Riesz transform / monogenic benchmark over the public models in ../shared/data (not a test).

Part 1 — the paper's Fig. 2(h).  The 4,098-vertex octahedron: the vertices
of ``sphere_oct4098.ply`` (a subdivided octahedron projected on the unit
sphere) mapped back to the octahedron ``|x|+|y|+|z| = 1``, with the paper's
centroid-distance signal.  (On the projected sphere that signal is constant
up to float32 rounding, std 1.6e-8, so the flat-faced model is the one the
figure can mean.)  ``spectral`` with 50, 150, 300, 600 and 1500 eigenpairs
(Eq. 18) and ``quadrature`` are compared with ``dense`` (Eq. 16).

Part 2 — the model ladder.  Per model, 15 IMF-like signals: band-passes of
the mean curvature ``H`` (Eq. 24) between 16 heat-smoothing scales
``u_t = (M + tL)⁻¹ M H``, ``t`` geometric from the squared mean edge
length to ``(diagonal/4)²`` (finest band first: ``H − u_{t_1}``).  Riesz
transform + monogenic quantities of all 15 at once with ``quadrature``
(default tol 1e-8) and ``spectral`` (300 eigenpairs), each in its own
subprocess for its own peak memory; errors against ``quadrature`` at
tol 1e-12.

Timed: :func:`hht3d.spectral.spectral_bounds` (quadrature) or
:func:`hht3d.spectral.riesz_transform.smallest_eigenpairs` (spectral), then
:func:`hht3d.spectral.monogenic_signal.monogenic`.  Not timed: loading, ``L``, ``M`` and the
gradient operator (shared by both methods; reported apart), and
pypardiso's search for the MKL library (looked up once, passed to the
workers as ``PYPARDISO_MKL_RT``).  OpenBLAS (dense eigensolver, ARPACK's
orthogonalisation) runs single-threaded by default (``--blas-threads``): on
this shared 2-core machine its spinning threads made ARPACK with 300
eigenpairs 9× slower (rocker_arm: 86 s against 10 s).  Peak memory: the worker's peak resident
set size during the timed part (``/proc/self/clear_refs`` resets it).

Usage::

    python -m benchmarks.bench_riesz [--models NAME ...] [--without-igea] [--skip-fig2]
"""

from __future__ import annotations

import argparse
import json
import sys
import time

import numpy as np

from benchmarks.common import (
    PAPER_IMFS,
    PAPER_RT,
    PAPER_VERTICES,
    SCRATCH,
    load_average,
    machine_meta,
    mean_adjacent_distance,
    mkl_environment,
    model_or_skip,
    model_path,
    paper_columns,
    paper_interpolated,
    reset_peak,
    short,
    status_mb,
    table,
    worker_json,
    write_results,
)

MODELS = ["spot", "sphere_oct4098", "spacetime_face_neutral", "rocker_arm", "bunny_zipper", "nefertiti", "igea"]
FIG2_EIGENPAIRS = [50, 150, 300, 600, 1500]
N_SIGNALS = 15
SPECTRAL_EIGENPAIRS = 300
REFERENCE_TOL = 1e-12
#: Quadrature tolerances whose shift counts and true errors are reported.
TOLERANCES = [1e-4, 1e-6, 1e-8, 1e-10]
#: Paper Table 1, RT column: (vertices, IMFs, seconds), MATLAB 2014 on a 4-core i7.
PAPER_TABLE1_RT = paper_columns(PAPER_VERTICES, PAPER_IMFS, PAPER_RT)


# -- measurement helpers ---------------------------------------------------------------------------


def _m_error(mass, approx, exact) -> np.ndarray:
    """Relative M-norm error per signal (last axes summed)."""
    axes = tuple(range(1, exact.ndim))
    w = mass.reshape((1, -1) + (1,) * (exact.ndim - 2))
    return np.sqrt(np.sum((approx - exact) ** 2 * w, axis=axes) / np.sum(exact**2 * w, axis=axes))


def _clear_riesz_cache(surface) -> None:
    for key in [k for k in surface.cache if k.startswith("riesz:")]:
        del surface.cache[key]


# -- part 1: Fig. 2(h) ----------------------------------------------------------------------------


def run_fig2() -> dict:
    import hht3d
    from hht3d.geometry.signals import centroid_distance
    from hht3d.spectral import fractional_laplacian, vertex_gradient

    sphere = hht3d.load(model_path("sphere_oct4098"))
    v = sphere.vertices / np.abs(sphere.vertices).sum(axis=1, keepdims=True)
    surface = hht3d.Surface(v, sphere.faces, name="octahedron4098")
    f = centroid_distance(surface)
    mass = surface.mass_diagonal
    surface.gradient("lsq")

    def run(method, **options):
        _clear_riesz_cache(surface)
        t0 = time.perf_counter()
        u = fractional_laplacian(surface, f, method=method, **options)
        seconds = time.perf_counter() - t0
        return u, vertex_gradient(surface, u, "lsq"), seconds

    u_ref, r_ref, dense_seconds = run("dense")
    magnitude = np.linalg.norm(r_ref, axis=1)
    rows = []

    def record(label, u, r, seconds):
        error = np.abs(np.linalg.norm(r, axis=1) - magnitude)
        rows.append(
            {
                "method": label,
                "seconds": seconds,
                "mean_magnitude_error": float(error.mean()),
                "relative_mean_magnitude_error": float(error.mean() / magnitude.mean()),
                "max_magnitude_error": float(error.max()),
                "relative_m_error_L-1/2": float(_m_error(mass, u[None], u_ref[None])[0]),
            }
        )

    for p in FIG2_EIGENPAIRS:
        record(f"spectral({p})", *run("spectral", eigenpairs=p))
    for tol in (1e-8, 1e-12):
        record(f"quadrature(tol={tol:g})", *run("quadrature", tol=tol))
    return {
        "model": "octahedron from sphere_oct4098",
        "vertices": surface.n_vertices,
        "signal": "centroid distance",
        "dense_seconds": dense_seconds,
        "mean_riesz_magnitude": float(magnitude.mean()),
        "rows": rows,
    }


# -- part 2: model ladder -------------------------------------------------------------------------


def band_signals(surface) -> np.ndarray:
    """15 band-passes of the mean curvature between heat-smoothing scales."""
    from hht3d import linalg
    from hht3d.geometry.signals import mean_curvature

    h = mean_curvature(surface)
    edge = mean_adjacent_distance(surface)
    times = np.geomspace(edge**2, (surface.bounding_box_diagonal / 4) ** 2, N_SIGNALS + 1)
    mass = surface.mass_diagonal
    smooth = [h] + [linalg.factorize(surface.mass + t * surface.stiffness).solve(mass * h) for t in times]
    return np.stack([smooth[i] - smooth[i + 1] for i in range(N_SIGNALS)])


def _load(name: str):
    import hht3d

    t0 = time.perf_counter()
    surface = hht3d.load(model_path(name))
    surface.stiffness, surface.gradient("lsq")
    operators = time.perf_counter() - t0
    return surface, operators


def run_ladder_case(name: str, method: str) -> dict:
    from hht3d.spectral import fractional_laplacian, quadrature_nodes, smallest_eigenpairs, spectral_bounds
    from hht3d.spectral.monogenic_signal import monogenic

    surface, operators = _load(name)
    signals = band_signals(surface)
    reset_peak()
    baseline = status_mb("VmRSS")
    t0 = time.perf_counter()
    if method == "quadrature":
        spectral_bounds(surface)
    else:
        smallest_eigenpairs(surface, SPECTRAL_EIGENPAIRS)
    t1 = time.perf_counter()
    result = monogenic(surface, signals, method=method, eigenpairs=SPECTRAL_EIGENPAIRS)
    t2 = time.perf_counter()
    peak = status_mb("VmHWM")
    arrays = {
        "u": fractional_laplacian(surface, signals, method=method, eigenpairs=SPECTRAL_EIGENPAIRS),
        "riesz": result.riesz,
        "amplitude": result.amplitude,
        "frequency": result.frequency,
        "mass": surface.mass_diagonal,
    }
    record = {
        "model": name,
        "method": method,
        "vertices": surface.n_vertices,
        "signals": len(signals),
        "operators_seconds": operators,
        "setup_seconds": t1 - t0,
        "monogenic_seconds": t2 - t1,
        "seconds": t2 - t0,
        "baseline_rss_mb": baseline,
        "peak_rss_mb": peak,
    }
    if method == "quadrature":
        m, mbar = spectral_bounds(surface)
        record.update(condition=mbar / m, shifts=len(quadrature_nodes(m, mbar, 1e-8)[0]))
        reference = monogenic(surface, signals, tol=REFERENCE_TOL)
        arrays.update(
            u_ref=fractional_laplacian(surface, signals, tol=REFERENCE_TOL),
            riesz_ref=reference.riesz,
            amplitude_ref=reference.amplitude,
            frequency_ref=reference.frequency,
        )
        record["tolerances"] = shifts_against_tolerance(surface, signals, arrays["u_ref"])
    SCRATCH.mkdir(parents=True, exist_ok=True)
    np.savez(SCRATCH / f"riesz_{name}_{method}.npz", **arrays)
    return record


def shifts_against_tolerance(surface, signals, reference) -> list[dict]:
    """Shifts and the true error of ``L^{-1/2}`` per tolerance, with today's and Gershgorin's upper bound."""
    from hht3d.spectral import fractional_laplacian, quadrature_nodes, spectral_bounds

    m, mbar = spectral_bounds(surface)
    gershgorin = float(np.max(abs(surface.stiffness).sum(axis=1).A1 / surface.mass_diagonal))
    rows = []
    for tol in TOLERANCES:
        t0 = time.perf_counter()
        u = fractional_laplacian(surface, signals, tol=tol)
        rows.append(
            {
                "tol": tol,
                "shifts": len(quadrature_nodes(m, mbar, tol)[0]),
                "shifts_gershgorin": len(quadrature_nodes(m, gershgorin, tol)[0]),
                "upper_bound": mbar,
                "gershgorin": gershgorin,
                "seconds": time.perf_counter() - t0,
                "error": float(_m_error(surface.mass_diagonal, u, reference).max()),
            }
        )
    return rows


def errors(name: str, method: str) -> dict:
    """Errors of one method against the tight-tolerance quadrature reference."""
    ours = np.load(SCRATCH / f"riesz_{name}_{method}.npz")
    ref = np.load(SCRATCH / f"riesz_{name}_quadrature.npz")
    mass = ref["mass"]
    weight = ref["amplitude_ref"] ** 2 * mass
    freq = np.sum(weight * np.abs(ours["frequency"] - ref["frequency_ref"]), axis=1) / np.sum(
        weight * ref["frequency_ref"], axis=1
    )
    riesz = _m_error(mass, ours["riesz"], ref["riesz_ref"])
    return {
        "L-1/2": float(_m_error(mass, ours["u"], ref["u_ref"]).max()),
        "riesz": float(riesz.max()),
        "amplitude": float(_m_error(mass, ours["amplitude"], ref["amplitude_ref"]).max()),
        "frequency": float(freq.max()),
        "riesz_per_signal_fine_to_coarse": riesz.tolist(),
    }


# -- reporting ----------------------------------------------------------------------------------------


def markdown(fig2: dict | None, ladder: list[dict], meta: dict) -> str:
    out = [
        "# Riesz transform and monogenic signal benchmark",
        "",
        f"Machine: {meta['machine']}; {meta['cpus']} CPUs (shared with other jobs, load average "
        f"{meta['load_average']}); backend `{meta['backend']}`; OpenBLAS threads "
        f"{meta['openblas_threads']}; Python {meta['python']}.  "
        "Generated by `python -m benchmarks.bench_riesz`; the method is in its docstring.",
        "",
    ]
    if fig2:
        out += [
            "## Fig. 2(h): truncated eigen-expansion vs. the exact transform",
            "",
            f"{fig2['model']} ({fig2['vertices']} vertices), signal: {fig2['signal']}; reference "
            f"`dense` ({short(fig2['dense_seconds'])} s).  Magnitude error = mean over vertices of "
            "| |Rf| − |Rf|_dense |, as in the paper's plot, also relative to the mean |Rf|_dense.",
            "",
            table(
                [
                    "method",
                    "seconds",
                    "mean magnitude error",
                    "relative",
                    "max magnitude error",
                    "rel. M-norm error of L^-1/2 f",
                ],
                [
                    [
                        r["method"],
                        short(r["seconds"]),
                        f"{r['mean_magnitude_error']:.2e}",
                        f"{r['relative_mean_magnitude_error']:.2e}",
                        f"{r['max_magnitude_error']:.2e}",
                        f"{r['relative_m_error_L-1/2']:.2e}",
                    ]
                    for r in fig2["rows"]
                ],
            ),
            "",
        ]
    if ladder:
        rows = []
        for q, s in ladder:
            for r in (q, s):
                e = r["errors"]
                extra = (
                    f"{r['shifts']} / {r['condition']:.1e}"
                    if r["method"] == "quadrature"
                    else str(SPECTRAL_EIGENPAIRS) + " pairs"
                )
                speed = f"{s['seconds'] / q['seconds']:.1f}x" if r is q else ""
                ratio = f"{s['errors']['riesz'] / max(q['errors']['riesz'], 1e-300):.1e}x" if r is q else ""
                paper = short(paper_interpolated(r["vertices"], PAPER_RT), 1) if r is q else ""
                rows.append(
                    [
                        r["model"],
                        f"{r['vertices']:,}",
                        short(r["operators_seconds"]),
                        r["method"],
                        extra,
                        short(r["seconds"]),
                        f"{r['peak_rss_mb']:.0f}",
                        f"{e['L-1/2']:.1e}",
                        f"{e['riesz']:.1e}",
                        f"{e['amplitude']:.1e}",
                        f"{e['frequency']:.1e}",
                        speed,
                        ratio,
                        paper,
                    ]
                )
        out += [
            "## Model ladder: 15 band-passed mean-curvature signals, Riesz + monogenic",
            "",
            "Seconds: bounds or eigenpairs + `monogenic()` of all 15 signals (operators L, M, "
            "gradient built beforehand, `ops s`).  Errors: largest over the 15 signals, relative, "
            f"against `quadrature` at tol {REFERENCE_TOL:g} — M-norm for L^-1/2 f, Riesz vectors and "
            "amplitude; energy-weighted mean |Δω|/ω for the frequency.  Peak RSS during the timed "
            "part.  Paper: Table 1 RT column interpolated at this vertex count (their IMF counts, "
            "3–15, MATLAB, 300 eigenpairs).",
            "",
            table(
                [
                    "model",
                    "#V",
                    "ops s",
                    "method",
                    "shifts / κ",
                    "seconds",
                    "peak RSS MB",
                    "err L^-1/2",
                    "err Riesz",
                    "err amplitude",
                    "err frequency",
                    "speed-up",
                    "error ratio",
                    "paper RT s",
                ],
                rows,
            ),
            "",
            "Speed-up: spectral(300) seconds / quadrature seconds in the same run.  Error ratio: "
            "spectral(300) Riesz error / quadrature Riesz error.",
            "",
            "Relative Riesz error of spectral(300) per band, finest to coarsest:",
            "",
            table(
                ["model"] + [str(i + 1) for i in range(N_SIGNALS)],
                [
                    [s["model"]] + [f"{x:.0e}" for x in s["errors"]["riesz_per_signal_fine_to_coarse"]]
                    for _, s in ladder
                ],
            ),
        ]
        out += [
            "",
            "Shifts against the tolerance: shifted solves with Gershgorin's upper bound "
            "max_i Σ_j|L_ij|/M_ii and with today's (Collatz–Wielandt, power-iterated), and the true "
            f"largest relative M-norm error of L^-1/2 over the 15 signals against tol {REFERENCE_TOL:g}; "
            "seconds of `fractional_laplacian` at that tolerance (bounds cached).",
            "",
            table(
                ["model", "M̄ / Gershgorin"] + [f"tol {x:g}: shifts (Gershgorin → now), error, s" for x in TOLERANCES],
                [
                    [q["model"], f"{rows[0]['upper_bound'] / rows[0]['gershgorin']:.2f}"]
                    + [
                        f"{r['shifts_gershgorin']} → {r['shifts']}, {r['error']:.1e}, {short(r['seconds'])}"
                        for r in rows
                    ]
                    for q, _ in ladder
                    for rows in [q.get("tolerances", [])]
                    if rows
                ],
            ),
            "",
        ]
    return "\n".join(out)


# -- driver -------------------------------------------------------------------------------------------


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--models", nargs="*", default=None, help="model names (default: the ladder)")
    parser.add_argument("--without-igea", action="store_true", help="leave out igea (134k vertices)")
    parser.add_argument("--skip-fig2", action="store_true", help="leave out the Fig. 2(h) part")
    parser.add_argument("--blas-threads", type=int, default=1, help="OpenBLAS threads of the workers")
    parser.add_argument("--worker", nargs="+", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker:
        record = run_fig2() if args.worker == ["fig2"] else run_ladder_case(*args.worker)
        json.dump(record, sys.stdout)
        return 0
    env, lookup = mkl_environment()
    env["OPENBLAS_NUM_THREADS"] = str(args.blas_threads)
    fig2 = None
    if not args.skip_fig2 and model_path("sphere_oct4098") is not None:
        fig2 = worker_json(__file__, ["--worker", "fig2"], env=env)
        print("fig2 done", file=sys.stderr)
    names = args.models or [m for m in MODELS if not (args.without_igea and m == "igea")]
    ladder = []
    for name in names:
        if model_or_skip(name) is None:
            continue
        pair = [worker_json(__file__, ["--worker", name, method], env=env) for method in ("quadrature", "spectral")]
        for r in pair:
            r["errors"] = errors(name, r["method"])
        for r in pair:
            (SCRATCH / f"riesz_{name}_{r['method']}.npz").unlink()
        ladder.append(pair)
        q, s = pair
        print(
            f"{name}: {q['vertices']} V, quadrature {q['seconds']:.2f} s (err {q['errors']['riesz']:.1e}), "
            f"spectral {s['seconds']:.2f} s (err {s['errors']['riesz']:.1e})",
            file=sys.stderr,
        )
    meta = machine_meta(
        load_average=load_average(1),
        pypardiso_mkl_lookup_seconds=lookup,
        openblas_threads=args.blas_threads,
        paper_table1_rt=PAPER_TABLE1_RT,
    )
    write_results("riesz", {"meta": meta, "fig2": fig2, "ladder": ladder}, markdown(fig2, ladder, meta), indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
