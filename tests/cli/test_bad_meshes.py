"""Bad inputs about the meshes and point clouds themselves (issue 15): flat clouds and points on a line,
meshes as found in the wild (odd encodings, huge or tiny coordinates, non-manifold edges), broken ones.

One table row each, run by :func:`helpers.bad_inputs.run_case` (what a row holds and checks is told there).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from plyfile import PlyData

from helpers.bad_files import _quads
from helpers.bad_inputs import Case, Ran, _decomposes, _npz, accepted, refused, run, run_case
from helpers.meshes import icosphere
from hht3d.io import load


# -- checks of correct results ----------------------------------------------------------------------------------
def _same_as_good(stem: str, scale: float = 1.0, rtol: float = 1e-9):
    """The result equals that of good.ply with lengths scaled by ``scale`` (curvature and frequency by 1/scale)."""

    def check(ran: Ran) -> None:
        good, other = _npz(ran, "good"), _npz(ran, stem)
        np.testing.assert_allclose(other["vertices"], scale * good["vertices"], rtol=rtol)
        for name in ("signal", "imfs", "frequency"):
            np.testing.assert_allclose(scale * other[name], good[name], rtol=rtol, atol=rtol * np.abs(good[name]).max())
        np.testing.assert_allclose(other["phase"], good["phase"], atol=1e-6)

    return check


def _flat_cloud(ran: Ran) -> None:
    result = _npz(ran, "flat_cloud")
    assert result["imfs"].shape == (0, 400) and np.abs(result["signal"]).max() < 1e-12
    normals = load(ran.inputs / "flat_cloud.ply").normals
    np.testing.assert_allclose(normals, np.tile([0.0, 0.0, 1.0], (400, 1)))


def _nearly_flat(stem: str):
    def check(ran: Ran) -> None:
        result = _npz(ran, stem)
        assert result["signal"].shape == (400,) and np.abs(result["signal"]).max() < 1e-6  # flat: ~no curvature
        _decomposes(result)

    return check


def _constant(ran: Ran) -> None:
    result = _npz(ran, "plane_at_2")
    assert result["imfs"].shape == (0, 64)
    np.testing.assert_array_equal(result["residue"], np.full(64, 2.0))


def _mixed(ran: Ran) -> None:
    result = _npz(ran, "mixed")
    v, faces = _quads()
    assert len(result["faces"]) == sum(len(f) - 2 for f in faces) == 98  # quads fan-triangulated
    np.testing.assert_array_equal(result["vertices"], v)
    _decomposes(result)


def _non_manifold(ran: Ran) -> None:
    result = _npz(ran, "non_manifold")
    assert result["signal"].shape == (163,) and np.all(np.isfinite(result["frequency"]))
    _decomposes(result)


def _zero_area(ran: Ran) -> None:
    result, good = _npz(ran, "zero_area"), _npz(ran, "good")
    np.testing.assert_array_equal(result["vertices"], good["vertices"])  # the flat sliver component is dropped
    np.testing.assert_allclose(result["imfs"], good["imfs"], atol=1e-12)


def _two_parts(ran: Ran) -> None:
    result = _npz(ran, "two_parts")
    half = len(result["signal"]) // 2
    np.testing.assert_allclose(result["signal"][:half], result["signal"][half:], atol=1e-12)
    _decomposes(result)


def _int8(ran: Ran) -> None:
    result = _npz(ran, "int8")
    np.testing.assert_array_equal(result["faces"], icosphere(1)[1])


def _strict_json(ran: Ran) -> None:
    """``info --json`` of a mesh near the coordinate limit: strict JSON (no NaN, no Infinity), finite area."""

    def refuse(constant):
        raise AssertionError(f"{constant} is not JSON")

    info = json.loads(ran.stdout, parse_constant=refuse)
    assert info["vertices"] == 162 and 1e139 < info["surface_area"] < 1e142


def _renamed_property(ran: Ran) -> None:
    header = PlyData.read(str(ran.out / "0bad_hht.ply"))["vertex"].data.dtype.names
    assert "_0bad" in header and "0bad" not in header


CASES = {
    # 2. flat point clouds: a result, and no Qhull output
    "exactly flat point cloud (z = 0)": accepted("flat_cloud.ply", check=_flat_cloud, issue=True),
    "tilted flat point cloud": accepted("tilted_cloud.ply", check=_nearly_flat("tilted_cloud"), issue=True),
    "nearly flat point cloud (1e-12)": accepted(
        "nearly_flat_cloud.ply", check=_nearly_flat("nearly_flat_cloud"), issue=True
    ),
    "points on a line": refused("line_cloud.ply", "50 points lie on a line"),
    # beyond the issue: meshes and point clouds as found in the wild
    "non-manifold edge": accepted("non_manifold.ply", check=_non_manifold),
    "zero-area component": accepted("good.ply", "zero_area.ply", check=_zero_area),
    "huge coordinates (1e30)": accepted("good.ply", "huge.ply", check=_same_as_good("huge", 1e30)),
    "tiny coordinates (1e-30)": accepted("good.ply", "tiny.ply", check=_same_as_good("tiny", 1e-30)),
    "mixed triangle/quad PLY": accepted("mixed.ply", check=_mixed),
    "big-endian binary PLY": accepted("good.ply", "big_endian.ply", check=_same_as_good("big_endian")),
    "ASCII PLY": accepted("good.ply", "ascii.ply", check=_same_as_good("ascii")),
    "vertex_indices as uint32": accepted("good.ply", "uint32.ply", check=_same_as_good("uint32")),
    "vertex_indices as int8": accepted("int8.ply", check=_int8),
    "disconnected components": accepted("two_parts.ply", check=_two_parts),
    "constant signal": Case(
        run("inputs=<in>/plane_at_2.ply", "steps.curvature.params.kind=z"), "", 0, (), check=_constant
    ),
    "NaN coordinates": refused("nan.ply", "1 vertices have NaN or infinite coordinates (first: vertex 5)"),
    "infinite coordinates": refused("infinite.ply", "NaN or infinite coordinates (first: vertex 7)"),
    "too few vertices": refused("three.ply", "3 vertices; a surface needs at least 4"),
    "every point the same": refused("same_point.ply", "1 vertices; a surface needs at least 4"),
    "every face degenerate": refused("all_degenerate.ply", "0 vertices; a surface needs at least 4"),
    "face index out of range": refused("bad_index.ply", "face indices must lie in [0, 162), got [0, 500]"),
    "point cloud smaller than n_neighbors": refused(
        "ten.xyz", "a point cloud of 10 points cannot give each point n_neighbors=30"
    ),
    "stored attribute that is not there": Case(
        run("steps.curvature.params={kind: stored, attribute: height}"), "no stored vertex attribute 'height'"
    ),
    "luminance without colours": Case(run("steps.curvature.params.kind=luminance"), "has no vertex colours"),
    "PLY property 0bad": Case(
        run("inputs=<in>/0bad.ply", "outputs.files=[{path: '{stem}_hht.ply'}]"), "", 0, (), check=_renamed_property
    ),
    "info --json of a mesh x1e300": Case(
        ("info", "--json", "<in>/huge300.ply"),
        "huge300.ply: huge300: coordinates reach 1.06e+300; beyond 1e+75 areas and curvatures overflow float64",
    ),
    "run on a mesh x1e300": Case(run("inputs=<in>/huge300.ply"), "coordinates reach 1.06e+300; beyond 1e+75"),
    "info --json of a mesh x1e70": Case(("info", "--json", "<in>/huge70.ply"), "", 0, (), check=_strict_json),
}


@pytest.mark.parametrize("name", CASES)
def test_bad_input(name, inputs, tmp_path, capfd, monkeypatch):
    run_case(CASES[name], inputs, tmp_path, capfd, monkeypatch)
