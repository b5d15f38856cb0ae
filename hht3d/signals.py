"""Per-vertex input signals: curvature, centroid distance, coordinates, colour, stored and user data.

Every function returns a float64 array of shape ``(n,)`` for a
:class:`~hht3d.surface.Surface`.  :func:`signal` selects one by name, which
is how the CLI and pipelines refer to them.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .errors import InputError
from .surface import Surface

__all__ = [
    "mean_curvature",
    "gaussian_curvature",
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


def mean_curvature(surface: Surface) -> np.ndarray:
    """Mean-curvature measure of Eq. (24): ``s_i = n_i · (M^{-1} L V)_i``.

    ``M^{-1} L V`` is the mean-curvature normal ``2 H n`` (Meyer et al. 2002),
    so ``s = 2H``: about ``2/r`` on a sphere of radius ``r`` with outward
    normals, positive on convex and negative on concave regions.  This is the
    paper's ``Δ(v_i) · n_i`` with the sign flipped (the paper's ``Δ`` of Eq. 9
    points inward), which is the sign Eq. (27) needs: ``L V' ≈ diag(s') N``.
    Works on meshes and point clouds.
    """
    lv = surface.stiffness @ surface.vertices / surface.mass_diagonal[:, None]
    return np.einsum("ij,ij->i", lv, surface.normals)


def gaussian_curvature(surface: Surface) -> np.ndarray:
    """Gaussian curvature density from the angle defect, ``K_i = θ_i / A_i``.

    ``θ_i = 2π - Σ angles`` at interior vertices and ``π - Σ angles`` at
    boundary vertices; ``A_i`` is the lumped mass.  ``Σ K_i A_i = 2π χ`` on a
    closed mesh (Gauss–Bonnet).  Meshes only.
    """
    if not surface.is_mesh:
        raise InputError(f"{surface.name}: Gaussian curvature (angle defect) needs a triangle mesh")
    v = surface.vertices[surface.faces]
    angles = np.empty((len(surface.faces), 3))
    for k in range(3):
        a = v[:, (k + 1) % 3] - v[:, k]
        b = v[:, (k + 2) % 3] - v[:, k]
        angles[:, k] = np.arctan2(np.linalg.norm(np.cross(a, b), axis=1), np.einsum("ij,ij->i", a, b))
    total = np.bincount(surface.faces.ravel(), weights=angles.ravel(), minlength=surface.n_vertices)
    defect = np.where(surface.boundary_vertices, np.pi, 2 * np.pi) - total
    return defect / surface.mass_diagonal


def centroid_distance(surface: Surface) -> np.ndarray:
    """Distance of each vertex to the area-weighted centroid (the signal of Fig. 2)."""
    w = surface.mass_diagonal
    centroid = (w[:, None] * surface.vertices).sum(axis=0) / w.sum()
    return np.linalg.norm(surface.vertices - centroid, axis=1)


def coordinate(surface: Surface, axis: str) -> np.ndarray:
    """The ``x``, ``y`` or ``z`` coordinate."""
    axes = {"x": 0, "y": 1, "z": 2}
    if axis not in axes:
        raise InputError(f"unknown coordinate {axis!r}; choose x, y or z")
    return surface.vertices[:, axes[axis]].copy()


def luminance(surface: Surface) -> np.ndarray:
    """Colour luminance ``0.2126 R + 0.7152 G + 0.0722 B`` (Rec. 709), the texture signal of Fig. 1."""
    if surface.colors is None:
        raise InputError(f"{surface.name}: has no vertex colours for a luminance signal")
    return surface.colors @ np.array([0.2126, 0.7152, 0.0722])


def stored(surface: Surface, name: str) -> np.ndarray:
    """A per-vertex scalar stored in the input file (e.g. a PLY vertex property)."""
    if name not in surface.attributes:
        raise InputError(f"{surface.name}: no stored vertex attribute {name!r}; "
                         f"available: {sorted(surface.attributes) or 'none'}")
    return check_signal(surface, surface.attributes[name], f"attribute {name!r}")


def check_signal(surface: Surface, values, what: str = "signal") -> np.ndarray:
    """Validate a user signal: one finite real float per vertex.

    Complex values are refused rather than cut to their real part.
    """
    if np.iscomplexobj(values):
        raise InputError(f"{what} is complex; pass a real signal, e.g. its real part (values.real) or its "
                         "magnitude (abs(values))")
    try:
        a = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"{what} is not numeric") from None
    if a.ndim != 1 or len(a) != surface.n_vertices:
        hint = ""
        if surface.clean_report is not None and surface.clean_report.changed and a.ndim == 1:
            hint = (f"; cleaning changed the vertex count ({surface.clean_report.summary()}): "
                    "index it with surface.clean_report.kept_vertices or load with clean=False")
        raise InputError(f"{what} has shape {a.shape}; {surface.name} has {surface.n_vertices} vertices{hint}")
    bad = ~np.isfinite(a)
    if bad.any():
        raise InputError(f"{what} has {int(bad.sum())} NaN or infinite values "
                         f"(first at vertex {int(np.flatnonzero(bad)[0])})")
    return a


def check_signal_path(path) -> Path:
    """``path`` if it names an existing ``.npy`` file; else an :class:`InputError` saying what it is."""
    path = Path(path)
    if path.suffix.lower() != ".npy":
        raise InputError(f"{path}: a signal file must be a .npy file written by numpy.save(path, values), "
                         f"not {path.suffix or 'a file without extension'}")
    if not path.is_file():
        raise InputError(f"{path}: no such signal file" + (" (it is a folder)" if path.is_dir() else ""))
    return path


def load_signal(surface: Surface, path) -> np.ndarray:
    """A user signal from a ``.npy`` file (one value per vertex), as written by ``numpy.save``."""
    path = check_signal_path(path)
    try:
        values = np.load(path, allow_pickle=False)
    except ValueError:  # numpy's message on object arrays recommends allow_pickle; we never unpickle
        raise InputError(f"{path}: not a .npy file of numbers (it holds Python objects or is not a .npy "
                         "file); save a float array with numpy.save") from None
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


def signal(surface: Surface, kind: str, *, attribute: str | None = None, path=None,
           values=None) -> np.ndarray:
    """Compute a signal by name.

    ``kind`` is one of :data:`SIGNALS`, or ``"stored"`` (with ``attribute``),
    ``"file"`` (a ``.npy`` at ``path``) or ``"array"`` (``values``).
    """
    if kind in SIGNALS:
        return SIGNALS[kind](surface)
    if kind == "stored":
        return stored(surface, attribute)
    if kind == "file":
        return load_signal(surface, path)
    if kind == "array":
        return check_signal(surface, values)
    raise InputError(f"unknown signal {kind!r}; choose one of {sorted(SIGNALS) + ['stored', 'file', 'array']}")
