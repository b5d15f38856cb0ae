"""Reading back an HHT result saved by :meth:`HHTResult.save <hht3d.transform.HHTResult.save>`.

The partner of ``result.save("x.npz")``: :func:`load_result` rebuilds the
surface (vertices, faces, normals, Laplacian choice and origin as saved), the IMFs,
the residue and the monogenic signal, so that its spectrum, quality figures,
figures and pages equal those of the result that was saved.
"""

from __future__ import annotations

from pathlib import Path, PurePosixPath

from .errors import InputError
from .geometry.surface import Surface
from .io import storage
from .io.read import read_npz
from .redaction import redact
from .spectral.monogenic_signal import MonogenicSignal
from .transform import RESULT_ARRAYS, HHTResult

__all__ = ["load_result", "RESULT_ARRAYS"]

#: Arrays that files saved by earlier releases lack (``origin``: they read back with the origin 0).
OPTIONAL_ARRAYS = ("origin",)


def load_result(path: Path | str, *, storage_options: dict | None = None) -> HHTResult:
    """The :class:`~hht3d.transform.HHTResult` saved as ``path`` (a ``.npz`` of ``HHTResult.save``).

    ``info`` holds ``{"source": path}``: the diagnostics of the run are not saved.

    Parameters
    ----------
    path : str or Path
        The ``.npz`` file, or an fsspec URL of one (``s3://bucket/out/x_hht.npz``).
    storage_options : dict, optional
        Options of the URL's fsspec back-end (:mod:`hht3d.io.storage`).

    Returns
    -------
    HHTResult
        The saved result (its ``info`` only ``{"source": path}``).

    Raises
    ------
    InputError
        Not a ``.npz`` (a PLY keeps no Riesz vectors), unreadable, or without the arrays of a result
        (:data:`~hht3d.transform.RESULT_ARRAYS`).

    Examples
    --------
    >>> import tempfile, numpy as np
    >>> from pathlib import Path
    >>> from hht3d import data_path, hht, load
    >>> from hht3d.geometry.signals import mean_curvature
    >>> from hht3d.results import load_result
    >>> spot = load(data_path("spot.ply"))
    >>> result = hht(spot, mean_curvature(spot), max_imfs=2)
    >>> again = load_result(result.save(Path(tempfile.mkdtemp()) / "spot_hht.npz"))
    >>> frequencies = again.spectrum.mean_frequency(), result.spectrum.mean_frequency()
    >>> np.array_equal(again.imfs, result.imfs), np.allclose(*frequencies, rtol=1e-12)
    (True, True)
    """
    shown = redact(str(path))
    if PurePosixPath(storage.file_name(path)).suffix.lower() != ".npz":
        raise InputError(f"{shown}: load_result reads the .npz of HHTResult.save (a .ply keeps no Riesz vectors)")
    with storage.local_copy(path, storage_options) as local:
        try:
            arrays = read_npz(local)
        except InputError as exc:
            raise InputError(str(exc).replace(str(local), shown)) from None
    missing = [name for name in RESULT_ARRAYS if name not in arrays and name not in OPTIONAL_ARRAYS]
    if missing:
        raise InputError(f"{shown}: no {', '.join(missing)}; expected a file written by HHTResult.save")
    surface = Surface(
        arrays["vertices"],
        arrays.get("faces"),
        normals=arrays["normals"],
        laplacian=str(arrays["laplacian"]),
        n_neighbors=int(arrays["n_neighbors"]),
        name=storage.stem(path),
        origin=arrays.get("origin"),  # absent from files saved before it was stored: the origin 0
    )
    mono = MonogenicSignal(
        imfs=arrays["imfs"],
        riesz=arrays["riesz"],
        amplitude=arrays["amplitude"],
        phase=arrays["phase"],
        frequency=arrays["frequency"],
        area=arrays["area"],
    )
    return HHTResult(
        surface=surface,
        signal=arrays["signal"],
        imfs=arrays["imfs"],
        residue=arrays["residue"],
        monogenic=mono,
        info={"source": str(path)},
    )
