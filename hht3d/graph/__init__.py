"""The lazy Dask layer: one task per stage over the core.

Data flow: :mod:`.tasks` (how tasks are made and surfaces shared) →
:mod:`.stages` (the lazy twins of the core functions).  Many files fan out in
:mod:`hht3d.dataset`; graphs run on the schedulers of :mod:`hht3d.execution`
(:func:`compute` is re-exported here).
"""

from ..execution import SCHEDULERS, compute, open_client, worker_count
from . import stages
from .stages import (
    eemd,
    emd,
    filter_geometry,
    filter_signal,
    hht,
    hks_features,
    imf_enhancement,
    load,
    manifold_harmonics_filter,
    mirror,
    monogenic,
    monogenic_from_potential,
    operators,
    prominent_features,
    reconstruct,
    save,
    signal,
    transform,
    transform_file,
)
from .tasks import Builder, as_key, from_surface, resident, riesz_potential

__all__ = ["SCHEDULERS", "open_client", "worker_count"]
__all__ += stages.__all__  # the lazy twins and the task-building names
