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

from importlib import import_module
from typing import TYPE_CHECKING, Any

from .version import __version__

if TYPE_CHECKING:
    from .decomposition import EMDResult, eemd, emd
    from .errors import HHT3DError, InputError, NumericalError, PipelineError
    from .geometry import Surface
    from .io import data_path, load
    from .results import load_result
    from .spectral import HilbertSpectrum, MonogenicSignal, fractional_laplacian, monogenic, riesz
    from .transform import HHTOptions, HHTResult, hht

#: Where each exported name lives.  They are imported on first use (PEP 562), so that
#: ``import hht3d`` and ``python -m hht3d`` start in tens of milliseconds: the command line
#: installs its stop handlers before numpy, scipy and Open3D load (:mod:`hht3d.__main__`).
_EXPORTS = {
    **dict.fromkeys(("EMDResult", "eemd", "emd"), "decomposition"),
    **dict.fromkeys(("HHT3DError", "InputError", "NumericalError", "PipelineError"), "errors"),
    "Surface": "geometry",
    **dict.fromkeys(("data_path", "load"), "io"),
    "load_result": "results",
    **dict.fromkeys(("HilbertSpectrum", "MonogenicSignal", "fractional_laplacian", "monogenic", "riesz"), "spectral"),
    **dict.fromkeys(("HHTOptions", "HHTResult", "hht"), "transform"),
}


def __getattr__(name: str) -> Any:
    """An exported name, or a subpackage (``hht3d.io`` after a bare ``import hht3d``), imported now."""
    if name in _EXPORTS:
        value = getattr(import_module(f".{_EXPORTS[name]}", __name__), name)
    elif not name.startswith("__"):
        try:
            value = import_module(f".{name}", __name__)
        except ModuleNotFoundError as exc:
            if exc.name != f"{__name__}.{name}":
                raise
            raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_EXPORTS})


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
