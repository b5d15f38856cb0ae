"""Per-vertex input signals: curvature, centroid distance, coordinates, colour, stored and user data.

Every function returns a float64 array of shape ``(n,)`` for a
:class:`~hht3d.geometry.surface.Surface`.  :func:`signal` selects one by name, which
is how the CLI and pipelines refer to them.  The curvatures are computed in
:mod:`hht3d.geometry.curvature`.
"""

from __future__ import annotations

from pathlib import Path
from typing import cast

import numpy as np

from ..errors import InputError
from .curvature import MIN_AREA_FRACTION, gaussian_curvature, mean_curvature, unreliable_vertices
from .surface import Surface
from .validation import check_signal

__all__ = [
    "fluctuation",
    "mean_curvature",
    "gaussian_curvature",
    "unreliable_vertices",
    "MIN_AREA_FRACTION",
    "centroid_distance",
    "coordinate",
    "luminance",
    "stored",
    "check_signal",
    "load_signal",
    "check_signal_path",
    "signal",
    "SIGNALS",
]


def centroid_distance(surface: Surface) -> np.ndarray:
    """Distance of each vertex to the area-weighted centroid (the signal of Fig. 2).

    Parameters
    ----------
    surface : Surface
        The surface whose vertices are measured.

    Returns
    -------
    (n,) ndarray
        The distance of each vertex.

    Examples
    --------
    >>> import numpy as np
    >>> from hht3d import data_path, load
    >>> from hht3d.geometry import centroid_distance
    >>> sphere = load(data_path("sphere_oct4098.ply"))
    >>> bool(np.allclose(centroid_distance(sphere), 1.0, atol=1e-3))  # the unit sphere about its centre
    True
    """
    w = surface.mass_diagonal
    centroid = (w[:, None] * surface.vertices).sum(axis=0) / w.sum()
    return np.linalg.norm(surface.vertices - centroid, axis=1)


def coordinate(surface: Surface, axis: str) -> np.ndarray:
    """The ``x``, ``y`` or ``z`` coordinate.

    Parameters
    ----------
    surface : Surface
        The surface whose vertex positions are read.
    axis : str
        ``"x"``, ``"y"`` or ``"z"``.

    Returns
    -------
    (n,) ndarray
        A copy of that coordinate of each vertex.

    Examples
    --------
    >>> from hht3d import data_path, load
    >>> spot = load(data_path("spot.ply"))
    >>> from hht3d.geometry import coordinate
    >>> bool((coordinate(spot, "y") == spot.vertices[:, 1]).all())
    True
    """
    axes = {"x": 0, "y": 1, "z": 2}
    if axis not in axes:
        raise InputError(f"unknown coordinate {axis!r}; choose x, y or z")
    return surface.vertices[:, axes[axis]].copy()


def luminance(surface: Surface) -> np.ndarray:
    """Colour luminance ``0.2126 R + 0.7152 G + 0.0722 B`` (Rec. 709), the texture signal of Fig. 1.

    Parameters
    ----------
    surface : Surface
        A surface with vertex colours.

    Returns
    -------
    (n,) ndarray
        The luminance of each vertex, in [0, 1].

    Examples
    --------
    >>> from hht3d import data_path, load
    >>> spot = load(data_path("spot.ply"))
    >>> import numpy as np
    >>> from hht3d.geometry import Surface, luminance
    >>> grey = Surface(spot.vertices, spot.faces, colors=np.full((2930, 3), 0.5))
    >>> bool(np.allclose(luminance(grey), 0.5))  # the Rec. 709 weights sum to 1
    True
    """
    if surface.colors is None:
        raise InputError(f"{surface.name}: has no vertex colours for a luminance signal")
    return surface.colors @ np.array([0.2126, 0.7152, 0.0722])


def stored(surface: Surface, name: str) -> np.ndarray:
    """A per-vertex scalar stored in the input file (e.g. a PLY vertex property).

    Parameters
    ----------
    surface : Surface
        The surface read from the file.
    name : str
        The attribute's name, a key of ``surface.attributes``.

    Returns
    -------
    (n,) ndarray
        The attribute as float64.

    Examples
    --------
    >>> from hht3d import data_path, load
    >>> spot = load(data_path("spot.ply"))
    >>> from hht3d.geometry import Surface, stored
    >>> scan = Surface(spot.vertices, spot.faces, attributes={"quality": spot.vertices[:, 2]}, name="scan")
    >>> stored(scan, "quality").shape
    (2930,)
    >>> stored(scan, "intensity")
    Traceback (most recent call last):
    hht3d.errors.InputError: scan: no stored vertex attribute 'intensity'; available: ['quality']
    """
    if name not in surface.attributes:
        raise InputError(
            f"{surface.name}: no stored vertex attribute {name!r}; available: {sorted(surface.attributes) or 'none'}"
        )
    return check_signal(surface, surface.attributes[name], f"attribute {name!r}")


def check_signal_path(path: Path | str) -> Path:
    """``path`` if it names an existing ``.npy`` file; else an :class:`InputError` saying what it is.

    Parameters
    ----------
    path : Path or str
        The signal file.

    Returns
    -------
    Path
        ``path`` as a :class:`~pathlib.Path`.

    Examples
    --------
    >>> from hht3d.geometry import check_signal_path
    >>> check_signal_path("curvature.txt")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    hht3d.errors.InputError: curvature.txt: a signal file must be a .npy file ..., not .txt
    """
    path = Path(path)
    if path.suffix.lower() != ".npy":
        raise InputError(
            f"{path}: a signal file must be a .npy file written by numpy.save(path, values), "
            f"not {path.suffix or 'a file without extension'}"
        )
    if not path.is_file():
        raise InputError(f"{path}: no such signal file" + (" (it is a folder)" if path.is_dir() else ""))
    return path


def load_signal(surface: Surface, path: Path | str) -> np.ndarray:
    """A user signal from a ``.npy`` file (one value per vertex), as written by ``numpy.save``.

    Parameters
    ----------
    surface : Surface
        The surface the signal lives on.
    path : Path or str
        A ``.npy`` file of one number per vertex (never unpickled).

    Returns
    -------
    (n,) ndarray
        The signal as float64.

    Examples
    --------
    >>> from hht3d import data_path, load
    >>> spot = load(data_path("spot.ply"))
    >>> import tempfile
    >>> import numpy as np
    >>> from pathlib import Path
    >>> from hht3d.geometry import load_signal
    >>> path = Path(tempfile.mkdtemp()) / "height.npy"
    >>> np.save(path, spot.vertices[:, 1])
    >>> bool((load_signal(spot, path) == spot.vertices[:, 1]).all())
    True
    """
    path = check_signal_path(path)
    try:
        values = np.load(path, allow_pickle=False)
    except ValueError:  # numpy's message on object arrays recommends allow_pickle; we never unpickle
        raise InputError(
            f"{path}: not a .npy file of numbers (it holds Python objects or is not a .npy "
            "file); save a float array with numpy.save"
        ) from None
    except OSError as exc:
        raise InputError(f"{path}: cannot read the signal ({exc.strerror or exc})") from None
    return check_signal(surface, values, f"signal {path}")


SIGNALS = {
    "mean_curvature": mean_curvature,
    "gaussian_curvature": gaussian_curvature,
    "centroid_distance": centroid_distance,
    "x": lambda s: coordinate(s, "x"),
    "y": lambda s: coordinate(s, "y"),
    "z": lambda s: coordinate(s, "z"),
    "luminance": luminance,
}


def signal(
    surface: Surface,
    kind: str,
    *,
    attribute: str | None = None,
    path: Path | str | None = None,
    values: np.ndarray | None = None,
) -> np.ndarray:
    """Compute a signal by name.

    ``kind`` is one of :data:`SIGNALS`, or ``"stored"`` (with ``attribute``),
    ``"file"`` (a ``.npy`` at ``path``) or ``"array"`` (``values``).

    Parameters
    ----------
    surface : Surface
        The surface to compute the signal on.
    kind : str
        A name of :data:`SIGNALS`, ``"stored"``, ``"file"`` or ``"array"``.
    attribute : str, optional
        The stored vertex attribute of ``kind="stored"``.
    path : Path or str, optional
        The ``.npy`` file of ``kind="file"``.
    values : ndarray, optional
        The per-vertex values of ``kind="array"``.

    Returns
    -------
    (n,) ndarray
        One value per vertex.

    Examples
    --------
    The mean curvature signal of Eq. 24 is ``2H``, which is 2 on the unit sphere:

    >>> import numpy as np
    >>> from hht3d import data_path, load
    >>> from hht3d.geometry.signals import signal
    >>> sphere = load(data_path("sphere_oct4098.ply"))
    >>> curvature = signal(sphere, "mean_curvature")
    >>> round(float(np.median(curvature)), 4)
    2.0
    """
    if kind in SIGNALS:
        return SIGNALS[kind](surface)
    if kind == "stored":
        return stored(surface, cast(str, attribute))  # checked there
    if kind == "file":
        return load_signal(surface, cast("Path | str", path))
    if kind == "array":
        return check_signal(surface, cast(np.ndarray, values))
    raise InputError(f"unknown signal {kind!r}; choose one of {sorted(SIGNALS) + ['stored', 'file', 'array']}")


def fluctuation_energy(surface: Surface, f: np.ndarray) -> float:
    """``‖f̃‖²_M``, the energy of the :func:`fluctuation` of ``f`` (n,) in the lumped mass."""
    g = fluctuation(surface, f)
    return float(np.dot(surface.mass_diagonal * g, g))


def fluctuation(surface: Surface, f: np.ndarray) -> np.ndarray:
    """``f`` (n,) or (k, n) minus its area-weighted mean on each connected component.

    ``f − Σ_c 1_c (1_cᵀ M f)/(1_cᵀ M 1_c)`` is M-orthogonal to the kernel of
    ``L`` (the per-component constants): the part of ``f`` that EMD
    decomposes and ``L^{-1/2}`` acts on (Sec. 4.2).  The caller checks ``f``.
    """
    labels, mass, k = surface.component_labels, surface.mass_diagonal, surface.n_components
    a = np.atleast_2d(f)
    areas = np.bincount(labels, weights=mass, minlength=k)
    sums = np.array([np.bincount(labels, weights=mass * row, minlength=k) for row in a]).reshape(len(a), k)
    means = sums / areas
    out = a - means[:, labels]
    return out[0] if np.ndim(f) == 1 else out
