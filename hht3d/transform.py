"""The Hilbert–Huang transform on a surface in one call: EMD + Hilbert spectra (Alg. 2).

:func:`hht` decomposes a signal into IMFs (Sec. 4.1, :func:`hht3d.decomposition.emd`),
takes the monogenic signal of every IMF at once (Sec. 4.2–4.3,
:func:`hht3d.spectral.monogenic`) and returns an :class:`HHTResult` that
can be saved (PLY with named vertex attributes, or ``.npz``) and handed to
Open3D as a tensor mesh or point cloud.  :func:`hht_stages` lists the
stages once, for :func:`hht`, the lazy graph (:mod:`hht3d.graph`) and the
pipeline's ``hht`` step.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from functools import cached_property
from operator import attrgetter
from pathlib import Path
from typing import Any, Callable, Protocol, cast

import numpy as np

from . import io
from .decomposition.decompose import emd
from .decomposition.display import value_range
from .decomposition.ensemble import combine_eemd, eemd_member
from .decomposition.options import EMDOptions, EnsembleOptions
from .decomposition.quality import (
    Quality,
    aliasing_warnings,
    decomposition_html,
    decomposition_quality,
    decomposition_repr,
    warn_quality,
)
from .errors import InputError
from .geometry.surface import Surface
from .geometry.validation import check_signal
from .hht_options import HHTOptions, hht_settings
from .io.sealed import Sealed, unsealed
from .spectral.monogenic_signal import MonogenicSignal, monogenic_from_potential, monogenic_from_riesz
from .spectral.multilevel import riesz_vectors
from .spectral.options import RieszOptions
from .spectral.riesz_transform import fractional_laplacian
from .spectral.spectrum import HilbertSpectrum

__all__ = [
    "HHTResult",
    "HHTOptions",
    "hht",
    "hht_stages",
    "hht_settings",
    "decomposition_stage",
    "Stages",
    "RESULT_ARRAYS",
    "FIELDS",
    "IMF_FIELDS",
    "field_imf",
]

#: The arrays of a saved result (:meth:`HHTResult.arrays`), each by the attribute of the result it holds;
#: a mesh adds ``faces``.
RESULT_ARRAYS = {
    "vertices": "surface.vertices",
    "normals": "surface.normals",
    "laplacian": "surface.laplacian",
    "n_neighbors": "surface.n_neighbors",
    "signal": "signal",
    "imfs": "imfs",
    "residue": "residue",
    "riesz": "monogenic.riesz",
    "amplitude": "monogenic.amplitude",
    "phase": "monogenic.phase",
    "frequency": "monogenic.frequency",
    "area": "surface.mass_diagonal",
    "origin": "surface.origin",
}
#: The fields of :meth:`HHTResult.vertex_attributes` that a result has once (attributes of the same name).
FIELDS = ("signal", "residue")
#: The fields it has per IMF: ``{kind}_{K}`` is row K - 1 (IMF K, from 1) of the attribute of its kind.
IMF_FIELDS = {
    "imf": "imfs",
    "amplitude": "monogenic.amplitude",
    "phase": "monogenic.phase",
    "frequency": "monogenic.frequency",
}


def field_imf(name: object) -> int | None:
    """The IMF number K of a field ``{kind}_K`` of :data:`IMF_FIELDS` (``imf_K``, ..., ``frequency_K``); else None.

    >>> field_imf("phase_2"), field_imf("signal"), field_imf("imf_0"), field_imf("frequncy_1")
    (2, None, None, None)
    """
    kind, _, number = name.rpartition("_") if isinstance(name, str) else ("", "", "")
    if kind in IMF_FIELDS and number.isascii() and number.isdigit() and not number.startswith("0"):
        return int(number)
    return None


@dataclass
class HHTResult:
    """Outcome of :func:`hht`.

    Attributes
    ----------
    surface : Surface
    signal : (n,) ndarray
    imfs : (k, n) ndarray
        Intrinsic mode functions, finest first.
    residue : (n,) ndarray
        ``signal − imfs.sum(0)`` (kept apart from the IMFs).
    monogenic : MonogenicSignal
        Riesz vectors, amplitude, phase and frequency of every IMF.
    info : dict
        ``"emd"``: the EMD diagnostics; ``"riesz"``: the Riesz settings used;
        ``"seconds"``: wall time of ``"emd"`` and ``"spectra"`` (eager :func:`hht` only).
    """

    surface: Surface
    signal: np.ndarray
    imfs: np.ndarray
    residue: np.ndarray
    monogenic: MonogenicSignal
    info: dict = field(default_factory=dict)

    @classmethod
    def from_parts(
        cls, surface: Surface, signal: np.ndarray, decomposition: Any, mono: MonogenicSignal, riesz_options: dict
    ) -> "HHTResult":
        """Assemble a result from an :class:`~hht3d.decomposition.EMDResult` and the monogenic
        signal of its IMFs (the last of :func:`hht_stages`)."""
        info = {"emd": decomposition.info, "riesz": dict(riesz_options)}
        result = cls(
            surface=surface,
            signal=check_signal(surface, signal),
            imfs=decomposition.imfs,
            residue=decomposition.residue,
            monogenic=mono,
            info=info,
        )
        for message in result._aliasing():  # EMD issued its own warnings already
            warn_quality(f"{surface.name}: {message}", stacklevel=2)
        return result

    @property
    def n_imfs(self) -> int:
        return len(self.imfs)

    @property
    def method(self) -> str | None:
        """The decomposition method (``"sifting"`` or ``"filtering"``); ``None`` for a result read back
        without its info."""
        return (self.info or {}).get("emd", {}).get("method")

    @cached_property
    def quality(self) -> Quality:
        """Energy ratio, index of orthogonality, energy shares and warnings (:mod:`hht3d.decomposition.quality`),
        with those of the IMFs' frequencies above the resolution limit."""
        decomposition = decomposition_quality(self.surface, self.signal, self.imfs, self.residue)
        return decomposition.with_warnings(self._aliasing())

    def _aliasing(self) -> tuple[str, ...]:
        """:func:`~hht3d.decomposition.quality.aliasing_warnings` of the IMFs' frequencies."""
        report = self.spectrum.resolution
        return aliasing_warnings(report.area_per_signal, report.limit)

    def __repr__(self) -> str:
        text = f"{self.surface.name!r}: {self.n_imfs} IMFs of {self.surface.n_vertices:,} vertices"
        return decomposition_repr("HHTResult", text, self.quality)

    def _repr_html_(self) -> str:
        frequency = {"frequency 5–95 %": [value_range(row) for row in self.monogenic.frequency]}
        facts = [("surface", repr(self.surface)), ("IMFs", str(self.n_imfs))]
        return decomposition_html(f"HHTResult: {self.surface.name}", facts, self.n_imfs, frequency, self.quality)

    def show(self, **options: Any) -> Any:
        """The viewer inline in a notebook (:func:`hht3d.viz.notebook.inline_view`: ``height``, ``field``, ...)."""
        from .viz.notebook import inline_view

        return inline_view(self, **options)

    @property
    def spectrum(self) -> HilbertSpectrum:
        """The :class:`~hht3d.spectral.spectrum.HilbertSpectrum` of the IMFs."""
        return HilbertSpectrum.from_monogenic(self.surface, self.monogenic)

    def vertex_attributes(self) -> dict[str, np.ndarray]:
        """Named per-vertex fields: :data:`FIELDS` (``signal``, ``residue``) and, for IMF ``K``
        (from 1), one per kind of :data:`IMF_FIELDS`: ``imf_K``, ``amplitude_K``, ``phase_K``,
        ``frequency_K``."""
        fields = {name: getattr(self, name) for name in FIELDS}
        per_imf = {kind: attrgetter(source)(self) for kind, source in IMF_FIELDS.items()}
        for i in range(self.n_imfs):
            fields.update({f"{kind}_{i + 1}": values[i] for kind, values in per_imf.items()})
        return fields

    def arrays(self) -> dict[str, np.ndarray]:
        """The arrays of the ``.npz`` file: :data:`RESULT_ARRAYS` (``vertices``, ``normals``,
        ``laplacian``, ``n_neighbors``, ``signal``, ``imfs``, ``residue``, ``riesz``,
        ``amplitude``, ``phase``, ``frequency``, ``area``: the vertex areas, ``origin``: where the local
        frame of ``vertices`` lies), then ``faces`` of a mesh."""
        arrays = {name: np.asarray(attrgetter(source)(self)) for name, source in RESULT_ARRAYS.items()}
        if self.surface.is_mesh:
            arrays["faces"] = cast(np.ndarray, self.surface.faces)
        return arrays

    def save(self, path: Path | str, *, storage_options: dict | Sealed | None = None) -> Path:
        """Write the result atomically in the format of its suffix, one of the formats of an HHT
        result that take no options (:func:`hht3d.output_formats.plain_formats`).

        ``.ply``: the surface with :meth:`vertex_attributes` as float64 vertex
        properties.  ``.npz``: :meth:`arrays`; :func:`hht3d.results.load_result`
        reads it back.  ``path`` may be an fsspec URL, with ``storage_options``
        (:mod:`hht3d.io.storage`; or their token in a task graph, :mod:`hht3d.io.sealed`).
        """
        from .output_formats import plain_formats

        if io.storage.is_url(path):  # object storage: written locally, then uploaded
            return io.uploads.write_via(self.save, path, storage_options=unsealed(storage_options))
        path = Path(io.storage.local_path(path))
        formats = plain_formats("hht")
        if path.suffix.lower() not in formats:
            raise InputError(f"cannot save an HHT result as {path.name!r}: use a {' or '.join(formats)} file name")
        return formats[path.suffix.lower()].write(self, self.surface, path)

    def to_html(self, path: Path | str, *, storage_options: dict | Sealed | None = None, **options: Any) -> Path:
        """Write an interactive page of every field, the marginal spectrum and the quality
        figures as one self-contained HTML file (:func:`hht3d.viz.viewer.result_html`, whose
        keyword arguments ``options`` takes: ``beside``, ``field``, ``max_vertices``, ...);
        ``path`` may be an fsspec URL, with ``storage_options``."""
        from .viz.viewer import result_html

        return io.uploads.write_via(result_html, self, path, storage_options=unsealed(storage_options), **options)

    def to_open3d(self) -> Any:
        """An Open3D tensor ``TriangleMesh`` (or ``PointCloud``) carrying
        :meth:`vertex_attributes` as named (n, 1) float vertex attributes."""
        return io.surface_to_open3d(self.surface, self.vertex_attributes())

    def to_pyvista(self) -> Any:
        """A ``pyvista.PolyData`` carrying :meth:`vertex_attributes` as point data
        (:func:`hht3d.io.surface_to_pyvista`; needs PyVista)."""
        return io.surface_to_pyvista(self.surface, self.vertex_attributes())


class Stages(Protocol):
    """How :func:`hht_stages` runs a stage: at once (:func:`hht`) or as graph tasks (:mod:`hht3d.graph`)."""

    def task(self, step: str, func: Callable) -> Callable:
        """``func`` as the stage ``step``: called at once, or made a lazy task."""

    def potential(self, surface: Surface, imfs: np.ndarray, riesz: RieszOptions, backend: str | None) -> Any:
        """``L^{-1/2}`` of the IMFs (Eq. 16): one call, or the quadrature's shift-group tasks."""

    def riesz_vectors(self, surface: Surface, decomposition: Any, riesz: RieszOptions, backend: str | None) -> Any:
        """The Riesz vectors of each IMF on its level (:mod:`hht3d.spectral.multilevel`): one call, or
        one task per group of IMFs."""


class _Eager:
    """Runs every stage at once and adds up its wall time by step."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = {}

    def task(self, step: str, func: Callable) -> Callable:
        def run(*args: Any, **kwargs: Any) -> Any:
            start = time.perf_counter()
            try:
                return func(*args, **kwargs)
            finally:
                self.seconds[step] = self.seconds.get(step, 0.0) + time.perf_counter() - start

        return run

    def potential(self, surface: Surface, imfs: np.ndarray, riesz: RieszOptions, backend: str | None) -> Any:
        return self.task("riesz", fractional_laplacian)(surface, imfs, -0.5, riesz, backend=backend)

    def riesz_vectors(self, surface: Surface, decomposition: Any, riesz: RieszOptions, backend: str | None) -> Any:
        return self.task("riesz", riesz_vectors)(surface, decomposition, riesz, backend)


def _imfs(decomposition: Any) -> np.ndarray:
    return decomposition.imfs


def decomposition_stage(
    stages: Stages,
    surface: Surface,
    signal: np.ndarray,
    options: EMDOptions,
    ensemble: EnsembleOptions | None,
    backend: str | None,
) -> Any:
    """EMD (one stage ``emd``), or EEMD: one ``eemd_member`` stage per member, then ``eemd_combine``."""
    if ensemble is None:
        return stages.task("emd", emd)(surface, signal, options, backend=backend)
    member = stages.task("eemd_member", eemd_member)
    members = [member(surface, signal, i, options, ensemble, backend) for i in range(ensemble.ensemble_size)]
    return stages.task("eemd_combine", combine_eemd)(surface, signal, members)


def _may_use_levels(options: HHTOptions) -> bool:
    """Whether the decomposition may carry IMFs on levels, whose Riesz vectors are then taken there
    (:mod:`hht3d.spectral.multilevel`; the stage also takes a decomposition without levels)."""
    emd = options.emd
    return (
        options.ensemble is None
        and emd.method == "filtering"
        and emd.multiresolution != "never"
        and options.riesz.potential == "quadrature"
    )


def hht_stages(
    stages: Stages,
    surface: Surface,
    signal: np.ndarray,
    options: HHTOptions | dict | None = None,
    *,
    backend: str | None = None,
    **overrides: Any,
) -> dict:
    """The HHT's stages in order (Alg. 2), by name: ``emd``, ``imfs``, ``riesz``, ``monogenic``, ``hht``.

    ``riesz`` is ``L^{-1/2}`` of the IMFs, or, when iterative filtering may use levels, their
    Riesz vectors ``(k, n, 3)`` (:mod:`hht3d.spectral.multilevel`).

    The one list of the stages: :func:`hht` runs it at once, :func:`hht3d.graph.transform`
    as lazy tasks, and the pipeline's ``hht`` step through the graph.  The settings
    (as for :func:`hht`) are checked here, before the first stage.
    """
    options = hht_settings(options, overrides, "hht_stages")
    riesz = options.riesz
    decomposition = decomposition_stage(stages, surface, signal, options.emd, options.ensemble, backend)
    imfs = stages.task("imfs", _imfs)(decomposition)
    if _may_use_levels(options):
        potential = stages.riesz_vectors(surface, decomposition, riesz, backend)
        mono = stages.task("monogenic", monogenic_from_riesz)(surface, imfs, potential, riesz)
    else:
        potential = stages.potential(surface, imfs, riesz, backend)
        mono = stages.task("monogenic", monogenic_from_potential)(surface, imfs, potential, riesz)
    result = stages.task("hht", HHTResult.from_parts)(surface, signal, decomposition, mono, riesz.as_dict())
    return {"emd": decomposition, "imfs": imfs, "riesz": potential, "monogenic": mono, "hht": result}


def hht(
    surface: Surface,
    signal: np.ndarray,
    options: HHTOptions | dict | None = None,
    *,
    backend: str | None = None,
    **overrides: Any,
) -> HHTResult:
    """Hilbert–Huang transform of a surface signal: EMD, then Algorithm 2 on all IMFs.

    Parameters
    ----------
    surface : Surface
    signal : (n,) array_like
    options : HHTOptions or dict, optional
        The settings of :func:`hht3d.decomposition.emd` (``max_imfs``, ``stopping``, ...),
        of the Riesz transform and Eq. 23 (``potential``, ``tol``, ``frequency``, ...; see
        :func:`hht3d.spectral.monogenic`) and, to decompose by ensemble EMD instead of EMD,
        of the ensemble (``ensemble_size``, ``noise_std``, ``seed``): an :class:`HHTOptions`,
        a dict of its parts (``{"emd": {...}, "riesz": {...}}``) or of settings by name.
    backend : str, optional
        Sparse solver of :mod:`hht3d.linalg` for EMD and the Riesz transform.
    **overrides
        Settings by name, each sent to the record that declares it (``max_imfs=2, tol=1e-6``).
        The former keywords ``emd=``, ``riesz=`` and ``ensemble=`` are accepted for one
        release with a DeprecationWarning.

    Returns
    -------
    HHTResult
        ``info["seconds"]`` holds the wall time of ``"emd"`` and ``"spectra"``.

    Examples
    --------
    >>> from hht3d import data_path, hht, load
    >>> from hht3d.geometry.signals import mean_curvature
    >>> surface = load(data_path("spot.ply"))
    >>> result = hht(surface, mean_curvature(surface), max_imfs=2)
    >>> result.n_imfs, result.monogenic.frequency.shape
    (2, (2, 2930))
    >>> result.quality.ok
    True
    >>> result.info["riesz"]["tol"]
    1e-08
    """
    stages = _Eager()
    result = hht_stages(stages, surface, signal, hht_settings(options, overrides, "hht"), backend=backend)["hht"]
    spent = stages.seconds
    result.info["seconds"] = {
        "emd": sum(spent.get(k, 0.0) for k in ("emd", "eemd_member", "eemd_combine")),
        "spectra": spent.get("riesz", 0.0) + spent.get("monogenic", 0.0),
    }
    return result
