"""PyVista conversion (hht3d.io.pyvista, HHTResult.to_pyvista): PyVista, an independent reader, sees every
field as point data, the faces of a mesh and the vertex cells of a cloud, and reads hht3d's VTU files as the
result; surface_from_pyvista triangulates what it is given."""

import sys

import numpy as np
import pytest

from helpers.meshes import icosphere
from hht3d import Surface, hht
from hht3d.errors import InputError
from hht3d.io import surface_from_pyvista, surface_to_pyvista
from hht3d.output_formats import FORMATS

pyvista = pytest.importorskip("pyvista")


@pytest.fixture
def result():
    surface = Surface(*icosphere(2), name="ball", origin=np.array([5e5, 5.4e6, 0.0]))
    surface.attributes["height"] = surface.vertices[:, 2].copy()
    return hht(surface, surface.vertices[:, 0] + surface.vertices[:, 1] ** 2, max_imfs=2)


def _fields(result):
    return {**result.vertex_attributes(), "height": result.surface.attributes["height"]}


def test_to_pyvista_is_polydata_with_every_field_the_faces_and_the_file_frame(result):
    poly = result.to_pyvista()
    assert isinstance(poly, pyvista.PolyData)
    np.testing.assert_array_equal(poly.points, result.surface.vertices + result.surface.origin)
    np.testing.assert_array_equal(poly.regular_faces, result.surface.faces)
    assert poly.n_verts == 0
    expected = _fields(result)
    assert set(poly.point_data.keys()) == set(expected) and len(expected) == 2 + 4 * result.n_imfs + 1
    for name, values in expected.items():
        np.testing.assert_array_equal(poly.point_data[name], values, err_msg=name)


def test_a_vtu_written_by_hht3d_reads_back_in_pyvista_as_the_result(tmp_path, result):
    path = FORMATS["hht"]["vtu"].write(result, result.surface, tmp_path / "ball.vtu")
    grid = pyvista.read(path)
    np.testing.assert_array_equal(grid.points, result.surface.vertices + result.surface.origin)
    np.testing.assert_array_equal(grid.cells_dict[pyvista.CellType.TRIANGLE], result.surface.faces)
    expected = _fields(result)
    assert set(grid.point_data.keys()) == set(expected)
    for name, values in expected.items():
        np.testing.assert_array_equal(grid.point_data[name], values, err_msg=name)
    back = surface_from_pyvista(grid, clean=False)  # its outer surface: the same points and triangles
    np.testing.assert_array_equal(back.vertices, grid.points)
    np.testing.assert_array_equal(back.faces, result.surface.faces)
    for name, values in expected.items():
        np.testing.assert_array_equal(back.attributes[name], values, err_msg=name)


def test_a_point_cloud_is_vertex_cells_and_comes_back_with_colours_and_attributes():
    rng = np.random.default_rng(0)
    cloud = Surface(rng.normal(size=(200, 3)), colors=rng.uniform(size=(200, 3)))
    cloud.attributes["intensity"] = rng.uniform(size=200)
    poly = surface_to_pyvista(cloud)
    assert (poly.n_verts, poly.GetNumberOfPolys()) == (200, 0)
    np.testing.assert_array_equal(poly.point_data["colors"], cloud.colors)
    back = surface_from_pyvista(poly, clean=False, name="cloud")
    assert not back.is_mesh and back.name == "cloud"
    np.testing.assert_array_equal(back.vertices, cloud.vertices)
    np.testing.assert_array_equal(back.colors, cloud.colors)
    np.testing.assert_array_equal(back.attributes["intensity"], cloud.attributes["intensity"])


def test_surface_from_pyvista_triangulates_quads_and_scales_byte_colours():
    plane = pyvista.Plane(i_size=2, j_size=3, i_resolution=4, j_resolution=3)  # 12 quads
    plane.point_data["colors"] = np.full((plane.n_points, 3), 255, dtype=np.uint8)
    surface = surface_from_pyvista(plane, clean=False)
    assert surface.faces.shape == (24, 3)
    np.testing.assert_array_equal(surface.vertices, plane.points)
    corners = surface.vertices[surface.faces]
    areas = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1)
    assert areas.min() > 0 and areas.sum() == pytest.approx(6.0, rel=1e-12)
    np.testing.assert_array_equal(surface.colors, np.ones((plane.n_points, 3)))


def test_what_is_not_a_pyvista_dataset_is_one_line():
    with pytest.raises(InputError, match=r"^expected a PyVista dataset, got ndarray$"):
        surface_from_pyvista(np.zeros((3, 3)))


def test_without_pyvista_each_conversion_says_how_to_install_it(result, monkeypatch):
    monkeypatch.setitem(sys.modules, "pyvista", None)  # import pyvista raises ImportError
    hint = r"^PyVista conversion needs pyvista: pip install pyvista$"
    with pytest.raises(InputError, match=hint):
        result.to_pyvista()
    with pytest.raises(InputError, match=hint):
        surface_from_pyvista(object())
