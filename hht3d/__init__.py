"""hht3d: the Hilbert–Huang transform on 3D surfaces (meshes and point clouds).

The main functions are exported here.  Four of them share their name with
the module that holds them and its building blocks: ``hht3d.emd``,
``hht3d.riesz``, ``hht3d.monogenic`` and ``hht3d.hht`` are those modules,
and calling one calls its function of the same name.  So both
``hht3d.emd(surface, signal)`` and ``import hht3d.emd as E;
E.envelope_operator(surface)`` work, as do ``from hht3d import emd`` and
``from hht3d.emd import emd`` (the plain function, for ``isinstance`` checks
and the like).

Examples
--------
>>> import hht3d
>>> from hht3d.signals import mean_curvature
>>> surface = hht3d.load(hht3d.data_path("spot.ply"))
>>> decomposition = hht3d.emd(surface, mean_curvature(surface), max_imfs=2)
>>> decomposition.n_imfs
2
>>> import hht3d.emd as E
>>> E.envelope_operator(surface).shape
(2930, 2930)
"""
import importlib
import inspect
import sys
import types

from . import emd, hht, monogenic, riesz
from .emd import EMDResult, eemd
from .errors import HHT3DError, InputError, NumericalError, PipelineError
from .hht import HHTResult
from .io import data_path, load
from .monogenic import MonogenicSignal
from .riesz import fractional_laplacian
from .spectrum import HilbertSpectrum
from .surface import Surface

__version__ = "0.1.0"

__all__ = [
    "EMDResult", "HHTResult", "HilbertSpectrum", "MonogenicSignal", "Surface",
    "HHT3DError", "InputError", "NumericalError", "PipelineError",
    "data_path", "eemd", "emd", "fractional_laplacian", "hht", "load", "monogenic", "riesz",
]


class _CallableModule(types.ModuleType):
    """A module that calls its function of the same name (``hht3d.emd(...)`` is ``hht3d.emd.emd(...)``)."""

    @property
    def function(self):
        return getattr(self, self.__name__.rpartition(".")[2])

    @property
    def __signature__(self) -> inspect.Signature:
        return inspect.signature(self.function)

    def __call__(self, *args, **kwargs):
        return self.function(*args, **kwargs)

    def __reduce__(self):
        return importlib.import_module, (self.__name__,)


for _module in (emd, hht, monogenic, riesz):
    sys.modules[_module.__name__].__class__ = _CallableModule
del _module
