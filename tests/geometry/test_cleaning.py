"""Mesh cleaning (hht3d.geometry.cleaning): what it reports and how attributes follow, on a made-up mesh and
a real scan."""

import numpy as np

from helpers.meshes import icosphere
from hht3d import Surface, load


def test_cleaning_reports_and_maps_attributes():
    v, f = icosphere(1)
    n = len(v)
    # append: an unreferenced vertex, a duplicate of vertex 0 used by a copied face,
    # a degenerate face and a duplicated face
    v2 = np.vstack([v, [[9, 9, 9]], v[[0]]])
    f2 = np.vstack([f, [[n + 1, f[0, 1], f[0, 2]]], [[1, 1, 2]], f[[5]]])
    surface = Surface.cleaned(v2, f2, attributes={"id": np.arange(len(v2), dtype=float)})
    r = surface.clean_report
    assert (r.merged_duplicate_vertices, r.removed_degenerate_faces) == (1, 1)
    assert r.removed_duplicate_faces == 2  # the copied face (after welding) and f[5]
    assert r.removed_unreferenced_vertices == 1
    assert surface.n_vertices == n and len(surface.faces) == len(f)
    np.testing.assert_array_equal(surface.attributes["id"], np.arange(n))
    assert r.original_to_new[n + 1] == 0 and r.original_to_new[n] == -1


def test_real_scan_cleaning(shared_model):
    # MANIFEST: 1,113 unreferenced vertices in the Stanford bunny; 2,100
    # duplicate positions and 108 zero-area faces in the dragon
    bunny = load(shared_model("bunny_zipper.ply"))
    assert bunny.clean_report.removed_unreferenced_vertices == 1113
    assert bunny.n_vertices == 35947 - 1113
