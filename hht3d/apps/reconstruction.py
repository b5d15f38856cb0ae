"""New vertex positions from a filtered mean-curvature signal (Sec. 5.1, Eq. 27).

The paper solves, in the least-squares sense,

    [ L  ]        [ diag(s') N ]
    [ μI ]  V' =  [ μ V        ]                                    (Eq. 27)

with the strong cotangent Laplacian ``L``, the vertex normals ``N`` and
per-vertex weights ``μ`` (0.01 interior, 1.0 boundary) that keep the new
positions ``V'`` near the old ones ``V``.

Formulation used here
---------------------
With the weak (stiffness) Laplacian ``L`` and lumped mass ``M`` of
:class:`~hht3d.geometry.surface.Surface`, the strong Laplacian of the coordinates is
``δ = M⁻¹ L V`` and the signal of Eq. (24) is ``s = n · δ``
(:func:`hht3d.geometry.signals.mean_curvature`).  Discretely ``δ`` is not exactly
parallel to ``n``, so the target ``diag(s') N`` of Eq. (27) would move the
vertices even when ``s' = s``.  We therefore keep the tangential part of
the original ``δ`` and change only its normal part,

    δ' = δ + (s' − s) n,

and minimise the area-weighted residual plus the soft position constraints

    E(V') = Σ_i A_i |(M⁻¹ L V')_i − δ'_i|² + Σ_i w_i |v'_i − v_i|²
          = ‖L V' − M δ'‖²_{M⁻¹} + ‖W^{1/2} (V' − V)‖².

Its normal equations, with ``D = V' − V``, are

    (L M⁻¹ L + W) D = L diag(s' − s) N,

symmetric positive definite (``L M⁻¹ L`` is PSD and ``W > 0``), solved
for the three coordinates at once with :func:`hht3d.linalg.backends.factorize`.
``s' = s`` gives ``D = 0`` exactly, so the identity filter returns the
input positions.

Weights
-------
The paper's ``μ`` multiplies rows of a strong Laplacian in the model's own
(unstated) length unit, so its values do not transfer between models.  Here

    w_i = μ_i A_i / Ā²,      Ā = mean vertex area,

i.e. ``μ`` weighs the squared, area-weighted position residual with lengths
in units of ``√Ā`` (about the mean edge length).  ``E`` is then invariant
to a uniform scaling of the model, and ``μ`` means the same at every
resolution: a displacement of wavelength ``ℓ`` costs ``(2π/ℓ)⁴`` in the
Laplacian term against ``μ/Ā²`` in the position term, so the positions
dominate above the wavelength ``2π √Ā / μ^{1/4}``: about 20 vertex spacings
for the interior default ``μ = 0.01`` and 6 for the boundary default
``μ = 1.0`` (which prevents boundary shrinkage, Hu et al. 2014).  Curvature
edits at finer scales are followed; coarser drift is damped.  That drift
matters: EMD leaves some low-frequency content in every IMF (the sifting
stops while the mean envelope is small, not zero), and the solve turns a
curvature change of frequency ``ω`` into a displacement ``∝ 1/ω²``.  The
weights were chosen on a test sphere with a band of bumps
(``benchmarks/results/design_notes.md``); the paper's 0.01 read as a row
weight, ``Σ μ² |v' − v|²``, makes that surface worse.
Point clouds have no boundary and use the interior weight everywhere.

Scale
-----
The linearised system keeps ``M`` (the vertex areas) fixed, so a uniform
change ``c`` of the signal on a closed surface is met by a uniform scaling
*with the wrong sign*: a larger mean curvature inflates the shape (its
``δ = M⁻¹LV`` grows with size when ``M`` is fixed).  IMFs oscillate about
zero, so the mean of ``s' − s`` is an artifact of gains that differ between
vertices; with ``preserve_scale=True`` (default) its area-weighted mean is
removed on every connected component, which keeps each component's size
(on an open component the same mode is a bulge of the patch, held by the
boundary weights; its mean is removed too, for the same reason).  What it
does to the enclosed volume: ``benchmarks/results/design_notes.md``.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp

from .. import linalg
from ..decomposition.quality import QualityWarning
from ..errors import InputError
from ..geometry.signals import fluctuation, mean_curvature
from ..geometry.surface import Surface
from ..geometry.validation import check_signal, check_surface
from ..records import Record, option

__all__ = [
    "ReconstructionOptions",
    "position_weights",
    "reconstruct",
    "reconstruct_from_change",
    "check_mean_curvature_signal",
    "moved",
    "INTERIOR_WEIGHT",
    "BOUNDARY_WEIGHT",
    "DISPLACEMENT_LIMIT",
    "MAX_WEIGHT",
]

#: Default position weight ``μ`` of interior vertices (paper, Sec. 5.1).
INTERIOR_WEIGHT = 0.01
#: Default position weight ``μ`` of boundary vertices (paper, Sec. 5.1).
BOUNDARY_WEIGHT = 1.0
#: A vertex moved by more than this fraction of the bounding-box diagonal gets a warning.
DISPLACEMENT_LIMIT = 0.05
#: The HHT signal must equal the surface's mean curvature to this relative accuracy.
_SIGNAL_RTOL = 1e-8
#: Position weights μ of Eq. 27 (the paper's are 0.01 and 1); far above useful values, it stops a typo.
MAX_WEIGHT = 1e6


@dataclass(frozen=True)
class ReconstructionOptions(Record):
    """The settings of :func:`reconstruct` and :func:`reconstruct_from_change` (Eq. 27; module notes)."""

    label = "reconstruction"

    interior_weight: float = option(
        INTERIOR_WEIGHT,
        "position weight μ of interior vertices (Eq. 27)",
        minimum=0,
        maximum=MAX_WEIGHT,
        open_minimum=True,
    )
    boundary_weight: float = option(
        BOUNDARY_WEIGHT,
        "position weight μ of boundary vertices (Eq. 27)",
        minimum=0,
        maximum=MAX_WEIGHT,
        open_minimum=True,
    )
    preserve_scale: bool = option(True, "remove the mean curvature change per component")


def position_weights(
    surface: Surface, interior_weight: float = INTERIOR_WEIGHT, boundary_weight: float = BOUNDARY_WEIGHT
) -> np.ndarray:
    """Per-vertex ``μ_i`` of Eq. (27): ``boundary_weight`` on boundary vertices, else ``interior_weight``.

    Both must be positive (a zero weight leaves the translation of a closed
    component undetermined).

    Parameters
    ----------
    surface : Surface
        The surface whose boundary vertices get ``boundary_weight``.
    interior_weight : float, optional
        Weight of interior vertices, positive (default :data:`INTERIOR_WEIGHT`, 0.01).
    boundary_weight : float, optional
        Weight of boundary vertices, positive (default :data:`BOUNDARY_WEIGHT`, 1.0).

    Returns
    -------
    (n,) ndarray
        The weight of each vertex.

    Examples
    --------
    >>> from hht3d import data_path, load
    >>> spot = load(data_path("spot.ply"))
    >>> from hht3d.apps import position_weights
    >>> weights = position_weights(spot, interior_weight=0.05)
    >>> weights.shape, set(weights.tolist())  # spot is closed: no boundary vertex
    ((2930,), {0.05})
    """
    surface = check_surface(surface)
    interior = ReconstructionOptions.check("interior_weight", interior_weight)
    boundary = ReconstructionOptions.check("boundary_weight", boundary_weight)
    return np.where(surface.boundary_vertices, boundary, interior)


def _weights(surface: Surface, options: ReconstructionOptions, weights: np.ndarray | None) -> np.ndarray:
    if weights is None:
        return position_weights(surface, options.interior_weight, options.boundary_weight)
    mu = check_signal(surface, weights, "weights")
    if np.any(mu <= 0):
        raise InputError(f"weights must all be > 0; {int(np.sum(mu <= 0))} are not")
    return mu


def reconstruct_from_change(
    surface: Surface,
    change: np.ndarray,
    options: ReconstructionOptions | dict | None = None,
    *,
    weights: np.ndarray | None = None,
    backend: str | None = None,
    name: str | None = None,
    **overrides: Any,
) -> Surface:
    """New surface whose mean-curvature signal changed by ``change = s' − s`` (Eq. 27).

    Solves ``(L M⁻¹ L + W) (V' − V) = L diag(s' − s) N`` (see the module
    notes); same faces, colours and stored attributes as ``surface``.
    Normals of the new surface are recomputed (meshes) or re-estimated
    (point clouds) when first needed.

    Parameters
    ----------
    surface : Surface
        Mesh (open or closed, any number of components) or point cloud.
    change : (n,) array_like
        ``s' − s``, the change of the signal of Eq. (24).
    options : ReconstructionOptions or dict, optional
        ``interior_weight``, ``boundary_weight``: the paper's ``μ`` for
        interior and boundary vertices (defaults 0.01 and 1.0), weights of the
        squared position residual in units of the mean vertex area (module
        notes, "Weights").  ``preserve_scale``: remove the area-weighted mean
        of ``change`` per connected component (module notes, "Scale");
        default True.
    weights : (n,) array_like, optional
        Per-vertex ``μ_i`` (all > 0), overriding the two weights.
    backend : str, optional
        Sparse solver of :mod:`hht3d.linalg.backends`.
    name : str, optional
        Name of the new surface; default ``"<name>_filtered"``.
    **overrides
        Settings that replace those of ``options``.

    Returns
    -------
    Surface
    """
    options = ReconstructionOptions.of(options, **overrides)
    surface = check_surface(surface)
    ds = check_signal(surface, change, "signal change")
    if options.preserve_scale:
        ds = fluctuation(surface, ds)
    mu = _weights(surface, options, weights)
    area = surface.mass_diagonal
    mean_area = float(np.mean(area))
    w = mu * area / mean_area**2
    lap = surface.stiffness
    system = (lap @ sp.diags(1.0 / area) @ lap + sp.diags(w)).tocsr()
    rhs = lap @ (ds[:, None] * surface.normals)
    displacement = linalg.factorize(system, backend).solve(rhs) if np.any(ds) else np.zeros_like(rhs)
    largest = float(np.max(np.linalg.norm(displacement, axis=1))) / surface.bounding_box_diagonal
    if largest > DISPLACEMENT_LIMIT:
        warnings.warn(
            f"{surface.name}: the reconstruction moved a vertex by {largest:.3g} of the bounding-box "
            f"diagonal (more than {DISPLACEMENT_LIMIT}): the curvature change has coarse-scale content "
            "or the mesh has bad triangles; raise interior_weight or check the result",
            QualityWarning,
            stacklevel=2,
        )
    return moved(surface, displacement, name)


def moved(surface: Surface, displacement: np.ndarray | float, name: str | None) -> Surface:
    """``surface`` with its vertices moved by ``displacement`` (faces, colours, fields, Laplacian and
    file frame kept: origin and header), named ``name`` or ``<name>_filtered``."""
    return Surface(
        surface.vertices + displacement,
        surface.faces,
        colors=surface.colors,
        attributes=dict(surface.attributes),
        laplacian=surface.laplacian,
        n_neighbors=surface.n_neighbors,
        name=name or f"{surface.name}_filtered",
        origin=surface.origin,
        header=surface.header,
    )


def reconstruct(
    surface: Surface,
    signal: np.ndarray,
    options: ReconstructionOptions | dict | None = None,
    *,
    weights: np.ndarray | None = None,
    backend: str | None = None,
    name: str | None = None,
    **overrides: Any,
) -> Surface:
    """New surface whose mean-curvature signal (Eq. 24) is ``signal`` (Eq. 27).

    ``s = mean_curvature(surface)`` is the reference; the vertices move by
    the least-squares solution of the module notes with ``s' − s`` as the
    change, so passing ``s`` itself returns the input positions.

    Parameters
    ----------
    surface : Surface
    signal : (n,) array_like
        The filtered signal ``s'`` (e.g. from
        :func:`hht3d.apps.filter_signal`).
    options, weights, backend, name, **overrides
        See :func:`reconstruct_from_change`.

    Returns
    -------
    Surface
    """
    options = ReconstructionOptions.of(options, **overrides)
    surface = check_surface(surface)
    target = check_signal(surface, signal, "filtered signal")
    return reconstruct_from_change(
        surface, target - mean_curvature(surface), options, weights=weights, backend=backend, name=name
    )


def check_mean_curvature_signal(surface: Surface, signal: np.ndarray) -> None:
    """Raise :class:`InputError` unless ``signal`` is the mean-curvature signal of ``surface``
    (regularized, the default, or pointwise Eq. 24 with ``min_area=0``).

    Parameters
    ----------
    surface : Surface
        The surface the result was computed on.
    signal : ndarray
        The result's signal, one value per vertex.
    """
    errors, scale = [], 0.0
    for reference in (mean_curvature(surface), mean_curvature(surface, min_area=0)):
        scale = max(scale, float(np.max(np.abs(reference))))
        errors.append(float(np.max(np.abs(np.asarray(signal) - reference))))
    error = min(errors)
    if not error <= _SIGNAL_RTOL * scale:
        raise InputError(
            f"{surface.name}: geometry filtering needs the HHT of the mean-curvature signal "
            "(Eq. 24, hht3d.geometry.signals.mean_curvature); this result's signal differs from it "
            f"by up to {error:.3g} (scale {scale:.3g})"
        )
