"""hht3d: the Hilbert–Huang transform on 3D surfaces (meshes and point clouds)."""
from .errors import HHT3DError, InputError, NumericalError, PipelineError
from .io import load
from .surface import Surface

__version__ = "0.1.0"

__all__ = ["HHT3DError", "InputError", "NumericalError", "PipelineError", "Surface", "load"]
