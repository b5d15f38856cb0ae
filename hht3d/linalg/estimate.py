"""Time and memory known before a factorization starts, and the advice that follows from them.

Each backend's cost of the whole HHT of a mesh (EMD with the default options,
Riesz transform, monogenic quantities) is a model fitted to measurements on
real meshes by ``benchmarks/bench_backends.py``:

* peak resident memory ``BASELINE + n (a + b log₂ n)`` bytes for ``n``
  vertices: the arrays of the transform grow like ``n`` and a
  nested-dissection or minimum-degree factor of a surface's matrix like
  ``n log n`` (``b >= 0``, so extrapolation never falls below linear);
* wall time ``t₅₀ₖ (n / 50,000)^e`` seconds.

:func:`check_memory` refuses, with one line, a computation whose estimate
exceeds the memory available (:func:`available_memory`: free memory, the
process's address-space limit and the container's limit, whichever is
smallest).  :func:`slow_fallback` names the extra to install when a slow
backend was chosen for a large mesh, and :func:`warn_slow_fallback` says it
once per process as a Python warning.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import cast

from ..errors import InputError
from . import backends
from .backends import available_backends, check_backend

__all__ = [
    "Cost",
    "COSTS",
    "Estimate",
    "estimate_hht",
    "backend_estimates",
    "available_memory",
    "check_memory",
    "estimate_lines",
    "BASELINE",
    "SLOW_FALLBACK_VERTICES",
    "SlowSolverWarning",
    "slow_fallback",
    "warn_slow_fallback",
]

#: Meshes above this many vertices get the slow-fallback advice (:func:`slow_fallback`).
SLOW_FALLBACK_VERTICES = 20_000
_FIX = "install the fast solvers (pip install 'hht3d[fast]'), decimate the mesh, or run on a cluster"


@dataclass(frozen=True)
class Cost:
    """A backend's fitted cost of the whole HHT (module notes).

    Attributes
    ----------
    a, b : float
        Peak memory ``n (a + b log₂ n)`` bytes.
    seconds_50k, exponent : float
        Wall time ``seconds_50k (n / 50,000)^exponent``.
    slow : bool
        Worth the advice of :func:`slow_fallback` on large meshes.
    """

    a: float
    b: float
    seconds_50k: float
    exponent: float
    slow: bool = False


#: Fitted costs by backend name (``benchmarks/bench_backends.py`` prints them after each run;
#: these from results/backends.json: nefertiti and igea, 2026-12-07, SuperLU ordered by nested dissection).
COSTS: dict[str, Cost] = {
    "pardiso": Cost(a=5209.4, b=0.0, seconds_50k=17.47, exponent=0.747),
    "cholmod": Cost(a=0.0, b=271.2, seconds_50k=18.45, exponent=1.104),
    "superlu": Cost(a=0.0, b=366.2, seconds_50k=76.0, exponent=0.985, slow=True),
}


@dataclass(frozen=True)
class Estimate:
    """Estimated peak memory and time of the whole HHT of ``vertices`` on ``backend``.

    ``peak_bytes`` is the whole process's peak, :data:`BASELINE` included;
    ``added_bytes`` what the computation adds to a process that already runs.
    """

    backend: str
    vertices: int
    peak_bytes: int
    seconds: float

    @property
    def added_bytes(self) -> int:
        return max(self.peak_bytes - BASELINE, 0)

    def describe(self) -> str:
        return f"~{_size(self.peak_bytes)} and ~{_duration(self.seconds)} on {self.backend}"


def estimate_hht(vertices: int, backend: str | None = None) -> Estimate | None:
    """The whole HHT's :class:`Estimate` for a surface of ``vertices``; ``None`` for an uncalibrated backend.

    Parameters
    ----------
    vertices : int
        Vertices (or points) of the surface: the order of every sparse system.
    backend : str, optional
        Default :func:`~hht3d.linalg.backends.default_backend`.

    Returns
    -------
    Estimate or None
        The estimate, or ``None`` for an uncalibrated backend.

    Examples
    --------
    >>> from hht3d.linalg import estimate_hht
    >>> small, large = estimate_hht(10_000, "superlu"), estimate_hht(100_000, "superlu")
    >>> large.seconds > small.seconds and large.peak_bytes > small.peak_bytes
    True
    """
    backend = check_backend(backend)
    cost = COSTS.get(backend)
    if cost is None:
        return None
    n = max(int(vertices), 2)
    grows = max(n * (cost.a + cost.b * math.log2(n)), 0.0)
    return Estimate(backend, int(vertices), int(BASELINE + grows), cost.seconds_50k * (n / 50_000) ** cost.exponent)


#: Resident memory of a Python process that has imported hht3d (bytes, measured: 66-100 MB); part of every estimate.
BASELINE = 100 * 2**20


def backend_estimates(vertices: int) -> list[Estimate]:
    """:func:`estimate_hht` for every installed, calibrated backend, fastest first.

    Parameters
    ----------
    vertices : int
        The surface's vertex count.

    Returns
    -------
    list of Estimate
        One estimate per installed, calibrated backend, fastest first.

    Examples
    --------
    >>> from hht3d.linalg import backend_estimates
    >>> estimates = backend_estimates(50_000)
    >>> all(e.vertices == 50_000 for e in estimates), "superlu" in [e.backend for e in estimates]
    (True, True)
    """
    return [e for e in (estimate_hht(vertices, name) for name in available_backends()) if e is not None]


def estimate_lines(vertices: int) -> list[str]:
    """For ``hht3d info --backends``: each installed backend's estimate at ``vertices``, and what is available.

    Parameters
    ----------
    vertices : int
        The surface's vertex count.

    Returns
    -------
    list of str
        A heading, then one line per backend.

    Examples
    --------
    >>> from hht3d.linalg import estimate_lines
    >>> estimate_lines(50_000)[0]  # doctest: +ELLIPSIS
    'estimated whole HHT of 50,000 vertices (memory available: ...):'
    """
    available = available_memory()
    lines = [
        f"estimated whole HHT of {vertices:,} vertices (memory available: "
        f"{'unknown' if available is None else _size(available)}):"
    ]
    for found in backend_estimates(vertices):
        fits = "" if available is None or found.added_bytes <= available else "  (does not fit)"
        lines.append(f"    {found.backend:<8} ~{_duration(found.seconds):>7}  peak ~{_size(found.peak_bytes)}{fits}")
    return lines


def available_memory() -> int | None:
    """Bytes this process may still allocate: the smallest of free memory, what the
    address-space limit (``ulimit -v``) leaves and what the cgroup limit leaves; ``None`` if unknown.

    Returns
    -------
    int or None
        The bytes, or ``None`` when no limit can be read.

    Examples
    --------
    >>> from hht3d.linalg import available_memory
    >>> free = available_memory()
    >>> free is None or free >= 0
    True
    """
    limits, vms = [], None
    try:
        import psutil

        limits.append(psutil.virtual_memory().available)
        vms = psutil.Process().memory_info().vms
    except (ImportError, OSError):  # depends on the platform
        pass
    try:
        import resource

        soft = resource.getrlimit(resource.RLIMIT_AS)[0]
        if soft != resource.RLIM_INFINITY and vms is not None:
            limits.append(soft - vms)
    except ImportError:  # Windows
        pass
    cgroup = Path("/sys/fs/cgroup")
    try:
        limit = (cgroup / "memory.max").read_text().strip()
        if limit != "max":
            limits.append(int(limit) - int((cgroup / "memory.current").read_text()))
    except (OSError, ValueError):
        pass
    return max(min(limits), 0) if limits else None


def check_memory(vertices: int, backend: str | None = None, available: int | None = None) -> Estimate | None:
    """Refuse with one line a computation that would add more than ``available`` bytes.

    ``available`` defaults to :func:`available_memory`; returns the estimate.

    Parameters
    ----------
    vertices : int
        The surface's vertex count.
    backend : str, optional
        The backend (default :func:`default_backend`).
    available : int, optional
        The bytes available (default :func:`available_memory`).

    Returns
    -------
    Estimate or None
        The estimate, or ``None`` for a backend without calibration.

    Raises
    ------
    InputError
        With the estimate, the memory available and the ways out.

    Examples
    --------
    >>> from hht3d.linalg import check_memory
    >>> check_memory(1_000, "superlu", available=10**12).vertices
    1000
    >>> check_memory(10_000_000, "superlu", available=10**9)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    hht3d.errors.InputError: a surface of 10,000,000 vertices needs ... but only ... is available; ...
    """
    found = estimate_hht(vertices, backend)
    available = available_memory() if available is None else int(available)
    if found is not None and available is not None and found.added_bytes > available:
        raise InputError(
            f"a surface of {vertices:,} vertices needs {found.describe()} but only "
            f"{_size(available)} is available; {_FIX}"
        )
    return found


class SlowSolverWarning(UserWarning):
    """A slow sparse solver was chosen for a large mesh (:func:`warn_slow_fallback`)."""


def slow_fallback(vertices: int, backend: str | None = None) -> str | None:
    """The advice to install a faster backend, when ``backend`` is slow and the mesh is large; else ``None``.

    Parameters
    ----------
    vertices : int
        The surface's vertex count.
    backend : str, optional
        The backend (default :func:`default_backend`).

    Returns
    -------
    str or None
        The advice, or ``None``.

    Examples
    --------
    >>> from hht3d.linalg import slow_fallback
    >>> slow_fallback(1_000, "superlu") is None  # a small mesh: no advice
    True
    """
    backend = check_backend(backend)
    cost = COSTS.get(backend)
    if cost is None or not cost.slow or vertices <= SLOW_FALLBACK_VERTICES:
        return None
    faster = [name for name, c in COSTS.items() if not c.slow and name in backends.SOLVER_BACKENDS]
    found = cast(Estimate, estimate_hht(vertices, backend))  # calibrated: COSTS has the backend
    return (
        f"{backend} is a slow sparse solver for {vertices:,} vertices (the HHT needs {found.describe()}); "
        f"pip install 'hht3d[fast]' for {' or '.join(faster)}"
    )


_WARNED: set[str] = set()


def warn_slow_fallback(vertices: int, backend: str | None = None) -> None:
    """Issue :func:`slow_fallback`'s advice as a :class:`SlowSolverWarning`, once per process and backend.

    Parameters
    ----------
    vertices : int
        The surface's vertex count.
    backend : str, optional
        The backend (default :func:`default_backend`).
    """
    advice = slow_fallback(vertices, backend)
    if advice is not None and check_backend(backend) not in _WARNED:
        _WARNED.add(check_backend(backend))
        warnings.warn(advice, SlowSolverWarning, stacklevel=3)


def _size(nbytes: float) -> str:
    return f"{nbytes / 2**30:.1f} GiB" if nbytes >= 2**30 else f"{nbytes / 2**20:.0f} MiB"


def _duration(seconds: float) -> str:
    return f"{seconds / 60:.0f} min" if seconds >= 120 else f"{seconds:.0f} s"
