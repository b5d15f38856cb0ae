"""What a page draws of a surface (hht3d.viz.shown): colour limits at the stated percentiles, decimated meshes
and subsampled point clouds that carry their fields."""

from __future__ import annotations

import numpy as np
import pytest

from helpers.meshes import fibonacci_sphere, icosphere
from helpers.pages import decoded, field_values, page_data
from hht3d import Surface
from hht3d.viz.viewer import PERCENTILES, color_limits, shown_copy, write_page


def test_color_limits_are_the_stated_percentiles():
    values = np.random.default_rng(1).standard_normal(5000) * 3 + 0.5
    values[:5] = [1e6, -1e6, 1e5, np.nan, np.inf]  # outliers and non-finite values do not move them
    finite = values[np.isfinite(values)]
    low, high = np.percentile(finite, PERCENTILES)
    limits = color_limits(values)
    np.testing.assert_allclose(limits["sequential"], [low, high], rtol=1e-12)
    bound = max(abs(low), abs(high))
    np.testing.assert_allclose(limits["symmetric"], [-bound, bound], rtol=1e-12)
    assert limits["auto"] == "symmetric"
    positive = np.abs(values[np.isfinite(values)]) + 1.0
    assert color_limits(positive)["auto"] == "sequential"
    np.testing.assert_allclose(color_limits(positive, (5, 95))["sequential"], np.percentile(positive, [5, 95]))


# -- big surfaces --------------------------------------------------------------------------------
@pytest.mark.slow
@pytest.mark.parametrize("budget", [2000, 3000])  # 10,242 > 4 x 2000: clustered first; < 4 x 3000: not
def test_decimation_transfers_fields_to_the_nearest_vertex(tmp_path, budget):
    v, f = icosphere(5)  # 10,242 vertices
    surface = Surface(v, f, name="sphere")
    field = np.sin(3 * v[:, 0]) + v[:, 1] * v[:, 2]
    shown = shown_copy(surface, budget)
    assert shown.decimated and 0.75 * budget <= len(shown.source) <= budget and len(shown.faces) > 1.25 * budget
    distance = np.linalg.norm(shown.vertices[:, None, :] - v[None, :, :], axis=2)
    # a nearest vertex (a clustered vertex can sit exactly midway between two)
    np.testing.assert_array_equal(distance[np.arange(len(distance)), shown.source], distance.min(axis=1))
    # the carried value is the analytic field near each drawn vertex (|grad| <= 4, moves < 2 edge lengths)
    drawn = shown.vertices
    exact = np.sin(3 * drawn[:, 0]) + drawn[:, 1] * drawn[:, 2]
    assert np.max(np.abs(shown.carry(field) - exact)) < 4 * 2 * 0.025
    page = write_page(tmp_path / "sphere.html", [surface], {"wave": field}, title="sphere", max_vertices=budget)
    data = page_data(page)
    np.testing.assert_array_equal(field_values(data, "wave"), field[shown.source].astype(np.float32))
    assert len(data["notices"]) == 1 and "decimated copy with" in data["notices"][0]
    np.testing.assert_allclose(next(e for e in data["fields"])["sequential"], np.percentile(field, PERCENTILES))


def test_point_cloud_is_drawn_as_points_and_subsampled_with_its_own_values(tmp_path):
    points = fibonacci_sphere(3000)
    cloud = Surface(points, name="cloud")
    height = points[:, 2]
    page = write_page(tmp_path / "cloud.html", [cloud], {"height": height}, title="cloud", max_vertices=1000)
    data = page_data(page)
    (trace,) = data["figure"]["data"]
    assert trace["type"] == "scatter3d" and trace["mode"] == "markers" and data["surfaces"][0]["points"]
    drawn_z = decoded(trace["z"])
    assert len(drawn_z) == 1000
    np.testing.assert_array_equal(field_values(data, "height"), drawn_z)  # each point keeps its own value
    assert "random subset of 1,000 points" in data["notices"][0]
