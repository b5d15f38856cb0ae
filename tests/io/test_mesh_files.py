"""VTU, VTP and the meshio formats (hht3d.io.mesh_files): every file read back by an independent reader
(meshio for VTU, VTK's own XML reader for VTP when the vtk package is installed), arrays compared."""

import sys

import numpy as np
import pytest

from helpers.meshes import icosphere
from hht3d import Surface, hht, load
from hht3d.errors import InputError
from hht3d.output_formats import FORMATS

meshio = pytest.importorskip("meshio")


@pytest.fixture
def result():
    surface = Surface(*icosphere(2), name="ball", origin=np.array([5e5, 5.4e6, 0.0]))
    surface.attributes["height"] = surface.vertices[:, 2].copy()
    return hht(surface, surface.vertices[:, 0] + surface.vertices[:, 1] ** 2, max_imfs=1)


def test_vtu_holds_the_triangles_and_every_field_as_point_data(tmp_path, result):
    path = FORMATS["hht"]["vtu"].write(result, result.surface, tmp_path / "ball.vtu")
    mesh = meshio.read(path)
    np.testing.assert_array_equal(mesh.points, result.surface.vertices + result.surface.origin)
    np.testing.assert_array_equal(mesh.cells_dict["triangle"], result.surface.faces)
    expected = {**result.vertex_attributes(), "height": result.surface.attributes["height"]}
    assert set(mesh.point_data) == set(expected)
    for name, values in expected.items():
        np.testing.assert_array_equal(mesh.point_data[name], values, err_msg=name)


def test_a_point_cloud_is_written_as_vertex_cells(tmp_path):
    rng = np.random.default_rng(0)
    cloud = Surface(rng.normal(size=(200, 3)), colors=rng.uniform(size=(200, 3)))
    mesh = meshio.read(FORMATS["surface"]["vtu"].write(cloud, cloud, tmp_path / "cloud.vtu"))
    np.testing.assert_array_equal(mesh.cells_dict["vertex"].ravel(), np.arange(200))
    np.testing.assert_array_equal(mesh.point_data["colors"], cloud.colors)
    back = load(tmp_path / "cloud.vtu", clean=False)
    assert not back.is_mesh and back.n_vertices == 200


def test_vtp_reads_back_in_vtk(tmp_path, result):
    vtk = pytest.importorskip("vtk")
    from vtk.util.numpy_support import vtk_to_numpy

    path = FORMATS["hht"]["vtp"].write(result, result.surface, tmp_path / "ball.vtp")
    reader = vtk.vtkXMLPolyDataReader()
    reader.SetFileName(str(path))
    reader.Update()
    polydata = reader.GetOutput()
    np.testing.assert_array_equal(
        vtk_to_numpy(polydata.GetPoints().GetData()), result.surface.vertices + result.surface.origin
    )
    polys = vtk_to_numpy(polydata.GetPolys().GetConnectivityArray())
    np.testing.assert_array_equal(polys.reshape(-1, 3), result.surface.faces)
    point_data = polydata.GetPointData()
    for name, values in result.vertex_attributes().items():
        np.testing.assert_array_equal(vtk_to_numpy(point_data.GetArray(name)), values, err_msg=name)


def test_quads_of_a_meshio_format_become_triangles(tmp_path):
    # a 3 x 3 grid of quads (16 points), written by meshio as legacy VTK, with a scalar per point
    u, v = np.meshgrid(np.arange(4.0), np.arange(4.0), indexing="ij")
    points = np.column_stack([u.ravel(), v.ravel(), np.sin(u.ravel()) * np.cos(v.ravel())])
    index = np.arange(16).reshape(4, 4)
    quads = np.array(
        [[index[i, j], index[i + 1, j], index[i + 1, j + 1], index[i, j + 1]] for i in range(3) for j in range(3)]
    )
    meshio.write_points_cells(
        tmp_path / "grid.vtk",
        points,
        [("quad", quads)],
        point_data={"heat": points[:, 2]},
        file_format="vtk",
    )
    surface = load(tmp_path / "grid.vtk", clean=False)
    assert surface.is_mesh and len(surface.faces) == 18
    np.testing.assert_array_equal(surface.faces[:9], quads[:, [0, 1, 2]])  # each quad's fan from corner 0
    np.testing.assert_array_equal(surface.faces[9:], quads[:, [0, 2, 3]])
    np.testing.assert_array_equal(surface.attributes["heat"], points[:, 2])


def test_clear_errors(tmp_path, monkeypatch):
    tetra = np.array([[0, 1, 2, 3]])
    points = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    meshio.write_points_cells(tmp_path / "solid.vtu", points, [("tetra", tetra)])
    with pytest.raises(InputError, match="solid.vtu: the file holds tetra cells and no triangles, quads or polygons"):
        load(tmp_path / "solid.vtu")
    (tmp_path / "junk.vtu").write_text("<VTKFile")
    with pytest.raises(InputError, match="junk.vtu: not a readable mesh file"):
        load(tmp_path / "junk.vtu")
    monkeypatch.setitem(sys.modules, "meshio", None)
    with pytest.raises(
        InputError, match=r"^VTU files and the meshio formats need meshio: pip install 'hht3d\[meshio\]'$"
    ):
        load(tmp_path / "solid.vtu")
