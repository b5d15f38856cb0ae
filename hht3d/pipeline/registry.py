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
parameters (the function's keyword arguments, with types and ranges;
defaults read from the function's signature by
:func:`~hht3d.pipeline.params.with_defaults`).
:meth:`Operation.tasks` makes the step's lazy task from that alone.  An
operation whose work is several tasks (EEMD members, the HHT stages) names
a ``build`` function of :mod:`hht3d.graph.stages` instead.  ``hht3d ops`` prints
this registry.

Adding an operation
-------------------
Write the core function (e.g. in :mod:`hht3d.apps`), then add one entry to
:data:`OPERATIONS`::

    Operation("smooth", "heat-flow smoothing of a signal", (_SURFACE, _SIGNAL_IN), "signal",
              with_defaults(smooth, Param("time", "float", "diffusion time", minimum=0)),
              func=smooth),

Its lazy twin, if wanted outside pipelines, is one line in
:mod:`hht3d.graph.stages`: ``smooth = mirror(smooth)``.
"""
from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from .. import graph, linalg
from ..apps import (filter_geometry, filter_signal, hks_features, imf_enhancement, manifold_harmonics_filter,
                    prominent_features, reconstruct)
from ..decomposition.decompose import emd
from ..decomposition.options import MAX_ENSEMBLE, MAX_IMFS, MAX_RING, MAX_SEED, EMDOptions, EnsembleOptions
from ..errors import InputError, PipelineError, shown
from ..io.read import load
from ..spectral.options import MAX_EIGENPAIRS, RieszOptions
from ..transform import decomposition_stage
from ..geometry.signals import SIGNALS, check_signal_path, signal
from ..geometry.surface import LAPLACIANS
from .params import REQUIRED, Param, did_you_mean, record_params, with_defaults

__all__ = ["Slot", "Operation", "OPERATIONS", "operation"]


class _Solvers(Sequence):
    """The names of :data:`hht3d.linalg.backends.SOLVER_BACKENDS`, read at each use, so that a backend
    registered after import is a ``backend:`` choice too (availability is checked when a step runs)."""

    def __getitem__(self, index):
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

    def __post_init__(self):
        if (self.func is None) == (self.build is None):
            raise ValueError(f"operation {self.name}: give exactly one of func and build")

    def param(self, name: str) -> Param | None:
        return next((p for p in self.params if p.name == name), None)

    def tasks(self, builder, inputs: dict, params: dict) -> dict:
        """The step's lazy tasks by name, its result under ``"result"``.

        ``inputs`` are the slots' values by slot name, ``params`` the checked parameters.
        """
        args = [inputs[slot.name] for slot in self.slots]
        if self.func is not None:
            return {"result": builder.task(self.name, self.func)(*args, **params)}
        made = self.build(builder, *args, **params)
        return made if isinstance(made, dict) else {"result": made}

    def fewest_vertices(self, params: dict) -> tuple[str, int] | None:
        """``(parameter, count)``: the fewest vertices an input needs for these parameters, if any."""
        return None if self.vertices is None else self.vertices(params)


# -- upper bounds -----------------------------------------------------------------------------------
# Every numeric parameter has a range, which `hht3d ops` prints.  The upper bounds lie far above
# useful values; they stop a typo from hanging validation or a run (a billion EEMD tasks, 100,000
# shift-group tasks, a dense block of a million eigenvectors).  Parameters in model units
# (merge_radius, time, gain frequencies) scale with the model and are only required to be finite.
# The settings of EMD, EEMD and the Riesz transform declare theirs in their option records.

#: Shift-group tasks of the Riesz quadrature, which has about 60 shifts even at the finest tol.
MAX_RIESZ_TASKS = 64
#: Neighbours of the point-cloud Laplacian and normals.
MAX_NEIGHBORS = 256
#: Position weights μ of Eq. 27 (the paper's are 0.01 and 1).
MAX_WEIGHT = 1e6
#: IMF factor of the enhancement baseline.
MAX_FACTOR = 1e3


# -- parameters -------------------------------------------------------------------------------------
_BACKEND = Param("backend", "choice", "sparse solver (default: the fastest installed)", default=None,
                 choices=SOLVERS)

LOAD = with_defaults(
    load,
    Param("clean", "bool", "weld duplicate vertices, drop degenerate faces and unused vertices"),
    Param("laplacian", "choice", "mesh Laplacian (point clouds always use the robust one)", choices=LAPLACIANS),
    Param("n_neighbors", "int", "neighbours of the point-cloud Laplacian and normals", minimum=3,
          maximum=MAX_NEIGHBORS),
)

SIGNAL = (
    Param("kind", "choice", "which signal; mean_curvature is Eq. 24", default=REQUIRED,
          choices=(*SIGNALS, "stored", "file")),
    Param("attribute", "str", "vertex property of the file, with kind: stored", default=None),
    Param("path", "str", "a .npy file of one value per vertex, with kind: file", default=None),
)

EMD = (*record_params(EMDOptions), _BACKEND)

_SEED = Param("seed", "int", "EEMD noise seed (default: execution.seed)", default=None, minimum=0,
              maximum=MAX_SEED)
ENSEMBLE = (*(p for p in record_params(EnsembleOptions) if p.name != "seed"), _SEED)

_RIESZ_TASKS = Param("riesz_tasks", "int", "parallel shift-group tasks of the quadrature (default: one per "
                     "worker)", default=None, minimum=1, maximum=MAX_RIESZ_TASKS)
SPECTRA = (*record_params(RieszOptions), _RIESZ_TASKS)

HHT = (
    *record_params(EMDOptions),
    Param("ensemble_size", "int", "use EEMD with this many members (default: plain EMD)", default=None,
          minimum=1, maximum=MAX_ENSEMBLE),
    *(p for p in ENSEMBLE if p.name != "ensemble_size"),
    *SPECTRA,
    _BACKEND,
)

def _weights(func, when_null: str = "") -> tuple[Param, ...]:
    """The Eq. 27 position weights of ``func`` (reconstruct or filter_geometry), its defaults."""
    return with_defaults(
        func,
        Param("interior_weight", "float", f"position weight μ of interior vertices (Eq. 27){when_null}", minimum=0,
              maximum=MAX_WEIGHT, open_minimum=True),
        Param("boundary_weight", "float", f"position weight μ of boundary vertices (Eq. 27){when_null}", minimum=0,
              maximum=MAX_WEIGHT, open_minimum=True),
        Param("preserve_scale", "bool", "remove the mean curvature change per component"),
    )


_WEIGHTS = _weights(reconstruct)
_FILTER_WEIGHTS = _weights(filter_geometry, "; null: from the gain, positions hold below a third of the "
                                                 "lowest edited frequency")
_GAIN = Param("gain", "gain", "μ(ω) of the instantaneous frequency, e.g. {kind: band_stop, low: 8, high: 20}",
              default=REQUIRED)

FEATURES = with_defaults(
    prominent_features,
    Param("ratio", "float", "a maximum is >= this fraction of its ring", minimum=0.5, maximum=1,
          open_minimum=True),
    Param("ring", "int", "neighbourhood in edges", minimum=1, maximum=MAX_RING),
    Param("fraction", "float", "hit: extremum of at least this fraction of the IMFs", minimum=0, maximum=1,
          open_minimum=True),
    Param("merge_radius", "float", "merge hits closer than this (model units)", minimum=0),
)

HKS = with_defaults(
    hks_features,
    Param("time", "float", "diffusion time (default: a fraction of 4 ln 10 / λ1)", minimum=0,
          open_minimum=True),
    Param("eigenpairs", "int", "eigenpairs in the heat-kernel sum", minimum=1, maximum=MAX_EIGENPAIRS),
    Param("ring", "int", "neighbourhood in edges", minimum=1, maximum=MAX_RING),
    Param("merge_radius", "float", "merge maxima closer than this (model units)", minimum=0),
) + (_BACKEND,)

ENHANCE = with_defaults(
    imf_enhancement,
    Param("factor", "float", "multiply the IMF by this", minimum=-MAX_FACTOR, maximum=MAX_FACTOR),
    Param("index", "int", "which IMF, from 0 (the finest)", minimum=0, maximum=MAX_IMFS - 1),
) + _WEIGHTS + (_BACKEND,)

MHB = with_defaults(
    manifold_harmonics_filter,
    Param("eigenpairs", "int", "Laplacian eigenpairs of the basis", minimum=1, maximum=MAX_EIGENPAIRS),
    Param("keep_remainder", "bool", "keep the part of the shape beyond the basis"),
) + (_BACKEND,)


# -- checks and builders -------------------------------------------------------------------------
def _check_signal(params, where):
    kind = params["kind"]
    needs = {"stored": "attribute", "file": "path"}
    for name in ("attribute", "path"):
        if params[name] is not None and needs.get(kind) != name:
            raise PipelineError(f"{where}: parameter {name} is only used with kind: "
                                f"{'stored' if name == 'attribute' else 'file'} (kind is {kind})")
    if kind in needs and params[needs[kind]] is None:
        raise PipelineError(f"{where}: kind: {kind} needs the parameter {needs[kind]}")
    if kind == "file":
        try:
            check_signal_path(params["path"])
        except InputError as exc:
            raise PipelineError(f"{where}: {exc}") from None


def _eigenpair_vertices(params) -> tuple[str, int] | None:
    """``k`` eigenpairs exclude the constant mode, so need ``k + 1`` vertices (with method spectral)."""
    if params.get("method", "spectral") != "spectral":
        return None
    return "eigenpairs", params["eigenpairs"] + 1


def _hht_tasks(builder, surface, signal, **params):
    """The HHT's stages (:func:`hht3d.graph.transform`) from the step's flat parameters."""
    emd, riesz, ensemble = ({k: params[k] for k in record.specs() if k in params}
                            for record in (EMDOptions, RieszOptions, EnsembleOptions))
    stages = graph.transform(builder, surface, signal, emd=emd, riesz=riesz,
                             ensemble=ensemble if ensemble["ensemble_size"] is not None else None,
                             backend=params["backend"], riesz_tasks=params["riesz_tasks"])
    return {**stages, "result": stages["hht"]}


def _eemd_tasks(builder, surface, signal, **params):
    """EEMD's member and averaging tasks from the step's flat parameters."""
    emd, ensemble = (record.of({k: params[k] for k in record.specs()}) for record in (EMDOptions, EnsembleOptions))
    return decomposition_stage(builder, surface, signal, emd, ensemble, params["backend"])


_SURFACE = Slot("surface", ("surface",))
_SIGNAL_IN = Slot("signal", ("signal",))
_IMFS = Slot("imfs", ("emd", "hht"))
_HHT = Slot("hht", ("hht",))

#: The operations by name.
OPERATIONS: dict[str, Operation] = {op.name: op for op in (
    Operation("load", "read a mesh or point cloud (PLY, OBJ, OFF, STL, GLB, PCD, XYZ, ...)",
              (Slot("file", ("file",)),), "surface", LOAD, func=load),
    Operation("signal", "a per-vertex signal: mean curvature (Eq. 24), coordinates, colour, stored values",
              (_SURFACE,), "signal", SIGNAL, func=signal, check=_check_signal),
    Operation("emd", "empirical mode decomposition with thin-plate envelopes (Sec. 4.1)",
              (_SURFACE, _SIGNAL_IN), "emd", EMD, func=emd),
    Operation("eemd", "ensemble EMD: one task per noisy member, then the average",
              (_SURFACE, _SIGNAL_IN), "emd", ENSEMBLE + EMD, build=_eemd_tasks),
    Operation("hht", "Hilbert–Huang transform: EMD, Riesz transform, Hilbert spectra (Alg. 2)",
              (_SURFACE, _SIGNAL_IN), "hht", HHT, build=_hht_tasks, vertices=_eigenpair_vertices),
    Operation("filter_signal", "the signal through a gain of the instantaneous frequency (Eq. 26)",
              (_HHT,), "signal", (_GAIN,), func=filter_signal),
    Operation("filter_geometry", "Hilbert-spectrum filtering of the mean curvature and new positions "
                                 "(Eqs. 26-27)",
              (_HHT,), "surface", (_GAIN, *_FILTER_WEIGHTS, _BACKEND), func=filter_geometry),
    Operation("reconstruct", "new positions whose mean curvature is the given signal (Eq. 27)",
              (_SURFACE, _SIGNAL_IN), "surface", (*_WEIGHTS, _BACKEND), func=reconstruct),
    Operation("features", "prominent feature points from IMF extrema counts (Sec. 5.2)",
              (_SURFACE, _IMFS), "features", FEATURES, func=prominent_features),
    Operation("hks_features", "baseline: maxima of the heat kernel signature (Sun et al. 2009)",
              (_SURFACE,), "features", HKS, func=hks_features, vertices=_eigenpair_vertices),
    Operation("imf_enhancement", "baseline: scale one IMF of the mean curvature (Hu et al. 2014)",
              (_SURFACE, _IMFS), "surface", ENHANCE, func=imf_enhancement),
    Operation("manifold_harmonics_filter", "baseline: filter in the Laplacian eigenbasis (Vallet & Lévy 2008)",
              (_SURFACE,), "surface", (_GAIN, *MHB), func=manifold_harmonics_filter, vertices=_eigenpair_vertices),
)}


def operation(name: str, where: str) -> Operation:
    """The operation called ``name``; a :class:`PipelineError` with "did you mean" otherwise."""
    if not isinstance(name, str) or name not in OPERATIONS:
        raise PipelineError(f"{where}: unknown op {shown(name)}{did_you_mean(name, OPERATIONS)} "
                            "(`hht3d ops` lists them)")
    return OPERATIONS[name]
