"""Instantaneous frequency benchmark: response to plane waves, calibration, white noise, cost (not a test).

Part 1 — response.  ``estimate / k`` for sampled plane waves ``cos(kx)`` at
64 … 2.2 points per wavelength, with the paper's route
(``frequency="gradient"``, before) and the edge-phase route
(``frequency="phase"``, after), on a flat 128×128 grid mesh of the unit square
(the issue's setting), the same grid with interior vertices jittered by
±0.2 and ±0.3 spacings, the ±0.2 points as a point cloud (no faces), and on
the regular grid a wave at 30° to the axes.  The axis-aligned waves are
``cos(mπx)``, Neumann eigenfunctions of the square, so the continuum Eq. 23
reads ``k = mπ`` everywhere; ``m`` is the integer nearest to the target
points per wavelength (the table gives the actual value).  Statistics over
the vertices at least two spacings from the boundary (0.15 for the oblique
wave, which is not an eigenfunction): the median and the energy-weighted mean
(weights ``a² A_v``, as in the spectrum), p5/p95 in the JSON.

Part 2 — calibration.  The continuum Eq. 23 of analytic patterns evaluated
at 200,000 random points (no mesh: ``f``, ``Rf``, ``∇f`` and ``∇Rf`` in
closed form for sums of plane waves): ``cos kx + cos ky`` and an isotropic
random wave (256 plane waves of wavenumber ``k``, uniform directions and
phases, Gaussian amplitudes); the energy-weighted mean and median of
``ω/k``.  Then Laplacian eigenfunctions of spot (dense eigendecomposition):
the energy-weighted mean of the phase route's ``ω`` over ``√λ``.

Part 3 — white noise.  Gaussian white noise (seed 0) on an icosphere
(2,562 vertices) and a 64×64 grid, decomposed by today's ``hht3d.decomposition.decompose``
(default options, at most 6 IMFs).  Per IMF the energy-weighted mean
frequency of both routes and an independent spectral centroid:
``Σ √λ_i c_i² / Σ c_i²`` from SciPy's dense eigendecomposition of
``L φ = λ M φ`` (icosphere) or
the DCT-I wavenumbers ``π|(i, j)|`` (grid); the RMS wavenumber too.  Target:
means strictly decreasing with the IMF index, each adjacent ratio within 25%
of the centroid ratio.

Part 4 — cost on igea (134k vertices).  The Riesz step ``riesz()`` (spectral
bounds, elliptic quadrature at tol 1e-8, vertex gradients) of 7 and 15
band-passes of the mean curvature (:func:`bench_riesz.band_signals`; igea
decomposes into 7 IMFs), then :func:`hht3d.spectral.frequency.instantaneous_frequency`
of the same signals: the phase route on a fresh surface (building its edge
stencil) and again (cached), and the gradient route.  Plain wall-clock
timers in one process; the ratio to the Riesz step is the figure of merit
(target ≤ 20%).

Usage::

    python -m benchmarks.bench_frequency [--parts response calibration noise cost]
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
import time

import numpy as np

from benchmarks.common import (
    SPOT,
    fixed,
    machine,
    mean_adjacent_distance,
    model_path,
    previous_results,
    table,
    write_results,
)
from benchmarks.meshes import grid, icosphere

PARTS = ("response", "calibration", "noise", "cost")
TARGET_PPW = (64, 16, 8, 5.3, 4, 3.2, 2.6, 2.2)
GRID = 128
METHODS = ("gradient", "phase")
SEED = 0


# -- part 1: response to plane waves ---------------------------------------------------------------


def _response(surface, signals, wavenumbers, mask) -> dict:
    from hht3d.spectral import fractional_laplacian
    from hht3d.spectral.monogenic_signal import monogenic_from_potential

    potential = fractional_laplacian(surface, signals)
    out = {}
    for method in METHODS:
        mono = monogenic_from_potential(surface, signals, potential, frequency=method)
        ratio = mono.frequency[:, mask] / wavenumbers[:, None]
        weight = (mono.amplitude**2 * surface.mass_diagonal)[:, mask]
        out[method] = {
            "median": np.median(ratio, axis=1).tolist(),
            "energy_mean": ((weight * ratio).sum(axis=1) / weight.sum(axis=1)).tolist(),
            "p5": np.percentile(ratio, 5, axis=1).tolist(),
            "p95": np.percentile(ratio, 95, axis=1).tolist(),
            "increasing": bool(np.all(np.diff(np.median(mono.frequency[:, mask], axis=1)) > 0)),
        }
    return out


def run_response() -> dict:
    from hht3d.geometry.surface import Surface

    h = 1.0 / (GRID - 1)
    modes = np.array([round(2 * (GRID - 1) / p) for p in TARGET_PPW])
    wavenumbers = modes * np.pi
    ppw = 2 * (GRID - 1) / modes
    cases = {}
    for label, jitter, faces in (
        ("grid", 0.0, True),
        ("jittered grid ±0.2", 0.2, True),
        ("jittered grid ±0.3", 0.3, True),
        ("point cloud ±0.2", 0.2, False),
    ):
        v, f = grid(GRID, GRID, jitter=jitter, seed=SEED)
        s = Surface(v, f) if faces else Surface(v, None, normals=np.tile([0.0, 0.0, 1.0], (len(v), 1)))
        x, y = s.vertices[:, 0], s.vertices[:, 1]
        mask = (np.minimum(x, 1 - x) > 1.5 * h) & (np.minimum(y, 1 - y) > 1.5 * h)
        t0 = time.perf_counter()
        cases[label] = _response(s, np.cos(wavenumbers[:, None] * x), wavenumbers, mask)
        cases[label]["seconds"] = time.perf_counter() - t0
        print(f"  response: {label} ({cases[label]['seconds']:.1f} s)", flush=True)
    s = Surface(*grid(GRID, GRID))
    x, y = s.vertices[:, 0], s.vertices[:, 1]
    oblique = 2 * np.pi / (np.array(TARGET_PPW) * h)
    direction = np.array([np.cos(np.pi / 6), np.sin(np.pi / 6)])
    mask = (np.minimum(x, 1 - x) > 0.15) & (np.minimum(y, 1 - y) > 0.15)
    cases["grid, 30° wave"] = _response(s, np.cos(oblique[:, None] * (s.vertices[:, :2] @ direction)), oblique, mask)
    return {"points_per_wavelength": ppw.tolist(), "oblique_points_per_wavelength": list(TARGET_PPW), "cases": cases}


# -- part 2: calibration of Eq. 23 --------------------------------------------------------------


def _continuum_eq23(points, wavevectors, phases, amplitudes) -> tuple[np.ndarray, np.ndarray]:
    """Eq. 23 and the energy f² + |Rf|² of Σ a cos(k·x + β) at points (closed form)."""
    k = np.linalg.norm(wavevectors, axis=1)
    theta = points @ wavevectors.T + phases
    cos, sin = amplitudes * np.cos(theta), amplitudes * np.sin(theta)
    unit = wavevectors / k[:, None]
    f = cos.sum(axis=1)
    r = -sin @ unit  # R cos(k·x) = −sin(k·x) k/|k|
    grad_f = -sin @ wavevectors
    jac = -np.einsum("pw,wc,wg->pcg", cos, unit, wavevectors)  # ∂_g (Rf)_c
    q = np.linalg.norm(r, axis=1)
    grad_q = np.einsum("pcg,pc->pg", jac, r / q[:, None])
    energy = f**2 + q**2
    return np.linalg.norm(f[:, None] * grad_q - q[:, None] * grad_f, axis=1) / energy, energy


def run_calibration() -> dict:
    from hht3d import load
    from hht3d.spectral.monogenic_signal import monogenic

    rng = np.random.default_rng(SEED)
    points = rng.uniform(0, 200, (200_000, 2))
    out = {}
    two = np.array([[1.0, 0.0], [0.0, 1.0]])
    waves = {"cos kx + cos ky": (two, np.zeros(2), np.ones(2))}
    angles = rng.uniform(0, 2 * np.pi, 256)
    waves["isotropic random wave"] = (
        np.c_[np.cos(angles), np.sin(angles)],
        rng.uniform(0, 2 * np.pi, 256),
        rng.standard_normal(256),
    )
    for name, (vectors, phases, amplitudes) in waves.items():
        omega, energy = _continuum_eq23(points, vectors, phases, amplitudes)
        order = np.argsort(omega)
        weighted_median = omega[order][np.searchsorted(np.cumsum(energy[order]), energy.sum() / 2)]
        out[name] = {
            "energy_mean": float((energy * omega).sum() / energy.sum()),
            "mean": float(omega.mean()),
            "median": float(np.median(omega)),
            "energy_median": float(weighted_median),
        }
    path = model_path("spot") or SPOT
    spot = load(path)
    values, vectors = _eigenpairs(spot)
    index = np.array([5, 20, 50, 100, 200, 400, 800])
    mono = monogenic(spot, vectors[:, index].T)
    weight = mono.amplitude**2 * spot.mass_diagonal
    mean = (weight * mono.frequency).sum(axis=1) / weight.sum(axis=1)
    edge = mean_adjacent_distance(spot)
    out["spot eigenfunctions"] = {
        "index": index.tolist(),
        "sqrt_lambda": np.sqrt(values[index]).tolist(),
        "points_per_wavelength": (2 * np.pi / np.sqrt(values[index]) / edge).tolist(),
        "ratio": (mean / np.sqrt(values[index])).tolist(),
    }
    return out


# -- part 3: white noise ------------------------------------------------------------------------


def _eigenpairs(surface) -> tuple[np.ndarray, np.ndarray]:
    """Non-zero eigenpairs of L φ = λ M φ by SciPy's dense solver (M-orthonormal φ)."""
    import scipy.linalg

    values, vectors = scipy.linalg.eigh(surface.stiffness.toarray(), np.diag(surface.mass_diagonal))
    return values[1:], vectors[:, 1:]


def _centroids_eigen(surface, imfs) -> tuple[np.ndarray, np.ndarray]:
    values, vectors = _eigenpairs(surface)
    power = ((imfs * surface.mass_diagonal) @ vectors) ** 2
    return (power @ np.sqrt(values)) / power.sum(axis=1), np.sqrt((power @ values) / power.sum(axis=1))


def _centroids_dct(imfs, n) -> tuple[np.ndarray, np.ndarray]:
    import scipy.fft

    wavenumber = np.pi * np.hypot(*np.meshgrid(np.arange(n), np.arange(n), indexing="ij"))
    power = np.stack([scipy.fft.dctn(f.reshape(n, n), type=1, norm="ortho") ** 2 for f in imfs])
    power[:, 0, 0] = 0
    return (
        (power * wavenumber).sum(axis=(1, 2)) / power.sum(axis=(1, 2)),
        np.sqrt((power * wavenumber**2).sum(axis=(1, 2)) / power.sum(axis=(1, 2))),
    )


def run_noise() -> dict:
    from hht3d.decomposition import emd
    from hht3d.geometry.surface import Surface
    from hht3d.spectral import fractional_laplacian
    from hht3d.spectral.monogenic_signal import monogenic_from_potential
    from hht3d.spectral.spectrum import HilbertSpectrum

    rng = np.random.default_rng(SEED)
    out = {}
    n = 64
    for label, surface, reference in (
        ("icosphere (2,562 V), eigendecomposition", Surface(*icosphere(4)), "eigen"),
        (f"{n}x{n} grid, DCT", Surface(*grid(n, n)), "dct"),
    ):
        t0 = time.perf_counter()
        decomposition = emd(surface, rng.standard_normal(surface.n_vertices), max_imfs=6)
        imfs = decomposition.imfs
        centroid, rms = _centroids_eigen(surface, imfs) if reference == "eigen" else _centroids_dct(imfs, n)
        potential = fractional_laplacian(surface, imfs)
        record = {
            "imfs": len(imfs),
            "centroid": centroid.tolist(),
            "rms": rms.tolist(),
            "centroid_ratio": (centroid[:-1] / centroid[1:]).tolist(),
        }
        for method in METHODS:
            mono = monogenic_from_potential(surface, imfs, potential, frequency=method)
            spectrum = HilbertSpectrum.from_monogenic(surface, mono)
            mean = spectrum.mean_frequency()
            ratio = mean[:-1] / mean[1:]
            record[method] = {
                "mean": mean.tolist(),
                "ratio": ratio.tolist(),
                "decreasing": bool(np.all(np.diff(mean) < 0)),
                "within_25pct": bool(np.all(np.abs(ratio / record["centroid_ratio"] - 1) <= 0.25)),
                "unresolved_energy_share": spectrum.resolution.energy_share,
            }
        record["seconds"] = time.perf_counter() - t0
        out[label] = record
        print(f"  noise: {label} ({record['seconds']:.1f} s)", flush=True)
    return out


# -- part 4: cost on igea -------------------------------------------------------------------------


@contextlib.contextmanager
def single_thread():
    """``OMP_NUM_THREADS=1`` for the duration: the phase route reads the signals in one thread."""
    saved = os.environ.get("OMP_NUM_THREADS")
    os.environ["OMP_NUM_THREADS"] = "1"
    try:
        yield
    finally:
        if saved is None:
            del os.environ["OMP_NUM_THREADS"]
        else:
            os.environ["OMP_NUM_THREADS"] = saved


def run_cost() -> dict:
    from benchmarks.bench_riesz import band_signals
    from hht3d import load
    from hht3d.spectral import riesz
    from hht3d.spectral.frequency import instantaneous_frequency

    path = model_path("igea")
    if path is None:
        return {"skipped": "igea.ply not present"}
    signals = band_signals(load(path))
    out = {}
    for count in (7, 15):
        surface = load(path)  # fresh: no cached bounds, factorizations or stencils
        surface.stiffness, surface.gradient("lsq")
        f = signals[:count]
        t0 = time.perf_counter()
        r = riesz(surface, f)
        t1 = time.perf_counter()
        instantaneous_frequency(surface, f, r)
        t2 = time.perf_counter()
        instantaneous_frequency(surface, f, r)
        t3 = time.perf_counter()
        instantaneous_frequency(surface, f, r, method="gradient")
        t4 = time.perf_counter()
        with single_thread():  # the phase route's own threads only: MKL read its setting at start
            instantaneous_frequency(surface, f, r)
        t5 = time.perf_counter()
        riesz_s = t1 - t0
        out[str(count)] = {
            "vertices": surface.n_vertices,
            "riesz_s": riesz_s,
            "phase_first_s": t2 - t1,
            "phase_cached_s": t3 - t2,
            "gradient_s": t4 - t3,
            "phase_one_thread_s": t5 - t4,
            "phase_first_ratio": (t2 - t1) / riesz_s,
            "phase_cached_ratio": (t3 - t2) / riesz_s,
            "gradient_ratio": (t4 - t3) / riesz_s,
        }
        print(f"  cost: {count} signals: Riesz {riesz_s:.1f} s, phase {t2 - t1:.2f} s", flush=True)
    return out


# -- report ----------------------------------------------------------------------------------------


def markdown(records: dict) -> str:
    meta = records["machine"]
    lines = [
        "# Instantaneous frequency benchmark",
        "",
        f"Machine: {meta['platform']}; {meta['cpus']} CPUs shared with other jobs (load average "
        f"{meta['load_average']}); backend `{meta['backend']}`; Python {meta['python']}.  Generated by "
        "`python -m benchmarks.bench_frequency`; the method is in its docstring.",
        "",
    ]
    response = records.get("response")
    if response:
        lines += [
            "## Response to plane waves: estimate / k",
            "",
            "Median over the vertices two spacings or more from the boundary (energy-weighted mean in "
            'brackets).  *before*: `frequency="gradient"` (the paper\'s Eq. 23 by vertex gradients); '
            '*after*: `frequency="phase"` (the default).  Target: within 5% from 64 to 3 points per '
            "wavelength, strictly increasing up to 2.2.",
            "",
        ]
        ppw = response["points_per_wavelength"]
        header = ["case", "route"] + [f"{p:.3g}" for p in ppw] + ["increasing"]
        rows = []
        for label, case in response["cases"].items():
            for method, name in (("gradient", "before"), ("phase", "after")):
                c = case[method]
                rows.append(
                    [label, name]
                    + [f"{m:.2f} ({e:.2f})" for m, e in zip(c["median"], c["energy_mean"])]
                    + ["yes" if c["increasing"] else "no"]
                )
        lines += [
            table(header, rows),
            "",
            "Points per wavelength: the axis-aligned waves are `cos(mπx)` with the integer `m` nearest the "
            f"targets {list(TARGET_PPW)} (values in the header); the 30° wave is at the targets exactly.",
            "",
        ]
    calibration = records.get("calibration")
    if calibration:
        lines += [
            "## Calibration: what Eq. 23 reads",
            "",
            "Continuum Eq. 23 of analytic patterns over 200,000 random points, relative to the wavenumber "
            "`k` (1 for any wave varying in one direction):",
            "",
            table(
                ["pattern", "energy-weighted mean ω/k", "energy-weighted median", "mean", "median"],
                [
                    [
                        name,
                        fixed(c["energy_mean"], 3),
                        fixed(c["energy_median"], 3),
                        fixed(c["mean"], 3),
                        fixed(c["median"], 3),
                    ]
                    for name, c in calibration.items()
                    if name != "spot eigenfunctions"
                ],
            ),
            "",
        ]
        spot = calibration["spot eigenfunctions"]
        lines += [
            "Laplacian eigenfunctions φ_i of spot, phase route: energy-weighted mean ω over √λ_i:",
            "",
            table(
                ["i", "√λ", "points per wavelength", "ω / √λ"],
                [
                    [i, fixed(s, 1), fixed(p, 1), fixed(r, 3)]
                    for i, s, p, r in zip(
                        spot["index"], spot["sqrt_lambda"], spot["points_per_wavelength"], spot["ratio"]
                    )
                ],
            ),
            "",
        ]
    noise = records.get("noise")
    if noise:
        lines += [
            "## White noise: IMF mean frequencies",
            "",
            "Energy-weighted mean frequency per IMF and adjacent ratios IMF_i / IMF_{i+1}, against the "
            "spectral-centroid ratio of an independent transform.  Target: strictly decreasing, each "
            "ratio within 25% of the centroid ratio.  EMD with its defaults (tension envelopes, cancellation "
            "guard, local-mean correction).",
            "",
        ]
        rows = []
        for label, c in noise.items():
            rows.append(
                [
                    label,
                    "centroid (reference)",
                    " / ".join(fixed(x, 1) for x in c["centroid"]),
                    " / ".join(fixed(x) for x in c["centroid_ratio"]),
                    "",
                    "",
                ]
            )
            for method, name in (("gradient", "before"), ("phase", "after")):
                m = c[method]
                rows.append(
                    [
                        label,
                        name,
                        " / ".join(fixed(x, 1) for x in m["mean"]),
                        " / ".join(fixed(x) for x in m["ratio"]),
                        "yes" if m["decreasing"] else "no",
                        "yes" if m["within_25pct"] else "no",
                    ]
                )
        lines += [
            table(["surface", "route", "mean ω per IMF", "adjacent ratios", "decreasing", "within 25%"], rows),
            "",
        ]
    cost = records.get("cost")
    if cost and "skipped" not in cost:
        lines += [
            "## Cost on igea (134k vertices)",
            "",
            "Riesz step: `riesz()` on a freshly loaded surface (bounds, quadrature, gradients).  Phase route "
            "first call (edge stencil built), cached, and cached on one thread (`OMP_NUM_THREADS=1`, the "
            "baseline of its thread per signal); gradient route.  Ratios to the Riesz step in the same run; "
            "target ≤ 20%.",
            "",
        ]
        lines += [
            table(
                [
                    "signals",
                    "Riesz s",
                    "phase s (first)",
                    "phase s (cached)",
                    "phase s (1 thread)",
                    "gradient s",
                    "phase / Riesz (first)",
                    "phase / Riesz (cached)",
                    "1 thread / threads",
                ],
                [
                    [
                        k,
                        fixed(c["riesz_s"], 1),
                        fixed(c["phase_first_s"]),
                        fixed(c["phase_cached_s"]),
                        fixed(c.get("phase_one_thread_s"), missing=""),
                        fixed(c["gradient_s"]),
                        f"{100 * c['phase_first_ratio']:.0f}%",
                        f"{100 * c['phase_cached_ratio']:.0f}%",
                        fixed(c["phase_one_thread_s"] / c["phase_cached_s"]) if "phase_one_thread_s" in c else "",
                    ]
                    for k, c in cost.items()
                ],
            ),
            "",
        ]
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--parts", nargs="+", choices=PARTS, default=list(PARTS))
    args = parser.parse_args(argv)
    records = previous_results("frequency")
    runners = {"response": run_response, "calibration": run_calibration, "noise": run_noise, "cost": run_cost}
    for part in args.parts:
        print(f"{part} ...", flush=True)
        records[part] = runners[part]()
    records["machine"] = machine()
    for path in write_results("frequency", records, markdown(records)):
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
