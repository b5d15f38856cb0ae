"""The operations a pipeline step can name, with their inputs, output and parameters.

Every operation takes *slots* (named inputs, each accepting results of some
kinds) and produces one result of one kind:

=========  ==============================================================
kind       value
=========  ==============================================================
file       the input file of the current item (only ``load`` takes it)
surface    :class:`~hht3d.geometry.surface.Surface`
signal     ``(n,)`` array
emd        :class:`~hht3d.decomposition.decompose.EMDResult`
hht        :class:`~hht3d.transform.HHTResult`
features   :class:`~hht3d.apps.FeatureResult`
=========  ==============================================================

An operation is data: the core function it runs, its slots (the
function's leading positional arguments, in order), its output kind and its
parameters (the function's keyword arguments: the settings of its option
record, read by :func:`~hht3d.pipeline.params.record_params`, so that a
type, range, default or description is written once, beside the function).
:meth:`Operation.tasks` makes the step's lazy task from that alone.  An
operation whose work is several tasks (EEMD members, the HHT stages) names
a ``build`` function of :mod:`hht3d.graph.stages` instead.  ``hht3d ops`` prints
this registry.

Adding an operation
-------------------
Write the core function (e.g. in :mod:`hht3d.apps`) taking ``(…, options=None,
**overrides)`` with its settings in an option record beside it
(``SmoothOptions`` with ``time: float = option(1.0, "diffusion time", minimum=0)``),
then add one entry to :data:`OPERATIONS`::

    Operation("smooth", "heat-flow smoothing of a signal", (_SURFACE, _SIGNAL_IN), "signal",
              record_params(SmoothOptions), func=smooth),

Its lazy twin, if wanted outside pipelines, is one line in
:mod:`hht3d.graph.stages`: ``smooth = mirror(smooth)``.  Another package adds operations
without changing this file through an entry point (:mod:`hht3d.pipeline.plugins`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from .. import graph, linalg
from ..apps import (
    filter_geometry,
    filter_signal,
    hks_features,
    imf_enhancement,
    manifold_harmonics_filter,
    prominent_features,
    reconstruct,
)
from ..apps.baselines import EnhancementOptions, HarmonicFilterOptions, HKSOptions
from ..apps.features import FeatureOptions
from ..apps.geometry_filter import FilterOptions
from ..apps.reconstruction import ReconstructionOptions
from ..decomposition.decompose import emd
from ..decomposition.ensemble import ensemble_settings
from ..decomposition.options import EMDOptions, EnsembleOptions
from ..errors import InputError, PipelineError
from ..geometry.signals import SIGNALS, check_signal_path, signal
from ..graph.tasks import GraphOptions
from ..io.read import LoadOptions, load
from ..spectral.options import RieszOptions
from ..transform import decomposition_stage
from . import python_step
from .params import REQUIRED, Param, record_params

if TYPE_CHECKING:
    from hht3d.geometry.surface import Surface
    from hht3d.graph.tasks import Builder


__all__ = ["Slot", "Operation", "OPERATIONS", "RENAMED"]


class _Solvers(Sequence):
    """The names of :data:`hht3d.linalg.backends.SOLVER_BACKENDS`, read at each use, so that a backend
    registered after import is a ``backend:`` choice too (availability is checked when a step runs)."""

    def __getitem__(self, index: Any) -> Any:
        return tuple(linalg.backends.SOLVER_BACKENDS)[index]

    def __len__(self) -> int:
        return len(linalg.backends.SOLVER_BACKENDS)

    def __repr__(self) -> str:
        return repr(tuple(self))


#: The ``backend:`` choices: every registered sparse solver backend, fastest first.
SOLVERS = _Solvers()


@dataclass(frozen=True)
class Slot:
    """A named input of an operation and the result kinds it accepts."""

    name: str
    kinds: tuple[str, ...]


@dataclass(frozen=True)
class Operation:
    """A registered operation: what it runs, takes, makes and accepts as parameters.

    Parameters
    ----------
    name, summary : str
        The ``op:`` of a step, and one line for ``hht3d ops``.
    slots : tuple of Slot
        The named inputs, passed to ``func`` (or ``build``) positionally, in order.
    output : str
        The kind of the result (module notes).
    params : tuple of Param
        The parameters, passed as keyword arguments.
    func : callable, optional
        The core function: the step is one task ``func(*inputs, **params)``.
    build : callable, optional
        Instead of ``func``: ``build(builder, *inputs, **params)`` makes the
        step's tasks (:mod:`hht3d.graph.stages`) and returns the result's task, or
        the tasks by stage name with the result under ``"result"``.
    check : callable, optional
        ``check(params, where)`` raises :class:`PipelineError` for
        parameter combinations the types cannot express.
    vertices : callable, optional
        ``vertices(params)`` gives ``(parameter, count)``: the fewest vertices an input needs.
    kind_of : callable, optional
        ``kind_of(params)`` gives the result's kind when a parameter chooses it (``output`` is the default).
    """

    name: str
    summary: str
    slots: tuple[Slot, ...]
    output: str
    params: tuple[Param, ...]
    func: Callable | None = field(default=None, repr=False)
    build: Callable | None = field(default=None, repr=False)
    check: Callable | None = field(default=None, repr=False)
    vertices: Callable | None = field(default=None, repr=False)
    kind_of: Callable | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        if (self.func is None) == (self.build is None):
            raise ValueError(f"operation {self.name}: give exactly one of func and build")

    def param(self, name: str) -> Param | None:
        return next((p for p in self.params if p.name == name), None)

    def tasks(self, builder: Builder, inputs: dict, params: dict) -> dict:
        """The step's lazy tasks by name, its result under ``"result"``.

        ``inputs`` are the slots' values by slot name, ``params`` the checked parameters.
        """
        args = [inputs[slot.name] for slot in self.slots]
        if self.func is not None:
            return {"result": builder.task(self.name, self.func)(*args, **params)}
        made = cast(Callable[..., Any], self.build)(builder, *args, **params)  # func or build is set
        return made if isinstance(made, dict) else {"result": made}

    def output_kind(self, params: dict) -> str:
        """The kind of the result for these parameters."""
        return self.output if self.kind_of is None else self.kind_of(params)

    def fewest_vertices(self, params: dict) -> tuple[str, int] | None:
        """``(parameter, count)``: the fewest vertices an input needs for these parameters, if any."""
        return None if self.vertices is None else self.vertices(params)


# -- parameters -------------------------------------------------------------------------------------
# Every numeric parameter has a range, which `hht3d ops` prints; each is declared once, in the option
# record beside the function that uses it (records.option), with an upper bound far above useful
# values that stops a typo from hanging validation or a run.  Parameters in model units
# (merge_radius, time, gain frequencies) scale with the model and are only required to be finite.

#: Former parameter names and their new ones, named in the message that refuses them.
RENAMED = dict(RieszOptions.renamed)

_BACKEND = Param("backend", "choice", "sparse solver (default: the fastest installed)", default=None, choices=SOLVERS)

LOAD = record_params(LoadOptions)

SIGNAL = (
    Param(
        "kind",
        "choice",
        "which signal; mean_curvature is Eq. 24",
        default=REQUIRED,
        choices=(*SIGNALS, "stored", "file"),
    ),
    Param("attribute", "str", "vertex property of the file, with kind: stored", default=None),
    Param("path", "str", "a .npy file of one value per vertex, with kind: file", default=None),
)

EMD = (*record_params(EMDOptions), _BACKEND)


def _optional(params: tuple[Param, ...], **docs: str) -> tuple[Param, ...]:
    """``params`` with those named in ``docs`` made optional (default null), described anew."""
    return tuple(dataclasses.replace(p, default=None, doc=docs[p.name]) if p.name in docs else p for p in params)


ENSEMBLE = _optional(record_params(EnsembleOptions), seed="EEMD noise seed (default: execution.seed)")
SPECTRA = (*record_params(RieszOptions), *record_params(GraphOptions))
HHT = (
    *record_params(EMDOptions),
    *_optional(ENSEMBLE, ensemble_size="use EEMD with this many members (default: plain EMD)"),
    *SPECTRA,
    _BACKEND,
)

_GAIN = Param(
    "gain", "gain", "μ(ω) of the instantaneous frequency, e.g. {kind: band_stop, low: 8, high: 20}", default=REQUIRED
)


# -- checks and builders -------------------------------------------------------------------------
def _check_signal(params: dict, where: str) -> None:
    kind = params["kind"]
    needs = {"stored": "attribute", "file": "path"}
    for name in ("attribute", "path"):
        if params[name] is not None and needs.get(kind) != name:
            raise PipelineError(
                f"{where}: parameter {name} is only used with kind: "
                f"{'stored' if name == 'attribute' else 'file'} (kind is {kind})"
            )
    if kind in needs and params[needs[kind]] is None:
        raise PipelineError(f"{where}: kind: {kind} needs the parameter {needs[kind]}")
    if kind == "file":
        try:
            check_signal_path(params["path"])
        except InputError as exc:
            raise PipelineError(f"{where}: {exc}") from None


def _eigenpair_vertices(params: dict) -> tuple[str, int] | None:
    """``k`` eigenpairs exclude the constant mode, so need ``k + 1`` vertices (with potential spectral)."""
    if params.get("potential", "spectral") != "spectral":
        return None
    return "eigenpairs", params["eigenpairs"] + 1


def _hht_tasks(
    builder: Builder,
    surface: Surface,
    signal: np.ndarray,
    *,
    backend: str | None,
    riesz_tasks: int | None,
    **settings: Any,
) -> dict:
    """The HHT's stages (:func:`hht3d.graph.transform`) from the step's flat settings; EEMD when
    ``ensemble_size`` is given."""
    if settings["ensemble_size"] is None:
        settings = {k: v for k, v in settings.items() if k not in EnsembleOptions.specs()}
    stages = graph.transform(builder, surface, signal, backend=backend, riesz_tasks=riesz_tasks, **settings)
    return {**stages, "result": stages["hht"]}


def _eemd_tasks(builder: Builder, surface: Surface, signal: np.ndarray, *, backend: str | None, **settings: Any) -> Any:
    """EEMD's member and averaging tasks from the step's flat settings."""
    return decomposition_stage(builder, surface, signal, *ensemble_settings(None, None, settings), backend)


_SURFACE = Slot("surface", ("surface",))
_SIGNAL_IN = Slot("signal", ("signal",))
_IMFS = Slot("imfs", ("emd", "hht"))
_HHT = Slot("hht", ("hht",))

#: The operations by name.
OPERATIONS: dict[str, Operation] = {
    op.name: op
    for op in (
        Operation(
            "load",
            "read a mesh or point cloud (PLY, OBJ, OFF, STL, GLB, PCD, XYZ, ...)",
            (Slot("file", ("file",)),),
            "surface",
            LOAD,
            func=load,
        ),
        Operation(
            "signal",
            "a per-vertex signal: mean curvature (Eq. 24), coordinates, colour, stored values",
            (_SURFACE,),
            "signal",
            SIGNAL,
            func=signal,
            check=_check_signal,
        ),
        Operation(
            "emd",
            "empirical mode decomposition: envelope sifting (Sec. 4.1) or iterative filtering (method)",
            (_SURFACE, _SIGNAL_IN),
            "emd",
            EMD,
            func=emd,
        ),
        Operation(
            "eemd",
            "ensemble EMD: one task per noisy member, then the average",
            (_SURFACE, _SIGNAL_IN),
            "emd",
            ENSEMBLE + EMD,
            build=_eemd_tasks,
        ),
        Operation(
            "hht",
            "Hilbert–Huang transform: EMD, Riesz transform, Hilbert spectra (Alg. 2)",
            (_SURFACE, _SIGNAL_IN),
            "hht",
            HHT,
            build=_hht_tasks,
            vertices=_eigenpair_vertices,
        ),
        Operation(
            "filter_signal",
            "the signal through a gain of the instantaneous frequency (Eq. 26)",
            (_HHT,),
            "signal",
            (_GAIN,),
            func=filter_signal,
        ),
        Operation(
            "filter_geometry",
            "Hilbert-spectrum filtering of the mean curvature and new positions (Eqs. 26-27)",
            (_HHT,),
            "surface",
            (_GAIN, *record_params(FilterOptions), _BACKEND),
            func=filter_geometry,
        ),
        Operation(
            "reconstruct",
            "new positions whose mean curvature is the given signal (Eq. 27)",
            (_SURFACE, _SIGNAL_IN),
            "surface",
            (*record_params(ReconstructionOptions), _BACKEND),
            func=reconstruct,
        ),
        Operation(
            "features",
            "prominent feature points from IMF extrema counts (Sec. 5.2)",
            (_SURFACE, _IMFS),
            "features",
            record_params(FeatureOptions),
            func=prominent_features,
        ),
        Operation(
            "hks_features",
            "baseline: maxima of the heat kernel signature (Sun et al. 2009)",
            (_SURFACE,),
            "features",
            (*record_params(HKSOptions), _BACKEND),
            func=hks_features,
            vertices=_eigenpair_vertices,
        ),
        Operation(
            "imf_enhancement",
            "baseline: scale one IMF of the mean curvature (Hu et al. 2014)",
            (_SURFACE, _IMFS),
            "surface",
            (*record_params(EnhancementOptions), _BACKEND),
            func=imf_enhancement,
        ),
        Operation(
            "manifold_harmonics_filter",
            "baseline: filter in the Laplacian eigenbasis (Vallet & Lévy 2008)",
            (_SURFACE,),
            "surface",
            (_GAIN, *record_params(HarmonicFilterOptions), _BACKEND),
            func=manifold_harmonics_filter,
            vertices=_eigenpair_vertices,
        ),
        Operation(
            python_step.NAME,
            "call an importable function module:function on a step's result (runs code: --allow-plugins)",
            (Slot("input", tuple(python_step.RESULTS)),),
            "signal",
            python_step.PARAMS,
            func=python_step.call,
            check=python_step.check_function,
            kind_of=lambda params: params["output"],
        ),
    )
}
