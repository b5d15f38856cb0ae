"""The data a page embeds: plotly traces and figure, the spectrum bars and the quality table."""

from __future__ import annotations

import base64
import re
from collections.abc import Iterable, Sequence
from typing import Any, cast

import numpy as np

from ..decomposition.quality import ENERGY_RATIO_LIMIT, LEAKAGE_LIMIT, ORTHOGONALITY_LIMIT, SPIKE_LIMIT, Quality
from ..geometry.surface import Surface
from ..spectral.spectrum import HilbertSpectrum
from .render import camera
from .shown import Shown

__all__ = [
    "typed",
    "colorscale",
    "field_title",
    "order",
    "figure_json",
    "spectrum_data",
    "quality_data",
    "size_text",
    "SPECTRUM_BINS",
]

#: Log-spaced frequency bins of the page's marginal spectrum.
SPECTRUM_BINS = 64
#: Point clouds with more drawn points than this get smaller markers, so dense scans stay legible.
SMALL_MARKERS_ABOVE = 20_000
#: The camera's distance from the model's centre, in units of plotly's scene box; far enough
#: to frame the whole model at plotly's default field of view.
EYE_DISTANCE = 1.75
_GROUPED = re.compile(r"^(imf|amplitude|phase|frequency)_([1-9][0-9]*)$")
_GROUPS = {
    "imf": "decomposition",
    "amplitude": "local amplitude (Eq. 21)",
    "phase": "local phase (Eq. 22)",
    "frequency": "instantaneous frequency (Eq. 23)",
}


def typed(values: np.ndarray) -> dict:
    """plotly.js's typed-array form: little-endian float32 in base64."""
    raw = np.ascontiguousarray(values, dtype="<f4").tobytes()
    return {"dtype": "f4", "bdata": base64.b64encode(raw).decode("ascii")}


def colorscale(name: str) -> list:
    import matplotlib

    cmap = matplotlib.colormaps[name]
    stops = np.linspace(0.0, 1.0, 11)
    return [[float(t), "rgb({},{},{})".format(*(int(round(255 * c)) for c in cmap(t)[:3]))] for t in stops]


def field_title(name: str) -> tuple[str, str]:
    """Display name and selector group of a field."""
    match = _GROUPED.match(name)
    if match is None:
        return name, "decomposition" if name in ("signal", "residue") else "other"
    kind, k = match.groups()
    return f"IMF {k}" if kind == "imf" else f"{kind} {k}", _GROUPS[kind]


def order(names: Iterable[str]) -> list[str]:
    """Signal, IMFs, residue, then amplitude, phase and frequency of each IMF, then the rest."""

    def key(name: str) -> tuple[int, int]:
        match = _GROUPED.match(name)
        if match is not None:
            kind, k = match.groups()
            return (1 if kind == "imf" else 3 + list(_GROUPS).index(kind), int(k))
        return {"signal": (0, 0), "residue": (2, 0)}.get(name, (7, 0))

    return sorted(names, key=key)


def _trace(shown: Shown, index: int, label: str) -> dict:
    import plotly.graph_objects as go

    x, y, z = (np.asarray(c, dtype=np.float32) for c in shown.vertices.T)
    scene = "scene" if index == 0 else f"scene{index + 1}"
    if shown.faces is None:
        size = 2 if len(shown.source) > SMALL_MARKERS_ABOVE else 3
        return go.Scatter3d(
            x=x, y=y, z=z, mode="markers", marker={"size": size}, name=label, scene=scene, showlegend=False
        )
    i, j, k = (np.asarray(c, dtype=np.int32) for c in shown.faces.T)
    return go.Mesh3d(
        x=x,
        y=y,
        z=z,
        i=i,
        j=j,
        k=k,
        name=label,
        scene=scene,
        flatshading=False,
        lighting={"ambient": 0.6, "diffuse": 0.7, "specular": 0.1, "roughness": 0.7},
        showlegend=False,
    )


def figure_json(shown: list[Shown], labels: list[str], view: str | Sequence[float], up: str | Sequence[float]) -> str:
    import plotly.graph_objects as go
    import plotly.io as pio

    cam = camera(view, up)
    eye = dict(zip("xyz", (EYE_DISTANCE * cam.toward).tolist()))
    cam_up = dict(zip("xyz", cam.up.tolist()))
    hidden = {"visible": False, "showspikes": False}
    layout: dict[str, Any] = {"margin": {"l": 0, "r": 0, "t": 28, "b": 0}, "uirevision": "hht3d", "annotations": []}
    width = 1.0 / len(shown)
    for index, label in enumerate(labels):
        name = "scene" if index == 0 else f"scene{index + 1}"
        layout[name] = {
            "domain": {"x": [index * width, (index + 1) * width], "y": [0, 1]},
            "aspectmode": "data",
            "xaxis": hidden,
            "yaxis": hidden,
            "zaxis": hidden,
            "camera": {"eye": eye, "up": cam_up, "center": {"x": 0, "y": 0, "z": 0}},
        }
        if len(shown) > 1:
            layout["annotations"].append(
                {
                    "text": label,
                    "x": (index + 0.5) * width,
                    "y": 1.0,
                    "xref": "paper",
                    "yref": "paper",
                    "yanchor": "bottom",
                    "showarrow": False,
                    "font": {"size": 14},
                }
            )
    figure = go.Figure([_trace(s, i, label) for i, (s, label) in enumerate(zip(shown, labels))], layout)
    return pio.to_json(figure, validate=True, pretty=False)


def spectrum_data(spectrum: HilbertSpectrum) -> dict | None:
    total = float(spectrum.imf_energy().sum())
    if not total > 0 or not np.any(spectrum.frequency > 0):
        return None
    edges, marginal = spectrum.marginal(SPECTRUM_BINS, "log", spectrum.frequency_limits("log"))
    per_imf = [
        100
        * HilbertSpectrum(spectrum.frequency[k : k + 1], spectrum.amplitude[k : k + 1], spectrum.area).marginal(
            SPECTRUM_BINS, "log", (edges[0], edges[-1])
        )[1]
        / total
        for k in range(len(spectrum.frequency))
    ]
    limit = getattr(spectrum, "resolvable_frequency", None)
    limit = limit() if callable(limit) else limit
    within = 100 * marginal.sum() / total
    caption = (
        f"Share of the IMF energy ∫a²dA per log-spaced frequency bin ({SPECTRUM_BINS} bins, "
        f"{within:.1f}% of the energy in the plotted range); the selected frequency field's colour "
        "range is shaded."
    )
    return {
        "edges": edges.tolist(),
        "marginal": (100 * marginal / total).tolist(),
        "imfs": [row.tolist() for row in per_imf],
        "scale": "log",
        "caption": caption,
        "resolvable_frequency": None if limit is None else float(limit),
    }


def quality_data(quality: Quality) -> dict:
    rows = [
        ["energy ratio (1 when orthogonal)", f"{quality.energy_ratio:.3g}", quality.energy_ratio > ENERGY_RATIO_LIMIT],
        [
            "index of orthogonality (0 when orthogonal)",
            f"{quality.orthogonality_index:.3g}",
            not ORTHOGONALITY_LIMIT <= quality.orthogonality_index <= LEAKAGE_LIMIT,
        ],
        ["  of which leaking (positive cross terms)", f"{quality.io_leaking:.3g}", False],
        ["  of which cancelling (negative cross terms)", f"{quality.io_cancelling:.3g}", False],
        ["signal spike max|s̃| / p99|s̃|", f"{quality.signal_spike:.3g}", quality.signal_spike > SPIKE_LIMIT],
    ]
    names = [f"IMF {k + 1}" for k in range(len(quality.energy_share) - 1)] + ["residue"]
    rows += [[f"energy share: {name}", f"{share:.1%}", False] for name, share in zip(names, quality.energy_share)]
    return {"rows": rows, "warnings": list(quality.warnings)}


def size_text(surface: Surface) -> str:
    kind = f"{len(cast(np.ndarray, surface.faces)):,} triangles" if surface.is_mesh else "point cloud"
    return f"{surface.n_vertices:,} vertices, {kind}"
