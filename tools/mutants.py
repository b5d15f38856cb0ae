"""Mutation check: does the test suite catch single-line faults in the core numerics?

    python -m tools.mutants                 # every mutant (about 10-20 minutes here)
    python -m tools.mutants --only eq27-sign quadrature-nodes
    python -m tools.mutants --list          # the mutants and whether their snippets still match

Each mutant replaces one exact snippet of one file of ``hht3d/`` by a faulty
version.  It is applied to a copy of the package and the tests in a temporary
folder, never to the working tree, and the mutant's test files run there
(``pytest -x``, strict-xfail tests deselected: they document known failures,
and a mutant that happens to make one pass says nothing).  A mutant is
*caught* when a test fails (the first failing test is reported), *survived*
when all pass, and *stale* when its snippet no longer occurs exactly once in
the file: after a rewrite of that code, update the snippet here (the table
says which).  Before the mutants, the same test files run on the unchanged
copy; if they fail there, the run stops.

Writes ``benchmarks/results/mutants.json`` and ``mutants.md``.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import asdict, dataclass
from pathlib import Path

from benchmarks.common import ROOT, machine, table, write_results

#: Longest run of one mutant's tests; a mutant that hangs the suite counts as caught (by timeout).
TIMEOUT = 900

EMD_TESTS = (
    "tests/decomposition/test_extrema.py",
    "tests/decomposition/test_envelopes.py",
    "tests/decomposition/test_sifting.py",
    "tests/decomposition/test_decompose.py",
    "tests/decomposition/test_ensemble.py",
    "tests/decomposition/test_quality.py",
    "tests/test_transform.py",
)
RIESZ_TESTS = (
    "tests/spectral/test_riesz_transform.py",
    "tests/spectral/test_eigenpairs.py",
    "tests/spectral/test_quadrature.py",
    "tests/spectral/test_shifts.py",
    "tests/spectral/test_monogenic_signal.py",
    "tests/spectral/test_spectrum.py",
)
MONOGENIC_TESTS = (
    "tests/spectral/test_monogenic_signal.py",
    "tests/spectral/test_spectrum.py",
    "tests/spectral/test_frequency.py",
    "tests/spectral/test_resolution.py",
    "tests/test_transform.py",
    "tests/apps/test_filters.py",
    "tests/apps/test_reconstruction.py",
    "tests/apps/test_baselines.py",
)
FILTERING_TESTS = ("tests/decomposition/test_filtering.py",)
FILTER_TESTS = ("tests/apps/test_filters.py", "tests/apps/test_reconstruction.py", "tests/apps/test_baselines.py")
OPERATOR_TESTS = (
    "tests/geometry/test_operators.py",
    "tests/geometry/test_surface.py",
    "tests/spectral/test_riesz_transform.py",
    "tests/spectral/test_eigenpairs.py",
    "tests/spectral/test_quadrature.py",
    "tests/spectral/test_shifts.py",
    "tests/geometry/test_signals.py",
)
GRADIENT_TESTS = (
    "tests/geometry/test_operators.py",
    "tests/geometry/test_surface.py",
    "tests/spectral/test_riesz_transform.py",
    "tests/spectral/test_eigenpairs.py",
    "tests/spectral/test_quadrature.py",
    "tests/spectral/test_shifts.py",
    "tests/spectral/test_monogenic_signal.py",
    "tests/spectral/test_spectrum.py",
)


@dataclass(frozen=True)
class Mutant:
    """One fault: ``original`` (exactly once in ``file``) becomes ``replacement``."""

    name: str
    fault: str
    file: str
    original: str
    replacement: str
    tests: tuple[str, ...]


MUTANTS = (
    # -- iterative filtering (hht3d/decomposition/filtering.py) ---------------------------------
    Mutant(
        "filtering-recurrence",
        "the Clenshaw recurrence in W instead of 2W - I",
        "hht3d/decomposition/filtering.py",
        "        return 2.0 * solve(mass * v) - v\n",
        "        return solve(mass * v)\n",
        FILTERING_TESTS,
    ),
    Mutant(
        "filtering-cut-power",
        "the filter's t is 1/ω_c instead of 1/ω_c²",
        "hht3d/decomposition/filtering.py",
        "        t = np.full(len(residue), 1.0 / cut**2)\n",
        "        t = np.full(len(residue), 1.0 / cut)\n",
        FILTERING_TESTS,
    ),
    Mutant(
        "filtering-cut-ratio",
        "the cut ratio multiplies the cut frequency instead of dividing it",
        "hht3d/decomposition/filtering.py",
        "        cut = EXTREMA_FREQUENCY / (self.options.cut_ratio * spacing)\n",
        "        cut = EXTREMA_FREQUENCY * self.options.cut_ratio / spacing\n",
        FILTERING_TESTS,
    ),
    Mutant(
        "filtering-no-trend-stop",
        "the stop on a residue whose extrema did not thin out is gone",
        "hht3d/decomposition/filtering.py",
        "        if min(counts) < 2 or (counts[0] >= self.counts[0] and counts[1] >= self.counts[1]):\n",
        "        if min(counts) < 2:\n",
        FILTERING_TESTS,
    ),
    Mutant(
        "filtering-membrane-diagonal",
        "the membrane resolvent's diagonal keeps the plain Laplacian's",
        "hht3d/decomposition/filtering.py",
        "            data[e.diagonal] = -np.bincount(rows[off], weights=data[off], minlength=e.n)\n",
        "            data[e.diagonal] = e.laplacian[e.diagonal]\n",
        FILTERING_TESTS,
    ),
    # -- EMD (hht3d/decomposition/) ------------------------------------------------------------
    Mutant(
        "emd-half-step",
        "sifting subtracts half the mean envelope",
        "hht3d/decomposition/sifting.py",
        "            candidate = h - mean\n",
        "            candidate = h - 0.5 * mean\n",
        EMD_TESTS,
    ),
    Mutant(
        "emd-sd-loose",
        "SD stopping threshold 10x looser",
        "hht3d/decomposition/sifting.py",
        'if o.stopping == "sd" and value < o.sd_threshold:',
        'if o.stopping == "sd" and value < 10 * o.sd_threshold:',
        EMD_TESTS,
    ),
    Mutant(
        "emd-imf-halved",
        "every IMF halved (the residue absorbs the rest)",
        "hht3d/decomposition/decompose.py",
        "            imfs.append(extracted[0])\n",
        "            imfs.append(0.5 * extracted[0])\n",
        EMD_TESTS,
    ),
    Mutant(
        "envelope-constrained-columns",
        "envelope system keeps the constrained columns in the free rows",
        "hht3d/decomposition/envelopes.py",
        "return np.repeat(free, self.row_lengths) & free[self.indices]",
        "return np.repeat(free, self.row_lengths)",
        EMD_TESTS,
    ),
    Mutant(
        "envelope-rhs-sign",
        "envelope right-hand side with the wrong sign",
        "hht3d/decomposition/envelopes.py",
        "rhs = -(e.matrix(q) @ np.where(constrained, f, 0.0))",
        "rhs = e.matrix(q) @ np.where(constrained, f, 0.0)",
        EMD_TESTS,
    ),
    Mutant(
        "envelope-tension-scale",
        "tension term (τ d)² L instead of (τ/d)² L",
        "hht3d/decomposition/envelopes.py",
        "return self.bilaplacian + (tension / spacing) ** 2 * self.laplacian",
        "return self.bilaplacian + (tension * spacing) ** 2 * self.laplacian",
        EMD_TESTS,
    ),
    Mutant(
        "guard-ladder-off",
        "the cancellation guard accepts every first extraction",
        "hht3d/decomposition/sifting.py",
        "sifted.step_energy_ratio <= 1 + o.cancellation_tolerance:",
        "sifted.step_energy_ratio <= 1e9 + o.cancellation_tolerance:",
        EMD_TESTS,
    ),
    Mutant(
        "mean-correction-sign",
        "the local mean added to the IMF instead of removed",
        "hht3d/decomposition/sifting.py",
        "removed = imf - fluctuation(self.surface, imf) + fluctuation(self.surface, slow)",
        "removed = imf - fluctuation(self.surface, imf) - fluctuation(self.surface, slow)",
        EMD_TESTS,
    ),
    Mutant(
        "mean-correction-scale",
        "local-mean filter with t = c d instead of (c d)²",
        "hht3d/decomposition/sifting.py",
        "data = (c * spacing) ** 4 * e.smoothing",
        "data = (c * spacing) ** 2 * e.smoothing",
        EMD_TESTS,
    ),
    # -- curvature signals (hht3d/geometry/signals.py) -------------------------------------------
    Mutant(
        "curvature-no-region",
        "unreliable vertices keep their pointwise density",
        "hht3d/geometry/signals.py",
        "density[seeds] = (regions @ integrated) / (regions @ area)[:, None]",
        "density[seeds] = density[seeds]",
        ("tests/geometry/test_signals.py",),
    ),
    # -- L^{-1/2} quadrature and spectral bounds (hht3d/spectral/) ------------------------------
    Mutant(
        "quadrature-nodes",
        "midpoint nodes shifted by a quarter step",
        "hht3d/spectral/quadrature.py",
        "u = (np.arange(1, count + 1) - 0.5) * kp / count",
        "u = (np.arange(1, count + 1) - 0.25) * kp / count",
        RIESZ_TESTS,
    ),
    Mutant(
        "quadrature-weights",
        "weights with dn/cn instead of dn/cn²",
        "hht3d/spectral/quadrature.py",
        "weights = 2.0 * kp * np.sqrt(m) / (np.pi * count) * dn / cn**2",
        "weights = 2.0 * kp * np.sqrt(m) / (np.pi * count) * dn / cn",
        RIESZ_TESTS,
    ),
    Mutant(
        "quadrature-tol-30x",
        "quadrature 30x less accurate than the tol it documents",
        "hht3d/spectral/quadrature.py",
        "plan = quadrature_plan(surface, tol, symbolic=symbolic)",
        "plan = quadrature_plan(surface, 30 * tol, symbolic=symbolic)",
        RIESZ_TESTS,
    ),
    Mutant(
        "bounds-lower-above-lambda1",
        "lower spectral bound 1.5 x 0.9 λ1 (above λ1)",
        "hht3d/spectral/eigenpairs.py",
        "m = SAFETY * float(np.min(",
        "m = 1.5 * SAFETY * float(np.min(",
        RIESZ_TESTS,
    ),
    Mutant(
        "bounds-upper-halved",
        "Collatz–Wielandt upper bound halved (below λmax)",
        "hht3d/spectral/eigenpairs.py",
        "best = min(best, float(np.max(y / w)))",
        "best = min(best, 0.5 * float(np.max(y / w)))",
        RIESZ_TESTS,
    ),
    # -- monogenic signal (hht3d/spectral/monogenic_signal.py, frequency.py) --------------------
    Mutant(
        "monogenic-amplitude",
        "amplitude a² instead of a (Eq. 21)",
        "hht3d/spectral/monogenic_signal.py",
        "amplitude=np.hypot(f, q)",
        "amplitude=np.hypot(f, q) ** 2",
        MONOGENIC_TESTS,
    ),
    Mutant(
        "monogenic-phase",
        "phase atan2(f, q) instead of atan2(q, f) (Eq. 22)",
        "hht3d/spectral/monogenic_signal.py",
        "phase=np.arctan2(q, f)",
        "phase=np.arctan2(f, q)",
        MONOGENIC_TESTS,
    ),
    Mutant(
        "monogenic-frequency",
        "frequency divided by a instead of a² (Eq. 23)",
        "hht3d/spectral/frequency.py",
        "return np.divide(numerator, energy, out=",
        "return np.divide(numerator, np.sqrt(energy), out=",
        MONOGENIC_TESTS,
    ),
    Mutant(
        "phase-unwrap-turn",
        "edge increments unwrapped by π instead of 2π",
        "hht3d/spectral/frequency.py",
        "grad = (st.fit @ (increment + 2 * np.pi * turns))",
        "grad = (st.fit @ (increment + np.pi * turns))",
        MONOGENIC_TESTS,
    ),
    Mutant(
        "phase-dispersion-sqrt",
        "Laplacian dispersion ratio without its square root",
        "hht3d/spectral/frequency.py",
        "laplacian_ratio = np.sqrt(\n",
        "laplacian_ratio = (\n",
        MONOGENIC_TESTS,
    ),
    # -- Eq. 26 (hht3d/apps/filters.py, reconstruction.py) --------------------------------------
    Mutant(
        "eq26-gain-order",
        "filter_signal applies each IMF's gains to the IMFs in reverse order",
        "hht3d/apps/filters.py",
        "return np.sum(mu * imfs, axis=0) + residue",
        "return np.sum(mu[::-1] * imfs, axis=0) + residue",
        FILTER_TESTS,
    ),
    Mutant(
        "eq26-gain-squared",
        "filter_geometry applies μ² instead of μ",
        "hht3d/apps/geometry_filter.py",
        "change = np.sum((mu - 1.0) * imfs, axis=0)",
        "change = np.sum((mu ** 2 - 1.0) * imfs, axis=0)",
        FILTER_TESTS,
    ),
    Mutant(
        "eq27-automatic-weight-power",
        "automatic weight (ω/3)² instead of (ω/3)⁴",
        "hht3d/apps/geometry_filter.py",
        "(STIFFNESS_FRACTION * frequency) ** 4",
        "(STIFFNESS_FRACTION * frequency) ** 2",
        FILTER_TESTS,
    ),
    # -- Eq. 27 (hht3d/apps/reconstruction.py) --------------------------------------------------
    Mutant(
        "eq27-sign",
        "right-hand side with the wrong sign",
        "hht3d/apps/reconstruction.py",
        "rhs = lap @ (ds[:, None] * surface.normals)",
        "rhs = -(lap @ (ds[:, None] * surface.normals))",
        FILTER_TESTS,
    ),
    Mutant(
        "eq27-missing-inverse-mass",
        "L L instead of L M⁻¹ L",
        "hht3d/apps/reconstruction.py",
        "system = (lap @ sp.diags(1.0 / area) @ lap + sp.diags(w)).tocsr()",
        "system = (lap @ lap + sp.diags(w)).tocsr()",
        FILTER_TESTS,
    ),
    Mutant(
        "eq27-weights-unscaled",
        "position weights μ A / Ā instead of μ A / Ā²",
        "hht3d/apps/reconstruction.py",
        "w = mu * area / mean_area**2",
        "w = mu * area / mean_area",
        FILTER_TESTS,
    ),
    Mutant(
        "eq27-weights-swapped",
        "boundary and interior weights swapped",
        "hht3d/apps/reconstruction.py",
        "return np.where(surface.boundary_vertices, boundary, interior)",
        "return np.where(surface.boundary_vertices, interior, boundary)",
        FILTER_TESTS,
    ),
    # -- operators (hht3d/geometry/operators.py) ------------------------------------------------
    Mutant(
        "cotan-wrong-edge",
        "cotangent of corner k put on edge (k, k+2) instead of (k+1, k+2)",
        "hht3d/geometry/operators.py",
        "    i = faces[:, [1, 2, 0]].ravel()\n",
        "    i = faces[:, [0, 1, 2]].ravel()\n",
        OPERATOR_TESTS,
    ),
    Mutant(
        "mass-barycentric-obtuse",
        "obtuse triangles split in thirds (not Meyer's 1/2, 1/4, 1/4)",
        "hht3d/geometry/operators.py",
        "np.where(obtuse_corner, area[:, None] / 2, area[:, None] / 4)",
        "np.where(obtuse_corner, area[:, None] / 3, area[:, None] / 3)",
        OPERATOR_TESTS,
    ),
    Mutant(
        "mass-voronoi-swap",
        "Voronoi share with the cotangents of the wrong corners",
        "hht3d/geometry/operators.py",
        "voronoi = (sq[:, [1, 2, 0]] * cot[:, [1, 2, 0]] + sq[:, [2, 0, 1]] * cot[:, [2, 0, 1]]) / 8.0",
        "voronoi = (sq[:, [1, 2, 0]] * cot[:, [2, 0, 1]] + sq[:, [2, 0, 1]] * cot[:, [1, 2, 0]]) / 8.0",
        OPERATOR_TESTS,
    ),
    Mutant(
        "lsq-gradient-sign",
        "least-squares gradient of f_i − f_j (the paper's sign)",
        "hht3d/geometry/operators.py",
        "entry_val = np.concatenate([coef, -sums[diagonal - first]])",
        "entry_val = np.concatenate([-coef, sums[diagonal - first]])",
        GRADIENT_TESTS,
    ),
    Mutant(
        "lsq-gradient-unprojected",
        "least-squares gradient without the tangent projection",
        "hht3d/geometry/operators.py",
        '    p = d - np.einsum("ei,ei->e", d, nrm)[:, None] * nrm\n',
        "    p = d\n",
        GRADIENT_TESTS,
    ),
    Mutant(
        "fem-gradient-sign",
        "FEM face gradient e × n instead of n × e",
        "hht3d/geometry/operators.py",
        "coef = np.cross(unit[:, None, :], e) /",
        "coef = np.cross(e, unit[:, None, :]) /",
        GRADIENT_TESTS,
    ),
)


def locate(mutant: Mutant, root: Path) -> tuple[int | None, str]:
    """``(line, "")`` of the snippet in ``root/mutant.file``, or ``(None, why)`` when it is stale."""
    path = root / mutant.file
    if not path.is_file():
        return None, f"{mutant.file} does not exist"
    text = path.read_text()
    count = text.count(mutant.original)
    if count != 1:
        return None, f"snippet occurs {count} times in {mutant.file} (expected once): update it here"
    return text[: text.index(mutant.original)].count("\n") + 1, ""


def make_copy(destination: Path) -> Path:
    """Copy the package and the tests into ``destination/repo``; link ``../shared`` beside it."""
    repo = destination / "repo"
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc")
    shutil.copytree(ROOT / "hht3d", repo / "hht3d", ignore=ignore)
    shutil.copytree(ROOT / "tests", repo / "tests", ignore=ignore)
    shutil.copy2(ROOT / "pyproject.toml", repo / "pyproject.toml")
    shared = ROOT.parent / "shared"
    if shared.is_dir():
        (destination / "shared").symlink_to(shared)
    return repo


_FAILED = re.compile(r"^(?:FAILED|ERROR) (\S+)")


def run_tests(repo: Path, tests: tuple[str, ...]) -> tuple[str, str, float, str]:
    """Run ``tests`` in ``repo``: ``(status, first failing test, seconds, output tail)``."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "HHT3D_REQUIRE_DATA")}
    command = [sys.executable, "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider", "-m", "not xfail", "-rfE", *tests]
    start = time.perf_counter()
    try:
        done = subprocess.run(command, cwd=repo, env=env, capture_output=True, text=True, timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        return "caught", f"(timeout after {TIMEOUT} s)", time.perf_counter() - start, ""
    seconds = time.perf_counter() - start
    output = done.stdout + done.stderr
    if done.returncode == 0:
        return "survived", "", seconds, output[-2000:]
    failed = [m.group(1) for line in output.splitlines() if (m := _FAILED.match(line))]
    return "caught", failed[0] if failed else f"(pytest exit {done.returncode})", seconds, output[-2000:]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", nargs="+", metavar="NAME", help="run only these mutants")
    parser.add_argument("--list", action="store_true", help="list the mutants and check their snippets")
    args = parser.parse_args(argv)
    names = {m.name for m in MUTANTS}
    unknown = set(args.only or ()) - names
    if unknown:
        parser.error(f"unknown mutants {sorted(unknown)}; --list shows them")
    chosen = [m for m in MUTANTS if not args.only or m.name in args.only]
    if args.list:
        for m in chosen:
            line, why = locate(m, ROOT)
            print(f"{m.name:30s} {m.file}:{line if line else '?':<5} {why or m.fault}")
        return 0

    rows, records = [], []
    with tempfile.TemporaryDirectory(prefix="hht3d-mutants-") as scratch:
        repo = make_copy(Path(scratch))
        files = tuple(dict.fromkeys(t for m in chosen for t in m.tests))
        status, failed, seconds, tail = run_tests(repo, files)
        print(f"baseline: {len(files)} test files on the unchanged copy: {status} ({seconds:.0f} s)", flush=True)
        if status != "survived":
            print(f"the unchanged copy fails {failed}; fix that first\n{tail}", file=sys.stderr)
            return 1
        for m in chosen:
            line, why = locate(m, repo)
            record = {**asdict(m), "line": line}
            if line is None:
                record.update(status="stale", caught_by="", seconds=0.0, note=why)
            else:
                path = repo / m.file
                original = path.read_text()
                path.write_text(original.replace(m.original, m.replacement))
                try:
                    status, failed, seconds, _ = run_tests(repo, m.tests)
                finally:
                    path.write_text(original)
                record.update(status=status, caught_by=failed, seconds=round(seconds, 1), note="")
            records.append(record)
            where = f"{m.file}:{line}" if line else m.file
            rows.append(
                [
                    m.name,
                    m.fault,
                    where,
                    record["status"],
                    record["caught_by"] or record["note"],
                    f"{record['seconds']:.0f}",
                ]
            )
            print(f"{m.name:30s} {where:32s} {record['status']:8s} {record['caught_by'] or record['note']}", flush=True)

    counts = {s: sum(r["status"] == s for r in records) for s in ("caught", "survived", "stale")}
    summary = (
        f"{counts['caught']} of {len(records)} mutants caught, {counts['survived']} survived, "
        f"{counts['stale']} stale (snippet not found)"
    )
    print(summary)
    markdown = "\n".join(
        [
            "# Mutation check",
            "",
            "`python -m tools.mutants`: single-line faults in the core numerics, each applied to a "
            "temporary copy of the package and run against its test files (`pytest -x`, strict xfails "
            "deselected).",
            "",
            summary,
            "",
            table(["mutant", "fault", "file:line", "status", "first failing test", "s"], rows),
            "",
        ]
    )
    if args.only:
        print("--only: benchmarks/results/mutants.* left as they are (they hold the full run)")
    else:
        write_results("mutants", {"machine": machine(), "summary": counts, "mutants": records}, markdown)
    return 0 if counts["survived"] == counts["stale"] == 0 else 2


if __name__ == "__main__":
    sys.exit(main())
