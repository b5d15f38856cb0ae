"""What the viewer shows of a saved file (:func:`hht3d.viz.viewer.file_html`): a result written by
:meth:`HHTResult.save <hht3d.transform.HHTResult.save>`, or any surface file with per-vertex properties."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ..decomposition.quality import decomposition_quality
from ..errors import InputError
from ..geometry.surface import Surface
from ..io.read import load as load_surface
from ..io.read import read_npz
from ..spectral.spectrum import HilbertSpectrum

__all__ = ["read_fields", "saved_decomposition"]

#: Stacked arrays of a saved result and the per-IMF field names they become.
_STACKED = {"imfs": "imf", "amplitude": "amplitude", "phase": "phase", "frequency": "frequency"}


def read_fields(path: Path | str) -> tuple[Surface, dict, np.ndarray | None]:
    """A surface, its per-vertex fields and stored vertex areas, from a saved file.

    ``.npz`` files as :meth:`HHTResult.save <hht3d.transform.HHTResult.save>`
    writes them (``vertices``, ``faces``, ``signal``, ``imfs``, ...): every
    ``(n,)`` array is a field and ``imfs``, ``amplitude``, ``phase`` and
    ``frequency`` (k, n) become ``imf_K``, ``amplitude_K``, ... Any surface
    file of :func:`hht3d.io.read.load` (read without cleaning, so vertices keep
    their order): its numeric vertex properties are the fields.

    Parameters
    ----------
    path : Path or str
        A saved ``.npz`` result or a surface file.

    Returns
    -------
    surface, fields, area
        ``area`` is the stored ``area`` array of an ``.npz``, else ``None``.

    Examples
    --------
    >>> from hht3d import data_path, load
    >>> spot = load(data_path("spot.ply"))
    >>> import tempfile
    >>> from pathlib import Path
    >>> from hht3d.io import write_ply
    >>> from hht3d.viz import read_fields
    >>> path = write_ply(Path(tempfile.mkdtemp()) / "spot.ply", spot, {"height": spot.vertices[:, 1]})
    >>> surface, fields, area = read_fields(path)
    >>> surface.n_vertices, sorted(fields), area
    (2930, ['height'], None)
    """
    path = Path(path)
    if path.suffix.lower() != ".npz":
        surface = load_surface(path, clean=False)
        return surface, dict(surface.attributes), None
    arrays = read_npz(path)
    if "vertices" not in arrays:
        raise InputError(f"{path}: no 'vertices' array; expected a file written by HHTResult.save")
    try:
        surface = Surface(
            arrays.pop("vertices"), arrays.pop("faces", None), name=path.stem, origin=arrays.pop("origin", None)
        )
    except InputError as exc:
        raise InputError(f"{path}: {exc}") from None
    n = surface.n_vertices
    area = arrays.pop("area", None)
    fields = {}
    for key, values in arrays.items():
        if values.shape == (n,):
            fields[key] = values
        elif key in _STACKED and values.ndim == 2 and values.shape[1] == n:
            fields.update({f"{_STACKED[key]}_{k + 1}": row for k, row in enumerate(values)})
    return surface, fields, None if area is None or area.shape != (n,) else area


def saved_decomposition(surface: Surface, fields: dict, area: np.ndarray | None) -> tuple[Any, Any]:
    """The spectrum and quality of the IMFs among ``fields`` (``None`` for what they lack)."""
    k = 0
    while all(f"{kind}_{k + 1}" in fields for kind in ("imf", "amplitude", "frequency")):
        k += 1
    if k == 0:
        return None, None
    stack = {
        kind: np.stack([fields[f"{kind}_{i + 1}"] for i in range(k)]) for kind in ("imf", "amplitude", "frequency")
    }
    spectrum = HilbertSpectrum(stack["frequency"], stack["amplitude"], surface.mass_diagonal if area is None else area)
    quality = None
    if "signal" in fields and "residue" in fields:
        quality = decomposition_quality(surface, fields["signal"], stack["imf"], fields["residue"])
    return spectrum, quality
