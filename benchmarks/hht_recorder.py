"""What ``bench_hht`` measures inside a case: the stage timer and memory meter, and the
instrumentation of the sparse solvers and a few sub-steps (benchmark only, no effect on the numerics).

:class:`Recorder` times each stage (wall and CPU seconds) and takes its peak resident set by
resetting the high-water mark at the stage's start.  Child processes (the blocks of a robust
Laplacian, :mod:`hht3d.geometry.block_processes`) add their CPU seconds and the largest sum of
their resident sets, sampled every :data:`CHILDREN_SAMPLE` seconds once they run their own program
(the kernel's peak of children, ``ru_maxrss``, carries the forking parent's over ``exec``, and a
child between fork and exec shows the parent's pages).
It wraps the PARDISO phases (analysis 11, numeric factorization 22, solve 33, with PARDISO's
own memory report from ``iparm``), the construction, factorizations and solves of the other
backends, and ``spectral_bounds``, ``monogenic_from_potential``, ``monogenic_from_riesz``,
``riesz_part`` and ``envelope_energies``.
"""

from __future__ import annotations

import contextlib
import functools
import os
import threading
import time
from collections.abc import Iterator

import psutil

from benchmarks.common import peak_rss_mb, reset_peak, status_mb

#: The stages of a case, in order; their seconds add up to its total.
STAGES = ["load", "operators", "signal", "emd", "rt"]


def _children_cpu() -> float:
    """CPU seconds of this process's ended children."""
    times = os.times()
    return times.children_user + times.children_system


#: Seconds between two samples of the children's resident sets.
CHILDREN_SAMPLE = 0.05


@contextlib.contextmanager
def _children_meter() -> Iterator[list[float]]:
    """Yields ``[MB]``: the largest sum of the children's resident sets sampled while inside."""
    largest, done, me = [0.0], threading.Event(), psutil.Process()

    def sample() -> None:
        while not done.wait(CHILDREN_SAMPLE):
            total = 0
            for child in me.children(recursive=True):
                with contextlib.suppress(psutil.Error):  # a child between fork and exec shows this process's pages
                    if any("block_processes" in part for part in child.cmdline()):
                        total += child.memory_info().rss
            largest[0] = max(largest[0], total / 2**20)

    thread = threading.Thread(target=sample, name="children-meter", daemon=True)
    thread.start()
    try:
        yield largest
    finally:
        done.set()
        thread.join()


class Recorder:
    """Stage timer/memory meter plus PARDISO and sub-step instrumentation."""

    def __init__(self):
        self.stages: dict[str, dict] = {}
        self.label = "setup"
        self.solver: dict[str, dict] = {}  # per label: phases of the sparse solver
        self.timers: dict[str, float] = {}
        self.peaks: dict[str, float] = {}  # peak RSS MB during a wrapped sub-step
        self.peak_resets = True
        self._stage_peak = 0.0
        self.energies_mb = 0.0  # L M^-1 L, L and the smoothing operator on one pattern

    def checkpoint(self) -> float:
        """Peak RSS (MB) since the last reset; resets it (the stage's peak keeps the maximum)."""
        peak = peak_rss_mb()
        self._stage_peak = max(self._stage_peak, peak)
        self.peak_resets &= reset_peak()
        return peak

    @contextlib.contextmanager
    def stage(self, name: str):
        rss_start = status_mb("VmRSS")
        self._stage_peak = 0.0
        self.peak_resets &= reset_peak()
        self.label = name
        start, cpu_start, children_start = time.perf_counter(), time.process_time(), _children_cpu()
        with _children_meter() as children:
            yield
        seconds, cpu = time.perf_counter() - start, time.process_time() - cpu_start
        children_cpu, children_mb = _children_cpu() - children_start, children[0]
        self.peaks[f"{name}:tail"] = peak_rss_mb()  # since the last checkpoint of the stage
        self.stages[name] = {
            "seconds": seconds,
            "cpu_seconds": cpu + children_cpu,
            "rss_start_mb": rss_start,
            "rss_end_mb": status_mb("VmRSS"),
            "children_peak_mb": children_mb,
            "peak_mb": max(self._stage_peak, peak_rss_mb()) + children_mb,
        }
        self.label = "between"

    @contextlib.contextmanager
    def sublabel(self, suffix: str):
        outer = self.label
        self.label = f"{outer}:{suffix}"
        try:
            yield
        finally:
            self.label = outer

    def timed(self, key: str, fn, sublabel: str | None = None):
        @functools.wraps(fn)
        def wrapper(*args, **kwargs):
            before = self.checkpoint()
            start = time.perf_counter()
            try:
                if sublabel is None:
                    return fn(*args, **kwargs)
                with self.sublabel(sublabel):
                    return fn(*args, **kwargs)
            finally:
                self.timers[key] = self.timers.get(key, 0.0) + time.perf_counter() - start
                self.peaks[key] = max(self.peaks.get(key, 0.0), self.checkpoint())
                self.peaks[f"before {key}"] = max(self.peaks.get(f"before {key}", 0.0), before)

        return wrapper

    def _entry(self) -> dict:
        return self.solver.setdefault(
            self.label,
            {
                "analysis_s": 0.0,
                "analysis": 0,
                "factorization_s": 0.0,
                "factorization": 0,
                "solve_s": 0.0,
                "solve": 0,
                "solve_columns": 0,
                "peak_kb": 0,
                "factor_nnz": 0,
                "n": 0,
            },
        )

    def _count(self, kind: str, start: float, cpu_start: float) -> None:
        entry = self._entry()
        entry[kind + "_s"] = entry.get(kind + "_s", 0.0) + time.perf_counter() - start
        entry[kind + "_cpu_s"] = entry.get(kind + "_cpu_s", 0.0) + time.process_time() - cpu_start
        entry[kind] = entry.get(kind, 0) + 1

    def _instrument_backend(self, impl) -> None:
        """Time analysis (construction), numeric factorization and solves of a non-PARDISO backend."""
        recorder = self
        init, factorize = impl.__init__, impl.factorize

        def timed_init(pattern, *args, **kwargs):
            start, cpu_start = time.perf_counter(), time.process_time()
            init(pattern, *args, **kwargs)
            recorder._count("analysis", start, cpu_start)

        def timed_factorize(pattern, a):
            start, cpu_start = time.perf_counter(), time.process_time()
            factor = factorize(pattern, a)
            recorder._count("factorization", start, cpu_start)
            # wrap the solver, not the bound method factor.solve: a closure over that would make
            # factor -> closure -> factor a cycle, freed only by the cyclic collector, and kept
            # every SuperLU factor of a run alive at once (the 20.8 GB peak of nefertiti)
            solve = factor._solve

            def timed_solve(b):
                start, cpu_start = time.perf_counter(), time.process_time()
                out = solve(b)
                recorder._count("solve", start, cpu_start)
                recorder._entry()["solve_columns"] += 1 if b.ndim == 1 else b.shape[1]
                return out

            factor._solve = timed_solve
            return factor

        impl.__init__, impl.factorize = timed_init, timed_factorize

    def instrument(self) -> None:
        """Wrap the solver phases of every backend and a few sub-steps (benchmark only)."""
        import hht3d.decomposition.envelopes as envelopes
        import hht3d.linalg.backends as linalg
        import hht3d.spectral.monogenic_signal as mono_module
        import hht3d.spectral.multilevel as multilevel
        import hht3d.spectral.quadrature as quadrature

        recorder = self
        backends = linalg.SOLVER_BACKENDS
        original = backends["pardiso"].pattern.run
        names = {11: "analysis", 22: "factorization", 33: "solve"}

        def run(pattern, phase, upper, b):
            start, cpu_start = time.perf_counter(), time.process_time()
            out = original(pattern, phase, upper, b)
            recorder._count(names.get(phase, f"phase{phase}"), start, cpu_start)
            entry = recorder._entry()
            if phase == 33:
                entry["solve_columns"] += 1 if b.ndim == 1 else b.shape[1]
            else:
                ip = pattern.solver.iparm
                entry["peak_kb"] = max(entry["peak_kb"], int(ip[14]), int(ip[15]) + int(ip[16]))
                entry["factor_nnz"] = max(entry["factor_nnz"], int(ip[17]))
                entry["n"] = pattern.n
            return out

        backends["pardiso"].pattern.run = run
        for impl in (backends["cholmod"].pattern, backends["superlu"].pattern):
            self._instrument_backend(impl)
        quadrature.spectral_bounds = self.timed("rt_bounds", quadrature.spectral_bounds, "bounds")
        mono_module.monogenic_from_potential = self.timed("rt_quantities", mono_module.monogenic_from_potential)
        mono_module.monogenic_from_riesz = self.timed("rt_quantities", mono_module.monogenic_from_riesz)
        multilevel.riesz_part = self.timed("rt_riesz_levels", multilevel.riesz_part)
        timed_energies = self.timed("emd_operator_q", envelopes.envelope_energies)

        def energies(surface):  # the surface holds them weakly, so their size is taken here
            q = timed_energies(surface)
            recorder.energies_mb = nbytes(q.indptr, q.indices, q.bilaplacian, q.laplacian, q.smoothing)
            return q

        envelopes.envelope_energies = energies


def nbytes(*arrays) -> float:
    """MB held by ``arrays``."""
    return sum(a.nbytes for a in arrays) / 2**20


def sparse_mb(a) -> float:
    """MB held by a CSR/CSC matrix."""
    return (a.data.nbytes + a.indices.nbytes + a.indptr.nbytes) / 2**20
