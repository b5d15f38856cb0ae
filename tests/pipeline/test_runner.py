"""YAML pipelines run (hht3d.pipeline.runner): the examples write their outputs, runtime errors name the step
and the input file, and the numbers match the graph API."""

import json
from pathlib import Path

import numpy as np
import pytest

from helpers.folders import dead_writers_part, produced_names
from helpers.pipelines import EXAMPLES, GOOD, _fast_overrides, _run, assert_output_fits
from helpers.results import assert_same_hht, hht_arrays_from_ply
from hht3d import graph
from hht3d.apps import HighBoost, LowPass, filter_geometry
from hht3d.geometry.signals import mean_curvature
from hht3d.io import load
from hht3d.pipeline import load_pipeline, run_pipeline
from hht3d.transform import hht


# -- the examples ------------------------------------------------------------------------------
def test_examples_are_there():
    assert {p.name for p in EXAMPLES} >= {"demo.yaml", "dataset_features.yaml", "filtering.yaml", "point_cloud.yaml"}


@pytest.mark.slow
@pytest.mark.parametrize("example", EXAMPLES, ids=lambda p: p.stem)
def test_example_runs_and_writes_its_outputs(example, tmp_path, mesh_file, cloud_file, folder):
    inputs = {"point_cloud": cloud_file, "dataset_features": folder}.get(example.stem, mesh_file)
    out = tmp_path / "out"
    overrides = [f"inputs={inputs}", f"outputs.folder={out}", *_fast_overrides(example)]
    assert _run(example, *[a for o in overrides for a in ("--set", o)]) == 0
    plan = load_pipeline(example, overrides)
    sources = sorted(inputs.iterdir()) if inputs.is_dir() else [inputs]
    for source in sources:
        n = load(source).n_vertices
        for path in plan.output_paths(source):
            assert_output_fits(path, n)
    if plan.summary:
        rows = json.loads((out / "summary.json").read_text())
        assert [r["status"] for r in rows] == ["ok"] * len(sources)
    assert not list(out.rglob("*.part"))


def test_point_cloud_example_keeps_points_and_fields(tmp_path, cloud_file):
    out = tmp_path / "out"
    example = next(p for p in EXAMPLES if p.stem == "point_cloud")
    _run(
        example,
        "--set",
        f"inputs={cloud_file}",
        "--set",
        f"outputs.folder={out}",
        "--set",
        "steps.hht.params.max_imfs=2",
    )
    result = load(out / "cloud_hht.ply", clean=False)
    assert result.faces is None and result.n_vertices == 300
    assert {"signal", "imf_1", "frequency_1", "residue"} <= set(result.attributes)
    cloud = load(cloud_file, n_neighbors=30)
    expected = hht(cloud, mean_curvature(cloud), max_imfs=2)
    np.testing.assert_array_equal(result.vertices, cloud.vertices)
    with np.load(out / "cloud_hht.npz") as saved:
        assert_same_hht(saved, expected)
    assert_same_hht(hht_arrays_from_ply(result.attributes), expected)


def test_filtering_example_moves_vertices_and_keeps_faces(tmp_path, mesh_file):
    out = tmp_path / "out"
    example = next(p for p in EXAMPLES if p.stem == "filtering")
    _run(
        example,
        "--set",
        f"inputs={mesh_file}",
        "--set",
        f"outputs.folder={out}",
        "--set",
        "steps.smooth.params.gain={kind: low_pass, cutoff: 1.0}",  # the bumps are at ~5 rad/unit
        "--set",
        "steps.enhance.params.gain={kind: high_boost, cutoff: 3.0, factor: 2.0, width: 1.0}",
    )
    original, smooth = load(mesh_file, clean=False), load(out / "bumpy_smooth.ply", clean=False)
    np.testing.assert_array_equal(smooth.faces, original.faces)
    assert np.abs(smooth.vertices - original.vertices).max() > 1e-4
    # the same filter through the Python API: Riesz round-off (1e-12) moves the gains and so the
    # vertices by far less than 1e-9 of the model size
    surface = load(mesh_file)
    result = hht(surface, mean_curvature(surface), max_imfs=6)
    expected = filter_geometry(result, LowPass(cutoff=1.0))
    np.testing.assert_allclose(smooth.vertices, expected.vertices, rtol=0, atol=1e-9)
    enhanced = filter_geometry(
        result, HighBoost(cutoff=3.0, factor=2.0, width=1.0), interior_weight=0.01, boundary_weight=1.0
    )
    assert np.abs(enhanced.vertices - original.vertices).max() > 1e-4  # the boost acts: not an unchanged copy
    np.testing.assert_allclose(
        load(out / "bumpy_enhanced.ply", clean=False).vertices, enhanced.vertices, rtol=0, atol=1e-9
    )


# -- same numbers through the CLI, the Python pipeline API and the graph API ------------------------
def test_cli_pipeline_and_graph_api_give_the_same_numbers(tmp_path, mesh_file):
    demo = next(p for p in EXAMPLES if p.stem == "demo")
    overrides = [f"inputs={mesh_file}", "steps.hht.params.max_imfs=3", "outputs.files=[{path: x.npz}]"]
    cli = [*overrides, f"outputs.folder={tmp_path / 'cli'}"]
    assert _run(demo, *[a for o in cli for a in ("--set", o)]) == 0
    plan = load_pipeline(demo, [*overrides, f"outputs.folder={tmp_path / 'api'}"])
    (row,) = run_pipeline(plan, scheduler="synchronous", progress=False)

    surface = graph.load(mesh_file)
    lazy = graph.hht(surface, graph.signal(surface, "mean_curvature"), max_imfs=3)
    (expected,) = graph.compute(lazy, scheduler="synchronous", progress=False)
    assert row.status == "ok" and row.imfs == expected.n_imfs >= 2
    mono = expected.monogenic
    arrays = {
        "signal": expected.signal,
        "imfs": expected.imfs,
        "residue": expected.residue,
        "riesz": mono.riesz,
        "amplitude": mono.amplitude,
        "frequency": mono.frequency,
    }
    for folder in ("cli", "api"):
        got = np.load(tmp_path / folder / "x.npz")
        for name, values in arrays.items():
            np.testing.assert_array_equal(got[name], values)


# -- runtime errors name the step and the input file -----------------------------------------------------
def test_failed_file_is_reported_with_step_and_file_while_others_finish(tmp_path, folder, capsys):
    (folder / "broken.ply").write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 9\n")
    path = tmp_path / "pipeline.yaml"
    path.write_text(GOOD.format(mesh=folder, out=tmp_path / "out"))
    assert _run(path) == 1
    captured = capsys.readouterr()
    assert captured.err.count("\n") == 1
    assert f"1 of 3 inputs failed; first: step load failed on {folder / 'broken.ply'}: InputError" in captured.err
    produced = produced_names(tmp_path / "out")
    assert produced == ["part0_imfs.npz", "part1_imfs.npz", "summary.csv", "summary.json"]
    rows = {Path(r["source"]).name: r for r in json.loads((tmp_path / "out" / "summary.json").read_text())}
    assert rows["broken.ply"]["status"] == "failed" and rows["broken.ply"]["step"] == "load"
    assert rows["part1.ply"]["status"] == "ok" and rows["part1.ply"]["imfs"] == 2


def test_failure_inside_a_step_names_that_step(tmp_path, mesh_file, capsys):
    path = tmp_path / "pipeline.yaml"
    path.write_text(GOOD.format(mesh=mesh_file, out=tmp_path / "out").replace("mean_curvature", "luminance"))
    assert _run(path) == 1
    err = capsys.readouterr().err
    assert f"step curvature failed on {mesh_file}: InputError: bumpy: has no vertex colours" in err
    assert not list((tmp_path / "out").glob("*.npz"))


def test_resume_skips_finished_inputs(tmp_path, folder):
    path = tmp_path / "pipeline.yaml"
    path.write_text(GOOD.format(mesh=folder, out=tmp_path / "out"))
    plan = load_pipeline(path)
    run_pipeline(plan, scheduler="synchronous", progress=False)
    (tmp_path / "out" / "part1_imfs.npz").unlink()
    rows = run_pipeline(plan, scheduler="synchronous", progress=False, resume=True)
    assert [r.status for r in rows] == ["skipped", "ok"]


def test_a_worker_killed_mid_write_leaves_no_temporary_file(tmp_path, folder, monkeypatch):
    """A worker killed while writing (a nanny then restarts it, and its task runs again) leaves
    its ``.part`` file behind; the run removes it once every task is done."""
    from hht3d.pipeline import runner

    real, parts = runner.compute, []

    def compute(*args, **kwargs):  # the killed worker's file appears while the run goes on
        parts.append(dead_writers_part(tmp_path / "out", "part1_imfs.npz"))
        return real(*args, **kwargs)

    monkeypatch.setattr(runner, "compute", compute)
    path = tmp_path / "pipeline.yaml"
    path.write_text(GOOD.format(mesh=folder, out=tmp_path / "out"))
    rows = run_pipeline(load_pipeline(path), scheduler="synchronous", progress=False)
    assert [r.status for r in rows] == ["ok", "ok"]
    assert not parts[0].exists() and (tmp_path / "out" / "part1_imfs.npz").is_file()


def test_a_pipeline_step_takes_the_method(tmp_path):
    """``method: filtering`` in the demo's ``hht`` step gives the IMFs of ``hht(method="filtering")``."""
    from hht3d import data_path

    demo = next(p for p in EXAMPLES if p.stem == "demo")
    out = tmp_path / "out"
    settings = [f"outputs.folder={out}", "steps.hht.params.method=filtering", "steps.hht.params.max_imfs=2"]
    assert _run(demo, *[a for s in settings for a in ("--set", s)]) == 0
    spot = load(data_path("spot.ply"))
    expected = hht(spot, mean_curvature(spot), method="filtering", max_imfs=2)
    assert_same_hht(hht_arrays_from_ply(load(out / "spot_hht.ply", clean=False).attributes), expected)
