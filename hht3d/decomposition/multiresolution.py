"""Iterative filtering on a coarsening hierarchy: each residue moves to the coarsest level that resolves it.

After the IMF cut at ``ω_c`` the residue ``r_k = (I − P(W_k)) r_{k−1}`` of
:mod:`.filtering` is a low-pass: its response ``I_G(m, m)`` is below 1e-6 from
``1.5 ω_c`` on (bilaplacian filter, ``m = 16``).  So it is carried on the coarsest level
``ℓ_k`` of :func:`~hht3d.geometry.hierarchy.hierarchy` whose spacing ``h`` has
``ω_c h ≤`` :data:`SPACING_LIMIT` (at least ``2π /`` :data:`SPACING_LIMIT` vertices per
wavelength at the cut), and the next IMF is filtered there, on a system
:data:`~hht3d.geometry.hierarchy.COARSENING` times smaller per level.

With ``P_ℓ`` the prolongation from level ``ℓ`` to the input's vertices and ``R`` the
restriction (sampling) between levels, IMF ``k`` on the input is

    f_k = P_{ℓ_{k−1}} r_{k−1} − P_{ℓ_k} R r_k,

so the IMFs and ``P_{ℓ_K} r_K`` add up to the signal exactly (the sum telescopes), and what
the coarse level cannot represent of ``r_k`` stays in IMF ``k``, the finer band it belongs
to.  That share is measured: ``transfer_error`` of each IMF is
``‖r_k − P R r_k‖_M / ‖r_k‖_M`` on level ``ℓ_{k−1}``.

Each level has its own :class:`~hht3d.decomposition.filtering.Filterer` (its own
factorizations), and the cut comes from the extrema of the residue on its level.  On a coarse
level only vertices of degree :data:`COARSE_MIN_DEGREE` or more may be extrema: vertex
clustering leaves vertices of degree 2 to 4 whose 1-ring misses a side, and with them the
1-ring rule found 31 maxima where the input has 14 (nefertiti, IMF 6's residue).  Without
them the median opposite distance of the direct residues on levels 1 and 2 is within 5% of the
input's (IMFs 3-7 of nefertiti; a strict 2-ring gave 4-8% more, and 50-70% more on level 2's
finer residues).  The trend stop compares residues on one level.
Prolonging a residue back to the input to find its extrema there does not work: the
interpolation's kinks are extrema too (the cut of IMF 7 rose threefold).  The
IMFs on their levels are kept in ``EMDResult.levels`` for the Riesz transform of each IMF
on its level (:func:`hht3d.spectral.multilevel.riesz_part`).  When a level's filter is a
polynomial (:mod:`.filtering`, "Evaluation"), IMF ``k`` there is ``p(A) r + e``, ``p ≈ P∘g`` and
``e = low − back`` what the transfer left.  Its entry also keeps ``x = r + e`` and the Riesz
potential ``ψ(A) x`` (:func:`~hht3d.decomposition.filtering.potential_response`): that of ``r``
from the filter's own pass (the same ``T_j(Y) r``, other coefficients), that of ``e`` from one
more pass on the IMFs whose residue moved, to the same error in absolute terms (its series stops
earlier by the ratio ``‖r‖ / ‖e‖``: :func:`_remainder_tolerance`).
"""

from __future__ import annotations

import math
import time

import numpy as np

from ..geometry.hierarchy import Hierarchy, hierarchy
from ..geometry.surface import Surface
from .filtering import POTENTIAL_TOLERANCE, Filterer, potential_usable
from .options import EMDOptions

__all__ = ["MultilevelFilterer", "COARSE_MIN_DEGREE", "SPACING_LIMIT", "MULTIRESOLUTION_VERTICES", "uses_levels"]

#: Largest ``ω_c h`` (radians) of the level a residue with cut ``ω_c`` moves to.
SPACING_LIMIT = 0.5
#: The largest series tolerance of a transfer remainder's Riesz potential (:func:`_remainder_tolerance`).
REMAINDER_TOLERANCE = 1e-4
#: Extrema on a coarse level are vertices of at least this many neighbours (module notes).
COARSE_MIN_DEGREE = 5
#: ``multiresolution="auto"`` uses the hierarchy from this many vertices on: the measured crossover (whole HHT of
#: igea decimated, PARDISO, median of 5: 1.17× the direct time at 3,125 vertices, 1.18× at 6,250, 1.00× at 9,375,
#: 0.88× at 12,500; ``benchmarks/results/multiresolution.md``).
MULTIRESOLUTION_VERTICES = 10_000


def uses_levels(options: EMDOptions, n_vertices: int) -> bool:
    """Whether :func:`~hht3d.decomposition.emd` decomposes on levels with these settings."""
    if options.method != "filtering" or options.multiresolution == "never":
        return False
    return options.multiresolution == "always" or n_vertices >= MULTIRESOLUTION_VERTICES


class MultilevelFilterer:
    """Iterative filtering with each residue on its level (module notes); the interface of :class:`Filterer`."""

    def __init__(self, surface: Surface, options: EMDOptions, backend: str | None):
        self.hierarchy: Hierarchy = hierarchy(surface)
        self.options, self.backend = options, backend
        self.filterers: dict[int, Filterer] = {}
        self.level = 0
        self.residue: np.ndarray | None = None
        self.levels: list[tuple[int, np.ndarray, np.ndarray | None, np.ndarray | None]] = []
        self.retired: dict[int, tuple[int, int, int, str]] = {}

    def filterer(self, index: int) -> Filterer:
        """The filterer of level ``index`` (made once)."""
        if index not in self.filterers:
            surface = self.hierarchy.levels[index].surface
            eligible = np.diff(surface.adjacency.indptr) >= COARSE_MIN_DEGREE if index > 0 else None
            usable = potential_usable(surface)  # its polynomial saves the level's band quadrature too
            self.filterers[index] = Filterer(surface, self.options, self.backend, eligible, index > 0, usable)
        return self.filterers[index]

    def imf(self, residue: np.ndarray) -> tuple[np.ndarray, dict] | None:
        """IMF ``k`` on the input's vertices and its diagnostics (``level``, ``level_vertices``,
        ``residue_level``, ``transfer_error``); ``None`` as :meth:`Filterer.cut`.

        ``residue`` is the input's signal on the first call; later calls continue from the residue
        kept on its level."""
        start = time.perf_counter()
        here = self.level
        r = residue if self.residue is None else self.residue
        filterer = self.filterer(here)
        factorizations = filterer.n_factorizations
        cut = filterer.cut(r)
        if cut is None:
            return None
        t, _, info = cut
        # without the potential here, the Riesz stage takes its band quadrature
        passed, potential = filterer.filtered_with_potential(t, r, info, potential=filterer.with_potential)
        low = r - passed
        target = self.hierarchy.coarsest_resolving(info["cut_frequency"], SPACING_LIMIT, here)
        carried = self.hierarchy.restrict(low, here, target)
        back = self.hierarchy.prolong(carried, target, here)
        level_imf = r - back
        mass = filterer.mass
        norm = math.sqrt(float(mass @ low**2))
        info.update(
            level=here,
            level_vertices=len(r),
            residue_level=target,
            transfer_error=math.sqrt(float(mass @ (low - back) ** 2)) / norm if norm > 0 else 0.0,
            factorizations=filterer.n_factorizations - factorizations,
        )
        if potential is not None and target > here:  # the transfer's remainder e = low − back is in the IMF too
            remainder = filterer.potential(t, low - back, _remainder_tolerance(mass, r, info["transfer_error"] * norm))
            potential = None if remainder is None else potential + remainder
        info["seconds"] = time.perf_counter() - start  # with the remainder's pass: 18 s of IMF 3 on a 1M cloud
        # a polynomial IMF is (r − low) + e: its potential is that of r + e through the filter
        self.levels.append((here, level_imf, level_imf + low if "degree" in info else None, potential))
        self.residue, self.level = carried, target
        if target > here:  # residues never come back: free the level's factorization now
            self._retire(here)
        return self.hierarchy.to_finest(level_imf, here), info

    def _retire(self, index: int) -> None:
        """Drop the filterer of level ``index`` (its factorizations), keeping its counts for :meth:`totals`."""
        filterer = self.filterers.pop(index)
        self.retired[index] = _counts(filterer)

    def totals(self) -> dict:
        """Run totals over the levels for ``EMDResult.info``, with ``levels``: the vertices of each level used."""
        if not self.filterers and not self.retired:
            self.filterer(0)
        counts = dict(self.retired)
        counts.update({i: _counts(f) for i, f in self.filterers.items()})
        used = sorted(counts)
        return {
            "sifts": 0,
            "solves": sum(counts[i][0] for i in used),
            "products": sum(counts[i][1] for i in used),
            "max_constraint_error": 0.0,
            "factorizations": sum(counts[i][2] for i in used),
            "backend": "+".join(dict.fromkeys(name for i in used for name in counts[i][3].split("+"))),
            "levels": [self.hierarchy.levels[i].surface.n_vertices for i in used],
        }


def _remainder_tolerance(mass: np.ndarray, r: np.ndarray, remainder_norm: float) -> float:
    """The series tolerance of the remainder's potential that bounds its error, ``tol ‖e‖``, by the error
    of the filter's own pass on ``r``, ``POTENTIAL_TOLERANCE ‖r‖`` (norms in ``M̃``): ``‖e‖`` is the transfer
    error's share of the low-pass, 0.04–1.6%, so the series can stop 1–2 decades earlier (20–35% fewer
    products); at most :data:`REMAINDER_TOLERANCE`."""
    scale = math.sqrt(float(mass @ r**2)) / remainder_norm if remainder_norm > 0 else math.inf
    return min(REMAINDER_TOLERANCE, POTENTIAL_TOLERANCE * scale)


def _counts(filterer: Filterer) -> tuple[int, int, int, str]:
    """A level's solves, polynomial products, factorizations and backend."""
    return filterer.n_solves, filterer.n_products, filterer.n_factorizations, filterer.backend_name
