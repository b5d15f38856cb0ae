"""The ``hht3d`` command: subcommands, output and exit codes."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from helpers.folders import produced_names
from helpers.meshes import icosphere
from helpers.results import assert_same_hht
from hht3d import Surface
from hht3d.cli import demo_model_path, demo_pipeline_path, main
from hht3d.geometry.signals import mean_curvature
from hht3d.io import load, write_ply
from hht3d.pipeline import OPERATIONS
from hht3d.transform import hht

PIPELINE = """\
version: 1
inputs: {mesh}
steps:
  - {{id: curvature, op: signal, params: {{kind: mean_curvature}}}}
  - {{id: hht, op: hht, params: {{max_imfs: 2}}}}
outputs:
  folder: {out}
  files:
    - {{from: hht, path: "{{stem}}_hht.npz"}}
"""


@pytest.fixture
def mesh_file(tmp_path):
    v, f = icosphere(2)
    path = tmp_path / "bumpy.ply"
    write_ply(path, Surface(v * (1 + 0.06 * np.sin(5 * v[:, [0]])), f, name="bumpy"))
    return path


@pytest.fixture
def pipeline(tmp_path, mesh_file):
    path = tmp_path / "pipeline.yaml"
    path.write_text(PIPELINE.format(mesh=mesh_file, out=tmp_path / "out"))
    return path


def test_run_succeeds_with_exit_code_0(pipeline, mesh_file, tmp_path, capsys):
    assert main(["run", str(pipeline), "--scheduler", "synchronous", "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "bumpy.ply: ok, 162 vertices, 2 IMFs" in out
    assert f"wrote {tmp_path / 'out' / 'bumpy_hht.npz'}" in out
    (row,) = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert (row["status"], row["vertices"], row["imfs"]) == ("ok", 162, 2)
    # the file holds what the Python API computes in memory
    surface = load(mesh_file)
    expected = hht(surface, mean_curvature(surface), max_imfs=2)
    with np.load(tmp_path / "out" / "bumpy_hht.npz") as saved:
        assert_same_hht(saved, expected)
        np.testing.assert_array_equal(saved["vertices"], surface.vertices)


def test_set_overrides_a_parameter_and_resume_skips(pipeline, tmp_path, capsys):
    args = ["run", str(pipeline), "--scheduler", "synchronous", "--quiet", "--set", "steps.hht.params.max_imfs=1"]
    assert main(args) == 0
    assert "1 IMFs" in capsys.readouterr().out
    assert np.load(tmp_path / "out" / "bumpy_hht.npz")["imfs"].shape[0] == 1
    assert main([*args, "--resume"]) == 0
    assert "skipped (outputs complete)" in capsys.readouterr().out


def test_failures_exit_1_with_one_line(pipeline, tmp_path, capsys):
    assert main(["run", str(pipeline), "--quiet", "--set", "steps.hht.params.max_imfs=-2"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "max_imfs must be an integer in [0, 64]; got -2" in err
    assert main(["run", str(tmp_path / "missing.yaml")]) == 1
    assert "cannot read the pipeline" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_usage_errors_exit_2(pipeline, capsys):
    for argv in (["run"], ["run", str(pipeline), "--scheduler", "bogus"], ["frobnicate"], []):
        with pytest.raises(SystemExit) as stop:
            main(argv)
        assert stop.value.code == 2
    assert "usage: hht3d" in capsys.readouterr().err


def test_validate_prints_the_planned_graph_and_runs_nothing(pipeline, tmp_path, capsys):
    assert main(["validate", str(pipeline), "--set", "steps.hht.params.riesz_tasks=3"]) == 0
    out = capsys.readouterr().out
    assert "hht        hht(surface=load, signal=curvature) -> hht" in out
    assert "max_imfs=2, riesz_tasks=3" in out
    assert "dask graph" not in out  # validation builds no graph (issue 15)
    assert "output locations checked, memory estimated; nothing was run" in out
    assert not (tmp_path / "out").exists()
    assert main(["validate", str(pipeline), "--set", "steps.hht.op=hhtt"]) == 1
    assert "unknown op 'hhtt'; did you mean 'hht'?" in capsys.readouterr().err


def test_ops_lists_every_operation_with_parameters_and_defaults(capsys):
    assert main(["ops"]) == 0
    out = capsys.readouterr().out
    for name in OPERATIONS:
        assert f"\n{name}(" in f"\n{out}"
    assert "max_imfs" in out and "sd | rfg | s_number | fixed" in out
    assert "hht       png" in out  # the output formats
    assert main(["ops", "emd"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == "emd(surface: surface, signal: signal) -> emd"
    assert any(line.split()[:2] == ["max_imfs", "10"] for line in lines)
    assert main(["ops", "emdd"]) == 1
    assert "unknown op 'emdd'; did you mean 'emd'?" in capsys.readouterr().err


def test_info_describes_a_file(mesh_file, tmp_path, capsys):
    assert main(["info", str(mesh_file)]) == 0
    info = dict(line.split(maxsplit=1) for line in capsys.readouterr().out.splitlines())
    # a subdivided icosahedron: 162 vertices, 320 faces, 480 edges, closed, χ = 2
    assert {k: info[k] for k in ("vertices", "faces", "edges", "euler_characteristic", "closed")} == {
        "vertices": "162",
        "faces": "320",
        "edges": "480",
        "euler_characteristic": "2",
        "closed": "True",
    }
    surface = load(mesh_file)
    corners = surface.vertices[surface.faces]
    area = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1).sum()
    assert float(info["surface_area"]) == pytest.approx(area, rel=1e-12)
    assert main(["info", str(tmp_path / "none.ply")]) == 1
    assert "no such file" in capsys.readouterr().err


@pytest.mark.slow
def test_demo_runs_the_shipped_pipeline_into_out(tmp_path, capsys):
    """The README's main job: ``hht3d demo --out out/demo``, on the shipped model."""
    import matplotlib

    out = tmp_path / "demo"
    assert main(["demo", "--out", str(out), "--scheduler", "synchronous", "--quiet"]) == 0
    expected = {
        f"spot_{name}"
        for name in (
            "hht.ply",
            "hht.npz",
            "signal.ply",
            "imf_1.ply",
            "frequency_1.ply",
            "hht.png",
            "spectrum.png",
            "hht.html",
        )
    }
    assert set(produced_names(out)) == expected
    assert "spot.ply: ok, 2930 vertices" in capsys.readouterr().out
    # contents: the signal is the mean curvature of the shipped model, computed here; the PLY files
    # hold the arrays of the npz (float64 properties: exact), and the single-field PLYs colour
    # them with matplotlib's viridis over the 1st-99th percentiles (8-bit: half a step)
    surface = load(demo_model_path())
    saved = dict(np.load(out / "spot_hht.npz"))
    np.testing.assert_allclose(
        saved["signal"], mean_curvature(surface), rtol=0, atol=1e-12 * np.abs(saved["signal"]).max()
    )
    assert 2 <= len(saved["imfs"]) <= 6 and saved["imfs"].shape[1] == 2930
    fields = load(out / "spot_hht.ply", clean=False).attributes
    for k in range(len(saved["imfs"])):
        for name in ("imfs", "amplitude", "phase", "frequency"):
            np.testing.assert_array_equal(fields[f"{name.rstrip('s')}_{k + 1}"], saved[name][k])
    np.testing.assert_array_equal(fields["residue"], saved["residue"])
    for name, values in (
        ("signal", saved["signal"]),
        ("imf_1", saved["imfs"][0]),
        ("frequency_1", saved["frequency"][0]),
    ):
        coloured = load(out / f"spot_{name}.ply", clean=False)
        np.testing.assert_array_equal(coloured.attributes[name], values)
        lo, hi = np.percentile(values, [1, 99])
        colours = matplotlib.colormaps["viridis"](np.clip((values - lo) / (hi - lo), 0, 1))[:, :3]
        np.testing.assert_allclose(coloured.colors, colours, rtol=0, atol=0.5 / 255 + 1e-12)


def test_pipelines_demo_is_the_shipped_demo():
    example = Path(__file__).resolve().parents[2] / "pipelines" / "demo.yaml"
    assert example.read_text() == demo_pipeline_path().read_text()


def test_module_entry_point():
    done = subprocess.run(
        [sys.executable, "-m", "hht3d", "ops", "load"], capture_output=True, text=True, check=False, timeout=120
    )
    assert done.returncode == 0 and done.stdout.startswith("load(file: file) -> surface")


def test_a_memory_output_folder_is_refused_by_the_cli(tmp_path, capfd):
    """Results in a memory:// folder would vanish with the command: one line, nothing computed."""
    assert main(["demo", "--out", "memory://bucket/out", "--scheduler", "synchronous"]) == 1
    err = capfd.readouterr().err
    assert err.count("\n") == 1 and "would vanish when the command ends" in err
