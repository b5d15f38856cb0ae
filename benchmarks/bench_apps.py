"""Applications benchmark (Sec. 5) over the public models in ../shared/data (not a test).

For each model of the ladder (absent files are skipped) four fresh
subprocesses run one stage each, so each peak resident memory is the
stage's own (plus the interpreter, the libraries and the loaded model,
reported apart as "baseline"):

``hht``
    load and clean, mean-curvature signal (Eq. 24), :func:`hht3d.transform.hht`
    with default options; the result is saved to a temporary ``.npz``.
``filter``
    Eq. (26) + Eq. (27) with :func:`hht3d.apps.filter_geometry` for two
    gains: a low-pass and a 2.5x high-frequency enhancement (the paper's
    Fig. 6 factor), both with the cutoff at the energy-weighted mean
    frequency of IMF 2 (IMF 1 when there is one) and a raised-cosine edge of
    a quarter of it.  Each call builds and factorizes ``L M⁻¹ L + W``.
``features``
    :func:`hht3d.apps.prominent_features` from the saved IMFs (2-ring,
    t = 0.8, half the IMF count), without and with merging within 2 mean
    edge lengths.
``noise``
    the HKS baseline (:func:`hht3d.apps.hks_features`, 100 eigenpairs,
    default time) on the model, timed with its peak memory; then a copy with
    Gaussian noise of 15% of the mean edge length per coordinate (seed 0,
    paper Fig. 8): EMD + our features and HKS features on it.
    Repeatability = fraction of one set's features within 2 mean edge lengths
    of a feature of the other (positions of the clean model, same vertex
    order); "chance" = the fraction of all vertices that close to a clean
    feature, what randomly placed features would score noisy->clean.

Results go to ``benchmarks/results/apps.json`` and ``apps.md``.

Usage::

    python -m benchmarks.bench_apps [--models NAME ...]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from benchmarks.common import (
    MESHES,
    fixed,
    machine_meta,
    mkl_environment,
    model_or_skip,
    model_path,
    peak_rss_mb,
    table,
    worker_json,
    write_results,
)

NOISE = 0.15
SEED = 0
HKS_EIGENPAIRS = 100


def _load(name: str):
    import hht3d

    return hht3d.load(model_path(name))


def _mean_edge(surface) -> float:
    p = surface.vertices[surface.faces]
    return float(np.mean(np.linalg.norm(p - np.roll(p, 1, axis=1), axis=2)))


def _load_result(name: str, scratch: Path):
    """The model's HHT saved by the hht stage (:func:`hht3d.load_result`)."""
    from hht3d import load_result

    return load_result(scratch / f"{name}.npz")


def stage_hht(name: str, scratch: Path) -> dict:
    from hht3d.geometry.signals import mean_curvature
    from hht3d.transform import hht

    surface = _load(name)
    signal = mean_curvature(surface)
    baseline = peak_rss_mb()
    t0 = time.perf_counter()
    result = hht(surface, signal)
    seconds = time.perf_counter() - t0
    result.save(scratch / f"{name}.npz")
    return {
        "vertices": surface.n_vertices,
        "boundary_vertices": int(surface.boundary_vertices.sum()),
        "imfs": result.n_imfs,
        "seconds": seconds,
        "emd_seconds": result.info["seconds"]["emd"],
        "spectra_seconds": result.info["seconds"]["spectra"],
        "baseline_rss_mb": baseline,
        "peak_rss_mb": peak_rss_mb(),
    }


def _cutoff(result) -> float:
    mean = result.spectrum.mean_frequency()
    return float(mean[1] if len(mean) > 1 else mean[0])


def stage_filter(name: str, scratch: Path) -> dict:
    from hht3d.apps import HighBoost, LowPass, filter_geometry

    result = _load_result(name, scratch)
    surface = result.surface
    _ = surface.stiffness, surface.normals  # operators are part of loading, not of the filter
    cutoff = _cutoff(result)
    baseline = peak_rss_mb()
    record = {"cutoff": cutoff, "baseline_rss_mb": baseline}
    for label, gain in (
        ("low_pass", LowPass(cutoff=cutoff, width=cutoff / 4)),
        ("high_boost", HighBoost(cutoff=cutoff, factor=2.5, width=cutoff / 4)),
    ):
        t0 = time.perf_counter()
        out = filter_geometry(result, gain)
        record[f"{label}_seconds"] = time.perf_counter() - t0
        moved = np.sqrt(np.mean(np.sum((out.vertices - surface.vertices) ** 2, axis=1)))
        record[f"{label}_rms_displacement_per_diagonal"] = float(moved / surface.bounding_box_diagonal)
    record["peak_rss_mb"] = peak_rss_mb()
    return record


def stage_features(name: str, scratch: Path) -> dict:
    from hht3d.apps import prominent_features

    result = _load_result(name, scratch)
    surface = result.surface
    _ = surface.ring(2)  # the 2-ring is a cached surface operator, built once per mesh
    h = _mean_edge(surface)
    baseline = peak_rss_mb()
    t0 = time.perf_counter()
    plain = prominent_features(surface, result.imfs)
    t1 = time.perf_counter()
    merged = prominent_features(surface, result.imfs, merge_radius=2 * h)
    t2 = time.perf_counter()
    return {
        "seconds": t1 - t0,
        "merged_seconds": t2 - t1,
        "features": plain.n_features,
        "merged_features": merged.n_features,
        "min_count": plain.min_count,
        "baseline_rss_mb": baseline,
        "peak_rss_mb": peak_rss_mb(),
    }


def stage_noise(name: str, scratch: Path) -> dict:
    from scipy.spatial import cKDTree

    from hht3d import Surface
    from hht3d.apps import hks_features, prominent_features, repeatability
    from hht3d.decomposition import emd
    from hht3d.geometry.signals import mean_curvature

    result = _load_result(name, scratch)
    surface = result.surface
    _ = surface.stiffness, surface.ring(2)
    baseline = peak_rss_mb()
    t0 = time.perf_counter()
    hks_clean = hks_features(surface, eigenpairs=HKS_EIGENPAIRS)
    hks_seconds = time.perf_counter() - t0
    hks_peak = peak_rss_mb()
    h = _mean_edge(surface)
    noise = np.random.default_rng(SEED).normal(scale=NOISE * h, size=surface.vertices.shape)
    noisy = Surface(surface.vertices + noise, surface.faces, name=f"{name}_noisy")
    t0 = time.perf_counter()
    decomposition = emd(noisy, mean_curvature(noisy))
    noisy_emd_seconds = time.perf_counter() - t0
    ours_clean = prominent_features(surface, result.imfs)
    ours_noisy = prominent_features(noisy, decomposition)
    hks_noisy = hks_features(noisy, eigenpairs=HKS_EIGENPAIRS)
    p = surface.vertices

    def scores(clean, perturbed) -> dict:
        a, b = p[clean.vertices], p[perturbed.vertices]
        chance = float(np.mean(cKDTree(a).query(p)[0] <= 2 * h)) if len(a) else float("nan")
        return {
            "clean_features": clean.n_features,
            "noisy_features": perturbed.n_features,
            "noisy_to_clean": repeatability(b, a, 2 * h),
            "clean_to_noisy": repeatability(a, b, 2 * h),
            "chance": chance,
        }

    return {
        "mean_edge": h,
        "noisy_imfs": decomposition.n_imfs,
        "noisy_emd_seconds": noisy_emd_seconds,
        "hks_seconds": hks_seconds,
        "hks_baseline_rss_mb": baseline,
        "hks_peak_rss_mb": hks_peak,
        "ours": scores(ours_clean, ours_noisy),
        "hks": scores(hks_clean, hks_noisy),
    }


STAGES = {"hht": stage_hht, "filter": stage_filter, "features": stage_features, "noise": stage_noise}


def markdown(records: list[dict], meta: dict) -> str:
    lines = [
        "# Applications benchmark: Hilbert-spectrum filtering + reconstruction, prominent features",
        "",
        f"Machine: {meta['machine']}; {meta['cpus']} CPUs shared with other jobs (1-minute load average "
        f"{meta['load_average_1min'][0]:.1f} before, {meta['load_average_1min'][1]:.1f} after), so timings "
        f"are noisy; backend `{meta['backend']}`; Python {meta['python']}.  Generated by "
        "`python -m benchmarks.bench_apps`; the method is in its docstring.",
        "",
        "## Time and memory",
        "",
        "Each stage ran in a fresh process: *baseline* MB is its peak RSS after loading the model, its "
        "operators and the saved HHT; *peak* MB is the stage's high-water mark.  Filter s: one "
        "`filter_geometry` call (Eq. 26 gains, then building and factorizing `L M^-1 L + W` and solving "
        "Eq. 27 for the 3 coordinates).  Features s: `prominent_features` from the IMFs (2-ring extrema "
        "per IMF and counting); HKS s: 100 smallest eigenpairs (shift-invert ARPACK) plus the HKS maxima.",
        "",
        table(
            [
                "model",
                "#V",
                "#IMFs",
                "HHT s (EMD + spectra)",
                "low-pass s",
                "2.5x boost s",
                "filter MB baseline/peak",
                "features s",
                "#features (merged 2h)",
                "features MB baseline/peak",
                "HKS s",
                "HKS MB baseline/peak",
            ],
            [
                [
                    r["model"],
                    f"{hh['vertices']:,}",
                    hh["imfs"],
                    f"{hh['seconds']:.1f} ({hh['emd_seconds']:.1f} + {hh['spectra_seconds']:.1f})",
                    f"{fi['low_pass_seconds']:.2f}",
                    f"{fi['high_boost_seconds']:.2f}",
                    f"{fi['baseline_rss_mb']:.0f}/{fi['peak_rss_mb']:.0f}",
                    f"{fe['seconds']:.3f}",
                    f"{fe['features']} ({fe['merged_features']})",
                    f"{fe['baseline_rss_mb']:.0f}/{fe['peak_rss_mb']:.0f}",
                    f"{no['hks_seconds']:.1f}",
                    f"{no['hks_baseline_rss_mb']:.0f}/{no['hks_peak_rss_mb']:.0f}",
                ]
                for r in records
                for hh, fi, fe, no in [(r["hht"], r["filter"], r["features"], r["noise"])]
            ],
        ),
        "",
        "## Repeatability under noise (paper Fig. 8)",
        "",
        f"Gaussian noise of {NOISE:.0%} of the mean edge length per coordinate (seed {SEED}).  "
        "noisy→clean: fraction of the noisy copy's features within 2 mean edge lengths of a feature of "
        "the model; clean→noisy: the reverse.  Chance: the noisy→clean score of features placed at random "
        "(fraction of all vertices within 2 mean edge lengths of a clean feature).",
        "",
        table(
            [
                "model",
                "#IMFs clean/noisy",
                "ours #features clean/noisy",
                "ours noisy→clean (chance)",
                "ours clean→noisy",
                "HKS #features clean/noisy",
                "HKS noisy→clean (chance)",
                "HKS clean→noisy",
            ],
            [
                [
                    r["model"],
                    f"{r['hht']['imfs']}/{no['noisy_imfs']}",
                    f"{o['clean_features']}/{o['noisy_features']}",
                    f"{fixed(o['noisy_to_clean'])} ({fixed(o['chance'])})",
                    fixed(o["clean_to_noisy"]),
                    f"{k['clean_features']}/{k['noisy_features']}",
                    f"{fixed(k['noisy_to_clean'])} ({fixed(k['chance'])})",
                    fixed(k["clean_to_noisy"]),
                ]
                for r in records
                for no in [r["noise"]]
                for o, k in [(no["ours"], no["hks"])]
            ],
        ),
    ]
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--models", nargs="*", default=None, help="model names (default: the ladder)")
    parser.add_argument("--worker", nargs=3, help=argparse.SUPPRESS)  # stage, model, scratch folder
    args = parser.parse_args(argv)
    if args.worker:
        stage, name, scratch = args.worker
        json.dump(STAGES[stage](name, Path(scratch)), sys.stdout)
        return 0
    env, _ = mkl_environment()
    load_before = os.getloadavg()[0]
    records = []
    with tempfile.TemporaryDirectory(prefix="bench_apps_") as scratch:
        for name in args.models or MESHES:
            if model_or_skip(name) is None:
                continue
            record = {"model": name}
            for stage in STAGES:
                record[stage] = worker_json(__file__, ["--worker", stage, name, scratch], env=env)
            records.append(record)
            print(
                f"{name}: HHT {record['hht']['seconds']:.1f} s, filter {record['filter']['low_pass_seconds']:.2f} s, "
                f"features {record['features']['seconds']:.3f} s, repeatability ours "
                f"{record['noise']['ours']['noisy_to_clean']:.2f} / HKS {record['noise']['hks']['noisy_to_clean']:.2f}",
                file=sys.stderr,
            )
    meta = machine_meta(
        load_average_1min=[load_before, os.getloadavg()[0]], noise=NOISE, seed=SEED, hks_eigenpairs=HKS_EIGENPAIRS
    )
    write_results("apps", {"meta": meta, "models": records}, markdown(records, meta), indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
