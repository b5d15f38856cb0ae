"""The Hilbert–Huang transform on a surface in one call: EMD + Hilbert spectra (Alg. 2).

:func:`hht` decomposes a signal into IMFs (Sec. 4.1, :func:`hht3d.decomposition.decompose.emd`),
takes the monogenic signal of every IMF at once (Sec. 4.2–4.3,
:func:`hht3d.spectral.monogenic_signal.monogenic`) and returns an :class:`HHTResult` that
can be saved (PLY with named vertex attributes, or ``.npz``) and handed to
Open3D as a tensor mesh or point cloud.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np

from . import io
from .decomposition.decompose import check_emd_options, emd
from .errors import InputError
from .spectral.monogenic_signal import MonogenicSignal, monogenic
from .spectral.options import RIESZ_DEFAULTS, RieszOptions
from .decomposition.quality import Quality, decomposition_quality
from .spectral.spectrum import HilbertSpectrum
from .geometry.surface import Surface
from .geometry.validation import check_signal

__all__ = ["HHTResult", "hht"]


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
        ``"emd"``: the EMD diagnostics; ``"riesz"``: the options used;
        ``"seconds"``: wall time of ``"emd"`` and ``"spectra"`` (by :func:`hht`).
    """

    surface: Surface
    signal: np.ndarray
    imfs: np.ndarray
    residue: np.ndarray
    monogenic: MonogenicSignal
    info: dict = field(default_factory=dict)

    @classmethod
    def from_parts(cls, surface: Surface, signal, decomposition, mono: MonogenicSignal,
                   riesz_options: dict, seconds: dict | None = None) -> "HHTResult":
        """Assemble a result from an :class:`~hht3d.decomposition.decompose.EMDResult` and the monogenic signal
        of its IMFs (as the lazy graph of :mod:`hht3d.graph.stages` does)."""
        info = {"emd": decomposition.info, "riesz": dict(riesz_options)}
        if seconds is not None:
            info["seconds"] = seconds
        return cls(surface=surface, signal=check_signal(surface, signal), imfs=decomposition.imfs,
                   residue=decomposition.residue, monogenic=mono, info=info)

    @property
    def n_imfs(self) -> int:
        return len(self.imfs)

    @cached_property
    def quality(self) -> Quality:
        """Energy ratio, index of orthogonality, energy shares and warnings (:mod:`hht3d.decomposition.quality`)."""
        return decomposition_quality(self.surface, self.signal, self.imfs, self.residue)

    @property
    def spectrum(self) -> HilbertSpectrum:
        """The :class:`~hht3d.spectral.spectrum.HilbertSpectrum` of the IMFs."""
        return HilbertSpectrum.from_monogenic(self.surface, self.monogenic)

    def vertex_attributes(self) -> dict[str, np.ndarray]:
        """Named per-vertex fields: ``signal``, ``residue`` and, for IMF ``i`` (from 1),
        ``imf_i``, ``amplitude_i``, ``phase_i``, ``frequency_i``."""
        fields = {"signal": self.signal, "residue": self.residue}
        mono = self.monogenic
        for i in range(self.n_imfs):
            fields.update({f"imf_{i + 1}": self.imfs[i], f"amplitude_{i + 1}": mono.amplitude[i],
                           f"phase_{i + 1}": mono.phase[i], f"frequency_{i + 1}": mono.frequency[i]})
        return fields

    def save(self, path, *, storage_options: dict | None = None) -> Path:
        """Write the result atomically.

        ``.ply``: the surface with :meth:`vertex_attributes` as float64
        vertex properties.  ``.npz``: arrays ``vertices``, ``faces`` (meshes),
        ``signal``, ``imfs``, ``residue``, ``riesz``, ``amplitude``,
        ``phase``, ``frequency`` and ``area`` (vertex areas).  ``path`` may be
        an fsspec URL, with ``storage_options`` (:mod:`hht3d.io.storage`).
        """
        if io.storage.is_url(path):  # object storage: written locally, then uploaded
            return io.storage.write_via(self.save, path, storage_options=storage_options)
        path = Path(path)
        suffix = path.suffix.lower()
        if suffix == ".ply":
            return io.write_ply(path, self.surface, self.vertex_attributes())
        if suffix == ".npz":
            mono = self.monogenic
            arrays = {"vertices": self.surface.vertices, "signal": self.signal, "imfs": self.imfs,
                      "residue": self.residue, "riesz": mono.riesz, "amplitude": mono.amplitude,
                      "phase": mono.phase, "frequency": mono.frequency,
                      "area": self.surface.mass_diagonal}
            if self.surface.is_mesh:
                arrays["faces"] = self.surface.faces
            return io.write_npz(path, arrays)
        raise InputError(f"cannot save an HHT result as {path.name!r}: use a .ply or .npz file name")

    def to_html(self, path, *, storage_options: dict | None = None, **options) -> Path:
        """Write an interactive page of every field, the marginal spectrum and the quality
        figures as one self-contained HTML file (:func:`hht3d.viz.viewer.result_html`, whose
        keyword arguments ``options`` takes: ``beside``, ``field``, ``max_vertices``, ...);
        ``path`` may be an fsspec URL, with ``storage_options``."""
        from .viz.viewer import result_html

        return io.storage.write_via(result_html, self, path, storage_options=storage_options, **options)

    def to_open3d(self):
        """An Open3D tensor ``TriangleMesh`` (or ``PointCloud``) carrying
        :meth:`vertex_attributes` as named (n, 1) float vertex attributes."""
        return self.surface.to_open3d(self.vertex_attributes())


def hht(surface: Surface, signal, *, emd_options: dict | None = None, gradient: str = RIESZ_DEFAULTS.gradient,
        frequency: str = RIESZ_DEFAULTS.frequency, method: str = RIESZ_DEFAULTS.method,
        tol: float = RIESZ_DEFAULTS.tol, eigenpairs: int = RIESZ_DEFAULTS.eigenpairs,
        backend: str | None = RIESZ_DEFAULTS.backend) -> HHTResult:
    """Hilbert–Huang transform of a surface signal: EMD, then Algorithm 2 on all IMFs.

    Parameters
    ----------
    surface : Surface
    signal : (n,) array_like
    emd_options : dict, optional
        Keyword arguments of :func:`hht3d.decomposition.decompose.emd` (``max_imfs``,
        ``stopping``, ...).
    gradient, frequency, method, tol, eigenpairs
        Riesz transform and Eq. 23 options; see :func:`hht3d.spectral.monogenic_signal.monogenic`.
    backend : str, optional
        Sparse solver for EMD and the Riesz transform.

    Returns
    -------
    HHTResult

    Examples
    --------
    >>> from hht3d import data_path, hht, load
    >>> from hht3d.geometry.signals import mean_curvature
    >>> surface = load(data_path("spot.ply"))
    >>> result = hht(surface, mean_curvature(surface), emd_options={"max_imfs": 2})
    >>> result.n_imfs, result.monogenic.frequency.shape
    (2, (2, 2930))
    >>> result.quality.ok
    True
    >>> result.info["riesz"]["tol"]
    1e-08
    """
    check_emd_options(emd_options or {})
    riesz_options = RieszOptions(gradient, frequency, method, tol, eigenpairs, backend)
    options = {"backend": backend, **(emd_options or {})}
    start = time.perf_counter()
    decomposition = emd(surface, signal, **options)
    middle = time.perf_counter()
    mono = monogenic(surface, decomposition.imfs, gradient=gradient, frequency=frequency, method=method,
                     tol=tol, eigenpairs=eigenpairs, backend=backend)
    end = time.perf_counter()
    return HHTResult.from_parts(surface, signal, decomposition, mono, riesz_options.recorded(),
                                {"emd": middle - start, "spectra": end - middle})
