"""Output folders (hht3d.io.folder): a ``file://`` URL is the local path it names at every entry, and a URL
folder keeps its outputs under its prefix (the CLI's cases are rows of tests/cli/test_bad_outputs.py)."""

from __future__ import annotations

import numpy as np
import pytest

from helpers.meshes import icosphere
from hht3d import Surface, load
from hht3d.dataset import run_dataset
from hht3d.errors import OutputError
from hht3d.io.folder import check_locations
from hht3d.io.storage import is_url, join, local_path
from hht3d.transform import hht


def test_a_file_url_is_a_local_path(tmp_path):
    assert not is_url(f"file://{tmp_path}/out") and not is_url(f"local://{tmp_path}")
    assert local_path(f"file://{tmp_path}/a%20b.ply") == tmp_path / "a b.ply"
    assert local_path("s3://b/k") == "s3://b/k" and local_path(tmp_path) == tmp_path


def test_a_file_url_folder_of_run_dataset_keeps_a_users_file(inputs, tmp_path):
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "good_hht.npz").write_bytes(b"mine")
    with pytest.raises(OutputError, match="good_hht.npz: exists and hht3d did not write it"):
        run_dataset(f"file://{inputs}/good.ply", f"file://{tmp_path}/out", scheduler="synchronous", progress=False)
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["good_hht.npz"]
    assert (tmp_path / "out" / "good_hht.npz").read_bytes() == b"mine"


def test_save_and_load_take_a_file_url(tmp_path):
    surface = Surface(*icosphere(2))
    result = hht(surface, surface.vertices[:, 2].copy(), max_imfs=1)
    url = f"file://{tmp_path}/r.ply"
    assert result.save(url) == tmp_path / "r.ply"
    assert load(url).n_vertices == surface.n_vertices
    np.testing.assert_array_equal(load(url).vertices, surface.vertices)


def test_url_output_keys_are_normalised_and_kept_under_the_folder():
    folder = "s3://bucket/out"
    assert join(folder, "U05/./a//b.npz") == "s3://bucket/out/U05/a/b.npz"
    escaping = join(folder, "U05/../../victim/x.npz")
    assert escaping == "s3://bucket/victim/x.npz"
    with pytest.raises(OutputError, match="s3://bucket/victim/x.npz leaves the output folder s3://bucket/out"):
        check_locations({"s3://bucket/in/a.ply": [escaping]}, folder)
    check_locations({"s3://bucket/in/a.ply": [escaping]}, folder, allow_outside=True)
