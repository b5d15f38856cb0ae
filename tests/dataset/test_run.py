"""Dataset runs: a corrupt file is reported, the others finish, nothing is half-written."""

import json
import re
import shutil

import numpy as np
import open3d as o3d
import pytest

from helpers.datasets import _make_inputs
from helpers.folders import dead_writers_part, produced_names
from helpers.meshes import icosphere
from helpers.results import assert_same_hht, hht_arrays_from_ply
from hht3d import Surface, load
from hht3d.dataset import dataset_graph, run_dataset
from hht3d.errors import OutputError
from hht3d.geometry.signals import mean_curvature
from hht3d.io import write_ply
from hht3d.transform import hht


def test_corrupt_file_is_reported_and_others_finish(tmp_path):
    inputs = _make_inputs(tmp_path / "in")
    out = tmp_path / "out"
    rows = run_dataset(inputs, out, scheduler="synchronous", progress=False, max_imfs=2, riesz_tasks=2)
    status = {r.source.rsplit("/", 1)[-1]: r for r in rows}
    assert status["good0.ply"].status == status["good1.ply"].status == "ok"
    assert status["good0.ply"].imfs == 2 and status["good0.ply"].vertices == 642
    bad = status["corrupt.ply"]
    assert bad.status == "failed" and bad.step == "load" and "not a readable PLY" in bad.error
    tiny = status["three_points.xyz"]
    assert tiny.status == "failed" and "at least 4" in tiny.error
    produced = produced_names(out)
    assert produced == [
        "good0_hht.npz",
        "good0_hht.ply",
        "good1_hht.npz",
        "good1_hht.ply",
        "summary.csv",
        "summary.json",
    ]  # nothing for the failures, no temp files
    summary = json.loads((out / "summary.json").read_text())
    assert [r["status"] for r in summary] == [
        status[k].status for k in [r["source"].rsplit("/", 1)[-1] for r in summary]
    ]
    # each file holds its own input's HHT, as the Python API computes it in memory
    for name in ("good0", "good1"):
        surface = load(inputs / f"{name}.ply")
        expected = hht(surface, mean_curvature(surface), max_imfs=2)
        with np.load(out / f"{name}_hht.npz") as saved:
            assert_same_hht(saved, expected)
        assert_same_hht(hht_arrays_from_ply(load(out / f"{name}_hht.ply", clean=False).attributes), expected)


def test_resume_skips_complete_items(tmp_path):
    inputs = _make_inputs(tmp_path / "in")
    for name in ("corrupt.ply", "three_points.xyz"):
        (inputs / name).unlink()
    out = tmp_path / "out"
    run_dataset(inputs, out, scheduler="synchronous", progress=False, max_imfs=1)
    (out / "good1_hht.npz").unlink()
    rows = run_dataset(inputs, out, scheduler="synchronous", progress=False, resume=True, max_imfs=1)
    assert [r.status for r in rows] == ["skipped", "ok"]
    shutil.rmtree(out)


def test_a_worker_killed_mid_write_leaves_no_temporary_file(tmp_path, monkeypatch):
    """As for pipelines: a killed writer's ``.part`` file is gone once the dataset run ends."""
    import hht3d.dataset.run as dataset

    inputs = _make_inputs(tmp_path / "in")
    real, parts = dataset.compute, []

    def compute(*args, **kwargs):
        parts.append(dead_writers_part(tmp_path / "out", "good0_hht.npz"))
        return real(*args, **kwargs)

    monkeypatch.setattr(dataset, "compute", compute)
    run_dataset(inputs / "good0.ply", tmp_path / "out", scheduler="synchronous", progress=False, max_imfs=1)
    assert not parts[0].exists() and (tmp_path / "out" / "good0_hht.npz").is_file()


def test_unwritable_output_folder_fails_before_computing(tmp_path, monkeypatch):
    inputs = _make_inputs(tmp_path / "in")
    monkeypatch.setattr("hht3d.graph.stages.transform_file", lambda *a, **k: pytest.fail("computed anyway"))
    with pytest.raises(OutputError, match="good0.ply is not a folder"):
        run_dataset(inputs, inputs / "good0.ply", scheduler="synchronous", progress=False)


@pytest.mark.parametrize(
    "options, message",
    [({"formats": (".obj",)}, "unknown output format '.obj'"), ({"signal": "bogus"}, "unknown signal 'bogus'")],
)
def test_run_dataset_refuses_bad_options_before_building_the_graph(options, message, inputs, tmp_path, monkeypatch):
    from hht3d.dataset import run_dataset
    from hht3d.errors import InputError

    monkeypatch.setattr("hht3d.graph.stages.transform_file", lambda *a, **k: pytest.fail("built the graph"))
    with pytest.raises(InputError, match=re.escape(message)):
        run_dataset([inputs / "good.ply"], tmp_path / "out", scheduler="synchronous", progress=False, **options)
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("pattern", ["{0}", "{name}", "{stem", "{stem.x}"])
def test_an_output_pattern_with_another_field_is_named(pattern, tmp_path):
    """Only {stem} is filled in; anything else is one InputError, not an IndexError or KeyError."""
    from hht3d import InputError, data_path

    with pytest.raises(InputError, match="the only field is {stem}"):
        run_dataset([data_path("spot.ply")], tmp_path / "out", scheduler="synchronous", pattern=pattern)
    assert not (tmp_path / "out").exists()


def test_the_largest_input_gets_the_highest_task_priority(tmp_path):
    """dask.distributed runs ready tasks by their ``priority`` annotation: the largest file's chain must
    start first, or it runs last while the other workers idle (1.57x on 2 workers, bench_graph)."""
    folder, out = tmp_path / "in", tmp_path / "out"
    folder.mkdir()
    for name, subdivisions in (("a", 4), ("b", 2), ("c", 3)):  # names in another order than sizes
        write_ply(folder / f"{name}.ply", Surface(*icosphere(subdivisions)))
    priority = {}
    for layer in dataset_graph(folder, out, max_imfs=1).__dask_graph__().layers.values():
        note = (layer.annotations or {}).get("priority")
        priority.update(
            {str(key).split("_hht.npz-")[0]: note(key) for key in layer if note and "_hht.npz-" in str(key)}
        )
    assert sorted(priority, key=priority.get) == ["write b", "write c", "write a"], priority


def test_inputs_rank_by_declared_vertices_not_bytes(tmp_path):
    """A bare point cloud has a third of a coloured one's bytes per vertex: ranked by bytes, the 40,256-point
    bunny scan ran last on 2 workers.  Local PLY inputs rank by the vertices their headers declare; with
    one input that declares none (not PLY), all rank by bytes, one unit for all."""
    from hht3d.dataset.run import _expected_work

    points = icosphere(3)[0]
    few, many = tmp_path / "few.ply", tmp_path / "many.ply"
    coloured = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points[:450]))
    coloured.colors = o3d.utility.Vector3dVector(np.full((450, 3), 0.5))
    coloured.normals = o3d.utility.Vector3dVector(np.tile([0.0, 0.0, 1.0], (450, 1)))
    o3d.io.write_point_cloud(str(few), coloured, write_ascii=True)
    o3d.io.write_point_cloud(str(many), o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points)))
    assert few.stat().st_size > many.stat().st_size
    assert _expected_work([few, many]) == {few: 450, many: len(points)}
    text = tmp_path / "other.xyz"
    np.savetxt(text, points[:10])
    assert _expected_work([few, many, text]) == {p: p.stat().st_size for p in (few, many, text)}
