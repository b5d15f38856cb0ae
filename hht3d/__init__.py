"""hht3d: the Hilbert–Huang transform on 3D surfaces (meshes and point clouds).

The main functions are exported here as plain functions; their building
blocks live in the subpackages, which follow the data flow:
:mod:`~hht3d.geometry` → :mod:`~hht3d.decomposition` → :mod:`~hht3d.spectral`
→ :mod:`~hht3d.transform` → :mod:`~hht3d.apps`, with :mod:`~hht3d.io`,
:mod:`~hht3d.linalg` beneath and :mod:`~hht3d.graph`, :mod:`~hht3d.pipeline`,
:mod:`~hht3d.viz` and the CLI above.

Examples
--------
>>> import hht3d
>>> from hht3d.geometry import mean_curvature
>>> surface = hht3d.load(hht3d.data_path("spot.ply"))
>>> decomposition = hht3d.emd(surface, mean_curvature(surface), max_imfs=2)
>>> decomposition.n_imfs
2
>>> from hht3d.decomposition import envelope_operator
>>> envelope_operator(surface, envelope="biharmonic").shape
(2930, 2930)
"""

from .decomposition import EMDResult, eemd, emd
from .errors import HHT3DError, InputError, NumericalError, PipelineError
from .geometry import Surface
from .io import data_path, load
from .results import load_result
from .spectral import HilbertSpectrum, MonogenicSignal, fractional_laplacian, monogenic, riesz
from .transform import HHTOptions, HHTResult, hht
from .version import __version__

__all__ = [
    "EMDResult",
    "HHTOptions",
    "HHTResult",
    "HilbertSpectrum",
    "MonogenicSignal",
    "Surface",
    "HHT3DError",
    "InputError",
    "NumericalError",
    "PipelineError",
    "__version__",
    "data_path",
    "eemd",
    "emd",
    "fractional_laplacian",
    "hht",
    "load",
    "load_result",
    "monogenic",
    "riesz",
]
