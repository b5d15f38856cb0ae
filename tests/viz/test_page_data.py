"""What a viewer page's data holds (hht3d.viz.page_data): one geometry for every field, the spectrum and the
quality figures, each field's colour limits, the spectrum's resolution limit."""

from __future__ import annotations

import base64

import numpy as np

from helpers.pages import cloud_with_spectrum, decoded, page_data
from hht3d.viz.viewer import color_limits


def test_page_geometry_is_shared_by_all_fields(result, result_page):
    data = page_data(result_page)
    (trace,) = data["figure"]["data"]
    assert trace["type"] == "mesh3d" and "intensity" not in trace
    np.testing.assert_array_equal(decoded(trace["x"]), result.surface.vertices[:, 0].astype(np.float32))
    faces = np.column_stack(
        [np.frombuffer(base64.b64decode(trace[c]["bdata"]), dtype=trace[c]["dtype"]) for c in "ijk"]
    )
    np.testing.assert_array_equal(faces, result.surface.faces)


def test_page_shows_spectrum_and_quality(result, result_page):
    data = page_data(result_page)
    spectrum, quality = data["spectrum"], data["quality"]
    assert len(spectrum["imfs"]) == 2 and len(spectrum["edges"]) == len(spectrum["marginal"]) + 1
    np.testing.assert_allclose(np.sum(spectrum["imfs"], axis=0), spectrum["marginal"], rtol=1e-9, atol=1e-12)
    assert 99 <= sum(spectrum["marginal"]) <= 100
    assert spectrum["resolvable_frequency"] is None or spectrum["resolvable_frequency"] > 0
    q = result.quality
    assert quality["rows"][0][1] == f"{q.energy_ratio:.3g}" and quality["warnings"] == list(q.warnings)
    imf_1 = next(f for f in data["fields"] if f["name"] == "imf_1")
    assert imf_1["label"] == f"IMF 1 — {q.energy_share[0]:.1%} of the energy"


def test_page_limits_are_those_of_every_vertex(result, result_page):
    data = page_data(result_page)
    for name, values in result.vertex_attributes().items():
        entry = next(f for f in data["fields"] if f["name"] == name)
        limits = color_limits(values)
        assert entry["auto"] == limits["auto"]
        np.testing.assert_allclose(entry["symmetric"], limits["symmetric"])
        np.testing.assert_allclose(entry["sequential"], limits["sequential"])


def test_resolution_limit_of_the_spectrum_is_marked(tmp_path):
    spectrum = page_data(cloud_with_spectrum(tmp_path))["spectrum"]
    assert spectrum["resolvable_frequency"] == 12.0 and spectrum["edges"][0] < 12.0 < spectrum["edges"][-1]
