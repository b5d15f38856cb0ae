"""Fixtures of the rendering and viewer tests: a small sphere, the HHT of the demo model and its page."""

from __future__ import annotations

import pytest

import hht3d
from helpers.meshes import icosphere
from hht3d.cli import demo_model_path
from hht3d.geometry import signals
from hht3d.geometry.surface import Surface


@pytest.fixture(scope="module")
def sphere() -> Surface:
    return Surface(*icosphere(3), name="sphere")


@pytest.fixture(scope="module")
def result():
    """The HHT of the shipped demo model's mean curvature, two IMFs."""
    surface = hht3d.load(demo_model_path())
    return hht3d.hht(surface, signals.mean_curvature(surface), max_imfs=2)


@pytest.fixture(scope="module")
def result_page(result, tmp_path_factory):
    return result.to_html(tmp_path_factory.mktemp("page") / "spot.html", view="back")
