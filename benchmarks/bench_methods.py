"""The two decomposition methods on the same cases: envelope sifting (the defaults) and iterative filtering.

Runs the parts of ``bench_quality`` (models, bumps, noise, eigen) and the
component recovery of ``recovery.py`` for ``sifting`` (``EMD_DEFAULTS``),
``filtering`` (``FILTERING_OPTIONS``: global cut) and ``filtering, local cut``,
all in one process, so that the time ratios per IMF compare like with like
(default backend).  Then it checks the targets of the iterative-filtering
issue that decide the default method:

* every model: ``|IO| <= 0.10`` and energy ratio ``>= 0.90``;
* recovery: no component below the sifting defaults by more than 0.02;
* strips: at least PyEMD's EMD - 0.02 (chirp, AM-FM);
* random-bump low-pass ``>= 3x`` closer, two-eigenfunction correlation ``>= 0.97``,
  white-noise extrema ratios within 2.5-5;
* EMD time per IMF ``<= 0.5x`` the sifting defaults', median over the models.

Run from the repository root::

    python -m benchmarks.bench_methods [--parts models recovery ...] [--models spot igea ...]

Writes ``benchmarks/results/methods.json`` and ``methods.md``.
"""

from __future__ import annotations

import argparse
import dataclasses
import functools

import numpy as np

import hht3d
from benchmarks import bench_quality, recovery
from benchmarks.common import DATA, SPOT, machine, table, write_results
from hht3d import emd
from hht3d.decomposition import EMD_DEFAULTS, FILTERING_OPTIONS

#: name -> (EMD options, curvature min_area, Eq. 27 weights), as ``bench_quality.CONFIGS``.
CONFIGS = {
    "sifting": (EMD_DEFAULTS, None, {}),
    "filtering": (FILTERING_OPTIONS, None, {}),
    "filtering, local cut": (dataclasses.replace(FILTERING_OPTIONS, cut="local"), None, {}),
}


def _decompose(surface, signal, options):
    return emd(surface, signal, options)


def part_recovery() -> list[dict]:
    methods = {name: functools.partial(_decompose, options=c[0]) for name, c in CONFIGS.items()}
    references = {"PyEMD EMD": recovery.pyemd_methods()["PyEMD EMD"]}
    return recovery.part_recovery(SPOT, DATA / "spacetime_face_neutral.ply", methods, references)


def targets(records: dict) -> list[list]:
    """One row per target and method: the measured value and whether it holds."""
    rows: list[list] = []
    methods = [m for m in CONFIGS if m != "sifting"]
    models = records.get("models", [])
    by_model = {(r["model"], r["config"]): r for r in models}
    names = list(dict.fromkeys(r["model"] for r in models))
    recovered = {(r["case"], r["method"]): r for r in records.get("recovery", [])}
    cases = list(dict.fromkeys(r["case"] for r in records.get("recovery", [])))
    for m in methods:
        if names:
            io = max(abs(by_model[(n, m)]["io"]) for n in names)
            ratio = min(by_model[(n, m)]["energy_ratio"] for n in names)
            time_ratio = float(
                np.median(
                    [by_model[(n, m)]["seconds_per_imf"] / by_model[(n, "sifting")]["seconds_per_imf"] for n in names]
                )
            )
            rows += [
                [m, "max abs(IO) over the models <= 0.10", f"{io:.3f}", io <= 0.10],
                [m, "min energy ratio over the models >= 0.90", f"{ratio:.3f}", ratio >= 0.90],
                [m, "median time per IMF / sifting <= 0.5", f"{time_ratio:.2f}", time_ratio <= 0.5],
            ]
        if cases:
            worst = min(
                min(np.subtract(recovered[(c, m)]["scores"], recovered[(c, "sifting")]["scores"]))
                for c in cases
                if (c, m) in recovered
            )
            rows.append([m, "worst component vs sifting >= -0.02", f"{worst:+.3f}", worst >= -0.02])
            strips = [c for c in cases if (c, "PyEMD EMD") in recovered and ("chirp" in c or "AM" in c)]
            if strips:
                gap = min(
                    min(np.subtract(recovered[(c, m)]["scores"], recovered[(c, "PyEMD EMD")]["scores"])) for c in strips
                )
                rows.append([m, "chirp and AM-FM strips vs PyEMD >= -0.02", f"{gap:+.3f}", gap >= -0.02])
        bumps = [r for r in records.get("bumps", []) if r["config"] == m and r["case"] == "random_bumps"]
        if bumps:
            closer = max(r["closer_fitted"] for r in bumps)
            rows.append([m, "random-bump low-pass closer >= 3x", f"{closer:.2f}", closer >= 3])
        eigen = [r["corr_imf1_high"] for r in records.get("eigen", []) if r["config"] == m]
        if eigen:
            rows.append([m, "two-eigenfunction IMF 1 correlation >= 0.97", f"{min(eigen):.3f}", min(eigen) >= 0.97])
        noise = [x for r in records.get("noise", []) if r["config"] == m for x in r["ratios"]]
        if noise:
            inside = all(2.5 <= x <= 5 for x in noise)
            rows.append([m, "white-noise extrema ratios within 2.5-5", f"{min(noise):.2f}-{max(noise):.2f}", inside])
    return rows


def markdown(records: dict) -> str:
    out = [
        "# Decomposition methods: sifting (defaults) and iterative filtering",
        "",
        f"Machine: {records['machine']}",
        "",
    ]
    if records.get("models"):
        by = {(r["model"], r["config"]): r for r in records["models"]}
        rows = [
            [name, by[(name, "sifting")]["vertices"]]
            + [
                f"{by[(name, m)]['imfs']} / {by[(name, m)]['energy_ratio']:.3f} / {by[(name, m)]['io']:+.3f} / "
                f"{by[(name, m)]['seconds_per_imf']:.2f}"
                for m in CONFIGS
            ]
            for name in dict.fromkeys(r["model"] for r in records["models"])
        ]
        out += [
            "## Models: IMFs / energy ratio / IO / EMD seconds per IMF",
            "",
            table(["model", "vertices", *CONFIGS], rows),
            "",
        ]
    out += ["## Targets", "", table(["method", "target", "measured", "holds"], targets(records)), ""]
    body = bench_quality.markdown({k: v for k, v in records.items() if k != "models"})
    out += body.split("\n")[4:]  # bench_quality's tables of the other parts, without its title
    return "\n".join(out)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--parts", nargs="*", default=["models", "bumps", "noise", "eigen", "recovery"])
    parser.add_argument("--models", nargs="*", default=bench_quality.MODELS)
    args = parser.parse_args()
    records = {"machine": machine()}
    spot = hht3d.load(SPOT)
    for config in CONFIGS:  # warm-up: the first run loads the solver and its libraries
        bench_quality.decompose(spot, np.sin(9 * spot.vertices[:, 0]), config, CONFIGS)
    parts = {
        "models": lambda: bench_quality.part_models(args.models, CONFIGS),
        "bumps": lambda: bench_quality.part_bumps(CONFIGS),
        "noise": lambda: bench_quality.part_noise(CONFIGS),
        "eigen": lambda: bench_quality.part_eigen(CONFIGS),
        "recovery": part_recovery,
    }
    for name in args.parts:
        records[name] = parts[name]()
    records["machine"]["load_average_end"] = machine()["load_average"]
    for path in write_results("methods", records, markdown(records)):
        print(f"wrote {path}")


if __name__ == "__main__":
    main()
