"""What a viewer page embeds: its JSON data and the float32 arrays of its fields."""

from __future__ import annotations

import base64
import json
import re

import numpy as np

from helpers.meshes import fibonacci_sphere
from hht3d import HilbertSpectrum, Surface
from hht3d.viz.viewer import write_page


def page_data(path) -> dict:
    """The JSON the script of the page in the file ``path`` reads."""
    return page_json(path.read_text(encoding="utf-8"))


def page_json(text: str) -> dict:
    """The JSON the script of the page ``text`` reads."""
    match = re.search(r'<script type="application/json" id="hht3d-data">(.*?)</script>', text, re.S)
    return json.loads(match.group(1))


def decoded(spec) -> np.ndarray:
    assert spec["dtype"] == "f4"
    return np.frombuffer(base64.b64decode(spec["bdata"]), dtype="<f4")


def field_values(data: dict, name: str, copy: int = 0) -> np.ndarray:
    return decoded(next(f for f in data["fields"] if f["name"] == name)["values"][copy])


class _Limited(HilbertSpectrum):
    """A spectrum that reports the frequency above which its surface resolves nothing."""

    @property
    def resolvable_frequency(self):
        return 12.0


def cloud_with_spectrum(tmp_path):
    points = fibonacci_sphere(4000)
    cloud = Surface(points, name="cloud")
    frequency = np.vstack([20 + 5 * points[:, 0], 4 + points[:, 1]])
    spectrum = _Limited(frequency, np.ones_like(frequency), np.full(len(points), 1 / len(points)))
    return write_page(tmp_path / "cloud.html", [cloud], {"z": points[:, 2]}, title="cloud", spectrum=spectrum)
