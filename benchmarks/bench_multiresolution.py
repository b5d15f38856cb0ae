"""Iterative filtering on a coarsening hierarchy against the direct full-resolution path, in one run (issue 39).

Per model, the whole HHT of the mean-curvature signal with ``method="filtering"`` in up to four
settings (:data:`MODES`), each in its own subprocess (so its peak resident memory, ``VmHWM``, is
its own):

``direct``      ``multiresolution="never"``, ``evaluation="solves"``: every IMF filtered on the
                input's vertices and its Riesz transform by the full quadrature there (the
                baseline, same run);
``multires``    ``multiresolution="always"``, ``evaluation="solves"``: each residue carried on the
                coarsest level of :func:`hht3d.geometry.hierarchy.hierarchy` that resolves it
                (:mod:`hht3d.decomposition.multiresolution`), and the Riesz transform of each IMF
                on its level and in its band (:mod:`hht3d.spectral.multilevel`);
``polynomial``  the same levels with ``evaluation="polynomial"``: every filter that can be is a
                Chebyshev polynomial, and so is the Riesz potential of its IMF (no factorization
                on those levels);
``auto``        the same levels with ``evaluation="auto"`` (the defaults on levels): polynomials on the
                coarse levels, and on the input from 2,000,000 vertices;
``plain``       ``auto``'s settings with ``backend="superlu"``: a plain install (polynomial from
                20,000 vertices), against ``auto`` on the fast backend.

All but ``plain`` use the fastest backend installed.

A worker first runs the same HHT on spot (2.9k vertices; loads the solver and its libraries, not
counted), resets its peak (``/proc/self/clear_refs``), then loads the model, takes the signal and
times :func:`hht3d.hht` as a whole, with ``result.info["seconds"]`` (``emd``, ``spectra``).  It
keeps the IMFs, amplitude, Riesz vectors, frequency and lumped mass in ``--folder`` as an ``.npz``,
and the parent compares the two runs of a model, the direct one the reference ``a``, IMF by IMF:
the relative M-norm error ``sqrt(Σ M (b − a)² / Σ M a²)`` of the IMFs, amplitudes and Riesz
vectors (summed over the three components), the ratio of the median instantaneous frequencies,
the level each IMF was filtered on and the ``transfer_error`` of its residue
(``‖r_k − P R r_k‖_M / ‖r_k‖_M``), and the differences (multires − direct) of the energy ratio
and of the index of orthogonality.  Time ratios are multires / direct of the whole ``hht``, of
EMD and of the spectra, for each setting against ``direct``.

Models: ``nefertiti`` (50k) and ``igea`` (134k) from ``../shared/data`` and the generated sizes of
:data:`benchmarks.meshes.SCALING` (``1m``: igea decimated and Loop-subdivided, made once and kept
in ``--folder``).  Run::

    python -m benchmarks.bench_multiresolution [--models 3k 6k 9k 12k 25k nefertiti igea 1m]
        [--modes direct multires polynomial auto plain] [--folder /tmp/hht3d-bench] [--timeout 3600]

Writes ``results/multiresolution.json`` and ``results/multiresolution.md`` (the records of models
and settings not re-run are kept from the previous file).  ``3k``, ``6k``, ``9k``, ``12k`` and ``25k``
(igea decimated) with nefertiti place the crossover of ``multiresolution="auto"``.  ``SIZE_cloud``
(``1m_cloud``) is a generated size's vertices read as a point cloud, whose Laplacian
(``robust-laplacian``) is intrinsic Delaunay, so that its polynomial filters give the Riesz potential too.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from benchmarks.common import (
    SPOT,
    log,
    machine,
    mkl_environment,
    model_or_skip,
    previous_results,
    reset_peak,
    run_worker,
    short,
    status_mb,
    table,
    worker_answer,
    write_results,
)
from benchmarks.meshes import SCALING

MODELS = ["3k", "6k", "9k", "12k", "25k", "nefertiti", "igea", "1m"]
#: name -> the settings of the run; ``direct`` is the baseline.
MODES = {
    "direct": {"multiresolution": "never", "evaluation": "solves"},
    "multires": {"multiresolution": "always", "evaluation": "solves"},
    "polynomial": {"multiresolution": "always", "evaluation": "polynomial"},
    "auto": {"multiresolution": "always", "evaluation": "auto"},
    "plain": {"multiresolution": "always", "evaluation": "auto", "backend": "superlu"},
}
#: The setting each one is compared with, beside ``direct``: the plain install against the fast backend.
PAIRS = {"multires": "direct", "polynomial": "direct", "auto": "direct", "plain": "auto"}
FOLDER = Path("/tmp/hht3d-bench")
#: A run still going after this many seconds is stopped and reported as such.
CASE_TIMEOUT = 3600


def mesh_path(name: str, folder: Path) -> Path | None:
    """The public model, the generated mesh of :data:`SCALING` in ``folder``, or its vertices as a point cloud
    for ``SIZE_cloud`` (:func:`benchmarks.meshes.cloud_of`; each made on first use)."""
    from benchmarks.meshes import SCALING_SOURCE, cloud_of, generate

    path = folder / f"{SCALING_SOURCE}_{name}.ply"
    if name.endswith("_cloud") and name.removesuffix("_cloud") in SCALING:
        mesh = mesh_path(name.removesuffix("_cloud"), folder)
        if mesh is not None and not path.is_file():
            log(f"making {name}: {cloud_of(mesh, path)}")
        return None if mesh is None else path
    if name not in SCALING:
        return model_or_skip(name)
    if not path.is_file():
        if model_or_skip(SCALING_SOURCE) is None:
            return None
        folder.mkdir(parents=True, exist_ok=True)
        log(f"generating {name}: {generate(name, path)}")
    return path


def arrays_path(folder: Path, name: str, mode: str) -> Path:
    return folder / f"multiresolution_{name}_{mode}.npz"


# -- a run (worker side) ------------------------------------------------------------------------------


def one(name: str, mode: str, folder: Path) -> dict:
    """The HHT of one model with one setting (module notes); its arrays go to :func:`arrays_path`."""
    import hht3d
    from hht3d.geometry.signals import mean_curvature

    setting = MODES[mode]
    spot = hht3d.load(SPOT)
    hht3d.hht(spot, mean_curvature(spot), method="filtering", **setting)
    path = mesh_path(name, folder)
    reset = reset_peak()
    baseline = status_mb("VmRSS")
    load_before = time.perf_counter()
    surface = hht3d.load(path)
    loaded = time.perf_counter()
    signal = mean_curvature(surface)
    start = time.perf_counter()
    result = hht3d.hht(surface, signal, method="filtering", **setting)
    seconds = time.perf_counter() - start
    peak = status_mb("VmHWM")
    quality = result.quality
    emd = result.info["emd"]
    mono = result.monogenic
    np.savez(
        arrays_path(folder, name, mode),
        imfs=mono.imfs,
        amplitude=mono.amplitude,
        riesz=mono.riesz,
        frequency=mono.frequency,
        mass=surface.mass_diagonal,
    )
    keys = ("level", "level_vertices", "residue_level", "transfer_error", "cut_frequency", "seconds", "factorizations")
    keys += ("degree",)
    return {
        "model": name,
        "mode": mode,
        "settings": setting,
        "source": str(path),
        "vertices": surface.n_vertices,
        "imfs": result.n_imfs,
        "levels": emd.get("levels", [surface.n_vertices]),
        "per_imf": [{k: i.get(k) for k in keys} for i in emd.get("imfs", [])],
        "stop_reason": emd.get("stop_reason"),
        "factorizations": emd.get("factorizations"),
        "solves": emd.get("solves"),
        "products": emd.get("products"),
        "backend": emd.get("backend"),
        "seconds": {
            "load": loaded - load_before,
            "signal": start - loaded,
            "hht": seconds,
            "emd": result.info["seconds"]["emd"],
            "spectra": result.info["seconds"]["spectra"],
        },
        "energy_ratio": quality.energy_ratio,
        "orthogonality_index": quality.orthogonality_index,
        "io_leaking": quality.io_leaking,
        "io_cancelling": quality.io_cancelling,
        "quality_warnings": list(quality.warnings),
        "peak_mb": peak,
        "baseline_mb": baseline,
        "peak_reset": reset,
    }


# -- comparison (parent side) -------------------------------------------------------------------------


def _error(mass: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    """``sqrt(Σ M (b − a)² / Σ M a²)`` over the vertices (and the components of vectors)."""
    weight = mass if a.ndim == 1 else mass[:, None]
    reference = float(np.sum(weight * a**2))
    return float(np.sqrt(np.sum(weight * (b - a) ** 2) / reference)) if reference > 0 else float("nan")


def compare(folder: Path, name: str, modes: tuple[str, str], direct: dict, multires: dict) -> dict:
    """IMF by IMF, the run of ``modes[1]`` (``multires``) against that of ``modes[0]`` (``direct``) (module notes)."""
    a, b = (np.load(arrays_path(folder, name, mode)) for mode in modes)
    mass = a["mass"]
    k = min(len(a["imfs"]), len(b["imfs"]))
    per_imf = []
    for i in range(k):
        fa, fb = a["frequency"][i], b["frequency"][i]
        positive = fa > 0
        info = multires["per_imf"][i] if i < len(multires["per_imf"]) else {}
        per_imf.append(
            {
                "k": i + 1,
                "level": info.get("level"),
                "level_vertices": info.get("level_vertices"),
                "residue_level": info.get("residue_level"),
                "transfer_error": info.get("transfer_error"),
                "cut_frequency": info.get("cut_frequency"),
                "cut_frequency_direct": direct["per_imf"][i].get("cut_frequency")
                if i < len(direct["per_imf"])
                else None,
                "imf_error": _error(mass, a["imfs"][i], b["imfs"][i]),
                "amplitude_error": _error(mass, a["amplitude"][i], b["amplitude"][i]),
                "riesz_error": _error(mass, a["riesz"][i], b["riesz"][i]),
                "frequency_ratio": float(np.median(fb) / np.median(fa)),
                "median_pointwise_frequency_ratio": float(np.median(fb[positive] / fa[positive])),
                "seconds_direct": direct["per_imf"][i].get("seconds") if i < len(direct["per_imf"]) else None,
                "seconds_setting": info.get("seconds"),
            }
        )
    ratio = {key: multires["seconds"][key] / direct["seconds"][key] for key in ("hht", "emd", "spectra")}
    return {
        "model": name,
        "modes": list(modes),
        "vertices": direct["vertices"],
        "imfs": [direct["imfs"], multires["imfs"]],
        "levels": multires["levels"],
        "seconds_direct": direct["seconds"]["hht"],
        "seconds_setting": multires["seconds"]["hht"],
        "time_ratio": ratio["hht"],
        "emd_ratio": ratio["emd"],
        "spectra_ratio": ratio["spectra"],
        "peak_mb_direct": direct["peak_mb"],
        "peak_mb_setting": multires["peak_mb"],
        "delta_energy_ratio": multires["energy_ratio"] - direct["energy_ratio"],
        "delta_io": multires["orthogonality_index"] - direct["orthogonality_index"],
        "runs": len(multires.get("repeats", [0])),
        "per_imf": per_imf,
    }


# -- driver ------------------------------------------------------------------------------------------


def _run_once(name: str, mode: str, folder: Path, env: dict, timeout: float) -> dict:
    """One worker's answer, or the record of its failure."""
    try:
        done = run_worker(__file__, ["--one", name, mode, "--folder", str(folder)], env=env, timeout=timeout)
    except subprocess.TimeoutExpired:
        log(f"  stopped after {timeout} s")
        return {"stopped_s": timeout}
    if done.returncode != 0:
        log(f"  failed (exit {done.returncode}):\n{done.stderr[-4000:]}")
        return {"error": f"exit {done.returncode}:\n{done.stderr[-4000:]}"}
    return worker_answer(done)


def run_model(
    name: str, modes: list[str], folder: Path, env: dict, timeout: float, previous: dict, repeats: int = 1
) -> dict:
    """The runs of one model, each in its own subprocess, ``repeats`` times with the median kept, and their
    comparisons; errors recorded, the runs of ``previous`` not re-run kept, with their comparisons when both
    runs of a pair are kept (a pair with one run re-run is dropped: it would compare two runs)."""
    record: dict = {"model": name, "runs": {m: r for m, r in previous.get("runs", {}).items() if m not in modes}}
    done_runs: dict[str, list[dict]] = {mode: [] for mode in modes}
    for repeat in range(repeats):  # settings in turn, so a drift of the machine's speed hits them alike
        for mode in [m for m in modes if m not in record["runs"] or done_runs[m]]:
            log(f"{name} {mode} ({MODES[mode]}) run {repeat + 1}/{repeats} ...")
            answer = _run_once(name, mode, folder, env, timeout)
            if "seconds" not in answer:
                record["runs"][mode] = answer
                done_runs[mode] = []
                continue
            done_runs[mode].append(answer)
            record["runs"][mode] = answer
            log(
                f"  {answer['vertices']:,} V, {answer['imfs']} IMFs, levels {answer['levels']}, "
                f"hht {answer['seconds']['hht']:.1f} s (EMD {answer['seconds']['emd']:.1f}, "
                f"spectra {answer['seconds']['spectra']:.1f}), peak {answer['peak_mb']:.0f} MB"
            )
    for mode, answers in done_runs.items():
        if answers:  # the run of median time, with every run's time
            answers.sort(key=lambda a: a["seconds"]["hht"])
            record["runs"][mode] = answers[len(answers) // 2] | {"repeats": [a["seconds"]["hht"] for a in answers]}
    runs = record["runs"]
    record["comparisons"] = {}
    for mode, base in PAIRS.items():
        if mode not in modes and base not in modes:  # neither re-run: the pair's comparison of one earlier run
            if mode in previous.get("comparisons", {}):
                record["comparisons"][mode] = previous["comparisons"][mode]
        elif mode in modes and base in modes and "seconds" in runs.get(mode, {}) and "seconds" in runs.get(base, {}):
            c = compare(folder, name, (base, mode), runs[base], runs[mode])
            record["comparisons"][mode] = c
            log(f"  {mode}/{base} {c['time_ratio']:.2f} (EMD {c['emd_ratio']:.2f}, spectra {c['spectra_ratio']:.2f})")
    return record


def _failure(run: dict) -> str:
    if "stopped_s" in run:
        return f"stopped at {run['stopped_s']} s"
    return "failed: " + run.get("error", "not run").strip().splitlines()[-1][:120]


def markdown(data: dict) -> str:
    """The page of ``results/multiresolution.json``."""
    meta = data["meta"]
    out = [
        "# Iterative filtering on a coarsening hierarchy against the direct path",
        "",
        f"Machine: {meta['platform']}, {meta['cpus']} CPUs, backend {meta['backend']}, load "
        f"{meta['load_average']} at the start and {meta.get('load_average_end')} at the end ({meta['date']}). "
        '`hht3d.hht(surface, mean_curvature(surface), method="filtering", ...)`, each run in its own '
        'process after a warm-up on spot. *direct*: `multiresolution="never"` (the baseline); *multires*: '
        '`"always"`, filters by solves; *polynomial*: `"always"`, `evaluation="polynomial"`; *auto*: '
        '`"always"`, `evaluation="auto"`; *plain*: *auto* on SuperLU, compared with *auto*. Seconds are the whole '
        "`hht` call; ratios are setting / its baseline; ΔER and ΔIO are setting − baseline. Models run with "
        "`--repeat N` ran each setting N times in turn; the run of median time is shown (all times: *runs*).",
        "",
        "## Per model",
        "",
    ]
    rows, failures = [], []
    for rec in data["models"]:
        for mode, run in rec["runs"].items():
            if "seconds" not in run:
                failures.append(f"- {rec['model']} {mode}: {_failure(run)}")
        for c in rec.get("comparisons", {}).values():
            rows.append(_model_row(c))
    header = ["model", "setting / baseline", "vertices", "IMFs", "baseline s", "setting s", "ratio"]
    header += ["EMD ratio", "spectra ratio", "peak MB baseline", "peak MB setting", "ΔER", "ΔIO", "level vertices used"]
    header += ["runs"]
    out += [table(header, rows), ""]
    if failures:
        out += ["Failed or stopped runs:", "", *failures, ""]
    out += [
        "## Per IMF (each setting against its baseline)",
        "",
        "*level*: the level IMF k was filtered on (its vertices) → the level its residue moved to; "
        "*degree*: of its polynomial (blank: solves); errors are relative M-norm errors against the "
        "baseline run; *freq ratio* is the median frequency of the setting over that of the baseline.",
        "",
    ]
    rows = []
    for rec in data["models"]:
        for c in rec.get("comparisons", {}).values():
            for p in c.get("per_imf", []):
                level = "" if p["level"] is None else f"{p['level']} ({p['level_vertices']:,}) → {p['residue_level']}"
                rows.append(
                    [c["model"], " / ".join(c["modes"][::-1]), p["k"], level, short(p.get("degree"), 0)]
                    + [short(p["transfer_error"], 3), short(p["imf_error"], 3), short(p["amplitude_error"], 3)]
                    + [short(p["riesz_error"], 3), short(p["frequency_ratio"], 3)]
                )
    header = ["model", "setting / baseline", "k", "level", "degree", "transfer error", "IMF err", "amplitude err"]
    header += ["Riesz err", "freq ratio"]
    out += [table(header, rows), ""]
    return "\n".join(out)


def _model_row(c: dict) -> list:
    return (
        [c["model"], " / ".join(c["modes"][::-1]), f"{c['vertices']:,}", f"{c['imfs'][0]} / {c['imfs'][1]}"]
        + [short(c["seconds_direct"], 1), short(c["seconds_setting"], 1), short(c["time_ratio"])]
        + [short(c["emd_ratio"]), short(c["spectra_ratio"])]
        + [short(c["peak_mb_direct"], 0), short(c["peak_mb_setting"], 0)]
        + [f"{c['delta_energy_ratio']:+.4f}", f"{c['delta_io']:+.4f}"]
        + [", ".join(f"{v:,}" for v in c["levels"]), c.get("runs", 1)]
    )


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--models", nargs="+", default=MODELS, help=f"default: {' '.join(MODELS)}")
    parser.add_argument("--folder", type=Path, default=FOLDER, help="generated meshes and the arrays of each run")
    parser.add_argument("--timeout", type=float, default=CASE_TIMEOUT, help="seconds before a run is stopped")
    parser.add_argument("--repeat", type=int, default=1, help="runs of each setting; the median is kept")
    parser.add_argument("--modes", nargs="+", choices=list(MODES), default=list(MODES), help="settings to run")
    parser.add_argument("--one", nargs=2, metavar=("MODEL", "MODE"), help=argparse.SUPPRESS)  # a worker
    args = parser.parse_args(argv)
    if args.one:
        print(json.dumps(one(*args.one, args.folder), default=float))
        return 0
    args.folder.mkdir(parents=True, exist_ok=True)
    env, _ = mkl_environment()
    data = previous_results("multiresolution")
    data["meta"] = machine() | {"date": time.strftime("%Y-%m-%d %H:%M"), "folder": str(args.folder)}
    records = {r["model"]: r for r in data.get("models", [])}
    for name in args.models:
        if mesh_path(name, args.folder) is None:
            continue
        records[name] = run_model(name, args.modes, args.folder, env, args.timeout, records.get(name, {}), args.repeat)
    order = {n: i for i, n in enumerate(MODELS)}
    data["models"] = sorted(records.values(), key=lambda r: order.get(r["model"], len(order)))
    data["meta"]["load_average_end"] = machine()["load_average"]
    for path in write_results("multiresolution", data, markdown(data)):
        log(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
