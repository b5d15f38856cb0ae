"""Decomposition quality before and after the defaults of issue "Trustworthy decompositions".

*Before* is the paper's method as hht3d ran it until then: thin-plate envelopes
without guard or local-mean correction (``hht3d.decomposition.PAPER_OPTIONS``), the
pointwise mean curvature of Eq. 24 (``min_area=0``) and the fixed Eq. 27
weights 0.01 / 1.0.  *After* is today's defaults.  Both run in the same
process, so time ratios compare like with like.

Parts (``--parts``):

``models``     every model of ../shared/data: IMFs, energy ratio, IO, signal
               spike, factorizations and EMD seconds per IMF (targets: energy
               ratio <= 1.5 and IO >= -0.25 everywhere; per-IMF time).
``slivers``    unit spheres with 200 needle vertices (``benchmarks/meshes.py``
               ``sliver_sphere``): largest error of 2H and K against 2 and 1,
               Gauss–Bonnet, and the decomposition's energy ratio.
``bumps``      unit sphere with 60 random Gaussian bumps (σ 0.05–0.12, peaks
               0.5–2%): a Hilbert-spectrum low-pass with Eq. 27, RMS distance
               to the clean sphere (radial, and to the best-fitting sphere,
               since curvature cannot see a translation) and volume change
               (target: >= 3x closer, volume within 1%); and the mixed-width
               sphere of ``benchmarks/meshes.py`` ``random_bump_sphere``.
``noise``      white noise on an icosphere (10,242 vertices) and a 128x128
               grid: drop of the extrema count from IMF to IMF (target 2.5-5).
``eigen``      the sum of two Laplacian eigenfunctions with eigenvalue ratio
               10-30 on spot and on the face scan: correlation of IMF 1 with
               the higher one (target >= 0.97).
``strip``      1-D reduction: a cylinder carrying a signal along its axis with
               the paper's options against PyEMD (target: correlation >= 0.99
               for IMFs 1-2 away from the ends).
``recovery``   known components (``recovery.py``): strips against PyEMD's EMD,
               EEMD and CEEMDAN, bumps of two and three widths, Laplacian
               eigenfunctions, curvature plus noise; the paper's options, the
               defaults and EEMD on the surfaces (targets: strips >= PyEMD's EMD
               - 0.01, no case below the paper's options by more than 0.02).

Run from the repository root::

    python -m benchmarks.bench_quality [--parts models slivers ...] [--models spot igea ...]

Writes ``benchmarks/results/quality.json`` and ``quality.md``.
"""

from __future__ import annotations

import argparse
import dataclasses
import time
import warnings

import numpy as np
import scipy.sparse.linalg as spla

import hht3d
from benchmarks import recovery
from benchmarks.common import DATA, SPOT, machine, model_or_skip, table, write_results
from benchmarks.meshes import grid, icosphere, open_cylinder, random_bump_sphere, sliver_sphere
from hht3d import Surface, emd, hht
from hht3d.apps import LowPass, filter_geometry
from hht3d.decomposition import EMD_DEFAULTS, PAPER_OPTIONS, local_extrema
from hht3d.geometry.signals import gaussian_curvature, mean_curvature

MODELS = [
    "spot",
    "sphere_oct4098",
    "spacetime_face_neutral",
    "rocker_arm",
    "bunny_zipper",
    "nefertiti",
    "office_kinect_colored",
    "igea",
    "dragon_vrip",
    "bunny_scan_bun000",
    "bunny_scans_merged",
]
#: name -> (EMD options, curvature min_area, Eq. 27 weights or None for the default)
CONFIGS = {
    "before": (PAPER_OPTIONS, 0.0, {"interior_weight": 0.01, "boundary_weight": 1.0}),
    "after": (EMD_DEFAULTS, None, {}),
}


def curvature(surface: Surface, config: str, configs: dict = CONFIGS) -> np.ndarray:
    min_area = configs[config][1]
    return mean_curvature(surface) if min_area is None else mean_curvature(surface, min_area=min_area)


def decompose(surface: Surface, signal, config: str, configs: dict = CONFIGS, **options):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the quality figures are the measurement here
        return emd(surface, signal, configs[config][0], **options)


def part_models(names, configs: dict = CONFIGS) -> list[dict]:
    rows = []
    for name in names:
        path = model_or_skip(name)
        if path is None:
            continue
        surface = hht3d.load(path)
        for config in configs:
            signal = curvature(surface, config, configs)
            start = time.perf_counter()
            result = decompose(surface, signal, config, configs)
            seconds = time.perf_counter() - start
            q = result.quality
            rows.append(
                {
                    "model": name,
                    "config": config,
                    "vertices": surface.n_vertices,
                    "imfs": result.n_imfs,
                    "energy_ratio": q.energy_ratio,
                    "io": q.orthogonality_index,
                    "io_leaking": q.io_leaking,
                    "io_cancelling": q.io_cancelling,
                    "spike": q.signal_spike,
                    "factorizations": result.info["factorizations"],
                    "seconds": seconds,
                    "seconds_per_imf": seconds / max(result.n_imfs, 1),
                }
            )
            print(rows[-1], flush=True)
    return rows


def part_slivers(configs: dict = CONFIGS) -> list[dict]:
    rows = []
    for kind in ("edge", "corner"):
        surface = Surface(*sliver_sphere(kind=kind), name=f"sliver_sphere_{kind}")
        area = surface.mass_diagonal
        for config in configs:
            min_area = configs[config][1]
            options = {} if min_area is None else {"min_area": min_area}
            h, k = mean_curvature(surface, **options), gaussian_curvature(surface, **options)
            result = decompose(surface, h, config, configs)
            rows.append(
                {
                    "mesh": surface.name,
                    "config": config,
                    "min_area_over_median": float(area.min() / np.median(area)),
                    "max_error_2H": float(np.abs(h - 2).max()),
                    "max_error_K": float(np.abs(k - 1).max()),
                    "gauss_bonnet": float(k @ area / (4 * np.pi)),
                    "spike": result.quality.signal_spike,
                    "energy_ratio": result.quality.energy_ratio,
                    "io": result.quality.orthogonality_index,
                }
            )
            print(rows[-1], flush=True)
    return rows


def _bump_sphere(seed: int = 3, count: int = 60):
    rng = np.random.default_rng(seed)
    clean, faces = icosphere(5)
    centres = rng.normal(size=(count, 3))
    centres /= np.linalg.norm(centres, axis=1, keepdims=True)
    sigma = rng.uniform(0.05, 0.12, count)
    peak = rng.uniform(0.005, 0.02, count) * rng.choice([-1, 1], count)
    angle = np.arccos(np.clip(clean @ centres.T, -1, 1))
    return clean * (1 + (np.exp(-(angle**2) / (2 * sigma**2)) * peak).sum(axis=1))[:, None], faces


def _sphere_distances(surface: Surface, vertices: np.ndarray) -> tuple[float, float]:
    """Area-weighted RMS distance to the unit sphere and to the best-fitting sphere."""
    area = surface.mass_diagonal
    radial = np.sqrt(area @ (np.linalg.norm(vertices, axis=1) - 1) ** 2 / area.sum())
    design = np.c_[2 * vertices, np.ones(len(vertices))] * np.sqrt(area)[:, None]
    solution = np.linalg.lstsq(design, (vertices**2).sum(axis=1) * np.sqrt(area), rcond=None)[0]
    centre, radius = solution[:3], np.sqrt(solution[3] + solution[:3] @ solution[:3])
    fitted = np.sqrt(area @ (np.linalg.norm(vertices - centre, axis=1) - radius) ** 2 / area.sum())
    return float(radial), float(fitted)


def _volume(vertices, faces) -> float:
    v = vertices[faces]
    return float(np.einsum("ij,ij->i", v[:, 0], np.cross(v[:, 1], v[:, 2])).sum() / 6)


def part_bumps(configs: dict = CONFIGS) -> list[dict]:
    rows = []
    vertices, faces = _bump_sphere()
    surface = Surface(vertices, faces, name="random_bumps")
    clean_volume = _volume(vertices / np.linalg.norm(vertices, axis=1, keepdims=True), faces)
    radial0, fitted0 = _sphere_distances(surface, vertices)
    for config in configs:
        options, _, weights = configs[config]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = hht(surface, curvature(surface, config, configs), **options.as_dict())
            for cutoff in (3.0, 4.0, 6.0):
                out = filter_geometry(result, LowPass(cutoff=cutoff, width=cutoff / 3), **weights)
                radial, fitted = _sphere_distances(surface, out.vertices)
                rows.append(
                    {
                        "case": "random_bumps",
                        "config": config,
                        "cutoff": cutoff,
                        "energy_ratio": result.quality.energy_ratio,
                        "closer_radial": radial0 / radial,
                        "closer_fitted": fitted0 / fitted,
                        "volume_change_percent": 100 * (_volume(out.vertices, faces) / clean_volume - 1),
                        "volume_change_before_percent": 100 * (_volume(vertices, faces) / clean_volume - 1),
                        "max_move_over_diagonal": float(
                            np.abs(out.vertices - vertices).max() / surface.bounding_box_diagonal
                        ),
                    }
                )
                print(rows[-1], flush=True)
    v, f, narrow, wide = random_bump_sphere()
    mixed = Surface(v, f, name="mixed_bumps")
    basis = np.c_[narrow, wide]
    area = mixed.mass_diagonal
    for config in configs:
        options, _, weights = configs[config]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = hht(mixed, curvature(mixed, config, configs), **dataclasses.replace(options, max_imfs=6).as_dict())
            out = filter_geometry(result, LowPass(cutoff=6.0, width=2.0), **weights)
        deviation = np.linalg.norm(out.vertices, axis=1) - 1
        kept = np.linalg.solve(basis.T @ (area[:, None] * basis), basis.T @ (area * deviation))
        rows.append(
            {
                "case": "mixed_bumps",
                "config": config,
                "cutoff": 6.0,
                "energy_ratio": result.quality.energy_ratio,
                "kept_narrow": float(kept[0]),
                "kept_wide": float(kept[1]),
            }
        )
        print(rows[-1], flush=True)
    return rows


def part_noise(configs: dict = CONFIGS) -> list[dict]:
    rows = []
    for surface in (Surface(*icosphere(5), name="icosphere"), Surface(*grid(128, 128), name="grid")):
        noise = np.random.default_rng(0).standard_normal(surface.n_vertices)
        for config in configs:
            result = decompose(surface, noise, config, configs)
            counts = [sum(map(len, local_extrema(surface, imf))) for imf in result.imfs]
            ratios = [counts[i] / counts[i + 1] for i in range(len(counts) - 1) if counts[i + 1] >= 50]
            rows.append(
                {
                    "mesh": surface.name,
                    "config": config,
                    "extrema": counts,
                    "ratios": ratios,
                    "energy_ratio": result.quality.energy_ratio,
                }
            )
            print(rows[-1], flush=True)
    return rows


def part_eigen(configs: dict = CONFIGS) -> list[dict]:
    rows = []
    for name, path, pairs in (
        ("spot", SPOT, [(3, 40), (5, 100)]),
        ("spacetime_face_neutral", DATA / "spacetime_face_neutral.ply", [(3, 40), (6, 110)]),
    ):
        if not path.is_file():
            continue
        surface = hht3d.load(path)
        values, vectors = spla.eigsh(
            surface.stiffness,
            k=max(b for _, b in pairs) + 1,
            M=surface.mass,
            sigma=-1e-8,
            v0=np.ones(surface.n_vertices),
        )  # eigsh's random start flips signs
        for low, high in pairs:
            fine = vectors[:, high] / np.abs(vectors[:, high]).max()
            for sign, config in ((sign, config) for sign in (1, -1) for config in configs):
                signal = vectors[:, low] / np.abs(vectors[:, low]).max() + sign * fine
                imf = decompose(surface, signal, config, configs).imfs[0]
                rows.append(
                    {
                        "model": name,
                        "pair": [low, sign * high],
                        "eigenvalue_ratio": float(values[high] / values[low]),
                        "config": config,
                        "corr_imf1_high": float(abs(np.corrcoef(imf, fine)[0, 1])),
                    }
                )
                print(rows[-1], flush=True)
    return rows


def part_strip() -> list[dict]:
    from PyEMD import EMD

    n_axial = 801
    surface = Surface(*open_cylinder(n_axial, 8, length=10.0, radius=0.1), name="cylinder")
    z = np.linspace(0.0, 10.0, n_axial)

    def axial(x):
        return (
            np.sin(2 * np.pi * 2.1 * x) + 0.8 * np.sin(2 * np.pi * 0.47 * x + 0.3) + 0.5 * np.sin(2 * np.pi * 0.09 * x)
        )

    result = emd(surface, axial(surface.vertices[:, 2]), PAPER_OPTIONS, stopping="fixed", fixed_sifts=10)
    reference = EMD(FIXE=10).emd(axial(z), z)
    rings = result.imfs.reshape(result.n_imfs, n_axial, 8)[:, :, 0]
    inner = slice(n_axial // 10, n_axial - n_axial // 10)
    return [
        {
            "imf": k + 1,
            "corr_all": float(np.corrcoef(rings[k], reference[k])[0, 1]),
            "corr_interior": float(np.corrcoef(rings[k, inner], reference[k][inner])[0, 1]),
        }
        for k in range(2)
    ]


def markdown(records: dict) -> str:
    out = [
        "# Decomposition quality: the paper's EMD (before) and today's defaults (after)",
        "",
        f"Machine: {records['machine']}",
        "",
    ]
    if records.get("models"):
        by = {(r["model"], r["config"]): r for r in records["models"]}
        rows = []
        for name in dict.fromkeys(r["model"] for r in records["models"]):
            b, a = by[(name, "before")], by[(name, "after")]
            rows.append(
                [
                    name,
                    a["vertices"],
                    f"{b['imfs']} / {a['imfs']}",
                    f"{b['energy_ratio']:.3g} / {a['energy_ratio']:.3g}",
                    f"{b['io']:.3g} / {a['io']:.3g}",
                    f"{b['io_leaking']:+.2f} {b['io_cancelling']:+.2f} / "
                    f"{a['io_leaking']:+.2f} {a['io_cancelling']:+.2f}",
                    f"{b['spike']:.3g} / {a['spike']:.3g}",
                    f"{b['seconds_per_imf']:.2f} / {a['seconds_per_imf']:.2f}",
                    f"{a['seconds_per_imf'] / b['seconds_per_imf']:.2f}",
                ]
            )
        out += [
            "## Models (before / after)",
            "",
            table(
                [
                    "model",
                    "vertices",
                    "IMFs",
                    "energy ratio",
                    "IO",
                    "IO leaking, cancelling",
                    "signal spike",
                    "EMD s per IMF",
                    "time ratio per IMF",
                ],
                rows,
            ),
            "",
        ]
    if records.get("recovery"):
        out += [
            "## Component recovery (`recovery.py`)",
            "",
            "Best correlation of each true component with an IMF, an adjacent pair or a tail "
            "(single: one IMF or the residue).",
            "",
            table(
                ["case", "method", "IMFs", "scores", "single", "IO"],
                [
                    [
                        r["case"],
                        r["method"],
                        r["imfs"],
                        ", ".join(f"{x:.3f}" for x in r["scores"]),
                        ", ".join(f"{x:.3f}" for x in r["single"]),
                        f"{r['io']:+.3f}" if "io" in r else "",
                    ]
                    for r in records["recovery"]
                ],
            ),
            "",
        ]
    for part, title in (
        ("slivers", "Sliver spheres"),
        ("bumps", "Bump spheres: low-pass + Eq. 27"),
        ("noise", "White noise: extrema count ratio between consecutive IMFs"),
        ("eigen", "Two eigenfunctions: IMF 1 against the higher one"),
        ("strip", "Strip against PyEMD (paper options)"),
    ):
        if records.get(part):
            keys = list(dict.fromkeys(k for r in records[part] for k in r))  # rows of a part may differ
            rows = [
                [
                    (
                        f"{v:.3g}"
                        if isinstance(v, float)
                        else "[" + ", ".join(f"{x:.2f}" if isinstance(x, float) else str(x) for x in v) + "]"
                        if isinstance(v, list)
                        else ""
                        if v is None
                        else v
                    )
                    for v in (r.get(k) for k in keys)
                ]
                for r in records[part]
            ]
            out += [f"## {title}", "", table(keys, rows), ""]
    return "\n".join(out)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--parts", nargs="*", default=["models", "slivers", "bumps", "noise", "eigen", "strip", "recovery"]
    )
    parser.add_argument("--models", nargs="*", default=MODELS)
    args = parser.parse_args()
    records = {"machine": machine()}
    parts = {
        "models": lambda: part_models(args.models),
        "slivers": part_slivers,
        "bumps": part_bumps,
        "noise": part_noise,
        "eigen": part_eigen,
        "strip": part_strip,
        "recovery": lambda: recovery.part_recovery(SPOT, DATA / "spacetime_face_neutral.ply"),
    }
    for name in args.parts:
        records[name] = parts[name]()
    records["machine"]["load_average_end"] = machine()["load_average"]
    for path in write_results("quality", records, markdown(records)):
        print(f"wrote {path}")


if __name__ == "__main__":
    main()
