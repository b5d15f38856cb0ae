"""Component recovery: signals whose true components are known, and how well each method finds them.

Each case is a surface, a signal and its components.  A method's score for a
component is the largest area-weighted correlation between that component and
one *candidate*: an IMF, the sum of two adjacent IMFs, or a tail (IMF ``k``
onward plus the residue, for the slowest components), all taken as
fluctuations about the mean.  Strips (600 × 3 vertices on ``[0, 1] × [0,
2/599]``) carry signals of ``x`` only, so 1-D EMD (PyEMD's EMD, EEMD and
CEEMDAN, cubic splines, mirrored ends) on the 600 samples is the reference
that knows nothing of surfaces.

Used by ``python -m benchmarks.bench_quality --parts recovery``.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import scipy.sparse.linalg as spla

import hht3d
from benchmarks.meshes import grid, icosphere
from hht3d import Surface, eemd, emd
from hht3d.decomposition import EMD_DEFAULTS, PAPER_OPTIONS
from hht3d.geometry.signals import fluctuation, mean_curvature

#: Members of every ensemble method here (EEMD on surfaces, PyEMD's EEMD and CEEMDAN).
ENSEMBLE = 50
#: Strip samples along x.
STRIP = 600


@dataclass
class Case:
    name: str
    surface: Surface
    components: list[np.ndarray]
    trend: np.ndarray | None = None
    x: np.ndarray | None = None  # strips: the 1-D abscissa of each vertex

    @property
    def signal(self) -> np.ndarray:
        return sum(self.components) + (0.0 if self.trend is None else self.trend)


def _strip(name: str, components, trend=None) -> Case:
    vertices, faces = grid(STRIP, 3, 1.0, 2 / (STRIP - 1))
    x = vertices[:, 0]
    return Case(
        name, Surface(vertices, faces, name=name), [c(x) for c in components], None if trend is None else trend(x), x
    )


def _hann(x, a, b):
    inside = (x > a) & (x < b)
    return np.where(inside, np.sin(np.pi * (x - a) / (b - a)) ** 2, 0.0)


def strip_cases() -> list[Case]:
    tau = 2 * np.pi
    return [
        _strip(
            "strip: three tones + ramp",
            [
                lambda x: np.sin(tau * 40 * x),
                lambda x: 0.8 * np.sin(tau * 9 * x + 0.3),
                lambda x: 0.5 * np.sin(tau * 2 * x),
            ],
            lambda x: x,
        ),
        _strip(
            "strip: AM tone + FM chirp",
            [
                lambda x: (1 + 0.5 * np.cos(tau * 1.5 * x)) * np.sin(tau * 50 * x),
                lambda x: 0.7 * np.sin(tau * (6 * x + 5 * x**2)),
            ],
            lambda x: 0.3 * x,
        ),
        _strip(
            "strip: linear chirp 6→62 cycles + tone 3",
            [lambda x: np.sin(tau * (6 * x + 28 * x**2)), lambda x: 0.8 * np.sin(tau * 3 * x + 0.4)],
        ),
        _strip(
            "strip: bursts + two tones",
            [
                lambda x: (_hann(x, 0.15, 0.35) + _hann(x, 0.55, 0.8)) * np.sin(tau * 60 * x),
                lambda x: np.sin(tau * 6 * x),
                lambda x: 0.5 * np.sin(tau * 1.5 * x),
            ],
        ),
    ]


def _bumps(points: np.ndarray, widths, counts, seed: int) -> list[np.ndarray]:
    """One component per width: a sum of Gaussian bumps of random sign at random vertices."""
    rng = np.random.default_rng(seed)
    out = []
    for width, count in zip(widths, counts):
        centres = points[rng.choice(len(points), count, replace=False)]
        signs = rng.choice([-1.0, 1.0], count)
        d2 = ((points[:, None, :] - centres[None]) ** 2).sum(-1)
        out.append((signs * np.exp(-d2 / (2 * width**2))).sum(1))
    return out


def _eigenvectors(surface: Surface, k: int) -> tuple[np.ndarray, np.ndarray]:
    return spla.eigsh(surface.stiffness, k=k, M=surface.mass, sigma=-1e-8, v0=np.ones(surface.n_vertices))


def _mean_edge(surface: Surface) -> float:
    f = surface.faces
    edges = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    return float(np.linalg.norm(surface.vertices[edges[:, 0]] - surface.vertices[edges[:, 1]], axis=1).mean())


def surface_cases(spot_path, face_path) -> list[Case]:
    """Bumps on a sphere and on a face scan (spot when the scan is missing), eigenfunctions, curvature + noise."""
    sphere = Surface(*icosphere(4), name="icosphere")
    spot = hht3d.load(spot_path)
    face = hht3d.load(face_path) if face_path.is_file() else spot
    cases = []
    for surface in (Surface(*icosphere(5), name="icosphere 10k"), face):
        edge = _mean_edge(surface)
        for widths, counts in (((2.5, 12), (40, 8)), ((2, 6, 18), (60, 16, 4))):
            parts = _bumps(surface.vertices, [w * edge for w in widths], counts, seed=len(widths))
            cases.append(Case(f"{surface.name}: bumps of σ {'/'.join(map(str, widths))} edges", surface, parts))
    for surface, sets in ((sphere, [(9, 144), (16, 81), (4, 36, 256)]), (spot, [(3, 40), (5, 100), (2, 12, 90)])):
        values, vectors = _eigenvectors(surface, max(max(s) for s in sets) + 1)
        for indices in sets:
            ratio = "/".join(f"{values[j] / values[indices[0]]:.3g}" for j in indices[1:])
            parts = [vectors[:, j] / np.abs(vectors[:, j]).max() for j in indices]
            cases.append(Case(f"{surface.name}: eigenfunctions {indices} (λ ratio {ratio})", surface, parts))
    sphere10k = Surface(*icosphere(5), name="icosphere 10k")
    edge, z = _mean_edge(sphere10k), sphere10k.vertices[:, 2]
    narrow, wide = _bumps(sphere10k.vertices, [2.5 * edge, 10 * edge], (60, 6), seed=7)
    narrow_top = narrow * _hann(z, -0.1, 2.1) ** 0.5  # the narrow bumps fade out below the equator
    wide_bottom = wide * _hann(z, -2.1, 0.1) ** 0.5
    cases.append(Case("icosphere 10k: narrow bumps north, wide south", sphere10k, [narrow_top, wide_bottom]))
    curvature = fluctuation(spot, mean_curvature(spot))
    noise = 0.3 * np.std(curvature) * np.random.default_rng(5).standard_normal(spot.n_vertices)
    cases.append(Case("spot: mean curvature + 30% white noise", spot, [noise, curvature]))
    return cases


def _weighted_corr(a: np.ndarray, b: np.ndarray, w: np.ndarray) -> float:
    a, b = a - np.average(a, weights=w), b - np.average(b, weights=w)
    denominator = np.sqrt(np.dot(w * a, a) * np.dot(w * b, b))
    return float(np.dot(w * a, b) / denominator) if denominator > 0 else 0.0


def scores(imfs: np.ndarray, residue: np.ndarray, components, weights: np.ndarray, single: bool = False) -> list[float]:
    """Best correlation of each component with an IMF, an adjacent pair or a tail (module notes);
    with ``single``, with one IMF or the residue only."""
    parts = list(imfs) + [residue]
    candidates = (
        parts
        if single
        else parts
        + [parts[k] + parts[k + 1] for k in range(len(parts) - 1)]
        + [np.sum(parts[k:], axis=0) for k in range(1, len(parts) - 1)]
    )
    return [max(abs(_weighted_corr(c, comp, weights)) for c in candidates) for comp in components]


def surface_methods() -> dict:
    """The methods on surfaces of ``bench_quality``: the paper's EMD, the defaults and EEMD."""
    members = {"ensemble_size": ENSEMBLE}
    return {
        "paper": lambda s, f: emd(s, f, PAPER_OPTIONS),
        "defaults": lambda s, f: emd(s, f, EMD_DEFAULTS),
        f"eemd×{ENSEMBLE}": lambda s, f: eemd(s, f, EMD_DEFAULTS, ensemble=members),
    }


def pyemd_methods() -> dict:
    from PyEMD import CEEMDAN, EEMD, EMD

    def run(method):
        def go(t, f):
            imfs = method(f, t)
            return imfs[:-1], imfs[-1]  # PyEMD returns the residue as the last row

        return go

    return {
        "PyEMD EMD": run(EMD()),
        f"PyEMD EEMD×{ENSEMBLE}": run(EEMD(trials=ENSEMBLE, noise_width=0.2, parallel=False)),
        f"PyEMD CEEMDAN×{ENSEMBLE}": run(CEEMDAN(trials=ENSEMBLE, parallel=False)),
    }


def _strip_1d(case: Case):
    """The strip's signal on its 600 distinct x (one row of vertices) and trapezoid weights."""
    row = np.flatnonzero(case.surface.vertices[:, 1] == 0)
    order = row[np.argsort(case.x[row])]
    weights = np.ones(len(order))
    weights[[0, -1]] = 0.5
    return order, weights


def part_recovery(spot_path, face_path, methods: dict | None = None, references: dict | None = None) -> list[dict]:
    """One row per case and method: the score of each component, and the EMD's IO and energy ratio.

    ``methods`` (default :func:`surface_methods`) run on the surfaces, ``references`` (default
    :func:`pyemd_methods`) on the strips' 1-D signals."""
    rows = []
    for case in strip_cases() + surface_cases(spot_path, face_path):
        for name, run in (methods or surface_methods()).items():
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                result = run(case.surface, case.signal)
            rows.append(
                {
                    "case": case.name,
                    "method": name,
                    "imfs": result.n_imfs,
                    "scores": scores(result.imfs, result.residue, case.components, case.surface.mass_diagonal),
                    "single": scores(result.imfs, result.residue, case.components, case.surface.mass_diagonal, True),
                    "io": result.quality.orthogonality_index,
                    "energy_ratio": result.quality.energy_ratio,
                }
            )
            print(rows[-1], flush=True)
        if case.x is not None:
            order, weights = _strip_1d(case)
            for name, run in (pyemd_methods() if references is None else references).items():
                imfs, residue = run(case.x[order], case.signal[order])
                rows.append(
                    {
                        "case": case.name,
                        "method": name,
                        "imfs": len(imfs),
                        "scores": scores(imfs, residue, [c[order] for c in case.components], weights),
                        "single": scores(imfs, residue, [c[order] for c in case.components], weights, True),
                    }
                )
                print(rows[-1], flush=True)
    return rows
