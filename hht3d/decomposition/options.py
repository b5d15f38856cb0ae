"""The settings of EMD and ensemble EMD, checked once, with their presets.

:class:`EMDOptions` holds every setting of :func:`~hht3d.decomposition.emd`
and :class:`EnsembleOptions` those of the noise ensemble of
:func:`~hht3d.decomposition.eemd`.  Each field declares its range and a
one-line description (:func:`hht3d.records.option`); the pipeline's
parameters, ``hht3d ops`` and the JSON Schema are read from them.  Presets
are instances: vary them with :func:`dataclasses.replace` or by passing
overrides to the function.

Examples
--------
>>> import dataclasses
>>> from hht3d.decomposition.options import EMDOptions, PAPER_OPTIONS
>>> EMDOptions().sd_threshold
0.2
>>> EMDOptions(envelope="biharmonic").tensions
(0.0, 3.0, 12.0, 48.0, inf)
>>> dataclasses.replace(PAPER_OPTIONS, max_imfs=3).envelope
'biharmonic'
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..records import Record, option

__all__ = [
    "EMDOptions",
    "EnsembleOptions",
    "EMD_DEFAULTS",
    "ENSEMBLE_DEFAULTS",
    "PAPER_OPTIONS",
    "FILTERING_OPTIONS",
    "STOPPING_RULES",
    "METHODS",
    "FILTERS",
    "CUTS",
    "MULTIRESOLUTION",
    "EVALUATIONS",
    "ENVELOPES",
    "EXTREMA_RULES",
    "GUARD_TENSIONS",
    "start_tension",
]

#: Decomposition methods: envelope sifting (Sec. 4.1, :mod:`.sifting`) or iterative filtering (:mod:`.filtering`).
METHODS = ("sifting", "filtering")
#: Low-pass resolvents of iterative filtering: ``(M̃ + t² L M̃⁻¹ L)⁻¹ M̃`` or ``(M̃ + t L)⁻¹ M̃``.
FILTERS = ("bilaplacian", "membrane")
#: Cuts of iterative filtering: one frequency for the surface, or one per vertex from the local extrema spacing.
CUTS = ("global", "local")
#: When iterative filtering carries its residues on coarser levels (:mod:`.multiresolution`).
MULTIRESOLUTION = ("auto", "always", "never")
#: How iterative filtering applies its pass band: sparse solves, or a Chebyshev polynomial (:mod:`.filtering`).
EVALUATIONS = ("auto", "solves", "polynomial")
#: Sifting stopping rules.
STOPPING_RULES = ("sd", "rfg", "s_number", "fixed")
#: Envelope interpolants: thin plate in tension (default), the paper's thin plate (Eq. 11), membrane.
ENVELOPES = ("tension", "biharmonic", "harmonic")
#: Extremum rules: above all of the 1-ring (``strict``), or above a fraction ``ratio`` of the ``ring``-ring
#: (``relaxed``, Sec. 5.2).
EXTREMA_RULES = ("strict", "relaxed")
#: Tensions the cancellation guard tries, in order, above the starting one; then the harmonic envelope.
GUARD_TENSIONS = (3.0, 12.0, 48.0)

# Upper bounds lie far above useful values; they stop a typo from hanging a run.
#: IMFs: more than log2 of the vertex count of any mesh that fits in memory.
MAX_IMFS = 64
#: Sifts per IMF (each solves one envelope system per extremum kind).
MAX_SIFTS = 1000
#: Envelope tension (scale-free; the cancellation guard stops at 48, then goes harmonic).
MAX_TENSION = 1000
#: ``m`` of iterative filtering's pass band (``2m − 1`` solves per IMF).
MAX_ORDER = 64
#: Neighbourhood rings of extrema.
MAX_RING = 16
#: EEMD members (Wu & Huang 2009 use 100); one graph task each.
MAX_ENSEMBLE = 1000
#: Random seeds (numpy's SeedSequence takes any non-negative integer; YAML and JSON need a bound).
MAX_SEED = 2**32 - 1


def start_tension(envelope: str, tension: float) -> float:
    """The tension ``τ`` an envelope starts from: ``tension``, 0 (thin plate) or ``inf`` (membrane).

    Parameters
    ----------
    envelope : str
        The envelope: ``"tension"``, ``"biharmonic"`` or ``"harmonic"``.
    tension : float
        The tension of a ``"tension"`` envelope.

    Returns
    -------
    float
        The starting tension ``τ``.

    Examples
    --------
    >>> from hht3d.decomposition import start_tension
    >>> start_tension("tension", 5.0), start_tension("biharmonic", 5.0), start_tension("harmonic", 5.0)
    (5.0, 0.0, inf)
    """
    return {"tension": float(tension), "biharmonic": 0.0, "harmonic": math.inf}[envelope]


@dataclass(frozen=True)
class EMDOptions(Record):
    """The settings of :func:`~hht3d.decomposition.emd` (Sec. 4.1), checked on creation.

    Frozen, so that one value describes one decomposition (it is recorded in
    ``EMDResult.info["options"]``).  The sparse-solver ``backend`` is not a
    setting of the method and is passed apart.  The meaning of each field is
    documented at :func:`~hht3d.decomposition.emd`.

    Raises
    ------
    InputError
        An unknown choice, a value out of range, a non-integer count.
    """

    label = "EMD"

    method: str = option(
        "sifting", "decomposition: envelope sifting (Sec. 4.1) or iterative filtering", choices=METHODS
    )
    max_imfs: int = option(10, "at most this many IMFs", minimum=0, maximum=MAX_IMFS)
    stopping: str = option("sd", "sifting stop rule", choices=STOPPING_RULES)
    sd_threshold: float = option(0.2, "SD stopping threshold", minimum=0, maximum=10)
    s_number: int = option(4, "S-number: unchanged extrema counts in a row", minimum=1, maximum=100)
    fixed_sifts: int = option(10, "sifts per IMF with stopping: fixed", minimum=1, maximum=MAX_SIFTS)
    max_sifts: int = option(50, "cap on sifts per IMF", minimum=1, maximum=MAX_SIFTS)
    envelope: str = option(
        "tension",
        "envelope interpolant: thin plate in tension, the paper's thin plate (Eqs. 8, 11) or membrane",
        choices=ENVELOPES,
    )
    tension: float = option(
        3.0, "tension of the envelope, relative to the extrema spacing", minimum=0, maximum=MAX_TENSION
    )
    cancellation_tolerance: float | None = option(
        0.05,
        "largest energy increase one IMF may cause before more tension is tried (null: no guard)",
        minimum=0,
        maximum=1,
        nullable=True,
    )
    mean_correction: float | None = option(
        0.6,
        "move each IMF's part slower than this many of its wavelengths to the residue (null: off)",
        minimum=0,
        maximum=10,
        nullable=True,
    )
    extrema: str = option(
        "strict",
        "extremum rule: above the whole 1-ring, or above ratio of the ring-ring (Sec. 5.2)",
        choices=EXTREMA_RULES,
    )
    ring: int = option(2, "neighbourhood in edges of the relaxed extremum rule", minimum=1, maximum=MAX_RING)
    ratio: float = option(
        0.8, "fraction of the neighbourhood a relaxed extremum exceeds", minimum=0.5, maximum=1, open_minimum=True
    )
    boundary_extrema: bool = option(
        False, "let open-boundary vertices be extrema (the paper's rule; a trend then enters the IMFs)"
    )
    energy_threshold: float = option(1e-8, "stop when the residue keeps less of the energy", minimum=0, maximum=1)
    filter: str = option("bilaplacian", "method filtering: the low-pass resolvent", choices=FILTERS)
    order: int = option(
        16, "method filtering: m of the pass band 1 - I_G(m, m), sharper as it grows", minimum=1, maximum=MAX_ORDER
    )
    cut: str = option("global", "method filtering: one cut for the surface or one per vertex", choices=CUTS)
    cut_ratio: float = option(
        1.5, "method filtering: the cut lies this many times below the extrema frequency", minimum=0.25, maximum=16
    )
    multiresolution: str = option(
        "auto",
        "method filtering: carry each residue on the coarsest level that resolves it "
        "(auto: from 10,000 vertices, the measured crossover)",
        choices=MULTIRESOLUTION,
    )
    evaluation: str = option(
        "auto",
        "method filtering: apply the pass band by sparse solves or by a Chebyshev polynomial, products only "
        "(auto: on levels from 2,000,000 vertices, or 20,000 with SuperLU; global cut only)",
        choices=EVALUATIONS,
    )

    @property
    def tensions(self) -> tuple[float, ...]:
        """The starting tension, then those the cancellation guard may try (:mod:`.sifting`)."""
        start = start_tension(self.envelope, self.tension)
        if self.cancellation_tolerance is None:
            return (start,)
        return (start, *(t for t in GUARD_TENSIONS if t > start), *((math.inf,) if start < math.inf else ()))


@dataclass(frozen=True)
class EnsembleOptions(Record):
    """The noise ensemble of :func:`~hht3d.decomposition.eemd` (Wu & Huang 2009)."""

    label = "EEMD"

    ensemble_size: int = option(100, "EEMD members", minimum=1, maximum=MAX_ENSEMBLE)
    noise_std: float = option(0.2, "EEMD noise, relative to the signal's standard deviation", minimum=0, maximum=10)
    seed: int = option(0, "EEMD noise seed", minimum=0, maximum=MAX_SEED)


#: The defaults of :func:`~hht3d.decomposition.emd`.
EMD_DEFAULTS = EMDOptions()
#: The defaults of :func:`~hht3d.decomposition.eemd`'s ensemble.
ENSEMBLE_DEFAULTS = EnsembleOptions()
#: The paper's EMD (Sec. 4.1): thin-plate envelopes, no cancellation guard, no local-mean correction.
PAPER_OPTIONS = EMDOptions(
    envelope="biharmonic", cancellation_tolerance=None, mean_correction=None, boundary_extrema=True
)
#: Iterative filtering (:mod:`.filtering`) with its calibrated settings: bilaplacian resolvent, ``m = 16``,
#: a global cut 1.5 times below the extrema frequency.
FILTERING_OPTIONS = EMDOptions(method="filtering")
