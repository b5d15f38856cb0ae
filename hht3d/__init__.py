"""hht3d: the Hilbert–Huang transform on 3D surfaces (meshes and point clouds).

The core functions are exported here; their modules (``hht3d.emd``,
``hht3d.riesz``, ...) hold the building blocks.  Import those with
``from hht3d.riesz import ...`` since ``hht3d.riesz`` names the function.
"""
from .emd import EMDResult, eemd, emd
from .errors import HHT3DError, InputError, NumericalError, PipelineError
from .hht import HHTResult, hht
from .io import load
from .monogenic import MonogenicSignal, monogenic
from .riesz import fractional_laplacian, riesz
from .spectrum import HilbertSpectrum
from .surface import Surface

__version__ = "0.1.0"

__all__ = [
    "EMDResult", "HHTResult", "HilbertSpectrum", "MonogenicSignal", "Surface",
    "HHT3DError", "InputError", "NumericalError", "PipelineError",
    "eemd", "emd", "fractional_laplacian", "hht", "load", "monogenic", "riesz",
]
