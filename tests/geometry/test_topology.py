"""Topology summary against the statistics published in ../shared/data/MANIFEST.md."""

import pytest

from hht3d import load
from hht3d.geometry.topology import describe


@pytest.mark.parametrize(
    "model, expected",
    [
        (
            "spacetime_face_neutral.ply",
            dict(
                vertices=7118,
                faces=14037,
                boundary_loops=2,
                boundary_vertices=199,
                components=1,
                euler_characteristic=0,
                non_manifold_vertices=0,
            ),
        ),
        (
            "office_kinect_colored.ply",
            dict(
                vertices=62143,
                faces=112953,
                boundary_loops=616,
                boundary_vertices=12747,
                components=9,
                euler_characteristic=-938,
                non_manifold_vertices=462,
            ),
        ),
        ("rocker_arm.ply", dict(vertices=10044, boundary_loops=0, closed=True, euler_characteristic=0)),
    ],
)
def test_describe_matches_manifest(shared_model, model, expected):
    info = describe(load(shared_model(model)))
    assert {k: info[k] for k in expected} == expected
